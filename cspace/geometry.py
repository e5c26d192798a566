"""Geometry values: line and arc segments, profile loops, parts, pairs.

All values are frozen dataclasses, validated at construction, and hashable, so a
variant is always a new value (``dataclasses.replace`` or ``model.build``).

Conventions
-----------
* Profile coordinates are world coordinates at configuration 0.
* A loop's material lies to the **left** of its direction of travel: outer
  boundaries run counter-clockwise, holes clockwise.  Loops nested inside a hole
  run counter-clockwise again.
* An :class:`Arc` runs from ``start_angle`` to ``end_angle``, counter-clockwise if
  ``ccw`` else clockwise; its sweep is in (0, 2 pi].  A full circle is one arc with
  ``end_angle = start_angle + 2 pi``.  A counter-clockwise arc of a loop is convex
  (material on the centre side); a clockwise one is concave.
* A :class:`Rotation` part at coordinate q is turned by q rad counter-clockwise
  about its centre; a :class:`Translation` part is moved by q along its unit
  direction.
* Validation tolerances are relative to the size of the loop or part
  (``VALIDATION_REL`` times its bounding-box diagonal), so validation is scale
  invariant.
"""

from __future__ import annotations

import contextlib
import functools
import contextvars
import math
from dataclasses import dataclass, field
from typing import Union

import numpy as np

from .argcheck import getpoint, getscalar
from .errors import (DegenerateGeometryError, InputError, NonPositiveRadiusError,
                     OpenLoopError, OrientationError, SelfIntersectionError,
                     ZeroDirectionError, ZeroLengthSegmentError)
from .geom2d import TWO_PI, degrees_hint, line_circle_quadratic, line_line, radical_foot, wrap_pi
from .tolerances import FULL_CIRCLE_SLACK, PARALLEL_REL, ROUNDING, SLACK, TINY

__all__ = ["Line", "Arc", "Segment", "Loop", "Rotation", "Translation", "Axis", "Part",
           "Pair", "Assembly", "VALIDATION_REL", "MAX_ARM_REL", "segment_intersections", "nesting_depths",
           "bounds_diagonal", "trusted", "BIASES", "check_bias"]

_VALIDATE = contextvars.ContextVar("cspace_validate_geometry", default=True)


@contextlib.contextmanager
def trusted():
    """Skip the whole-loop checks (closure, crossings, orientation) while building
    many small variants of geometry that was validated once at nominal.

    Segment checks (finite numbers, positive radius, non-zero length) still run.
    Used internally by the zone and defect computations; user input is always
    validated.
    """
    token = _VALIDATE.set(False)
    try:
        yield
    finally:
        _VALIDATE.reset(token)


#: Relative tolerance of construction-time validation (loop closure, zero length,
#: crossings), relative to the bounding-box diagonal.  1e-9 leaves six decimal
#: digits of head-room above double rounding of coordinates, yet is far below any
#: manufacturing tolerance.
VALIDATION_REL = 1e-9
#: Largest coordinate or radius magnitude (their squares and products must stay
#: finite in the contact equations).
MAX_COORD = 1e100
#: Farthest a rotating part's material may lie from its rotation centre, in
#: multiples of the part's own size (bounding-box diagonal).  A part at arm
#: length R turns by its own size s within s / R rad, so its contacts occupy a
#: q-range of that width, and rounding of the moved coordinates (R times 1e-16)
#: must stay far below the validation tolerance (1e-9 s): beyond 1e7 the
#: contact curves of the built-in pairs break up into rounding noise, beyond
#: about 1e15 the contact equations divide 0 by 0.  1e5 leaves a factor 100.
MAX_ARM_REL = 1e5
#: A lone segment's end points closer than this share of its coordinates are
#: equal to rounding (the loop compares lengths with its own size).
_ROUNDING_REL = 1e-13


def _fmt(p) -> str:
    return "(" + ", ".join(f"{float(v):.10g}" for v in p) + ")"


def _check_name(name) -> str:
    if not isinstance(name, str):
        raise InputError(f"segment name must be a str, got {type(name).__name__}",
                         name="name", value=name)
    return name


@dataclass(frozen=True)
class Line:
    """A directed line segment from ``start`` to ``end`` (model length units)."""

    start: tuple[float, float]
    end: tuple[float, float]
    name: str = ""

    def __post_init__(self):
        s = _coords(self.start, "Line.start")
        e = _coords(self.end, "Line.end")
        object.__setattr__(self, "start", s)
        object.__setattr__(self, "end", e)
        _check_name(self.name)
        # alone, a segment knows no size but its coordinates': it rejects only
        # end points equal to rounding; the loop checks lengths against its size
        scale = max(abs(s[0]), abs(s[1]), abs(e[0]), abs(e[1]), TINY)
        if math.hypot(e[0] - s[0], e[1] - s[1]) <= _ROUNDING_REL * scale:
            raise ZeroLengthSegmentError(
                f"line segment must have positive length; start {s} and end {e} coincide",
                where=self.name or None)

    kind = "line"

    @property
    def length(self) -> float:
        return math.hypot(self.end[0] - self.start[0], self.end[1] - self.start[1])

    @property
    def start_point(self) -> np.ndarray:
        return np.array(self.start)

    @property
    def end_point(self) -> np.ndarray:
        return np.array(self.end)

    @property
    def direction(self) -> np.ndarray:
        d = np.subtract(self.end, self.start)
        return d / np.hypot(*d)

    def start_tangent(self) -> np.ndarray:
        return self.direction

    def end_tangent(self) -> np.ndarray:
        return self.direction

    def sample(self, n: int) -> np.ndarray:
        t = np.linspace(0.0, 1.0, max(int(n), 2))[:, None]
        return (1 - t) * np.array(self.start) + t * np.array(self.end)

    def reversed(self) -> "Line":
        return Line(self.end, self.start, self.name)

    def bounds(self) -> tuple[float, float, float, float]:
        xs = (self.start[0], self.end[0])
        ys = (self.start[1], self.end[1])
        return min(xs), min(ys), max(xs), max(ys)

    def transformed(self, fn) -> "Line":
        return Line(tuple(fn(self.start)), tuple(fn(self.end)), self.name)

    def to_dict(self) -> dict:
        d = {"type": "line", "start": list(self.start), "end": list(self.end)}
        if self.name:
            d["name"] = self.name
        return d


#: How far (relative) an arc's angles may lie more than a turn apart: the
#: rounding of ``start + 2 pi`` only.
_TURN_SLACK = 1e-9


@dataclass(frozen=True)
class Arc:
    """A circular arc (model length units, angles in rad)."""

    center: tuple[float, float]
    radius: float
    start_angle: float
    end_angle: float
    ccw: bool = True
    name: str = ""

    def __post_init__(self):
        c = _coords(self.center, "Arc.center")
        object.__setattr__(self, "center", c)
        r = getscalar(self.radius, "Arc.radius")
        if abs(r) > MAX_COORD:
            raise InputError(f"Arc.radius must be at most {MAX_COORD:g} in magnitude, got {r:g}",
                             name="Arc.radius", value=r)
        if not r > 0:
            raise NonPositiveRadiusError(f"arc radius must be > 0, got {r}",
                                         where=self.name or None)
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "start_angle", getscalar(self.start_angle, "Arc.start_angle"))
        object.__setattr__(self, "end_angle", getscalar(self.end_angle, "Arc.end_angle"))
        gap = abs(self.end_angle - self.start_angle)
        turns = gap / TWO_PI
        if turns > 1 + _TURN_SLACK and abs(turns - round(turns)) > FULL_CIRCLE_SLACK * turns:
            # not a whole number of turns (a full circle, see sweep): a slip,
            # most often angles in degrees
            raise InputError(f"Arc angles must lie within a turn of each other, or whole "
                             f"turns apart (the sweep is in (0, 2 pi] rad; end_angle = "
                             f"start_angle + 2 pi is a full circle), got start_angle "
                             f"{self.start_angle:.6g} and end_angle {self.end_angle:.6g} rad, "
                             f"{gap:.6g} apart"
                             f"{degrees_hint(self.start_angle, self.end_angle)}",
                             name="Arc.end_angle", value=self.end_angle)
        if not isinstance(self.ccw, (bool, np.bool_)):
            raise InputError(f"Arc.ccw must be a bool, got {self.ccw!r}", name="ccw",
                             value=self.ccw)
        object.__setattr__(self, "ccw", bool(self.ccw))
        _check_name(self.name)
        if self.sweep * r <= _ROUNDING_REL * max(r, abs(c[0]), abs(c[1])):
            raise ZeroLengthSegmentError(
                f"arc must have positive length above rounding (sweep in (0, 2 pi], at "
                f"least {_ROUNDING_REL:g} of its coordinates' size along the arc; a full "
                f"circle is end_angle = start_angle + 2 pi); start_angle {self.start_angle} "
                f"and end_angle {self.end_angle} give a sweep of {self.sweep:.6g} rad",
                where=self.name or None)

    kind = "arc"

    @property
    def sweep(self) -> float:
        """Unsigned sweep in (0, 2 pi] (tiny or 0 only for a rejected degenerate arc).

        An angle difference that is a whole number of turns up to rounding is a
        full circle; a difference that is merely tiny (say 1e-15 rad) is a tiny
        arc, which the length check refuses, not a full circle.
        """
        d = (self.end_angle - self.start_angle) if self.ccw else (self.start_angle - self.end_angle)
        if d == 0.0:
            return 0.0
        s = d % TWO_PI
        if s <= FULL_CIRCLE_SLACK * TWO_PI * max(1.0, abs(d)):
            return TWO_PI if abs(d) > math.pi else abs(d)
        return s

    @property
    def signed_sweep(self) -> float:
        return self.sweep if self.ccw else -self.sweep

    @property
    def is_full_circle(self) -> bool:
        return abs(self.sweep - TWO_PI) <= ROUNDING

    @property
    def mid_angle(self) -> float:
        return self.start_angle + 0.5 * self.signed_sweep

    @property
    def length(self) -> float:
        return self.radius * self.sweep

    def point_at(self, angle) -> np.ndarray:
        a = np.asarray(angle, dtype=float)
        return np.stack([self.center[0] + self.radius * np.cos(a),
                         self.center[1] + self.radius * np.sin(a)], -1)

    @property
    def start_point(self) -> np.ndarray:
        return self._ends()[0].copy()

    @property
    def end_point(self) -> np.ndarray:
        return self._ends()[1].copy()

    def _ends(self) -> tuple:
        """The end points, kept on the arc (validation reads them again and
        again); the properties hand out copies."""
        got = self.__dict__.get("_end_points")
        if got is None:
            got = (self.point_at(self.start_angle),
                   self.point_at(self.start_angle + self.signed_sweep))
            self.__dict__["_end_points"] = got
        return got

    def _tangent(self, a: float) -> np.ndarray:
        t = np.array([-math.sin(a), math.cos(a)])
        return t if self.ccw else -t

    def start_tangent(self) -> np.ndarray:
        return self._tangent(self.start_angle)

    def end_tangent(self) -> np.ndarray:
        return self._tangent(self.start_angle + self.signed_sweep)

    def contains_angle(self, angle, tol: float = 0.0):
        """Whether directions ``angle`` (rad, array) lie on the arc (within ``tol`` rad)."""
        h = 0.5 * self.sweep
        return h - np.abs(wrap_pi(np.asarray(angle) - self.mid_angle)) >= -tol

    def sample(self, n: int) -> np.ndarray:
        t = np.linspace(0.0, 1.0, max(int(n), 2))
        return self.point_at(self.start_angle + t * self.signed_sweep)

    def reversed(self) -> "Arc":
        return Arc(self.center, self.radius, self.end_angle, self.start_angle, not self.ccw,
                   self.name)

    def bounds(self) -> tuple[float, float, float, float]:
        # kept on the arc (a frozen value): a part's validation reads each
        # segment's box several times (the loop's size, its crossing pairs,
        # the part's), and an arc's costs some fifty numpy calls
        got = self.__dict__.get("_bounds")
        if got is None:
            pts = [self.start_point, self.end_point]
            for k in range(4):
                a = k * math.pi / 2
                if self.contains_angle(a):
                    pts.append(self.point_at(a))
            pts = np.array(pts)
            got = (float(pts[:, 0].min()), float(pts[:, 1].min()),
                   float(pts[:, 0].max()), float(pts[:, 1].max()))
            self.__dict__["_bounds"] = got
        return got

    def to_dict(self) -> dict:
        d = {"type": "arc", "center": list(self.center), "radius": self.radius,
             "start_angle": self.start_angle, "end_angle": self.end_angle, "ccw": self.ccw}
        if self.name:
            d["name"] = self.name
        return d


Segment = Union[Line, Arc]


def bounds_diagonal(boxes) -> float:
    """Diagonal of the box that holds bounding boxes ``boxes`` (rows xmin, ymin,
    xmax, ymax): the size of a drawing, against which tolerances are relative."""
    b = np.asarray(boxes, dtype=float).reshape(-1, 4)
    return float(math.hypot(b[:, 2].max() - b[:, 0].min(), b[:, 3].max() - b[:, 1].min()))


def bounds_of(segs) -> tuple:
    """(xmin, ymin, xmax, ymax) of segments' bounding boxes."""
    b = np.array([sg.bounds() for sg in segs], dtype=float).reshape(-1, 4)
    return (float(b[:, 0].min()), float(b[:, 1].min()), float(b[:, 2].max()),
            float(b[:, 3].max()))


def _seg_bounds_diag(segs) -> float:
    return bounds_diagonal([s.bounds() for s in segs])


#: Up to this many segments, the candidate pairs of the intersection checks come
#: from one array comparison; beyond it from an R-tree.  Both give every pair
#: whose grown bounding boxes meet, so validation costs O(n log n) for drawings
#: whose segments do not pile up on one another.
_BOX_PAIRS_DENSE = 400


def _box_pairs(segs, pad: float) -> list:
    """Index pairs (i, j), i < j, in increasing order, of the segments whose
    bounding boxes, each grown by ``pad``, meet."""
    b = np.array([s.bounds() for s in segs], dtype=float).reshape(-1, 4)
    lo, hi = b[:, :2] - pad, b[:, 2:] + pad
    if len(b) <= _BOX_PAIRS_DENSE:
        meet = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]),
                      axis=2)
        i, j = np.nonzero(np.triu(meet, 1))
    else:
        import shapely
        boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
        i, j = shapely.STRtree(boxes).query(boxes)
        keep = i < j
        i, j = i[keep], j[keep]
        order = np.lexsort((j, i))
        i, j = i[order], j[order]
    return list(zip(i.tolist(), j.tolist()))


def nesting_depths(loops) -> list:
    """How many of the other ``loops`` contain the first point of each loop.

    A loop is asked only when the point is not right of, above or below its
    bounding box (grown by far more than rounding), where the +x ray test cannot
    count a crossing; the answer is that of asking every loop.
    """
    b = np.array([lp.bounds() for lp in loops], dtype=float).reshape(-1, 4)
    pad = SLACK * max(float(np.abs(b).max()), bounds_diagonal(b))
    out = []
    for i, lp in enumerate(loops):
        x, y = (float(v) for v in lp.segments[0].start_point)
        ask = (x <= b[:, 2] + pad) & (y >= b[:, 1] - pad) & (y <= b[:, 3] + pad)
        ask[i] = False
        out.append(sum(1 for j in np.flatnonzero(ask) if loops[j].contains((x, y))))
    return out


# --- exact segment intersection (scalar; used by validation) -------------------------

def _line_line(a: Line, b: Line, tol: float):
    p, r = np.array(a.start), np.subtract(a.end, a.start)
    q, s = np.array(b.start), np.subtract(b.end, b.start)
    t, u, rxs = line_line(p, r, q, s)
    if abs(rxs) <= PARALLEL_REL * np.dot(r, r) ** 0.5 * np.dot(s, s) ** 0.5:
        # parallel: collinear overlap?
        qp = q - p
        if abs(qp[0] * r[1] - qp[1] * r[0]) > tol * np.hypot(*r):
            return []
        rr = np.dot(r, r)
        t0 = np.dot(qp, r) / rr
        t1 = t0 + np.dot(s, r) / rr
        lo, hi = max(0.0, min(t0, t1)), min(1.0, max(t0, t1))
        if hi < lo:
            return []
        return [p + lo * r, p + hi * r]
    el = tol / np.hypot(*r)
    es = tol / np.hypot(*s)
    if -el <= t <= 1 + el and -es <= u <= 1 + es:
        return [p + t * r]
    return []


def _on_arc(arc: Arc, pts, tol: float):
    out = []
    for p in pts:
        ang = math.atan2(p[1] - arc.center[1], p[0] - arc.center[0])
        if arc.contains_angle(ang, tol / arc.radius):
            out.append(np.asarray(p))
    return out


def _line_arc(a: Line, b: Arc, tol: float):
    p = np.array(a.start)
    d = np.subtract(a.end, a.start)
    A, B, disc = (float(x) for x in line_circle_quadratic(p, d, b.center, b.radius))
    L = math.sqrt(A)
    if disc < -4 * A * (2 * b.radius * tol):
        return []
    sq = math.sqrt(max(disc, 0.0))
    ts = {(-B - sq) / (2 * A), (-B + sq) / (2 * A)}
    pts = [p + t * d for t in ts if -tol / L <= t <= 1 + tol / L]
    return _on_arc(b, pts, tol)


def _arc_arc(a: Arc, b: Arc, tol: float):
    dist = math.hypot(*np.subtract(b.center, a.center))
    if dist <= tol and abs(a.radius - b.radius) <= tol:
        # same circle: overlapping arcs?
        pts = [q for q in (a.start_point, a.end_point) if _on_arc(b, [q], tol)]
        pts += [q for q in (b.start_point, b.end_point) if _on_arc(a, [q], tol)]
        if not pts:
            mid = a.point_at(a.mid_angle)
            if _on_arc(b, [mid], tol):
                pts = [mid]
        return pts
    if dist <= tol:
        return []
    base, n, h2 = radical_foot(a.center, a.radius, b.center, b.radius)
    if h2 < -2 * a.radius * tol:
        return []
    h = math.sqrt(max(float(h2), 0.0))
    pts = [base + h * n] if h == 0 else [base + h * n, base - h * n]
    return _on_arc(b, _on_arc(a, pts, tol), tol)


def segment_intersections(a: Segment, b: Segment, tol: float = 0.0) -> list:
    """Points where two segments meet (within ``tol``).  Collinear or co-circular
    overlaps return the overlap's end points."""
    if isinstance(a, Line) and isinstance(b, Line):
        return _line_line(a, b, tol)
    if isinstance(a, Line):
        return _line_arc(a, b, tol)
    if isinstance(b, Line):
        return _line_arc(b, a, tol)
    return _arc_arc(a, b, tol)


def _coords(x, name: str) -> tuple:
    """A finite point whose coordinates are at most MAX_COORD in magnitude."""
    p = getpoint(x, name)
    if max(abs(p[0]), abs(p[1])) > MAX_COORD:
        raise InputError(f"{name} coordinates must be at most {MAX_COORD:g} in magnitude, got "
                         f"({p[0]:g}, {p[1]:g})", name=name, value=p)
    return p


def _signed_area(segs) -> float:
    """Signed area enclosed by a closed chain of lines and arcs (shoelace plus the
    circular segments of arcs)."""
    area = 0.0
    for s in segs:
        p, q = s.start_point, s.end_point
        area += 0.5 * (p[0] * q[1] - q[0] * p[1])
        if isinstance(s, Arc):
            th = s.sweep
            seg_area = 0.5 * s.radius ** 2 * (th - math.sin(th))
            area += seg_area if s.ccw else -seg_area
    return area


def _point_in_loop(pt, segs) -> bool:
    """Even-odd ray test (ray towards +x) against one closed chain."""
    x, y = float(pt[0]), float(pt[1])
    crossings = 0
    for s in segs:
        if isinstance(s, Line):
            (x0, y0), (x1, y1) = s.start, s.end
            if (y0 > y) != (y1 > y):
                xi = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
                if xi > x:
                    crossings += 1
        else:
            cx, cy = s.center
            dy = y - cy
            if abs(dy) >= s.radius:
                continue
            dx = math.sqrt(s.radius ** 2 - dy * dy)
            for xi in (cx - dx, cx + dx):
                if xi > x and s.contains_angle(math.atan2(dy, xi - cx)):
                    # half-open rule at arc end points: count the end whose other
                    # side is above the ray consistently with lines
                    crossings += 1
    return crossings % 2 == 1


@dataclass(frozen=True)
class Loop:
    """A closed chain of segments; material to the left of travel.

    Raises
    ------
    OpenLoopError, SelfIntersectionError, ZeroLengthSegmentError
    """

    segments: tuple
    name: str = ""

    def __post_init__(self):
        segs = self.segments
        if isinstance(segs, (Line, Arc)):
            segs = (segs,)
        try:
            segs = tuple(segs)
        except TypeError:
            raise InputError(f"Loop.segments must be a sequence of Line/Arc, got "
                             f"{type(self.segments).__name__}") from None
        if not segs:
            raise OpenLoopError("a loop needs at least one segment, got none")
        for i, s in enumerate(segs):
            if not isinstance(s, (Line, Arc)):
                raise InputError(f"Loop.segments[{i}] must be a Line or Arc, got "
                                 f"{type(s).__name__}")
        object.__setattr__(self, "segments", segs)
        _check_name(self.name)
        if not _VALIDATE.get():
            return
        scale = max(_seg_bounds_diag(segs), TINY)
        tol = VALIDATION_REL * 100 * scale
        n = len(segs)
        for i, sg in enumerate(segs):
            if sg.length <= VALIDATION_REL * scale:
                raise ZeroLengthSegmentError(
                    f"segment {i} ({sg.kind}) has length {sg.length:.3g}, not more than "
                    f"{VALIDATION_REL:g} of the loop size {scale:.6g}; segments must have "
                    f"positive length", where=self.name or None)
        for i in range(n):
            e = segs[i].end_point
            s = segs[(i + 1) % n].start_point
            gap = float(np.hypot(*(e - s)))
            if gap > tol:
                what = ("the loop does not close" if i == n - 1
                        else f"segment {i} does not meet segment {i + 1}")
                raise OpenLoopError(
                    f"{what}: end {_fmt(e)} vs start {_fmt(s)}, "
                    f"gap {gap:.3g} > allowed {tol:.3g} (1e-7 of loop size)",
                    where=self.name or None)
        if n == 1 and isinstance(segs[0], Line):
            raise OpenLoopError("a single line cannot form a closed loop")
        # crossings: non-adjacent segments must not meet; adjacent ones only at
        # their shared end point.
        itol = VALIDATION_REL * scale
        for i, j in _box_pairs(segs, 10 * itol):
            pts = segment_intersections(segs[i], segs[j], itol)
            if not pts:
                continue
            shared = []
            if j == i + 1:
                shared.append(segs[i].end_point)
            if i == 0 and j == n - 1:
                shared.append(segs[0].start_point)
            bad = [p for p in pts
                   if all(np.hypot(*(p - q)) > tol * 10 for q in shared)]
            if bad:
                raise SelfIntersectionError(
                    f"loop crosses itself: segment {i} ({segs[i].kind}) meets segment "
                    f"{j} ({segs[j].kind}) at {_fmt(bad[0])}; loops must "
                    "be simple", where=self.name or None)
        if abs(self.area) <= VALIDATION_REL * scale ** 2:
            raise DegenerateGeometryError("loop encloses zero area", where=self.name or None)

    @property
    def area(self) -> float:
        """Signed area: > 0 for a counter-clockwise (outer) loop."""
        return _signed_area(self.segments)

    @property
    def is_ccw(self) -> bool:
        return self.area > 0

    def contains(self, pt) -> bool:
        return _point_in_loop(pt, self.segments)

    def reversed(self) -> "Loop":
        return Loop(tuple(s.reversed() for s in reversed(self.segments)), self.name)

    def bounds(self):
        b = np.array([s.bounds() for s in self.segments])
        return float(b[:, 0].min()), float(b[:, 1].min()), float(b[:, 2].max()), float(b[:, 3].max())

    def sample(self, per_arc: int = 64) -> np.ndarray:
        """Closed polyline through the loop (arcs with ``per_arc`` points per full turn)."""
        pts = []
        for s in self.segments:
            if isinstance(s, Line):
                pts.append(np.array([s.start]))
            else:
                n = max(2, int(math.ceil(per_arc * s.sweep / TWO_PI)) + 1)
                pts.append(s.sample(n)[:-1])
        return np.vstack(pts)

    def to_list(self) -> list:
        return [s.to_dict() for s in self.segments]

    @staticmethod
    def from_bulges(points, bulges=None, names=None) -> "Loop":
        """A closed loop through ``points`` whose edge i (from point i to point i+1)
        is a line for bulge 0 or an arc otherwise (bulge = tan(sweep / 4), positive
        counter-clockwise), as in DXF polylines.
        """
        pts = [_coords(p, f"points[{i}]") for i, p in enumerate(points)]
        n = len(pts)
        if n < 2:
            raise OpenLoopError(f"a polyline loop needs at least 2 points, got {n}")
        bl = [0.0] * n if bulges is None else [getscalar(b, "bulge") for b in bulges]
        if len(bl) != n:
            raise InputError(f"need one bulge per edge ({n}), got {len(bl)}")
        nm = [""] * n if names is None else list(names)
        if len(nm) != n:
            raise InputError(f"need one name per edge ({n}: edge i runs from point i to point "
                             f"i + 1, the last back to the first), got {len(nm)}: {nm}"[:300],
                             name="names")
        segs = []
        for i in range(n):
            p, q = np.array(pts[i]), np.array(pts[(i + 1) % n])
            b = bl[i]
            if b == 0.0:
                segs.append(Line(tuple(p), tuple(q), nm[i]))
                continue
            theta = 4.0 * math.atan(b)
            chord = q - p
            c = float(np.hypot(*chord))
            if c == 0.0:
                raise ZeroLengthSegmentError(f"edge {i} has coincident end points {tuple(p)}")
            if 0.5 * abs(b) * c <= _ROUNDING_REL * max(c, *np.abs(p), *np.abs(q)):
                # a sagitta at rounding level (say bulge 5e-324): a straight edge,
                # not an arc whose centre lies at infinity (inf * 0 = NaN)
                segs.append(Line(tuple(p), tuple(q), nm[i]))
                continue
            r = c / (2.0 * math.sin(abs(theta) / 2.0))
            left = np.array([-chord[1], chord[0]]) / c
            d = (c / 2.0) / math.tan(theta / 2.0)
            center = 0.5 * (p + q) + left * d
            a0 = math.atan2(p[1] - center[1], p[0] - center[0])
            a1 = math.atan2(q[1] - center[1], q[0] - center[0])
            segs.append(Arc((float(center[0]), float(center[1])), r, a0, a1, b > 0, nm[i]))
        return Loop(tuple(segs))


@dataclass(frozen=True)
class Rotation:
    """Rotation about a fixed ``center`` (q in rad, counter-clockwise positive)."""

    center: tuple[float, float] = (0.0, 0.0)
    kind = "rotation"

    def __post_init__(self):
        object.__setattr__(self, "center", _coords(self.center, "Rotation.center"))

    @property
    def periodic(self) -> bool:
        return True

    def to_dict(self) -> dict:
        return {"type": "rotation", "center": list(self.center)}


@dataclass(frozen=True)
class Translation:
    """Translation along a fixed unit ``direction`` (q in model length units).

    ``origin`` marks the reference point of the slide (for drawings only).
    """

    direction: tuple[float, float] = (1.0, 0.0)
    origin: tuple[float, float] = (0.0, 0.0)
    kind = "translation"

    def __post_init__(self):
        d = getpoint(self.direction, "Translation.direction")
        n = math.hypot(*d)
        if n <= ROUNDING:
            raise ZeroDirectionError(
                f"translation direction must be a non-zero vector, got {d}")
        if abs(n - 1.0) > ROUNDING:
            d = (d[0] / n, d[1] / n)
        object.__setattr__(self, "direction", d)
        object.__setattr__(self, "origin", _coords(self.origin, "Translation.origin"))

    @property
    def periodic(self) -> bool:
        return False

    def to_dict(self) -> dict:
        return {"type": "translation", "direction": list(self.direction),
                "origin": list(self.origin)}


Axis = Union[Rotation, Translation]


def place_points(axis, q, pts) -> np.ndarray:
    """World positions of body points ``pts`` (..., 2) when the part is at
    coordinate(s) ``q`` (broadcast against the leading axes): (..., 2)."""
    q = np.asarray(q, dtype=float)
    pts = np.asarray(pts, dtype=float)
    if isinstance(axis, Rotation):
        c = np.asarray(axis.center)
        cq, sq = np.cos(q), np.sin(q)
        x, y = pts[..., 0] - c[0], pts[..., 1] - c[1]
        return np.stack([c[0] + cq * x - sq * y, c[1] + sq * x + cq * y], -1)
    e = np.asarray(axis.direction)
    return np.stack([pts[..., 0] + q * e[0], pts[..., 1] + q * e[1]], -1)


@dataclass(frozen=True)
class Part:
    """A rigid part: disjoint (or nested) profile loops plus a motion axis.

    Raises
    ------
    OrientationError
        A loop's orientation does not match its nesting (outer loops CCW, holes CW).
    SelfIntersectionError
        Two loops cross.
    """

    name: str
    loops: tuple
    axis: Axis = field(default_factory=Rotation)

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"Part.name must be a non-empty str, got {self.name!r}")
        loops = self.loops
        if isinstance(loops, Loop):
            loops = (loops,)
        loops = tuple(loops)
        if not loops:
            raise InputError(f"part {self.name!r} needs at least one loop")
        for i, lp in enumerate(loops):
            if not isinstance(lp, Loop):
                raise InputError(f"part {self.name!r}: loops[{i}] must be a Loop, got "
                                 f"{type(lp).__name__}")
        if not isinstance(self.axis, (Rotation, Translation)):
            raise InputError(f"part {self.name!r}: axis must be Rotation or Translation, got "
                             f"{type(self.axis).__name__}")
        object.__setattr__(self, "loops", loops)
        if not _VALIDATE.get():
            return
        allsegs = [s for lp in loops for s in lp.segments]
        scale = max(_seg_bounds_diag(allsegs), TINY)
        itol = VALIDATION_REL * scale
        which = [i for i, lp in enumerate(loops) for _ in lp.segments]
        cross = sorted((which[a], which[b], a, b) for a, b in _box_pairs(allsegs, 10 * itol)
                       if which[a] != which[b])          # a < b, so which[a] < which[b]
        for i, j, a, b in cross:
            pts = segment_intersections(allsegs[a], allsegs[b], itol)
            if pts:
                raise SelfIntersectionError(
                    f"part {self.name!r}: loop {i} and loop {j} meet at "
                    f"{_fmt(pts[0])}; loops of a part must be "
                    "disjoint", where=self.name)
        if isinstance(self.axis, Rotation):
            x0, y0, x1, y1 = bounds_of(allsegs)
            cx, cy = self.axis.center
            arm = math.hypot(max(abs(x0 - cx), abs(x1 - cx)), max(abs(y0 - cy), abs(y1 - cy)))
            if not arm <= MAX_ARM_REL * scale:
                raise InputError(
                    f"part {self.name!r}: its material reaches {arm:.6g} from its rotation "
                    f"centre {_fmt(self.axis.center)}, {arm / scale:.3g} times its own size "
                    f"{scale:.6g}; at most {MAX_ARM_REL:g} times is allowed (farther, double "
                    f"precision cannot resolve its contacts)", name="axis.center",
                    value=self.axis.center)
        for i, (lp, depth) in enumerate(zip(loops, nesting_depths(loops))):
            want_ccw = depth % 2 == 0
            if lp.is_ccw != want_ccw:
                role = "an outer boundary" if want_ccw else "a hole"
                raise OrientationError(
                    f"part {self.name!r}: loop {i} is {role} (nesting depth {depth}) and must "
                    f"run {'counter-clockwise' if want_ccw else 'clockwise'}, but runs "
                    f"{'counter-clockwise' if lp.is_ccw else 'clockwise'} (material lies left "
                    "of travel)", where=self.name)

    def contains(self, pt) -> bool:
        """Whether ``pt`` (at q = 0) lies in the part's material."""
        return sum(lp.contains(pt) for lp in self.loops) % 2 == 1

    def bounds(self):
        b = np.array([lp.bounds() for lp in self.loops])
        return float(b[:, 0].min()), float(b[:, 1].min()), float(b[:, 2].max()), float(b[:, 3].max())

    @property
    def size(self) -> float:
        x0, y0, x1, y1 = self.bounds()
        return math.hypot(x1 - x0, y1 - y0)

    def reach(self) -> float:
        """Largest distance of the profile from the rotation centre (rotating part) or
        the bounding-box diagonal (translating part)."""
        if isinstance(self.axis, Rotation):
            # numpy's hypot, cos and sin on arrays of every point at once (the
            # numbers of those functions on each value alone, elementwise, as
            # this took them one at a time; a pair's characteristic length is
            # read for every variant a batch builds): line ends; an arc's
            # farthest circle point when the arc holds it, else its ends
            cx, cy = (float(v) for v in self.axis.center)
            lx, ly, arcs = [], [], []
            for lp in self.loops:
                for s in lp.segments:
                    if isinstance(s, Line):
                        (ax, ay), (bx, by) = s.start, s.end
                        lx += (float(ax) - cx, float(bx) - cx)
                        ly += (float(ay) - cy, float(by) - cy)
                    else:
                        arcs.append(s)
            r = float(np.max(np.hypot(lx, ly))) if lx else 0.0
            if not arcs:
                return r
            vx = np.array([float(a.center[0]) - cx for a in arcs])
            vy = np.array([float(a.center[1]) - cy for a in arcs])
            d = np.hypot(vx, vy)
            # the farthest circle point from c (the C library's atan2, as before)
            far = np.array([math.atan2(y, x) for x, y in zip(vx.tolist(), vy.tolist())])
            half = np.array([0.5 * a.sweep for a in arcs])
            mid = np.array([a.mid_angle for a in arcs])
            held = (d == 0.0) | (half - np.abs(wrap_pi(far - mid)) >= 0.0)
            rad = np.array([a.radius for a in arcs])
            if held.any():
                r = max(r, float(np.max(d[held] + rad[held])))
            if not held.all():
                ends = [(a.start_angle, a.start_angle + a.signed_sweep)
                        for a, h in zip(arcs, held) if not h]
                ang = np.array(ends)
                ccx = np.array([float(a.center[0]) for a, h in zip(arcs, held) if not h])[:, None]
                ccy = np.array([float(a.center[1]) for a, h in zip(arcs, held) if not h])[:, None]
                rr = rad[~held][:, None]
                px = ccx + rr * np.cos(ang)
                py = ccy + rr * np.sin(ang)
                r = max(r, float(np.max(np.hypot(px - cx, py - cy))))
            return float(r)
        return self.size

    def to_dict(self) -> dict:
        return {"name": self.name, "axis": self.axis.to_dict(),
                "loops": [lp.to_list() for lp in self.loops]}


#: The closures a follower may have (:attr:`Pair.bias`): 0 form closure (pushed
#: only), -1 and +1 force closure toward decreasing and increasing q2.
BIASES = (-1, 0, 1)


def check_bias(v, name: str = "bias") -> int:
    """A follower bias (:attr:`Pair.bias`): one of -1, 0, +1 as an int.

    Raises
    ------
    InputError
        ``v`` is not one of those numbers (a bool, a string, 0.5, NaN...).
    """
    ok = (not isinstance(v, (bool, np.bool_)) and isinstance(v, (int, float, np.integer,
                                                                   np.floating))
          and v in BIASES)
    if not ok:
        raise InputError(f"{name} must be -1 (follower held toward decreasing q2), 0 (form "
                         f"closure: moved only when pushed) or +1 (held toward increasing "
                         f"q2), got {v!r}", name=name, value=v)
    return int(v)


@dataclass(frozen=True)
class Pair:
    """Two parts that touch: a ``driver`` (coordinate q1) and a ``follower`` (q2).

    Attributes
    ----------
    driver, follower : Part
    units : str
        Length unit of the model (e.g. ``"cm"``); stated in every file and report.
    name : str
    bias : {0, -1, 1}
        How the follower is held against the driver (its closure):

        * ``0``, form closure (the default): the follower moves only when the
          driver pushes it and otherwise stays where it is;
        * ``-1`` or ``+1``, force closure (spring-loaded, or held by gravity):
          the follower is pushed toward decreasing (-1) or increasing (+1) q2,
          so it rests on that side's bound of its free interval at every
          driver position and rises and falls with the driver
          (:func:`cspace.simulate.simulate`).
    """

    driver: Part
    follower: Part
    units: str = "mm"
    name: str = "pair"
    bias: int = 0

    def __post_init__(self):
        for role in ("driver", "follower"):
            if not isinstance(getattr(self, role), Part):
                raise InputError(f"Pair.{role} must be a Part, got "
                                 f"{type(getattr(self, role)).__name__}")
        if not isinstance(self.units, str) or not self.units:
            raise InputError(f"Pair.units must be a non-empty str such as 'mm', got {self.units!r}")
        object.__setattr__(self, "bias", check_bias(self.bias, "Pair.bias"))

    @property
    def parts(self) -> tuple[Part, Part]:
        return (self.driver, self.follower)

    @functools.cached_property
    def char_length(self) -> float:
        """Characteristic length L of the C-space metric: a slide of L counts as 1 rad.

        The largest reach of a rotating part about its centre; for two translating
        parts, the larger part size.
        """
        rs = [p.reach() for p in self.parts if isinstance(p.axis, Rotation)]
        if rs:
            return max(rs)
        return max(p.size for p in self.parts)

    @property
    def size(self) -> float:
        x0 = min(p.bounds()[0] for p in self.parts)
        y0 = min(p.bounds()[1] for p in self.parts)
        x1 = max(p.bounds()[2] for p in self.parts)
        y1 = max(p.bounds()[3] for p in self.parts)
        return math.hypot(x1 - x0, y1 - y0)

    def to_dict(self) -> dict:
        d = {"format": "cspace-pair", "version": 1, "name": self.name, "units": self.units,
             "parts": [self.driver.to_dict(), self.follower.to_dict()]}
        if self.bias:
            d["closure"] = {"bias": self.bias}
        return d


@dataclass(frozen=True)
class Assembly:
    """Several pairs driven by one driver axis (e.g. three cams on one shaft).

    Every pair's driver must have the same axis.  Each pair keeps its own follower.
    """

    pairs: tuple
    name: str = "assembly"

    def __post_init__(self):
        pairs = tuple(self.pairs)
        if not pairs or not all(isinstance(p, Pair) for p in pairs):
            raise InputError("Assembly.pairs must be a non-empty sequence of Pair")
        ax = pairs[0].driver.axis
        for i, p in enumerate(pairs[1:], 1):
            if p.driver.axis != ax:
                raise InputError(f"Assembly pair {i}: driver axis {p.driver.axis} differs "
                                 f"from pair 0's {ax}; all drivers must share one axis")
        object.__setattr__(self, "pairs", pairs)

    @property
    def units(self) -> str:
        return self.pairs[0].units
