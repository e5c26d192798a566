"""synthesis: the tolerance synthesis loop of [Tolerance synthesis] §4 and the command line.

Main entry points
-----------------
synthesize(model, accuracy, ...) -> SynthesisResult
    The loop: check list, defect tests, transition points, shift and shrink.
monte_carlo(model, n, ...) -> MonteCarloResult
    Independent seeded sampling of a tolerance box.
yield_estimate(model, n, method=..., ...) -> YieldResult
    Statistical yield: failure probability (ppm) with a 95 % interval, design
    points and contributors (``synthesis.statistics``).
make_executor(kind, workers, scheduler)
    ``process`` (default), ``serial`` or ``dask`` executors for the defect tests.

Index
-----
accuracy     SynthesisAccuracy: the geometry's knobs plus the synthesis's own, presets
loop         synthesize: the loop (check list, defect tests, removal), one iteration at a time
checklist    the check list: zone extremes, parameter combination, epsilon-filter
removal      removal of defective variants: transition points, shift, tolerance cut
minimal      minimal changes from defect margins (the removal step ``removal="lp"``)
guards       what a run may change and at what cost (fixed, hard, min_keep, costs)
result       values of the loop: iteration record, resumable state, SynthesisResult
executors    defect tests on any concurrent.futures.Executor (process, serial, dask)
memo         the defect tests of the iteration in progress, kept for a resume inside it
checkpoint   the checkpoint file: its content hash
progress     progress reporting: silent, a log, or a bar
stopping     how a run stops on SIGINT and SIGTERM
verify       monte_carlo: independent verification of a tolerance box by sampling
statistics   yield_estimate: statistical yield in ppm, design points, contributors
target       synthesis to a target yield: YieldTarget, the estimate of each iteration
cli          the command line ``cspace-tol`` (also ``python -m synthesis``): its
             subcommands, the report and figures of a run, the output-folder lock

See ``docs/synthesis.md``.
"""

from .accuracy import SynthesisAccuracy
from .executors import SerialExecutor, make_executor
from .loop import synthesize
from .result import SynthesisResult, SynthesisState, SynthesisStatus
from .statistics import YieldResult, yield_estimate
from .verify import MonteCarloResult, box_samples, monte_carlo

__all__ = ["synthesize", "SynthesisResult", "SynthesisState", "SynthesisStatus", "monte_carlo",
           "MonteCarloResult", "box_samples", "yield_estimate", "YieldResult", "make_executor",
           "SerialExecutor", "SynthesisAccuracy"]
