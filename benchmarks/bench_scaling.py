"""Scaling with the worker count: synthesis and Monte Carlo on process pools and dask.

Every figure is measured in one run of this script, and every ratio is against a
baseline measured in the same run.  Plain script::

    python benchmarks/bench_scaling.py            # serial, process pool and dask
                                                  # LocalCluster with 1 and 2 workers
    python benchmarks/bench_scaling.py --quick    # serial and 2 workers, fewer samples

Options ``--workers``, ``--executors``, ``--cam-samples``, ``--geneva-samples`` and
``--no-synthesis`` choose the cases.  It prints the tables and writes them to
``docs/benchmarks/scaling.md`` (written to a temporary file, then renamed).

Cases
-----
synthesis          ``synthesize(geneva(), "fast", executor=ex)`` from the built-in
                   design (the main job; the reciprocating cam's synthesis takes
                   about a second since the defect tests are batched, too little
                   to share between workers).
Monte Carlo        ``monte_carlo(model, n, seed=0, accuracy="fast", executor=ex)`` of
                   the built-in tolerance box, for the reciprocating cam and for the
                   Geneva model (``n`` from ``--cam-samples`` / ``--geneva-samples``).

Executors
---------
serial    ``make_executor("serial")``: every defect test in this process.  The
          baseline of every ratio.
process   ``make_executor("process", w)``: a fresh local process pool of w workers
          for each case.
dask      a fresh ``distributed.LocalCluster(n_workers=w, threads_per_worker=1,
          processes=True)`` for each case, used through the path of the command
          line, ``make_executor("dask", scheduler=cluster.scheduler_address)``
          (``Client(address).get_executor()``).

Measurements
------------
start       the executor is opened and every worker has run a warm-up task
            (import of the defect test, then a 0.5 s hold so that the next warm-up
            task goes to another worker) before the clock starts; that time (for
            dask including the cluster start and the client connection) is its own
            column.  Each worker's process id is known from its warm-up task.
wall time   that of the ``synthesize`` / ``monte_carlo`` call alone.
speed-up    t(serial) / t(executor, w workers) for the same case; efficiency is the
            speed-up over w (the serial run counts as one worker).
CPU         user + system CPU seconds of this process and of all its child
            processes (pool workers; dask worker processes) during the call
            (``psutil``), also as a multiple of the serial run's CPU; "cores busy" is
            CPU seconds over wall seconds.  A 1-worker run that uses more than 1.2
            times the serial CPU gets a note.  Below w,
            the workers waited: for work, or for a core the machine gave to other
            processes.
same result synthesis: ``json.dumps(result.to_dict(timing=False), sort_keys=True)``
            equal to that of the serial run; Monte Carlo: the same defective sample
            indices and the same defect reasons.  A difference is printed (the
            first differing JSON paths) and marked in the report, and the script
            exits with status 1 after writing it: the executor must not change a
            result.
serial share the part of the serial run that no executor can spread: for the
            synthesis, the serial run's time outside the ``defects`` and ``search``
            phases (``IterationRecord.times``: nominal reference, zones, check list,
            removal plan, final zones); for the Monte Carlo, the nominal reference
            that ``monte_carlo`` builds in this process before it submits the
            samples (timed once, on its own, before the runs).  Amdahl's bound for w
            workers is 1 / (s + (1 - s) / w).

The machine may be loaded by other work: the load average at the start and the end
of the run, and the 1-minute load at the start of every measurement, are in the
report; every time is a single measurement.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import logging
import math
import os
import platform
import sys
import time
from concurrent.futures import wait
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchlib import load_average, fmt_seconds as _fmt_t  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from cspace.io import atomic_write  # noqa: E402

DOC = ROOT / "docs" / "benchmarks" / "scaling.md"
PRESET = "fast"
SEED = 0
EXECUTOR_KINDS = ("process", "dask")
WORKERS = (1, 2)
CAM_SAMPLES = 2000
GENEVA_SAMPLES = 2000
QUICK = {"workers": (2,), "cam_samples": 100, "geneva_samples": 40}
WARM_HOLD = 0.5
WARM_ROUNDS = 6
CPU_EXCESS = 1.2      # a 1-worker run above this multiple of the serial CPU gets a note


# ----------------------------------------------------------------------- helpers

def machine() -> dict:
    try:
        import distributed
        dist = distributed.__version__
    except ImportError:
        dist = None
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "nproc": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "distributed": dist,
            "platform": f"{platform.system()} {platform.machine()}"}


def _fmt_x(x, spec=".2f", suffix="×") -> str:
    if x is None or not math.isfinite(x):
        return "—"
    return f"{x:{spec}}{suffix}"


def _warm(pause: float, tag) -> int:
    """Worker warm-up: import what a defect test needs, then hold the worker a
    moment so that the next warm-up task goes to another worker.  ``tag`` makes
    every task distinct (dask merges identical pure tasks)."""
    import cspace.defects  # noqa: F401
    import synthesis.executors  # noqa: F401
    time.sleep(pause)
    return os.getpid()


def warm_workers(ex, workers: int) -> set:
    """Process ids of the executor's workers, once each of the ``workers`` has run a
    warm-up task (a few rounds at most)."""
    pids: set = set()
    for k in range(WARM_ROUNDS):
        fs = [ex.submit(_warm, WARM_HOLD, (k, i)) for i in range(workers)]
        wait(fs)
        pids |= {f.result() for f in fs}
        if len(pids) >= workers:
            break
    return pids


def cpu_now() -> dict:
    """pid -> user + system CPU seconds, for this process and all its descendants."""
    try:
        import psutil
    except ImportError:
        return {}
    me = psutil.Process()
    out = {}
    for p in [me, *me.children(recursive=True)]:
        try:
            t = p.cpu_times()
            out[p.pid] = t.user + t.system
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            pass
    return out


def cpu_used(before: dict, after: dict):
    """CPU seconds between two :func:`cpu_now` snapshots (None without psutil)."""
    if not after:
        return None
    return sum(max(0.0, t - before.get(pid, 0.0)) for pid, t in after.items())


@contextlib.contextmanager
def open_executor(kind: str, workers: int):
    """(executor, start seconds, worker pids) for one case; everything closed on exit."""
    from synthesis import make_executor
    t0 = time.perf_counter()
    if kind == "serial":
        with make_executor("serial") as ex:
            yield ex, time.perf_counter() - t0, set()
        return
    if kind == "process":
        with make_executor("process", workers) as ex:
            pids = warm_workers(ex, workers)
            yield ex, time.perf_counter() - t0, pids
        return
    if kind == "dask":
        from distributed import LocalCluster
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=logging.ERROR) as cluster:
            with make_executor("dask", scheduler=cluster.scheduler_address) as ex:
                pids = warm_workers(ex, workers)
                yield ex, time.perf_counter() - t0, pids
        return
    raise ValueError(f"unknown executor kind {kind!r}")


# ------------------------------------------------------------------------- cases

def cases(args) -> list:
    """The cases of this run, in run order."""
    out = []
    if args.synthesis:
        out.append({"id": "synthesis geneva", "job": "synthesis",
                    "model": "geneva", "preset": PRESET})
    out.append({"id": f"Monte Carlo reciprocating_cam, {args.cam_samples} samples",
                "job": "monte_carlo", "model": "reciprocating_cam", "preset": PRESET,
                "samples": args.cam_samples, "seed": SEED})
    out.append({"id": f"Monte Carlo geneva, {args.geneva_samples} samples",
                "job": "monte_carlo", "model": "geneva", "preset": PRESET,
                "samples": args.geneva_samples, "seed": SEED})
    return out


def _model(name):
    from mechanisms.models import BUILTIN
    return BUILTIN[name]()


def result_signature(case: dict, r) -> str:
    """What must not depend on the executor, as canonical JSON."""
    if case["job"] == "synthesis":
        return json.dumps(r.to_dict(timing=False), sort_keys=True)
    return json.dumps({"n": r.n, "defective": list(r.defective),
                       "reasons": dict(sorted(r.reasons.items()))}, sort_keys=True)


def summarize_result(case: dict, r) -> dict:
    if case["job"] == "synthesis":
        phases = {k: float(sum(h.times.get(k, 0.0) for h in r.history))
                  for k in ("defects", "search", "total")}
        return {"status": r.status.name, "nit": r.nit,
                "defects": list(r.defects_per_iteration()),
                "checklist": [h.counts.get("checklist", 0) for h in r.history],
                "tests": int(sum(h.tests for h in r.history)), "e": float(r.e),
                "units": r.units, "phases": phases}
    return {"n": r.n, "n_defective": r.n_defective, "defective": list(r.defective)}


def run_case(case: dict, kind: str, workers: int, log=None) -> dict:
    """One measurement: the case on a fresh executor of ``kind`` with ``workers``."""
    from synthesis import synthesize
    from synthesis.progress import LogProgress, Progress
    from synthesis.verify import monte_carlo
    model = _model(case["model"])
    load = load_average()
    with open_executor(kind, workers) as (ex, t_start, pids):
        c0 = cpu_now()
        t0 = time.perf_counter()
        if case["job"] == "synthesis":
            r = synthesize(model, case["preset"], executor=ex,
                           progress=LogProgress(log) if log is not None else Progress())
        else:
            r = monte_carlo(model, case["samples"], seed=case["seed"],
                            accuracy=case["preset"], executor=ex)
        wall = time.perf_counter() - t0
        cpu = cpu_used(c0, cpu_now())
    return {"case": case["id"], "kind": kind, "workers": workers if kind != "serial" else 1,
            "start": t_start, "warm_workers": len(pids), "wall": wall, "cpu": cpu,
            "load": load[0] if load else None, "signature": result_signature(case, r),
            **summarize_result(case, r)}


def reference_time(case: dict) -> float:
    """Seconds of the nominal reference ``monte_carlo`` builds in this process."""
    from cspace.accuracy import as_accuracy
    from cspace.defects import reference
    model = _model(case["model"])
    t0 = time.perf_counter()
    reference(model, as_accuracy(case["preset"]), None)
    return time.perf_counter() - t0


def serial_share(rows: list, ref_times: dict) -> dict:
    """case -> fraction of the serial run that no executor can spread."""
    out = {}
    for r in rows:
        if r["kind"] != "serial" or not r["wall"] > 0:
            continue
        if "phases" in r:
            par = r["phases"]["defects"] + r["phases"]["search"]
            out[r["case"]] = min(1.0, max(0.0, (r["wall"] - par) / r["wall"]))
        elif r["case"] in ref_times:
            out[r["case"]] = min(1.0, ref_times[r["case"]] / r["wall"])
    return out


def amdahl(s: float, w: int) -> float:
    return 1.0 / (s + (1.0 - s) / w)


# ---------------------------------------------------------------------- analysis

def scaling(rows: list) -> dict:
    """(case, kind, workers) -> {"speedup", "efficiency", "cpu_ratio", "same"} against
    the case's serial run of the same script run (None where it has no serial run)."""
    base = {r["case"]: r for r in rows if r["kind"] == "serial"}
    out = {}
    for r in rows:
        b = base.get(r["case"])
        if b is None:
            out[(r["case"], r["kind"], r["workers"])] = {"speedup": None, "efficiency": None,
                                                          "cpu_ratio": None, "same": None}
            continue
        sp = b["wall"] / r["wall"] if r["wall"] > 0 else math.nan
        cr = (r["cpu"] / b["cpu"] if r["cpu"] is not None and b["cpu"] else None)
        out[(r["case"], r["kind"], r["workers"])] = {
            "speedup": sp, "efficiency": sp / r["workers"], "cpu_ratio": cr,
            "same": r["signature"] == b["signature"]}
    return out


def json_diff(a, b, path="", limit=8) -> list:
    """The first ``limit`` JSON paths where ``a`` and ``b`` differ."""
    out: list = []

    def walk(x, y, p):
        if len(out) >= limit:
            return
        if isinstance(x, dict) and isinstance(y, dict):
            for k in sorted(set(x) | set(y), key=str):
                if k not in x or k not in y:
                    out.append(f"{p}.{k}: only in {'serial' if k in x else 'this run'}")
                else:
                    walk(x[k], y[k], f"{p}.{k}")
        elif isinstance(x, list) and isinstance(y, list):
            if len(x) != len(y):
                out.append(f"{p}: length {len(x)} != {len(y)}")
            for i, (u, v) in enumerate(zip(x, y)):
                walk(u, v, f"{p}[{i}]")
        elif x != y:
            out.append(f"{p}: {x!r} != {y!r}")

    walk(a, b, path)
    return out[:limit]


def mismatches(rows: list) -> list:
    """(row, differing paths) of every run whose result differs from its serial run."""
    base = {r["case"]: r for r in rows if r["kind"] == "serial"}
    out = []
    for r in rows:
        b = base.get(r["case"])
        if b is not None and r is not b and r["signature"] != b["signature"]:
            out.append((r, json_diff(json.loads(b["signature"]), json.loads(r["signature"]))))
    return out


# ------------------------------------------------------------------- rendering

def _kind_label(kind: str) -> str:
    return {"serial": "serial", "process": "process pool", "dask": "dask LocalCluster"}.get(
        kind, kind)


def scaling_table(rows: list) -> list:
    """Markdown lines of the main table (one line per measurement)."""
    sc = scaling(rows)
    out = ["| case | executor | workers | start | wall time | speed-up vs serial | efficiency |"
           " CPU (this process + workers) | CPU vs serial | cores busy | 1-min load at start |"
           " same result as serial |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        s = sc[(r["case"], r["kind"], r["workers"])]
        if r["kind"] == "serial":
            same = "(baseline)"
        else:
            same = "—" if s["same"] is None else ("yes" if s["same"] else "**no**")
        start = "—" if r["kind"] == "serial" else _fmt_t(r["start"])
        if r["kind"] != "serial" and r["warm_workers"] < r["workers"]:
            start += f" ({r['warm_workers']} warmed)"
        cpu = r["cpu"]
        busy = cpu / r["wall"] if cpu is not None and r["wall"] > 0 else None
        load = "—" if r["load"] is None else f"{r['load']:.2f}"
        eff = None if s["efficiency"] is None else 100 * s["efficiency"]
        out.append(f"| {r['case']} | {_kind_label(r['kind'])} | {r['workers']} | {start} | "
                   f"{_fmt_t(r['wall'])} | {_fmt_x(s['speedup'])} | {_fmt_x(eff, '.0f', ' %')}"
                   f" | {_fmt_t(cpu)} | {_fmt_x(s['cpu_ratio'])} | {_fmt_x(busy, '.2f', '')}"
                   f" | {load} | {same} |")
    return out


def bound_table(rows: list, ref_times: dict, workers) -> list:
    """Markdown lines: serial share, Amdahl's bound and the best measured speed-up."""
    share = serial_share(rows, ref_times)
    sc = scaling(rows)
    ws = sorted({w for w in workers if w > 1} or {max(workers)})
    head = "| case | serial share | " + " | ".join(
        f"Amdahl bound, {w} workers | best measured, {w} workers" for w in ws) + " |"
    out = [head, "|---|---:|" + "---:|---:|" * len(ws)]
    for case in dict.fromkeys(r["case"] for r in rows):
        if case not in share:
            continue
        s = share[case]
        cells = []
        for w in ws:
            meas = [v["speedup"] for (c, k, n), v in sc.items()
                    if c == case and n == w and k != "serial" and v["speedup"] is not None]
            best = max(meas) if meas else None
            cells += [_fmt_x(amdahl(s, w)), _fmt_x(best)]
        out.append(f"| {case} | {100 * s:.1f} % | " + " | ".join(cells) + " |")
    return out


def results_lines(rows: list) -> list:
    """What each case computed (from its serial run, else its first run)."""
    out = []
    seen = set()
    for r in sorted(rows, key=lambda r: r["kind"] != "serial"):
        if r["case"] in seen:
            continue
        seen.add(r["case"])
        if "nit" in r:
            out.append(f"- {r['case']}: {r['status']} after {r['nit']} iterations; check list"
                       f" per iteration {', '.join(map(str, r['checklist']))}; defective"
                       f" vectors per iteration {', '.join(map(str, r['defects']))}"
                       f" (the tasks of one bisection step); {r['tests']} defect tests;"
                       f" e = {r['e']:.4g} {r['units']}.")
        else:
            idx = r["defective"]
            shown = ", ".join(map(str, idx[:12])) + (", …" if len(idx) > 12 else "")
            out.append(f"- {r['case']}: {r['n_defective']} of {r['n']} samples defective"
                       + (f" (indices {shown})." if idx else "."))
    return out


def report(rows: list, ref_times: dict, info: dict, args, loads: tuple, total: float) -> str:
    L: list = []
    P = L.append
    P("# Benchmark: scaling with the worker count (process pool and dask)")
    P("")
    P("Script: `benchmarks/bench_scaling.py` (run `python benchmarks/bench_scaling.py`)."
      "  Every figure below was measured in one run of that script; every ratio is against"
      " the serial run of the same case in the same run.")
    P("")
    P(f"- date: {info['date']}")
    P(f"- machine: {info['nproc']} cores ({info['platform']}), Python {info['python']},"
      f" numpy {info['numpy']}, distributed {info.get('distributed') or '—'}")
    mode = "quick" if args.quick else "full"
    P(f"- mode: {mode} (executors serial, {', '.join(args.executors)}; workers"
      f" {', '.join(map(str, args.workers))}; preset {PRESET}; Monte Carlo samples: cam"
      f" {args.cam_samples}, Geneva {args.geneva_samples}, seed {SEED}); whole run {total:.0f} s")
    P(f"- load average (1, 5, 15 min) at the start {loads[0]}, at the end {loads[1]}")
    P("")
    P("## Method")
    P("")
    P("- **cases**: `synthesize(geneva(), \"fast\", executor=ex)` from the built-in"
      " design; `monte_carlo(model, n, seed=0, accuracy=\"fast\", executor=ex)` of the built-in"
      " tolerance box of the reciprocating cam and of the Geneva model.")
    P("- **executors**: serial (`make_executor(\"serial\")`, the baseline); a fresh process pool"
      " (`make_executor(\"process\", w)`) per case; a fresh"
      " `distributed.LocalCluster(n_workers=w, threads_per_worker=1, processes=True)` per case,"
      " used as the command line uses it: `make_executor(\"dask\","
      " scheduler=cluster.scheduler_address)`.")
    P("- **start**: opening the executor (for dask: cluster start and client connection) and"
      " one warm-up task on every worker (library import and a 0.5 s hold), before the clock"
      " starts.  **wall time**: the `synthesize` / `monte_carlo` call alone.  **speed-up**:"
      " t(serial) / t(run); **efficiency**: speed-up / workers.")
    P("- **CPU**: user + system seconds of this process and all its child processes during"
      " the call (`psutil`); **CPU vs serial**: that over the serial run's CPU; **cores busy**"
      " = CPU / wall time.")
    P("- **same result**: synthesis, the result's `to_dict(timing=False)` as canonical JSON;"
      " Monte Carlo, the defective sample indices and the defect reasons; both compared with"
      " the serial run.")
    P("- **serial share** s: synthesis, the serial run's time outside the `defects` and"
      " `search` phases; Monte Carlo, the nominal reference built in this process before the"
      " samples are submitted (timed on its own).  Amdahl's bound: 1 / (s + (1 − s) / w).")
    P("")
    P("## Wall time, speed-up and efficiency")
    P("")
    L.extend(scaling_table(rows))
    P("")
    P("### Against Amdahl's bound")
    P("")
    L.extend(bound_table(rows, ref_times, args.workers))
    P("")
    P("### What was computed")
    P("")
    L.extend(results_lines(rows))
    P("")
    notes = notes_lines(rows, info, loads)
    P("## Notes")
    P("")
    L.extend(notes)
    P("")
    P("## Scaling on a cluster")
    P("")
    L.extend(cluster_lines(rows))
    P("")
    return "\n".join(L) + "\n"


def notes_lines(rows: list, info: dict, loads: tuple) -> list:
    out = []
    nproc = info.get("nproc") or 1
    out.append(f"- The machine has {nproc} cores: no run here can show more than {nproc}-fold"
               " parallelism, and the 2-worker figures are an upper limit of this machine,"
               " not of the method.  The executors add work of their own (pickling, the"
               " pool's or the scheduler's threads) on the same cores.")
    busy = [la for la in loads if la is not None and la[0] >= 0.5 * nproc]
    if busy:
        out.append(f"- The machine carried other load during the run (1-minute load average"
                   f" {', '.join(str(la[0]) for la in busy)} on {nproc} cores): the times are"
                   " upper bounds, and the speed-up of more workers is understated when the"
                   " cores were already busy; \"cores busy\" below the worker count shows"
                   " workers that waited.  Cases ran one after the other (serial first), so"
                   " a change of the outside load between runs shows up in the ratios.")
    if any(r["workers"] > nproc for r in rows):
        out.append(f"- Some runs used more workers than the machine's {nproc} cores.")
    if any(r["kind"] != "serial" for r in rows):
        out.append("- Each worker builds the nominal reference of every design once for its"
                   " own defect tests; the serial run reuses the one built in this process."
                   "  That is work the parallel runs do w times and the serial run once.")
    sc = scaling(rows)
    heavy = [(r, sc[(r["case"], r["kind"], r["workers"])]["cpu_ratio"]) for r in rows
             if r["kind"] != "serial" and r["workers"] == 1]
    heavy = [(r, x) for r, x in heavy if x is not None and x > CPU_EXCESS]
    if heavy:
        out.append("- With a single worker, "
                   + "; ".join(f"{r['case']} on {_kind_label(r['kind'])} used {x:.2f}× the CPU"
                               f" of the serial run" for r, x in heavy)
                   + ": with one worker nothing runs in parallel, so the excess is work of the"
                   " executor path (for dask it includes the scheduler, which a LocalCluster"
                   " runs in this process), which a parallel run must first make up for.")
    short = [r for r in rows if r["kind"] != "serial" and r["warm_workers"] < r["workers"]]
    if short:
        out.append("- In " + ", ".join(f"{r['case']} ({r['kind']}, {r['workers']})"
                                       for r in short)
                   + " not every worker ran a warm-up task; its first tasks include the"
                   " library import.")
    bad = mismatches(rows)
    if bad:
        out.append("- **The result differs from the serial run** for "
                   + "; ".join(f"{r['case']} on {r['kind']} with {r['workers']} worker(s)"
                               f" (first differences: {', '.join(d[:3]) or '—'})"
                               for r, d in bad)
                   + ".  The executor must not change a result: this is a bug.")
    else:
        out.append("- Every parallel run gave the same result as the serial run of its case.")
    return out


def cluster_lines(rows: list) -> list:
    syn = next((r for r in rows if r["kind"] == "serial" and "nit" in r), None)
    out = ["The recipe for a real cluster (a `dask scheduler` on the head node,"
           " `dask worker ADDR --nthreads 1` on every worker node, then"
           " `cspace-tol synthesize MODEL --executor dask --scheduler ADDR`) is in"
           " [the synthesis guide, section Executors](../synthesis.md#executors).  What to"
           " expect from more workers than measured here:", ""]
    if syn is not None:
        out.append(f"- Synthesis: the work of one batch is a check list"
                   f" ({', '.join(map(str, syn['checklist']))} vectors per iteration for the"
                   f" cam) or one bisection step ({', '.join(map(str, syn['defects']))}"
                   " defective vectors per iteration); a batch cannot use more workers than"
                   " it has vectors, and the steps of a bisection run one after the other.")
    else:
        out.append("- Synthesis: the work of one batch is a check list or one bisection step;"
                   " a batch cannot use more workers than it has vectors, and the steps of"
                   " a bisection run one after the other.")
    out.append("- Monte Carlo: every sample is an independent task, so it spreads over as"
               " many workers as there are samples; each worker first builds the nominal"
               " reference (once per design), a fixed cost per worker.")
    out.append("- Start one single-threaded worker process per core (`--nthreads 1`): the"
               " defect test is Python code, and threads of one process share one"
               " interpreter lock.")
    return out


# ------------------------------------------------------------------------ main

def _check_args(ap, args):
    if any(w < 1 for w in args.workers):
        ap.error("--workers must be positive")
    if args.cam_samples < 1 or args.geneva_samples < 1:
        ap.error("sample counts must be positive")
    for k in args.executors:
        if k not in EXECUTOR_KINDS:
            ap.error(f"unknown executor {k!r}; allowed: {list(EXECUTOR_KINDS)}")
    if "dask" in args.executors:
        try:
            import distributed  # noqa: F401
        except ImportError:
            ap.error("the dask cases need the 'distributed' package (pip install '.[dask]');"
                     " or pass --executors process")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help=f"workers {' '.join(map(str, QUICK['workers']))}, "
                         f"{QUICK['cam_samples']} cam and {QUICK['geneva_samples']} Geneva "
                         "Monte Carlo samples")
    ap.add_argument("--workers", nargs="+", type=int,
                    help=f"worker counts (default: {' '.join(map(str, WORKERS))})")
    ap.add_argument("--executors", nargs="+", default=list(EXECUTOR_KINDS),
                    help="parallel executors besides the serial baseline "
                         "(default: %(default)s)")
    ap.add_argument("--cam-samples", type=int,
                    help=f"Monte Carlo samples, reciprocating cam (default {CAM_SAMPLES})")
    ap.add_argument("--geneva-samples", type=int,
                    help=f"Monte Carlo samples, Geneva (default {GENEVA_SAMPLES})")
    ap.add_argument("--no-synthesis", dest="synthesis", action="store_false",
                    help="Monte Carlo cases only")
    ap.add_argument("--out", type=Path, default=DOC, help="markdown report (default: %(default)s)")
    args = ap.parse_args(argv)
    dflt = QUICK if args.quick else {"workers": WORKERS, "cam_samples": CAM_SAMPLES,
                                     "geneva_samples": GENEVA_SAMPLES}
    for k, v in dflt.items():
        if getattr(args, k) is None:
            setattr(args, k, v)
    args.workers = sorted(set(args.workers))
    args.executors = list(dict.fromkeys(args.executors))
    _check_args(ap, args)

    t_all = time.perf_counter()
    load0 = load_average()
    info = machine()
    print(f"scaling benchmark ({'quick' if args.quick else 'full'}): {info['nproc']} cores, "
          f"Python {info['python']}, distributed {info['distributed']}, load {load0}",
          flush=True)

    rows, ref_times = [], {}
    for case in cases(args):
        if case["job"] == "monte_carlo":
            ref_times[case["id"]] = reference_time(case)
            print(f"{case['id']}: nominal reference {ref_times[case['id']]:.2f} s", flush=True)
        runs = [("serial", 1)] + [(k, w) for k in args.executors for w in args.workers]
        for kind, w in runs:
            print(f"{case['id']}: {kind}, {w} worker(s) ...", flush=True)
            r = run_case(case, kind, w)
            rows.append(r)
            b = rows[-1] if kind == "serial" else next(
                x for x in rows if x["case"] == r["case"] and x["kind"] == "serial")
            same = r["signature"] == b["signature"]
            cpu = "—" if r["cpu"] is None else f"{r['cpu']:.1f}"
            print(f"  start {r['start']:.2f} s, wall {r['wall']:.2f} s, speed-up "
                  f"{b['wall'] / r['wall']:.2f}, cpu {cpu} s, load {r['load']}, "
                  f"same result as serial: {same}", flush=True)

    bad = mismatches(rows)
    for r, diff in bad:
        print(f"error: {r['case']}: {r['kind']} with {r['workers']} worker(s) differs from the "
              f"serial run: {'; '.join(diff)}", file=sys.stderr)
    load1 = load_average()
    text = report(rows, ref_times, info, args, (load0, load1), time.perf_counter() - t_all)
    print(text)
    atomic_write(args.out, text)
    print(f"written: {args.out.relative_to(ROOT) if args.out.is_relative_to(ROOT) else args.out}")
    if bad:
        print("error: results differ between executors (see the report's notes)",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
