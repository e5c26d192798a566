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
