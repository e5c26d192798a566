"""Process-tree helpers for the signal tests (Linux /proc)."""

import os
import time


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
