"""Process-tree helpers for the signal tests (Linux /proc), and a synthesis
run started and stopped as from a shell."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def start_synthesize(model, out, *extra, preset="fast"):
    """``python -m synthesis synthesize MODEL --out OUT`` on two process
    workers without plots, with ``extra`` options; stderr piped."""
    cmd = [sys.executable, "-m", "synthesis", "synthesize", model, "--out", str(out),
           "--preset", preset, "--executor", "process", "--workers", "2", "--no-plots",
           *extra]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # its own process group, as a shell job is: Ctrl-C goes to the whole group
    return subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, env=env, cwd=str(ROOT),
                            start_new_session=True)


def interrupt(p, timeout=60) -> str:
    """Ctrl-C (SIGINT) to the run ``p`` and wait for it to end: its stderr.
    Killed if it has not ended when the wait fails."""
    try:
        p.send_signal(signal.SIGINT)
        return p.communicate(timeout=timeout)[1]
    finally:
        if p.poll() is None:
            p.kill()


def _stat(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            s = f.read()
    except OSError:
        return None
    rest = s[s.rindex(")") + 2:].split()
    return rest[0], int(rest[1])          # state, ppid


def children(pid) -> list:
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            st = _stat(int(d))
            if st and st[1] == pid:
                out.append(int(d))
    return out


def descendants(pid) -> list:
    out, todo = [], [pid]
    while todo:
        kids = children(todo.pop())
        out += kids
        todo += kids
    return out


def alive(pid) -> bool:
    st = _stat(pid)
    return st is not None and st[0] not in ("Z", "X")


def wait_for(cond, timeout, step=0.1):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        v = cond()
        if v:
            return v
        time.sleep(step)
    return cond()


def cpu_seconds(pid) -> float:
    """User + system CPU time of a process, s (0 when it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            s = f.read()
    except OSError:
        return 0.0
    rest = s[s.rindex(")") + 2:].split()
    return (int(rest[11]) + int(rest[12])) / os.sysconf("SC_CLK_TCK")


def computing(pids, window=1.0, share=0.3) -> list:
    """The processes among ``pids`` that used more than ``share`` of a CPU over
    the next ``window`` seconds."""
    before = {p: cpu_seconds(p) for p in pids}
    time.sleep(window)
    return [p for p in pids if cpu_seconds(p) - before[p] > share * window]
