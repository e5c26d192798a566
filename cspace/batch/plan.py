"""The nominal motion of one pair, laid out for batched evaluation.

A :class:`PathPlan` is computed once per nominal design and pair.  It holds:

* the driver samples of the nominal simulation (``SimulationResult.q1``: the
  uniform output samples and every event the motion crosses) and the nominal
  output ``f0`` there;
* the cell of the nominal motion at each sample, with its lower and upper
  bounding curves;
* the *candidates* of every cell: the contact curves of its slab and of the
  two neighbouring slabs that lie below the channel (they can only bound it
  from below) or above it.  In a variant the channel's lower bound is the
  largest valid below-candidate and its upper bound the smallest valid
  above-candidate; the neighbouring slabs' curves are candidates too because a
  variant's events move, so a curve that starts just after a nominal event may
  start just before it.

The plan does not depend on the variants; which candidates are kept for a
batch (the ones that a variant of the batch can bring near the channel) is
decided by :func:`cspace.batch.margins.defect_margins`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geom2d import TWO_PI
from ..tolerances import SLACK

__all__ = ["PathPlan", "path_plan"]

#: Validity margins down to this (characteristic lengths or rad) count as a
#: valid contact: event samples lie on curve ends to ``Accuracy.root_tol``.
VALID_TOL = 1e-7


@dataclass(frozen=True, eq=False)
class PathPlan:
    """The nominal motion of one pair for :func:`~cspace.batch.margins.defect_margins`.

    Attributes
    ----------
    pair : int
        Index of the pair in the model.
    x : (N,) float
        Driver samples along the drive (unwrapped).
    xw : (N,) float
        The same, in the C-space window.
    f0 : (N,) float
        Nominal output (follower coordinate, continuous).
    is_ref : (N,) bool
        The samples of the nominal simulation (where the deviation is
        measured, as :func:`cspace.defects.is_defective` does); the others
        refine the driver where the follower is let go (and around events,
        see :func:`path_plan`).
    cell : (N,) int
        Index into ``cells`` of the path cell at each sample.
    cells : tuple of (int, int)
        (slab, cell) of the cells the nominal motion passes through, in order.
    lower, upper : (N,) int
        Curve index of the path cell's lower and upper bound (-1: window edge).
    lo0, hi0 : (N,) float
        Nominal channel bounds (continuous follower coordinates; +-inf where a
        rotating follower's cell is unbounded).
    candidates : dict
        ``(curve, side) -> (M,) int`` sample indices where the curve is a
        candidate bound: side +1 below the channel (a lower bound), -1 above.
    distance : dict
        ``(curve, side) -> (M,) float``: how far the nominal curve (its closed
        form, valid there or not) lies from the channel at those samples
        (C-space metric, >= 0).
    margin0 : dict
        ``(curve, side) -> (M,) float``: the nominal curve's validity margin
        at those samples (>= 0 where it is a real contact).
    margin_near : dict or None
        The same, the largest within ``reach`` of driver motion of each sample
        (:func:`path_plan`): where a variant's contact may be real, its start
        and end moved as its events move.
    key : (n_curves,) int
        Per curve of the C-space, the index of its contact equation and branch
        (a curve split at the window seam, or trimmed into pieces, is one key):
        the identity a contact sequence is compared by.
    place : dict
        ``(curve, side) -> (M,) float``: the nominal curve's value there as a
        continuous follower coordinate, on the turn where it lies below
        (side +1) or above (side -1) the channel; a variant's value is placed
        by its difference from the nominal one.
    start : float
        Follower start coordinate.
    periodic2 : bool
        The follower rotates.
    window : tuple
        The C-space window.
    scale2 : float
        Follower coordinate that counts as 1 in the C-space metric.
    scale1 : float
        Driver coordinate that counts as 1 in the C-space metric.
    bias : int
        The follower's closure in the nominal motion (``SimulationResult.bias``):
        0 form closure, -1 or +1 held toward decreasing or increasing q2.
    on_grid : (N,) bool or None
        The samples every variant's simulation has too (the drive's regular
        samples, :func:`cspace.simulate.drive_grid`, when the driver rotates:
        a sliding driver's step is a share of each variant's own
        characteristic length), where the full test reads a variant's output
        without interpolation; None: not known (none).
    cyclic : bool
        The nominal motion ends where it starts after whole turns of the
        driver (:func:`cspace.match.closed_motion`): its contact sequences
        are compared as cycles, as the full test compares them.
    resolved : bool
        The extra samples are ``fine`` apart as asked (False: a step so fine,
        from a tiny deviation threshold, that they were spread
        :data:`REFINE_MAX` a side instead; the batch then certifies nothing
        and leaves every verdict to the full test).
    """

    pair: int
    x: np.ndarray
    xw: np.ndarray
    f0: np.ndarray
    is_ref: np.ndarray
    cell: np.ndarray
    cells: tuple
    lower: np.ndarray
    upper: np.ndarray
    lo0: np.ndarray
    hi0: np.ndarray
    candidates: dict
    distance: dict
    margin0: dict
    place: dict
    key: np.ndarray
    start: float
    periodic2: bool
    window: tuple
    scale2: float
    scale1: float
    bias: int = 0
    on_grid: np.ndarray | None = None
    margin_near: dict | None = None
    cyclic: bool = False
    resolved: bool = True

    @property
    def n(self) -> int:
        return len(self.x)

    def __repr__(self):
        return (f"<PathPlan pair {self.pair}: {self.n} samples, {len(self.cells)} cells, "
                f"{len(self.candidates)} candidate curves>")


def _event_samples(cs, x) -> np.ndarray:
    """Which samples lie on an event of the C-space (wrapped to the window)."""
    ev = cs.events
    lo1, hi1 = cs.window[0], cs.window[1]
    if cs.periodic[0]:
        period = hi1 - lo1
        k = np.floor((x - lo1) / period)
        out = np.zeros(len(x), dtype=bool)
        for e in ev[:-1]:
            out |= x == e + k * period
            out |= x == e + (k + 1) * period
            out |= x == e + (k - 1) * period
        return out
    return np.isin(x, ev[1:-1])


def _sample_cells(cs, sim, xw, at_event) -> np.ndarray:
    """Index into ``sim.cells`` of the path cell at every sample.

    The simulation walks the cells in order: a sample in slab k belongs to the
    next visited cell of that slab; a sample on an event still belongs to the
    cell before it (the simulation evaluates the event in the cell it leaves)."""
    slabs = cs.slab_of(xw)
    visited = sim.cells
    out = np.zeros(len(xw), dtype=int)
    p = 0
    for i in range(len(xw)):
        if not at_event[i] or i == 0:
            k = int(slabs[i])
            q = p
            while q < len(visited) and visited[q][0] != k:
                q += 1
            if q < len(visited):
                p = q
        out[i] = p
    return out


#: The nominal output between simulation samples is interpolated; it may lie
#: this far (rad) on the wrong side of the curve pushing it.
_INTERP_SLACK = 1e-2


def _unwrap_below(ref, v, slack: float = _INTERP_SLACK):
    """The value of v (mod 2 pi) at or below ref, within one turn (a value up
    to ``slack`` above ref, by rounding or interpolation, stays above it)."""
    dv = (ref - v) % TWO_PI
    dv = np.where(dv > TWO_PI - slack, dv - TWO_PI, dv)
    return ref - dv


def _unwrap_above(ref, v, slack: float = _INTERP_SLACK):
    """The value of v (mod 2 pi) at or above ref (see :func:`_unwrap_below`)."""
    dv = (v - ref) % TWO_PI
    dv = np.where(dv > TWO_PI - slack, dv - TWO_PI, dv)
    return ref + dv


def _bounds0(cs, idx, xw, f0, periodic2):
    """Nominal channel bounds of the cells ``idx`` (curve index or -1) at the samples."""
    lo2, hi2 = cs.window[2], cs.window[3]
    lo0 = np.full(len(xw), -math.inf if periodic2 else lo2)
    hi0 = np.full(len(xw), math.inf if periodic2 else hi2)
    low, up = idx
    for c in np.unique(np.concatenate([low, up])):
        if c < 0:
            continue
        for arr, out, fn in ((low, lo0, _unwrap_below), (up, hi0, _unwrap_above)):
            sel = np.nonzero(arr == c)[0]
            if not len(sel):
                continue
            v = cs.curves[c].raw(xw[sel])
            out[sel] = fn(f0[sel], v) if periodic2 else v
    return lo0, hi0


#: :func:`_refined`: the most extra samples on either side of an event
#: sample, and in all.  A finer step asked for (the resolution of a tiny
#: deviation threshold: d = 1e-9 asked for 2.5e9 a side on the Geneva pair)
#: is widened to fit, and the plan says it is not resolved
#: (:attr:`PathPlan.resolved`).  The models of the tests ask for 9 to 313 a
#: side.
REFINE_MAX = 4096
REFINE_TOTAL = 200_000


def _refined(x, at_event, fine: float, width: float):
    """The samples ``x`` (monotone) and samples ``fine`` apart within ``width``
    of every event sample, in order; which of them are the original ones; and
    whether ``fine`` was kept (False: it asked for more than
    :data:`REFINE_MAX` samples a side, or :data:`REFINE_TOTAL` in all, and
    they are that many)."""
    if fine <= 0 or width <= 0 or not at_event.any():
        return x, np.ones(len(x), dtype=bool), True
    sgn = 1.0 if x[-1] >= x[0] else -1.0
    lo, hi = min(x[0], x[-1]), max(x[0], x[-1])
    need = math.ceil(width / fine) if math.isfinite(width / fine) else math.inf
    cap = max(16, min(REFINE_MAX, REFINE_TOTAL // (2 * int(at_event.sum()))))
    kept = need <= cap
    if not kept:
        fine = width / cap
    k = int(min(need, cap))
    offs = fine * np.arange(-k, k + 1)
    extra = (x[at_event][:, None] + offs[None, :]).ravel()
    extra = extra[(extra > lo) & (extra < hi)]
    allx = np.concatenate([x, extra])
    ref = np.concatenate([np.ones(len(x), dtype=bool), np.zeros(len(extra), dtype=bool)])
    order = np.lexsort((~ref, sgn * allx))
    allx, ref = allx[order], ref[order]
    # a new sample within a tenth of the fine step of an older one adds nothing
    keep = np.ones(len(allx), dtype=bool)
    close = np.abs(np.diff(allx)) < 0.1 * fine
    keep[1:] &= ~(close & ~ref[1:])
    keep[:-1] &= ~(close & ~ref[:-1] & ref[1:])
    return allx[keep], ref[keep], kept


def path_plan(cs, sim, pair: int, start: float, reach: float = 0.25, fine: float = 0.0,
              width: float = 0.0, events: bool = True) -> PathPlan:
    """The :class:`PathPlan` of the nominal motion ``sim`` in C-space ``cs``.

    ``reach``: how far (driver motion, C-space metric) a variant's events may
    move from the nominal ones.  ``fine``, ``width``: extra samples ``fine``
    apart within ``width`` (driver motion, C-space metric) of every point
    where the follower is let go and, with ``events``, of every event the
    motion crosses, where contacts hand over and short ones come and go.
    :func:`~cspace.batch.margins.defect_margins` samples each variant's own
    hand-overs instead (``margins._handovers``): a variant's events move
    away from the nominal's."""
    from ..match import closed_motion
    from ..metric import driver_scale, follower_scale
    L = cs.pair.char_length
    s1 = driver_scale(cs.pair)
    x0 = np.asarray(sim.q1, dtype=float)
    lo1, hi1 = cs.window[0], cs.window[1]
    # where contacts hand over (events) and where the follower is let go (the
    # pushing bound peaks between samples), extra samples resolve both
    contact = np.array([c != "" for c in sim.contact], dtype=bool)
    release = np.zeros(len(x0), dtype=bool)
    if len(contact) == len(x0) and len(x0) > 1:
        release[1:] = contact[:-1] & ~contact[1:]
    around = release | _event_samples(cs, x0) if events else release
    x, is_ref, resolved = _refined(x0, around, fine * s1, width * s1)
    f0 = np.asarray(sim.q2, dtype=float) if len(x) == len(x0) else sim.output_at(x)
    if len(x) != len(x0):
        f0[is_ref] = sim.q2
    xw = (x - lo1) % (hi1 - lo1) + lo1 if cs.periodic[0] else x.copy()
    at_event = _event_samples(cs, x)
    cell = _sample_cells(cs, sim, xw, at_event)
    cells = tuple(tuple(int(v) for v in kj) for kj in sim.cells)
    lower = np.array([cs.cells[k][j].lower for k, j in cells], dtype=int)[cell]
    upper = np.array([cs.cells[k][j].upper for k, j in cells], dtype=int)[cell]
    periodic2 = bool(cs.periodic[1])
    lo0, hi0 = _bounds0(cs, (lower, upper), xw, f0, periodic2)
    # slab ranges of the path cells, in path order (unwrapped driver values)
    first = np.full(len(cells), np.inf)
    last = np.full(len(cells), -np.inf)
    np.minimum.at(first, cell, x)
    np.maximum.at(last, cell, x)
    act = [cs.active(k) for k, _ in cells]
    # a motion that ends where it starts goes on from its end at its start:
    # the cells near its end are near its start too (a variant's hand-over
    # there moves across the start)
    cyclic = closed_motion(cs, sim)
    period = float(x0[-1] - x0[0]) if cyclic else None
    shifts = (0.0, period, -period) if cyclic else (0.0,)
    # the same, in the C-space metric (the windows below measure in it)
    per = period / s1 if cyclic else None
    cand: dict = {}
    for p, (k, j) in enumerate(cells):
        sel = np.nonzero(cell == p)[0]
        if not len(sel):
            continue
        # the curves of the path cells within ``reach`` of driver motion: a
        # variant's events move, so a curve that ends just before this cell
        # may reach into it; each takes its side from the nearest path cell
        # where it bounds a cell of the slab (a curve bounds from below, or
        # from above: that does not change along it)
        near = [q for q in range(len(cells))
                if any(first[q] + t - reach * s1 <= last[p] and last[q] + t + reach * s1
                       >= first[p] for t in shifts)]
        near.sort(key=lambda q: abs(q - p), reverse=True)
        sides = {}
        for q in near:
            kq, jq = cells[q]
            for c in act[q]:
                s = _side(cs, c, kq, jq, periodic2)
                if s:
                    sides[c] = s
        for c, s in sides.items():
            cand.setdefault((c, s), []).append(sel)
    cand = {key: np.unique(np.concatenate(v)) for key, v in cand.items()}
    scale2 = follower_scale(cs.pair)
    dist, marg, place, near = {}, {}, {}, {}
    for (c, side), idx in cand.items():
        mg, v = cs.curves[c].kernel.margin(xw[idx], cs.curves[c].bi)
        if not periodic2:
            mg = np.minimum(mg, np.minimum(v - cs.window[2], cs.window[3] - v) / L)
        marg[c, side] = mg
        # a variant's contact begins and ends earlier or later too: it may be
        # real wherever the nominal one is real within ``reach``
        near[c, side] = -_window_min(x[idx] / s1, -mg, reach, per)
        if periodic2:
            v = placed_on_turn(v, lo0[idx], hi0[idx], f0[idx], side)
        place[c, side] = v
        dd = (lo0[idx] - v) if side > 0 else (v - hi0[idx])
        dd = np.where(np.isnan(dd), 0.0, np.maximum(dd, 0.0)) / scale2
        # where the channel's bound jumps (a curve ends and one farther away
        # takes over), a variant's jump comes earlier or later: a curve is as
        # near as it is anywhere within ``reach`` of driver motion
        dist[c, side] = _window_min(x[idx] / s1, dd, reach, per)
    return PathPlan(pair, x, xw, f0, is_ref, cell, cells, lower, upper, lo0, hi0, cand, dist,
                    marg, place, _curve_keys(cs), float(start), periodic2, tuple(cs.window),
                    scale2, s1, int(getattr(sim, "bias", 0)), margin_near=near,
                    cyclic=cyclic, resolved=resolved)


def _side(cs, curve: int, k: int, cellj: int, periodic2: bool):
    """+1 if curve lies below cell (k, cellj) of its slab, -1 if above, 0 if it
    is not active in slab k."""
    row = cs.cells[k]
    order = []
    for c in row:
        order.append(c.lower)
    # the cells of a slab are ordered bottom-up and each cell's upper bound is
    # the next cell's lower bound, so the curves of the slab in order are the
    # lower bounds (and the top cell's upper bound)
    if row[-1].upper >= 0 and row[-1].upper not in order:
        order.append(row[-1].upper)
    if curve not in order:
        return 0
    c = row[cellj]
    if curve == c.lower:
        return 1
    if curve == c.upper:
        return -1
    pos = order.index(curve)
    jl = order.index(c.lower) if c.lower in order else -1
    if not periodic2:
        return 1 if pos <= jl else -1
    n = len(order)
    down = (jl - pos) % n
    up = (pos - jl) % n
    return 1 if down <= up else -1




def placed_on_turn(v, lo, hi, f0, side):
    """A rotating follower's curve values v on the turn where they can bound
    the channel [lo, hi] from their side: a curve below it (side +1) at or
    below the upper bound, one above it (side -1) at or above the lower bound
    (where a curve lies beyond the opposite bound, it bounds another cell and
    lands a turn away).  ``side``: one for every value, or one per value."""
    top = np.where(np.isfinite(hi), hi, f0 + math.pi)
    bot = np.where(np.isfinite(lo), lo, f0 - math.pi)
    # the bounds are curve values, not interpolated: only rounding is slack
    if np.ndim(side) == 0:
        if side > 0:
            return _unwrap_below(top, v, SLACK)
        return _unwrap_above(bot, v, SLACK)
    with np.errstate(invalid="ignore"):
        return np.where(np.asarray(side) > 0, _unwrap_below(top, v, SLACK),
                        _unwrap_above(bot, v, SLACK))


def _window_min(x, v, width: float, period: float | None = None):
    """min of v over the samples within ``width`` of each (x: the samples'
    places, monotone), taken over bins of a quarter of the width; with a
    ``period`` (the drive's length, signed: a motion that ends where it
    starts), a sample near one end is near the samples at the other too."""
    if period is not None and len(x):
        n = len(x)
        ext = _window_min(np.concatenate([x - period, x, x + period]), np.tile(v, 3), width)
        return ext[n:2 * n]
    from scipy.ndimage import minimum_filter1d
    if not len(x) or width <= 0:
        return v
    b = np.floor((x - x.min()) / (0.25 * width)).astype(np.int64)
    b = np.abs(b - b.min()) if x[-1] >= x[0] else b.max() - b
    nb = int(b.max()) + 1
    m = np.full(nb, np.inf)
    np.minimum.at(m, b, v)
    m = minimum_filter1d(m, size=9, mode="nearest")
    return m[b]


def _curve_keys(cs) -> np.ndarray:
    """Index of each curve's (label, branch) among the C-space's curves."""
    seen: dict = {}
    return np.array([seen.setdefault((c.label, c.branch), len(seen)) for c in cs.curves],
                    dtype=np.int32)
