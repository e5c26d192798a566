"""Small helpers shared by the benchmark scripts (not a benchmark itself)."""

from __future__ import annotations

import math
import os


def load_average():
    """The (1, 5, 15 min) load average rounded to 0.01, or None where the system
    has none."""
    try:
        return tuple(round(x, 2) for x in os.getloadavg())
    except (AttributeError, OSError):
        return None


def fmt_seconds(s) -> str:
    """A duration for a table: ms below 1 s, two decimals below 100 s, "—" if unknown."""
    if s is None or not math.isfinite(s):
        return "—"
    if s < 1.0:
        return f"{s * 1e3:.0f} ms"
    if s < 100.0:
        return f"{s:.2f} s"
    return f"{s:.0f} s"


# ------------------------------------------------- boundary accuracy of a C-space
import numpy as np  # noqa: E402

_FRACS = np.arange(1, 8) / 8.0


def _wrapped(d, periodic):
    """|d|, wrapped into (-pi, pi] first for a periodic coordinate."""
    d = np.asarray(d, dtype=float)
    if periodic:
        d = (d + math.pi) % (2 * math.pi) - math.pi
    return np.abs(d)


def polyline_error(cs, scale2: float = 1.0) -> dict:
    """Largest distance between the boundary polylines and the exact curves.

    Each polyline segment of ``cs.curve_polylines(boundary_only=True)`` is compared
    with the exact curve of the same feature pair and branch at 7 interior points
    (the midpoint among them): vertically (q2 at the same q1, times ``scale2``) and
    normal to the segment (the measure ``Accuracy.chord`` bounds when ``scale2`` is
    the C-space metric).  Returns ``max`` (vertical), ``max_mid`` (at midpoints),
    ``max_normal``, ``segments`` and ``where`` (label, branch, q1, slope) of ``max``.
    """
    per = bool(cs.periodic[1])
    bykey: dict = {}
    for b in cs.boundary:
        c = cs.curves[b.curve]
        bykey.setdefault((c.label, c.branch), {})[id(c.kernel)] = c
    worst, worst_mid, worst_n, n_seg, where = 0.0, 0.0, 0.0, 0, None
    for label, branch, pl in cs.curve_polylines(boundary_only=True):
        t0, t1 = pl[:-1, 0], pl[1:, 0]
        v0, v1 = pl[:-1, 1], pl[1:, 1]
        keep = t1 > t0
        t0, t1, v0, v1 = t0[keep], t1[keep], v0[keep], v1[keep]
        if t0.size == 0:
            continue
        n_seg += t0.size
        t = t0[:, None] + _FRACS[None, :] * (t1 - t0)[:, None]
        chord = v0[:, None] + _FRACS[None, :] * (v1 - v0)[:, None]
        err = np.full(t.shape, np.inf)
        for c in bykey[(label, branch)].values():
            with np.errstate(invalid="ignore"):
                e = _wrapped(c.raw(t.ravel()).reshape(t.shape) - chord, per) * scale2
            err = np.fmin(err, e)
        if not np.all(np.isfinite(err)):
            raise RuntimeError(f"boundary polyline of {label} (branch {branch}) leaves its curve")
        dt, dv = t1 - t0, v1 - v0
        cos = (dt / np.hypot(dt, dv * scale2))[:, None]
        k = np.unravel_index(int(np.argmax(err)), err.shape)
        if err[k] > worst:
            worst, where = float(err[k]), (label, branch, float(t[k]), float(dv[k[0]] / dt[k[0]]))
        worst_mid = max(worst_mid, float(np.max(err[:, 3])))
        worst_n = max(worst_n, float(np.max(err * cos)))
    return {"max": worst, "max_mid": worst_mid, "max_normal": worst_n, "segments": n_seg,
            "where": where}


def boundary_ends(cs) -> np.ndarray:
    """(n, 2) end points of the boundary pieces of ``cs``."""
    pts = []
    for b in cs.boundary:
        c = cs.curves[b.curve]
        x = np.array([b.q1_start, b.q1_end])
        pts.append(np.stack([x, c.evaluate(x)], 1))
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def endpoint_error(cs, ref, scale2: float = 1.0, q1_only: bool = False) -> float:
    """Hausdorff distance (max-norm, wrapped, q2 times ``scale2``) between the
    boundary-piece end points of ``cs`` and of the reference C-space ``ref``; with
    ``q1_only`` the largest q1 difference of the nearest pairs (both ways) instead."""
    a, b = boundary_ends(cs), boundary_ends(ref)
    if len(a) == 0 and len(b) == 0:
        return 0.0
    if len(a) == 0 or len(b) == 0:
        return math.inf
    d1 = _wrapped(a[:, None, 0] - b[None, :, 0], cs.periodic[0])
    d = np.maximum(d1, _wrapped(a[:, None, 1] - b[None, :, 1], cs.periodic[1]) * scale2)
    if q1_only:
        ia, ib = d.argmin(axis=1), d.argmin(axis=0)
        return float(max(d1[np.arange(len(a)), ia].max(), d1[ib, np.arange(len(b))].max()))
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


# ------------------------------------------------------------ process-pool start
def warm_worker(pause: float) -> int:
    """Worker warm-up: import what a defect test needs, then hold the worker a
    moment so that the next warm-up task goes to another worker."""
    import time

    import cspace.defects  # noqa: F401
    import synthesis.executors  # noqa: F401
    time.sleep(pause)
    return os.getpid()


def start_pool(ex, workers: int) -> float:
    """Start every worker of a fresh process pool; seconds taken."""
    import time
    from concurrent.futures import wait
    t0 = time.perf_counter()
    wait([ex.submit(warm_worker, 0.3) for _ in range(workers)])
    return time.perf_counter() - t0
