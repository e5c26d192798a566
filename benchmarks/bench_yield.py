"""Statistical yield: importance sampling against plain Monte Carlo.

Every figure is measured in one run of this script, on the pin-in-slot yoke of
``tests/synthesis/test_statistics.py`` (normal pin radius and slot half-width
of equal sigma, crank held at its nominal), whose failure probability has the
closed form ``Phi(-gap / (sigma sqrt 2))``.  Plain script::

    python benchmarks/bench_yield.py                 # P = 1e-2, 1e-3, 1e-4
    python benchmarks/bench_yield.py --p 1e-4 --samples 400

Measurements (one core: the serial executor, in this process)
-------------------------------------------------------------
mc          plain Monte Carlo of ``--mc`` parts (run at P >= 1e-2 only: at
            smaller P it finds too few failures to give a width), its
            Clopper-Pearson 95 % interval and the time per test.
is          design point search and ``--samples`` importance samples: the
            estimate, its 95 % interval, and the defect tests used.
ratio       plain Monte Carlo tests for the same interval width (the binomial
            variance at the closed-form P) over the tests importance sampling
            used, and, where plain Monte Carlo ran, its measured width over
            the width it would have with that many tests.
"""

from __future__ import annotations

import argparse
import datetime
import math
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.benchlib import load_average   # noqa: E402
from cspace.io import atomic_write   # noqa: E402
from synthesis.executors import SerialExecutor   # noqa: E402
from synthesis.statistics import Z95, yield_estimate   # noqa: E402
from tests.synthesis.test_statistics import closed_form, pin_in_slot, sigma_for   # noqa: E402


def run(p: float, samples: int, mc: int) -> dict:
    sigma = sigma_for(p)
    m, truth, ex = pin_in_slot(sigma), closed_form(sigma), SerialExecutor()
    t = time.perf_counter()
    r = yield_estimate(m, samples, method="is", seed=0, accuracy="fast", executor=ex)
    t_is = time.perf_counter() - t
    width = r.ci[1] - r.ci[0]
    n_mc = truth * (1 - truth) * (2 * Z95 / width) ** 2
    row = {"P": truth, "is": r.probability, "is_ci": r.ci, "is_tests": r.tests,
           "is_search": r.tests_search, "is_s": t_is, "mc_equiv_tests": n_mc,
           "ratio": n_mc / r.tests, "covers": r.ci[0] <= truth <= r.ci[1]}
    if p >= 1e-2:
        t = time.perf_counter()
        q = yield_estimate(m, mc, seed=0, accuracy="fast", executor=ex, search=False)
        row.update(mc=q.probability, mc_ci=q.ci, mc_s=time.perf_counter() - t,
                   mc_width=(q.ci[1] - q.ci[0]),
                   mc_width_at_is_tests=2 * Z95 * math.sqrt(truth * (1 - truth) / r.tests))
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--p", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument("--samples", type=int, default=400, help="importance samples")
    ap.add_argument("--mc", type=int, default=2000, help="plain Monte Carlo parts (P >= 1e-2)")
    ap.add_argument("--out", default=str(ROOT / "docs" / "benchmarks" / "yield.md"),
                    help="report file (written atomically; default docs/benchmarks/yield.md)")
    a = ap.parse_args(argv)
    lines = [f"# Statistical yield ({datetime.date.today().isoformat()})", "",
             f"Machine: {platform.processor() or platform.machine()}, Python "
             f"{platform.python_version()}, load average {load_average()}.  Command: "
             f"`{' '.join(['python benchmarks/bench_yield.py'] + list(argv if argv is not None else sys.argv[1:]))}`.",
             "", "Target (issue 25): at P = 1e-4, the rare-event method reaches the interval "
             "width of plain Monte Carlo with at least 10x fewer defect tests.", "",
             "| P (closed form) | IS estimate | IS 95 % CI | IS tests (search) | covers | "
             "plain MC tests for the same width | ratio | plain MC (n, CI) |",
             "|---|---|---|---|---|---|---|---|"]
    print("\n".join(lines[-2:]))
    for p in a.p:
        r = run(p, a.samples, a.mc)
        mc = (f"{a.mc}, [{r['mc_ci'][0]:.3g}, {r['mc_ci'][1]:.3g}], {r['mc_s']:.1f} s"
              if "mc" in r else "not run")
        lines.append(f"| {r['P']:.3g} | {r['is']:.3g} | [{r['is_ci'][0]:.3g}, "
                     f"{r['is_ci'][1]:.3g}] | {r['is_tests']} ({r['is_search']}), "
                     f"{r['is_s']:.1f} s | {r['covers']} | {r['mc_equiv_tests']:.3g} | "
                     f"{r['ratio']:.3g} | {mc} |")
        print(lines[-1], flush=True)
    atomic_write(Path(a.out), "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
