"""Tolerance synthesis: wall time, parallel speed-up, cost split and curve reuse.

Every figure is measured in one run of this script, and every ratio is against a
baseline measured in the same run.  Plain script::

    python benchmarks/bench_synthesis.py            # reciprocating cam and Geneva,
                                                    # presets fast and default, 1 and 2 workers
    python benchmarks/bench_synthesis.py --quick    # reciprocating cam, fast, 1 and 2 workers

Options ``--models``, ``--presets``, ``--workers`` and ``--reuse-vectors`` choose
the cases; ``--max-iter N`` caps every synthesis at N iterations (the times then
cover those iterations only, and the target is reported as not measured to the
end).  Without it every synthesis runs to its end: since the defect tests are
batched (``cspace.batch.margins``), a whole Geneva synthesis takes some 25 s
(``fast``) and 45 s (``default``) on two workers (``CAPS`` can cap a model again
should that change).  The target run::

    python benchmarks/bench_synthesis.py --models geneva --presets default \
        --workers 2 --uncapped --reuse-vectors 5 \
        --out docs/benchmarks/synthesis_target.md \
        --title "the default-preset Geneva synthesis run to the end (the target)"

``--uncapped`` runs every synthesis to its end.  The script
prints the tables and writes them to ``docs/benchmarks/synthesis.md`` (or ``--out``)
(written to a temporary file, then renamed).

Measurements
------------
synthesis   ``synthesize(model, preset, executor=ex)`` from the model's built-in
            design, once per model x preset x worker count, on a process pool
            (``make_executor("process", workers)``).  The pool is started and its
            workers have imported the library before the clock starts (the start
            time, with a 0.3 s hold per worker so that every worker gets a warm-up
            task, is reported on its own); the wall time is that of the
            ``synthesize`` call.  The speed-up of w workers is t(1 worker) / t(w
            workers) for the same model and preset.  The run's iterations, defects
            per iteration, e and status are compared between worker counts (the
            executor must not change the result).
cost split  the sum over the iterations of ``IterationRecord.times`` (reference,
            zones, checklist, defects, search, plan) as a share of the sum of the
            iterations' ``total``; ``other`` is what is left of it.  Defect tests
            per second: the tests of all iterations (check list plus bisection)
            over the time of the ``defects`` and ``search`` phases.
curve reuse the check list of iteration 1 is rebuilt as the loop builds it
            (nominal reference, operating zones, ``build_checklist``) and its
            first N vectors are tested serially in this process with
            ``is_defective(model, u, ref=ref)`` twice: reuse on (the reference's
            own ``CurveCache``, filled with the nominal curves) and reuse off (a
            fresh, empty ``CurveCache`` per call).  The two calls of a vector are
            made one after the other, in alternating order, so that a change of
            machine load hits both alike.  The ratio is the summed time off / on;
            the hit rate is that of the reference's cache over the "on" calls.
            The defective flags must be identical; if not, the script prints the
            differences and exits with status 1 without writing the report.

The machine may be loaded by other work: the load average at the start and the end
of the run is in the report, and every time is a single measurement.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import shlex
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchlib import fmt_seconds as _fmt_t, load_average, start_pool  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from cspace.accuracy import PRESETS, as_accuracy  # noqa: E402
from cspace.io import atomic_write  # noqa: E402

DOC = ROOT / "docs" / "benchmarks" / "synthesis.md"
MODELS = ("reciprocating_cam", "geneva")
PRESET_NAMES = ("fast", "default")
WORKERS = (1, 2)
REUSE_N = 30
#: iteration cap per model when neither --max-iter nor --uncapped is given
CAPS: dict = {}
QUICK = {"models": ("reciprocating_cam",), "presets": ("fast",), "workers": (1, 2),
         "reuse_vectors": 10}
PHASES = ("reference", "zones", "checklist", "defects", "search", "plan")

TITLE = "tolerance synthesis time, parallel speed-up and curve reuse"

# target of the work item
TARGET_MODEL, TARGET_PRESET, TARGET_WORKERS, TARGET_S = "geneva", "default", 2, 60.0
TARGET_TEXT = ("the default-preset Geneva synthesis finishes in under a minute on a "
               "2-core machine")


# ----------------------------------------------------------------------- helpers

def machine() -> dict:
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "nproc": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "platform": f"{platform.system()} {platform.machine()}"}


def _pct(x) -> str:
    return f"{100 * x:.1f} %"


def _signature(row: dict) -> tuple:
    """What must not depend on the executor."""
    return (row["status"], row["nit"], tuple(row["defects"]), row["e"])


# ---------------------------------------------------------------- (a) synthesis

def run_synthesis(name: str, preset: str, workers: int, log=None,
                  max_iter: int | None = None) -> dict:
    """One synthesis of a built-in model on a process pool of ``workers`` (at most
    ``max_iter`` iterations when given)."""
    from mechanisms.models import BUILTIN
    from synthesis import make_executor, synthesize
    from synthesis.progress import LogProgress, Progress
    model = BUILTIN[name]()
    with make_executor("process", workers) as ex:
        t_pool = start_pool(ex, workers)
        t0 = time.perf_counter()
        kw = {} if max_iter is None else {"max_iter": max_iter}
        r = synthesize(model, preset, executor=ex,
                       progress=LogProgress(log) if log is not None else Progress(), **kw)
        wall = time.perf_counter() - t0
    return summarize(name, preset, workers, r, wall, t_pool)


def summarize(name, preset, workers, r, wall, t_pool) -> dict:
    """The figures of one run, from its SynthesisResult."""
    phases = {k: float(sum(h.times.get(k, 0.0) for h in r.history)) for k in PHASES}
    total = float(sum(h.times.get("total", 0.0) for h in r.history))
    tests = int(sum(h.tests for h in r.history))
    t_tests = phases["defects"] + phases["search"]
    return {"model": name, "preset": preset, "workers": workers, "wall": wall,
            "pool_start": t_pool, "status": r.status.name, "nit": r.nit,
            "defects": list(r.defects_per_iteration()),
            "checklist": [h.counts.get("checklist", 0) for h in r.history],
            "e": float(r.e), "tol": float(np.max(r.initial_tol)), "units": r.units,
            "phases": phases, "iter_total": total, "tests": tests,
            "tests_per_s": tests / t_tests if t_tests > 0 else math.nan,
            "patience": r.patience, "two_sided": r.two_sided}


def speedups(rows: list) -> dict:
    """(model, preset, workers) -> t(1 worker) / t(workers), where both were measured."""
    base = {(r["model"], r["preset"]): r["wall"] for r in rows if r["workers"] == 1}
    out = {}
    for r in rows:
        b = base.get((r["model"], r["preset"]))
        if b is not None and r["wall"] > 0:
            out[(r["model"], r["preset"], r["workers"])] = b / r["wall"]
    return out


def consistency(rows: list) -> dict:
    """(model, preset, workers) -> True/False: same result as the fewest-worker run."""
    first: dict = {}
    out = {}
    for r in sorted(rows, key=lambda r: r["workers"]):
        key = (r["model"], r["preset"])
        sig = _signature(r)
        first.setdefault(key, sig)
        out[(r["model"], r["preset"], r["workers"])] = sig == first[key]
    return out


# -------------------------------------------------------------- (b) curve reuse

def iteration_one_checklist(model, acc):
    """The nominal reference and the check list of iteration 1, as the loop builds them."""
    from cspace.defects import reference
    from synthesis.loop import checklist_of, operating_zones
    ref = reference(model, acc, getattr(model, "deviation", None))
    zones = operating_zones(model, ref, acc)
    return ref, checklist_of(model, ref, zones, acc)


def reuse_run(name: str, preset: str, n: int) -> dict:
    """Defect tests of the first ``n`` check-list vectors, curve reuse on and off."""
    from cspace.cache import CurveCache
    from cspace.defects import is_defective
    from mechanisms.models import BUILTIN
    model = BUILTIN[name]()
    acc = as_accuracy(preset)
    ref, cl = iteration_one_checklist(model, acc)
    vecs = [v.u for v in cl.vectors[:n]]
    # warm-up (first-call costs of this process), outside the reference's cache
    if vecs:
        is_defective(model, vecs[0], ref=ref, cache=CurveCache())
    h0, m0 = ref.cache.hits, ref.cache.misses
    t_on = t_off = 0.0
    on, off = [], []
    for i, u in enumerate(vecs):
        for mode in (("on", "off") if i % 2 == 0 else ("off", "on")):
            t = time.perf_counter()
            if mode == "on":
                res = is_defective(model, u, ref=ref)
                t_on += time.perf_counter() - t
                on.append(res)
            else:
                res = is_defective(model, u, ref=ref, cache=CurveCache())
                t_off += time.perf_counter() - t
                off.append(res)
    hits, misses = ref.cache.hits - h0, ref.cache.misses - m0
    mismatch = [i for i, (a, b) in enumerate(zip(on, off)) if a.defective != b.defective]
    dev = [abs(a.max_deviation - b.max_deviation) for a, b in zip(on, off)
           if math.isfinite(a.max_deviation) and math.isfinite(b.max_deviation)]
    return {"model": name, "preset": preset, "checklist": len(cl.vectors), "n": len(vecs),
            "t_on": t_on, "t_off": t_off,
            "ratio": t_off / t_on if t_on > 0 else math.nan,
            "hits": hits, "misses": misses,
            "hit_rate": hits / (hits + misses) if hits + misses else math.nan,
            "cache": dict(ref.cache.stats),
            "defective": sum(r.defective for r in on), "mismatch": mismatch,
            "max_dev_diff": max(dev) if dev else 0.0}


# ------------------------------------------------------------------- rendering

def synthesis_table(rows: list) -> list:
    """Markdown lines of the synthesis table."""
    sp, same = speedups(rows), consistency(rows)
    out = ["| model | preset | workers | pool start | synthesis wall time | speed-up vs 1 worker |"
           " iterations | status | check list per iteration | defects per iteration |"
           " e / largest tolerance | defect tests | tests/s | same result as fewest workers |",
           "|---|---|---:|---:|---:|---:|---:|---|---|---|---|---:|---:|---|"]
    for r in rows:
        key = (r["model"], r["preset"], r["workers"])
        s = sp.get(key)
        out.append(
            f"| {r['model']} | {r['preset']} | {r['workers']} | {_fmt_t(r['pool_start'])} | "
            f"{_fmt_t(r['wall'])} | {'—' if s is None else f'{s:.2f}×'} | {r['nit']} | "
            f"{r['status']} | {', '.join(map(str, r['checklist']))} | "
            f"{', '.join(map(str, r['defects']))} | "
            f"{r['e']:.4g} / {r['tol']:.4g} {r['units']} | {r['tests']} | "
            f"{r['tests_per_s']:.1f} | {'yes' if same.get(key, True) else '**no**'} |")
    return out


def split_table(rows: list) -> list:
    """Markdown lines of the cost split (share of the summed iteration totals)."""
    out = ["| model | preset | workers | reference | zones | check list | defect tests |"
           " search | plan | other | sum of iteration totals |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        tot = r["iter_total"]
        ph = r["phases"]
        if tot > 0:
            cells = [_pct(ph[k] / tot) for k in PHASES]
            cells.append(_pct(max(0.0, tot - sum(ph.values())) / tot))
        else:
            cells = ["—"] * (len(PHASES) + 1)
        out.append(f"| {r['model']} | {r['preset']} | {r['workers']} | " + " | ".join(cells)
                   + f" | {_fmt_t(tot)} |")
    return out


def reuse_table(reuse: list) -> list:
    """Markdown lines of the curve-reuse table."""
    out = ["| model | preset | check list (iteration 1) | vectors timed | defective |"
           " reuse off | reuse on | off / on | hit rate (on calls) | hits / misses |"
           " cache entries | same defective flags |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in reuse:
        ok = "yes" if not r["mismatch"] else f"**no** (vectors {r['mismatch']})"
        rate = _pct(r["hit_rate"]) if math.isfinite(r["hit_rate"]) else "—"
        out.append(f"| {r['model']} | {r['preset']} | {r['checklist']} | {r['n']} | "
                   f"{r['defective']} | {_fmt_t(r['t_off'])} | {_fmt_t(r['t_on'])} | "
                   f"{r['ratio']:.2f}× | {rate} | {r['hits']} / {r['misses']} | "
                   f"{r['cache']['entries']} | {ok} |")
    return out


def target_line(rows: list, nproc=None) -> str:
    """The target statement and whether this run met it."""
    cand = [r for r in rows if r["model"] == TARGET_MODEL and r["preset"] == TARGET_PRESET]
    if not cand:
        return f"- Target: {TARGET_TEXT} — not measured in this run."
    two = [r for r in cand if r["workers"] == TARGET_WORKERS]
    r = two[0] if two else min(cand, key=lambda r: r["wall"])
    if r["status"] == "MAX_ITER":
        return (f"- Target: {TARGET_TEXT} — not measured to the end in this run: its first "
                f"{r['nit']} iteration(s) took {_fmt_t(r['wall'])} with {r['workers']} "
                f"worker(s) ({'**NOT met**' if r['wall'] >= TARGET_S else 'open'}: the run "
                "was capped, and the whole synthesis takes longer).")
    met = r["wall"] < TARGET_S
    where = f"{r['workers']} worker(s)"
    if nproc is not None and nproc != 2:
        where += f", on a {nproc}-core machine"
    return (f"- Target: {TARGET_TEXT} — {_fmt_t(r['wall'])} with {where}, "
            f"status {r['status']}: {'met' if met else '**NOT met**'}.")


def report(rows: list, reuse: list, info: dict, args, loads: tuple, total: float) -> str:
    L: list = []
    P = L.append
    P(f"# Benchmark: {getattr(args, 'title', None) or TITLE}")
    P("")
    cmd = " ".join(["python", "benchmarks/bench_synthesis.py"]
                   + [shlex.quote(str(a)) for a in (getattr(args, "argv", None) or [])])
    P(f"Script: `benchmarks/bench_synthesis.py` (run `{cmd}`)."
      "  Every figure below was measured in one run of that script; every ratio is against"
      " a baseline measured in the same run.")
    P("")
    P(f"- date: {info['date']}")
    P(f"- machine: {info['nproc']} cores ({info['platform']}), Python {info['python']},"
      f" numpy {info['numpy']}")
    mode = "quick" if args.quick else "full"
    P(f"- mode: {mode} (models {', '.join(args.models)}; presets {', '.join(args.presets)};"
      f" workers {', '.join(map(str, args.workers))}; reuse vectors {args.reuse_vectors}"
      + (f"; iterations capped at {args.max_iter}" if getattr(args, "max_iter", None) else "")
      + "".join(f"; {m} capped at {c} iteration(s)" for m, c in _caps(args).items()
                if m in args.models and not getattr(args, "max_iter", None))
      + ");"
      f" whole run {total:.0f} s")
    settings = sorted({(r["patience"], r["two_sided"]) for r in rows})
    if settings:
        P("- synthesis settings (the defaults): "
          + "; ".join(f"patience {p}, two-sided {'on' if t else 'off'}" for p, t in settings))
    P(f"- load average (1, 5, 15 min) at the start {loads[0]}, at the end {loads[1]}")
    P("")
    P("## Method")
    P("")
    P("- **synthesis**: `synthesize(model, preset, executor=ex)` from the built-in design, once"
      " per model × preset × worker count, on a process pool (`make_executor(\"process\","
      " workers)`).  The pool's workers are started (and have imported the library) before"
      " the clock starts; that start time, which includes a 0.3 s hold of each worker, is"
      " its own column.  The wall time is that of the"
      " `synthesize` call.  Speed-up: t(1 worker) / t(w workers), same model and preset.")
    P("- **cost split**: `IterationRecord.times` summed over the iterations, as a share of"
      " the summed iteration totals (`other` is the rest).  Each worker builds the nominal"
      " reference of each design once more for its own defect tests; that cost is inside"
      " `defect tests`.  Tests/s: defect tests (check list and bisection) per second of the"
      " `defects` and `search` phases.")
    P("- **curve reuse**: the first N vectors of the iteration-1 check list (built as the loop"
      " builds it) tested serially with `is_defective(model, u, ref=ref)`: reuse on (the"
      " reference's `CurveCache`, filled with the nominal curves) and off (a fresh, empty"
      " `CurveCache` per call), the two calls of a vector one after the other in alternating"
      " order.  The run stops without a report if the defective flags differ.")
    P("")
    P("## Synthesis")
    P("")
    L.extend(synthesis_table(rows))
    P("")
    P("### Where the time goes")
    P("")
    L.extend(split_table(rows))
    P("")
    P("## Curve reuse in the defect test")
    P("")
    L.extend(reuse_table(reuse))
    if reuse:
        worst = max(r["max_dev_diff"] for r in reuse)
        P("")
        P(f"Largest difference of `max_deviation` between reuse on and off: {worst:.3g}.")
    P("")
    P("## Target")
    P("")
    P(target_line(rows, info.get("nproc")))
    P("")
    notes = notes_lines(rows, info, loads, reuse)
    if notes:
        P("## Notes")
        P("")
        L.extend(notes)
        P("")
    return "\n".join(L) + "\n"


def notes_lines(rows: list, info: dict, loads: tuple, reuse: list = ()) -> list:
    out = []
    nproc = info.get("nproc") or 1
    busy = [la for la in loads if la is not None and la[0] >= 0.5 * nproc]
    if busy:
        out.append(f"- The machine carried other load during the run (1-minute load average"
                   f" {', '.join(str(la[0]) for la in busy)} on {nproc} cores): the times are"
                   " upper bounds, and the speed-up of more workers is understated when the"
                   " cores were already busy.")
    if any(r["workers"] > nproc for r in rows):
        out.append(f"- Some runs used more workers than the machine's {nproc} cores.")
    healthy = [f"{r['model']} {r['preset']}" for r in reuse if r["n"] and not r["defective"]]
    if healthy:
        out.append("- No vector timed in the reuse test of " + ", ".join(healthy) + " is"
                   " defective: there the flag comparison covers healthy variants only.")
    same = consistency(rows)
    bad = [k for k, v in same.items() if not v]
    if bad:
        out.append("- The result changed with the worker count for "
                   + ", ".join(f"{m} {p} ({w} workers)" for m, p, w in bad)
                   + "; the executor should not change it.")
    return out


# ------------------------------------------------------------------------ main

def _caps(args) -> dict:
    """Iteration caps per model of this run (empty with --uncapped or --max-iter)."""
    if getattr(args, "uncapped", False) or getattr(args, "max_iter", None):
        return {}
    return dict(CAPS)


def _check_args(ap, args):
    from mechanisms.models import BUILTIN
    for m in args.models:
        if m not in BUILTIN:
            ap.error(f"unknown model {m!r}; allowed: {sorted(BUILTIN)}")
    for p in args.presets:
        if p not in PRESETS:
            ap.error(f"unknown preset {p!r}; allowed: {sorted(PRESETS)}")
    if any(w < 1 for w in args.workers):
        ap.error("--workers must be positive")
    if args.reuse_vectors < 1:
        ap.error("--reuse-vectors must be positive")
    if args.max_iter is not None and args.max_iter < 1:
        ap.error("--max-iter must be positive")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="reciprocating cam, preset fast, workers 1 2, 10 reuse vectors")
    ap.add_argument("--models", nargs="+", help=f"default: {' '.join(MODELS)}")
    ap.add_argument("--presets", nargs="+", help=f"default: {' '.join(PRESET_NAMES)}")
    ap.add_argument("--workers", nargs="+", type=int, help="process-pool sizes (default: 1 2)")
    ap.add_argument("--reuse-vectors", type=int,
                    help=f"check-list vectors in the reuse test (default {REUSE_N})")
    ap.add_argument("--max-iter", type=int,
                    help="cap every synthesis at this many iterations (default: run each to "
                         "its end); a capped run's wall time covers those iterations only")
    ap.add_argument("--uncapped", action="store_true",
                    help="run every synthesis to its end, whatever CAPS says (the default "
                         "while CAPS is empty)")
    ap.add_argument("--out", type=Path, default=DOC, help="markdown report (default: %(default)s)")
    ap.add_argument("--title", help=f"report title after 'Benchmark: ' (default: {TITLE!r}); "
                                    "give another one with --out for a second report")
    args = ap.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    dflt = QUICK if args.quick else {"models": MODELS, "presets": PRESET_NAMES,
                                     "workers": WORKERS, "reuse_vectors": REUSE_N}
    for k, v in dflt.items():
        if getattr(args, k) is None:
            setattr(args, k, v)
    args.models, args.presets = list(args.models), list(args.presets)
    args.workers = sorted(set(args.workers))
    _check_args(ap, args)

    t_start = time.perf_counter()
    load0 = load_average()
    info = machine()
    print(f"synthesis benchmark ({'quick' if args.quick else 'full'}): {info['nproc']} cores, "
          f"Python {info['python']}, numpy {info['numpy']}, load {load0}", flush=True)

    # (b) first: it is short and a wrong result stops the run before the long part
    reuse = []
    for name in args.models:
        for preset in args.presets:
            print(f"reuse: {name} {preset} ...", flush=True)
            r = reuse_run(name, preset, args.reuse_vectors)
            reuse.append(r)
            print(f"  {r['n']} of {r['checklist']} vectors: off {r['t_off']:.2f} s, "
                  f"on {r['t_on']:.2f} s, ratio {r['ratio']:.2f}, hit rate "
                  f"{r['hit_rate']:.3f}", flush=True)
    bad = [r for r in reuse if r["mismatch"]]
    for r in bad:
        print(f"error: {r['model']} {r['preset']}: curve reuse changed the defective flag of "
              f"check-list vectors {r['mismatch']}", file=sys.stderr)

    # (a)
    rows = []
    if not bad:
        for name in args.models:
            for preset in args.presets:
                for w in args.workers:
                    print(f"synthesis: {name} {preset}, {w} worker(s) ...", flush=True)
                    cap = args.max_iter or _caps(args).get(name)
                    r = run_synthesis(name, preset, w, log=sys.stdout, max_iter=cap)
                    rows.append(r)
                    print(f"  {r['wall']:.2f} s (pool start {r['pool_start']:.2f} s), "
                          f"{r['nit']} iterations, defects {r['defects']}, e {r['e']:.4g}, "
                          f"{r['status']}", flush=True)

    load1 = load_average()
    text = report(rows, reuse, info, args, (load0, load1), time.perf_counter() - t_start)
    print(text)
    if bad:
        print("error: curve reuse changed defect results; the report was not written",
              file=sys.stderr)
        return 1
    atomic_write(args.out, text)
    print(f"written: {args.out.relative_to(ROOT) if args.out.is_relative_to(ROOT) else args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
