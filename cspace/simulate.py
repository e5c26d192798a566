"""Quasi-static, frictionless kinematic simulation in the free space.

The driver moves monotonically through a range (either direction).  The follower
stays where it is unless pushed; when a contact curve reaches it, it is pushed
along that curve.  In the sweep decomposition this is a clamp of the follower
coordinate into the free cell it occupies; across an event the follower moves
into the free cell of the next slab that continues its cell.  When no free
cell continues it, the driver is blocked: a jam.

Closure
-------
That is form closure, the default: the follower moves only when pushed.  A
force-closed follower (spring-loaded, or held by gravity; ``Pair.bias`` -1 or
+1, or the ``bias`` argument) is held toward decreasing or increasing q2, so at
every driver position it rests on that side's bound of its free cell: it rises
and falls with the driver.  Otherwise the rules are the same:

* the stated start picks the free cell (it must be free or in contact, as
  for form closure); the follower is laid on the cell's bias-side bound at
  once;
* across an event it moves into the next slab's cell that holds it (where it
  lies on the boundary of two, the one on the bias side), then onto that
  cell's bias-side bound;
* where its cell has no contact curve on the bias side, a sliding follower
  rests on the window's edge: the window stands for its travel limit (the
  stop the spring presses it against), and the output there is that edge,
  with no contact.  A rotating follower whose cell has no curve at all (a free
  full turn) keeps its place;
* when no free cell continues its cell the driver is blocked, a jam, as for
  form closure.

The output function f(q1) is returned as sampled arrays with the contact active at
each sample.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .freespace import ConfigurationSpace, cell_interval
from .geom2d import TWO_PI, drive_in_degrees
from .geometry import Rotation
from .tolerances import ROUNDING, SLACK

__all__ = ["SimStatus", "SimulationResult", "SystemSimulation", "drive_grid", "simulate",
           "simulate_system"]


def _window_edge_note(cs, q2: float) -> str:
    """Where a jam lies on an edge of a sliding or bounded follower's C-space
    window, a note saying so: the window stands for the follower's travel
    limit there, which a window drawn too small makes a jam."""
    if cs.periodic[1]:
        return ""
    lo, hi = cs.window[2], cs.window[3]
    tol = 1e-6 * max(1.0, abs(hi - lo))
    for edge, v in (("lower", lo), ("upper", hi)):
        if abs(q2 - v) <= tol:
            return (f", against the {edge} edge of the C-space window (q2 = {v:.6g}), which "
                    "stands for the follower's travel limit; if the follower can travel "
                    "further, widen the window")
    return ""


def _kinds(cs) -> dict:
    """The :class:`SimulationResult` fields ``rotating`` and ``units`` of the
    pair of ``cs``."""
    pair = cs.pair
    return {"rotating": tuple(isinstance(p.axis, Rotation) for p in pair.parts),
            "units": pair.units}


def _curve_text(curve) -> str:
    return curve.label or f"contact curve {curve.kind}"


def _jam_curves_note(cs, k: int, j: int, knext: int, x: float, lo: float, hi: float,
                     periodic2: bool) -> str:
    """The contact curves that close the channel at a jam at driver value ``x``
    (wrapped), e.g. ``" (crank:pin|yoke:cap.top meets crank:pin|yoke:slot.left)"``:
    the bounds of the follower's cell (k, j) there, and any curve of the slab
    ahead (``knext``) that starts inside the channel [lo, hi]; "" when no curve
    bounds it (the window's edges only)."""
    cell = cs.cells[k][j]
    bounds = [cs.curves[i] for i in (cell.lower, cell.upper) if i >= 0]
    ahead = []
    old = set(cs.active(k))
    for i in cs.active(knext):
        if i in old:
            continue
        cv = cs.curves[i]
        try:
            v = float(np.asarray(cv.evaluate(np.array([x])), dtype=float).ravel()[0])
        except (ValueError, ArithmeticError, IndexError):   # pragma: no cover - defensive
            continue
        if not math.isfinite(v):
            continue
        if not periodic2:
            inside = lo <= v <= hi
        else:
            inside = hi - lo >= TWO_PI or (v - lo) % TWO_PI <= hi - lo
        if inside and _curve_text(cv) not in [_curve_text(a) for a in ahead]:
            ahead.append(cv)
    names = [_curve_text(b) for b in bounds]
    if ahead:
        new = " and ".join(_curve_text(a) for a in ahead)
        around = f" between {' and '.join(names)}" if names else ""
        return f" ({new} {'enter' if len(ahead) > 1 else 'enters'} the channel{around})"
    if len(bounds) == 2:
        a, b = bounds
        if names[0] == names[1]:
            if a.branch != b.branch:
                return f" ({names[0]} meets itself: two branches of that contact curve join)"
            return f" ({names[0]} meets itself)"
        return f" ({names[0]} meets {names[1]})"
    if bounds:
        return f" (at {names[0]})"
    return ""


class SimStatus(enum.IntEnum):
    OK = 0              #: the driver completed its range
    JAMMED = 1          #: no free continuation: the driver is blocked
    START_BLOCKED = 2   #: the start configuration is not free


@dataclass(frozen=True)
class SimulationResult:
    """Sampled motion of one pair.

    Attributes
    ----------
    q1, q2 : (n,) float
        Driver and follower coordinates (q2 continuous, not wrapped).
    contact : tuple of str
        Feature-pair label pushing the follower at each sample ("" when free).
    status : SimStatus
    jam_q : (float, float) or None
        Where the driver was blocked.
    jam_reason : str
    message : str
    cells : tuple of (int, int)
        The C-space cells (slab, cell) the motion passed through, in order (the
        operating region that :func:`cspace.match.match` compares).
    bias : int
        The follower's closure the motion was simulated with: 0 form closure,
        -1 or +1 held toward decreasing or increasing q2 (:attr:`Pair.bias
        <cspace.geometry.Pair.bias>`).
    rotating : (bool, bool)
        Whether the driver and the follower rotate (q in rad) or slide (q in
        ``units``).
    units : str
        The pair's length unit (of a sliding part's q), as the model states it.
    """

    q1: np.ndarray
    q2: np.ndarray
    contact: tuple
    status: SimStatus
    jam_q: tuple | None = None
    jam_reason: str = ""
    message: str = ""
    pair: str = ""
    cells: tuple = ()
    bias: int = 0
    rotating: tuple = (True, True)
    units: str = ""

    @property
    def success(self) -> bool:
        return self.status == SimStatus.OK

    def __repr__(self):
        s = f"<SimulationResult {self.pair!r}: {self.status.name}, {len(self.q1)} samples"
        if self.bias:
            s += f", held toward {'+' if self.bias > 0 else '-'}q2"
        if len(self.q1):
            # (+ 0.0: no negative zero in the text)
            s += (f", q1 {self.q1[0] + 0.0:.6g} -> {self.q1[-1] + 0.0:.6g}, output "
                  f"{self.q2[0] + 0.0:.6g} -> {self.q2[-1] + 0.0:.6g}")
        if self.jam_q is not None:
            s += f", jam at q = ({self.jam_q[0]:.6g}, {self.jam_q[1]:.6g})"
        return s + ">"

    def output_at(self, q1) -> np.ndarray:
        """f interpolated at driver coordinates ``q1`` (a number or an array)
        inside the simulated range, ``min(self.q1) <= q1 <= max(self.q1)``
        (up to a rounding slack at either end).

        Raises
        ------
        InputError
            A value outside the simulated range (the motion says nothing
            there), no sample to interpolate, or ``q1`` not numeric;
            :class:`~cspace.errors.NonFiniteError` for NaN or infinity.
        """
        from .errors import NonFiniteError
        name = f"pair {self.pair!r}: " if self.pair else ""
        try:
            x = np.asarray(q1, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{name}output_at expects driver coordinates (a number or an "
                             f"array of numbers), got {q1!r}", name="q1", value=q1) from None
        if not len(self.q1):
            raise InputError(f"{name}output_at needs a simulated motion, but this one has no "
                             f"sample (status {self.status.name}): there is no range to "
                             f"interpolate in", name="q1", value=q1)
        if not np.all(np.isfinite(x)):
            raise NonFiniteError(f"{name}output_at expects finite driver coordinates inside "
                                 f"the simulated range, got {x[~np.isfinite(x)].flat[0]!r}",
                                 name="q1", value=q1)
        lo, hi = float(np.min(self.q1)), float(np.max(self.q1))
        slack = SLACK * max(1.0, abs(lo), abs(hi))
        out = (x < lo - slack) | (x > hi + slack)
        if np.any(out):
            bad = np.ravel(x)[np.ravel(out)]
            far = bad[np.argmax(np.maximum(lo - bad, bad - hi))]
            got = (f"{len(bad)} values outside it, the farthest {far:.6g}" if len(bad) > 1
                   else f"{far:.6g}")
            raise InputError(f"{name}output_at expects driver coordinates inside the simulated "
                             f"range [{lo:.6g}, {hi:.6g}], got {got}; the motion is known only "
                             f"there (simulate a longer drive for more)", name="q1", value=q1)
        order = np.argsort(self.q1)
        return np.interp(x, self.q1[order], self.q2[order])

    def to_dict(self) -> dict:
        return {"pair": self.pair, "status": self.status.name, "q1": self.q1.tolist(),
                "q2": self.q2.tolist(), "contact": list(self.contact),
                "jam_q": list(self.jam_q) if self.jam_q else None,
                "jam_reason": self.jam_reason, "message": self.message, "bias": self.bias}


#: Most output samples one simulation takes (some 10 million: about a
#: thousand driver turns at the ``precise`` step).
MAX_SAMPLES = 1e7


def _bounds(cs: ConfigurationSpace, k: int, j: int, x, memo: dict | None = None):
    """Lower and upper bound of cell (k, j) at driver values x (array).

    ``memo`` holds curve values at single driver values (:func:`_memo`): the
    slab mid-points (the continuity reference of :func:`cell_interval`), which
    every call of a slab repeats, and the event rows."""
    c = cs.cells[k][j]
    xm = _mid(cs, k)
    return cell_interval(cs.curves, c.lower, c.upper, len(cs.cells[k]), x, xm, cs.window,
                         cs.periodic[1], _memo(cs, memo))


def _mid(cs: ConfigurationSpace, k: int) -> float:
    """Driver value at the middle of slab k."""
    return 0.5 * (cs.events[k] + cs.events[k + 1])


def _memo(cs: ConfigurationSpace, memo: dict | None):
    """Curve values ``values(i, xx) -> (wrapped, raw)`` that keep those at a single
    driver value in ``memo``, keyed by (curve, value)."""
    if memo is None:
        return None

    def values(i, xx):
        if len(xx) == 1:
            key = (i, float(xx[0]))
            v = memo.get(key)
            if v is None:
                v = memo[key] = cs.curves[i].values(xx)
            return v
        return cs.curves[i].values(xx)
    return values


def _prefetch(cs: ConfigurationSpace, memo: dict, points) -> None:
    """Fill ``memo`` with the curve values at ``points`` (pairs (curve, driver
    value)), one array evaluation per curve.  A contact curve gives the same
    value at a point whether evaluated alone or among others (bit for bit,
    tests/cspace/test_contact.py), so this changes the cost only."""
    by: dict = {}
    for i, x in points:
        if (i, x) not in memo:
            by.setdefault(i, set()).add(x)
    for i, xx in by.items():
        xx = sorted(xx)
        w, r = cs.curves[i].values(np.array(xx))
        for t, x in enumerate(xx):
            memo[(i, x)] = (w[t:t + 1].copy(), r[t:t + 1].copy())


def _refine_release(cs, k, j, side, xa, xb, q2, wrap1, periodic, x0=None, memo=None):
    """Follower position after the pushing bound of cell (k, j) peaks: the extremum
    of that bound over [x0, xb] (x0: the sample before the last contact at xa, since
    the peak may lie just before xa), found by bounded minimisation."""
    from scipy.optimize import minimize_scalar
    which = 0 if side < 0 else 1
    sgn = -1.0 if side < 0 else 1.0   # maximise the lower bound, minimise the upper

    def bound(x):
        v = _bounds(cs, k, j, np.array([wrap1(x)]), memo)[which][0]
        return sgn * v

    x0 = xa if x0 is None else x0
    off = xa - wrap1(xa)  # whole driver periods between the path and the window
    lo_x = max(x0, cs.events[k] + off) if xb > xa else min(x0, cs.events[k + 1] + off)
    a, b = (lo_x, xb) if lo_x < xb else (xb, lo_x)
    ref = bound(xa)
    r = minimize_scalar(bound, bounds=(a, b), method="bounded",
                        options={"xatol": max(cs.accuracy.root_tol, ROUNDING) * cs._s1})
    best = min(r.fun, ref, bound(xb))
    # the bound at xa equals q2 (the follower was in contact there)
    delta = sgn * (best - ref)
    if periodic:
        delta = (delta + math.pi) % TWO_PI - math.pi
    return q2 + delta


def _place_in(q2, lo, hi, periodic):
    """Clamp q2 (unwrapped) into the interval [lo, hi] (cyclic when periodic).

    Returns (new q2 unwrapped, side) with side -1 pushed by the lower bound, +1 by the
    upper, 0 inside."""
    if not periodic or not np.isfinite(lo):
        if q2 < lo:
            return lo, -1
        if q2 > hi:
            return hi, 1
        return q2, 0
    off = (q2 - lo) % TWO_PI
    if off <= hi - lo:
        return q2, 0
    below = TWO_PI - off          # distance up to lo
    above = off - (hi - lo)       # distance down to hi
    if below <= above:
        return q2 + below, -1
    return q2 - above, 1


def _rest(q2, lo, hi, periodic, bias, bounded):
    """A force-closed follower at q2 (unwrapped) in the interval [lo, hi]: on
    its ``bias`` side's bound (-1 lower, +1 upper).  ``bounded``: a contact
    curve bounds that side (else, for a sliding follower, the window edge is
    the bound; a rotating follower's free full turn has none and the follower
    stays, clamped).  Returns (new q2 unwrapped, side)."""
    if not periodic:
        return (lo, -1) if bias < 0 else (hi, 1)
    q, side = _place_in(q2, lo, hi, periodic)
    if not bounded:
        return q, side
    # q lies in the cyclic interval: its distance to the bias-side bound is at
    # most hi - lo; a distance just under a full turn is q a rounding error
    # beyond that bound
    off = ((q - lo) if bias < 0 else (hi - q)) % TWO_PI
    if off > TWO_PI - _TURN_SLACK:
        off -= TWO_PI
    return (q - off, -1) if bias < 0 else (q + off, 1)


#: A rotating follower this close (rad) to a full turn from its bound is on it
#: (:func:`_rest`): rounding of the wrapped bounds.
_TURN_SLACK = 1e-9

#: Driver positions this close (relative to the driver's scale ``s1``; rad for
#: a rotating driver) are the same place: an event, a stop or a window end
#: reached up to rounding.
_AT_EVENT = 1e-12


def _row_points(cs: ConfigurationSpace, path_events, at, slab_for, wrap1, direction):
    """(curve, driver value) pairs that the rows of free cells ahead of the path's
    events evaluate (:meth:`ConfigurationSpace.row_bounds`), with the slab
    mid-points of a rotating follower: each event row is computed at its first
    crossing."""
    seen = set()
    for x in path_events:
        e = at[x]
        if e in seen:
            continue
        seen.add(e)
        kn = slab_for(x, direction)
        xw = float(wrap1(x))
        xm = _mid(cs, kn)
        for c in cs.cells[kn]:
            if not c.free:
                continue
            for ci in (c.lower, c.upper):
                if ci >= 0:
                    yield ci, xw
                    if cs.periodic[1]:
                        yield ci, xm


def _first_reach(q2, lo, hi, periodic) -> int:
    """Index of the first sample where :func:`_place_in` moves a follower at rest
    at q2 (``len(lo)`` if none): the same rule, elementwise."""
    with np.errstate(invalid="ignore"):
        if not periodic:
            moved = (q2 < lo) | (q2 > hi)
        else:
            plain = ~np.isfinite(lo)
            moved = np.where(plain, (q2 < lo) | (q2 > hi),
                             ~((q2 - lo) % TWO_PI <= hi - lo))
    hit = np.flatnonzero(moved)
    return int(hit[0]) if hit.size else len(lo)


def _free_neighbour(cs: ConfigurationSpace, k: int, j: int, x: float, q2: float, tol: float,
                    memo) -> int:
    """The free cell next to blocked cell (k, j) whose bounds at driver value x
    hold q2 within ``tol`` (the start is in contact with its boundary), else j."""
    row = cs.cells[k]
    n = len(row)
    for jj in (j - 1, j + 1):
        if cs.periodic[1]:
            jj %= n
        if not 0 <= jj < n or jj == j or not row[jj].free:
            continue
        lo, hi = _bounds(cs, k, jj, np.array([x]), memo)
        q, _ = _place_in(q2, lo[0], hi[0], cs.periodic[1])
        if abs(q - q2) <= tol:
            return jj
    return j


def _overlap(a_lo, a_hi, b_lo, b_hi, periodic, tol):
    if not periodic or not (np.isfinite(a_lo) and np.isfinite(b_lo)):
        return min(a_hi, b_hi) - max(a_lo, b_lo) > tol
    for sh in (-TWO_PI, 0.0, TWO_PI):
        if min(a_hi, b_hi + sh) - max(a_lo, b_lo + sh) > tol:
            return True
    return False


def simulate(cs: ConfigurationSpace, q1_start: float, q1_end: float, q2_start: float, *,
             step: float | None = None, bias: int | None = None) -> SimulationResult:
    """Quasi-static simulation of one pair.

    Parameters
    ----------
    cs : ConfigurationSpace
        Its window must cover the driver range (a periodic driver wraps).
    q1_start, q1_end : float
        Driver range; the driver moves monotonically from start to end.
    q2_start : float
        Follower start coordinate (must be free or in contact).  A force-closed
        follower starts on the bias-side bound of the free interval it picks.
    step : float, optional
        Output sampling step of the driver (default ``accuracy.sim_step``: rad, or
        that many characteristic lengths for a sliding driver).
    bias : {-1, 0, 1}, optional
        The follower's closure (module docstring, "Closure"): 0 form closure,
        -1 or +1 held toward decreasing or increasing q2.  Default: the pair's
        own (:attr:`cs.pair.bias <cspace.geometry.Pair.bias>`).

    Examples
    --------
    A spring-loaded follower (held toward decreasing q2) rides the cam:

    >>> sim = simulate(cs, 0.0, 2 * math.pi, q2_start, bias=-1)   # doctest: +SKIP
    """
    from .argcheck import getscalar
    from .geometry import check_bias
    q1_start = getscalar(q1_start, "q1_start")
    q1_end = getscalar(q1_end, "q1_end")
    q2_start = getscalar(q2_start, "q2_start")
    degrees = drive_in_degrees(q1_start, q1_end) if cs.periodic[0] else None
    if degrees:
        raise InputError(degrees, name="q1_end", value=q1_end)
    bias = cs.pair.bias if bias is None else check_bias(bias)
    s1 = cs._s1   # q1 length that counts as 1 (rad, or the characteristic length)
    step = cs.accuracy.sim_step * s1 if step is None else getscalar(step, "step",
                                                                      positive=True)
    w = _Walk(cs, q1_start, q1_end, step, bias)
    blocked = w.start(q2_start)
    if blocked is not None:
        return blocked
    return w.run()


def drive_grid(q1_start: float, q1_end: float, step: float) -> np.ndarray:
    """The regular driver samples of :func:`simulate` from ``q1_start`` to
    ``q1_end``, at most ``step`` apart (the simulation adds the C-space's
    events to them).  A variant simulated over the same drive at the same step
    has these very samples (the same bits): the defect test reads its output
    there without interpolation."""
    span = abs(q1_end - q1_start)
    direction = 1.0 if q1_end >= q1_start else -1.0
    n = max(2, int(math.ceil(span / step)) + 1)
    return q1_start + direction * np.linspace(0.0, span, n)


class _Walk:
    """One run of :func:`simulate`: the driver samples and events of the path
    (:meth:`__init__`), the start (:meth:`start`), then the walk
    (:meth:`run`): from event to event, the samples of one slab at a time
    (:meth:`slab`), and at each event the cell ahead (:meth:`cross`)."""

    def __init__(self, cs, q1_start, q1_end, step, bias):
        self.cs, self.bias = cs, bias
        self.s1 = s1 = cs._s1
        lo1, hi1 = cs.window[0], cs.window[1]
        if not cs.periodic[0]:
            for v, nm in ((q1_start, "q1_start"), (q1_end, "q1_end")):
                if not (lo1 - _AT_EVENT * s1 <= v <= hi1 + _AT_EVENT * s1):
                    raise InputError(f"{nm} = {v} lies outside the C-space window "
                                     f"[{lo1}, {hi1}] of a non-periodic driver")
        self.direction = direction = 1.0 if q1_end >= q1_start else -1.0
        span = abs(q1_end - q1_start)
        if span / step > MAX_SAMPLES:
            raise InputError(f"the driver range {span:.6g} sampled every {step:.3g} needs "
                             f"{span / step:.3g} output samples; at most {MAX_SAMPLES:g} are "
                             f"allowed: shorten the range or take a larger step", name="step",
                             value=step)
        xs = drive_grid(q1_start, q1_end, step)
        self.lo1, self.period = lo1, hi1 - lo1
        # event crossings along the path (unwrapped driver values), each with its
        # event index: an unwrapped event wraps back to the window with a rounding
        # error, so the slab ahead is taken from the index, not searched
        self.at = self._path_events(q1_start, q1_end)
        self.rows: dict = {}   # free cells of the slab ahead and their bounds, per
        #                        event index: later turns cross the same events
        path_events = sorted(self.at, reverse=direction < 0)
        self.xs = np.array(sorted(set(xs.tolist()) | set(path_events), reverse=direction < 0))
        self.ev_set = set(path_events)
        self.periodic2 = cs.periodic[1]
        self.memo: dict = {}   # curve values at single driver values (_memo)
        _prefetch(cs, self.memo, _row_points(cs, path_events, self.at, self.slab_for,
                                             self.wrap1, direction))
        self.out_q1, self.out_q2, self.out_c = [], [], []
        self.tol_c = max(cs.accuracy.contact_rel, SLACK)

    def _path_events(self, q1_start, q1_end) -> dict:
        cs = self.cs
        ev = cs.events
        nslab = len(ev) - 1
        at: dict = {}

        def add_event(u, i):
            if min(q1_start, q1_end) < u < max(q1_start, q1_end):
                at[u] = i

        if cs.periodic[0]:
            kmin = math.floor((min(q1_start, q1_end) - self.lo1) / self.period) - 1
            kmax = math.ceil((max(q1_start, q1_end) - self.lo1) / self.period) + 1
            for kk in range(kmin, kmax + 1):
                for i, e in enumerate(ev[:-1]):
                    add_event(e + kk * self.period, i)
        else:
            for i in range(1, nslab):
                add_event(ev[i], i)
        return at

    def wrap1(self, x):
        """The driver value(s) x in the window (scalar or array, elementwise)."""
        return (x - self.lo1) % self.period + self.lo1 if self.cs.periodic[0] else x

    def slab_for(self, x, moving_dir):
        """Slab index containing x, choosing the slab ahead when x is an event."""
        cs, at, s1 = self.cs, self.at, self.s1
        ev = cs.events
        if x in at:
            return at[x] if moving_dir > 0 else (at[x] - 1) % (len(ev) - 1)
        xw = self.wrap1(x)
        k = int(np.searchsorted(ev, xw, side="right") - 1)
        k = min(max(k, 0), len(ev) - 2)
        if moving_dir < 0 and abs(xw - ev[k]) <= _AT_EVENT * s1 and k > 0:
            k -= 1
        if moving_dir < 0 and cs.periodic[0] and abs(xw - ev[0]) <= _AT_EVENT:
            k = len(ev) - 2
        return k

    # ------------------------------------------------------------ start
    def start(self, q2_start):
        """Place the follower in its start cell; a SimulationResult when the
        start is blocked, else None."""
        cs, xs, memo = self.cs, self.xs, self.memo
        k = self.slab_for(xs[0], self.direction)
        _, ci = cs.cell_at(np.array([[self.wrap1(xs[0]) + self.direction * _AT_EVENT * self.s1,
                                      q2_start]]))
        j = int(ci[0])
        if not cs.cells[k][j].free:
            # a start on a contact that pushes the follower at once lies just
            # outside its free cell a hair after the start: take that cell
            j = _free_neighbour(cs, k, j, self.wrap1(xs[0]), q2_start, self.tol_c, memo)
        cell = cs.cells[k][j]
        lo, hi = _bounds(cs, k, j, self.wrap1(xs[0]), memo)
        q2, side = _place_in(q2_start, lo[0], hi[0], self.periodic2)
        if not cell.free or abs(q2 - q2_start) > self.tol_c:
            return SimulationResult(np.array([xs[0]]), np.array([q2_start]), ("",),
                                    SimStatus.START_BLOCKED, (float(xs[0]), float(q2_start)),
                                    "start configuration is blocked",
                                    f"the start configuration ({xs[0]:.6g}, {q2_start:.6g}) "
                                    "is not in free space", cs.pair.name, bias=self.bias,
                                    **_kinds(cs))
        self.k, self.j = k, j
        if self.bias:
            q2, side = _rest(q2, lo[0], hi[0], self.periodic2, self.bias, self.bounded(k, j))
        self.q2, self.side = q2, side
        self.visited = [(k, j)]
        self.record(xs[0], q2, side)
        return None

    def bounded(self, k_, j_):
        """Whether a contact curve bounds cell (k_, j_) on the bias side."""
        c = self.cs.cells[k_][j_]
        return (c.lower if self.bias < 0 else c.upper) >= 0

    def label(self, side_, k_, j_):
        cs = self.cs
        c = cs.cells[k_][j_]
        if side_ < 0 and c.lower >= 0:
            return cs.curves[c.lower].label
        if side_ > 0 and c.upper >= 0:
            return cs.curves[c.upper].label
        return ""

    def record(self, x, q, s):
        self.out_q1.append(float(x))
        self.out_q2.append(float(q))
        self.out_c.append(self.label(s, self.k, self.j))

    def result(self, status, jam=None, reason="", message="completed"):
        return SimulationResult(np.array(self.out_q1), np.array(self.out_q2),
                                tuple(self.out_c), status, jam, reason, message,
                                self.cs.pair.name, tuple(self.visited), self.bias,
                                **_kinds(self.cs))

    # ------------------------------------------------------------ walk
    def run(self):
        """Walk: group consecutive samples of one slab and clamp sequentially;
        at each event pick the next cell."""
        xs, ev_set = self.xs, self.ev_set
        i = 1
        nx_ = len(xs)
        self.at_event = None
        while i < nx_:
            x = xs[i]
            if x in ev_set:
                jam = self.cross(x)
                if jam is not None:
                    return jam
                i += 1
                continue
            # samples up to the next event (exclusive) lie in slab k
            i_end = i
            while i_end < nx_ and xs[i_end] not in ev_set:
                i_end += 1
            self.slab(i, i_end)
            i = i_end
        return self.result(SimStatus.OK)

    def cross(self, x):
        """Reach the event x inside the current cell, then pick the next cell;
        a JAMMED SimulationResult when none holds the follower."""
        cs, memo, periodic2, bias = self.cs, self.memo, self.periodic2, self.bias
        k, j, q2 = self.k, self.j, self.q2
        if self.at_event is not None:
            lo_e, hi_e = self.at_event
            self.at_event = None
        else:
            lo_e, hi_e = _bounds(cs, k, j, self.wrap1(x), memo)
        q2, side = _place_in(q2, lo_e[0], hi_e[0], periodic2)
        if bias:
            q2, side = _rest(q2, lo_e[0], hi_e[0], periodic2, bias, self.bounded(k, j))
        self.q2, self.side = q2, side
        self.record(x, q2, side)
        knext = self.slab_for(x, self.direction)
        if knext == k:
            return None
        cands = self._candidates(x, knext, lo_e, hi_e, q2)
        if not cands:
            reason = ("the free channel closes ahead" if hi_e[0] - lo_e[0] > SLACK
                      else "the channel narrows to zero width")
            reason += _jam_curves_note(cs, k, j, knext, self.wrap1(x), lo_e[0], hi_e[0],
                                       periodic2)
            reason += _window_edge_note(cs, q2)
            return self.result(SimStatus.JAMMED, (float(x), float(q2)), reason,
                               f"driver blocked at q1 = {x:.6g} (q2 = {q2:.6g}): {reason}")
        _, j, q2, side = cands[0][:4]
        self.k, self.j, self.q2 = knext, j, q2
        if self.visited[-1] != (knext, j):
            self.visited.append((knext, j))
        if bias:
            side = bias
        self.side = side
        self.out_c[-1] = self.label(side, knext, j) or self.out_c[-1]
        return None

    def _candidates(self, x, knext, lo_e, hi_e, q2) -> list:
        """The free cells of slab ``knext`` that overlap the current cell at the
        event x, each ``(distance, cell, q2, side, lo, hi)``, best first."""
        cs, periodic2, bias, at = self.cs, self.periodic2, self.bias, self.at
        if at[x] not in self.rows:
            free = [jj for jj, c in enumerate(cs.cells[knext]) if c.free]
            self.rows[at[x]] = (free, *cs.row_bounds(knext, self.wrap1(x),
                                                     _memo(cs, self.memo), free))
        free, l2, h2 = self.rows[at[x]]
        cands = []
        for jj, a2, b2 in zip(free, l2, h2):
            if _overlap(lo_e[0], hi_e[0], a2, b2, periodic2, ROUNDING):
                qq, ss = _place_in(q2, a2, b2, periodic2)
                cands.append((abs(qq - q2), jj, qq, ss, a2, b2))
        if bias:
            # a follower on the boundary of two cells goes to the one on its
            # bias side: the one reaching farther that way (candidate cells
            # whose placements differ by less than the tie, relative to the
            # follower coordinate, hold the follower alike)
            tie = _TIE_REL * max(1.0, abs(q2))
            cands.sort(key=lambda c_: ((0, -_reach(c_[2], c_[4], c_[5], bias, periodic2))
                                       if c_[0] <= tie else (1, c_[0])))
        else:
            cands.sort(key=lambda c_: c_[:2])
        return cands

    def slab(self, i, i_end):
        """The samples ``xs[i:i_end]`` of the current slab: held on the bias
        side, or at rest until a bound pushes the follower."""
        cs, memo, periodic2, bias = self.cs, self.memo, self.periodic2, self.bias
        k, j = self.k, self.j
        xs = self.xs
        seg = xs[i:i_end]
        # the bounds at the event ending the slab come with those of its samples
        lo_a, hi_a = _bounds(cs, k, j, self.wrap1(xs[i:i_end + 1]), memo)
        if i_end < len(xs):
            self.at_event = (lo_a[-1:], hi_a[-1:])
        nseg = len(seg)
        if bias:
            self._held(seg, lo_a, hi_a)
            return
        q2, side = self.q2, self.side
        out_q1, out_q2, out_c = self.out_q1, self.out_q2, self.out_c
        t = 0
        while t < nseg:
            if side == 0:
                # at rest: the follower keeps q2 until a bound reaches it (one
                # vectorised test over the rest of the slab, the rule of _place_in)
                t_hit = t + _first_reach(q2, lo_a[t:nseg], hi_a[t:nseg], periodic2)
                out_q1.extend(seg[t:t_hit].tolist())
                out_q2.extend([float(q2)] * (t_hit - t))
                out_c.extend([""] * (t_hit - t))
                t = t_hit
                if t == nseg:
                    break
            q2_new, side_new = _place_in(q2, lo_a[t], hi_a[t], periodic2)
            if side != 0 and side_new == 0:
                # contact lost: the pushing bound peaked between samples; the follower
                # stops at that extremum, not at the last sample
                x0 = out_q1[-2] if len(out_q1) > 1 and out_q1[-2] != out_q1[-1] else out_q1[-1]
                q2_new = _refine_release(cs, k, j, side, out_q1[-1], seg[t], q2,
                                         self.wrap1, periodic2, x0, memo)
            q2, side = q2_new, side_new
            self.q2, self.side = q2, side
            self.record(seg[t], q2, side)
            t += 1
        self.q2, self.side = q2, side

    def _held(self, seg, lo_a, hi_a):
        """A force-closed follower: on the bias-side bound at every sample."""
        bias, periodic2, k, j = self.bias, self.periodic2, self.k, self.j
        nseg = len(seg)
        q2, side = self.q2, self.side
        b_ok = self.bounded(k, j)
        if not periodic2:
            vals = (lo_a if bias < 0 else hi_a)[:nseg]
            self.out_q2.extend(vals.tolist())
            q2, side = float(vals[-1]), bias
        else:
            for t in range(nseg):
                q2, side = _rest(q2, lo_a[t], hi_a[t], periodic2, bias, b_ok)
                self.out_q2.append(float(q2))
        self.out_q1.extend(seg.tolist())
        self.out_c.extend([self.label(side, k, j)] * nseg)
        self.q2, self.side = q2, side


#: Candidate cells at an event whose placements differ by less than this
#: (relative to the follower coordinate) hold a force-closed follower alike.
_TIE_REL = 1e-12


def _reach(q, lo, hi, bias, periodic) -> float:
    """How far the interval [lo, hi] reaches from q (inside it) toward the bias
    side (:func:`simulate`'s choice between cells a follower lies between)."""
    d = (q - lo) if bias < 0 else (hi - q)
    if not np.isfinite(d):
        return math.inf
    if periodic:
        d %= TWO_PI
        if d > TWO_PI - _TURN_SLACK:
            d = 0.0     # q a rounding error beyond the bound
    return float(d)


@dataclass(frozen=True)
class SystemSimulation:
    """Simulation of several pairs on one driver.

    ``results[i]`` is pair i's motion.  The driver stops at the first jam of any
    pair; every result is cut there.
    """

    results: tuple
    status: SimStatus
    jam_pair: int = -1
    jam_q1: float | None = None

    @property
    def success(self) -> bool:
        return self.status == SimStatus.OK

    def __repr__(self):
        s = f"<SystemSimulation {len(self.results)} pairs: {self.status.name}"
        if self.jam_q1 is not None:
            s += f", pair {self.jam_pair} blocks the driver at q1 = {self.jam_q1:.6g}"
        return s + ">"


def simulate_system(spaces, q1_start: float, q1_end: float, q2_starts, *,
                    step: float | None = None) -> SystemSimulation:
    """Simulate several pairs on one driver (e.g. three cams on one shaft)."""
    spaces = list(spaces)
    q2_starts = list(np.broadcast_to(np.asarray(q2_starts, dtype=float), (len(spaces),)))
    res = [simulate(cs, q1_start, q1_end, q2s, step=step) for cs, q2s in zip(spaces, q2_starts)]
    direction = 1.0 if q1_end >= q1_start else -1.0
    stops = [(r.jam_q[0] if r.jam_q else None) for r in res]
    blocked = [(direction * s, i) for i, s in enumerate(stops) if s is not None]
    if not blocked:
        return SystemSimulation(tuple(res), SimStatus.OK)
    _, ij = min(blocked)
    xstop = stops[ij]
    cut = []
    for r in res:
        keep = (direction * (r.q1 - xstop)) <= _AT_EVENT
        cut.append(SimulationResult(r.q1[keep], r.q2[keep], tuple(np.array(r.contact, dtype=object)[keep]),
                                    r.status if r.jam_q and abs(r.jam_q[0] - xstop) <= _AT_EVENT
                                    else (SimStatus.JAMMED if r is res[ij] else r.status),
                                    r.jam_q, r.jam_reason, r.message, r.pair, r.cells, r.bias,
                                    r.rotating, r.units))
    status = SimStatus.START_BLOCKED if res[ij].status == SimStatus.START_BLOCKED else SimStatus.JAMMED
    return SystemSimulation(tuple(cut), status, ij, float(xstop))
