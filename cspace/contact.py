"""Contact curves between the features of two fixed-axis parts.

Every planar contact between a vertex, line or arc of the driver and a vertex,
line or arc of the follower reduces to one of two equations between a *point* P
(a vertex, or the centre of an arc) on one part and a *target* on the other:

* point-line:   n . (P - L0) = r     (n: the line's free-side normal; r: 0 for a
  vertex, the radius for a convex arc)
* point-circle: |P - C| = rho        (rho: the target radius, plus or minus the
  point's arc radius for external or internal arc-arc contact)

For a rotating follower the equation is ``A(q1) cos q2 + B(q1) sin q2 + g(q1) = 0``
with two branches ``q2 = atan2(B, A) +/- arccos(-g / hypot(A, B))``; for a
translating follower it is linear (point-line) or quadratic (point-circle) in the
slide, solved explicitly.  A solution is a real contact only where the contact
point lies inside both features and the vertex's material cone lies on the free
side of the other feature; curves are trimmed there, with end points found by
root finding to ``Accuracy.root_tol``.

A follower feature concentric with the follower's rotation centre (or a line
parallel to the slide) gives a contact that does not depend on q2: a *vertical*
curve ``q1 = const`` (:class:`VerticalCurve`).

Broad-phase pruning removes feature pairs that can never touch: radial annulus
bounds for rotating parts and slab bounds for sliding ones.
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass, field

import numpy as np

from .accuracy import Accuracy
from .geometry import Arc, Line, Pair, Part, Rotation, Translation, place_points
from .geom2d import TWO_PI, wrap_pi
from .metric import coord_scale

__all__ = ["Equation", "Feature", "features", "ContactCurve", "VerticalCurve", "contact_curves",
           "CurveSet", "feature_pairs"]


# --------------------------------------------------------------------------- features

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
    n = len(segs)
    s = segs[si]
    nm = _seg_name(part, li, si)
    if isinstance(s, Line):
        out = [Feature(index, "line", (index, li, si), nm, s.start, s.end,
                       segs=((index, li, si),))]
    else:
        out = [Feature(index, "arc", (index, li, si), nm, s.center, radius=s.radius,
                       convex=s.ccw, mid=float(s.mid_angle), half=0.5 * s.sweep,
                       segs=((index, li, si),))]
    prev = segs[(si - 1) % n]
    t_in = prev.end_tangent()
    t_out = s.start_tangent()
    turn = t_in[0] * t_out[1] - t_in[1] * t_out[0]
    if n > 1 or not isinstance(s, Arc):
        if turn > 1e-9 or (abs(turn) <= 1e-9 and np.dot(t_in, t_out) < 0):
            pv = s.start_point
            pname = _seg_name(part, li, (si - 1) % n)
            out.append(Feature(index, "vertex", (index, li, si), f"{pname}^{nm}",
                               (float(pv[0]), float(pv[1])),
                               e1=(float(-t_in[0]), float(-t_in[1])),
                               e2=(float(t_out[0]), float(t_out[1])),
                               segs=((index, li, (si - 1) % n), (index, li, si))))
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


def _free_normal(f: Feature) -> np.ndarray:
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


def _radial_range(f: Feature, c) -> tuple[float, float]:
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


def _proj_range(f: Feature, u) -> tuple[float, float]:
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


def _can_touch(fa: Feature, fb: Feature, pair: Pair, margin: float) -> bool:
    """Broad phase: can feature fa of the driver ever touch fb of the follower?"""
    ax_a, ax_b = pair.driver.axis, pair.follower.axis
    if isinstance(ax_a, Rotation) and isinstance(ax_b, Rotation):
        amin, amax = _radial_range(fa, ax_a.center)
        bmin, bmax = _radial_range(fb, ax_b.center)
        D = float(np.hypot(*np.subtract(ax_a.center, ax_b.center)))
        return (amax + bmax >= D - margin and amin - bmax <= D + margin
                and bmin - amax <= D + margin)
    if isinstance(ax_a, Rotation) and isinstance(ax_b, Translation):
        # slab bound: perpendicular to the slide, the follower feature is fixed
        e = np.array(ax_b.direction)
        u = np.array([-e[1], e[0]])
        amin, amax = _radial_range(fa, ax_a.center)
        c = float(np.dot(ax_a.center, u))
        lo, hi = _proj_range(fb, u)
        # distance from the driver centre to the slab [lo, hi] along u
        dist = max(lo - c, c - hi, 0.0)
        if dist > amax + margin:
            return False
        # a feature entirely inside the driver's inner radius never touches: only
        # when the slab lies within that radius band everywhere (rare) - skip
        return True
    if isinstance(ax_a, Translation) and isinstance(ax_b, Rotation):
        e = np.array(ax_a.direction)
        u = np.array([-e[1], e[0]])
        bmin, bmax = _radial_range(fb, ax_b.center)
        c = float(np.dot(ax_b.center, u))
        lo, hi = _proj_range(fa, u)
        return max(lo - c, c - hi, 0.0) <= bmax + margin
    # two translations: parallel slides can always be brought together if the
    # perpendicular slabs overlap
    return True


class Equation(str, enum.Enum):
    """The two closed-form contact equations a kernel solves.

    A ``str`` enum: a member equals (and hashes as) its value, so ``"pl"`` and
    ``Equation.POINT_LINE`` are interchangeable where a tag was stored."""

    POINT_LINE = "pl"      #: a point (or an arc's centre) at offset r from a line
    POINT_CIRCLE = "pc"    #: a point (or an arc's centre) at distance rho from a centre

    __hash__ = str.__hash__

    def __str__(self) -> str:
        return self.value


def _types(fa: Feature, fb: Feature):
    """Equation descriptors for a feature pair: list of (eq, owner_of_point, r_or_rho).

    Returns an empty list for pairs that cannot give a 2-D contact curve
    (vertex-vertex, line-line, concave arc against a line, two concave arcs).
    """
    ka, kb = fa.kind, fb.kind
    if ka == "vertex" and kb == "line":
        return [(Equation.POINT_LINE, 0, 0.0)]
    if ka == "line" and kb == "vertex":
        return [(Equation.POINT_LINE, 1, 0.0)]
    if ka == "vertex" and kb == "arc":
        return [(Equation.POINT_CIRCLE, 0, fb.radius)]
    if ka == "arc" and kb == "vertex":
        return [(Equation.POINT_CIRCLE, 1, fa.radius)]
    if ka == "arc" and kb == "line":
        return [(Equation.POINT_LINE, 0, fa.radius)] if fa.convex else []
    if ka == "line" and kb == "arc":
        return [(Equation.POINT_LINE, 1, fb.radius)] if fb.convex else []
    if ka == "arc" and kb == "arc":
        if fa.convex and fb.convex:
            return [(Equation.POINT_CIRCLE, 0, fa.radius + fb.radius)]
        if fa.convex and not fb.convex and fb.radius > fa.radius:
            return [(Equation.POINT_CIRCLE, 0, fb.radius - fa.radius)]
        if fb.convex and not fa.convex and fa.radius > fb.radius:
            return [(Equation.POINT_CIRCLE, 0, fa.radius - fb.radius)]
    return []


def feature_pairs(pair: Pair, *, margin_rel: float = 1e-6):
    """Candidate feature pairs after broad-phase pruning.

    The broad phase is the test of :func:`_can_touch`, run through sorted
    bounds: each feature's radial range about its centre (or its slab across a
    slide) is computed once, and for each driver feature only the follower
    features whose bound can reach it are visited, so a pair of parts that
    mostly do not touch costs O(n log n) in their segment counts, not
    O(n1 n2).  The pairs and their order are those of the pairwise test.

    Returns
    -------
    pairs : list of (Feature, Feature, eq, owner, r)
    n_pruned : int
        Pairs of compatible types removed by the broad phase.
    """
    fa_all = features(pair.driver, 0)
    fb_all = features(pair.follower, 1)
    margin = margin_rel * pair.size
    out = []
    kept = 0
    for ia, jb in _reachable(fa_all, fb_all, pair, margin):
        fa = fa_all[ia]
        for j in jb:
            ts = _types(fa, fb_all[j])
            kept += len(ts)
            for eq, owner, r in ts:
                out.append((fa, fb_all[j], eq, owner, r))
    return out, _n_compatible(fa_all, fb_all) - kept


def _slab_distances(center, direction, rot_feats, slide_feats):
    """For a rotating part (centre ``center``) against a sliding one (slide
    ``direction``): the radial ranges (n, 2) of the rotating features about the
    centre, the distance of each sliding feature's slab (perpendicular to the
    slide) from the centre, and the centre's coordinate across the slide."""
    e = np.array(direction)
    u = np.array([-e[1], e[0]])
    c = float(np.dot(center, u))
    rr = np.array([_radial_range(f, center) for f in rot_feats]).reshape(-1, 2)
    pp = np.array([_proj_range(f, u) for f in slide_feats]).reshape(-1, 2)
    return rr, np.maximum(np.maximum(pp[:, 0] - c, c - pp[:, 1]), 0.0), c


def _reachable(fa_all, fb_all, pair, margin):
    """For each driver feature index, the sorted follower feature indices that
    pass :func:`_can_touch` (same arithmetic, evaluated through sorted bounds)."""
    ax_a, ax_b = pair.driver.axis, pair.follower.axis
    nb = len(fb_all)
    if isinstance(ax_a, Translation) and isinstance(ax_b, Translation):
        allb = np.arange(nb)
        return [(i, allb) for i in range(len(fa_all))]
    if isinstance(ax_a, Rotation) and isinstance(ax_b, Rotation):
        ra = np.array([_radial_range(f, ax_a.center) for f in fa_all]).reshape(-1, 2)
        rb = np.array([_radial_range(f, ax_b.center) for f in fb_all]).reshape(-1, 2)
        D = float(np.hypot(*np.subtract(ax_a.center, ax_b.center)))
        order = np.argsort(rb[:, 1], kind="stable")
        bmax_sorted = rb[order, 1]
        res = []
        for i, (amin, amax) in enumerate(ra):
            # amax + bmax >= D - margin, for bmax at or above a threshold
            k = np.searchsorted(bmax_sorted, D - margin - amax - _SLACK * (D + amax),
                                side="left")
            cand = order[k:]
            bmin, bmax = rb[cand, 0], rb[cand, 1]
            ok = ((amax + bmax >= D - margin) & (amin - bmax <= D + margin)
                  & (bmin - amax <= D + margin))
            res.append((i, np.sort(cand[ok])))
        return res
    if isinstance(ax_a, Rotation):
        # the follower slides: its slab distance from the driver centre is fixed
        ra, dist, c = _slab_distances(ax_a.center, ax_b.direction, fa_all, fb_all)
        order = np.argsort(dist, kind="stable")
        ds = dist[order]
        res = []
        for i, (_, amax) in enumerate(ra):
            k = np.searchsorted(ds, amax + margin + _SLACK * (abs(amax) + abs(c)), side="right")
            cand = order[:k]
            res.append((i, np.sort(cand[~(dist[cand] > amax + margin)])))
        return res
    rb, dist, c = _slab_distances(ax_b.center, ax_a.direction, fb_all, fa_all)
    order = np.argsort(rb[:, 1], kind="stable")
    bs = rb[order, 1]
    res = []
    for i, d in enumerate(dist):
        k = np.searchsorted(bs, d - margin - _SLACK * (abs(d) + abs(c)), side="left")
        cand = order[k:]
        res.append((i, np.sort(cand[rb[cand, 1] + margin >= d])))
    return res


#: Relative slack of the sorted-bound searches of :func:`_reachable`: the
#: search keeps a few more candidates than needed, and the exact test of
#: :func:`_can_touch` (same expression, same rounding) decides.
_SLACK = 1e-12


def _n_compatible(fa_all, fb_all) -> int:
    """Number of (driver, follower) feature pairs with a contact equation
    (``sum(len(_types(a, b)))`` over all pairs), counted by kind."""
    def census(fs):
        n = {"vertex": 0, "line": 0}
        vex, cave = [], []
        for f in fs:
            if f.kind == "arc":
                (vex if f.convex else cave).append(f.radius)
            else:
                n[f.kind] += 1
        return n, np.sort(vex), np.sort(cave)

    (na, vexa, cavea), (nb, vexb, caveb) = census(fa_all), census(fb_all)
    arcs_a, arcs_b = len(vexa) + len(cavea), len(vexb) + len(caveb)
    total = na["vertex"] * nb["line"] + na["line"] * nb["vertex"]
    total += na["vertex"] * arcs_b + arcs_a * nb["vertex"]
    total += len(vexa) * nb["line"] + na["line"] * len(vexb)
    total += len(vexa) * len(vexb)
    # convex driver arc in a concave follower arc of larger radius, and back
    total += int(sum(len(caveb) - np.searchsorted(caveb, r, side="right") for r in vexa))
    total += int(sum(len(cavea) - np.searchsorted(cavea, r, side="right") for r in vexb))
    return total


# --------------------------------------------------------------------------- kernels

def _place(axis, q, pts):
    """World position of body points ``pts`` (2,) at coordinates q (N,) -> (N, 2)."""
    q = np.asarray(q, dtype=float)
    if len(pts) == 2 and not hasattr(pts[0], "__len__"):
        # one body point (the hot path of the contact kernels): no array stacking
        px, py = float(pts[0]), float(pts[1])
        if q.shape == (1,):
            v = float(q[0])
            return np.array([_place_one(axis, v, px, py, *_cos_sin(axis, v))])
        out = np.empty(q.shape + (2,))
        if isinstance(axis, Rotation):
            cx, cy = axis.center
            cq, sq = np.cos(q), np.sin(q)
            x, y = px - cx, py - cy
            out[..., 0] = cx + cq * x - sq * y
            out[..., 1] = cy + sq * x + cq * y
        else:
            ex, ey = axis.direction
            out[..., 0] = px + q * ex
            out[..., 1] = py + q * ey
        return out
    return place_points(axis, q, pts)


def _cos_sin(axis, v: float):
    """(cos v, sin v) for a rotation axis, else (None, None)."""
    return (math.cos(v), math.sin(v)) if isinstance(axis, Rotation) else (None, None)


def _place_one(axis, v: float, px: float, py: float, cq, sq) -> tuple:
    """World (x, y) of one body point at one coordinate ``v`` (``cq, sq``: from
    :func:`_cos_sin`): the operations of :func:`_place` in Python floats, bit
    for bit the same (math.cos/sin agree with numpy's), 4x faster."""
    if cq is not None:
        cx, cy = axis.center
        x, y = px - cx, py - cy
        return cx + cq * x - sq * y, cy + sq * x + cq * y
    ex, ey = axis.direction
    return px + v * ex, py + v * ey


def _dot(v, e):
    """Row-wise dot product of (N, 2) with (2,) as two products and a sum: ``@``
    goes through BLAS, whose rounding may depend on N (a value must not depend
    on how many others were computed with it)."""
    return v[:, 0] * e[0] + v[:, 1] * e[1]


def _turn(axis, q, vec):
    """World direction of body vector ``vec`` at coordinates q."""
    q = np.asarray(q, dtype=float)
    if isinstance(axis, Rotation):
        cq, sq = np.cos(q), np.sin(q)
        vx, vy = float(vec[0]), float(vec[1])
        out = np.empty(q.shape + (2,))
        out[..., 0] = cq * vx - sq * vy
        out[..., 1] = sq * vx + cq * vy
        return out
    return np.broadcast_to(np.asarray(vec, dtype=float), q.shape + (2,)).copy()


def _angle_of(axis, q):
    return np.asarray(q, dtype=float) if isinstance(axis, Rotation) else np.zeros_like(np.asarray(q, dtype=float))


@dataclass(frozen=True)
class _Kernel:
    """Closed-form contact equation of one feature pair (picklable)."""

    eq: Equation       # the contact equation
    owner: int         # part owning the point P
    r: float           # point-line offset, or point-circle rho
    fa: Feature
    fb: Feature
    axis_a: object
    axis_b: object
    scale: float       # characteristic length

    @property
    def fp(self) -> Feature:
        return self.fa if self.owner == 0 else self.fb

    @property
    def ft(self) -> Feature:
        return self.fb if self.owner == 0 else self.fa

    @property
    def nbranch(self) -> int:
        if isinstance(self.axis_b, Rotation):
            return 2
        return 1 if self.eq == Equation.POINT_LINE else 2

    def is_vertical(self) -> bool:
        """Whether the equation does not depend on q2."""
        tol = 1e-12 * self.scale
        if isinstance(self.axis_b, Rotation):
            ob = np.array(self.axis_b.center)
            if self.owner == 0:
                return self.eq == Equation.POINT_CIRCLE and np.hypot(*(np.array(self.ft.p) - ob)) <= tol
            return np.hypot(*(np.array(self.fp.p) - ob)) <= tol
        e = np.array(self.axis_b.direction)
        if self.owner == 0 and self.eq == Equation.POINT_LINE:
            return abs(float(np.dot(_free_normal(self.ft), e))) <= 1e-12
        if self.owner == 1 and self.eq == Equation.POINT_LINE and isinstance(self.axis_a, Translation):
            return abs(float(np.dot(_free_normal(self.ft), e))) <= 1e-12
        return False

    # ---- solve for q2 on each branch
    @functools.cached_property
    def _k(self) -> tuple:
        """Constants of :meth:`solve` (computed once per kernel; the arithmetic
        of :meth:`solve` is unchanged, only not repeated)."""
        ax_b = self.axis_b
        fp, ft = self.fp, self.ft
        if isinstance(ax_b, Rotation):
            ob = np.array(ax_b.center)
            if self.owner == 0:
                if self.eq == Equation.POINT_LINE:
                    n = _free_normal(ft)
                    l = np.array(ft.p) - ob
                    return ("r0l", ob, n, -(float(n @ l) + self.r))
                c = np.array(ft.p) - ob
                return ("r0c", ob, c, float(c @ c), self.r ** 2)
            p = np.array(fp.p) - ob
            if self.eq == Equation.POINT_LINE:
                return ("r1l", ob, p, _free_normal(ft))
            return ("r1c", ob, p, float(p @ p), self.r ** 2)
        e = np.array(ax_b.direction)
        if self.owner == 0:
            if self.eq == Equation.POINT_LINE:
                n = _free_normal(ft)
                ne = float(n @ e)
                return ("t0l", e, n, np.array(ft.p), ne if ne != 0 else 1e-300)
            return ("t0c", e, np.array(ft.p))
        if self.eq == Equation.POINT_LINE:
            return ("t1l", e, _free_normal(ft), np.array(fp.p))
        return ("t1c", e, np.array(fp.p))

    def __getstate__(self):
        d = dict(self.__dict__)
        d.pop("_k", None)
        return d

    def __setstate__(self, d):
        self.__dict__.update(d)

    def solve(self, q1):
        """Return (q2 of shape (nbranch, N), existence condition (N,), >= 0 where real)."""
        q1 = np.asarray(q1, dtype=float)
        if q1.ndim != 1:
            q1 = np.atleast_1d(q1)
        L = self.scale
        ax_a = self.axis_a
        k = self._k
        kind = k[0]
        if kind[0] == "r" and q1.shape == (1,):
            return self._solve_one(float(q1[0]))
        if kind[0] == "r":
            ob = k[1]
            if kind == "r0l":
                w = _place(ax_a, q1, self.fp.p) - ob
                n = k[2]
                A = n[0] * w[:, 0] + n[1] * w[:, 1]
                B = n[0] * w[:, 1] - n[1] * w[:, 0]
                g = np.full_like(A, k[3])
            elif kind == "r0c":
                w = _place(ax_a, q1, self.fp.p) - ob
                c = k[2]
                A = -2 * (c[0] * w[:, 0] + c[1] * w[:, 1])
                B = -2 * (c[0] * w[:, 1] - c[1] * w[:, 0])
                g = (w ** 2).sum(1) + k[3] - k[4]
            elif kind == "r1l":
                p = k[2]
                nw = _turn(ax_a, q1, k[3])
                lw = _place(ax_a, q1, self.ft.p)
                A = nw[:, 0] * p[0] + nw[:, 1] * p[1]
                B = p[0] * nw[:, 1] - p[1] * nw[:, 0]
                g = ((ob - lw) * nw).sum(1) - self.r
            else:
                p = k[2]
                m = ob - _place(ax_a, q1, self.ft.p)
                A = 2 * (p[0] * m[:, 0] + p[1] * m[:, 1])
                B = 2 * (p[0] * m[:, 1] - p[1] * m[:, 0])
                g = (m ** 2).sum(1) + k[3] - k[4]
            R = np.hypot(A, B)
            alpha = np.arctan2(B, A)
            Rs = np.where(R > 0, R, 1.0)
            cosv = np.minimum(np.maximum(-g / Rs, -1.0), 1.0)
            acs = np.arccos(cosv)
            q2 = np.empty((2,) + alpha.shape)
            np.add(alpha, acs, out=q2[0])
            np.subtract(alpha, acs, out=q2[1])
            # existence in length units (R ~ length^2 for pc, length for pl)
            if self.eq == Equation.POINT_CIRCLE:
                exist = (R - np.abs(g)) / (2 * L)
            else:
                exist = R - np.abs(g)
            return q2, exist / L
        # translating follower
        e = k[1]
        if kind == "t0l":
            pw = _place(ax_a, q1, self.fp.p)
            d = pw - k[3]
            s = (_dot(d, k[2]) - self.r) / k[4]
            return s[None, :], np.ones_like(s)
        if kind == "t0c":
            w = _place(ax_a, q1, self.fp.p) - k[2]
        elif kind == "t1l":
            nw = _turn(ax_a, q1, k[2])
            lw = _place(ax_a, q1, self.ft.p)
            ne = _dot(nw, e)
            ne_s = np.where(np.abs(ne) > 1e-300, ne, 1e-300)
            s = (self.r - ((k[3] - lw) * nw).sum(1)) / ne_s
            return s[None, :], np.abs(ne) - 1e-9
        else:
            w = _place(ax_a, q1, self.ft.p) - k[2]
        ew = _dot(w, e)
        cr = w[:, 0] * e[1] - w[:, 1] * e[0]
        disc = self.r ** 2 - cr ** 2
        sq = np.sqrt(np.where(disc > 0, disc, 0.0))
        s = np.stack([ew + sq, ew - sq])
        return s, (self.r - np.abs(cr)) / L

    def _solve_one(self, v: float):
        """:meth:`solve` of a rotating follower at one driver value: the same IEEE
        operations in Python floats and numpy scalar functions (identical to
        the array path bit for bit, tests/cspace/test_contact.py), 3x faster;
        the simulation and the cell bounds call it with one value at a time."""
        k = self._k
        kind = k[0]
        ob0, ob1 = float(k[1][0]), float(k[1][1])
        ax_a = self.axis_a
        cq, sq = _cos_sin(ax_a, v)

        def place(pt):
            return _place_one(ax_a, v, float(pt[0]), float(pt[1]), cq, sq)

        if kind == "r0l":
            wx, wy = place(self.fp.p)
            wx, wy = wx - ob0, wy - ob1
            n0, n1 = float(k[2][0]), float(k[2][1])
            A = n0 * wx + n1 * wy
            B = n0 * wy - n1 * wx
            g = float(k[3])
        elif kind == "r0c":
            wx, wy = place(self.fp.p)
            wx, wy = wx - ob0, wy - ob1
            c0, c1 = float(k[2][0]), float(k[2][1])
            A = -2 * (c0 * wx + c1 * wy)
            B = -2 * (c0 * wy - c1 * wx)
            g = (wx * wx + wy * wy) + k[3] - k[4]
        elif kind == "r1l":
            p0, p1 = float(k[2][0]), float(k[2][1])
            vx, vy = float(k[3][0]), float(k[3][1])
            if cq is not None:
                nx, ny = cq * vx - sq * vy, sq * vx + cq * vy
            else:
                nx, ny = vx, vy
            lx, ly = place(self.ft.p)
            A = nx * p0 + ny * p1
            B = p0 * ny - p1 * nx
            g = ((ob0 - lx) * nx + (ob1 - ly) * ny) - self.r
        else:
            p0, p1 = float(k[2][0]), float(k[2][1])
            mx, my = place(self.ft.p)
            mx, my = ob0 - mx, ob1 - my
            A = 2 * (p0 * mx + p1 * my)
            B = 2 * (p0 * my - p1 * mx)
            g = (mx * mx + my * my) + k[3] - k[4]
        R = float(np.hypot(A, B))
        alpha = float(np.arctan2(B, A))
        Rs = R if R > 0 else 1.0
        cosv = -g / Rs
        if cosv < -1.0:
            cosv = -1.0
        elif cosv > 1.0:
            cosv = 1.0
        acs = float(np.arccos(cosv))
        q2 = np.array([[alpha + acs], [alpha - acs]])
        L = self.scale
        if self.eq == Equation.POINT_CIRCLE:
            exist = (R - abs(g)) / (2 * L)
        else:
            exist = R - abs(g)
        return q2, np.array([exist / L])

    # ---- validity of a solution
    def conditions(self, q1, q2):
        """Smallest validity margin (>= 0 where the solution is a real contact).

        Margins are in units of the characteristic length (or rad for angles).
        """
        q1 = np.atleast_1d(np.asarray(q1, dtype=float))
        q2 = np.atleast_1d(np.asarray(q2, dtype=float))
        L = self.scale
        qs = (q1, q2)
        axes = (self.axis_a, self.axis_b)
        fp, ft = self.fp, self.ft
        po, to = self.owner, 1 - self.owner
        P = _place(axes[po], qs[po], fp.p)
        margins = []
        if self.eq == Equation.POINT_LINE:
            n = _turn(axes[to], qs[to], _free_normal(ft))
            l0 = _place(axes[to], qs[to], ft.p)
            l1 = _place(axes[to], qs[to], ft.q)
            X = P - self.r * n if fp.kind == "arc" else P
            d = l1 - l0
            ln = np.hypot(d[:, 0], d[:, 1])
            t = ((X - l0) * d).sum(1) / ln
            margins += [t / L, (ln - t) / L]
            if fp.kind == "arc":
                dirn = -n
                margins.append(self._arc_margin(fp, dirn, axes[po], qs[po]))
            free_n = n
        else:
            C = _place(axes[to], qs[to], ft.p)
            u = P - C
            un = np.hypot(u[:, 0], u[:, 1])
            u = u / np.where(un > 0, un, 1.0)[:, None]
            p_concave = fp.kind == "arc" and not fp.convex
            dc = -u if p_concave else u
            margins.append(self._arc_margin(ft, dc, axes[to], qs[to]))
            if fp.kind == "arc":
                if p_concave:
                    dp = -u
                elif ft.convex:
                    dp = -u
                else:
                    dp = u
                margins.append(self._arc_margin(fp, dp, axes[po], qs[po]))
            free_n = u if ft.convex else -u
        if fp.kind == "vertex":
            for ev in (fp.e1, fp.e2):
                ew = _turn(axes[po], qs[po], ev)
                margins.append((ew * free_n).sum(1))
        return functools.reduce(np.minimum, margins)

    @staticmethod
    def _arc_margin(f: Feature, dirn, axis, q):
        """Angular margin (rad) of world direction ``dirn`` inside arc f's sweep."""
        if f.half >= math.pi - 1e-15:
            return np.full(dirn.shape[0], 1.0)
        ang = np.arctan2(dirn[:, 1], dirn[:, 0]) - _angle_of(axis, q)
        return f.half - np.abs(wrap_pi(ang - f.mid))

    def margin(self, q1, branch: int):
        """Combined validity function along one branch (continuous in q1)."""
        q2, ex = self.solve(q1)
        c = self.conditions(q1, q2[branch])
        return np.minimum(ex, c), q2[branch]

    def margins(self, q1):
        """:meth:`margin` of every branch from one solve: (nbranch, N) margins and q2."""
        q1 = np.atleast_1d(np.asarray(q1, dtype=float))
        q2, ex = self.solve(q1)
        m = np.stack([np.minimum(ex, self.conditions(q1, q2[b])) for b in range(self.nbranch)])
        return m, q2

    # ---- vertical contacts (independent of q2)
    def vertical_residual(self, q1):
        """Contact residual as a function of q1 alone (vertical curves)."""
        q1 = np.atleast_1d(np.asarray(q1, dtype=float))
        if isinstance(self.axis_b, Rotation):
            ob = np.array(self.axis_b.center)
            if self.owner == 0:
                w = _place(self.axis_a, q1, self.fp.p) - ob
                return (np.hypot(w[:, 0], w[:, 1]) - self.r) / self.scale
            m = _place(self.axis_a, q1, self.ft.p) - ob
            return (np.hypot(m[:, 0], m[:, 1]) - self.r) / self.scale
        n = _free_normal(self.ft)
        if self.owner == 0:
            pw = _place(self.axis_a, q1, self.fp.p)
            return (_dot(pw - np.array(self.ft.p), n) - self.r) / self.scale
        # the follower's point against a line of a sliding driver, the line
        # parallel to the follower's slide: the follower's position does not
        # change the distance, the driver's does
        p0 = np.array(_place(self.axis_b, np.zeros(1), self.fp.p)[0])
        lw = _place(self.axis_a, q1, self.ft.p)
        return (_dot(p0[None, :] - lw, n) - self.r) / self.scale


# --------------------------------------------------------------------------- curves

def _label(fa: Feature, fb: Feature, pair: Pair) -> str:
    return f"{pair.driver.name}:{fa.name}|{pair.follower.name}:{fb.name}"


@dataclass(frozen=True, eq=False)
class ContactCurve:
    """One trimmed branch of a contact curve: q2 = f(q1) on [q1_start, q1_end].

    Attributes
    ----------
    label : str
        ``"driver:feature|follower:feature"``.
    kind : str
        Feature kinds, e.g. ``"arc-line"``; ``"arc-arc-int"`` for internal arc contact.
    branch : int
        +1 / -1 (two-branch equations), 0 (point-line with a sliding follower).
    features : tuple
        Feature keys ``((0, loop, seg, kind), (1, loop, seg, kind))``.
    depends : frozenset of str
        Model parameters the contact equation depends on (empty without a model).
    q1_start, q1_end : float
        The trimmed driver range (rad or length).
    """

    label: str
    kind: str
    branch: int
    features: tuple
    depends: frozenset
    q1_start: float
    q1_end: float
    kernel: _Kernel = field(repr=False)
    periodic: bool = field(default=True, repr=False)
    q2_origin: float = field(default=0.0, repr=False)
    start_closed: bool = field(default=True, repr=False)
    end_closed: bool = field(default=True, repr=False)

    @property
    def bi(self) -> int:
        return 0 if self.branch >= 0 else 1

    @property
    def key(self) -> tuple:
        """Identity of the curve independent of trimming: features + branch."""
        return (self.features, self.branch)

    def evaluate(self, q1):
        """Exact q2 at driver coordinates ``q1`` (array), wrapped into the follower
        window for a rotating follower."""
        q2 = self.kernel.solve(q1)[0][self.bi]
        if self.periodic:
            q2 = (q2 - self.q2_origin) % TWO_PI + self.q2_origin
        return q2

    def raw(self, q1):
        """q2 without wrapping (continuous along the curve)."""
        return self.kernel.solve(q1)[0][self.bi]

    def values(self, q1):
        """``(evaluate(q1), raw(q1))`` from one solve."""
        r = self.kernel.solve(q1)[0][self.bi]
        if self.periodic and r.shape == (1,):
            v = float(r[0])  # Python's float % is numpy's remainder, bit for bit
            return np.array([(v - self.q2_origin) % TWO_PI + self.q2_origin]), r
        if self.periodic:
            return (r - self.q2_origin) % TWO_PI + self.q2_origin, r
        return r, r

    def margin(self, q1):
        """Validity margin along the branch (>= 0 where a real contact)."""
        return self.kernel.margin(q1, self.bi)[0]

    def polyline(self, accuracy: Accuracy | None = None) -> np.ndarray:
        """Adaptive polyline (n, 2) in (q1, q2) whose chord error is at most
        ``accuracy.chord`` in the C-space metric.  q2 is continuous (unwrapped)."""
        from .accuracy import as_accuracy
        acc = as_accuracy(accuracy)
        s2 = 1.0 if self.periodic else 1.0 / self.kernel.scale
        s1 = coord_scale(self.kernel.axis_a, self.kernel.scale)
        return adaptive_polyline(self.raw, self.q1_start, self.q1_end, acc.chord,
                                 acc.max_step * s1, scale=s2, scale1=1.0 / s1)

    def point_world(self, q1):
        """(contact configuration) helper: (q1, q2) arrays."""
        q1 = np.atleast_1d(np.asarray(q1, dtype=float))
        return np.stack([q1, self.evaluate(q1)], -1)


@dataclass(frozen=True, eq=False)
class VerticalCurve:
    """A contact independent of q2: the segment q1 = ``q1_value``, q2 in [q2_lo, q2_hi]."""

    label: str
    kind: str
    features: tuple
    depends: frozenset
    q1_value: float
    q2_lo: float
    q2_hi: float
    kernel: _Kernel = field(repr=False)
    branch: int = 0

    @property
    def key(self) -> tuple:
        return (self.features, "vertical")


def adaptive_polyline(fn, a: float, b: float, chord: float, max_step: float, scale=1.0,
                      max_rounds: int = 40, scale1=1.0) -> np.ndarray:
    """Polyline through (t, fn(t)) on [a, b] with midpoint chord error <= chord,
    measured with t times ``scale1`` and fn times ``scale`` (the C-space metric)."""
    n = max(2, int(math.ceil((b - a) / max_step)) + 1)
    t = np.linspace(a, b, n)
    v = fn(t)
    for _ in range(max_rounds):
        tm = 0.5 * (t[:-1] + t[1:])
        vm = fn(tm)
        # perpendicular distance of the true midpoint from the chord
        dt = (t[1:] - t[:-1]) * scale1
        dv = (v[1:] - v[:-1]) * scale
        err = np.abs((vm - 0.5 * (v[:-1] + v[1:])) * scale) * dt / np.maximum(np.hypot(dt, dv), 1e-300)
        bad = (err > chord) & (dt > 1e-12)
        if not bad.any():
            break
        t = np.insert(t, np.nonzero(bad)[0] + 1, tm[bad])
        v = np.insert(v, np.nonzero(bad)[0] + 1, vm[bad])
    return np.stack([t, v], -1)


def _roots_refine(fn, a, b, fa, tol):
    """Root of a continuous scalar function on [a, b] with sign change."""
    r = vroots(fn, np.array([a]), np.array([b]), tol)
    return float(r[0])


def vroots(fn, a, b, tol, maxiter: int = 200, fa=None, fb=None):
    """Roots of a vectorised continuous function in many brackets at once.

    Illinois (modified regula falsi) steps; a bracket that fails to halve over two
    steps takes a bisection step.  Each root is returned once its bracket is
    shorter than ``tol`` (or a probe 0.4 tol beside the step closes it) or its
    value is exactly zero, within ``tol / 2`` of a root.  ``fn`` maps an array
    of abscissae to an array of values; it is called with the N bracket points,
    or with 3 N points (three blocks of N, point k of a block belonging to
    bracket k).  Each bracket [a_i, b_i] must hold a sign change (otherwise its
    midpoint is returned).  ``fa``, ``fb``: the values at the bracket ends when
    the caller has them already (saves two evaluations).
    """
    a = np.asarray(a, dtype=float).copy()
    b = np.asarray(b, dtype=float).copy()
    if a.size == 0:
        return a
    fa = fn(a) if fa is None else np.asarray(fa, dtype=float).copy()
    fb = fn(b) if fb is None else np.asarray(fb, dtype=float).copy()
    done = (fa == 0) | (fb == 0) | (np.sign(fa) == np.sign(fb)) | (np.abs(b - a) <= tol)
    root = np.where(fa == 0, a, np.where(fb == 0, b, 0.5 * (a + b)))
    side = np.zeros(a.shape, dtype=int)
    w_old = np.abs(b - a)
    stall = np.zeros(a.shape, dtype=int)
    for _ in range(maxiter):
        if done.all():
            break
        act = ~done
        denom = fb - fa
        c = (a * fb - b * fa) / np.where(denom != 0, denom, 1.0)
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        bis = (denom == 0) | ~np.isfinite(c) | (c <= lo) | (c >= hi) | (stall >= 2)
        c = np.where(bis, 0.5 * (a + b), c)
        # keep the new point a little inside the bracket so that it always shrinks
        eps = 0.25 * tol
        c = np.clip(c, lo + eps, hi - eps)
        # two probes 0.4 tol either side of c ride along in the same call (the cost
        # of a call hardly depends on its length): once c is within 0.4 tol of the
        # root, one of them closes the bracket at once instead of waiting for the
        # far end to creep in
        cm = np.maximum(c - 0.4 * tol, lo)
        cp = np.minimum(c + 0.4 * tol, hi)
        n_ = len(a)
        f3 = fn(np.concatenate([np.where(act, c, a), np.where(act, cm, a), np.where(act, cp, a)]))
        fc, fm, fp = f3[:n_], f3[n_:2 * n_], f3[2 * n_:]
        zero = act & (fc == 0)
        same_b = np.sign(fc) == np.sign(fb)
        nb = act & same_b & ~zero
        na = act & ~same_b & ~zero
        fa = np.where(nb & (side == -1), 0.5 * fa, fa)
        fb = np.where(na & (side == 1), 0.5 * fb, fb)
        b = np.where(nb, c, b)
        fb = np.where(nb, fc, fb)
        a = np.where(na, c, a)
        fa = np.where(na, fc, fa)
        side = np.where(nb, -1, np.where(na, 1, side))
        root = np.where(zero, c, root)
        done |= zero
        w = np.abs(b - a)
        stall = np.where(bis, 0, np.where(w > 0.5 * w_old, stall + 1, 0))
        w_old = np.where(stall == 0, w, w_old)
        conv = act & ~zero & (w <= tol)
        root = np.where(conv, 0.5 * (a + b), root)
        done |= conv
        # a probe beside c closes the bracket
        live = act & ~done
        left = live & (np.sign(fm) * np.sign(fc) <= 0) & (cm < c)
        right = live & ~left & (np.sign(fp) * np.sign(fc) <= 0) & (cp > c)
        root = np.where(left, np.where(fm == 0, cm, 0.5 * (cm + c)), root)
        root = np.where(right, np.where(fp == 0, cp, 0.5 * (c + cp)), root)
        done |= left | right
    return np.where(done, root, 0.5 * (a + b))


def _valid_runs(grid, mvals):
    """Maximal runs of grid indices where the margin is >= 0: list of (i, j) and
    the root brackets (grid index pairs) of their interior ends, lower and upper."""
    ok = mvals >= 0
    n = len(grid)
    if not ok.any():
        return [], [], []
    d = np.diff(ok.astype(int))
    starts = list(np.nonzero(d == 1)[0] + 1)
    stops = list(np.nonzero(d == -1)[0])
    if ok[0]:
        starts = [0] + starts
    if ok[-1]:
        stops = stops + [n - 1]
    lo_br = [(i - 1, i) for i in starts if i > 0]
    hi_br = [(j, j + 1) for j in stops if j < n - 1]
    return list(zip(starts, stops)), lo_br, hi_br


def _branch_intervals(mfun, grid, mvals, tol) -> list:
    """Per branch, the maximal grid intervals where the margin is >= 0, with the
    interior ends refined in one vectorised root search over every branch.

    ``mfun(x)`` gives the margins of all B branches at x, shape (B, len(x));
    ``mvals`` is ``mfun(grid)``.  Returns B lists of (lo, hi, at_grid_start,
    at_grid_end)."""
    n = len(grid)
    runs, lo_br, hi_br, own_lo, own_hi = [], [], [], [], []
    for bi, mv in enumerate(mvals):
        r, lb, hb = _valid_runs(grid, mv)
        runs.append(r)
        lo_br += lb
        hi_br += hb
        own_lo += [bi] * len(lb)
        own_hi += [bi] * len(hb)
    br = np.array(lo_br + hi_br, dtype=int).reshape(-1, 2)
    owner = np.array(own_lo + own_hi, dtype=int)

    roots = vroots(_rows(mfun, owner), grid[br[:, 0]], grid[br[:, 1]], tol,
                   fa=mvals[owner, br[:, 0]], fb=mvals[owner, br[:, 1]])
    roots = _plateau_edges(mfun, roots, owner, grid[br[:, 0]], grid[br[:, 1]],
                           len(lo_br), tol)
    n_lo = len(lo_br)
    out = []
    for bi, r in enumerate(runs):
        lo_r = iter(roots[:n_lo][owner[:n_lo] == bi])
        hi_r = iter(roots[n_lo:][owner[n_lo:] == bi])
        iv = []
        for i, j in r:
            lo = grid[i] if i == 0 else float(next(lo_r))
            hi = grid[j] if j == n - 1 else float(next(hi_r))
            iv.append((lo, hi, i == 0, j == n - 1))
        out.append(iv)
    for bi, lo, hi in _short_runs(mfun, grid, mvals, tol):
        out[bi] = sorted(out[bi] + [(lo, hi, False, False)])
    return out


def _rows(mfun, owner):
    """The margin of search k's own branch at its abscissa, as :func:`vroots`
    asks: ``x`` holds one abscissa per search, repeated in blocks, and search k
    belongs to branch ``owner[k]`` of ``mfun`` (shape (B, len(x)))."""
    owner = np.asarray(owner, dtype=int)

    def f(x):
        reps = len(x) // max(len(owner), 1)
        return mfun(x)[np.tile(owner, reps), np.arange(len(x))]
    return f


def _valid_sign(m):
    """Margins with exact zeros made positive (valid), for a sign search."""
    return np.where(m == 0, np.finfo(float).tiny, m)


def _plateau_edges(mfun, roots, owner, a, b, n_lo: int, tol: float):
    """Valid-run ends where the margin is exactly 0 over a stretch.

    The root search stops where the margin is exactly 0.  Where one condition
    is 0 all along (a vertex whose edge lies along the line it touches), that
    is anywhere on the valid stretch, not at its edge.  A root with margin 0
    whose neighbour ``tol`` towards the invalid end is valid too is searched
    again for the edge of {margin >= 0} (zeros counted as valid).  Elsewhere
    the roots are returned unchanged."""
    if not roots.size:
        return roots
    rows = np.arange(roots.size)
    m0 = mfun(roots)[owner, rows]
    sus = np.nonzero(m0 == 0)[0]
    if not sus.size:
        return roots
    # invalid side: left of a run's lower end (brackets < n_lo), right of its upper
    step = np.where(sus < n_lo, -tol, tol)
    probe = np.clip(roots[sus] + step, np.minimum(a[sus], b[sus]), np.maximum(a[sus], b[sus]))
    flat = sus[mfun(probe)[owner[sus], np.arange(sus.size)] >= 0]
    if not flat.size:
        return roots
    rows_flat = _rows(mfun, owner[flat])
    inv = np.where(flat < n_lo, a[flat], b[flat])
    out = roots.copy()
    out[flat] = vroots(lambda xx: _valid_sign(rows_flat(xx)), inv, roots[flat], tol)
    return out


#: Interior samples per step of the search for short valid runs (_short_runs).
_ZOOM = 8


def _short_runs(mfun, grid, mvals, tol, max_levels: int = 40) -> list:
    """Valid runs that lie wholly between two grid points: (branch, lo, hi).

    A contact shorter than the scan step (a short chamfer, one edge of a
    finely polygonised profile) has a negative margin at both grid points
    around it.  Where the margin at both ends of a step is within reach of 0
    (at most half a step times twice the steepest slope the scan saw there),
    the step is searched: ``_ZOOM`` interior samples, then the same around the
    best of them, until a sample is valid (the run's ends are then refined to
    ``tol``), the best can no longer reach 0, or the step is shorter than
    ``tol``.  Steps that cannot hold a positive margin cost nothing more.
    """
    B, n = mvals.shape
    if n < 2:
        return []
    h = np.diff(grid)
    with np.errstate(invalid="ignore"):
        fin = np.isfinite(mvals)
        m = np.where(fin, mvals, -np.inf)
        slope = np.abs(np.diff(m, axis=1)) / h
        slope = np.where(np.isfinite(slope), slope, 0.0)
        steep = slope.copy()
        steep[:, 1:] = np.maximum(steep[:, 1:], slope[:, :-1])
        steep[:, :-1] = np.maximum(steep[:, :-1], slope[:, 1:])
        reach = np.maximum(2.0 * steep, 1.0) * h
        hi_end = np.maximum(m[:, :-1], m[:, 1:])
        cand = (m[:, :-1] < 0) & (m[:, 1:] < 0) & (hi_end > -0.5 * reach)
    bi, ki = np.nonzero(cand)
    if not bi.size:
        return []
    a = grid[ki].astype(float)
    b = grid[ki + 1].astype(float)
    a0, b0 = a.copy(), b.copy()
    c = (reach / h)[bi, ki]
    t = np.arange(1, _ZOOM + 1) / (_ZOOM + 1)
    found = np.full(bi.size, np.nan)
    live = np.ones(bi.size, dtype=bool)
    for _ in range(max_levels):
        idx = np.nonzero(live)[0]
        if not idx.size:
            break
        xs = a[idx, None] + (b - a)[idx, None] * t[None, :]
        vals = mfun(xs.ravel())[np.repeat(bi[idx], _ZOOM), np.arange(xs.size)]
        vals = np.where(np.isfinite(vals), vals, -np.inf).reshape(xs.shape)
        best = np.argmax(vals, axis=1)
        bv = vals[np.arange(idx.size), best]
        hit = bv >= 0
        found[idx[hit]] = xs[np.arange(idx.size), best][hit]
        live[idx[hit]] = False
        rest = ~hit
        r_idx = idx[rest]
        bb = best[rest]
        xr = xs[rest]
        na = np.where(bb > 0, xr[np.arange(r_idx.size), np.maximum(bb - 1, 0)], a[r_idx])
        nb = np.where(bb < _ZOOM - 1, xr[np.arange(r_idx.size), np.minimum(bb + 1, _ZOOM - 1)],
                      b[r_idx])
        a[r_idx], b[r_idx] = na, nb
        keep = (bv[rest] > -0.5 * c[r_idx] * (nb - na)) & (nb - na > tol)
        live[r_idx[~keep]] = False
    ok = np.nonzero(np.isfinite(found))[0]
    if not ok.size:
        return []
    x = found[ok]
    own = bi[ok]
    branch_margin = _rows(mfun, own)
    lo = vroots(branch_margin, a0[ok], x, tol)
    hi = vroots(branch_margin, x, b0[ok], tol)
    return [(int(o), float(l_), float(h_)) for o, l_, h_ in zip(own, lo, hi)]


def _valid_intervals(mfun, grid, mvals, tol):
    """Maximal intervals of the grid where the margin is >= 0, ends refined."""
    return _branch_intervals(lambda x: mfun(x)[None], grid, np.asarray(mvals)[None], tol)[0]


@dataclass(frozen=True)
class CurveSet:
    """All trimmed contact curves of a pair in a driver window.

    Attributes
    ----------
    curves : tuple of ContactCurve
    vertical : tuple of VerticalCurve
    n_candidates : int
        Feature pairs of compatible type.
    n_pruned : int
        Pairs removed by the broad phase.
    window : (float, float, float, float)
        (q1_lo, q1_hi, q2_lo, q2_hi).
    n_reused : int
        Feature pairs whose pieces came from a :class:`~cspace.cache.CurveCache`.
    """

    curves: tuple
    vertical: tuple
    n_candidates: int
    n_pruned: int
    window: tuple
    n_reused: int = 0


def _dep_of(feature: Feature, part_axis_key, deps) -> frozenset:
    if deps is None:
        return frozenset()
    s = set(deps.get(part_axis_key, ()))
    for k in feature.segs:
        s |= set(deps.get(k, ()))
    return frozenset(s)


def curve_pieces(pair: Pair, fa: Feature, fb: Feature, eq: str, owner: int, r: float,
                 window, accuracy: Accuracy, deps=None, periodic_q1: bool = True):
    """Trimmed curve pieces (and vertical pieces) of one feature pair."""
    L = pair.char_length
    k = _Kernel(eq, owner, float(r), fa, fb, pair.driver.axis, pair.follower.axis, L)
    q1lo, q1hi, q2lo, q2hi = window
    kind = f"{fa.kind}-{fb.kind}"
    if fa.kind == "arc" and fb.kind == "arc":
        kind += "-ext" if fa.convex and fb.convex else "-int"
    label = _label(fa, fb, pair)
    feats = (fa.key + (fa.kind,), fb.key + (fb.kind,))
    dep = _dep_of(fa, (0, "axis"), deps) | _dep_of(fb, (1, "axis"), deps)
    periodic_q2 = isinstance(pair.follower.axis, Rotation)
    if k.is_vertical():
        return [], _vertical_pieces(k, label, kind, feats, dep, window, accuracy)
    s1 = coord_scale(pair.driver.axis, L)
    step = min(accuracy.scan_step * s1, (q1hi - q1lo) / 8)
    n = max(9, int(math.ceil((q1hi - q1lo) / step)) + 1)
    grid = np.linspace(q1lo, q1hi, n)

    def margins(x):
        m, q2 = k.margins(x)
        if not periodic_q2:
            m = np.minimum(m, np.minimum(q2 - q2lo, q2hi - q2) / L)
        return m

    # the ends of every branch's valid runs are refined in one vectorised search
    out = []
    for bi, intervals in enumerate(_branch_intervals(margins, grid, margins(grid),
                                                     accuracy.root_tol * s1)):
        branch = (1 if bi == 0 else -1) if k.nbranch == 2 else 0
        for lo, hi, at_lo, at_hi in intervals:
            if hi - lo <= accuracy.root_tol * 10 * s1:
                continue
            out.append(ContactCurve(label, kind, branch, feats, dep, float(lo), float(hi), k,
                                    periodic_q2, q2lo,
                                    start_closed=not (at_lo and periodic_q1),
                                    end_closed=not (at_hi and periodic_q1)))
    return out, []


def _vertical_pieces(k: _Kernel, label, kind, feats, dep, window, accuracy):
    q1lo, q1hi, q2lo, q2hi = window
    s1, s2 = coord_scale(k.axis_a, k.scale), coord_scale(k.axis_b, k.scale)
    n = max(9, int(math.ceil((q1hi - q1lo) / (accuracy.scan_step * s1))) + 1)
    grid = np.linspace(q1lo, q1hi, n)
    res = k.vertical_residual(grid)
    roots = []
    for i in range(n - 1):
        if res[i] == 0:
            roots.append(grid[i])
        elif res[i] * res[i + 1] < 0:
            roots.append(_roots_refine(k.vertical_residual, grid[i], grid[i + 1], None,
                                       accuracy.root_tol * s1))
    out = []
    m = max(17, int(math.ceil((q2hi - q2lo) / (accuracy.scan_step * s2))) + 1)
    q2g = np.linspace(q2lo, q2hi, m)
    for r in roots:
        mv = k.conditions(np.full(m, r), q2g)
        fn = lambda y, r=r: k.conditions(np.full(np.shape(y), r), y)
        for lo, hi, _, _ in _valid_intervals(fn, q2g, mv, accuracy.root_tol * s2):
            if hi - lo > accuracy.root_tol * 10 * s2:
                out.append(VerticalCurve(label, kind, feats, dep, float(r), float(lo), float(hi), k))
    return out


def default_window(pair: Pair) -> tuple:
    """One period of each rotating coordinate; for a sliding coordinate, the range
    over which the parts can touch (from the broad-phase bounds) plus 5 % margin."""
    out = []
    for role in (0, 1):
        part = pair.parts[role]
        if isinstance(part.axis, Rotation):
            out += [0.0, TWO_PI]
            continue
        other = pair.parts[1 - role]
        e = np.array(part.axis.direction)
        # slide range: the part's projection interval must overlap the other part's
        # reach along e
        x0, y0, x1, y1 = part.bounds()
        corners = np.array([[x0, y0], [x1, y0], [x0, y1], [x1, y1]])
        proj = corners @ e
        if isinstance(other.axis, Rotation):
            c = float(np.array(other.axis.center) @ e)
            R = other.reach()
            lo, hi = c - R, c + R
        else:
            ox0, oy0, ox1, oy1 = other.bounds()
            oc = np.array([[ox0, oy0], [ox1, oy0], [ox0, oy1], [ox1, oy1]]) @ e
            lo, hi = oc.min(), oc.max()
        smin = lo - proj.max()
        smax = hi - proj.min()
        pad = 0.05 * (smax - smin)
        out += [float(smin - pad), float(smax + pad)]
    return tuple(out)


def contact_curves(pair: Pair, accuracy: Accuracy | str | None = None, *, window=None,
                   deps=None, prune: bool = True, cache=None) -> CurveSet:
    """All trimmed contact curves of a pair.

    Parameters
    ----------
    pair : Pair
    accuracy : Accuracy, preset name or None
    window : (q1_lo, q1_hi, q2_lo, q2_hi), optional
        C-space window; defaults to :func:`default_window`.  Only the q1 range asked
        for is computed.
    deps : mapping, optional
        Parameter dependencies: ``{(part, loop, seg): names, (part, "axis"): names}``
        (see :meth:`mechanisms.models.Model.dependencies`).
    prune : bool
        Apply the broad phase (off only for benchmarks).
    cache : cspace.cache.CurveCache, optional
        Reuse the pieces of feature pairs whose geometry, axes and settings are
        unchanged (bit for bit) since they were cached.
    """
    from .accuracy import as_accuracy
    acc = as_accuracy(accuracy)
    win = _check_window(pair, window)
    if prune:
        cands, pruned = feature_pairs(pair)
    else:
        cands, pruned = feature_pairs(pair, margin_rel=math.inf)[0], 0
    periodic_q1 = isinstance(pair.driver.axis, Rotation) and is_period(win[0], win[1])
    curves, vert = [], []
    reused = 0
    if cache is not None:
        L = pair.char_length
        ax = (pair.driver.axis, pair.follower.axis, pair.driver.name, pair.follower.name)
    for fa, fb, eq, owner, r in cands:
        if cache is None:
            c, v = curve_pieces(pair, fa, fb, eq, owner, r, win, acc, deps, periodic_q1)
        else:
            dep = _dep_of(fa, (0, "axis"), deps) | _dep_of(fb, (1, "axis"), deps)
            key = (fa, fb, eq, owner, float(r), ax, L, win, acc, periodic_q1, dep)
            h0 = cache.hits
            c, v = cache.get_or_compute(key, lambda fa=fa, fb=fb, eq=eq, owner=owner, r=r:
                                        curve_pieces(pair, fa, fb, eq, owner, r, win, acc,
                                                     deps, periodic_q1))
            reused += cache.hits - h0
        curves += c
        vert += v
    return CurveSet(tuple(curves), tuple(vert), len(cands) + pruned, pruned, win, reused)


#: Narrowest window (C-space metric: rad, or slide / characteristic length).
MIN_WINDOW = 1e-6
#: Widest window of a sliding coordinate, in characteristic lengths.
MAX_SLIDE_WINDOW = 1e4


def _period_tol(lo: float, hi: float) -> float:
    """Rounding allowed when ``hi - lo`` is compared with 2 pi (it grows with
    the window's distance from 0)."""
    return 1e-12 + 8 * np.finfo(float).eps * max(abs(lo), abs(hi))


def is_period(lo: float, hi: float) -> bool:
    """Whether the window [lo, hi] of a rotating coordinate is one full turn."""
    return abs(hi - lo - TWO_PI) <= _period_tol(lo, hi)


def _check_window(pair: Pair, window):
    from .argcheck import getvector
    from .errors import InputError
    if window is None:
        return default_window(pair)
    w = getvector(window, 4, "window")
    if not (w[1] > w[0] and w[3] > w[2]):
        raise InputError(f"window must be (q1_lo, q1_hi, q2_lo, q2_hi) with lo < hi, got "
                         f"{tuple(w.tolist())}", name="window", value=window)
    L = pair.char_length
    for i, part in enumerate(pair.parts):
        rot = isinstance(part.axis, Rotation)
        span = (w[2 * i + 1] - w[2 * i]) / (1.0 if rot else L)
        if span < MIN_WINDOW:
            unit = "rad" if rot else f"{pair.units or 'length units'} ({span:.3g} of the " \
                                     f"characteristic length {L:.6g})"
            raise InputError(f"window for q{i + 1} spans {w[2 * i + 1] - w[2 * i]:.3g} {unit}; "
                             f"at least {MIN_WINDOW:g} rad (or {MIN_WINDOW:g} of the "
                             f"characteristic length for a slide) is allowed", name="window",
                             value=window)
        if not rot and span > MAX_SLIDE_WINDOW:
            raise InputError(f"window for q{i + 1} spans {w[2 * i + 1] - w[2 * i]:.3g} "
                             f"{pair.units or 'length units'}, {span:.3g} characteristic "
                             f"lengths ({L:.6g}); at most {MAX_SLIDE_WINDOW:g} are allowed "
                             f"(the parts touch only within a few)", name="window",
                             value=window)
        if rot and w[2 * i + 1] - w[2 * i] > TWO_PI + _period_tol(w[2 * i], w[2 * i + 1]):
            raise InputError(f"window for rotating coordinate q{i + 1} spans "
                             f"{w[2 * i + 1] - w[2 * i]:.6g} rad; at most one period (2 pi) is "
                             "allowed", name="window", value=window)
    if isinstance(pair.follower.axis, Rotation) and not is_period(w[2], w[3]):
        raise InputError("the follower window of a rotating follower must be one full period "
                         f"(2 pi); got {w[3] - w[2]:.6g} rad", name="window", value=window)
    return tuple(float(x) for x in w)
