"""Statistical yield of every built-in model's initial and final box.

For each built-in model, the initial box (the model as shipped) and the final
box of its synthesis case study (the state of ``benchmarks/runs/<model>_<preset>/
checkpoint.json`` written by ``benchmarks/case_studies.py``) are estimated by
:func:`synthesis.yield_estimate` at process capabilities Cp = 1 and 1.33 (every
parameter a normal truncated at its tolerance, sigma = t / (3 Cp)), plain Monte
Carlo with the design-point search for contributors.  Parts are compared with
the initial design (the design intent), as the synthesis does.

Plain script::

    python benchmarks/yield_case_studies.py                 # 2000 samples each
    python benchmarks/yield_case_studies.py --samples 500 --models reciprocating_cam

It writes ``docs/benchmarks/yield_case_studies.md`` and ``.json`` (atomically).
A model without a case-study checkpoint gets its initial box only.
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.benchlib import load_average  # noqa: E402
from cspace.io import atomic_write  # noqa: E402


def final_model(model, name: str, preset: str):
    """The final box of the model's case study, or None."""
    from synthesis.checkpoint import read_checkpoint
    path = ROOT / "benchmarks" / "runs" / f"{name}_{preset}" / "checkpoint.json"
    if not path.exists():
        return None
    state, _ = read_checkpoint(path)
    return model.with_nominal(state.nominal).with_tolerances(state.tol)


def estimate(model, intent, cp, n, preset, executor, seed, method="mc"):
    from synthesis import yield_estimate
    t = time.perf_counter()
    r = yield_estimate(model, n, method=method, seed=seed, accuracy=preset, cp=cp,
                       intent=intent, executor=executor)
    return r, time.perf_counter() - t


def _top(contrib: dict, k: int = 3) -> str:
    items = sorted(contrib.items(), key=lambda kv: -kv[1])[:k]
    return ", ".join(f"{n} {100 * s:.0f} %" for n, s in items) or "—"


def main(argv=None):
    from mechanisms.models import BUILTIN
    from synthesis.target import ppm_text
    from synthesis.executors import make_executor
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=sorted(BUILTIN))
    p.add_argument("--samples", type=int, default=2000)
    p.add_argument("--preset", default="fast")
    p.add_argument("--cps", nargs="+", type=float, default=[1.0, 1.33])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks" / "yield_case_studies"))
    a = p.parse_args(argv)
    rows = []
    t0 = time.perf_counter()
    la0 = load_average()
    with make_executor("process", a.workers) as ex:
        for name in a.models:
            m = BUILTIN[name]()
            boxes = [("initial", m)]
            fm = final_model(m, name, a.preset)
            if fm is not None:
                boxes.append(("final", fm))
            for box, model in boxes:
                for cp in a.cps:
                    r, dt = estimate(model, m, cp, a.samples, a.preset, ex, a.seed)
                    row = {"model": name, "box": box, "cp": cp, "time_s": dt, **r.to_dict()}
                    rows.append(row)
                    print(f"{name} {box} Cp {cp}: {r!r} ({dt:.0f} s)", flush=True)
                    if r.failures == 0 and box == "initial":
                        # none in the plain samples: the rare-event method
                        r, dt = estimate(model, m, cp, a.samples, a.preset, ex, a.seed, "is")
                        rows.append({"model": name, "box": box, "cp": cp, "time_s": dt,
                                     **r.to_dict()})
                        print(f"{name} {box} Cp {cp} (is): {r!r} ({dt:.0f} s)", flush=True)
    head = [f"# Statistical yield of the built-in models ({datetime.date.today().isoformat()})",
            "",
            f"Script: `benchmarks/yield_case_studies.py` (run `python "
            f"benchmarks/yield_case_studies.py {' '.join(sys.argv[1:])}`).  Machine: "
            f"{platform.processor() or platform.machine()}, Python "
            f"{platform.python_version()}; whole run {time.perf_counter() - t0:.0f} s; load "
            f"average at the start {la0}, at the end {load_average()}.", "",
            f"Every parameter a normal truncated at its tolerance, sigma = t / (3 Cp); "
            f"{a.samples} plain Monte Carlo samples per row (seed {a.seed}), preset "
            f"`{a.preset}`; parts compared with the initial design.  *Final* is the box "
            "of the model's synthesis case study (`benchmarks/case_studies.py`).  The "
            "interval is Clopper-Pearson 95 %.  Contributors: shares of the margin "
            "variance at the most probable failure point (FORM), largest three.", "",
            "Where the plain samples of an initial box find no failure, the rare-event "
            "method follows (`is`: design points from the defective probed box corners, "
            "then importance sampling around them; its interval is the weighted normal one, "
            "or the conservative [0, 1] (here [0, 1000000] ppm) where the failing samples' "
            "weights are too uneven to trust their standard error (fewer than 10 "
            "effective); "
            "a box without a defective corner has no design point and reports none).", "",
            "| model | box | Cp | method | failing / samples | P (ppm) | 95 % interval (ppm) | "
            "FORM (ppm) | by reason | contributors | tests | time |",
            "|---|---|---:|---|---:|---:|---|---:|---|---|---:|---:|"]
    for r in rows:
        lo, hi = r["ci_ppm"]
        form = "—" if r["p_form"] is None else ppm_text(1e6 * r["p_form"])
        reasons = ", ".join(f"{k} {ppm_text(1e6 * v)}" for k, v in sorted(r["by_reason"].items())
                            if v > 0) or "—"
        head.append(f"| {r['model']} | {r['box']} | {r['cp']:g} | {r['method']} | {r['failures']}/"
                    f"{r['samples']} | {ppm_text(r['ppm'])} | [{ppm_text(lo)}, {ppm_text(hi)}] | {form} | "
                    f"{reasons} | {_top(r['contributors'])} | {r['tests']} | "
                    f"{r['time_s']:.0f} s |")
    out = Path(a.out)
    atomic_write(out.with_suffix(".md"), "\n".join(head) + "\n")
    atomic_write(out.with_suffix(".json"), json.dumps(rows, indent=1, default=str) + "\n")


if __name__ == "__main__":
    main()
