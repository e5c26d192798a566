"""Batched defect margins against the full per-variant defect test.

Every figure is measured in one run of this script, and every ratio is against a
baseline measured in the same run on the same vectors.  Plain script::

    python benchmarks/bench_batch.py                     # Geneva, fast and default
    python benchmarks/bench_batch.py --models geneva reciprocating_cam --presets fast
    python benchmarks/bench_batch.py --quick             # fewer baseline tests

It prints the tables and writes them to ``docs/benchmarks/batch.md`` (atomically).

Measurements (one core: the serial executor, in this process)
-------------------------------------------------------------
full        ``cspace.defects.is_defective`` of ``--baseline`` vectors of the
            first check list (every k-th, in order), per vector.
batch       ``cspace.batch.margins.defect_margins`` of the whole first check
            list (and of a seeded Monte Carlo of the box: ``--mc`` samples, half
            corners, seed 0), per vector, fall-backs to the full test included.
            The nominal plan (computed once per design) is timed apart.
one-row     a call with one vector (the median of 5, fall-back off): what a
call        call costs before its rows (the walk over the candidate curves).
compiled    the same batch with the compiled kernel (``cspace.batch.compiled``,
            numba, when installed), verdicts checked equal.
agreement   the batch's verdicts against the full test's on the baseline
            vectors (and, with ``--verify``, on every vector).
fallbacks   vectors the margins could not certify (the full test decided).
workers     the whole check list and ``--mc-workers`` box samples (seed 1, half
            corners) as synthesis and ``synthesis.verify`` test them:
            ``synthesis.executors.run_batched`` on a process pool of
            ``--workers`` workers, started (and every worker's nominal
            reference made) before the clock; verdicts checked equal to the
            one-core batch's on the check list.
zones       ``synthesis.loop.operating_zones`` (the contact zones synthesis
            computes first), as the library runs it (each stage's vectors in
            stacked passes, ``cspace.zones._Evaluator.many``) against one vector
            at a time (the stages' look-ahead switched off); the bands' extreme
            vectors and evaluation counts checked equal.

The check list is the one synthesis builds in its first iteration
(:func:`synthesis.loop.checklist_of`).
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

from benchmarks.benchlib import fmt_seconds, load_average  # noqa: E402
from cspace.io import atomic_write  # noqa: E402


def measure(name: str, preset: str, baseline: int, mc: int, verify: bool, workers: int = 0,
            mc_workers: int = 0) -> dict:
    from cspace.batch.margins import defect_margins, plans_of
    from cspace.defects import is_defective, reference
    from mechanisms.models import BUILTIN
    from synthesis.loop import checklist_of, operating_zones
    from synthesis.verify import box_samples
    m = BUILTIN[name]()
    ref = reference(m, preset)
    t = time.perf_counter()
    plans_of(ref)
    t_plan = time.perf_counter() - t
    t = time.perf_counter()
    zones = operating_zones(m, ref, ref.accuracy)
    t_zones = time.perf_counter() - t
    zone_row = _zones_one_at_a_time(m, ref, zones, t_zones)
    U = np.array([v.u for v in checklist_of(m, ref, zones, ref.accuracy).vectors])
    k = max(1, len(U) // baseline)
    base = U[::k][:baseline]
    t = time.perf_counter()
    full = [is_defective(m, u, ref=ref).defective for u in base]
    t_full = (time.perf_counter() - t) / len(base)
    from cspace.batch import compiled
    was = compiled.ENABLED
    from cspace.batch.kernels import reset_kernel_values
    compiled.ENABLED = False                # the library's default kernel
    try:
        reset_kernel_values()
        t = time.perf_counter()
        mb = defect_margins(m, U, ref)
        t_batch = (time.perf_counter() - t) / len(U)
        paths = reset_kernel_values()
        t_compiled = None
        if compiled.AVAILABLE:
            compiled.ENABLED = True
            defect_margins(m, U[:1], ref)   # compiled-kernel load (on-disk cache) apart
            t = time.perf_counter()
            mk = defect_margins(m, U, ref)
            t_compiled = (time.perf_counter() - t) / len(U)
            if not (np.array_equal(mk.defective, mb.defective)
                    and np.array_equal(mk.certified, mb.certified)):
                raise SystemExit(f"{name} {preset}: the compiled kernel's verdicts differ")
    finally:
        compiled.ENABLED = was
    one = []
    for i in range(5):
        t = time.perf_counter()
        defect_margins(m, U[i:i + 1], ref, fallback=False)
        one.append(time.perf_counter() - t)
    agree = [mb.defective[i * k] == full[i] for i in range(len(base))]
    out = {"model": name, "preset": preset, "vectors": len(U), "baseline": len(base),
           "plan": t_plan, "full": t_full, "batch": t_batch, "ratio": t_full / t_batch,
           "compiled": t_compiled, "one_row": float(np.median(one)),
           "fallback": mb.n_fallback, "defective": int(mb.defective.sum()),
           "fused_share": paths["fused"] / max(1, paths["fused"] + paths["numpy"]),
           "kernel_values": paths["fused"] + paths["numpy"],
           "agree": int(sum(agree)), "verified": None, "zones": zone_row}
    if verify:
        allfull = [is_defective(m, u, ref=ref).defective for u in U]
        out["verified"] = (int(sum(a == b for a, b in zip(allfull, mb.defective))), len(U))
    if mc:
        S = box_samples(m.nominal, m.tol, mc, seed=0)
        t = time.perf_counter()
        mm = defect_margins(m, S, ref)
        out.update(mc=mc, mc_time=time.perf_counter() - t, mc_fallback=mm.n_fallback,
                   mc_defective=int(mm.defective.sum()))
    if workers:
        out["pool"] = _on_workers(name, m, preset, ref.d, U, mb.defective, workers,
                                  mc_workers)
    return out


def _on_workers(name, m, preset, d, U, defective, workers: int, samples: int) -> dict:
    """The check list and ``samples`` box samples through
    :func:`synthesis.executors.run_batched` on a pool of ``workers``."""
    from synthesis import make_executor
    from synthesis.executors import BatchStats, run_batched
    from synthesis.verify import box_samples
    with make_executor("process", workers) as ex:
        # every worker makes its reference before the clock: one task each
        run_batched(ex, m, U[:2 * workers], preset, d)
        st = BatchStats()
        t = time.perf_counter()
        res = run_batched(ex, m, U, preset, d, stats=st)
        t_list = time.perf_counter() - t
        if [r.defective for r in res] != [bool(x) for x in defective]:
            raise SystemExit(f"{name} {preset}: the pool's verdicts differ from one core's")
        out = {"workers": workers, "checklist": t_list, "fallback": st.get("fallback", 0)}
        if samples:
            S = box_samples(m.nominal, m.tol, samples, seed=1)
            st = BatchStats()
            t = time.perf_counter()
            res = run_batched(ex, m, S, preset, d, stats=st)
            out.update(mc=samples, mc_time=time.perf_counter() - t,
                       mc_defective=sum(r.defective for r in res),
                       mc_fallback=st.get("fallback", 0))
    return out


def _zones_one_at_a_time(m, ref, zones, t_zones) -> dict:
    """The zones again with each stage asking one vector at a time; the same
    extremes and counts are checked."""
    from unittest import mock
    from cspace import zones as zmod
    from synthesis.loop import operating_zones
    with mock.patch.object(zmod._CurveZone, "prefetch", lambda self, us: None):
        t = time.perf_counter()
        single = operating_zones(m, ref, ref.accuracy)
        t_single = time.perf_counter() - t
    bands = [b for z in zones for b in z.bands]
    other = [b for z in single for b in z.bands]
    same = sum(a.n_evaluated == b.n_evaluated and np.array_equal(a.u_upper, b.u_upper)
               and np.array_equal(a.u_lower, b.u_lower) for a, b in zip(bands, other))
    worst = max((float(np.nanmax(np.abs(np.r_[a.upper - b.upper, a.lower - b.lower])))
                 for a, b in zip(bands, other) if np.isfinite(a.upper).any()), default=0.0)
    return {"bands": len(bands), "stacked": t_zones, "single": t_single, "same": same,
            "worst": worst, "evaluated": sum(b.n_evaluated for b in bands),
            "fallbacks": sum(z.stats.get("stack_fallbacks", 0) for z in zones)}


def render(rows, args) -> str:
    la = load_average()
    lines = [f"# Batched defect margins ({datetime.date.today().isoformat()})", "",
             f"Machine: {platform.processor() or platform.machine()}, Python "
             f"{platform.python_version()}, load average {la}.  Command: "
             f"`python benchmarks/bench_batch.py {' '.join(sys.argv[1:])}`.", "",
             "Target (issue 21): defect tests per second on the Geneva pair, batched "
             "against the full per-variant test, same vectors, one core: >= 50x at "
             "`default`.", "",
             "`batched / vector` runs the library's default path: the fused kernel "
             "(`cspace.batch.fused`) where it covers a curve, numpy's otherwise, and the "
             "compiled bookkeeping of the bounds (`cspace.batch.fused_bounds`); `fused "
             "share` is the share of the batch's curve values the fused kernel computed "
             "(the rest ran the numpy code: the same numbers).  `compiled kernel` is the "
             "same batch, same vectors, with the numba loop of `cspace.batch.compiled` "
             "(identical verdicts, checked in the run; off by default).", "",
             "`one-row call` is a batched call with one vector: what a call costs before "
             "its rows.", "",
             "| model | preset | check list | plan (once) | full test / vector | batched / "
             "vector | ratio | one-row call | fused share | compiled kernel / vector | "
             "fall-backs | agreement on the baseline | all verified |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        v = r["verified"]
        lines.append(
            f"| {r['model']} | {r['preset']} | {r['vectors']} ({r['defective']} defective) | "
            f"{fmt_seconds(r['plan'])} | {fmt_seconds(r['full'])} | "
            f"{fmt_seconds(r['batch'])} | {r['ratio']:.1f}x | "
            f"{'—' if r.get('one_row') is None else fmt_seconds(r['one_row'])} | "
            f"{100 * r['fused_share']:.1f} % of {r['kernel_values']:,} | "
            f"{'—' if r.get('compiled') is None else fmt_seconds(r['compiled'])} | {r['fallback']} | "
            f"{r['agree']}/{r['baseline']} | {'—' if v is None else f'{v[0]}/{v[1]}'} |")
    if any("mc" in r for r in rows):
        lines += ["", "Monte Carlo of the initial box (seed 0, half corners), batched, one "
                      "core:", "", "| model | preset | samples | time | defective | "
                      "fall-backs |", "|---|---|---|---|---|---|"]
        for r in rows:
            if "mc" in r:
                lines.append(f"| {r['model']} | {r['preset']} | {r['mc']} | "
                             f"{fmt_seconds(r['mc_time'])} | {r['mc_defective']} | "
                             f"{r['mc_fallback']} |")
    if any("pool" in r for r in rows):
        lines += ["", "On a process pool (`synthesis.executors.run_batched`, as synthesis and "
                      "`synthesis.verify` run them; targets, issue 21: one pass over the Geneva "
                      "check list within 3 s and 2,000 box samples within 10 s on two cores):",
                  "", "| model | preset | workers | check list | time | fall-backs | box "
                      "samples (seed 1) | time | defective | fall-backs |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            q = r.get("pool")
            if q is None:
                continue
            mc = (f"{q['mc']} | {fmt_seconds(q['mc_time'])} | {q['mc_defective']} | "
                  f"{q['mc_fallback']}" if "mc" in q else "— | — | — | —")
            lines.append(f"| {r['model']} | {r['preset']} | {q['workers']} | {r['vectors']} | "
                         f"{fmt_seconds(q['checklist'])} | {q['fallback']} | {mc} |")
    lines += ["", "Contact zones of the operating region (`synthesis.loop.operating_zones`), "
                  "one core: stacked passes against one vector at a time (extreme vectors "
                  "and counts equal per band; largest difference of the band edges, C-space "
                  "metric):", "",
              "| model | preset | bands | vectors evaluated | one at a time | stacked | ratio | "
              "same extremes | band edges differ by | left to the single call |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        z = r["zones"]
        lines.append(f"| {r['model']} | {r['preset']} | {z['bands']} | {z['evaluated']} | "
                     f"{fmt_seconds(z['single'])} | {fmt_seconds(z['stacked'])} | "
                     f"{z['single'] / z['stacked']:.2f}x | {z['same']}/{z['bands']} | "
                     f"{z['worst']:.1e} | {z.get('fallbacks', '—')} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=["geneva"])
    p.add_argument("--presets", nargs="+", default=["fast", "default"])
    p.add_argument("--baseline", type=int, default=40, help="full tests timed per case")
    p.add_argument("--mc", type=int, default=500, help="Monte Carlo samples (0: none)")
    p.add_argument("--verify", action="store_true", help="full test of every vector too")
    p.add_argument("--workers", type=int, default=2,
                   help="process-pool workers for the pool rows (0: none)")
    p.add_argument("--mc-workers", type=int, default=2000,
                   help="box samples tested on the pool (0: none)")
    p.add_argument("--quick", action="store_true", help="10 baseline tests, 100 samples")
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks" / "batch.md"))
    a = p.parse_args(argv)
    if a.quick:
        a.baseline, a.mc, a.mc_workers = 10, 100, 200
    rows = []
    for name in a.models:
        for preset in a.presets:
            r = measure(name, preset, a.baseline, a.mc, a.verify, a.workers, a.mc_workers)
            print(f"{name} {preset}: full {fmt_seconds(r['full'])}, batched "
                  f"{fmt_seconds(r['batch'])} per vector ({r['ratio']:.1f}x), "
                  f"{r['fallback']} fall-backs, agreement {r['agree']}/{r['baseline']}",
                  flush=True)
            rows.append(r)
    text = render(rows, a)
    print(text)
    atomic_write(Path(a.out), text)


if __name__ == "__main__":
    main()
