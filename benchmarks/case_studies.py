"""Synthesis case studies: the three built-in models to zero defects, with an
independent Monte Carlo check of the initial and final boxes.

    python benchmarks/case_studies.py [--preset fast] [--samples 2000] [--search margin|bisect]
        [--removal lp|greedy] [MODEL ...]

For each model it runs :func:`synthesis.synthesize` (process pool), writing a
checkpoint after every iteration into ``benchmarks/runs/<model>_<preset>/`` (a
rerun resumes it; the folder is kept in the repository, so that a run of several
hours can be continued on another machine), then :func:`synthesis.monte_carlo`
with ``--samples`` seeded vectors (half corners, half interior, seed 1) over the
initial and the final box, with the run's d, both against the initial design; each Monte Carlo result is kept in
the same folder and not recomputed for the same box.  Results go to ``docs/case_studies.json`` (merged per
model, written atomically) and a Markdown table is printed, with the paper's
figures ([Tolerance synthesis] §5) beside ours.

Without ``--removal`` a run uses the library's default removal (the LP of
:mod:`synthesis.minimal`): the case study a user's ``cspace-tol synthesize``
reproduces.  ``--removal lp`` or ``--removal greedy`` runs that removal method
(:func:`synthesis.synthesize`, ``removal``) from scratch in its own folder
(``<model>_<preset>_<removal>``), kept under ``MODEL:<removal>``; the two are
compared side by side between the removal-comparison markers of
``docs/synthesis.md``.  ``--search bisect`` runs the paper's search with the
paper's greedy removal (``MODEL:bisect``); the search comparison sets it beside
``MODEL:greedy``, the same removal with the margin search.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# [Tolerance synthesis] §5, tables and figures: check list, defects by run, runs, e vs tolerance
PAPER = {
    "geneva": {"checklist": "44 → 137", "defects": "21, 5, 2, 1, …, 0", "runs": 9,
               "e": 0.003224, "tol": 0.018},
    "optical_filter": {"checklist": "77 → 700", "defects": "146 → 0", "runs": 19,
                       "e": 0.002709, "tol": 0.002},
    "reciprocating_cam": {"checklist": "45-57", "defects": "15 → 0", "runs": 9,
                          "e": 0.016054, "tol": 0.02},
}


def _mc_cached(path, model, samples, preset, d, ex, intent):
    """Monte Carlo of one box against the initial design ``intent``, kept in
    ``path`` so that a rerun does not redo it."""
    from cspace.io import atomic_write, dumps, load_json
    from synthesis import monte_carlo
    key = {"nominal": [float(v) for v in model.nominal], "tol": [float(v) for v in model.tol],
           "d": d, "samples": samples, "preset": preset,
           "intent": [float(v) for v in intent.nominal]}
    if path.exists():
        old = load_json(path)
        if old.get("key") == key:
            return old["result"]

    def tick(done, total):
        if done % 100 == 0 or done == total:
            print(f"  Monte Carlo {path.stem}: {done}/{total}", file=sys.stderr, flush=True)

    res = monte_carlo(model, samples, seed=1, accuracy=preset, d=d, executor=ex,
                      progress=tick, intent=intent).to_dict()
    atomic_write(path, dumps({"key": key, "result": res}))
    return res


def run(name, preset, samples, workers, search="margin", removal=None):
    from cspace.io import atomic_write, load_json
    from mechanisms.models import BUILTIN
    from synthesis import make_executor, synthesize
    from synthesis.checkpoint import checkpoint_text
    from synthesis.progress import LogProgress
    from synthesis.result import SynthesisState
    m = BUILTIN[name]()
    out = ROOT / "benchmarks" / "runs" / ((f"{name}_{preset}" if search == "margin"
                                           else f"{name}_{preset}_{search}")
                                          + ("" if removal is None else f"_{removal}"))
    out.mkdir(parents=True, exist_ok=True)
    ck = out / "checkpoint.json"
    state = SynthesisState.from_dict(load_json(ck)) if ck.exists() else None
    t0 = time.perf_counter()
    with make_executor("process", workers) as ex:
        r = synthesize(m, preset, executor=ex, state=state, progress=LogProgress(),
                       on_iteration=lambda s: atomic_write(ck, checkpoint_text(s)),
                       search=None if state is not None else search,
                       removal=None if state is not None else (
                           removal or ("greedy" if search == "bisect" else None)))
        t_syn = time.perf_counter() - t0
        final = m.with_nominal(r.nominal).with_tolerances(r.tol)
        t1 = time.perf_counter()
        before = _mc_cached(out / f"mc_initial_{samples}.json", m, samples, preset, r.d, ex, m)
        after = _mc_cached(out / f"mc_final_{samples}.json", final, samples, preset, r.d, ex, m)
        t_mc = time.perf_counter() - t1
    rep = r.to_dict()
    return {"model": name, "preset": preset, "units": r.units, "status": r.status.name,
            "nit": r.nit, "e": r.e, "tol": float(m.tol.max()),
            "checklist": [(h.counts["seeds"], h.counts["checklist"]) for h in r.history],
            "defects": r.defects_per_iteration(), "changed": rep["changed"],
            "shrunk": rep["shrunk"], "d": r.d, "two_sided": r.two_sided,
            "patience": r.patience, "search": r.search, "removal": r.removal,
            "margin_evaluations": int(sum(h.counts.get("margin_evaluations", 0)
                                          for h in r.history)),
            "lp_defects": int(sum(h.counts.get("lp_defects", 0) for h in r.history)),
            "greedy_defects": int(sum(h.counts.get("greedy_defects", 0) for h in r.history)),
            "tests": int(sum(h.tests for h in r.history)),
            "search_tests": int(sum(h.tests - h.counts.get("checklist", 0) for h in r.history)),
            "cuts": len(rep["shrunk"]),
            "smallest_kept": min([b / a for a, b in rep["shrunk"].values() if a > 0],
                                 default=1.0),
            "volume_kept": float(np.prod([b / a for a, b in zip(r.initial_tol, r.tol)
                                          if a > 0])),
            "time_synthesis_s": sum(h.times.get("total", 0.0) for h in r.history),
            "wall_s": t_syn, "time_monte_carlo_s": t_mc,
            "mc_initial": before, "mc_final": after,
            "machine": f"{platform.machine()}, {workers or 'all'} worker(s)"}


def table(results) -> str:
    rows = ["| model | check list (seeds → vectors), run 1 | defects per run | runs | e / tolerance "
            "| tolerances cut | Monte Carlo initial → final (defective / samples) | paper: check "
            "list | paper: defects | paper: runs | paper: e / tolerance |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name in ("geneva", "optical_filter", "reciprocating_cam"):
        r = results.get(name)
        if r is None:
            continue
        p = PAPER[name]
        s, c = r["checklist"][0]
        cuts = r.get("shrunk") or {}
        if cuts:
            keep = min(new / old for old, new in cuts.values() if old > 0)
            cut = f"{len(cuts)}, the smallest kept at {100 * keep:.0f} %"
        else:
            cut = "none"
        rows.append(
            f"| {name} | {s} → {c} | {', '.join(map(str, r['defects']))} | {r['nit']} | "
            f"{r['e']:.4g} / {r['tol']:.4g} {r['units']} | {cut} | "
            f"{r['mc_initial']['defective']}/{r['mc_initial']['samples']} → "
            f"{r['mc_final']['defective']}/{r['mc_final']['samples']} | {p['checklist']} | "
            f"{p['defects']} | {p['runs']} | {p['e']:.4g} / {p['tol']:.4g} cm |")
    return "\n".join(rows)


START, END = "<!-- case-studies:start -->", "<!-- case-studies:end -->"
CMP_START, CMP_END = "<!-- search-comparison:start -->", "<!-- search-comparison:end -->"


def _cells(r, with_margins: bool) -> list:
    """The columns of one run in a side-by-side table (after model and method):
    runs, [defects per run,] tests, [margin evaluations,] e, cuts, smallest
    kept, volume kept, time and the Monte Carlo of the final box."""
    tests = f"{r['tests']} ({r['search_tests']})"
    head = ([r["nit"], ", ".join(map(str, r["defects"])), tests,
             r.get("margin_evaluations", 0)] if with_margins else [r["nit"], tests])
    return head + [f"{r['e']:.4g} / {r['tol']:.4g} {r['units']}", r["cuts"],
                   f"{100 * r['smallest_kept']:.0f} %", f"{r['volume_kept']:.3g}",
                   f"{r['time_synthesis_s'] / 60:.1f} min",
                   f"{r['mc_final']['defective']}/{r['mc_final']['samples']}"]


def _side_by_side(results, head: list, variants, with_margins: bool) -> str:
    """A table of each model's runs ``variants`` ((key suffix, label) pairs);
    a run not recorded, or recorded before its figures were kept, is left out."""
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name in ("geneva", "optical_filter", "reciprocating_cam"):
        for suffix, label in variants:
            r = results.get(f"{name}:{suffix}")
            if r is None or "tests" not in r:
                continue
            rows.append("| " + " | ".join(str(c) for c in [name, label]
                                          + _cells(r, with_margins)) + " |")
    return "\n".join(rows)


_TAIL = ["e / tolerance", "cuts", "smallest kept", "box volume kept", "time",
         "Monte Carlo final"]


def comparison(results) -> str:
    """The runs with the margin search beside those with the paper's bisection,
    both with the paper's greedy removal."""
    return _side_by_side(
        results, ["model", "search", "runs", "defect tests (of which search)"] + _TAIL,
        (("greedy", "margin"), ("bisect", "bisect (paper)")), with_margins=False)


RM_START, RM_END = "<!-- removal-comparison:start -->", "<!-- removal-comparison:end -->"


def removal_comparison(results) -> str:
    """The runs with the LP removal beside those with the paper's greedy."""
    return _side_by_side(
        results, ["model", "removal", "runs", "defects per run",
                  "defect tests (of which search)", "margin evaluations"] + _TAIL,
        (("lp", "lp"), ("greedy", "greedy (paper)")), with_margins=True)


def progress_note(names, preset: str = "fast") -> str:
    """Where the unfinished runs stand, read from their checkpoints."""
    import json as _json
    parts = []
    for n in names:
        ck = ROOT / "benchmarks" / "runs" / f"{n}_{preset}" / "checkpoint.json"
        if not ck.exists():
            continue
        st = _json.loads(ck.read_text())
        hist = st.get("history", [])
        if not hist:
            continue
        defects = ", ".join(str(h["defects"]) for h in hist)
        secs = sum(h.get("times", {}).get("total", 0.0) for h in hist)
        parts.append(f"`{n}` ({preset}): {len(hist)} iteration(s) so far, defective check-list "
                     f"vectors per iteration {defects} ({secs / 60:.0f} min), status "
                     f"{st.get('status')}")
    return (" Checkpointed so far: " + "; ".join(parts) + ".") if parts else ""


def update_docs(results) -> None:
    """Put the table between the case-study markers of README.md and
    docs/synthesis.md (or in place of a bare ``CASE_STUDY_TABLE`` line)."""
    from cspace.io import atomic_write
    done = [n for n in ("geneva", "optical_filter", "reciprocating_cam") if n in results]
    missing = [n for n in ("geneva", "optical_filter", "reciprocating_cam") if n not in results]
    block = table(results)
    if missing:
        block += ("\n\nNot yet run to completion with this script: "
                  + ", ".join(f"`{n}`" for n in missing)
                  + " (`python benchmarks/case_studies.py "
                  + " ".join(missing) + "` resumes from the checkpoints in "
                    "`benchmarks/runs/`)." + progress_note(missing))
    presets = sorted({results[n]["preset"] for n in done})
    from synthesis.result import DEFAULT_PATIENCE
    # a result recorded before the settings were kept ran one-sided, patience 4
    sides = sorted({"two-sided (the default)" if results[n].get("two_sided")
                    else "one-sided (--no-two-sided)" for n in done})
    pats = sorted({str(results[n].get("patience", DEFAULT_PATIENCE)) for n in done})
    rems = sorted({"LP removal (the default)" if results[n].get("removal") == "lp"
                   else "the paper's greedy removal" for n in done})
    block = (f"Preset {', '.join(presets)}, {' and '.join(rems)}, {' and '.join(sides)}, "
             f"patience {', '.join(pats)}; Monte Carlo: seeded samples of the box (half random "
             f"corners, half interior) with the same defect test.\n\n" + block)
    cmp_block = comparison(results)
    rm_block = removal_comparison(results)
    for path in (ROOT / "README.md", ROOT / "docs" / "synthesis.md"):
        text = original = path.read_text()
        if RM_START in text and RM_END in text:
            head, rest = text.split(RM_START, 1)
            _, tail = rest.split(RM_END, 1)
            text = head + RM_START + "\n" + rm_block + "\n" + RM_END + tail
        if CMP_START in text and CMP_END in text:
            head, rest = text.split(CMP_START, 1)
            _, tail = rest.split(CMP_END, 1)
            text = head + CMP_START + "\n" + cmp_block + "\n" + CMP_END + tail
        if START in text and END in text:
            head, rest = text.split(START, 1)
            _, tail = rest.split(END, 1)
            text = head + START + "\n" + block + "\n" + END + tail
        elif "CASE_STUDY_TABLE" in text:
            text = text.replace("CASE_STUDY_TABLE", START + "\n" + block + "\n" + END)
        if text != original:
            atomic_write(path, text)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("models", nargs="*", default=["reciprocating_cam", "geneva", "optical_filter"])
    ap.add_argument("--preset", default="fast")
    ap.add_argument("--samples", type=int, default=2000)
    ap.add_argument("--workers", type=int)
    ap.add_argument("--search", choices=("margin", "bisect"), default="margin",
                    help="transition-point search (bisect: the paper's; its runs are kept "
                         "apart, under MODEL:bisect)")
    ap.add_argument("--removal", choices=("lp", "greedy"), default=None,
                    help="removal method, run from scratch in its own folder and kept under "
                         "MODEL:REMOVAL (default: resume the case study's own run)")
    ap.add_argument("--docs-only", action="store_true",
                    help="only rewrite the tables in README.md and docs/synthesis.md")
    a = ap.parse_args()
    from cspace.io import atomic_write, dumps
    path = ROOT / "docs" / "case_studies.json"
    results = json.loads(path.read_text()) if path.exists() else {}
    for name in ([] if a.docs_only else a.models):
        print(f"== {name} ({a.preset})", flush=True)
        key = ((name if a.search == "margin" else f"{name}:{a.search}")
               + ("" if a.removal is None else f":{a.removal}"))
        results[key] = run(name, a.preset, a.samples, a.workers, a.search, a.removal)
        atomic_write(path, dumps(results))
        print(json.dumps({k: v for k, v in results[key].items()
                          if k not in ("mc_initial", "mc_final")}), flush=True)
    print(table(results))
    update_docs(results)


if __name__ == "__main__":
    main()
