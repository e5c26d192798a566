"""Synthesis to a target yield beside worst-case synthesis, on a built-in model.

Runs :func:`synthesis.synthesize` twice on the same model and preset: worst
case (no defective check-list vector left) and to a target yield
(``target_yield``), then confirms the target run's final design with an
independent seeded yield estimate (another seed, more samples) against the
initial design.  Plain script::

    python benchmarks/target_yield.py                       # Geneva, fast, 99 %
    python benchmarks/target_yield.py --model reciprocating_cam --target 0.999

It writes ``docs/benchmarks/target_yield.md`` (atomically).
"""

from __future__ import annotations

import argparse
import datetime
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.benchlib import load_average  # noqa: E402
from cspace.io import atomic_write  # noqa: E402


def _row(label, r, m, t, ye=None):
    kept = r.tol / m.tol
    cuts = int(np.sum(r.tol < m.tol))
    ye = ye if ye is not None else r.yield_estimate
    est = "—" if ye is None else (f"{ye['ppm']:.4g} [{ye['ci_ppm'][0]:.4g}, "
                                  f"{ye['ci_ppm'][1]:.4g}]")
    return (f"| {label} | {r.status.name} | {r.nit} | {r.history[-1].n_defects} | "
            f"{r.e:.4g} {r.units} | {cuts} | {100 * kept.min():.0f} % | "
            f"{float(np.prod(kept)):.3g} | {est} | {t / 60:.1f} min |")


def main(argv=None):
    from mechanisms.models import BUILTIN
    from synthesis import make_executor, synthesize, yield_estimate
    from synthesis.target import YieldTarget
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", default="geneva")
    p.add_argument("--preset", default="fast")
    p.add_argument("--target", type=float, default=0.99)
    p.add_argument("--samples", type=int, default=2000, help="samples of each estimate")
    p.add_argument("--check", type=int, default=4000, help="samples of the independent check")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks" / "target_yield.md"))
    a = p.parse_args(argv)
    m = BUILTIN[a.model]()
    target = YieldTarget(a.target, samples=a.samples, seed=0)
    la0 = load_average()
    t_all = time.perf_counter()
    with make_executor("process", a.workers) as ex:
        t = time.perf_counter()
        worst = synthesize(m, a.preset, executor=ex)
        t_worst = time.perf_counter() - t
        t = time.perf_counter()
        aimed = synthesize(m, a.preset, executor=ex, target_yield=target)
        t_aimed = time.perf_counter() - t
        finals = {}
        for label, r in (("worst case", worst), ("target", aimed)):
            final = m.with_nominal(r.nominal).with_tolerances(r.tol)
            finals[label] = yield_estimate(final, a.check, seed=12345, accuracy=a.preset,
                                           d=r.d, executor=ex, intent=m, search=False)
    chk = finals["target"]
    lines = [f"# Synthesis to a target yield ({datetime.date.today().isoformat()})", "",
             f"Script: `benchmarks/target_yield.py` (run `python benchmarks/target_yield.py "
             f"{' '.join(sys.argv[1:])}`).  Machine: {platform.processor() or platform.machine()},"
             f" Python {platform.python_version()}; whole run "
             f"{time.perf_counter() - t_all:.0f} s; load average at the start {la0}, at the "
             f"end {load_average()}.", "",
             f"Model `{a.model}`, preset `{a.preset}`, every parameter a normal truncated at "
             f"its tolerance with sigma = t / 3 (Cp 1).  Target yield {a.target:g} (at most "
             f"{1e6 * target.failure:.4g} ppm defective), estimated each iteration by plain "
             f"Monte Carlo with {a.samples} samples (seed 0): the run stops when the upper "
             f"bound of the 95 % interval is at or below the target.  Both runs compare every "
             f"part with the initial design.", "",
             "| run | status | iterations | defective check-list vectors left | e | cuts | "
             "smallest kept | box volume kept | estimated ppm [95 % interval] | time |",
             "|---|---|---:|---:|---:|---:|---:|---:|---|---:|",
             _row("worst case", worst, m, t_worst),
             _row(f"target yield {a.target:g}", aimed, m, t_aimed), "",
             "The target run's estimate per iteration: " + "; ".join(
                 f"iteration {h.iteration}: {h.yield_estimate['failures']}/"
                 f"{h.yield_estimate['samples']}, {h.yield_estimate['ppm']:.0f} ppm "
                 f"[{h.yield_estimate['ci_ppm'][0]:.0f}, {h.yield_estimate['ci_ppm'][1]:.0f}]"
                 f"{' (met)' if h.yield_estimate['met'] else ''}"
                 for h in aimed.history if h.yield_estimate) + ".", "",
             f"Independent check of the final designs: {a.check} plain Monte Carlo samples, "
             f"seed 12345, against the initial design:", "",
             "| final design of | failing / samples | ppm | 95 % interval (ppm) | meets the "
             "target |", "|---|---:|---:|---|---|"]
    for label, y in finals.items():
        lo, hi = y.ci
        lines.append(f"| {label} | {y.failures}/{y.samples} | {y.ppm:.4g} | "
                     f"[{1e6 * lo:.4g}, {1e6 * hi:.4g}] | "
                     f"{'yes' if hi <= target.failure else 'no'} (upper bound) |")
    lines += ["", f"The target run's own last estimate and the independent check "
                  f"{'agree' if chk.ci[0] <= aimed.yield_estimate['ci'][1] and aimed.yield_estimate['ci'][0] <= chk.ci[1] else 'disagree'}"
                  f" (their 95 % intervals overlap)."]
    text = "\n".join(lines) + "\n"
    print(text)
    atomic_write(Path(a.out), text)


if __name__ == "__main__":
    main()
