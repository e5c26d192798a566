"""SIGINT and SIGTERM handlers of a run: the first signal raises and arms a
hard-exit timer, a second one (or the timer) ends the process with the
shell's status; ``restore`` puts the previous handlers back."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from synthesis.stopping import HARD_EXIT_AFTER, STATUS, StopSignals

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")

ROOT = Path(__file__).resolve().parents[2]


class Terminated(Exception):
    pass


def test_statuses_are_128_plus_the_signal():
    assert STATUS == {signal.SIGINT: 130, signal.SIGTERM: 143}
    assert all(v == 128 + int(k) for k, v in STATUS.items())
    assert HARD_EXIT_AFTER > 0


def _deliver(sig):
    os.kill(os.getpid(), sig)
    # the handler runs in the main thread between byte codes
    for _ in range(100):
        time.sleep(0.01)


@pytest.mark.parametrize("sig, exc", [(signal.SIGINT, KeyboardInterrupt),
                                      (signal.SIGTERM, Terminated)])
def test_first_signal_raises_and_restore_disarms(sig, exc):
    before = {s: signal.getsignal(s) for s in STATUS}
    stop = StopSignals(Terminated, after=60.0).install()
    try:
        assert all(signal.getsignal(s) == stop._handle for s in STATUS)
        with pytest.raises(exc):
            _deliver(sig)
        timer = stop._timer
        assert timer is not None and timer.is_alive() and timer.daemon
    finally:
        stop.restore()
    # the timer was cancelled: its thread ends without firing
    timer.join(5)
    assert stop._timer is None and not timer.is_alive()
    assert {s: signal.getsignal(s) for s in STATUS} == before


def test_restore_without_a_signal_leaves_the_old_handlers():
    def mine(signum, frame):
        pass
    old = signal.signal(signal.SIGTERM, mine)
    try:
        stop = StopSignals(Terminated).install()
        stop.restore()
        assert signal.getsignal(signal.SIGTERM) is mine
        stop.restore()                              # twice: nothing left to restore
        assert signal.getsignal(signal.SIGTERM) is mine
    finally:
        signal.signal(signal.SIGTERM, old)


def _child(body: str, after: float):
    """A Python process that installs the handlers (hard exit ``after`` s after a
    first signal), then runs ``body``, which reports ready once it can take a
    signal."""
    code = textwrap.dedent(f"""
        import os, signal, sys, time
        from synthesis.stopping import StopSignals

        class Terminated(Exception):
            pass

        stop = StopSignals(Terminated, after={after!r}).install()
    """) + textwrap.dedent(body)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, cwd=str(ROOT))


def _run(body, after, signals):
    """Exit status, output and error output of ``body`` sent ``signals``, and
    the seconds from the first signal to the end."""
    p = _child(body, after)
    try:
        assert p.stdout.readline().strip() == "ready"
        t0 = time.monotonic()
        for k, s in enumerate(signals):
            if k:
                time.sleep(0.3)
            p.send_signal(s)
        out, err = p.communicate(timeout=20)
        return p.returncode, out, err, time.monotonic() - t0
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()


WIND_DOWN_HANGS = """
try:
    print("ready", flush=True)
    while True:
        time.sleep(0.05)
except (KeyboardInterrupt, Terminated):
    print("winding down", flush=True)
    while True:
        time.sleep(0.05)
"""


def test_a_second_signal_ends_the_process_at_once():
    rc, out, err, took = _run(WIND_DOWN_HANGS, 60.0, [signal.SIGINT, signal.SIGINT])
    assert rc == 130
    assert "winding down" in out
    assert "stopped hard (second signal)" in err
    assert took < 10                         # long before the 60 s timer


def test_a_run_that_does_not_wind_down_is_ended_by_the_timer():
    rc, out, err, took = _run(WIND_DOWN_HANGS, 0.5, [signal.SIGTERM])
    assert rc == 143, err
    assert "winding down" in out
    assert "stopped hard (not wound down 0.5 s after the signal)" in err
    assert 0.5 <= took < 10


def test_a_run_that_winds_down_in_time_exits_normally():
    body = """
try:
    print("ready", flush=True)
    while True:
        time.sleep(0.05)
except Terminated:
    stop.restore()
    time.sleep(1.0)        # longer than the timer had
    print("clean", flush=True)
    sys.exit(3)
"""
    rc, out, err, _ = _run(body, 0.3, [signal.SIGTERM])
    assert rc == 3 and "clean" in out and "stopped hard" not in err
