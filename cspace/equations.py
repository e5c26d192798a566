"""The closed-form contact equations of a feature pair.

Every planar contact between a vertex, line or arc of the driver and a vertex,
line or arc of the follower reduces to one of two equations
(:class:`Equation`) between a *point* P (a vertex, or the centre of an arc) on
one part and a *target* on the other:

* point-line:   n . (P - L0) = r     (n: the line's free-side normal; r: 0 for a
  vertex, the radius for a convex arc)
* point-circle: |P - C| = rho        (rho: the target radius, plus or minus the
  point's arc radius for external or internal arc-arc contact)

For a rotating follower the equation is ``A(q1) cos q2 + B(q1) sin q2 + g(q1) = 0``
with two branches ``q2 = atan2(B, A) +/- arccos(-g / hypot(A, B))``; for a
translating follower it is linear (point-line) or quadratic (point-circle) in the
slide, solved explicitly.  A solution is a real contact only where the contact
point lies inside both features and the vertex's material cone lies on the free
side of the other feature (the kernel's validity margin).
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass

import numpy as np

from .features import Feature, free_normal
from .geom2d import wrap_pi
from .geometry import Rotation, Translation, place_points
from .tolerances import FULL_CIRCLE_SLACK, NEAR_PARALLEL, TINY

__all__ = ["Equation"]


#: A contact does not depend on q2 (a vertical curve, ``Kernel.is_vertical``)
#: when its point lies this close to the follower's rotation centre (relative
#: to the characteristic length), or its line this close to parallel to the
#: slide (the sine of the angle).
VERTICAL_REL = 1e-12



class Equation(str, enum.Enum):
    """The two closed-form contact equations a kernel solves.

    A ``str`` enum: a member equals (and hashes as) its value, so ``"pl"`` and
    ``Equation.POINT_LINE`` are interchangeable where a tag was stored."""

    POINT_LINE = "pl"      #: a point (or an arc's centre) at offset r from a line
    POINT_CIRCLE = "pc"    #: a point (or an arc's centre) at distance rho from a centre

    __hash__ = str.__hash__

    def __str__(self) -> str:
        return self.value


def equation_types(fa: Feature, fb: Feature):
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
class Kernel:
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
        tol = VERTICAL_REL * self.scale
        if isinstance(self.axis_b, Rotation):
            ob = np.array(self.axis_b.center)
            if self.owner == 0:
                return self.eq == Equation.POINT_CIRCLE and np.hypot(*(np.array(self.ft.p) - ob)) <= tol
            return np.hypot(*(np.array(self.fp.p) - ob)) <= tol
        e = np.array(self.axis_b.direction)
        if self.owner == 0 and self.eq == Equation.POINT_LINE:
            return abs(float(np.dot(free_normal(self.ft), e))) <= VERTICAL_REL
        if self.owner == 1 and self.eq == Equation.POINT_LINE and isinstance(self.axis_a, Translation):
            return abs(float(np.dot(free_normal(self.ft), e))) <= VERTICAL_REL
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
                    n = free_normal(ft)
                    l = np.array(ft.p) - ob
                    return ("r0l", ob, n, -(float(n @ l) + self.r))
                c = np.array(ft.p) - ob
                return ("r0c", ob, c, float(c @ c), self.r ** 2)
            p = np.array(fp.p) - ob
            if self.eq == Equation.POINT_LINE:
                return ("r1l", ob, p, free_normal(ft))
            return ("r1c", ob, p, float(p @ p), self.r ** 2)
        e = np.array(ax_b.direction)
        if self.owner == 0:
            if self.eq == Equation.POINT_LINE:
                n = free_normal(ft)
                ne = float(n @ e)
                return ("t0l", e, n, np.array(ft.p), ne if ne != 0 else TINY)
            return ("t0c", e, np.array(ft.p))
        if self.eq == Equation.POINT_LINE:
            return ("t1l", e, free_normal(ft), np.array(fp.p))
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
            ne_s = np.where(np.abs(ne) > TINY, ne, TINY)
            s = (self.r - ((k[3] - lw) * nw).sum(1)) / ne_s
            return s[None, :], np.abs(ne) - NEAR_PARALLEL
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
            n = _turn(axes[to], qs[to], free_normal(ft))
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
        if f.half >= math.pi - FULL_CIRCLE_SLACK:
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
        n = free_normal(self.ft)
        if self.owner == 0:
            pw = _place(self.axis_a, q1, self.fp.p)
            return (_dot(pw - np.array(self.ft.p), n) - self.r) / self.scale
        # the follower's point against a line of a sliding driver, the line
        # parallel to the follower's slide: the follower's position does not
        # change the distance, the driver's does
        p0 = np.array(_place(self.axis_b, np.zeros(1), self.fp.p)[0])
        lw = _place(self.axis_a, q1, self.ft.p)
        return (_dot(p0[None, :] - lw, n) - self.r) / self.scale
