"""Free space of a pair by a sweep (vertical decomposition) over the driver axis.

Between consecutive *events* (curve ends, curve crossings, vertical contacts) no
two contact curves cross, so at every driver coordinate of such a *slab* the
follower's coordinate range is split by the same curves in the same order into
*cells*.  Each cell is classified free or blocked by an exact part-overlap test
at its centre; cells of equal class that touch across an event form *faces*.
The curve pieces that separate free cells from blocked ones are the free-space
boundary; they form the free-space graph (networkx), labelled by feature pair
and branch.

Nothing here nodes polylines: narrow channels (a few thousandths of a radian) are
resolved to the accuracy of the events (``Accuracy.root_tol``).
"""

from __future__ import annotations

import enum
import math
import weakref
from dataclasses import dataclass, field

import networkx as nx
import numpy as np
from scipy.optimize import brentq

from .accuracy import Accuracy, as_accuracy
from .errors import CSpaceError
from .contact import CurveSet, contact_curves, is_period
from .geometry import Pair, Rotation
from .geom2d import TWO_PI
from .metric import driver_scale, follower_scale, split_wrapped
from .metric import wrap_to as _wrap
from .overlap import parts_overlap
from .tolerances import PROBE_REL, ROUNDING, TINY

__all__ = ["Status", "Cell", "BoundaryPiece", "ConfigurationSpace", "configuration_space",
           "StartChoice", "MAX_SEGMENTS"]


class Status(enum.IntEnum):
    """Point classification."""

    FREE = 0
    BLOCKED = 1
    CONTACT = 2


_STATUS = {int(s): s for s in Status}


@dataclass(frozen=True)
class Cell:
    """A trapezoid-like cell of one slab between two curves (or window edges).

    ``lower``/``upper`` are curve indices, or -1 for the window edge.  For a
    rotating follower the cell runs upwards from ``lower`` and may wrap through the
    window seam.
    """

    slab: int
    lower: int
    upper: int
    free: bool
    face: int


@dataclass(frozen=True)
class BoundaryPiece:
    """A maximal piece of one contact curve that separates free from blocked.

    Attributes
    ----------
    curve : int
        Index into ``ConfigurationSpace.curves``.
    label, branch : the curve's feature-pair label and branch
    q1_start, q1_end : float
    free_above : bool
        Free space lies at larger q2 (locally).
    free_face, blocked_face : int
    u, v : int
        Graph node ids of the start and end vertices.
    """

    curve: int
    label: str
    branch: int
    q1_start: float
    q1_end: float
    free_above: bool
    free_face: int
    blocked_face: int
    u: int = -1
    v: int = -1


#: Two boundary-piece ends at one event are one vertex when their q2 intervals
#: (see ``configuration_space``, step 6) are closer than this (rad, or length
#: over the characteristic length).
NODE_Q2_TOL = 1e-5


def _interval_rule(il, iu, ncells: int, lo_v, lo_r, hi_v, hi_r, lo_m, hi_m, window,
                   periodic2: bool):
    """Cell bounds from the values of its bounding curves (elementwise; shared by
    :func:`cell_interval`, one cell at many driver values, and
    :meth:`ConfigurationSpace.row_bounds`, a whole slab at one driver value).

    ``il, iu``: lower and upper curve indices (-1: the window edge); ``lo_v,
    hi_v``: their wrapped values, ``lo_r, hi_r``: raw values at x; ``lo_m,
    hi_m``: raw values at the slab mid-point (any value where the index is -1).
    """
    lo2, hi2 = window[2], window[3]
    il, iu = np.asarray(il), np.asarray(iu)
    lo = np.where(il >= 0, lo_v, lo2)
    if not periodic2:
        return lo, np.where(iu >= 0, hi_v, hi2)
    if ncells == 1 and np.all(il < 0):
        return np.full(lo.shape, lo2), np.full(lo.shape, hi2)
    dm = hi_m - lo_m
    w = dm % TWO_PI + ((hi_r - lo_r - dm + math.pi) % TWO_PI - math.pi)
    hi = lo + np.clip(w, 0.0, TWO_PI)
    if ncells > 1:
        hi = np.where(il == iu, lo + TWO_PI, hi)
    return lo, hi


def _row_bounds(lowers, uppers, ncells: int, x: float, xmid: float, values, window,
                periodic2: bool):
    """Bounds (lo, hi) of several cells of one slab (lower and upper curve
    indices; ``ncells`` cells in the whole slab) at one driver value x, each
    bounding curve evaluated once through ``values(i, xx) -> (wrapped, raw)``."""
    il = np.asarray(lowers, dtype=int)
    iu = np.asarray(uppers, dtype=int)
    xa = np.array([float(x)])
    xm = np.array([xmid])
    at = {i: values(i, xa) for i in set(il.tolist()) | set(iu.tolist()) if i >= 0}
    mid = {i: values(i, xm)[1][0] for i in at} if periodic2 else {}

    def pick(idx, j):
        return np.array([at[i][j][0] if i >= 0 else np.nan for i in idx.tolist()])

    mids = ((np.array([mid.get(i, 0.0) for i in il.tolist()]),
             np.array([mid.get(i, 0.0) for i in iu.tolist()])) if periodic2 else (0.0, 0.0))
    return _interval_rule(il, iu, ncells, pick(il, 0), pick(il, 1), pick(iu, 0), pick(iu, 1),
                          *mids, window, periodic2)


def cell_interval(curves, lower: int, upper: int, ncells: int, x, xmid: float,
                  window, periodic2: bool, values=None):
    """Bounds (lo, hi) of a cell at driver values x (arrays, hi >= lo).

    For a rotating follower the width is followed by continuity from the slab's
    mid-point ``xmid``: where the two bounding curves meet at an event, one cell of
    the slab shrinks to width 0 and its complement grows to a full turn, which a
    fixed tolerance on the wrapped difference cannot tell apart.

    ``values(i, x) -> (wrapped, raw)`` may supply (memoised) curve values.
    """
    if values is None:
        def values(i, xx):
            return curves[i].values(xx)
    x = np.atleast_1d(np.asarray(x, dtype=float))
    nan = np.full(x.shape, np.nan)
    lo_v, lo_r = values(lower, x) if lower >= 0 else (nan, nan)
    hi_v, hi_r = values(upper, x) if upper >= 0 else (nan, nan)
    lo_m = hi_m = 0.0
    if periodic2 and lower >= 0 and upper >= 0:
        xm = np.array([xmid])
        lo_m, hi_m = float(values(lower, xm)[1][0]), float(values(upper, xm)[1][0])
    return _interval_rule(lower, upper, ncells, lo_v, lo_r, hi_v, hi_r, lo_m, hi_m,
                          window, periodic2)


def _dedupe(vals, tol):
    vals = np.sort(np.asarray(vals, dtype=float))
    if vals.size == 0:
        return vals
    keep = [vals[0]]
    for v in vals[1:]:
        if v - keep[-1] > tol:
            keep.append(v)
    return np.array(keep)


@dataclass(frozen=True)
class StartChoice:
    """How a follower start was chosen when the model states none
    (:meth:`ConfigurationSpace.start_choice`).

    Attributes
    ----------
    q1 : float
        The driver value of the start.
    q2 : float
        The chosen follower start: the middle of the widest free interval.
    intervals : tuple of (lo, hi)
        Every free follower interval at ``q1`` (bottom-up, window
        coordinates; rad, or model units for a slide).
    chosen : int
        Index of the interval chosen.
    pair : str
        The pair's name.
    """

    q1: float
    q2: float
    intervals: tuple
    chosen: int
    pair: str = ""
    #: intervals passed over: wider ones whose nominal motion jams
    #: (:func:`cspace.defects.reference`)
    jams: tuple = ()

    @property
    def ambiguous(self) -> bool:
        """More than one free interval: the follower could start in another one,
        and the motion, the operating region and every defect test would be
        another mechanism's."""
        return len(self.intervals) > 1

    def __repr__(self):
        return (f"<StartChoice {self.pair!r}: q2 = {self.q2:.6g} at q1 = {self.q1:.6g}, "
                f"interval {self.chosen + 1} of {len(self.intervals)}>")

    def describe(self, unit: str = "") -> str:
        """One sentence for a log: the start, and why it was chosen."""
        u = f" {unit}" if unit else ""
        lo, hi = self.intervals[self.chosen]
        text = (f"pair {self.pair!r} states no follower start: q2 = {self.q2:.6g}{u} at "
                f"q1 = {self.q1:.6g}, the middle of the widest free interval "
                f"[{lo:.6g}, {hi:.6g}]{u}")
        if self.jams:
            text += (" in which the nominal motion completes its drive (it jams from the "
                     "middle of the wider " + ", ".join(
                         f"[{self.intervals[i][0]:.6g}, {self.intervals[i][1]:.6g}]"
                         for i in self.jams) + ")")
        if not self.ambiguous:
            return text + " (the only one)"
        others = ", ".join(f"[{a:.6g}, {b:.6g}]" for i, (a, b) in enumerate(self.intervals)
                           if i != self.chosen)
        return (text + f", one of {len(self.intervals)} free intervals (also {others}): "
                       f"the follower could start in another, and the motion would differ")

    def to_dict(self) -> dict:
        return {"pair": self.pair, "q1": self.q1, "q2": self.q2,
                "intervals": [list(iv) for iv in self.intervals], "chosen": self.chosen,
                "ambiguous": self.ambiguous, "jams": list(self.jams)}


class UnionFind:
    """Disjoint sets of the integers 0..n-1 (path halving; the smaller root
    wins a union, so a set's representative is its smallest member)."""

    def __init__(self, n):
        self.p = list(range(n))

    def find(self, a):
        while self.p[a] != a:
            self.p[a] = self.p[self.p[a]]
            a = self.p[a]
        return a

    def union(self, a, b):
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.p[max(ra, rb)] = min(ra, rb)


#: :meth:`ConfigurationSpace.face_polygons` of the C-spaces alive (not part of
#: the object: it is not pickled with it).
_FACE_POLYGONS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


@dataclass(frozen=True, eq=False)
class ConfigurationSpace:
    """The computed C-space of a pair in a window.

    Attributes
    ----------
    pair : Pair
    accuracy : Accuracy
    window : (q1_lo, q1_hi, q2_lo, q2_hi)
    curves : tuple of ContactCurve
        All trimmed contact curves (boundary or not).
    vertical : tuple of VerticalCurve
    events : (m,) float
        Slab boundaries in q1.
    cells : tuple of tuple of Cell
        Cells per slab, in increasing q2 order (from the window bottom).
    faces : dict int -> bool
        Face id -> free.
    boundary : tuple of BoundaryPiece
    graph : networkx.MultiGraph
        Nodes are boundary vertices (attribute ``q``); edges are boundary pieces
        with ``label``, ``branch``, ``kind``, ``key``, ``free_face``,
        ``blocked_face``, ``q1_range``, ``free_above``.
    stats : dict
        Counts: candidates, pruned, reused (curves taken from a cache), curves, events,
        cells, faces, and ``thin_cells``: slab cells narrower than the resolution
        (100 x ``Accuracy.root_tol``, in the C-space metric) that were closed.  A
        channel narrower than that is reported as contact, not free; a finer
        preset resolves it.
    """

    pair: Pair
    accuracy: Accuracy
    window: tuple
    curves: tuple
    vertical: tuple
    events: np.ndarray
    cells: tuple
    faces: dict
    boundary: tuple
    graph: nx.MultiGraph
    stats: dict
    periodic: tuple = (True, True)
    _crossings: tuple = field(default=(), repr=False)

    def __repr__(self):
        nfree = sum(self.faces.values())
        return (f"<ConfigurationSpace {self.pair.name!r}: {len(self.curves)} curves, "
                f"{len(self.boundary)} boundary pieces, {nfree} free / "
                f"{len(self.faces) - nfree} blocked faces>")

    @property
    def free_faces(self) -> list[int]:
        return sorted(f for f, free in self.faces.items() if free)

    # ------------------------------------------------------------------ queries
    @property
    def _s1(self) -> float:
        """Length along q1 that counts as 1 in the C-space metric (1 for a
        rotating driver, the characteristic length for a sliding one)."""
        return driver_scale(self.pair)

    def slab_of(self, q1) -> np.ndarray:
        q1 = np.asarray(q1, dtype=float)
        k = np.searchsorted(self.events, q1, side="right") - 1
        return np.clip(k, 0, len(self.events) - 2)

    def active(self, k: int) -> list[int]:
        return sorted({c.lower for c in self.cells[k] if c.lower >= 0}
                      | {c.upper for c in self.cells[k] if c.upper >= 0})

    def cell_at(self, q) -> np.ndarray:
        """Index of the cell (within its slab) containing each configuration, and the
        slab.  Returns (slab (N,), cell (N,))."""
        q = _as_configs(q)
        q1 = q[:, 0]
        if self.periodic[0]:
            q1 = _wrap(q1, self.window[0])
        q2 = q[:, 1]
        if self.periodic[1]:
            q2 = _wrap(q2, self.window[2])
        slabs = self.slab_of(q1)
        cell_idx = np.zeros(len(q1), dtype=int)
        # every lower bound evaluated once, at all the points of all the slabs
        # it bounds (a curve's value does not depend on the others computed
        # with it, tests/cspace/test_contact.py)
        rows, need = [], {}
        for k in np.unique(slabs):
            if len(self.cells[k]) == 1:
                continue
            sel = np.nonzero(slabs == k)[0]
            rows.append((k, sel))
            for c in self.cells[k]:
                if c.lower >= 0:
                    need.setdefault(c.lower, []).append((k, sel))
        at = {}
        for i, parts in need.items():
            v = self.curves[i].evaluate(q1[np.concatenate([sel for _, sel in parts])])
            o = 0
            for k, sel in parts:
                at[i, k] = v[o:o + len(sel)]
                o += len(sel)
        for k, sel in rows:
            vals = np.array([at[c.lower, k] if c.lower >= 0 else np.full(len(sel), -np.inf)
                             for c in self.cells[k]])
            if self.periodic[1]:
                dist = (q2[sel][None, :] - vals) % TWO_PI
                # the cell whose lower bound lies closest below q2; where lower
                # bounds coincide to rounding (zero-height cells between equal
                # curves, as at a zero-clearance fit) the last of those cells in
                # cyclic order, since q2 lies above the zero-height ones
                near = dist <= dist.min(axis=0)[None, :] + _TIE
                last = near & ~np.roll(near, -1, axis=0)
                cell_idx[sel] = np.where(last.any(axis=0), np.argmax(last, axis=0),
                                         np.argmin(dist, axis=0))
            else:
                below = vals <= q2[sel][None, :]
                # cells are ordered bottom-up: last lower bound below q2
                cell_idx[sel] = np.maximum(np.sum(below, axis=0) - 1, 0)
        return slabs, cell_idx

    def row_bounds(self, k: int, x: float, values=None, which=None):
        """Bounds (lo, hi) of the cells of slab ``k`` at one driver value ``x``
        (arrays in cell order; the rule of :func:`cell_interval`).

        ``values(i, xx) -> (wrapped, raw)`` may supply (memoised) curve values;
        ``which`` (cell indices) limits the work to those cells."""
        row = self.cells[k]
        cells = row if which is None else [row[j] for j in which]
        if values is None:
            def values(i, xx):
                return self.curves[i].values(xx)
        return _row_bounds([c.lower for c in cells], [c.upper for c in cells], len(row), x,
                           0.5 * (self.events[k] + self.events[k + 1]), values, self.window,
                           self.periodic[1])

    def free_intervals(self, q1: float) -> list:
        """Free follower intervals at one driver value.

        Returns a list of ``(lo, hi, face)`` (q2 bounds in the window's
        coordinates, ``hi >= lo``; for a rotating follower ``hi`` may exceed the
        window top by up to one period), in the order of the slab's cells:
        bottom-up, except that for a rotating follower an interval across the
        window's seam (from ``lo`` near the top to ``hi`` beyond it) may come
        first, so the list is not always sorted by ``lo``.
        """
        return [(a, b, int(c.face)) for a, b, c in self.free_cells(q1)]

    def free_cells(self, q1: float) -> list:
        """The free cells at one driver value with their bounds there:
        ``(lo, hi, cell)`` per free interval of :meth:`free_intervals`, in its
        order (the cell names the curves below and above it)."""
        x = float(q1)
        if self.periodic[0]:
            x = float(_wrap(np.array([x]), self.window[0])[0])
        k = int(self.slab_of(x))
        lo, hi = self.row_bounds(k, x)
        return [(float(a), float(b), c) for c, a, b in zip(self.cells[k], lo, hi) if c.free]

    def default_start(self, q1: float) -> float:
        """Follower coordinate in the middle of the widest free interval at ``q1``
        (the start used when a model gives none; :meth:`start_choice` says
        which intervals there were)."""
        return self.start_choice(q1).q2

    def start_choice(self, q1: float) -> StartChoice:
        """The follower start used when a model states none, and the free
        intervals it was chosen from: the middle of the widest free interval at
        ``q1`` (the first of equally wide ones).  Several free intervals make
        the choice ambiguous (:attr:`StartChoice.ambiguous`)."""
        ivs = [iv for iv in self.free_intervals(q1) if np.isfinite(iv[0]) and np.isfinite(iv[1])]
        if not ivs:
            raise CSpaceError(f"pair {self.pair.name!r}: no free follower position at "
                              f"q1 = {q1:.6g}; expected a driver value with a free interval")
        widths = [hi - lo for lo, hi, _ in ivs]
        k = int(np.argmax(widths))
        lo, hi, _ = ivs[k]
        q2 = 0.5 * (lo + hi)
        if self.periodic[1]:
            q2 = float(_wrap(np.array([q2]), self.window[2])[0])
        return StartChoice(float(q1), float(q2), tuple((float(a), float(b)) for a, b, _ in ivs),
                           k, self.pair.name)

    def face_at(self, q) -> np.ndarray:
        """Face id of the cell containing each configuration (N,) int."""
        slabs, ci = self.cell_at(q)
        return np.array([self.cells[k][c].face for k, c in zip(slabs, ci)], dtype=int)

    def classify(self, q, tol: float | None = None) -> np.ndarray:
        """Classify configurations as FREE, BLOCKED or CONTACT.

        Parameters
        ----------
        q : (2,) or (N, 2) float
            Configurations (q1, q2).
        tol : float, optional
            Distance (C-space metric) to a free-space boundary below which a point
            counts as CONTACT; default ``accuracy.contact_rel``.

        Returns
        -------
        (N,) object array of :class:`Status` members (``Status.FREE`` ...);
        being an ``IntEnum``, each compares equal to its int value too.
        """
        q = _as_configs(q)
        tol = self.accuracy.contact_rel if tol is None else float(tol)
        slabs, ci = self.cell_at(q)
        out = np.empty(len(q), dtype=int)
        L = self.pair.char_length
        s2 = 1.0 if self.periodic[1] else 1.0 / L
        q1 = _wrap(q[:, 0], self.window[0]) if self.periodic[0] else q[:, 0]
        for k in np.unique(slabs):
            sel = np.nonzero(slabs == k)[0]
            cells = self.cells[k]
            out[sel] = [Status.FREE if cells[c].free else Status.BLOCKED for c in ci[sel]]
            # contact: near a boundary curve of this slab
            bcurves = {c.upper for i, c in enumerate(cells)
                       if c.upper >= 0 and cells[(i + 1) % len(cells)].free != c.free}
            for b in bcurves:
                v = self.curves[b].evaluate(q1[sel])
                d = q[sel, 1] - v
                if self.periodic[1]:
                    d = (d + math.pi) % TWO_PI - math.pi
                out[sel[np.abs(d) * s2 <= tol]] = Status.CONTACT
        for vc in self.vertical:
            near = (np.abs(q1 - vc.q1_value) <= tol)
            q2 = _wrap(q[:, 1], self.window[2]) if self.periodic[1] else q[:, 1]
            near &= (q2 >= vc.q2_lo - tol) & (q2 <= vc.q2_hi + tol)
            out[near] = Status.CONTACT
        members = np.empty(len(out), dtype=object)
        members[:] = [_STATUS[v] for v in out]
        return members

    # ------------------------------------------------------------------ geometry
    def cell_polygons(self):
        """Polygons of all cells: list of (slab, cell index, free, face, shapely geometry)."""
        from shapely.geometry import Polygon, box
        from shapely import affinity, intersection, make_valid
        out = []
        lo1, hi1, lo2, hi2 = self.window
        span2 = hi2 - lo2
        win = box(lo1, lo2, hi1, hi2)
        for k, cells in enumerate(self.cells):
            a, b = self.events[k], self.events[k + 1]
            xm = 0.5 * (a + b)
            ends = np.array([a, b])
            bounds = {}        # curve -> (t, q2) outline along the slab
            for j, c in enumerate(cells):
                if c.lower >= 0:
                    tl, lower = bounds.setdefault(c.lower, self._bound_samples(c.lower, a, b))
                else:
                    tl, lower = ends, np.full(2, lo2)
                if c.upper >= 0:
                    tu, upper = bounds.setdefault(c.upper, self._bound_samples(c.upper, a, b))
                elif self.periodic[1]:
                    tu, upper = tl, lower + span2
                else:
                    tu, upper = ends, np.full(2, hi2)
                if self.periodic[1] and len(cells) > 1:
                    # the cell runs up from its lower bound to the next value of
                    # its upper one, as cell_at places points (at the middle)
                    lm, um = np.interp(xm, tl, lower), np.interp(xm, tu, upper)
                    shift = 0.0
                    while um + shift < lm:
                        shift += span2
                    while um + shift - lm > span2 + ROUNDING:
                        shift -= span2
                    upper = upper + shift
                elif self.periodic[1] and len(cells) == 1:
                    tl, lower = ends, np.full(2, lo2)
                    tu, upper = ends, np.full(2, hi2)
                ring = np.vstack([np.stack([tl, lower], 1), np.stack([tu[::-1], upper[::-1]], 1)])
                poly = Polygon(ring)
                if not poly.is_valid:
                    # where the bounds meet (a cell closing at the slab's end)
                    # rounding can cross them: keep every lobe (buffer(0) keeps
                    # only those of one orientation and may drop the cell)
                    poly = _polygonal(make_valid(poly))
                pieces = []
                for sh in ((-span2, 0.0, span2) if self.periodic[1] else (0.0,)):
                    g = intersection(affinity.translate(poly, 0, sh), win)
                    if not g.is_empty and g.area > 0:
                        pieces.append(g)
                from shapely import unary_union
                geom = unary_union(pieces) if pieces else Polygon()
                out.append((k, j, c.free, c.face, geom))
        return out

    def _bound_samples(self, i: int, a: float, b: float):
        """Outline of curve ``i`` over the slab [a, b]: (t, q2) arrays, within the
        accuracy's chord of the curve (C-space metric), continuous along t, and
        equal to :meth:`ContactCurve.evaluate` at the slab's middle, where
        :meth:`cell_at` compares the bounds.

        The contact solver returns a rotating follower's angle from an arctan,
        so its raw values may jump by 2 pi inside a slab: they are made
        continuous before the outline is drawn (such a jump made one cell's
        polygon overlap its neighbours', which ``classify`` rightly did not).
        """
        from .roots import adaptive_polyline
        cv = self.curves[i]
        acc = self.accuracy
        if self.periodic[1]:
            n = max(2, int(math.ceil((b - a) / (acc.max_step * self._s1))) + 1)
            t0 = np.linspace(a, b, n)
            v0 = np.unwrap(cv.raw(t0))

            def fn(t):
                r = cv.raw(t)
                return r + TWO_PI * np.round((np.interp(t, t0, v0) - r) / TWO_PI)
        else:
            fn = cv.raw

        s2 = 1.0 / follower_scale(self.pair)
        pl = adaptive_polyline(fn, a, b, acc.chord, acc.max_step * self._s1, scale=s2,
                               scale1=1.0 / self._s1)
        t, v = pl[:, 0], pl[:, 1]
        xm = 0.5 * (a + b)
        ref = float(cv.evaluate(np.array([xm]))[0])
        return t, v + (ref - float(fn(np.array([xm]))[0]))

    def face_polygons(self) -> dict:
        """Face id -> shapely (Multi)Polygon in the window.  Computed once per
        C-space and kept while it lives (a synthesis report draws the faces
        of the same C-space in several figures); each call returns a new dict
        of the same (immutable) geometries."""
        got = _FACE_POLYGONS.get(self)
        if got is None:
            from shapely import unary_union
            byface: dict = {}
            for _, _, _, face, g in self.cell_polygons():
                if not g.is_empty:
                    byface.setdefault(face, []).append(g)
            got = {f: unary_union(gs) for f, gs in byface.items()}
            _FACE_POLYGONS[self] = got
        return dict(got)

    def curve_polylines(self, boundary_only: bool = False):
        """Polylines (label, branch, (n, 2) array) of curves, split at the q2 seam."""
        out = []
        if boundary_only:
            items = [(self.curves[b.curve], b.q1_start, b.q1_end) for b in self.boundary]
        else:
            items = [(c, c.q1_start, c.q1_end) for c in self.curves]
        from .roots import adaptive_polyline
        for c, a, b in items:
            if b - a <= 0:
                continue
            s2 = 1.0 / follower_scale(self.pair)
            pl = adaptive_polyline(c.raw, a, b, self.accuracy.chord,
                                   self.accuracy.max_step * self._s1, scale=s2,
                                   scale1=1.0 / self._s1)
            for seg in split_wrapped(pl, self.window[2], self.periodic[1]):
                out.append((c.label, c.branch, seg))
        return out

    def to_dict(self, *, boundary_only: bool = False) -> dict:
        """The C-space JSON of the file-format documentation."""
        from .io import cspace_to_dict
        return cspace_to_dict(self, boundary_only=boundary_only)


def _polygonal(g):
    """The polygons of a shapely geometry (lines and points of a collection dropped)."""
    import shapely
    from shapely.geometry import Polygon
    parts = [p for p in shapely.get_parts(g) if p.geom_type in ("Polygon", "MultiPolygon")]
    return shapely.unary_union(parts) if parts else Polygon()


#: Two curve values closer than this (rad) are the same value when a point is
#: placed among the cells of a slab (rounding of coincident curves).
_TIE = 1e-12


def _as_configs(q) -> np.ndarray:
    from .errors import InputError, NonFiniteError
    try:
        a = np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"configurations must be numbers of shape (2,) or (N, 2), got {q!r}") from None
    if a.ndim == 1 and a.shape[0] == 2:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 2:
        raise InputError(f"configurations must have shape (2,) or (N, 2), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError("configurations must be finite (no NaN or inf)")
    return a


# ---------------------------------------------------------------------- the sweep

def _diff(vi, vj, periodic):
    d = vj - vi
    if periodic:
        d = (d + math.pi) % TWO_PI - math.pi
    return d


_S = np.linspace(0, 1, 9)[1:-1]
_H = np.stack([2 * _S ** 3 - 3 * _S ** 2 + 1, _S ** 3 - 2 * _S ** 2 + _S,
               -2 * _S ** 3 + 3 * _S ** 2, _S ** 3 - _S ** 2])  # cubic Hermite basis (4, 7)


def _crossings(curves, grid, V, Vp, periodic2, tol, scale2: float = 1.0):
    """Crossing events between pairs of curves: list of (q1, i, j).

    Sign changes of the (wrapped) difference on the scan grid are refined by
    Brent's method; an interval without a sign change is refined only when the
    cubic Hermite interpolant of the difference (values and slopes at both ends)
    dips towards zero, which finds double crossings and touches inside one step.
    ``scale2`` is the length that counts as 1 rad for a sliding follower (the
    C-space metric), so that the proximity screens below are scale-free.
    """
    out = []
    P = len(curves)
    valid = ~np.isnan(V)
    idx = [np.nonzero(valid[i])[0] for i in range(P)]
    rng = [(ix[0], ix[-1]) if ix.size else (1, 0) for ix in idx]
    for i in range(P):
        ai, bi = rng[i]
        if ai > bi or i + 1 >= P:
            continue
        # broad screen of every later curve at once: a crossing needs the two
        # curves within 0.5 (scaled) of each other at some common sample
        with np.errstate(invalid="ignore"):
            dall = np.abs(_diff(V[i, ai:bi + 1][None, :], V[i + 1:, ai:bi + 1], periodic2))
        near = np.nonzero(np.min(np.where(np.isnan(dall), np.inf, dall), axis=1)
                          <= 0.5 * scale2)[0] + i + 1
        for j in near:
            aj, bj = rng[j]
            lo, hi = max(ai, aj), min(bi, bj)
            if hi - lo < 1:
                continue
            d = _diff(V[i, lo:hi + 1], V[j, lo:hi + 1], periodic2)
            ok = valid[i, lo:hi + 1] & valid[j, lo:hi + 1]
            if not ok.any() or np.min(np.abs(d[ok])) > 0.5 * scale2:
                continue  # far apart everywhere sampled: a crossing needs |d| small
            d0, d1 = d[:-1], d[1:]
            okk = ok[:-1] & ok[1:] & (np.abs(d0) <= scale2) & (np.abs(d1) <= scale2)
            if not okk.any():
                continue
            ci, cj = curves[i], curves[j]
            fn = (lambda x, ci=ci, cj=cj: _diff(ci.raw(np.atleast_1d(x)), cj.raw(np.atleast_1d(x)), periodic2)[0])
            g = grid[lo:hi + 1]
            zero = okk & (d0 == 0.0)
            for k in np.nonzero(zero)[0]:
                out.append((g[k], i, j))
            sc = okk & (d0 * d1 < 0)
            for k in np.nonzero(sc)[0]:
                out.append((_brent(fn, g[k], g[k + 1], tol), i, j))
            rest = okk & (d0 * d1 > 0)
            if not rest.any():
                continue
            h = np.diff(g)
            dp = Vp[j, lo:hi + 1] - Vp[i, lo:hi + 1]
            cub = (_H[0][None, :] * d0[:, None] + _H[1][None, :] * (h * dp[:-1])[:, None]
                   + _H[2][None, :] * d1[:, None] + _H[3][None, :] * (h * dp[1:])[:, None])
            sg = np.sign(d0)
            ext = np.min(sg[:, None] * cub, axis=1)
            cand = rest & (ext < 0.25 * np.minimum(np.abs(d0), np.abs(d1)))
            kc = np.nonzero(cand)[0]
            if kc.size:
                # sample the candidate intervals densely in one vectorised call each
                t = np.linspace(0.0, 1.0, 17)[1:-1]
                xs = (g[kc][:, None] + h[kc][:, None] * t[None, :]).ravel()
                dd = _diff(ci.raw(xs), cj.raw(xs), periodic2).reshape(len(kc), -1)
                for row, k in enumerate(kc):
                    a, b = g[k], g[k + 1]
                    sgk = sg[k]
                    vals = sgk * dd[row]
                    if vals.min() >= 0:
                        continue
                    xk = a + (b - a) * t
                    neg = np.nonzero(vals < 0)[0]
                    i0, i1 = neg[0], neg[-1]
                    left = a if i0 == 0 else xk[i0 - 1]
                    right = b if i1 == len(t) - 1 else xk[i1 + 1]
                    out.append((_brent(fn, left, xk[i0], tol), i, j))
                    out.append((_brent(fn, xk[i1], right, tol), i, j))
    return out


def _brent(fn, a, b, tol):
    try:
        return brentq(fn, a, b, xtol=tol, maxiter=200)
    except (ValueError, RuntimeError):
        return 0.5 * (a + b)


#: Supported size of a pair: segments of both parts together.  The broad phase
#: keeps the cost near-linear in segments for parts that mostly do not touch,
#: but every contact curve is traced and ordered against the others, so a
#: drawing whose whole outline comes into contact costs more: 1000 segments of
#: two meshing outlines take about 15 s CPU with the "fast" preset.  Beyond
#: this many, configuration_space asks for an explicit ``max_segments`` (or the
#: environment variable ``CSPACE_MAX_SEGMENTS``, for the command line).
MAX_SEGMENTS = 2000


def _segment_limit(pair, max_segments):
    import os
    from .argcheck import getint
    from .errors import InputError
    if max_segments is None:
        env = os.environ.get("CSPACE_MAX_SEGMENTS", "").strip()
        if env:
            try:
                max_segments = int(env)
            except ValueError:
                raise InputError(f"CSPACE_MAX_SEGMENTS must be a positive integer, got "
                                 f"{env[:40]!r}", name="CSPACE_MAX_SEGMENTS",
                                 value=env[:40]) from None
        else:
            max_segments = MAX_SEGMENTS
    max_segments = getint(max_segments, "max_segments", minimum=1)
    n = sum(len(lp.segments) for part in pair.parts for lp in part.loops)
    if n > max_segments:
        raise InputError(f"pair {pair.name!r} has {n} segments; the supported size is "
                         f"{max_segments} (both parts together). Larger drawings run when "
                         f"asked for: configuration_space(..., max_segments={n}) or the "
                         f"environment variable CSPACE_MAX_SEGMENTS={n}", name="pair",
                         value=n)


def configuration_space(pair: Pair, accuracy: Accuracy | str | None = None, *, window=None,
                        deps=None, prune: bool = True,
                        curveset: CurveSet | None = None, cache=None,
                        max_segments: int | None = None) -> ConfigurationSpace:
    """Compute the free space of a pair.

    No result passes through a NaN: an invalid floating-point operation (0/0,
    inf - inf) anywhere in the computation raises
    :class:`~cspace.errors.NumericalError` instead of a C-space that looks clean.

    Parameters
    ----------
    pair : Pair
    accuracy : Accuracy, preset name or None
    window : (q1_lo, q1_hi, q2_lo, q2_hi), optional
        Default: one period of each rotating coordinate, the reachable range of a
        sliding one.  Only the driver range asked for is computed.
    deps : mapping, optional
        Parameter dependencies of the segments (recorded on the curves).
    prune : bool
        Broad-phase pruning of feature pairs (on by default).
    curveset : CurveSet, optional
        Precomputed curves.
    cache : cspace.cache.CurveCache, optional
        Reuse unchanged contact curves across variants (:mod:`cspace.cache`).
    max_segments : int, optional
        Largest pair accepted, in segments of both parts (default
        :data:`MAX_SEGMENTS`, or the environment variable
        ``CSPACE_MAX_SEGMENTS``); a larger pair is an InputError.

    Returns
    -------
    ConfigurationSpace

    Examples
    --------
    >>> from mechanisms.models import geneva                       # doctest: +SKIP
    >>> cs = configuration_space(geneva().build())                  # doctest: +SKIP
    >>> cs.classify([[0.0, 0.0]])                                   # doctest: +SKIP
    """
    if isinstance(pair, Pair):
        _segment_limit(pair, max_segments)
    try:
        with np.errstate(invalid="raise"):
            return _configuration_space(pair, accuracy, window=window, deps=deps, prune=prune,
                                        curveset=curveset, cache=cache)
    except FloatingPointError as e:
        from .errors import NumericalError
        raise NumericalError(
            f"pair {getattr(pair, 'name', '?')!r}: the C-space computation met an invalid "
            f"floating-point operation ({e}); expected finite intermediate values. The "
            f"geometry is probably beyond what double precision resolves (coordinates "
            f"far from the parts, sizes far apart)") from None


def _configuration_space(pair, accuracy, *, window, deps, prune, curveset, cache):
    """The stages of :func:`configuration_space`, top to bottom."""
    if not isinstance(pair, Pair):
        from .errors import InputError
        raise InputError(f"pair must be a Pair, got {type(pair).__name__}")
    acc = as_accuracy(accuracy)
    cs = curveset if curveset is not None else contact_curves(pair, acc, window=window,
                                                              deps=deps, prune=prune,
                                                              cache=cache)
    fr = _frame(pair, acc, cs)
    grid, V, Vp = _scan(fr)                                       # 1. scan grid
    cross, events = _events(fr, grid, V, Vp)                      # 2. events
    slab_cells, blocked, thin = _slab_cells(fr, events)           # 3. cells per slab
    cells_out, faces = _faces(fr, events, slab_cells, blocked)    # 4. faces
    merged = _boundary_runs(fr, events, cross, cells_out)         # 5. boundary pieces
    pieces, G = _graph(fr, events, merged, faces)                 # 6. graph
    curves = fr.curves
    stats = {"candidates": cs.n_candidates, "pruned": cs.n_pruned, "reused": cs.n_reused,
             "thin_cells": int(thin),
             "curves": len(curves),
             "vertical": len(cs.vertical), "crossings": len(cross), "events": len(events),
             "cells": sum(len(r) for r in cells_out), "faces": len(faces),
             "free_faces": sum(faces.values()), "boundary_pieces": len(pieces)}
    return ConfigurationSpace(pair, acc, cs.window, curves, cs.vertical, events,
                              tuple(cells_out), faces, tuple(pieces), G, stats,
                              (fr.periodic1, fr.periodic2), tuple(cross))


@dataclass(frozen=True, eq=False)
class _Frame:
    """What every stage of :func:`_configuration_space` reads: the pair, its
    curves and window, periodicity, and the tolerances in both coordinates."""

    pair: Pair
    acc: Accuracy
    cs: CurveSet
    curves: tuple
    window: tuple
    periodic1: bool
    periodic2: bool
    s1: float        # q1 lengths: rad, or model units per C-space-metric rad
    tol: float       # root tolerance along q1
    merge: float     # merge distance (C-space metric)
    merge1: float    # the same along q1
    scale2: float    # a follower length counted as 1 rad


def _frame(pair, acc, cs) -> _Frame:
    lo1, hi1 = cs.window[0], cs.window[1]
    # q1 lengths: rad for a rotating driver; a sliding driver's in model
    # units, as many characteristic lengths as the C-space metric's rad
    s1 = driver_scale(pair)
    merge = max(acc.root_tol * 100, ROUNDING)   # C-space metric
    periodic2 = isinstance(pair.follower.axis, Rotation)
    return _Frame(pair, acc, cs, cs.curves, cs.window,
                  isinstance(pair.driver.axis, Rotation) and is_period(lo1, hi1), periodic2,
                  s1, acc.root_tol * s1, merge, merge * s1,
                  follower_scale(pair))


def _curve_ends(fr: _Frame) -> tuple:
    curves = fr.curves
    return ([c.q1_start for c in curves] + [c.q1_end for c in curves],
            [v.q1_value for v in fr.cs.vertical])


def _scan(fr: _Frame):
    """Stage 1: every curve's value and slope on a scan grid holding every
    curve end: the grid (G,), values (P, G) (NaN off the curve), slopes."""
    lo1, hi1 = fr.window[0], fr.window[1]
    n = max(9, int(math.ceil((hi1 - lo1) / (fr.acc.scan_step * fr.s1))) + 1)
    ends, vq = _curve_ends(fr)
    grid = _dedupe(np.concatenate([np.linspace(lo1, hi1, n), ends, vq]), fr.merge1)
    P = len(fr.curves)
    V = np.full((P, len(grid)), np.nan)
    Vp = np.zeros((P, len(grid)))
    hstep = PROBE_REL * fr.s1
    merge1 = fr.merge1
    for i, c in enumerate(fr.curves):
        ia = np.searchsorted(grid, c.q1_start - merge1)
        ib = np.searchsorted(grid, c.q1_end + merge1) - 1
        if ib < ia:
            continue
        g = np.clip(grid[ia:ib + 1], c.q1_start, c.q1_end)
        gp = np.clip(g + hstep, c.q1_start, c.q1_end)
        gm = np.clip(g - hstep, c.q1_start, c.q1_end)
        r = c.raw(np.concatenate([g, gp, gm])).reshape(3, -1)   # one solve
        V[i, ia:ib + 1] = r[0]
        Vp[i, ia:ib + 1] = (r[1] - r[2]) / np.maximum(gp - gm, TINY)
    return grid, V, Vp


def _events(fr: _Frame, grid, V, Vp):
    """Stage 2: the crossings [(q1, i, j)] and the sorted event driver values
    (window ends, curve ends, vertical segments, crossings)."""
    curves, merge1 = fr.curves, fr.merge1
    lo1, hi1 = fr.window[0], fr.window[1]
    cross = _crossings(curves, grid, V, Vp, fr.periodic2, fr.tol, fr.scale2)
    # A "crossing" within the merge distance of an end of both curves is where
    # one contact hands over to the next (the curves join at a shared end, as a
    # vertex passes the junction of two arcs); the end event already holds both
    # curves.  Kept or not, it would merge into that event, but whether the root
    # finder reports it depends on the last bits of the geometry, so drop it.
    cross = [(x, i, j) for x, i, j in cross
             if not (min(abs(x - curves[i].q1_start), abs(x - curves[i].q1_end)) <= merge1
                     and min(abs(x - curves[j].q1_start), abs(x - curves[j].q1_end)) <= merge1)]
    ends, vq = _curve_ends(fr)
    events = _dedupe(np.concatenate([[lo1, hi1], ends, vq, [x for x, _, _ in cross]]), merge1)
    events = events[(events >= lo1 - merge1) & (events <= hi1 + merge1)]
    events[0], events[-1] = lo1, hi1
    return cross, events


def _slab_cells(fr: _Frame, events):
    """Stage 3: per slab between events, its cells ``(lower curve, upper
    curve, q2 at the centre)`` bottom to top (-1: window edge), whether each
    cell's centre is blocked (one flat array, slab by slab), and the number of
    cells thinner than the merge distance (dropped)."""
    nslab = len(events) - 1
    mids = 0.5 * (events[:-1] + events[1:])
    slab_vals: list = [dict() for _ in range(nslab)]
    merge1 = fr.merge1
    for i, c in enumerate(fr.curves):
        ks = np.nonzero((c.q1_start <= events[:-1] + merge1) & (c.q1_end >= events[1:] - merge1))[0]
        if ks.size:
            for k, v in zip(ks, c.evaluate(mids[ks])):
                slab_vals[k][i] = v
    slab_cells, samples, thin = [], [], 0
    for k in range(nslab):
        act = sorted(slab_vals[k])
        vals = np.array([slab_vals[k][i] for i in act]) if act else np.zeros(0)
        order = np.argsort(vals, kind="stable")
        act = [act[o] for o in order]
        cells, t = _cells_of_slab(fr, act, vals[order])
        thin += t
        slab_cells.append(cells)
        samples += [(mids[k], c[2]) for c in cells]
    blocked = (parts_overlap(fr.pair, np.array(samples)) if samples
               else np.zeros(0, bool))
    return slab_cells, blocked, thin


def _cells_of_slab(fr: _Frame, act, vals):
    """The cells of one slab from its curves ``act`` sorted by their values
    ``vals`` at the slab's centre, and how many thin ones were dropped."""
    lo2, hi2 = fr.window[2], fr.window[3]
    merge = fr.merge
    cells, thin = [], 0
    if fr.periodic2:
        if not act:
            cells.append((-1, -1, lo2 + 0.5 * (hi2 - lo2)))
        else:
            for t in range(len(act)):
                lo_v = vals[t]
                hi_v = vals[t + 1] if t + 1 < len(act) else vals[0] + TWO_PI
                if hi_v - lo_v <= merge:
                    thin += hi_v > lo_v
                    continue
                cells.append((act[t], act[(t + 1) % len(act)], _wrap(0.5 * (lo_v + hi_v), lo2)))
            if not cells:  # all curves coincide
                cells.append((act[0], act[0], _wrap(vals[0] + math.pi, lo2)))
    else:
        bounds = [(-1, lo2)] + list(zip(act, vals)) + [(-1, hi2)]
        for t in range(len(bounds) - 1):
            (il, vl), (iu, vu) = bounds[t], bounds[t + 1]
            if vu - vl <= merge * fr.scale2:
                thin += vu > vl
                continue
            cells.append((il, iu, 0.5 * (vl + vu)))
    return cells, thin


def _faces(fr: _Frame, events, slab_cells, blocked):
    """Stage 4: the cells (per slab, :class:`Cell`) united into faces across
    curves that are not boundaries and across events; ``{face: free}``."""
    flat = []
    rows = []
    pos = 0
    for cells in slab_cells:
        row = []
        for c in cells:
            row.append((len(flat), c[0], c[1], not bool(blocked[pos])))
            flat.append(row[-1])
            pos += 1
        rows.append(row)
    uf = UnionFind(len(flat))
    # cells of one class on both sides of a curve that is not a boundary are one face
    for row in rows:
        nrow = len(row)
        pairs_ = range(nrow) if (fr.periodic2 and nrow > 1) else range(nrow - 1)
        for t in pairs_:
            a_, b_ = row[t], row[(t + 1) % nrow]
            if a_[3] == b_[3]:
                uf.union(a_[0], b_[0])
    _link_slabs(fr, events, rows, uf)
    roots = {}
    faces = {}
    cells_out = []
    for k, row in enumerate(rows):
        rc = []
        for fid, il, iu, free in row:
            r = uf.find(fid)
            face = roots.setdefault(r, len(roots))
            faces[face] = free
            rc.append(Cell(k, il, iu, free, face))
        cells_out.append(tuple(rc))
    return cells_out, faces


def _link_slabs(fr: _Frame, events, rows, uf) -> None:
    """Unite the cells of one class of neighbouring slabs that overlap at
    their common driver value (and across the seam of a periodic driver)."""
    curves, periodic2 = fr.curves, fr.periodic2
    nslab = len(rows)
    # evaluate every curve once, vectorised, at all the driver values the linking
    # below asks for (slab ends and mid-points), instead of point by point
    _ccache: dict = {}
    need: dict = {}
    for k, cells in enumerate(rows):
        xs = (float(events[k]), float(events[k + 1]), 0.5 * (events[k] + events[k + 1]))
        for _, il, iu, _ in cells:
            for i in (il, iu):
                if i >= 0:
                    need.setdefault(i, set()).update(xs)
    for i, xs_ in need.items():
        xx = np.array(sorted(xs_))
        vals, raws = curves[i].values(xx)
        for t, x_ in enumerate(xx):
            _ccache[(i, float(x_))] = (vals[t:t + 1], raws[t:t + 1])

    def bounds_at(k, x):
        """[(face id, lo, hi, free)] of the cells of slab k at driver value x."""
        cells = rows[k]
        lo, hi = _row_bounds([c[1] for c in cells], [c[2] for c in cells], len(cells), x,
                             0.5 * (events[k] + events[k + 1]),
                             lambda i, xx: _ccache[(i, float(xx[0]))], fr.window, periodic2)
        return [(c[0], float(vl), float(vu), c[3]) for c, vl, vu in zip(cells, lo, hi)]

    shifts = np.array([-TWO_PI, 0.0, TWO_PI] if periodic2 else [0.0])
    reach = fr.merge * fr.scale2

    def link_rows(A, B):
        """Union the cells of one class of two neighbouring slabs that overlap
        (by more than ``merge``) at their common driver value."""
        a = np.array([(la, ua, fa_) for fa_, la, ua, fr_ in A], dtype=float).reshape(-1, 3)
        b = np.array([(lb, ub, fb_) for fb_, lb, ub, fr_ in B], dtype=float).reshape(-1, 3)
        fra = np.array([fr_ for *_, fr_ in A], dtype=bool)
        frb = np.array([fr_ for *_, fr_ in B], dtype=bool)
        same = fra[:, None] == frb[None, :]
        hit = np.zeros(same.shape, dtype=bool)
        for sh in shifts:
            ov = (np.minimum(a[:, 1:2], b[None, :, 1] + sh)
                  - np.maximum(a[:, 0:1], b[None, :, 0] + sh))
            hit |= ov > reach
        for ia, ib in zip(*np.nonzero(hit & same)):
            uf.union(int(a[ia, 2]), int(b[ib, 2]))

    for k in range(nslab - 1):
        link_rows(bounds_at(k, events[k + 1]), bounds_at(k + 1, events[k + 1]))
    if fr.periodic1 and nslab > 1:
        # the seam: slab nslab-1 at hi1 meets slab 0 at lo1 (same configurations)
        link_rows(bounds_at(nslab - 1, fr.window[1]), bounds_at(0, fr.window[0]))


def _boundary_runs(fr: _Frame, events, cross, cells_out) -> list:
    """Stage 5: the boundary pieces as runs ``(curve, first slab, last slab,
    free above, free face, blocked face)``: a curve between a free and a
    blocked cell, merged over consecutive slabs unless an event of the curve
    lies between them."""
    event_curves: dict = {}
    for x, i, j in cross:
        ke = int(np.argmin(np.abs(events - x)))
        event_curves.setdefault(ke, set()).update((i, j))
    for i, c in enumerate(fr.curves):
        for x in (c.q1_start, c.q1_end):
            ke = int(np.argmin(np.abs(events - x)))
            event_curves.setdefault(ke, set()).add(i)
    raw_pieces = []  # (curve, slab, free_above, free_face, blocked_face)
    for k, row in enumerate(cells_out):
        nrow = len(row)
        if nrow < 2:
            continue
        rng_ = range(nrow) if fr.periodic2 else range(nrow - 1)
        for t in rng_:
            below, above = row[t], row[(t + 1) % nrow]
            if below.upper < 0 or below.free == above.free:
                continue
            ff = above.face if above.free else below.face
            bf = below.face if above.free else above.face
            raw_pieces.append((below.upper, k, above.free, ff, bf))
    raw_pieces.sort(key=lambda r: (r[0], r[1]))
    merged = []
    for cidx, k, fa, ff, bf in raw_pieces:
        if merged:
            m = merged[-1]
            if (m[0] == cidx and m[2] == k - 1 and m[3] == fa
                    and cidx not in event_curves.get(k, set())):
                merged[-1] = (cidx, m[1], k, fa, ff, bf)
                continue
        merged.append((cidx, k, k, fa, ff, bf))
    return merged


def _graph(fr: _Frame, events, merged, faces):
    """Stage 6: the boundary pieces and the boundary graph (vertices where
    piece ends meet, :class:`_Vertices`)."""
    G = nx.MultiGraph(name=fr.pair.name)
    verts = _Vertices(fr, events, merged, G)
    pieces = []
    for cidx, k0, k1, fa, ff, bf in merged:
        c = fr.curves[cidx]
        a, b = events[k0], events[k1 + 1]
        u = verts.node_id(a, verts.end_span(cidx, a))
        v = verts.node_id(b, verts.end_span(cidx, b))
        bp = BoundaryPiece(cidx, c.label, c.branch, float(a), float(b), fa, ff, bf, u, v)
        pieces.append(bp)
        G.add_edge(u, v, key=len(pieces) - 1, label=c.label, branch=c.branch, kind=c.kind,
                   ckey=c.key, free_face=ff, blocked_face=bf, q1_range=(float(a), float(b)),
                   free_above=fa, curve=cidx)
    G.graph["faces"] = dict(faces)
    G.graph["window"] = fr.cs.window
    return pieces, G


class _Vertices:
    """The vertices of the boundary graph.

    A vertex is where boundary pieces meet at one event.  The event's q1 is
    known to the merge distance only (nearby events are merged), and near a
    vertical tangent (the turning point where the two branches of one contact
    equation meet) q2 moves by ~sqrt(merge) over that distance.  So a piece end
    stands for the q2 interval its curve covers within the merge distance of
    the event, together with the other branch of the same equation when that
    branch ends there too; ends whose intervals touch are one vertex."""

    def __init__(self, fr: _Frame, events, merged, G):
        self.fr, self.G = fr, G
        self.nodes: list = []
        self.s2n = 1.0 / follower_scale(fr.pair)
        self.siblings: dict = {}
        for i, c in enumerate(fr.curves):
            if c.branch != 0:
                self.siblings.setdefault(c.features, []).append(i)
        self.ends, self.spans = {}, {}
        need_x: dict = {}
        for cidx, k0, k1, *_ in merged:
            for x in (float(events[k0]), float(events[k1 + 1])):
                j = self.ends[(cidx, x)] = self.partner(cidx, x)
                for i in (cidx, j):
                    if i is not None:
                        need_x.setdefault(i, set()).add(x)
        self._spans(need_x)

    def partner(self, cidx, x):
        """The other branch of curve cidx's equation when it also ends at x."""
        curves, merge1 = self.fr.curves, self.fr.merge1
        c = curves[cidx]
        for j in self.siblings.get(c.features, ()) if c.branch != 0 else ():
            o = curves[j]
            if (o.branch == -c.branch and o.q1_start - merge1 <= x <= o.q1_end + merge1
                    and min(abs(x - o.q1_start), abs(x - o.q1_end)) <= merge1):
                return j
        return None

    def _spans(self, need_x) -> None:
        """The q2 interval of every piece end (and of its partner branch): the
        centre and half-width of the values at x and at the merge distance
        either side, one vectorised evaluation per curve (the closed form is
        continuous a little past a trimmed end, and at an existence end both
        branches take the tangent value there)."""
        fr = self.fr
        for i, xs_ in need_x.items():
            c = fr.curves[i]
            xx = np.array(sorted(xs_))
            t = np.concatenate([xx, xx - fr.merge1, xx + fr.merge1])
            raw = c.raw(t).reshape(3, -1)
            base = c.evaluate(xx)
            d = raw - raw[0]
            if fr.periodic2:
                d = (d + math.pi) % TWO_PI - math.pi
            lo_, hi_ = d.min(0), d.max(0)
            cen = base + 0.5 * (lo_ + hi_)
            if fr.periodic2:
                cen = _wrap(cen, fr.window[2])
            for x, cc, hw in zip(xx, cen, 0.5 * (hi_ - lo_)):
                self.spans[(i, float(x))] = (float(cc), float(hw))

    def gap(self, a_, b_):
        d2 = b_[0] - a_[0]
        if self.fr.periodic2:
            d2 = (d2 + math.pi) % TWO_PI - math.pi
        return d2, abs(d2) - a_[1] - b_[1]

    def hull(self, a_, b_):
        d2, _ = self.gap(a_, b_)
        lo_ = min(-a_[1], d2 - b_[1])
        hi_ = max(a_[1], d2 + b_[1])
        c_ = a_[0] + 0.5 * (lo_ + hi_)
        return (_wrap(c_, self.fr.window[2]) if self.fr.periodic2 else c_), 0.5 * (hi_ - lo_)

    def end_span(self, cidx, x):
        x = float(x)
        sp = self.spans[(cidx, x)]
        j = self.ends[(cidx, x)]
        if j is not None and self.gap(sp, self.spans[(j, x)])[1] * self.s2n <= NODE_Q2_TOL:
            sp = self.hull(sp, self.spans[(j, x)])
        return sp

    def node_id(self, q1, sp):
        nodes, fr = self.nodes, self.fr
        for nid, (x, ns) in enumerate(nodes):
            d1 = q1 - x
            if fr.periodic1:
                d1 = (d1 + math.pi) % TWO_PI - math.pi
            if abs(d1) <= PROBE_REL * fr.s1 and self.gap(ns, sp)[1] * self.s2n <= NODE_Q2_TOL:
                nodes[nid] = (x, self.hull(ns, sp))
                return nid
        nodes.append((q1, sp))
        self.G.add_node(len(nodes) - 1, q=(float(q1), float(sp[0])))
        return len(nodes) - 1
