"""The batched contact kernel compiled to machine code (numba), one loop over
variants and driver values.

:meth:`cspace.batch.kernels.KernelStack.branch` evaluates one contact curve for
``V`` variants at ``N`` driver values.  Written with numpy, every one of its
some 100 array operations makes a temporary ``(V, N)`` array and a trip
through the interpreter; on the small arrays of a batch most of the time goes
there.  :func:`branch` evaluates the same equations in one compiled loop: no
temporaries, one call.

The numpy code stays the reference.  Both give the same values to rounding,
which ``tests/cspace/batch/test_compiled.py`` checks on every curve of the
built-in models: the compiled trigonometric functions are the C library's,
numpy's may be its own, and the numpy code takes a rotating follower's
``cos q2`` and ``sin q2`` from the equation's terms and a segment's length
from its ends (:meth:`~cspace.batch.kernels.KernelStack.branch_numpy`),
where this loop calls ``cos``, ``sin`` and ``hypot``.  Verdicts do not depend on rounding: ties are decided
with a slack (:data:`cspace.batch.margins.TIE`).

It is off by default: measured on the Geneva check list
(``benchmarks/bench_batch.py``), a whole batch takes as long with it as with
numpy or slower (20 against 18 ms per variant at ``fast``, 26 against 21
at ``default``, ``docs/BENCHMARKS.md``): its trigonometric functions are
the C library's, one value at a time, where numpy's are vectorised.
:mod:`cspace.batch.fused` keeps numpy's trigonometric functions and
compiles only the arithmetic between them, the same numbers bit for bit as
the numpy code; that one runs by default.  With the environment variable
``CSPACE_NUMBA=1`` (:data:`ENABLED`), this loop runs instead; its code is
cached on disk (numba's ``cache=True``), so its compile cost (a few seconds)
is paid once per installation.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..equations import Equation
from ..tolerances import FULL_CIRCLE_SLACK, NEAR_PARALLEL, TINY

__all__ = ["AVAILABLE", "ENABLED", "branch", "pack"]

try:  # pragma: no cover - exercised by whichever the environment has
    import numba
except ImportError:  # pragma: no cover
    numba = None

#: numba can be imported.
AVAILABLE = numba is not None

#: Whether :meth:`~cspace.batch.kernels.KernelStack.branch` runs compiled
#: (numba importable and asked for with ``CSPACE_NUMBA=1``).
ENABLED = AVAILABLE and os.environ.get("CSPACE_NUMBA", "0") == "1"

# the layout of a packed row (see :func:`pack`); feature fields as in
# cspace.batch.kernels (_P, _Q, _R, _CONVEX, _MID, _HALF, _E1, _E2)
_FP, _FT, _AA, _AB, _SC, _RR = 0, 13, 26, 28, 30, 31
_NPACK = 32
_P, _Q, _CONVEX, _MID, _HALF, _E1, _E2 = 0, 2, 5, 6, 7, 8, 10
_KIND = {"vertex": 0, "line": 1, "arc": 2}
TWO_PI = 2.0 * math.pi


def pack(stack) -> np.ndarray:
    """The per-variant constants of a :class:`~cspace.batch.kernels.KernelStack`
    as one contiguous (V, 32) array: point feature row, target feature row,
    driver axis, follower axis, characteristic length, equation radius."""
    V = len(stack.ok)
    out = np.empty((V, _NPACK))
    out[:, _FP:_FP + 13] = stack.fp
    out[:, _FT:_FT + 13] = stack.ft
    out[:, _AA:_AA + 2] = stack.axis_a
    out[:, _AB:_AB + 2] = stack.axis_b
    out[:, _SC] = stack.scale[:, 0]
    out[:, _RR] = stack.r[:, 0]
    return out


def _flags(stack, bi: int, window) -> np.ndarray:
    ft_convex = stack.ft[0, _CONVEX] == 1.0 if len(stack.ok) else False
    p_concave = (stack.fp_kind == "arc" and len(stack.ok) > 0
                 and stack.fp[0, _CONVEX] == 0.0)
    use_window = window is not None and not stack.rotating[1]
    return np.array([1 if stack.eq == Equation.POINT_CIRCLE else 0, stack.owner, int(stack.rotating[0]),
                     int(stack.rotating[1]), _KIND[stack.fp_kind], _KIND[stack.ft_kind], bi,
                     int(ft_convex), int(p_concave), int(use_window)], dtype=np.int64)


def branch(stack, q1, bi: int, window=None):
    """q2 (V, N) of branch ``bi`` and its validity margin (V, N): the values of
    :meth:`~cspace.batch.kernels.KernelStack.branch`.  ``q1`` is (N,) (every
    variant at every value) or (V, 1) (one value per variant)."""
    q1 = np.asarray(q1, dtype=float)
    V = len(stack.ok)
    if q1.ndim == 1:
        q1b = q1[None, :]
    elif q1.ndim == 2 and q1.shape[1] == 1 and q1.shape[0] == V:
        q1b = q1
    else:
        q1b = np.broadcast_to(q1, (V, q1.shape[-1]))
    N = q1b.shape[1]
    w = np.zeros(4) if window is None else np.asarray(window, dtype=float)
    q = np.empty((V, N))
    m = np.empty((V, N))
    _branch_loop(pack(stack), np.ascontiguousarray(q1b), _flags(stack, bi, window), w, q, m)
    return q, m


# ---------------------------------------------------------------- compiled
def _jit(f):
    if numba is None:
        return f
    return numba.njit(cache=True, nogil=True, error_model="numpy")(f)


@_jit
def _mn(a, b):
    """np.minimum of two floats (NaN propagates)."""
    if a != a or b != b:
        return math.nan
    return a if a < b else b


@_jit
def _wrap(a):
    return (a + math.pi) % TWO_PI - math.pi


@_jit
def _normal(k, f0):
    """Unit free-side normal of the line row at column f0 of packed row k."""
    dx = k[f0 + _Q] - k[f0 + _P]
    dy = k[f0 + _Q + 1] - k[f0 + _P + 1]
    h = math.hypot(dx, dy)
    if not h > 0:
        h = 1.0
    return dy / h, -dx / h


@_jit
def _place(k, part, rotating, q, c, s, px, py):
    """World (x, y) of body point (px, py) of ``part`` at coordinate q (c, s =
    cos q, sin q of a rotating part)."""
    a0 = _AA if part == 0 else _AB
    if rotating:
        cx, cy = k[a0], k[a0 + 1]
        x, y = px - cx, py - cy
        return cx + c * x - s * y, cy + s * x + c * y
    return px + q * k[a0], py + q * k[a0 + 1]


@_jit
def _turn(rotating, c, s, vx, vy):
    if rotating:
        return c * vx - s * vy, s * vx + c * vy
    return vx, vy


@_jit
def _arc_margin(k, f0, dx, dy, rotating, q):
    half, mid = k[f0 + _HALF], k[f0 + _MID]
    ang = math.atan2(dy, dx) - (q if rotating else 0.0)
    if half >= math.pi - FULL_CIRCLE_SLACK:
        return 1.0
    return half - abs(_wrap(ang - mid))


@_jit
def _solve(k, q1, c1, s1, fl):
    """q2 of branch fl[6] and the existence condition at q1 (one variant; c1,
    s1: cos q1, sin q1 of a rotating driver)."""
    eq_pc, owner, rot0, rot1, bi = fl[0] == 1, fl[1], fl[2] == 1, fl[3] == 1, fl[6]
    L = k[_SC]
    r = k[_RR]
    if rot1:
        ox, oy = k[_AB], k[_AB + 1]
        if owner == 0:
            wx, wy = _place(k, 0, rot0, q1, c1, s1, k[_FP + _P], k[_FP + _P + 1])
            wx, wy = wx - ox, wy - oy
            if not eq_pc:
                nx, ny = _normal(k, _FT)
                lx, ly = k[_FT + _P] - ox, k[_FT + _P + 1] - oy
                A = nx * wx + ny * wy
                B = nx * wy - ny * wx
                g = -((nx * lx + ny * ly) + r)
            else:
                cx, cy = k[_FT + _P] - ox, k[_FT + _P + 1] - oy
                A = -2 * (cx * wx + cy * wy)
                B = -2 * (cx * wy - cy * wx)
                g = (wx ** 2 + wy ** 2) + (cx * cx + cy * cy) - r ** 2
        else:
            px, py = k[_FP + _P] - ox, k[_FP + _P + 1] - oy
            if not eq_pc:
                vx, vy = _normal(k, _FT)
                nx, ny = _turn(rot0, c1, s1, vx, vy)
                lx, ly = _place(k, 0, rot0, q1, c1, s1, k[_FT + _P], k[_FT + _P + 1])
                A = nx * px + ny * py
                B = px * ny - py * nx
                g = ((ox - lx) * nx + (oy - ly) * ny) - r
            else:
                mx, my = _place(k, 0, rot0, q1, c1, s1, k[_FT + _P], k[_FT + _P + 1])
                mx, my = ox - mx, oy - my
                A = 2 * (px * mx + py * my)
                B = 2 * (px * my - py * mx)
                g = (mx ** 2 + my ** 2) + (px * px + py * py) - r ** 2
        R = math.hypot(A, B)
        alpha = math.atan2(B, A)
        Rs = R if R > 0 else 1.0
        x = -g / Rs
        if x == x:
            x = min(max(x, -1.0), 1.0)
        acs = math.acos(x) if x == x else math.nan
        q2 = alpha + acs if bi == 0 else alpha - acs
        ex = (R - abs(g)) / (2 * L) if eq_pc else R - abs(g)
        return q2, ex / L
    ex_, ey_ = k[_AB], k[_AB + 1]
    if owner == 0 and not eq_pc:
        nx, ny = _normal(k, _FT)
        wx, wy = _place(k, 0, rot0, q1, c1, s1, k[_FP + _P], k[_FP + _P + 1])
        dx, dy = wx - k[_FT + _P], wy - k[_FT + _P + 1]
        ne = nx * ex_ + ny * ey_
        if ne == 0:
            ne = TINY
        return (dx * nx + dy * ny - r) / ne, 1.0
    if owner == 1 and not eq_pc:
        vx, vy = _normal(k, _FT)
        nx, ny = _turn(rot0, c1, s1, vx, vy)
        lx, ly = _place(k, 0, rot0, q1, c1, s1, k[_FT + _P], k[_FT + _P + 1])
        ne = nx * ex_ + ny * ey_
        ne_s = ne if abs(ne) > TINY else TINY
        s = (r - ((k[_FP + _P] - lx) * nx + (k[_FP + _P + 1] - ly) * ny)) / ne_s
        return s, abs(ne) - NEAR_PARALLEL
    if owner == 0:
        wx, wy = _place(k, 0, rot0, q1, c1, s1, k[_FP + _P], k[_FP + _P + 1])
        wx, wy = wx - k[_FT + _P], wy - k[_FT + _P + 1]
    else:
        wx, wy = _place(k, 0, rot0, q1, c1, s1, k[_FT + _P], k[_FT + _P + 1])
        wx, wy = wx - k[_FP + _P], wy - k[_FP + _P + 1]
    ew = wx * ex_ + wy * ey_
    cr = wx * ey_ - wy * ex_
    disc = r ** 2 - cr ** 2
    sq = math.sqrt(disc) if disc > 0 else 0.0
    return (ew + sq if bi == 0 else ew - sq), (r - abs(cr)) / L


@_jit
def _conditions(k, q1, c1, s1, q2, fl):
    """Smallest validity margin of the solution q2 at q1 (one variant)."""
    eq_pc, owner, rot0, rot1 = fl[0] == 1, fl[1], fl[2] == 1, fl[3] == 1
    fp_kind, ft_convex, p_concave = fl[4], fl[7] == 1, fl[8] == 1
    L = k[_SC]
    rot = (rot0, rot1)
    qs = (q1, q2)
    cs = (c1, math.cos(q2) if rot1 else 0.0)
    ss = (s1, math.sin(q2) if rot1 else 0.0)
    po, to = owner, 1 - owner
    Px, Py = _place(k, po, rot[po], qs[po], cs[po], ss[po], k[_FP + _P], k[_FP + _P + 1])
    if not eq_pc:
        vx, vy = _normal(k, _FT)
        nx, ny = _turn(rot[to], cs[to], ss[to], vx, vy)
        l0x, l0y = _place(k, to, rot[to], qs[to], cs[to], ss[to], k[_FT + _P], k[_FT + _P + 1])
        l1x, l1y = _place(k, to, rot[to], qs[to], cs[to], ss[to], k[_FT + _Q], k[_FT + _Q + 1])
        if fp_kind == 2:
            Xx, Xy = Px - k[_RR] * nx, Py - k[_RR] * ny
        else:
            Xx, Xy = Px, Py
        dx, dy = l1x - l0x, l1y - l0y
        ln = math.hypot(dx, dy)
        t = ((Xx - l0x) * dx + (Xy - l0y) * dy) / ln
        out = _mn(t / L, (ln - t) / L)
        if fp_kind == 2:
            out = _mn(out, _arc_margin(k, _FP, -nx, -ny, rot[po], qs[po]))
        fx, fy = nx, ny
    else:
        Cx, Cy = _place(k, to, rot[to], qs[to], cs[to], ss[to], k[_FT + _P], k[_FT + _P + 1])
        ux, uy = Px - Cx, Py - Cy
        un = math.hypot(ux, uy)
        if not un > 0:
            un = 1.0
        ux, uy = ux / un, uy / un
        sc = -1.0 if p_concave else 1.0
        out = _arc_margin(k, _FT, sc * ux, sc * uy, rot[to], qs[to])
        if fp_kind == 2:
            sp = -1.0 if (p_concave or ft_convex) else 1.0
            out = _mn(out, _arc_margin(k, _FP, sp * ux, sp * uy, rot[po], qs[po]))
        sf = 1.0 if ft_convex else -1.0
        fx, fy = sf * ux, sf * uy
    if fp_kind == 0:
        for e in (_E1, _E2):
            ex, ey = _turn(rot[po], cs[po], ss[po], k[_FP + e], k[_FP + e + 1])
            out = _mn(out, ex * fx + ey * fy)
    return out


@_jit
def _branch_loop(K, Q1, fl, w, q_out, m_out):
    V, N = q_out.shape
    one = Q1.shape[0] == 1
    use_window = fl[9] == 1
    rot0 = fl[2] == 1
    C1 = np.cos(Q1) if rot0 else np.zeros_like(Q1)
    S1 = np.sin(Q1) if rot0 else np.zeros_like(Q1)
    for v in range(V):
        k = K[v]
        r = 0 if one else v
        L = k[_SC]
        for n in range(N):
            q1, c1, s1 = Q1[r, n], C1[r, n], S1[r, n]
            q2, ex = _solve(k, q1, c1, s1, fl)
            m = _mn(ex, _conditions(k, q1, c1, s1, q2, fl))
            if use_window:
                m = _mn(m, _mn(q2 - w[2], w[3] - q2) / L)
            q_out[v, n] = q2
            m_out[v, n] = m
