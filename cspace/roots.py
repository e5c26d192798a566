"""Adaptive polylines of a function of one variable, and a vectorised
bracketing root finder (many brackets at once) for the ends of contact curves
and zones.
"""

from __future__ import annotations

import math

import numpy as np

from .tolerances import ROUNDING, TINY

__all__ = ["adaptive_polyline", "vroots"]


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
        err = np.abs((vm - 0.5 * (v[:-1] + v[1:])) * scale) * dt / np.maximum(np.hypot(dt, dv), TINY)
        bad = (err > chord) & (dt > ROUNDING)
        if not bad.any():
            break
        t = np.insert(t, np.nonzero(bad)[0] + 1, tm[bad])
        v = np.insert(v, np.nonzero(bad)[0] + 1, vm[bad])
    return np.stack([t, v], -1)


def refine_root(fn, a, b, fa, tol):
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
