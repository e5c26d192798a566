"""The batched defect test's verdicts against the full per-variant test, on the
vectors the synthesis tests: every check list of every iteration of the case
studies, and a seeded Monte Carlo of each initial box.

    python benchmarks/verify_batch.py                               # all, fast
    python benchmarks/verify_batch.py --models geneva --presets fast default --mc 2000
    python benchmarks/verify_batch.py --quick                      # 100 samples, one list

It prints the tables and writes them to ``docs/benchmarks/batch_agreement.md``
(atomically).  It exits with status 1 when a certified verdict differs from the
full test's (and lists the vectors).

What is compared
----------------
check lists  for every iteration recorded in the case study's checkpoint
             (``benchmarks/runs/<model>_<preset>/checkpoint.json``): the design
             of that iteration (its nominal and tolerances), its nominal
             Reference (the run's d), its operating zones and check list, built
             as the synthesis builds them (:func:`synthesis.loop.checklist_of`).
             Models without a checkpoint for the preset: the initial design's
             check list only.
Monte Carlo  ``--mc`` box samples of the initial design (half corners, seed 0,
             :func:`synthesis.verify.box_samples`).

Every vector goes through :func:`cspace.batch.margins.defect_margins` without
its fall-back (``fallback=False``: the margins' own verdicts, and which ones
they certify) and through the full test (:func:`cspace.defects.is_defective`,
on ``--workers`` processes).  Agreement is counted over the certified vectors;
the uncertain ones are those the synthesis hands to the full test (the
fall-backs), whose verdict is the full test's by construction.
"""

from __future__ import annotations

import argparse
import datetime
import json
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

MODELS = ("reciprocating_cam", "geneva", "optical_filter")
TASK = 16


def full_verdicts(model, U, accuracy, d) -> list:
    """The full test's verdicts of the rows of ``U`` (one task of a worker:
    :func:`synthesis.executors.defect_task` of each)."""
    from synthesis.executors import defect_task
    return [bool(defect_task(model, u, accuracy, d).defective) for u in U]


def designs(name: str, preset: str) -> list:
    """(label, model, d) of every design whose check list is compared."""
    from cspace.defects import reference
    from mechanisms.models import BUILTIN
    m0 = BUILTIN[name]()
    path = ROOT / "benchmarks" / "runs" / f"{name}_{preset}" / "checkpoint.json"
    if not path.exists():
        return [("initial design", m0, reference(m0, preset).d)]
    ck = json.loads(path.read_text())
    out = []
    for h in ck["history"]:
        m = m0.with_nominal(np.array(h["nominal"])).with_tolerances(np.array(h["tol"]))
        out.append((f"iteration {h['iteration']}", m, float(ck["d"])))
    return out


def compare(model, U, ref, pool) -> dict:
    """Batched (without fall-back) and full verdicts of the rows of ``U``
    against the Reference ``ref`` of ``model``."""
    from cspace.batch.margins import defect_margins
    d = ref.d
    t = time.perf_counter()
    mb = defect_margins(model, U, ref, fallback=False)
    t_batch = time.perf_counter() - t
    t = time.perf_counter()
    futs = [pool.submit(full_verdicts, model, U[i:i + TASK], ref.accuracy, d)
            for i in range(0, len(U), TASK)]
    full = np.array([v for f in futs for v in f.result()], dtype=bool)
    t_full = time.perf_counter() - t
    cert = mb.certified
    wrong = np.nonzero(cert & (mb.defective != full))[0]
    return {"vectors": len(U), "defective": int(full.sum()), "certified": int(cert.sum()),
            "fallback": int((~cert).sum()), "agree": int((cert & (mb.defective == full)).sum()),
            "wrong": [U[v].tolist() for v in wrong], "batch": t_batch, "full": t_full}


def run(name: str, preset: str, mc: int, pool, lists: int | None, only=None) -> list:
    from synthesis.loop import checklist_of, operating_zones
    from synthesis.verify import box_samples
    from cspace.defects import reference
    rows = []
    ds = designs(name, preset)
    for k, (label, m, d) in enumerate(ds[:lists], start=1):
        if only and k not in only:
            continue
        ref = reference(m, preset, d=d)
        zones = operating_zones(m, ref, ref.accuracy)
        U = np.array([v.u for v in checklist_of(m, ref, zones, ref.accuracy).vectors])
        r = compare(m, U, ref, pool)
        rows.append({"model": name, "preset": preset, "what": f"check list, {label}", **r})
        _say(rows[-1])
    if mc:
        label, m, d = ds[0]
        U = box_samples(m.nominal, m.tol, mc, seed=0)
        r = compare(m, U, reference(m, preset, d=d), pool)
        rows.append({"model": name, "preset": preset,
                     "what": "Monte Carlo of the initial box", **r})
        _say(rows[-1])
    return rows


def _say(r) -> None:
    print(f"{r['model']} {r['preset']} {r['what']}: {r['agree']}/{r['certified']} certified "
          f"agree, {r['fallback']} fall-backs, {len(r['wrong'])} wrong", flush=True)


def render(rows, wall: float) -> str:
    la = load_average()
    ok = all(not r["wrong"] for r in rows)
    lines = [f"# Batched verdicts against the full test ({datetime.date.today().isoformat()})",
             "", f"Machine: {platform.processor() or platform.machine()}, Python "
             f"{platform.python_version()}, load average {la}.  Command: "
             f"`python benchmarks/verify_batch.py {' '.join(sys.argv[1:])}` ({wall:.0f} s).",
             "", "Target (issue 21): the batched verdicts match the full test 100 % on every "
             "check list of every iteration of the case studies and on 2,000 seeded Monte "
             "Carlo samples of each initial box.", "",
             "Certified: decided by the margins; fall-backs: left to the full test (the "
             "synthesis runs it on them, so their verdict is the full test's).  `agree` "
             "counts the certified verdicts equal to the full test's.", "",
             f"Result: **{'every certified verdict agrees' if ok else 'DISAGREEMENTS'}**.", "",
             "| model | preset | vectors tested | defective (full test) | certified | agree | "
             "fall-backs | batched (one core) | full test (workers) |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['model']} | {r['preset']} | {r['what']} ({r['vectors']}) | "
                     f"{r['defective']} | {r['certified']} | {r['agree']} | {r['fallback']} | "
                     f"{fmt_seconds(r['batch'])} | {fmt_seconds(r['full'])} |")
    tot = {k: sum(r[k] for r in rows) for k in ("vectors", "certified", "agree", "fallback")}
    lines += ["", f"Overall: {tot['vectors']} vectors, {tot['certified']} certified, "
                  f"{tot['agree']} of them agree, {tot['fallback']} fall-backs."]
    for r in rows:
        for u in r["wrong"]:
            lines.append(f"- wrong: {r['model']} {r['preset']} {r['what']}: {u}")
    return "\n".join(lines) + "\n"


def main(argv=None):
    from concurrent.futures import ProcessPoolExecutor
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=list(MODELS))
    p.add_argument("--presets", nargs="+", default=["fast"])
    p.add_argument("--mc", type=int, default=2000, help="Monte Carlo samples (0: none)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--quick", action="store_true", help="100 samples, the first check list")
    p.add_argument("--iterations", nargs="+", type=int, default=None,
                   help="only these iterations' check lists (1 = the first)")
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks" / "batch_agreement.md"))
    a = p.parse_args(argv)
    lists = None
    if a.quick:
        a.mc, lists = 100, 1
    t = time.perf_counter()
    rows = []
    with ProcessPoolExecutor(a.workers) as pool:
        for name in a.models:
            for preset in a.presets:
                rows += run(name, preset, a.mc, pool, lists, a.iterations)
    text = render(rows, time.perf_counter() - t)
    print(text)
    atomic_write(Path(a.out), text)
    return 0 if all(not r["wrong"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
