"""``cspace-tol synthesize``: outputs, checkpoint, SIGTERM and --resume."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from synthesis.cli import main

ROOT = Path(__file__).resolve().parents[3]


def _plain_report(path):
    d = json.loads(Path(path).read_text())
    d.pop("time", None)
    for h in d["history"]:
        h.pop("times", None)
    return d


@pytest.fixture(scope="module")
def full_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("syn") / "recip"
    rc = main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
               "--preset", "fast", "--verify", "40", "--seed", "2"])
    return rc, out


def test_synthesize_writes_report_geometry_plots_and_checkpoint(full_run):
    rc, out = full_run
    assert rc == 0
    names = {p.name for p in out.iterdir()}
    assert {"report.json", "checkpoint.json", "pair.json", "pair_initial.json",
            "zones_before.png", "zones_after.png", "zones.png", "defects.png"} <= names
    rep = json.loads((out / "report.json").read_text())
    assert rep["success"] and rep["status"] == "CONVERGED" and rep["units"] == "cm"
    assert rep["defects_per_iteration"][-1] == 0 and rep["defects_per_iteration"][0] > 0
    assert rep["verification"]["final"]["defective"] == 0
    assert rep["verification"]["final"]["samples"] == 40
    assert set(rep["files"]) >= {"pair.json", "report.json"}
    ck = json.loads((out / "checkpoint.json").read_text())
    assert ck["format"] == "cspace-synthesis-checkpoint" and ck["status"] == "CONVERGED"
    # the final pair is the synthesized nominal geometry
    from cspace.io import load_pair
    from mechanisms.models import reciprocating_cam
    import numpy as np
    m = reciprocating_cam()
    final = m.with_nominal(np.array(rep["final"]["nominal"])).build()
    assert load_pair(out / "pair.json") == final


def test_unfinished_checkpoint_is_not_overwritten(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
                 "--preset", "fast", "--max-iter", "1", "--no-plots"]) == 1
    ck = json.loads((out / "checkpoint.json").read_text())
    assert ck["status"] == "MAX_ITER"
    rc = main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
               "--preset", "fast", "--no-plots"])
    assert rc == 2 and "--resume" in capsys.readouterr().err
    assert json.loads((out / "checkpoint.json").read_text()) == ck


def test_cli_errors_are_clear(tmp_path, capsys):
    assert main(["synthesize", "reciprocating_cam", "--out", str(tmp_path / "x"),
                 "--resume"]) == 2
    assert "no checkpoint" in capsys.readouterr().err
    assert main(["synthesize", "reciprocating_cam", "--out", str(tmp_path / "x"),
                 "--executor", "dask"]) == 2
    assert "--scheduler" in capsys.readouterr().err
    pair = tmp_path / "p"
    assert main(["analyze", "reciprocating_cam", "--out", str(pair), "--no-plots"]) == 0
    capsys.readouterr()
    assert main(["synthesize", str(pair / "pair.json"), "--out", str(tmp_path / "y")]) == 2
    assert "parametric model" in capsys.readouterr().err


def test_patience_option_is_checked_and_kept_in_the_checkpoint(tmp_path, capsys):
    out = tmp_path / "p"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--patience", "0"]) == 2
    assert "--patience must be >= 1, got 0" in capsys.readouterr().err
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
                 "--preset", "fast", "--max-iter", "1", "--patience", "2", "--no-plots"]) == 1
    saved = json.loads((out / "checkpoint.json").read_text())
    assert saved["patience"] == 2 and saved["two_sided"] is True   # on by default
    capsys.readouterr()
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
                 "--preset", "fast", "--resume", "--patience", "3", "--no-plots"]) == 2
    assert "checkpoint used patience 2" in capsys.readouterr().err
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
                 "--preset", "fast", "--resume", "--no-two-sided", "--no-plots"]) == 2
    assert "checkpoint used two_sided True" in capsys.readouterr().err
    # the paper's order on request
    one = tmp_path / "one-sided"
    assert main(["synthesize", "reciprocating_cam", "--out", str(one), "--executor", "serial",
                 "--preset", "fast", "--max-iter", "1", "--no-two-sided", "--no-plots"]) == 1
    assert json.loads((one / "checkpoint.json").read_text())["two_sided"] is False
    assert json.loads((one / "report.json").read_text())["two_sided"] is False


def test_sigterm_leaves_a_checkpoint_and_resume_reproduces(full_run, tmp_path):
    _, ref_out = full_run
    out = tmp_path / "r"
    cmd = [sys.executable, "-m", "synthesis", "synthesize", "reciprocating_cam", "--out",
           str(out), "--executor", "serial", "--preset", "fast", "--no-plots"]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, env=env, cwd=str(ROOT))
    ck = out / "checkpoint.json"
    t0 = time.monotonic()
    def iterations():
        # a checkpoint is written from the first iteration's start; wait for
        # the one after an iteration
        try:
            return len(json.loads(ck.read_text())["history"])
        except (OSError, ValueError, KeyError):
            return 0

    while iterations() < 1 and p.poll() is None and time.monotonic() - t0 < 300:
        time.sleep(0.05)
    assert p.poll() is None, "the run ended before its first iteration's checkpoint"
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 143, err
    assert "--resume" in err and "terminated" in err
    state = json.loads(ck.read_text())
    assert state["status"] == "RUNNING" and len(state["history"]) >= 1
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
                 "--preset", "fast", "--no-plots", "--resume"]) == 0
    a = _plain_report(out / "report.json")
    b = _plain_report(ref_out / "report.json")
    a.pop("files"), b.pop("files"), b.pop("verification")
    assert a == b
