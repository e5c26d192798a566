"""Contact equations of one feature pair, evaluated for many variants at once.

:class:`cspace.equations.Kernel` solves the contact equation of one feature pair
of one design.  A :class:`KernelStack` holds the same equation for ``V``
variants of a design: every geometric constant (points, normals, radii, arc
sweeps, axis centres) is a ``(V, 1)`` column, so one call evaluates the curve
for all variants at ``N`` driver values and returns ``(V, N)`` arrays.  The
equations are those of :meth:`Kernel.solve` and :meth:`Kernel.conditions`, so
a stack of one variant gives the kernel's values to rounding
(``tests/cspace/batch/test_kernels.py``).  Three steps are cheaper here than
there, with the same values to rounding: a rotating follower's ``cos q2`` and
``sin q2`` come from the equation's own terms instead of the trigonometric
functions (:func:`_branch_trig`), lengths are ``sqrt(x x + y y)`` rather
than ``hypot`` (:func:`_norm`), and a segment's length is that of its ends
in its part, not re-measured after it turns; on the Geneva check list's
calls the kernel takes 1.35 to 1.4 times less time for them.

Feature geometry comes from a :class:`FeatureTable`: the contact features of
both parts of every variant, as one float array indexed by (variant, feature,
field), built once per batch.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from ..equations import Equation
from ..features import feature_by_key, feature_rows, features
from ..geometry import Rotation
from ..geom2d import wrap_pi
from . import compiled, fused
from ..tolerances import FULL_CIRCLE_SLACK, NEAR_PARALLEL, TINY

__all__ = ["FeatureTable", "KernelStack", "curve_stack", "feature_table", "stack_kernel",
           "KERNEL_VALUES", "reset_kernel_values"]

# field layout of a FeatureTable row
_P, _Q, _R, _CONVEX, _MID, _HALF, _E1, _E2, _KIND = 0, 2, 4, 5, 6, 7, 8, 10, 12
_NF = 13
_KINDS = {"vertex": 0.0, "line": 1.0, "arc": 2.0}


@dataclass(frozen=True, eq=False)
class FeatureTable:
    """Contact features of the two parts of one pair, for ``V`` variants.

    Attributes
    ----------
    keys : dict
        ``(part, loop, seg, kind) -> column`` of the nominal design's features.
    data : (V, F, 13) float
        Per variant and feature: point p (2), point q (2), radius, convex, arc
        mid angle, arc half sweep, vertex edge directions e1 (2) and e2 (2),
        kind code (model units, rad).
    present : (V, F) bool
        The variant has the feature with the nominal's kind (a vertex that is
        no longer convex, or a loop with other segments, is absent).
    axes : (V, 2, 2) float
        Per variant and part (driver, follower): the rotation centre or the
        slide direction.
    rotating : (bool, bool)
        Whether driver and follower rotate (the same for every variant).
    scale : (V,) float
        Characteristic length of each variant.
    extra : (V,) bool or None
        The variant has a feature the nominal design has not (a vertex that
        became convex: a tangent join drawn as two segments whose variant
        turns at it), which no column holds: its contacts are not the
        nominal's curves, so the batch cannot certify it (None: no row has).
    """

    keys: dict
    data: np.ndarray
    present: np.ndarray
    axes: np.ndarray
    rotating: tuple
    scale: np.ndarray
    extra: np.ndarray | None = None

    @property
    def n(self) -> int:
        return self.data.shape[0]


def _row(f) -> list:
    return [f.p[0], f.p[1], f.q[0], f.q[1], f.radius, 1.0 if f.convex else 0.0, f.mid, f.half,
            f.e1[0], f.e1[1], f.e2[0], f.e2[1], _KINDS[f.kind]]


#: Curve values :meth:`KernelStack.branch` computed in this process, per path:
#: ``fused`` (:mod:`cspace.batch.fused`), ``numpy`` (:meth:`~KernelStack.branch_numpy`:
#: a stack the fused loops do not cover, a sliding part, or the fused loops
#: off) and ``compiled`` (:mod:`cspace.batch.compiled`).  Every path gives the
#: numpy code's numbers (``compiled`` to rounding); the counts say how much of
#: a batch the fast path took (``benchmarks/bench_batch.py`` reports them).
#: :func:`reset_kernel_values` sets them to zero.
KERNEL_VALUES = {"fused": 0, "numpy": 0, "compiled": 0}


def reset_kernel_values() -> dict:
    """Set :data:`KERNEL_VALUES` to zero; returns the counts it had."""
    old = dict(KERNEL_VALUES)
    for k in KERNEL_VALUES:
        KERNEL_VALUES[k] = 0
    return old


def _axis_row(axis) -> tuple:
    return tuple(axis.center) if isinstance(axis, Rotation) else tuple(axis.direction)


def feature_table(pairs, keys=None, scale=None) -> FeatureTable:
    """The :class:`FeatureTable` of a sequence of pairs (variants of one pair).

    Parameters
    ----------
    pairs : sequence of Pair or None
        The variants; None for one that does not build (no feature present).
    keys : sequence of feature keys, optional
        The columns: ``(part, loop, seg, kind)`` keys, each read with
        :func:`cspace.features.feature_by_key`.  Default: every feature of
        the first pair that builds.
    scale : float, optional
        The characteristic length of every row; default each pair's own.
    """
    first = next((p for p in pairs if p is not None), None)
    if keys is None:
        cols = {}
        for part, idx in ((first.driver, 0), (first.follower, 1)):
            for f in features(part, idx):
                cols[f.key + (f.kind,)] = len(cols)
    else:
        cols = {k: i for i, k in enumerate(keys)}
    V, F = len(pairs), len(cols)
    data = np.zeros((V, F, _NF))
    present = np.zeros((V, F), dtype=bool)
    axes = np.zeros((V, 2, 2))
    sc = np.ones(V)
    rot = (isinstance(first.driver.axis, Rotation), isinstance(first.follower.axis, Rotation))
    extra = None
    for v, pair in enumerate(pairs):
        if pair is None:
            continue
        if keys is None:
            # every feature's numbers (feature_rows: those of features())
            for part, idx in ((pair.driver, 0), (pair.follower, 1)):
                for key, row in feature_rows(part, idx):
                    c = cols.get(key)
                    if c is not None:
                        data[v, c] = row
                        present[v, c] = True
                    else:
                        if extra is None:
                            extra = np.zeros(V, dtype=bool)
                        extra[v] = True
        else:
            for k in keys:
                f = feature_by_key(pair.driver if k[0] == 0 else pair.follower, k)
                c = None if f is None else cols.get(f.key + (f.kind,))
                if c is not None:
                    data[v, c] = _row(f)
                    present[v, c] = True
        axes[v, 0] = _axis_row(pair.driver.axis)
        axes[v, 1] = _axis_row(pair.follower.axis)
        sc[v] = pair.char_length if scale is None else scale
        if (isinstance(pair.driver.axis, Rotation), isinstance(pair.follower.axis, Rotation)) != rot:
            present[v] = False
    return FeatureTable(cols, data, present, axes, rot, sc, extra)


def curve_stack(pairs, feats: tuple, eq: str, owner: int, scale=None) -> KernelStack | None:
    """The :class:`KernelStack` of one contact curve for variant pairs, from a
    :func:`feature_table` of the curve's two features only.

    Parameters
    ----------
    pairs : sequence of Pair or None
        The variants; None for one that does not build (its row is not ``ok``).
    feats : tuple
        The curve's feature keys (``ContactCurve.features``: driver, follower).
    eq, owner
        The curve's equation type and point owner.
    scale : float, optional
        The characteristic length every variant's margins are measured in (as
        :class:`cspace.equations.Kernel` takes it); default each pair's own.

    Returns None when no pair builds.
    """
    if all(p is None for p in pairs):
        return None
    st = stack_kernel(feature_table(pairs, feats, scale), feats, eq, owner)
    # the structural flags are read from the first row: a row whose features
    # changed convexity is not the same curve
    same = ((st.fp[:, _CONVEX] == st.fp[0, _CONVEX]) & (st.ft[:, _CONVEX] == st.ft[0, _CONVEX]))
    return replace(st, ok=st.ok & same)


#: The per-variant fields of a :class:`KernelStack`.
_ROW_FIELDS = ("ok", "r", "fp", "ft", "axis_a", "axis_b", "scale")


def _col(a) -> np.ndarray:
    return np.asarray(a, dtype=float)[:, None]


@dataclass(frozen=True, eq=False)
class KernelStack:
    """One contact equation (feature pair, equation type, point owner) for ``V``
    variants.  Geometric constants are ``(V, 1)`` columns.

    ``ok`` (V,) marks the variants whose features exist with the nominal's kinds
    and give the same equation type; elsewhere the values are meaningless.
    """

    eq: str
    owner: int
    rotating: tuple
    ok: np.ndarray
    r: np.ndarray
    fp: np.ndarray       # (V, 13) point feature rows
    ft: np.ndarray       # (V, 13) target feature rows
    fp_kind: str
    ft_kind: str
    axis_a: np.ndarray   # (V, 2) driver centre / direction
    axis_b: np.ndarray   # (V, 2) follower centre / direction
    scale: np.ndarray    # (V, 1)

    def take(self, rows) -> "KernelStack":
        """The stack of some of its variants (``rows``: indices or a mask)."""
        return replace(self, **{f: getattr(self, f)[rows] for f in _ROW_FIELDS})

    @functools.cached_property
    def packed(self) -> np.ndarray:
        """Every per-variant field in one (V, 33) float array, in the order of
        ``_ROW_FIELDS`` (``ok`` as 1.0 or 0.0): rows of several stacks are
        gathered with one index and one concatenation
        (:meth:`from_packed`)."""
        V = self.ok.shape[0]
        return np.ascontiguousarray(np.hstack(
            [np.asarray(getattr(self, f), dtype=float).reshape(V, -1) for f in _ROW_FIELDS]))

    def from_packed(self, packed) -> "KernelStack":
        """This stack's equation with the variants of ``packed`` (rows of
        :attr:`packed` arrays, of this stack or another of the same
        equation): the same numbers as the fields it was packed from."""
        f = np.ascontiguousarray(packed, dtype=float)
        out = replace(self, ok=f[:, 0] != 0.0, r=f[:, 1:2], fp=f[:, 2:15], ft=f[:, 15:28],
                      axis_a=f[:, 28:30], axis_b=f[:, 30:32], scale=f[:, 32:33])
        out.__dict__["packed"] = f       # its own packing (cached_property's slot)
        return out

    @property
    def nbranch(self) -> int:
        return 2 if self.rotating[1] or self.eq == Equation.POINT_CIRCLE else 1

    # ------------------------------------------------------------ placement
    def _trig(self, part: int, q):
        """(q, cos q, sin q) of a rotating part's coordinates (computed once per
        call and shared by every placement), or (q, None, None)."""
        if self.rotating[part]:
            return q, np.cos(q), np.sin(q)
        return q, None, None

    def _place(self, part: int, t, pt):
        """World (x, y) of body points ``pt`` ((V, 2) columns) at coordinates
        ``t`` (from :meth:`_trig`) of ``part`` (0 driver, 1 follower)."""
        q, cq, sq = t
        px, py = pt[:, 0:1], pt[:, 1:2]
        ax = self.axis_a if part == 0 else self.axis_b
        if cq is not None:
            cx, cy = ax[:, 0:1], ax[:, 1:2]
            x, y = px - cx, py - cy
            # (cx + cq x) - sq y and (cy + sq x) + cq y, in place
            wx, wy = cq * x, sq * x
            wx += cx
            wx -= sq * y
            wy += cy
            wy += cq * y
            return wx, wy
        return px + q * ax[:, 0:1], py + q * ax[:, 1:2]

    @staticmethod
    def _turn(t, vx, vy):
        q, cq, sq = t
        if cq is not None:
            wx, wy = cq * vx, sq * vx
            wx -= sq * vy
            wy += cq * vy
            return wx, wy
        shape = np.broadcast(q, vx).shape
        return np.broadcast_to(vx, shape), np.broadcast_to(vy, shape)

    def _angle(self, part: int, q):
        return q if self.rotating[part] else 0.0

    @staticmethod
    def _normal(f):
        """Unit free-side normal (x, y) columns of line rows f."""
        dx, dy = f[:, _Q:_Q + 1] - f[:, _P:_P + 1], f[:, _Q + 1:_Q + 2] - f[:, _P + 1:_P + 2]
        h = np.hypot(dx, dy)
        h = np.where(h > 0, h, 1.0)
        return dy / h, -dx / h

    # ------------------------------------------------------------ solve
    def solve(self, q1):
        """q2 of every branch, (nbranch, V, N), and the existence condition
        (V, N) (>= 0 where real), in the units of :meth:`Kernel.solve`."""
        q1 = np.asarray(q1, dtype=float)
        t1 = self._trig(0, q1)
        if self.rotating[1]:
            A, B, g, R, alpha, c, acs = self._rotating(t1)
            return np.stack([alpha + acs, alpha - acs]), self._exists(R, g)
        return self._sliding(t1)

    def _rotating(self, t1):
        """A rotating follower's equation terms at ``t1`` (:meth:`_turning`,
        :meth:`_polar`) and the branches' offset ``arccos(c)`` from alpha."""
        A, B, g = self._turning(t1)
        R, alpha, c = self._polar(A, B, g)
        return A, B, g, R, alpha, c, np.arccos(c)

    def _turning(self, t1):
        """A, B, g (V, N) of a rotating follower's equation ``A cos q2 + B sin q2
        + g = 0`` at the driver coordinates ``t1`` (:meth:`_trig`)."""
        fp, ft = self.fp, self.ft
        ob = self.axis_b
        ox, oy = ob[:, 0:1], ob[:, 1:2]
        r = self.r
        if self.owner == 0:
            wx, wy = self._place(0, t1, fp[:, _P:_P + 2])
            wx, wy = wx - ox, wy - oy
            if self.eq == Equation.POINT_LINE:
                nx, ny = self._normal(ft)
                lx, ly = ft[:, _P:_P + 1] - ox, ft[:, _P + 1:_P + 2] - oy
                A = nx * wx + ny * wy
                B = nx * wy - ny * wx
                g = np.broadcast_to(-((nx * lx + ny * ly) + r), A.shape)
            else:
                cx, cy = ft[:, _P:_P + 1] - ox, ft[:, _P + 1:_P + 2] - oy
                A = -2 * (cx * wx + cy * wy)
                B = -2 * (cx * wy - cy * wx)
                g = (wx ** 2 + wy ** 2) + (cx * cx + cy * cy) - r ** 2
            return A, B, g
        px, py = fp[:, _P:_P + 1] - ox, fp[:, _P + 1:_P + 2] - oy
        if self.eq == Equation.POINT_LINE:
            vx, vy = self._normal(ft)
            nx, ny = self._turn(t1, vx, vy)
            lx, ly = self._place(0, t1, ft[:, _P:_P + 2])
            A = nx * px + ny * py
            B = px * ny - py * nx
            g = ((ox - lx) * nx + (oy - ly) * ny) - r
        else:
            mx, my = self._place(0, t1, ft[:, _P:_P + 2])
            mx, my = ox - mx, oy - my
            A = 2 * (px * mx + py * my)
            B = 2 * (px * my - py * mx)
            g = (mx ** 2 + my ** 2) + (px * px + py * py) - r ** 2
        return A, B, g

    @staticmethod
    def _polar(A, B, g):
        """``R = |(A, B)|``, ``alpha = atan2(B, A)`` and the cosine ``c`` of the
        branches' offset from alpha, ``-g / R`` clipped to [-1, 1]: the
        branches are ``alpha +- arccos(c)``."""
        R = _norm(A, B)
        alpha = np.arctan2(B, A)
        Rs = np.where(R > 0, R, 1.0)
        return R, alpha, np.minimum(np.maximum(-g / Rs, -1.0), 1.0)

    def _exists(self, R, g):
        """The existence condition of :meth:`solve`: ``R - |g|``, over ``2 L``
        for a point-circle equation (whose terms are squared lengths), over
        ``L``."""
        L = self.scale
        f = 1.0 / (2 * L * L) if self.eq == Equation.POINT_CIRCLE else 1.0 / L
        return (R - np.abs(g)) * f

    def _sliding(self, t1):
        """:meth:`solve` of a sliding follower."""
        fp, ft = self.fp, self.ft
        L = self.scale
        ex, ey = self.axis_b[:, 0:1], self.axis_b[:, 1:2]
        r = self.r
        if self.owner == 0 and self.eq == Equation.POINT_LINE:
            nx, ny = self._normal(ft)
            wx, wy = self._place(0, t1, fp[:, _P:_P + 2])
            dx, dy = wx - ft[:, _P:_P + 1], wy - ft[:, _P + 1:_P + 2]
            ne = nx * ex + ny * ey
            ne = np.where(ne != 0, ne, TINY)
            s = (dx * nx + dy * ny - r) / ne
            return s[None], np.ones_like(s)
        if self.owner == 1 and self.eq == Equation.POINT_LINE:
            vx, vy = self._normal(ft)
            nx, ny = self._turn(t1, vx, vy)
            lx, ly = self._place(0, t1, ft[:, _P:_P + 2])
            ne = nx * ex + ny * ey
            ne_s = np.where(np.abs(ne) > TINY, ne, TINY)
            s = (r - ((fp[:, _P:_P + 1] - lx) * nx + (fp[:, _P + 1:_P + 2] - ly) * ny)) / ne_s
            return s[None], np.abs(ne) - NEAR_PARALLEL
        if self.owner == 0:
            wx, wy = self._place(0, t1, fp[:, _P:_P + 2])
            wx, wy = wx - ft[:, _P:_P + 1], wy - ft[:, _P + 1:_P + 2]
        else:
            wx, wy = self._place(0, t1, ft[:, _P:_P + 2])
            wx, wy = wx - fp[:, _P:_P + 1], wy - fp[:, _P + 1:_P + 2]
        ew = wx * ex + wy * ey
        cr = wx * ey - wy * ex
        disc = r ** 2 - cr ** 2
        sq = np.sqrt(np.where(disc > 0, disc, 0.0))
        return np.stack([ew + sq, ew - sq]), (r - np.abs(cr)) / L

    # ------------------------------------------------------------ validity
    def _arc_margin(self, f, kind_is_arc: bool, dx, dy, part: int, q):
        if not kind_is_arc:
            return None
        half, mid = f[:, _HALF:_HALF + 1], f[:, _MID:_MID + 1]
        ang = np.arctan2(dy, dx) - self._angle(part, q)
        m = half - np.abs(wrap_pi(ang - mid))
        full = half >= math.pi - FULL_CIRCLE_SLACK
        return np.where(full, 1.0, m) if full.any() else m

    def conditions(self, q1, q2, t1=None, t2=None):
        """Smallest validity margin (V, N) of the solutions q2 (V, N) at q1
        (``t1``, ``t2``: their :meth:`_trig`, when known)."""
        q1 = np.asarray(q1, dtype=float)
        L = self.scale
        qs = (q1, q2)
        ts = (self._trig(0, q1) if t1 is None else t1, self._trig(1, q2) if t2 is None else t2)
        fp, ft = self.fp, self.ft
        po, to = self.owner, 1 - self.owner
        Px, Py = self._place(po, ts[po], fp[:, _P:_P + 2])
        margins = []
        if self.eq == Equation.POINT_LINE:
            vx, vy = self._normal(ft)
            nx, ny = self._turn(ts[to], vx, vy)
            l0x, l0y = self._place(to, ts[to], ft[:, _P:_P + 2])
            if self.fp_kind == "arc":
                Xx, Xy = Px - self.r * nx, Py - self.r * ny
            else:
                Xx, Xy = Px, Py
            # the segment's direction turns with its part; its length does not
            bx, by = ft[:, _Q:_Q + 1] - ft[:, _P:_P + 1], ft[:, _Q + 1:_Q + 2] - ft[:, _P + 1:_P + 2]
            dx, dy = self._turn(ts[to], bx, by)
            ln = _norm(bx, by)
            # the foot's place along the segment from either end, over L
            t = ((Xx - l0x) * dx + (Xy - l0y) * dy) * (1.0 / (ln * L))
            margins += [t, ln / L - t]
            if self.fp_kind == "arc":
                margins.append(self._arc_margin(fp, True, -nx, -ny, po, qs[po]))
            fx, fy = nx, ny
        else:
            Cx, Cy = self._place(to, ts[to], ft[:, _P:_P + 2])
            ux, uy = Px - Cx, Py - Cy
            un = _norm(ux, uy)
            inv = 1.0 / np.where(un > 0, un, 1.0)
            ux, uy = ux * inv, uy * inv
            p_concave = self.fp_kind == "arc" and self._flag(fp, _CONVEX) == 0.0
            ft_convex = self._flag(ft, _CONVEX) == 1.0
            sc = -1.0 if p_concave else 1.0
            margins.append(self._arc_margin(ft, True, sc * ux, sc * uy, to, qs[to]))
            if self.fp_kind == "arc":
                sp = -1.0 if (p_concave or ft_convex) else 1.0
                margins.append(self._arc_margin(fp, True, sp * ux, sp * uy, po, qs[po]))
            sf = 1.0 if ft_convex else -1.0
            fx, fy = sf * ux, sf * uy
        if self.fp_kind == "vertex":
            for e in (_E1, _E2):
                ex, ey = self._turn(ts[po], fp[:, e:e + 1], fp[:, e + 1:e + 2])
                margins.append(ex * fx + ey * fy)
        out = margins[0]
        for m in margins[1:]:
            out = np.minimum(out, m)
        return out

    @staticmethod
    def _flag(f, field) -> float:
        """A structural flag (convexity), the same for every valid variant: the
        first row's value."""
        return float(f[0, field])

    def branch(self, q1, bi: int, window=None):
        """q2 (V, N) of branch index ``bi`` and its validity margin (V, N) (the
        margins of :meth:`cspace.equations.Kernel.margin`; with ``window``, the
        follower-window limits of a sliding follower too).  Runs
        :meth:`branch_numpy`, or the compiled loop of
        :mod:`cspace.batch.compiled` when that is enabled; ``q1`` is (N,)
        or one value per variant (V, 1)."""
        if compiled.ENABLED:
            path = "compiled"
            out = compiled.branch(self, q1, bi, window)
        elif fused.ENABLED and np.ndim(q1) in (1, 2) and fused.supports(self):
            path = "fused"
            out = fused.branch(self, q1, bi)
        else:
            path = "numpy"
            out = self.branch_numpy(q1, bi, window)
        KERNEL_VALUES[path] += out[0].size
        return out

    def branch_numpy(self, q1, bi: int, window=None):
        """:meth:`branch` in numpy: the reference the compiled loop follows.

        A rotating follower's ``cos q2`` and ``sin q2``, which the validity
        conditions place the follower's features with, come from the
        equation's own terms (``q2 = alpha +- arccos(c)``: ``cos alpha = A /
        R``, ``cos(arccos c) = c``) instead of the trigonometric functions
        of q2 (the same values to rounding, without the two slowest array
        operations of a call)."""
        q1 = np.asarray(q1, dtype=float)
        t1 = self._trig(0, q1)
        if self.rotating[1]:
            A, B, g, R, alpha, c, acs = self._rotating(t1)
            q = alpha + acs if bi == 0 else alpha - acs
            ex = self._exists(R, g)
            t2 = (q,) + _branch_trig(A, B, R, c, bi)
        else:
            q2, ex = self._sliding(t1)
            q, t2 = q2[bi], None
        m = np.minimum(ex, self.conditions(q1, q, t1, t2))
        if window is not None and not self.rotating[1]:
            m = np.minimum(m, np.minimum(q - window[2], window[3] - q) / self.scale)
        return q, m


def _norm(x, y):
    """``|(x, y)|`` of arrays: ``sqrt(x x + y y)`` (the coordinates of a
    mechanism are far from overflow; ``np.hypot``, which guards against it, is
    four times slower)."""
    return np.sqrt(x * x + y * y)


def _branch_trig(A, B, R, c, bi: int) -> tuple:
    """``cos q2`` and ``sin q2`` of branch ``bi`` of ``A cos q2 + B sin q2 + g
    = 0``, ``q2 = alpha +- arccos(c)`` (:meth:`KernelStack._polar`):
    ``(cos alpha, sin alpha) = (A, B) / R`` ((1, 0) where ``R = 0``, as
    ``atan2(0, 0) = 0``), ``cos(arccos c) = c``, ``sin(arccos c) = sqrt((1 -
    c)(1 + c))`` (the product keeps its digits where ``c`` is near +-1, a
    tangency)."""
    pos = R > 0
    inv = 1.0 / np.where(pos, R, 1.0)
    ca, sa = A * inv, B * inv
    if not pos.all():
        ca[~pos], sa[~pos] = 1.0, 0.0
    s = 1.0 - c
    s *= 1.0 + c
    np.sqrt(s, out=s)
    cc, ss = ca * c, sa * s
    if bi == 0:
        cc -= ss
        sa *= c
        ca *= s
        sa += ca
    else:
        cc += ss
        sa *= c
        ca *= s
        sa -= ca
    return cc, sa


def stack_kernel(table: FeatureTable, feats: tuple, eq: str, owner: int) -> KernelStack:
    """The :class:`KernelStack` of the curve between features ``feats`` (the
    ``ContactCurve.features`` keys) for every variant of ``table``."""
    ca, cb = table.keys[feats[0]], table.keys[feats[1]]
    fa, fb = table.data[:, ca], table.data[:, cb]
    ok = table.present[:, ca] & table.present[:, cb]
    ka, kb = feats[0][3], feats[1][3]
    # the equation's radius and type, per variant (the rule of equations.equation_types)
    ra, rb = fa[:, _R], fb[:, _R]
    cva, cvb = fa[:, _CONVEX] == 1.0, fb[:, _CONVEX] == 1.0
    r = _radius(ka, kb, ra, rb, cva, cvb, eq, owner, ok)
    ok = ok & np.isfinite(r)
    if ka == "arc" and kb == "arc":
        # convexity decides the equation: a variant whose arcs changed it is not
        # the same curve
        ok = ok & (cva == cva[0]) & (cvb == cvb[0])
    fp, ft = (fa, fb) if owner == 0 else (fb, fa)
    kp, kt = (ka, kb) if owner == 0 else (kb, ka)
    return KernelStack(eq, owner, table.rotating, ok, _col(np.where(np.isfinite(r), r, 0.0)),
                       fp, ft, kp, kt, table.axes[:, 0], table.axes[:, 1], _col(table.scale))


def _radius(ka, kb, ra, rb, cva, cvb, eq, owner, ok):
    """Per-variant ``r`` of the equation (``equations.equation_types``); NaN where the
    variant's features give another equation."""
    r = np.full(ra.shape, np.nan)
    if ka == "vertex" and kb == "line" or ka == "line" and kb == "vertex":
        r[:] = 0.0
    elif ka == "vertex" and kb == "arc":
        r[:] = rb
    elif ka == "arc" and kb == "vertex":
        r[:] = ra
    elif ka == "arc" and kb == "line":
        r = np.where(cva, ra, np.nan)
    elif ka == "line" and kb == "arc":
        r = np.where(cvb, rb, np.nan)
    elif ka == "arc" and kb == "arc":
        r = np.where(cva & cvb, ra + rb,
                     np.where(cva & ~cvb & (rb > ra), rb - ra,
                              np.where(cvb & ~cva & (ra > rb), ra - rb, np.nan)))
    return np.where(ok, r, np.nan)
