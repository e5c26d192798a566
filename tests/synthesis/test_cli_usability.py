"""The command line for a new user (issue 24): --version, checks before work,
--resume taking the checkpoint's preset, progress off a terminal."""

import json
from pathlib import Path

import pytest

from synthesis.cli import main

FAST = ["--executor", "serial", "--preset", "fast", "--no-plots"]


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    import cspace
    assert capsys.readouterr().out.strip() == f"cspace-tol {cspace.__version__}"


def _no_work(monkeypatch):
    import mechanisms.analysis as an

    def boom(*a, **k):
        raise AssertionError("computed before checking the output folder")
    monkeypatch.setattr(an, "model_cspaces", boom)
    import cspace.defects as de
    monkeypatch.setattr(de, "reference", boom)


@pytest.mark.parametrize("where", ["under-a-file", "proc"])
def test_unusable_out_fails_before_any_work(tmp_path, capsys, monkeypatch, where):
    if where == "proc":
        if not Path("/proc/self").is_dir():
            pytest.skip("no /proc")
        out = "/proc/x"
    else:
        (tmp_path / "f").write_text("")
        out = str(tmp_path / "f" / "x")
    _no_work(monkeypatch)
    assert main(["analyze", "reciprocating_cam", "--out", out]) == 2
    err = capsys.readouterr().err
    assert "--out must name a folder that can be created and written" in err and out in err
    assert main(["synthesize", "reciprocating_cam", "--out", out, *FAST]) == 2
    assert "--out must name a folder" in capsys.readouterr().err


def test_max_iter_zero_is_refused_and_writes_nothing(tmp_path, capsys, monkeypatch):
    _no_work(monkeypatch)
    out = tmp_path / "o"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--max-iter", "0",
                 *FAST]) == 2
    assert "--max-iter must be >= 1" in capsys.readouterr().err
    assert not out.exists()


def test_resume_takes_the_preset_from_the_checkpoint(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--max-iter", "1",
                 *FAST]) == 1
    capsys.readouterr()
    # no --preset: the checkpoint's ("fast"), not the parser's default
    no_preset = ["--executor", "serial", "--no-plots"]
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--max-iter", "1", *no_preset]) == 1
    err = capsys.readouterr().err
    assert "preset fast" in err and "accuracy" not in err
    assert json.loads((out / "report.json").read_text())["accuracy"]["name"] == "fast"
    # the same preset named explicitly is fine, another one is refused by flag
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--max-iter", "1", "--preset", "fast", *no_preset]) == 1
    capsys.readouterr()
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--preset", "default", *no_preset]) == 2
    err = capsys.readouterr().err
    assert "--preset default conflicts with the checkpoint" in err and "'fast'" in err
    assert err.count("\n") == 1        # one line, not an accuracy diff
