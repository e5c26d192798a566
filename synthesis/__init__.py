"""synthesis: the tolerance synthesis loop of [Tolerance synthesis] §4 and the command line.

Main entry points
-----------------
synthesize(model, accuracy, ...) -> SynthesisResult
    The loop: check list, defect tests, transition points, shift and shrink.
monte_carlo(model, n, ...) -> MonteCarloResult
    Independent seeded sampling of a tolerance box.
make_executor(kind, workers, scheduler)
    ``process`` (default), ``serial`` or ``dask`` executors for the defect tests.

See ``docs/synthesis.md``.
"""

from .executors import SerialExecutor, make_executor
from .loop import synthesize
from .result import SynthesisResult, SynthesisState, SynthesisStatus
from .verify import MonteCarloResult, box_samples, monte_carlo

__all__ = ["synthesize", "SynthesisResult", "SynthesisState", "SynthesisStatus", "monte_carlo",
           "MonteCarloResult", "box_samples", "make_executor", "SerialExecutor"]
