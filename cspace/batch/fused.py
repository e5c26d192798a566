"""The batched contact kernel of a turning driver and a turning follower, its
arithmetic fused into compiled loops (numba), the same numbers bit for bit as
:meth:`cspace.batch.kernels.KernelStack.branch_numpy`.

Written with numpy, each of the kernel's some 60 arithmetic operations makes
a temporary ``(V, N)`` array: on the Geneva pair a curve evaluation costs 100
to 160 ns a value, most of it memory traffic, where its trigonometric
functions cost some 10 (numpy's vectorised ``arctan2`` and ``arccos``).
Here the arithmetic runs in three compiled loops, one pass over the values
each, and the trigonometric functions between them stay numpy's, on whole
arrays:

1. the equation's terms ``A cos q2 + B sin q2 + g = 0``, ``R = |(A, B)|``
   and the clipped cosine ``c`` (:func:`_terms`); then numpy's
   ``alpha = arctan2(B, A)`` and ``arccos(c)``;
2. the branch ``q2``, ``cos q2`` and ``sin q2`` from the terms, the
   existence condition and the validity margins without an arc's angle
   (:func:`_margins_for`: one loop per equation type, point owner and
   point kind, whose flags are constants), and the directions whose angles
   the arcs' margins need; then numpy's ``arctan2`` of those;
3. the arcs' angular margins (:func:`_arc_margins`).

Every array a loop reads or writes is one contiguous ``(V, N)`` block, and
the second stage's flags are constants of each of its eight loops: so the
loops over the values vectorise (twice as fast as with broadcast inputs and
the flags read at run time), and each loop has one compiled layout.

Every operation is the numpy code's, in its order, on the same operands:
IEEE arithmetic and ``sqrt`` give the same bits (numba does not contract a
product and a sum into one rounding without ``fastmath``), and the
trigonometric functions are the same calls.  ``min`` keeps numpy's rule (a
NaN wins).  ``tests/cspace/batch/test_fused.py`` checks the bits on every
curve of the built-in models and on random stacks.

It covers the equations of a turning driver and follower (a Geneva pair, an
indexing cam): point-circle and point-line, either part owning the point,
vertex and arc points.  Others (a sliding part) run the numpy code.  numba
is a dependency; without it (or with ``CSPACE_FUSED=0``) everything runs the
numpy code.  Its code is cached on disk (``cache=True``): the first use
after an installation compiles it (about 6 s for all the loops; a process
pool's workers do it while the caller computes its reference), and a
process loads it in about 0.6 s.
"""

from __future__ import annotations

import functools
import math
import os

import numpy as np

from ..equations import Equation
from ..tolerances import FULL_CIRCLE_SLACK

__all__ = ["AVAILABLE", "ENABLED", "supports", "branch"]

try:  # pragma: no cover - exercised by whichever the environment has
    import numba
except ImportError:  # pragma: no cover
    numba = None

#: numba can be imported.
AVAILABLE = numba is not None

#: Whether :meth:`~cspace.batch.kernels.KernelStack.branch` runs the fused
#: loops where they apply (numba importable, and not turned off with
#: ``CSPACE_FUSED=0``).
ENABLED = AVAILABLE and os.environ.get("CSPACE_FUSED", "1") != "0"

# feature row fields (cspace.batch.kernels)
_P, _Q, _R, _CONVEX, _MID, _HALF, _E1, _E2 = 0, 2, 4, 5, 6, 7, 8, 10
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_FULL = math.pi - FULL_CIRCLE_SLACK


def supports(stack) -> bool:
    """Whether the fused loops evaluate ``stack``: a turning driver and
    follower, a point-circle or point-line equation, a vertex or arc point."""
    return (ENABLED and stack.rotating[0] and stack.rotating[1]
            and stack.eq in (Equation.POINT_CIRCLE, Equation.POINT_LINE)
            and stack.fp_kind in ("vertex", "arc")
            and stack.ft_kind == ("arc" if stack.eq == Equation.POINT_CIRCLE else "line"))


def _jit(f):
    return numba.njit(cache=True, nogil=True)(f) if AVAILABLE else f



@_jit
def _min(a, b):
    # numpy's minimum: a NaN wins
    return a if (a <= b or a != a) else b


@_jit
def _max(a, b):
    return a if (a >= b or a != a) else b


@_jit
def _wrap_pi(a):
    # cspace.geom2d.wrap_pi of one value: (a + pi) in [0, 2 pi) less pi
    x = a + _PI
    if 0.0 <= x and x < _TWO_PI:
        return x - _PI
    r = x if (-_TWO_PI < x and x < _TWO_PI) else np.fmod(x, _TWO_PI)
    if r < 0:
        r = r + _TWO_PI
    return r - _PI


@_jit
def _placed(c, s, px, py, ax, ay):
    """A body point (px, py) of a part turned by (cos, sin) = (c, s) about its
    centre (ax, ay) (KernelStack._place, the same operations)."""
    x, y = px - ax, py - ay
    wx = c * x
    wx = wx + ax
    wx = wx - s * y
    wy = s * x
    wy = wy + ay
    wy = wy + c * y
    return wx, wy


@_jit
def _turned(c, s, vx, vy):
    """A body direction turned by (c, s) (KernelStack._turn)."""
    wx = c * vx
    wx = wx - s * vy
    wy = s * vx
    wy = wy + c * vy
    return wx, wy


@_jit
def _terms(pc, owner, K, cq1, sq1, A, B, g, R, c):
    """Stage 1: A, B, g of ``A cos q2 + B sin q2 + g = 0``, R and the clipped
    cosine c (KernelStack._turning, _polar)."""
    V, N = A.shape
    for v in range(V):
        ax, ay, ox, oy, rr = K[v, 0], K[v, 1], K[v, 2], K[v, 3], K[v, 4]
        fpx, fpy, ftx, fty = K[v, 5], K[v, 6], K[v, 7], K[v, 8]
        nx0, ny0 = K[v, 9], K[v, 10]
        for j in range(N):
            cq, sq = cq1[v, j], sq1[v, j]
            if owner == 0:
                # the point on the driver, placed
                wx, wy = _placed(cq, sq, fpx, fpy, ax, ay)
                wx, wy = wx - ox, wy - oy
                if pc:
                    cx, cy = ftx - ox, fty - oy
                    a_ = -2 * (cx * wx + cy * wy)
                    b_ = -2 * (cx * wy - cy * wx)
                    g_ = (wx * wx + wy * wy) + (cx * cx + cy * cy) - rr * rr
                else:
                    lx, ly = ftx - ox, fty - oy
                    a_ = nx0 * wx + ny0 * wy
                    b_ = nx0 * wy - ny0 * wx
                    g_ = -((nx0 * lx + ny0 * ly) + rr)
            else:
                px, py = fpx - ox, fpy - oy
                # the target's point on the driver, placed
                mx, my = _placed(cq, sq, ftx, fty, ax, ay)
                if pc:
                    mx, my = ox - mx, oy - my
                    a_ = 2 * (px * mx + py * my)
                    b_ = 2 * (px * my - py * mx)
                    g_ = (mx * mx + my * my) + (px * px + py * py) - rr * rr
                else:
                    nx, ny = _turned(cq, sq, nx0, ny0)
                    a_ = nx * px + ny * py
                    b_ = px * ny - py * nx
                    g_ = ((ox - mx) * nx + (oy - my) * ny) - rr
            r_ = math.sqrt(a_ * a_ + b_ * b_)
            rs = r_ if r_ > 0 else 1.0
            A[v, j], B[v, j], g[v, j], R[v, j] = a_, b_, g_, r_
            c[v, j] = _min(_max(-g_ / rs, -1.0), 1.0)


@functools.lru_cache(maxsize=None)
def _margins_for(pc: bool, owner: int, fp_arc: bool):
    """Stage 2 compiled for one equation type (``pc``: point-circle, else
    point-line), point owner and point kind (``fp_arc``: an arc point, else a
    vertex): the branch q2, its cos and sin from the terms
    (kernels._branch_trig), the existence condition and every validity
    margin but the arcs' angular ones (KernelStack.conditions), and the
    directions whose angles those need.  The three flags are constants of
    each compiled loop, so its branches are pruned and the loop over the
    values vectorises: some twice as fast as with the flags read at run time,
    the same operations and so the same bits.  Each of the eight loops is
    compiled on its first use after an installation and cached on disk."""

    def margins(bi, flags, K, q1, cq1, sq1, A, B, g, R, c, alpha, acs, q_out, m_out, d1x,
                d1y, d2x, d2y):
        V, N = A.shape
        p_concave, ft_convex = flags[0], flags[1]
        for v in range(V):
            ax, ay, ox, oy, rr = K[v, 0], K[v, 1], K[v, 2], K[v, 3], K[v, 4]
            fpx, fpy, ftx, fty = K[v, 5], K[v, 6], K[v, 7], K[v, 8]
            nx0, ny0 = K[v, 9], K[v, 10]
            exf = K[v, 11]
            e1x, e1y, e2x, e2y = K[v, 12], K[v, 13], K[v, 14], K[v, 15]
            bx, by, inv_lnl, ln_l = K[v, 16], K[v, 17], K[v, 18], K[v, 19]
            for j in range(N):
                a_, b_, r_, cc_ = A[v, j], B[v, j], R[v, j], c[v, j]
                q = alpha[v, j] + acs[v, j] if bi == 0 else alpha[v, j] - acs[v, j]
                ex = (r_ - abs(g[v, j])) * exf
                # cos q2, sin q2 (kernels._branch_trig)
                if r_ > 0:
                    inv = 1.0 / r_
                    ca, sa = a_ * inv, b_ * inv
                else:
                    ca, sa = 1.0, 0.0
                s = 1.0 - cc_
                s = s * (1.0 + cc_)
                s = math.sqrt(s)
                if bi == 0:
                    c2 = ca * cc_ - sa * s
                    s2 = sa * cc_ + ca * s
                else:
                    c2 = ca * cc_ + sa * s
                    s2 = sa * cc_ - ca * s
                cq, sq = cq1[v, j], sq1[v, j]
                # the parts' placements: (cos, sin) and centre of each part
                if owner == 0:
                    pc_, ps_, pax, pay = cq, sq, ax, ay         # the point's part
                    tc_, ts_, tax, tay = c2, s2, ox, oy         # the target's part
                else:
                    pc_, ps_, pax, pay = c2, s2, ox, oy
                    tc_, ts_, tax, tay = cq, sq, ax, ay
                Px, Py = _placed(pc_, ps_, fpx, fpy, pax, pay)
                m = 0.0
                if pc:
                    Cx, Cy = _placed(tc_, ts_, ftx, fty, tax, tay)
                    ux, uy = Px - Cx, Py - Cy
                    un = math.sqrt(ux * ux + uy * uy)
                    inv = 1.0 / (un if un > 0 else 1.0)
                    ux, uy = ux * inv, uy * inv
                    sc = -1.0 if p_concave else 1.0
                    d1x[v, j], d1y[v, j] = sc * ux, sc * uy
                    if fp_arc:
                        sp = -1.0 if (p_concave or ft_convex) else 1.0
                        d2x[v, j], d2y[v, j] = sp * ux, sp * uy
                    sf = 1.0 if ft_convex else -1.0
                    fx, fy = sf * ux, sf * uy
                    have = False
                else:
                    nx, ny = _turned(tc_, ts_, nx0, ny0)
                    l0x, l0y = _placed(tc_, ts_, ftx, fty, tax, tay)
                    if fp_arc:
                        Xx, Xy = Px - rr * nx, Py - rr * ny
                    else:
                        Xx, Xy = Px, Py
                    dx, dy = _turned(tc_, ts_, bx, by)
                    t = ((Xx - l0x) * dx + (Xy - l0y) * dy) * inv_lnl
                    m = _min(t, ln_l - t)
                    have = True
                    if fp_arc:
                        d2x[v, j], d2y[v, j] = -nx, -ny
                    fx, fy = nx, ny
                if not fp_arc:
                    # a vertex's edges, turned with its part
                    ex_, ey_ = _turned(pc_, ps_, e1x, e1y)
                    m1 = ex_ * fx + ey_ * fy
                    ex_, ey_ = _turned(pc_, ps_, e2x, e2y)
                    m2 = ex_ * fx + ey_ * fy
                    m = _min(m, m1) if have else m1
                    m = _min(m, m2)
                    have = True
                q_out[v, j] = q
                m_out[v, j] = _min(ex, m) if have else ex

    return _jit(margins)


@_jit
def _arc_margins(pc, owner, fp_arc, K, q1, q, m, ang1, ang2):
    """Stage 3: the arcs' angular margins (KernelStack._arc_margin) into m:
    the target arc's of a point-circle equation, the point arc's."""
    V, N = m.shape
    for v in range(V):
        h1, mid1, h2, mid2 = K[v, 20], K[v, 21], K[v, 22], K[v, 23]
        full1, full2 = h1 >= _FULL, h2 >= _FULL
        for j in range(N):
            out = m[v, j]
            # the target's arc turns with the part that does not own the point
            if pc:
                qt = q[v, j] if owner == 0 else q1[v, j]
                a = ang1[v, j] - qt
                mm = 1.0 if full1 else h1 - abs(_wrap_pi(a - mid1))
                out = _min(out, mm)
            if fp_arc:
                qp = q1[v, j] if owner == 0 else q[v, j]
                a = ang2[v, j] - qp
                mm = 1.0 if full2 else h2 - abs(_wrap_pi(a - mid2))
                out = _min(out, mm)
            m[v, j] = out


@_jit
def _fill_constants(pc, f, h, K):
    """The per-variant constants of the loops from a stack's packed fields
    ``f`` (:attr:`~cspace.batch.kernels.KernelStack.packed`: ok, r, fp (13),
    ft (13), axis_a, axis_b, scale) and, for a point-line equation, the
    length ``h`` of the line's direction (numpy's ``hypot``), computed as the
    numpy code computes them (KernelStack._normal, _exists, conditions)."""
    V = f.shape[0]
    for v in range(V):
        L = f[v, 32]
        K[v, 0], K[v, 1] = f[v, 28], f[v, 29]          # driver centre
        K[v, 2], K[v, 3] = f[v, 30], f[v, 31]          # follower centre
        K[v, 4] = f[v, 1]                              # the equation's radius
        K[v, 5], K[v, 6] = f[v, 2 + _P], f[v, 3 + _P]     # point feature p
        K[v, 7], K[v, 8] = f[v, 15 + _P], f[v, 16 + _P]   # target feature p
        if pc:
            K[v, 11] = 1.0 / (2 * L * L)
            K[v, 20], K[v, 21] = f[v, 15 + _HALF], f[v, 15 + _MID]
        else:
            dx = f[v, 15 + _Q] - f[v, 15 + _P]
            dy = f[v, 16 + _Q] - f[v, 16 + _P]
            hh = h[v] if h[v] > 0 else 1.0
            K[v, 9], K[v, 10] = dy / hh, -dx / hh
            K[v, 11] = 1.0 / L
            ln = math.sqrt(dx * dx + dy * dy)
            K[v, 16], K[v, 17] = dx, dy
            K[v, 18] = 1.0 / (ln * L)
            K[v, 19] = ln / L
        K[v, 12], K[v, 13] = f[v, 2 + _E1], f[v, 3 + _E1]
        K[v, 14], K[v, 15] = f[v, 2 + _E2], f[v, 3 + _E2]
        K[v, 22], K[v, 23] = f[v, 2 + _HALF], f[v, 2 + _MID]


def _constants(stack) -> np.ndarray:
    """The per-variant constants of the loops, (V, 24) (:func:`_fill_constants`),
    kept on the stack."""
    K = stack.__dict__.get("_fused_constants")
    if K is None:
        f = stack.packed
        pc = stack.eq == Equation.POINT_CIRCLE
        if pc:
            h = f[:, 0]                      # not read
        else:
            h = np.hypot(f[:, 15 + _Q] - f[:, 15 + _P], f[:, 16 + _Q] - f[:, 16 + _P])
        K = np.zeros((len(f), 24))
        _fill_constants(pc, f, h, K)
        stack.__dict__["_fused_constants"] = K
    return K


def branch(stack, q1, bi: int):
    """:meth:`~cspace.batch.kernels.KernelStack.branch_numpy` of a stack
    :func:`supports` (no follower window: a turning follower has none),
    the same numbers."""
    q1 = np.asarray(q1, dtype=float)
    V = len(stack.ok)
    shape = np.broadcast_shapes((V, 1), q1.shape if q1.ndim == 2 else (1,) + q1.shape)
    # every array one contiguous (V, N) block: one compiled layout, and loops
    # that vectorise
    q1b = _block(q1, shape)
    cq1, sq1 = _block(np.cos(q1), shape), _block(np.sin(q1), shape)
    pc = stack.eq == Equation.POINT_CIRCLE
    fp_arc = stack.fp_kind == "arc"
    K = _constants(stack)
    A, B, g, R, c = (np.empty(shape) for _ in range(5))
    _terms(pc, stack.owner, K, cq1, sq1, A, B, g, R, c)
    alpha = np.arctan2(B, A)
    acs = np.arccos(c)
    flags = np.array([fp_arc and float(stack.fp[0, _CONVEX]) == 0.0,
                      float(stack.ft[0, _CONVEX]) == 1.0])
    q, m = np.empty(shape), np.empty(shape)
    empty = np.empty((0, 0))
    d1x, d1y = (np.empty(shape), np.empty(shape)) if pc else (empty, empty)
    d2x, d2y = (np.empty(shape), np.empty(shape)) if fp_arc else (empty, empty)
    _margins_for(bool(pc), int(stack.owner), bool(fp_arc))(
        int(bi), flags, K, q1b, cq1, sq1, A, B, g, R, c, alpha, acs, q, m, d1x, d1y, d2x, d2y)
    if pc or fp_arc:
        ang1 = np.arctan2(d1y, d1x) if pc else empty
        ang2 = np.arctan2(d2y, d2x) if fp_arc else empty
        _arc_margins(pc, stack.owner, fp_arc, K, q1b, q, m, ang1, ang2)
    return q, m


def _block(a, shape) -> np.ndarray:
    """``a`` ((N,) per sample, or (V, N) or (V, 1)) as a contiguous (V, N) array."""
    if a.shape == shape and a.flags.c_contiguous:
        return a
    return np.ascontiguousarray(np.broadcast_to(a if a.ndim == 2 else a[None, :], shape))


def warm_up() -> None:
    """Load (or, after a new installation, compile) the loops, the eight
    variants of stage 2 among them, on tiny made-up stacks: a process pays
    that once, and a worker pays it before its first task
    (``synthesis.executors`` warms its workers up while the caller computes
    its reference)."""
    if not ENABLED:
        return
    from .kernels import KernelStack
    V = 2
    f = np.zeros((V, 13))
    f[:, 0:4] = [[1.0, 0.5, 2.0, 0.5], [1.1, 0.4, 2.1, 0.6]]
    f[:, 4], f[:, 5], f[:, 7] = 0.5, 1.0, 1.0
    for eq, kind in ((Equation.POINT_CIRCLE, "arc"), (Equation.POINT_LINE, "line")):
        for owner in (0, 1):
            for fp_kind in ("vertex", "arc"):
                st = KernelStack(eq, owner, (True, True), np.ones(V, dtype=bool),
                                 np.full((V, 1), 0.5), f, f, fp_kind, kind, np.zeros((V, 2)),
                                 np.full((V, 2), 3.0), np.full((V, 1), 4.0))
                with np.errstate(all="ignore"):
                    branch(st, np.linspace(0.0, 1.0, 3), 0)
