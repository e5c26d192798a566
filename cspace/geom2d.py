"""Shared 2-D geometry: rotations, rigid transforms, angle wrapping, and
circle/line intersections with explicit branch handling.

All functions are vectorised over leading array dimensions and return finite
numbers: a missing intersection is reported by an :class:`IntersectionKind` array,
never by NaN.  The mechanism modules (four-bar, manipulators) build on these so
that branch conventions are the same everywhere.

Branch convention
-----------------
For two circles with centres ``c1`` and ``c2`` the intersection on branch
``+1`` lies to the **left** of the directed line ``c1 -> c2`` and branch ``-1`` to
its right.  (For a four-bar with ground A->D and joint C found from B and D, this
is the usual "open"/"crossed" choice once the orientation is fixed.)
"""

from __future__ import annotations

import enum
import math

import numpy as np

from .tolerances import TINY

__all__ = [
    "TWO_PI", "angle_spans", "wrap_pi", "wrap_2pi", "rot", "rotate", "transform", "cross2",
    "dot2", "perp",
    "IntersectionKind", "circle_circle", "line_circle", "unit", "norm2", "line_line",
    "line_circle_quadratic", "radical_foot",
]

TWO_PI = 2.0 * math.pi


def wrap_pi(a):
    """Wrap angles to [-pi, pi)."""
    # the numbers of (a + pi) % 2pi - pi, bit for bit (numpy's remainder is
    # fmod plus the divisor where the two differ in sign; a zero's sign is
    # lost in the - pi), at less than half the cost: remainder also divides.
    # fmod(x, 2pi) is x itself (exactly) where |x| < 2pi, as for nearly every
    # angle this is given; fmod, the costliest step, only runs otherwise (a
    # NaN fails the test and takes it too)
    x = np.asarray(a) + math.pi
    if x.size:
        lo, hi = x.min(), x.max()
        if 0.0 <= lo and hi < TWO_PI:
            # every angle within [-pi, pi) already: no turn to add either
            return x - math.pi
        r = x if -TWO_PI < lo and hi < TWO_PI else np.fmod(x, TWO_PI)
    else:
        r = x
    return np.where(r < 0, r + TWO_PI, r) - math.pi


#: Angles this far apart (or more) read as degrees are at most a turn: a
#: span of 90 to 360 stated in rad is most often one written in degrees.
DEGREE_SPAN = (90.0, 360.000001)

#: A turning driver's drive spanning this many rad or more (about 14 turns)
#: that is not a whole number of turns is refused: most likely one written in
#: degrees (``(0, 360)`` is 57.3 turns), the low end of :data:`DEGREE_SPAN`
#: (``Model.drive``, :func:`cspace.simulate.simulate`).  Whole turns pass (a
#: 16-slot Geneva wheel's drive is 16 turns, 100.5 rad).
MAX_DRIVE_SPAN = 90.0


def drive_in_degrees(a: float, b: float):
    """The message for a turning driver's drive ``(a, b)`` (rad) that is most
    likely written in degrees (:data:`MAX_DRIVE_SPAN`), else None."""
    span = abs(b - a)
    turns = span / TWO_PI
    if span < MAX_DRIVE_SPAN or abs(turns - round(turns)) <= 1e-9 * turns:
        return None
    return (f"the drive ({a:.6g}, {b:.6g}) turns the rotating driver {span:.6g} rad "
            f"({turns:.3g} turns); drive angles are in rad, and a drive of {MAX_DRIVE_SPAN:g} "
            f"rad or more must be whole turns"
            f"{degrees_hint(a, b, span=(0.0, math.inf))}")


def degrees_hint(a: float, b: float, span=DEGREE_SPAN) -> str:
    """``"; written in degrees? radians(a) and radians(b) are ... rad"`` when
    the angles ``a`` and ``b`` (stated in rad) lie ``span`` apart (default
    :data:`DEGREE_SPAN`), else ``""``: what a message about angles out of
    range adds."""
    if not span[0] <= abs(b - a) <= span[1]:
        return ""
    return (f"; written in degrees? radians({a:.6g}) and radians({b:.6g}) are "
            f"{math.radians(a):.6g} and {math.radians(b):.6g} rad")


def angle_spans(t, ok, most: int = 4) -> list:
    """The runs of ``ok`` along sorted angles ``t`` (rad), as ``"[a, b] deg"``
    texts (the first ``most``): where a sampled condition holds, for a
    message."""
    ok = np.asarray(ok, dtype=bool)
    runs = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
    return [f"[{math.degrees(t[a]):.1f}, {math.degrees(t[b - 1]):.1f}] deg"
            for a, b in zip(runs[::2], runs[1::2])][:most]


def wrap_2pi(a):
    """Wrap angles to [0, 2 pi)."""
    return np.asarray(a) % TWO_PI


def rot(theta):
    """Rotation matrices, shape ``theta.shape + (2, 2)``."""
    t = np.asarray(theta, dtype=float)
    c, s = np.cos(t), np.sin(t)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def rotate(p, theta, center=(0.0, 0.0)):
    """Rotate points ``p`` (..., 2) counter-clockwise by ``theta`` about ``center``.

    ``theta`` broadcasts against ``p[..., 0]``.
    """
    p = np.asarray(p, dtype=float)
    c0 = np.asarray(center, dtype=float)
    t = np.asarray(theta, dtype=float)
    c, s = np.cos(t), np.sin(t)
    x = p[..., 0] - c0[..., 0]
    y = p[..., 1] - c0[..., 1]
    return np.stack([c0[..., 0] + c * x - s * y, c0[..., 1] + s * x + c * y], -1)


def transform(p, theta, offset):
    """Rigid transform: rotate ``p`` by ``theta`` about the origin, then add ``offset``."""
    return rotate(p, theta) + np.asarray(offset, dtype=float)


def cross2(a, b):
    """z-component of the cross product of 2-D vectors."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def dot2(a, b):
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


def perp(v):
    """Rotate vectors by +90 degrees."""
    v = np.asarray(v, dtype=float)
    return np.stack([-v[..., 1], v[..., 0]], -1)


def norm2(v):
    v = np.asarray(v, dtype=float)
    return np.hypot(v[..., 0], v[..., 1])


def unit(v):
    """Unit vectors; a zero vector maps to (1, 0) (callers validate beforehand)."""
    v = np.asarray(v, dtype=float)
    n = norm2(v)
    safe = np.where(n > 0, n, 1.0)
    out = v / safe[..., None]
    return np.where((n > 0)[..., None], out, np.array([1.0, 0.0]))


class IntersectionKind(enum.IntEnum):
    """How two curves meet."""

    NONE = 0        #: no real intersection
    TANGENT = 1     #: one double point (within tolerance)
    TWO = 2         #: two distinct points
    COINCIDENT = 3  #: identical circles


def circle_circle(c1, r1, c2, r2, branch=1, *, tol: float = 1e-12):
    """Intersection of two circles, on a chosen branch.

    Parameters
    ----------
    c1, c2 : (..., 2) float
        Centres.
    r1, r2 : (...) float
        Radii (> 0).
    branch : +1 or -1 (or array of them)
        +1: the point to the left of ``c1 -> c2``; -1: to the right.
    tol : float
        Relative tolerance for the tangent case: when the discriminant is
        within ``tol * (r1 + r2)**2`` of zero it is clamped to the tangent point.

    Returns
    -------
    p : (..., 2) float
        The intersection point.  Where there is none, the foot of the radical
        axis on the line of centres, ``c1 + a u`` with ``a = (d**2 + r1**2 -
        r2**2) / (2 d)`` (between the circles when they lie apart, beyond both
        when one holds the other), or the common centre of concentric circles:
        finite, never NaN.
    kind : (...) IntersectionKind values (int array)
    """
    c1 = np.asarray(c1, dtype=float)
    c2 = np.asarray(c2, dtype=float)
    r1 = np.asarray(r1, dtype=float)
    r2 = np.asarray(r2, dtype=float)
    d = norm2(c2 - c1)
    # centres closer than tol * (r1 + r2) count as concentric: no finite intersection
    # point (or COINCIDENT circles); dividing by such a d would overflow
    concentric = d <= tol * np.maximum(r1 + r2, TINY)
    base, n, h2 = radical_foot(c1, r1, c2, r2, concentric=concentric)
    scale = (r1 + r2) ** 2
    tang = ~concentric & (np.abs(h2) <= tol * scale)
    h = np.sqrt(np.where(h2 > 0, h2, 0.0))
    p = base + (np.asarray(branch, dtype=float) * h)[..., None] * n
    kind = np.where(h2 > 0, IntersectionKind.TWO, IntersectionKind.NONE)
    kind = np.where(tang, IntersectionKind.TANGENT, kind)
    coincident = concentric & (np.abs(r1 - r2) <= tol * (r1 + r2))
    kind = np.where(coincident, IntersectionKind.COINCIDENT, kind)
    return p, kind.astype(int)


def radical_foot(c1, r1, c2, r2, *, concentric=None):
    """The frame in which two circles meet: the foot of their radical axis on the
    line of centres, the unit normal to the left of ``c1 -> c2``, and the squared
    half-chord.

    The intersections, where ``h2 >= 0``, are ``base +- sqrt(h2) * n``; callers
    apply their own tolerance to ``h2`` (a tangency is ``h2`` near 0).  This is
    the one place that computes them: :func:`circle_circle`, the validation of
    part outlines (:func:`cspace.geometry.segment_intersections`), the overlap
    test and the model builders all start here.

    Parameters
    ----------
    c1, c2 : (..., 2) float
        Centres.
    r1, r2 : (...) float
        Radii.
    concentric : (...) bool, optional
        Where to treat the centres as one (default: where they are equal).
        There ``base`` is ``c1``, ``n`` is (-0, 1) and ``h2`` is -1 (no point).

    Returns
    -------
    base : (..., 2) float
        ``c1 + a u`` with ``a = (d**2 + r1**2 - r2**2) / (2 d)``.
    n : (..., 2) float
        The unit normal, ``u`` turned by +90 degrees.
    h2 : (...) float
        ``r1**2 - a**2``.
    """
    c1 = np.asarray(c1, dtype=float)
    r1 = np.asarray(r1, dtype=float)
    r2 = np.asarray(r2, dtype=float)
    d_vec = np.asarray(c2, dtype=float) - c1
    d = norm2(d_vec)
    if concentric is None:
        concentric = d == 0
    dsafe = np.where(concentric, 1.0, d)
    a = np.where(concentric, 0.0, (d * d + r1 * r1 - r2 * r2) / (2.0 * dsafe))
    h2 = np.where(concentric, -1.0, r1 * r1 - a * a)
    u = d_vec / dsafe[..., None]
    return c1 + a[..., None] * u, perp(u), h2


def line_line(p, r, q, s):
    """Where the lines ``p + t r`` and ``q + u s`` meet.

    Returns
    -------
    t, u : (...) float
        The parameters of the meeting point on each line; 0 where the lines
        are parallel.
    rxs : (...) float
        ``r x s``: 0 for parallel lines (callers judge near-parallel against
        their own tolerance).
    """
    p, r, q, s = (np.asarray(x, dtype=float) for x in (p, r, q, s))
    rxs = cross2(r, s)
    qp = q - p
    par = rxs == 0
    safe = np.where(par, 1.0, rxs)
    return (np.where(par, 0.0, cross2(qp, s) / safe), np.where(par, 0.0, cross2(qp, r) / safe),
            rxs)


def line_circle_quadratic(p0, direction, c, r):
    """The quadratic ``a t**2 + b t + cc = 0`` of the points ``p0 + t * direction``
    at distance ``r`` from ``c``: returns ``a``, ``b`` and the discriminant.

    The roots are ``(-b -+ sqrt(disc)) / (2 a)`` where ``disc >= 0``; callers
    apply their own tolerance to ``disc``.
    """
    v = np.asarray(direction, dtype=float)
    w = np.asarray(p0, dtype=float) - np.asarray(c, dtype=float)
    r = np.asarray(r, dtype=float)
    a = dot2(v, v)
    b = 2.0 * dot2(v, w)
    cc = dot2(w, w) - r * r
    return a, b, b * b - 4 * a * cc


def line_circle(p0, direction, c, r, *, tol: float = 1e-12):
    """Intersections of the line ``p0 + t * direction`` with a circle.

    Returns
    -------
    t : (..., 2) float
        Line parameters of the two intersections (t[..., 0] <= t[..., 1]);
        for no intersection, both equal the foot of the perpendicular.
    kind : (...) int IntersectionKind
    """
    r = np.asarray(r, dtype=float)
    a, b, disc = line_circle_quadratic(p0, direction, c, r)
    tang = np.abs(disc) <= tol * (b * b + 4 * a * r * r)
    sq = np.sqrt(np.where(disc > 0, disc, 0.0))
    t1 = (-b - sq) / (2 * a)
    t2 = (-b + sq) / (2 * a)
    kind = np.where(disc > 0, IntersectionKind.TWO, IntersectionKind.NONE)
    kind = np.where(tang, IntersectionKind.TANGENT, kind)
    return np.stack([t1, t2], -1), kind.astype(int)
