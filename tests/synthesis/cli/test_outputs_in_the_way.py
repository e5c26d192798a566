"""A folder in DIR where ``synthesize`` writes a file is refused before the run
(no computing lost), naming the real path; a write that fails after the run
names its target and says how to write the outputs later."""

import importlib

import pytest

from synthesis.cli import main

ARGS = ["synthesize", "reciprocating_cam", "--preset", "fast", "--executor", "serial",
        "--no-plots", "--max-iter", "1"]


@pytest.mark.parametrize("name", ["report.md", "checkpoint.json", "zones_before.png"])
def test_a_folder_in_the_way_is_refused_before_the_run(tmp_path, capsys, monkeypatch, name):
    cli = importlib.import_module("synthesis.cli.main")

    def no_run(*a, **k):
        raise AssertionError("the run started")
    monkeypatch.setattr(cli, "_run_synthesis", no_run)
    out = tmp_path / "o"
    (out / name).mkdir(parents=True)
    assert main([*ARGS, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and ".tmp" not in err
    assert f"{out / name} is a directory" in err and "expected a file" in err


def test_a_failed_output_write_names_its_target(tmp_path, capsys, monkeypatch):
    report = importlib.import_module("synthesis.cli.report")
    real = report.write_outputs
    out = tmp_path / "o"

    def write_outputs(*a, **k):
        (out / "report.md").mkdir()      # appears while the run is computing
        return real(*a, **k)
    monkeypatch.setattr(report, "write_outputs", write_outputs)
    assert main([*ARGS, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"error: cannot use '{out / 'report.md'}'" in err and ".tmp" not in err
    assert "found a directory" in err and "rerun with --resume" in err
    # the finished run is kept: --resume writes its outputs
    monkeypatch.undo()
    (out / "report.md").rmdir()
    assert main([*ARGS, "--out", str(out), "--resume"]) == 1
    assert (out / "report.md").is_file()
