"""SIGINT or SIGTERM to the main process, or Ctrl-C to the process group, stops
``synthesize`` within seconds, leaves a valid checkpoint and exits with the
documented status: 130 for SIGINT, 143 for SIGTERM (issue 23, item 11).  A
stop inside an iteration keeps the defect tests it had finished, writes a
report with status INTERRUPTED, and ``--resume`` continues to the
uninterrupted run's result (issue 24)."""

import json

import os
import signal
import subprocess
import sys
import time

import pytest

from synthesis.checkpoint import read_checkpoint

from .proc_util import (ROOT, alive, computing, descendants, interrupt, start_synthesize,
                        wait_for)

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="reads the process tree from /proc")

#: How soon the run must have ended after the signal, s.
STOP_WITHIN = 10.0


def _signal_and_check(p, how, status):
    kids = descendants(p.pid)
    assert kids, "no pool workers were running"
    t0 = time.monotonic()
    try:
        if how == "group":
            os.killpg(p.pid, signal.SIGINT)
        else:
            os.kill(p.pid, how)
        _, err = p.communicate(timeout=STOP_WITHIN + 20)
        took = time.monotonic() - t0
        assert took < STOP_WITHIN, f"stopped {took:.1f} s after the signal"
        assert p.returncode == status, err
        assert "Traceback" not in err
        assert wait_for(lambda: not any(alive(k) for k in kids), 5), "workers outlived the run"
        return err
    finally:
        if p.poll() is None:
            p.kill()
        for k in kids:
            if alive(k):
                os.kill(k, signal.SIGKILL)


@pytest.mark.parametrize("how, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143),
                                         ("group", 130)],
                         ids=["sigint-main", "sigterm-main", "ctrl-c-group"])
def test_signal_after_a_checkpoint(tmp_path, how, status):
    out = tmp_path / "o"
    p = start_synthesize("reciprocating_cam", out)
    ck = out / "checkpoint.json"
    wait_for(lambda: _iterations(ck) >= 1 or p.poll() is not None, 300, step=0.05)
    assert p.poll() is None, "the run ended before its first iteration's checkpoint"
    err = _signal_and_check(p, how, status)
    assert "--resume" in err
    state, verified = read_checkpoint(ck)
    assert verified and state.iterations >= 1
    assert not (out / ".cspace-tol.lock").exists()


@pytest.mark.parametrize("how, status", [(signal.SIGINT, 130), ("group", 130)],
                         ids=["sigint-main", "ctrl-c-group"])
def test_signal_during_a_long_first_iteration(tmp_path, how, status):
    # Geneva's first iteration takes minutes: the workers must not finish it
    out = tmp_path / "o"
    p = start_synthesize("geneva", out, "--checkpoint-every", "0", preset="default")
    ck = out / "checkpoint.json"
    # the workers are computing defect tests, and some have finished
    assert wait_for(lambda: p.poll() is not None or _kept(ck) > 0, 600, step=0.2)
    assert p.poll() is None and computing(descendants(p.pid))
    err = _signal_and_check(p, how, status)
    assert "iteration 1" in err and "--resume" in err
    state, verified = read_checkpoint(ck)
    assert verified and state.iterations == 0 and state.partial.iteration == 1
    assert len(state.partial.tests) > 0
    rep = json.loads((out / "report.json").read_text())
    assert rep["status"] == "INTERRUPTED" and rep["success"] is False
    assert rep["interrupted"]["tests_kept"] == len(state.partial.tests)
    assert "INTERRUPTED" in (out / "report.md").read_text()


def _checkpoint(ck):
    try:
        return read_checkpoint(ck)[0]
    except Exception:        # not there yet, or being replaced
        return None


def _iterations(ck) -> int:
    st = _checkpoint(ck)
    return -1 if st is None else st.iterations


def _kept(ck) -> int:
    st = _checkpoint(ck)
    return 0 if st is None or st.partial is None else len(st.partial.tests)


def _comparable(out) -> dict:
    rep = json.loads((out / "report.json").read_text())
    for k in ("time", "files"):
        rep.pop(k, None)
    for h in rep["history"]:
        h.pop("times", None)
    return rep


def test_resume_after_a_stop_inside_an_iteration_gives_the_same_report(tmp_path):
    # a stop after the first batch of tests of an iteration, then --resume: the
    # report is the uninterrupted run's
    ref_out = tmp_path / "whole"
    whole = start_synthesize("reciprocating_cam", ref_out, "--max-iter", "2")
    _, err = whole.communicate(timeout=600)
    assert whole.returncode in (0, 1), err
    out = tmp_path / "o"
    p = start_synthesize("reciprocating_cam", out, "--max-iter", "2", "--checkpoint-every", "0")
    ck = out / "checkpoint.json"
    try:
        assert wait_for(lambda: p.poll() is not None or _kept(ck) > 0, 300, step=0.02)
        assert p.poll() is None, "the run ended before a test of iteration 1 was kept"
        err = interrupt(p)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, err
    state, _ = read_checkpoint(ck)
    assert state.partial is not None and len(state.partial.tests) > 0
    assert json.loads((out / "report.json").read_text())["status"] == "INTERRUPTED"
    again = start_synthesize("reciprocating_cam", out, "--max-iter", "2", "--resume")
    _, err = again.communicate(timeout=600)
    assert again.returncode == whole.returncode, err
    assert "finished defect test(s) of iteration" in err
    assert _comparable(out) == _comparable(ref_out)


def test_a_hung_wind_down_is_ended_hard():
    # an interrupt whose handling hangs (here: a lock that is never released)
    # still ends the process, with the signal's status
    script = (
        "import threading, time\n"
        "from synthesis.stopping import StopSignals\n"
        "class T(Exception): pass\n"
        "StopSignals(T, after=1.0).install()\n"
        "lock = threading.Lock(); lock.acquire()\n"
        "try:\n"
        "    print('ready', flush=True)\n"
        "    time.sleep(60)\n"
        "except (KeyboardInterrupt, T):\n"
        "    lock.acquire()\n")
    for sig, status in ((signal.SIGINT, 130), (signal.SIGTERM, 143)):
        p = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, cwd=str(ROOT))
        try:
            assert p.stdout.readline().strip() == "ready"
            t0 = time.monotonic()
            p.send_signal(sig)
            _, err = p.communicate(timeout=20)
            assert time.monotonic() - t0 < 5
            assert p.returncode == status and "stopped hard" in err
        finally:
            if p.poll() is None:
                p.kill()
