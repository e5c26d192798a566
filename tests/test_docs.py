"""Every code block of README.md and docs/*.md runs (issue 24).

* ``python`` blocks of one file run in order in one namespace (a later block may
  use an earlier one's names), in a scratch folder holding a link to ``docs/``.
* ``bash``/``sh`` blocks run with ``bash -e`` there, with this interpreter's
  scripts (``cspace-tol``) first on ``PATH``.
* A block that cannot run in the suite (a long job, a cluster) is preceded by
  ``<!-- docs-test: skip: REASON -->``; the reason is required, and
  :func:`test_skip_marks_are_few_and_explained` lists them.
* ``text``, ``json`` and untagged blocks are not code (output, file fragments);
  an untagged block that starts with a command is an error, so a shell example
  cannot hide from this test by losing its tag.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w-]*)[ \t]*\n(?P<body>.*?)^(?P=indent)```",
                   re.S | re.M)
SKIP = re.compile(r"<!--\s*docs-test:\s*skip:\s*(?P<why>[^>]*?)\s*-->\s*$")
RUN = {"python": "python", "py": "python", "bash": "shell", "sh": "shell", "console": "shell"}


def blocks(path):
    """(lang, code, line, skip reason or None) of every fenced block."""
    text = path.read_text(encoding="utf-8")
    out = []
    for m in FENCE.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        before = text[:m.start()].rstrip("\n").splitlines()
        why = None
        if before:
            sm = SKIP.search(before[-1])
            why = sm.group("why") if sm else None
        body = "\n".join(ln[len(m.group("indent")):] if ln.startswith(m.group("indent")) else ln
                         for ln in m.group("body").splitlines())
        out.append((m.group("lang").lower(), body, line, why))
    return out


def _scratch(tmp_path):
    (tmp_path / "docs").symlink_to(ROOT / "docs", target_is_directory=True)
    return tmp_path


def _ids(paths):
    return [str(p.relative_to(ROOT)) for p in paths]


def test_the_collector_finds_the_blocks():
    found = {p.name: blocks(p) for p in DOCS}
    for name in ("README.md", "fourbar.md", "manipulators.md", "spatial.md", "synthesis.md",
                 "model_file.md"):
        assert any(RUN.get(lang) == "python" for lang, *_ in found[name]), name
    assert sum(len(b) for b in found.values()) >= 20


def test_untagged_blocks_are_not_commands():
    for p in DOCS:
        for lang, code, line, _ in blocks(p):
            if lang == "" and re.match(r"\s*(cspace-tol|python|pip|\$)", code):
                pytest.fail(f"{p.name}:{line}: an untagged block with a command; tag it bash")


def test_skip_marks_are_few_and_explained():
    marks = [(p.name, line, why) for p in DOCS for lang, _, line, why in blocks(p)
             if why is not None]
    assert all(len(why) > 10 for _, _, why in marks), marks
    # the README's two setup one-liners (a new venv: the main job of some minutes and
    # the suite itself) and the dask cluster example; a new mark is a decision
    assert len(marks) <= 3, marks


@pytest.mark.parametrize("path", DOCS, ids=_ids(DOCS))
def test_python_blocks_run(path, tmp_path, monkeypatch):
    code = [(c, line) for lang, c, line, why in blocks(path)
            if RUN.get(lang) == "python" and why is None]
    if not code:
        pytest.skip("no python block")
    import matplotlib
    matplotlib.use("Agg")
    monkeypatch.chdir(_scratch(tmp_path))
    ns = {"__name__": "__docs__"}
    for c, line in code:
        try:
            exec(compile(c, f"{path.name}:{line}", "exec"), ns)
        except Exception as e:  # name the block in the failure
            raise AssertionError(f"{path.name}, block at line {line}: "
                                 f"{type(e).__name__}: {e}") from e
    import matplotlib.pyplot as plt
    plt.close("all")


SHELL = [(p, line) for p in DOCS for lang, _, line, why in blocks(p)
         if RUN.get(lang) == "shell" and why is None]


@pytest.mark.parametrize("path, line", SHELL,
                         ids=[f"{p.relative_to(ROOT)}:{line}" for p, line in SHELL])
def test_shell_blocks_run(path, line, tmp_path):
    code = next(c for lang, c, ln, _ in blocks(path) if ln == line)
    env = dict(os.environ, MPLBACKEND="Agg",
               PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
               PYTHONPATH=f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}")
    r = subprocess.run(["bash", "-e", "-c", code], cwd=_scratch(tmp_path), env=env,
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, f"{path.name}:{line} exited {r.returncode}\n{r.stderr[-3000:]}"
