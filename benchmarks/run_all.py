"""Run every benchmark script, then assemble ``docs/BENCHMARKS.md``.

    python benchmarks/run_all.py            # full runs
    python benchmarks/run_all.py --quick    # smaller runs where a script offers --quick
    python benchmarks/run_all.py --list     # show what would run, run nothing

The scripts are ``benchmarks/bench_*.py``: ``bench_cspace.py``, ``bench_fourbar.py``,
``bench_spatial.py`` and ``bench_synthesis.py`` in this order, then any other by name.
Each runs as a subprocess of the same Python from the repository root, its output
passing through.  ``--quick`` is passed on only to the scripts whose argument parser
declares it; the others get no arguments.  The first script that fails stops the run
with its name and exit status, and the document is then not rebuilt.  Otherwise
``benchmarks/assemble.py`` builds ``docs/BENCHMARKS.md`` from the reports in
``docs/benchmarks/`` (and ``docs/case_studies.json``, which
``benchmarks/case_studies.py`` writes; that script is not run here).
"""

from __future__ import annotations

import argparse
import ast
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
ORDER = ("bench_cspace.py", "bench_fourbar.py", "bench_spatial.py", "bench_synthesis.py")


def scripts(folder: Path = HERE) -> list:
    """The benchmark scripts of ``folder`` in run order."""
    known = [folder / n for n in ORDER if (folder / n).is_file()]
    rest = sorted(p for p in folder.glob("bench_*.py") if p.name not in ORDER)
    return known + rest


def accepts_quick(path: Path) -> bool:
    """Whether the script's argument parser declares ``--quick``
    (an ``add_argument("--quick", ...)`` call anywhere in its source)."""
    try:
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    except (OSError, SyntaxError):
        return False
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and node.func.attr == "add_argument"):
            if any(isinstance(a, ast.Constant) and a.value == "--quick" for a in node.args):
                return True
    return False


def plan(quick: bool, folder: Path = HERE) -> list:
    """(script, arguments) of every run."""
    return [(p, ["--quick"] if quick and accepts_quick(p) else []) for p in scripts(folder)]


def _rel(p: Path) -> str:
    try:
        return str(p.relative_to(ROOT))
    except ValueError:
        return str(p)


def _reports(src: Path) -> dict:
    return {p.name: p.stat().st_mtime_ns for p in src.glob("*.md")} if src.is_dir() else {}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="pass --quick to the scripts that accept it")
    ap.add_argument("--list", action="store_true", help="print the runs and exit")
    args = ap.parse_args(argv)
    runs = plan(args.quick)
    if args.list:
        for p, a in runs:
            print(" ".join(["python", _rel(p), *a]))
        print("python benchmarks/assemble.py")
        return 0
    src = ROOT / "docs" / "benchmarks"
    t_all = time.perf_counter()
    silent = []
    for i, (p, a) in enumerate(runs, 1):
        print(f"\n=== [{i}/{len(runs)}] {' '.join(['python', _rel(p), *a])}", flush=True)
        before = _reports(src)
        t0 = time.perf_counter()
        try:
            rc = subprocess.run([sys.executable, str(p), *a], cwd=ROOT).returncode
        except KeyboardInterrupt:
            print(f"\nrun_all: interrupted during {_rel(p)}; docs/BENCHMARKS.md was not "
                  "rebuilt", file=sys.stderr)
            return 130
        dt = time.perf_counter() - t0
        if rc != 0:
            print(f"\nrun_all: FAILED: {_rel(p)} exited with status {rc} after {dt:.0f} s; "
                  f"stopping ({len(runs) - i} script(s) not run, docs/BENCHMARKS.md not "
                  "rebuilt)", file=sys.stderr)
            return rc if 0 < rc < 256 else 1
        after = _reports(src)
        if not any(after.get(k) != before.get(k) for k in after):
            silent.append(p)
        print(f"=== {_rel(p)}: done in {dt:.0f} s", flush=True)
    sys.path.insert(0, str(HERE))
    import assemble
    print("\n=== python benchmarks/assemble.py", flush=True)
    assemble.main([])
    print(f"run_all: {len(runs)} script(s) in {time.perf_counter() - t_all:.0f} s", flush=True)
    if silent:
        print("run_all: note: " + ", ".join(p.name for p in silent) + " wrote no report in "
              "docs/benchmarks/ (they print their tables); their sections of "
              "docs/BENCHMARKS.md are the reports already there", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
