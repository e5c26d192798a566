"""Assemble ``docs/BENCHMARKS.md`` from the per-benchmark reports.

    python benchmarks/assemble.py [--src DIR] [--out PATH] [--case-studies PATH]

The parts are the Markdown files of ``docs/benchmarks/`` (``cspace.md``,
``fourbar.md``, ``spatial.md``, ``synthesis.md``, ``synthesis_target.md``, ``zones.md`` and
``accuracy.md`` in this order when present, then any other ``*.md`` there by
name) and, when present, the synthesis case studies of ``docs/case_studies.json``
(written by ``benchmarks/case_studies.py``), rendered as a table.

The document starts with a table of contents (one link per part, with the part's
date and its target lines when it has any) and how to reproduce the figures;
then every part follows with its headings demoted by one level, unchanged
otherwise (each keeps its own date and machine lines).  Nothing is measured here.
The output is written to a temporary file, then renamed.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from cspace.io import atomic_write  # noqa: E402

SRC = ROOT / "docs" / "benchmarks"
OUT = ROOT / "docs" / "BENCHMARKS.md"
CASES = ROOT / "docs" / "case_studies.json"
ORDER = ("cspace.md", "fourbar.md", "spatial.md", "synthesis.md", "synthesis_target.md", "zones.md",
         "accuracy.md")
CASE_ORDER = ("geneva", "optical_filter", "reciprocating_cam")
CASE_TITLE = "Synthesis case studies"

_FENCE = re.compile(r"^\s*(```|~~~)")
_HEADING = re.compile(r"^(#{1,6})(\s+)(.*?)\s*#*\s*$")
_LINK = re.compile(r"(\]\()([^)\s]+)")


# ----------------------------------------------------------------------- parts

def part_files(src: Path) -> list:
    """The part files of ``src`` in document order."""
    if not src.is_dir():
        return []
    known = [src / n for n in ORDER if (src / n).is_file()]
    rest = sorted(p for p in src.glob("*.md") if p.name not in ORDER and p.is_file())
    return known + rest


def _headings(lines):
    """(index, level, text) of every ATX heading outside fenced code blocks."""
    fence = None
    for i, line in enumerate(lines):
        m = _FENCE.match(line)
        if m:
            if fence is None:
                fence = m.group(1)
            elif m.group(1) == fence:
                fence = None
            continue
        if fence is None:
            h = _HEADING.match(line)
            if h:
                yield i, len(h.group(1)), h.group(3)


def demote(text: str, by: int = 1) -> str:
    """Every heading outside code blocks one level (``by``) deeper, at most level 6."""
    lines = text.splitlines()
    for i, level, title in _headings(lines):
        lines[i] = "#" * min(6, level + by) + " " + title
    return "\n".join(lines)


def title_of(text: str, fallback: str) -> str:
    """The first level-1 heading (else the first heading, else ``fallback``)."""
    heads = list(_headings(text.splitlines()))
    for _, level, t in heads:
        if level == 1:
            return t
    return heads[0][2] if heads else fallback


def _section_lines(text: str, names) -> list:
    """Bullet lines of the level-2 section(s) called one of ``names``."""
    lines = text.splitlines()
    heads = list(_headings(lines))
    out = []
    for k, (i, level, t) in enumerate(heads):
        if level == 2 and t.strip().lower() in names:
            end = next((j for j, lv, _ in heads[k + 1:] if lv <= 2), len(lines))
            out.extend(s.strip() for s in lines[i + 1:end] if s.lstrip().startswith(("- ", "* ")))
    return out


def headline(text: str) -> dict:
    """The part's date line and its target lines (both may be missing)."""
    date = None
    for line in text.splitlines():
        m = re.match(r"^\s*[-*]\s+date:\s*(.+?)\s*$", line)
        if m:
            date = m.group(1)
            break
    return {"date": date, "targets": _section_lines(text, ("target", "targets"))}


def relink(text: str, src: Path, out: Path) -> str:
    """Relative link targets of a part re-expressed from the output's directory."""
    def fix(m):
        target = m.group(2)
        if re.match(r"^([a-z][a-z0-9+.-]*:|#|/)", target, re.I):
            return m.group(0)
        new = os.path.relpath(src / target, out.parent).replace(os.sep, "/")
        return m.group(1) + new
    return _LINK.sub(fix, text)


# ------------------------------------------------------------------ case studies

def _fmt(x, spec=".4g") -> str:
    if x is None:
        return "—"
    if isinstance(x, float) and not math.isfinite(x):
        return "—"
    return format(x, spec) if isinstance(x, (int, float)) else str(x)


def _mc(d) -> str:
    if not isinstance(d, dict) or "defective" not in d or "samples" not in d:
        return "—"
    return f"{d['defective']} / {d['samples']}"


def case_table(data: dict) -> list:
    """Markdown lines of the case-study table (model name -> run record)."""
    out = ["| model | preset | iterations | defects per iteration | e / tolerance |"
           " Monte Carlo, initial box (defective / samples) |"
           " Monte Carlo, final box (defective / samples) | synthesis wall time |",
           "|---|---|---:|---|---|---:|---:|---:|"]
    names = [n for n in CASE_ORDER if n in data] + sorted(n for n in data if n not in CASE_ORDER)
    for name in names:
        r = data[name]
        if not isinstance(r, dict):
            continue
        defects = r.get("defects")
        defects = ", ".join(map(str, defects)) if isinstance(defects, list) else "—"
        units = r.get("units") or ""
        e_tol = f"{_fmt(r.get('e'))} / {_fmt(r.get('tol'))} {units}".rstrip()
        wall = r.get("wall_s")
        wall = f"{wall:.1f} s" if isinstance(wall, (int, float)) and math.isfinite(wall) else "—"
        out.append(f"| {name} | {r.get('preset', '—')} | {_fmt(r.get('nit'), 'd')} | {defects} | "
                   f"{e_tol} | {_mc(r.get('mc_initial'))} | {_mc(r.get('mc_final'))} | {wall} |")
    return out


def case_section(data: dict) -> str:
    lines = [f"# {CASE_TITLE}", "",
             "From `docs/case_studies.json`, written by `python benchmarks/case_studies.py`"
             " (each model to zero defects, then an independent seeded Monte Carlo of the"
             " initial and the final tolerance box with the run's threshold d).  The method"
             " and the paper's figures are in `docs/synthesis.md`.", ""]
    lines.extend(case_table(data))
    machines = sorted({str(r["machine"]) for r in data.values()
                       if isinstance(r, dict) and r.get("machine")})
    if machines:
        lines += ["", f"Machine: {'; '.join(machines)}."]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------- document

def slug(text: str) -> str:
    """GitHub's anchor of a heading (without the duplicate suffix)."""
    t = re.sub(r"[^\w\- ]", "", text.strip().lower())
    return t.replace(" ", "-")


def anchors(doc: str) -> list:
    """(heading text, anchor) of every heading of ``doc``, duplicates numbered."""
    seen: dict = {}
    out = []
    for _, _, t in _headings(doc.splitlines()):
        s = slug(t)
        n = seen.get(s, 0)
        seen[s] = n + 1
        out.append((t, s if n == 0 else f"{s}-{n}"))
    return out


HEAD = """# Benchmarks

Measured speed and accuracy of the library.  Every part below was measured in one run of its
own script, on the machine and at the date it states; its ratios are against baselines
measured in the same run.  This file is put together from `docs/benchmarks/*.md` by
`benchmarks/assemble.py`; edit those, not this.

## Contents

{toc}

## How to reproduce

Run `python benchmarks/run_all.py` from the repository root (add `--quick` for a smaller
run).  It runs every `benchmarks/bench_*.py` script with the same Python, stops at the
first failure, and then rebuilds this file; each part can also be rerun on its own with
its script, followed by `python benchmarks/assemble.py`.  The synthesis case studies are
run separately with `python benchmarks/case_studies.py`, and the check of the batched
defect test's verdicts against the full test (every check list of the case studies,
2,000 box samples per model) with `python benchmarks/verify_batch.py`.
"""


def build(src: Path = SRC, out: Path = OUT, cases: Path | None = CASES) -> str:
    """The assembled document."""
    parts = []           # (title, source label, body, headline)
    for p in part_files(src):
        text = p.read_text(encoding="utf-8")
        parts.append((title_of(text, p.stem), p.name, relink(text, src, out), headline(text)))
    if cases is not None and Path(cases).is_file():
        try:
            data = json.loads(Path(cases).read_text(encoding="utf-8"))
        except json.JSONDecodeError as e:
            raise SystemExit(f"assemble: {cases}: not valid JSON ({e})") from None
        if not isinstance(data, dict):
            raise SystemExit(f"assemble: {cases}: expected an object of model name -> record")
        if data:
            parts.append((CASE_TITLE, Path(cases).name, case_section(data), {}))
    body = "\n".join(demote(b).rstrip("\n") + "\n" for _, _, b, _ in parts)
    # anchors: the head's own headings come first, then the parts' (demoted) headings
    head_titles = ["Benchmarks", "Contents", "How to reproduce"]
    all_anchors = anchors("\n".join(f"# {t}" for t in head_titles) + "\n" + body)
    part_anchor = {}
    k = len(head_titles)
    part_titles = {t for t, _, _, _ in parts}
    for t, a in all_anchors[k:]:
        if t in part_titles and t not in part_anchor:
            part_anchor[t] = a
    toc = []
    for t, label, _, h in parts:
        line = f"- [{t}](#{part_anchor.get(t, slug(t))}) — `{label}`"
        if h.get("date"):
            line += f", measured {h['date']}"
        toc.append(line)
        for tl in h.get("targets", ()):
            toc.append("  " + tl)
    if not toc:
        toc = ["(no benchmark reports found)"]
    return HEAD.format(toc="\n".join(toc)) + ("\n" + body if body else "")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--src", type=Path, default=SRC,
                    help="directory of the per-benchmark reports (default: %(default)s)")
    ap.add_argument("--out", type=Path, default=OUT, help="output file (default: %(default)s)")
    ap.add_argument("--case-studies", type=Path, default=CASES,
                    help="case-study JSON, used when it exists (default: %(default)s)")
    args = ap.parse_args(argv)
    text = build(args.src, args.out, args.case_studies)
    atomic_write(args.out, text)
    print(f"written: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
