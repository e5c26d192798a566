"""The channel bounds' bookkeeping of :func:`cspace.batch.margins._envelopes`
in compiled loops (numba), the same numbers bit for bit as its numpy code.

For every candidate curve (and side) of a plan, the batch decides where each
variant must evaluate it (:func:`cspace.batch.margins._needed`) and then adds
its values to the variants' running lower or upper bound
(:func:`cspace.batch.margins._accumulate`).  Written with numpy, each of the
some 240 candidates of the Geneva pair makes a dozen temporary ``(V, M)``
arrays per stage; here each stage is one pass over the values:

:func:`need`
    the samples a candidate is evaluated at and which variants need each
    (the variants that move the curve, and those that see the nominal's);
:func:`accumulate`
    the candidate's values, placed on the nominal's turn where the follower
    turns, into the bounds, the curve ids that attain them and (when kept)
    their runners-up.

Every comparison and every arithmetic operation is the numpy code's, on the
same operands, in its order: ``max`` and ``min`` keep numpy's rule that a
NaN wins, and the angle wrap is :func:`cspace.geom2d.wrap_pi`'s per value
(:func:`cspace.batch.fused._wrap_pi`).  Where the numpy code adds the far
bound for a value a variant does not need (or that is no contact), the loops
skip it: a bound is never NaN, so the far bound never wins and leaves the
runner-up as it was.  The numpy code stays and runs where
numba is missing or ``CSPACE_FUSED=0``; ``tests/cspace/batch/test_fused_bounds.py``
compares the two on the built-in models.
"""

from __future__ import annotations

import numpy as np

from . import fused
from .fused import _jit, _max, _min, _wrap_pi

__all__ = ["enabled", "need", "accumulate", "clamp_scan", "untie", "flip_marks", "warm_up"]


def enabled() -> bool:
    """Whether the compiled loops run (as the fused kernel: numba importable and
    ``CSPACE_FUSED`` not 0; :data:`cspace.batch.fused.ENABLED`)."""
    return fused.ENABLED


@_jit
def _need_flags(dist0, m0, mn, sub, disp, dm, inv, dmax, rows, other, rf, rounding, valid_tol,
                stride, flags, keep):
    """Per sample of ``sub`` and row (``rows`` then ``other``), whether it is
    needed; per sample, whether any row needs it (``disp``, ``dm``: per
    distinct row, row i's is ``inv[i]``)."""
    S = len(sub)
    R, O = len(rows), len(other)
    nc = disp.shape[1]
    for s in range(S):
        j = sub[s]
        d0 = dist0[j]
        c0 = j // stride
        c1 = c0 + 1 if c0 + 1 < nc else nc - 1
        any_ = False
        for i in range(R):
            # _spread_at: the larger of the two coarse samples around it
            r = inv[i]
            a = _max(disp[r, c0], disp[r, c1])
            b = _max(dm[r, c0], dm[r, c1])
            f = (d0 <= rf * (a + dmax[rows[i]]) + rounding) and (mn[j] >= -rf * b - valid_tol)
            flags[i, s] = f
            any_ = any_ or f
        real0 = m0[j] >= -valid_tol
        for i in range(O):
            f = (d0 <= rf * dmax[other[i]] + rounding) and real0
            flags[R + i, s] = f
            any_ = any_ or f
        keep[s] = any_


def need(dist0, m0, mn, sub, disp, dm, inv, dmax, rows, other, rf: float, rounding: float,
         valid_tol: float, stride: int):
    """The needs of one candidate at its samples ``sub`` (positions among its
    samples, those within the largest reach): ``(keep, need, need_o)``, the
    positions in ``sub`` that some row needs, and per row (the variants that
    move the curve, ``rows``; those that see the nominal's, ``other``)
    whether it needs each (:func:`cspace.batch.margins._needed`).  ``disp``
    and ``dm`` hold one row per distinct row of the curve's stack; row i of
    ``rows`` reads row ``inv[i]``."""
    S = len(sub)
    R = len(rows)
    flags = np.empty((R + len(other), S), dtype=np.bool_)
    keep = np.empty(S, dtype=np.bool_)
    _need_flags(_f(dist0), _f(m0), _f(mn), _i(sub), _f(disp), _f(dm), _i(inv), _f(dmax), _i(rows),
                _i(other), float(rf), float(rounding), float(valid_tol), int(stride), flags, keep)
    k = np.nonzero(keep)[0]
    if len(k) == S:
        return k, flags[:R], flags[R:]
    f = flags[:, k]
    return k, f[:R], f[R:]


# The update of a bound is written out in each loop below, not shared: a
# helper taking a row's views measured a third slower on the Geneva pair's
# finite-difference steps (a view per value of the rows that see the
# nominal's curve).
@_jit
def _accumulate(b, b2, ids, has2, side, key, idx, rows, other, q, m, inv, need_, need_o,
                place, periodic2, far, valid_tol, qp, keep_qp):
    """One candidate's values into the bounds, row by row (the numpy code's
    rule per value: :meth:`cspace.batch.margins._Bounds.add`).  A value not
    needed or not valid stands for the far bound ``far``, which changes
    nothing (a bound is never NaN, so the far value is never better and
    leaves the runner-up as it is): it is skipped.  The placed values go to
    ``qp`` at every sample (``keep_qp``)."""
    R, K = len(rows), q.shape[1]
    O = len(other)
    for i in range(R):
        r = inv[i]
        v = rows[i]
        br, b2r, ir = b[v], b2[v], ids[v]
        for k in range(K):
            if periodic2:
                qi = place[k] + _wrap_pi(q[r, k] - q[0, k])
            else:
                qi = q[r, k]
            if keep_qp:
                qp[i, k] = qi
            if not (m[r, k] >= -valid_tol and need_[i, k]):
                continue
            col = idx[k]
            cur = br[col]
            if side > 0:
                if has2:
                    b2r[col] = _max(b2r[col], _min(cur, qi))
                better = qi > cur
            else:
                if has2:
                    b2r[col] = _min(b2r[col], _max(cur, qi))
                better = qi < cur
            if better:
                br[col] = qi
                ir[col] = key
    for k in range(K):
        if not m[0, k] >= -valid_tol:
            continue
        q0 = q[0, k]
        p0 = place[k] + _wrap_pi(q0 - q0) if periodic2 else q0
        col = idx[k]
        for i in range(O):
            if not need_o[i, k]:
                continue
            v = other[i]
            cur = b[v, col]
            if side > 0:
                if has2:
                    b2[v, col] = _max(b2[v, col], _min(cur, p0))
                better = p0 > cur
            else:
                if has2:
                    b2[v, col] = _min(b2[v, col], _max(cur, p0))
                better = p0 < cur
            if better:
                b[v, col] = p0
                ids[v, col] = key


@_jit
def _accumulate_lean(b, ids, side, key, idx, rows, other, q, m, inv, need_, need_o, place,
                     periodic2, valid_tol):
    """:func:`_accumulate` without runners-up or placed values, in one pass:
    a value not needed, or not valid, is the far bound, which changes nothing
    (a bound is never NaN, and the far value is never better), so it is
    skipped."""
    R, K = len(rows), q.shape[1]
    O = len(other)
    for i in range(R):
        r = inv[i]
        v = rows[i]
        br, ir = b[v], ids[v]
        for k in range(K):
            if not (need_[i, k] and m[r, k] >= -valid_tol):
                continue
            if periodic2:
                f = place[k] + _wrap_pi(q[r, k] - q[0, k])
            else:
                f = q[r, k]
            col = idx[k]
            if (f > br[col]) if side > 0 else (f < br[col]):
                br[col] = f
                ir[col] = key
    if O:
        for k in range(K):
            if not m[0, k] >= -valid_tol:
                continue
            q0 = q[0, k]
            p0 = place[k] + _wrap_pi(q0 - q0) if periodic2 else q0
            col = idx[k]
            for i in range(O):
                if need_o[i, k]:
                    v = other[i]
                    if (p0 > b[v, col]) if side > 0 else (p0 < b[v, col]):
                        b[v, col] = p0
                        ids[v, col] = key


def accumulate(b, b2, ids, side: int, key: int, idx, rows, other, q, m, inv, need_, need_o,
               place, far: float, valid_tol: float, placed: bool):
    """Add one candidate's values ``q``, ``m`` (one row per distinct row of
    its stack, the nominal's first; row i of ``rows`` reads row ``inv[i]``;
    at the samples ``idx``) to the bound ``b`` (V, N), its curve ids
    ``ids`` and runners-up ``b2`` (None: not kept), in place; ``place``: the
    nominal values' places on their turn at those samples (None where the
    follower does not turn).  Returns the placed values (R, M) when ``placed``
    (what the hand-over flips read), else None."""
    periodic2 = place is not None
    if b2 is None and not placed:
        _accumulate_lean(b, ids, int(side), int(key), _i(idx), _i(rows), _i(other), _f(q),
                         _f(m), _i(inv), _b(need_), _b(need_o),
                         _f(place) if periodic2 else np.empty(0), periodic2, float(valid_tol))
        return None
    qp = np.empty((len(rows), q.shape[1])) if placed else np.empty((0, 0))
    has2 = b2 is not None
    _accumulate(b, b2 if has2 else b, ids, has2, int(side), int(key), _i(idx), _i(rows),
                _i(other), _f(q), _f(m), _i(inv), _b(need_), _b(need_o),
                _f(place) if periodic2 else np.empty(0), periodic2, float(far),
                float(valid_tol), qp, bool(placed))
    return qp if placed else None


@_jit
def _clamp_rows(lo, hi, start, f):
    V, N = lo.shape
    for v in range(V):
        x = start
        for i in range(N):
            x = _min(_max(x, lo[v, i]), hi[v, i])
            f[v, i] = x


def clamp_scan(lo, hi, start: float):
    """The follower of a form-closed pair, ``f[i] = min(max(f[i - 1], lo[i]),
    hi[i])`` from ``f[-1] = start`` per row of ``lo`` and ``hi`` (V, N):
    the loop itself, compiled (:func:`cspace.batch.margins._clamp_scan`
    computes it with array operations; a clamp only picks one of its
    numbers, so both give the same bits)."""
    f = np.empty(np.shape(lo))
    _clamp_rows(_f(lo), _f(hi), float(start), f)
    return f


@_jit
def _untie_rows(ids, tie):
    V, N = ids.shape
    for v in range(V):
        # the first sample of a run of ties takes the id before it (the
        # samples read are untied, so none of them is written here)
        for i in range(N - 1):
            if tie[v, i + 1] and not tie[v, i]:
                ids[v, i + 1] = ids[v, i]
        # the last sample of a run of ties takes the id after it, where it is
        # not also the run's first (or the run starts the row)
        for i in range(N - 1):
            if tie[v, i] and not tie[v, i + 1] and (i == 0 or tie[v, i - 1]):
                ids[v, i] = ids[v, i + 1]


def untie(ids, tie) -> None:
    """:func:`cspace.batch.margins._untie` in a compiled loop, in place: ``ids``
    (V, N) int32, ``tie`` (V, N) bool, both C-contiguous.  Each of its two
    assignments reads only untied samples and writes only tied ones, so the
    loop, in order, gives its numbers."""
    _untie_rows(ids, tie)


@_jit
def _flip_marks(m, inv, valid_tol, need, need_o, nxt, r_out, k_out, o_r, o_k):
    R, K = need.shape
    O = need_o.shape[0]
    n = 0
    for i in range(R):
        r = inv[i]
        for k in range(K - 1):
            if not nxt[k]:
                continue
            a = m[r, k] >= -valid_tol
            b = m[r, k + 1] >= -valid_tol
            if (a != b and (need[i, k + 1] or need[i, k])
                    and (need[i, k + 1] or need[0, k + 1]) and (need[i, k] or need[0, k])):
                r_out[n] = i
                k_out[n] = k
                n += 1
    n_o = 0
    r0 = inv[0]
    for i in range(O):
        for k in range(K - 1):
            if not nxt[k]:
                continue
            a = m[r0, k] >= -valid_tol
            b = m[r0, k + 1] >= -valid_tol
            if (a != b and (need_o[i, k + 1] or need_o[i, k])
                    and (need_o[i, k + 1] or need[0, k + 1])
                    and (need_o[i, k] or need[0, k])):
                o_r[n_o] = i
                o_k[n_o] = k
                n_o += 1
    return n, n_o


def flip_marks(m, inv, valid_tol: float, need, need_o, nxt):
    """Where a candidate begins or ends between two of its samples
    (:func:`cspace.batch.margins._flips`): the (row, sample) positions, in
    row-major order, of its rows (``need``) and of the rows that see the
    nominal's (``need_o``), as ``np.nonzero`` gives them.  ``m``: the
    candidate's validity margins per distinct row (row i of ``need`` reads
    ``inv[i]``; its first row the nominal's); ``nxt``: whether each sample and
    the next are neighbours."""
    R, K = need.shape
    O = need_o.shape[0]
    span = max(K - 1, 0)
    r_, k_ = np.empty(R * span, dtype=np.int64), np.empty(R * span, dtype=np.int64)
    o_r, o_k = np.empty(O * span, dtype=np.int64), np.empty(O * span, dtype=np.int64)
    n, n_o = _flip_marks(_f(m), _i(inv), float(valid_tol), _b(need), _b(need_o), _b(nxt),
                         r_, k_, o_r, o_k)
    return r_[:n], k_[:n], o_r[:n_o], o_k[:n_o]


# one layout and type per argument, so that each loop is compiled (and
# cached) once: a contiguous array of float64, int64 or bool (no copy when it
# is one already)
def _f(a):
    return np.ascontiguousarray(a, dtype=np.float64)


def _i(a):
    return np.ascontiguousarray(a, dtype=np.int64)


def _b(a):
    return np.ascontiguousarray(a, dtype=np.bool_)


def warm_up() -> None:
    """Load (or, after a new installation, compile) the loops on a tiny
    made-up candidate (:func:`cspace.batch.fused.warm_up` does the kernel's)."""
    if not enabled():
        return
    V, N, K = 2, 9, 3
    rows, other = np.arange(1), np.arange(1, 2)
    keep, nd, nd_o = need(np.zeros(N), np.zeros(N), np.zeros(N), np.arange(N), np.zeros((1, 2)),
                          np.zeros((1, 2)), np.zeros(1, dtype=np.int64), np.zeros(V), rows, other,
                          2.0, 0.0, 0.0, 8)
    b, ids = np.zeros((V, N)), np.zeros((V, N), dtype=np.int32)
    clamp_scan(np.zeros((1, 2)), np.ones((1, 2)), 0.5)
    untie(np.zeros((1, 3), dtype=np.int32), np.array([[False, True, False]]))
    flip_marks(np.zeros((1, K)), np.zeros(1, dtype=np.int64), 0.0, nd[:, :K], nd_o[:, :K],
               np.ones(K - 1, dtype=bool))
    for b2, placed in ((b.copy(), True), (None, False)):     # with runners-up, and lean
        accumulate(b, b2, ids, 1, 0, np.arange(K), rows, other, np.zeros((1, K)),
                   np.zeros((1, K)), np.zeros(1, dtype=np.int64), nd[:, :K], nd_o[:, :K],
                   np.zeros(K), -np.inf, 0.0, placed)
