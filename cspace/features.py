"""The features of a part: its vertices, lines and arcs, with their free sides.

Every contact of two parts is a contact of one feature of each
(:mod:`cspace.equations`).  A vertex carries its two edge directions (its
material cone), a line its end points, an arc its centre, radius, angular range
and convexity; :func:`features` lists them per part, keyed by loop and segment.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .geom2d import wrap_pi
from .geometry import Arc, Line, Part

__all__ = ["Feature", "features", "feature_by_key", "feature_rows"]


#: Two segments meeting with a turn (cross product of their unit tangents)
#: within this of zero continue each other: no vertex between them, unless
#: they fold back.
STRAIGHT = 1e-9


@dataclass(frozen=True)
class Feature:
    """A contact feature of a part, in world coordinates at q = 0.

    Attributes
    ----------
    part : int
        0 for the driver, 1 for the follower.
    kind : {"vertex", "line", "arc"}
    key : tuple
        ``(part, loop, segment)``; a vertex has the key of the segment it starts.
    name : str
        Readable label, e.g. ``"slot1.left"`` or ``"pin"``; built from segment names.
    p, q : (2,) tuple
        Vertex point / line start and end / arc centre (q unused).
    radius : float
        Arc radius (0 otherwise).
    convex : bool
        Arc with material on the centre side.
    mid, half : float
        Arc mid angle and half sweep (rad).
    e1, e2 : (2,) tuple
        Vertex only: unit directions of the two edges leaving the vertex.
    segs : tuple
        Keys of the segments this feature is made of (for dependency tracking).
    """

    part: int
    kind: str
    key: tuple
    name: str
    p: tuple
    q: tuple = (0.0, 0.0)
    radius: float = 0.0
    convex: bool = True
    mid: float = 0.0
    half: float = math.pi
    e1: tuple = (0.0, 0.0)
    e2: tuple = (0.0, 0.0)
    segs: tuple = ()


def _seg_name(part: Part, li: int, si: int) -> str:
    s = part.loops[li].segments[si]
    return s.name or f"L{li}S{si}"


def _segment_features(part: Part, index: int, li: int, si: int) -> list[Feature]:
    """The features a segment contributes: itself, and the vertex at its start when
    that vertex is convex."""
    segs = part.loops[li].segments
    s = segs[si]
    nm = _seg_name(part, li, si)
    if isinstance(s, Line):
        out = [Feature(index, "line", (index, li, si), nm, s.start, s.end,
                       segs=((index, li, si),))]
    else:
        out = [Feature(index, "arc", (index, li, si), nm, s.center, radius=s.radius,
                       convex=s.ccw, mid=float(s.mid_angle), half=0.5 * s.sweep,
                       segs=((index, li, si),))]
    vx = _convex_vertex(segs, si)
    if vx is not None:
        pv, t_in, t_out = vx
        n = len(segs)
        pname = _seg_name(part, li, (si - 1) % n)
        out.append(Feature(index, "vertex", (index, li, si), f"{pname}^{nm}",
                           (float(pv[0]), float(pv[1])),
                           e1=(float(-t_in[0]), float(-t_in[1])),
                           e2=(float(t_out[0]), float(t_out[1])),
                           segs=((index, li, (si - 1) % n), (index, li, si))))
    return out


def _convex_vertex(segs, si: int):
    """``(point, incoming tangent, outgoing tangent)`` of the vertex at the start
    of segment ``si`` of a loop when it is convex (a feature), else None."""
    n = len(segs)
    s = segs[si]
    t_in = segs[(si - 1) % n].end_tangent()
    t_out = s.start_tangent()
    return (s.start_point, t_in, t_out) if _convex(t_in, t_out, n, s) else None


def _convex(t_in, t_out, n: int, s) -> bool:
    """Whether the vertex where tangent ``t_in`` turns into ``t_out`` at the
    start of segment ``s`` of a loop of ``n`` segments is convex: it turns
    left, or reverses (a cusp); a lone full circle has no vertex."""
    turn = t_in[0] * t_out[1] - t_in[1] * t_out[0]
    return (n > 1 or not isinstance(s, Arc)) and (
        turn > STRAIGHT or (abs(turn) <= STRAIGHT
                            and t_in[0] * t_out[0] + t_in[1] * t_out[1] < 0))


def _tangents(s):
    """``(start tangent, end tangent)`` of a segment as float pairs, the
    numbers of :meth:`~cspace.geometry.Line.start_tangent` and
    :meth:`~cspace.geometry.Arc.end_tangent` (the same operations on the same
    operands, numpy's ``hypot`` among them) without their arrays."""
    if isinstance(s, Line):
        dx, dy = s.end[0] - s.start[0], s.end[1] - s.start[1]
        h = np.hypot(dx, dy)
        t = (dx / h, dy / h)
        return t, t
    a0, a1 = s.start_angle, s.start_angle + s.signed_sweep
    t0, t1 = (-math.sin(a0), math.cos(a0)), (-math.sin(a1), math.cos(a1))
    if not s.ccw:
        t0, t1 = (-t0[0], -t0[1]), (-t1[0], -t1[1])
    return t0, t1


def feature_rows(part: Part, index: int) -> list:
    """The numbers of :func:`features` without the :class:`Feature` objects:
    ``[((part, loop, seg, kind), row), ...]`` in the same order, each row the 13
    fields of a :class:`cspace.batch.kernels.FeatureTable` row (point p, point
    q, radius, convex, mid, half, e1, e2, kind code), the same values.  What a
    batch reads of every variant, at less cost."""
    out = []
    for li, lp in enumerate(part.loops):
        segs = lp.segments
        tan = [_tangents(s) for s in segs]
        n = len(segs)
        for si, s in enumerate(segs):
            if isinstance(s, Line):
                a, b = s.start, s.end
                out.append(((index, li, si, "line"),
                            (a[0], a[1], b[0], b[1], 0.0, 1.0, 0.0, math.pi,
                             0.0, 0.0, 0.0, 0.0, 1.0)))
            else:
                c = s.center
                out.append(((index, li, si, "arc"),
                            (c[0], c[1], 0.0, 0.0, s.radius, 1.0 if s.ccw else 0.0,
                             float(s.mid_angle), 0.5 * s.sweep, 0.0, 0.0, 0.0, 0.0, 2.0)))
            # _convex_vertex on the tangents worked out once per segment
            t_in, t_out = tan[(si - 1) % n][1], tan[si][0]
            if _convex(t_in, t_out, n, s):
                pv = s.start_point
                out.append(((index, li, si, "vertex"),
                            (float(pv[0]), float(pv[1]), 0.0, 0.0, 0.0, 1.0, 0.0, math.pi,
                             float(-t_in[0]), float(-t_in[1]), float(t_out[0]),
                             float(t_out[1]), 0.0)))
    return out


def features(part: Part, index: int) -> list[Feature]:
    """The contact features of a part: every line, every arc, and every convex vertex.

    Vertices where the boundary is tangent-continuous or turns right (reflex) are
    not features: the adjacent edges govern contact there.
    """
    out = []
    for li, lp in enumerate(part.loops):
        for si in range(len(lp.segments)):
            out += _segment_features(part, index, li, si)
    return out


def feature_by_key(part: Part, key) -> Feature | None:
    """The feature ``(part, loop, seg, kind)`` of a part, or None if it is not one
    (e.g. a vertex that is no longer convex in a variant)."""
    index, li, si, kind = key
    try:
        cands = _segment_features(part, index, li, si)
    except IndexError:
        return None
    for f in cands:
        if f.kind == kind:
            return f
    return None


def free_normal(f: Feature) -> np.ndarray:
    """Unit free-side normal of a line feature (material lies to the left);
    read-only (shared between calls)."""
    return _normal_of(tuple(f.p), tuple(f.q))


@functools.lru_cache(maxsize=8192)
def _normal_of(p, q) -> np.ndarray:
    d = np.subtract(q, p)
    d = d / np.hypot(*d)
    n = np.array([d[1], -d[0]])
    n.setflags(write=False)
    return n


def radial_range(f: Feature, c) -> tuple[float, float]:
    """Range of distances from point c over the feature's points."""
    c = np.asarray(c, dtype=float)
    if f.kind == "vertex":
        d = float(np.hypot(*(np.array(f.p) - c)))
        return d, d
    if f.kind == "line":
        a, b = np.array(f.p), np.array(f.q)
        ab = b - a
        t = np.clip(np.dot(c - a, ab) / np.dot(ab, ab), 0, 1)
        dmin = float(np.hypot(*(a + t * ab - c)))
        return dmin, float(max(np.hypot(*(a - c)), np.hypot(*(b - c))))
    cc = np.array(f.p)
    dc = float(np.hypot(*(cc - c)))
    ang = math.atan2(c[1] - cc[1], c[0] - cc[0])
    pts = [cc + f.radius * np.array([math.cos(f.mid + s * f.half), math.sin(f.mid + s * f.half)])
           for s in (-1, 1)]
    ds = [float(np.hypot(*(p - c))) for p in pts]
    lo, hi = min(ds), max(ds)
    if abs(wrap_pi(ang - f.mid)) <= f.half:
        lo = min(lo, abs(dc - f.radius))
    if abs(wrap_pi(ang + math.pi - f.mid)) <= f.half:
        hi = max(hi, dc + f.radius)
    return lo, hi


def projection_range(f: Feature, u) -> tuple[float, float]:
    """Range of the projection of the feature's points on direction u."""
    u = np.asarray(u, dtype=float)
    if f.kind == "vertex":
        v = float(np.dot(f.p, u))
        return v, v
    if f.kind == "line":
        a, b = float(np.dot(f.p, u)), float(np.dot(f.q, u))
        return min(a, b), max(a, b)
    c = float(np.dot(f.p, u))
    ang = math.atan2(u[1], u[0])
    vals = [c + f.radius * math.cos(f.mid + s * f.half - ang) for s in (-1, 1)]
    lo, hi = min(vals), max(vals)
    if abs(wrap_pi(ang - f.mid)) <= f.half:
        hi = c + f.radius
    if abs(wrap_pi(ang + math.pi - f.mid)) <= f.half:
        lo = c - f.radius
    return lo, hi
