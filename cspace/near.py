"""Contacts the nominal parts do not make but a variant in the tolerance box may.

The broad phase (:mod:`cspace.pruning`) drops the feature pairs of the
nominal parts that can never touch, and the nominal C-space has no curve for
them.  A variant's features move, though: a pin whose crank reaches 25 mm
turns clear of a slot end at 25.2 mm, and jams against it when the slot is
made 0.3 mm shorter.  The full per-variant test builds each variant's own
C-space and sees that contact; the batched margins
(:mod:`cspace.batch.margins`) evaluate the nominal's curves and would not, and
certified such a variant healthy.

So a :class:`~cspace.defects.Reference` lists its *near pairs*
(:func:`near_pairs`): the feature pairs the broad phase drops at the nominal
by a gap that the tolerance box can close, with how far a move of each
parameter brings each pair's features together (first order, from one build
per parameter at its tolerance).  A variant that moves them together by half
the gap or more is tested with its own features (:func:`touching`); where its
broad phase lets the pair touch, the batch leaves the variant to the full
test.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .equations import equation_types
from .features import feature_by_key, features
from .geom2d import wrap_pi
from .geometry import Rotation
from .pruning import _reachable, pair_gap

__all__ = ["NearPairs", "near_pairs", "touching", "SAFETY"]

#: A near pair is one whose gap is at most this many times the most its
#: features move over the box (first order), and a variant is tested with its
#: own features where it moves them together by at least 1 / SAFETY of the
#: gap: head-room for the geometry's curvature in the parameters.
SAFETY = 2.0


@dataclass(frozen=True, eq=False)
class NearPairs:
    """The near pairs of one pair of parts (module docstring).

    Attributes
    ----------
    keys : tuple of (driver feature key, follower feature key)
        Feature keys ``(part, loop, seg, kind)``.
    gaps : (k,) float
        The broad phase's gap of each at the nominal (model units).
    reach : (n, k) float
        How far a unit move of each parameter brings each pair's features
        together at most (model units per model unit; inf where a move of
        the parameter's tolerance does not build or loses the feature).
    margin : float
        The broad phase's margin (model units).
    closing : (k, n) float
        Per pair, the sign of each parameter's move (-1, 0 or +1) that
        narrows its gap (first order): ``u0 + closing * tol`` is the box corner
        that brings the pair's features closest, a check-list vector
        (:func:`corners`).
    """

    keys: tuple
    gaps: np.ndarray
    reach: np.ndarray
    margin: float
    closing: np.ndarray

    def corners(self, u0, tol) -> np.ndarray:
        """(k, n) the box corner of each pair that narrows its gap the most
        (first order), the other parameters at their nominal."""
        return np.asarray(u0, dtype=float) + self.closing * np.asarray(tol, dtype=float)

    def __len__(self) -> int:
        return len(self.keys)


def near_pairs(model, pair_index: int, pair, cs, u0, tol) -> NearPairs:
    """The near pairs of pair ``pair_index`` of ``model`` (built at ``u0``:
    ``pair``, its C-space ``cs``) for the box ``u0 +/- tol``."""
    n = len(u0)
    margin = 1e-6 * pair.size
    fa_all, fb_all = features(pair.driver, 0), features(pair.follower, 1)
    move, probes = _moves(model, pair_index, pair, u0, tol, fa_all + fb_all)
    have = {tuple(c.features) for c in cs.curves}
    most = {k: float(np.sum(np.where(tol > 0, tol * v, 0.0))) for k, v in move.items()}
    widest = max(most.values(), default=0.0)
    keys, gaps, reach = [], [], []
    if widest > 0:
        for ia, jb in _reachable(fa_all, fb_all, pair, SAFETY * widest + margin):
            fa = fa_all[ia]
            ka = fa.key + (fa.kind,)
            for j in jb:
                fb = fb_all[j]
                kb = fb.key + (fb.kind,)
                if (ka, kb) in have or not equation_types(fa, fb):
                    continue
                g = pair_gap(fa, fb, pair)
                if g <= margin or g > SAFETY * (most[ka] + most[kb]):
                    continue
                keys.append((ka, kb))
                gaps.append(g)
                reach.append(move[ka] + move[kb])
    closing = np.zeros((len(keys), n))
    for k, (ka, kb) in enumerate(keys):
        for i, (step, pv) in probes.items():
            fa, fb = feature_by_key(pv.driver, ka), feature_by_key(pv.follower, kb)
            if fa is not None and fb is not None:
                dg = pair_gap(fa, fb, pv) - gaps[k]
                closing[k, i] = -np.sign(dg) * np.sign(step)
    return NearPairs(tuple(keys), np.array(gaps, dtype=float),
                     np.array(reach, dtype=float).reshape(-1, n).T, margin, closing)


def _moves(model, pair_index, pair, u0, tol, feats) -> dict:
    """Per feature key, (n,) how far its points move per unit move of each
    parameter (its part's axis included), from one build at ``+tol`` (or
    ``-tol`` where that does not build) per parameter."""
    n = len(u0)
    out = {f.key + (f.kind,): np.zeros(n) for f in feats}
    probes = {}
    for i in np.flatnonzero(np.asarray(tol) > 0):
        step, pv = _built(model, pair_index, u0, i, tol[i])
        if pv is None:
            for k in out:
                out[k][i] = math.inf
            continue
        probes[int(i)] = (step, pv)
        got = {f.key + (f.kind,): f for f in features(pv.driver, 0) + features(pv.follower, 1)}
        axes = (_axis_shift(pair.driver, pv.driver), _axis_shift(pair.follower, pv.follower))
        for f in feats:
            k = f.key + (f.kind,)
            fv = got.get(k)
            out[k][i] = math.inf if fv is None else (_shift(f, fv) + axes[f.part]) / tol[i]
    return out, probes


def _built(model, pair_index, u0, i, t):
    """``(step, pair)``: pair ``pair_index`` built with parameter ``i`` moved by
    ``step``, ``t`` or ``-t`` (:func:`cspace.zones._built_pair`), or ``(0,
    None)``."""
    from .zones import _built_pair
    for step in (t, -t):
        u = np.array(u0, dtype=float)
        u[i] += step
        pv = _built_pair(model, pair_index, u)
        if pv is not None:
            return step, pv
    return 0.0, None


def _shift(f, g) -> float:
    """The most any point of feature ``f`` moves to reach feature ``g`` (the
    same feature of another variant), in the part's own frame."""
    dp = math.hypot(g.p[0] - f.p[0], g.p[1] - f.p[1])
    if f.kind == "vertex":
        return dp
    if f.kind == "line":
        return max(dp, math.hypot(g.q[0] - f.q[0], g.q[1] - f.q[1]))
    # an arc: its centre and radius, and its ends turning about the centre
    ends = max(abs(float(wrap_pi(np.array((g.mid - g.half) - (f.mid - f.half))))),
               abs(float(wrap_pi(np.array((g.mid + g.half) - (f.mid + f.half))))))
    return dp + abs(g.radius - f.radius) + max(f.radius, g.radius) * ends


def _axis_shift(a, b) -> float:
    """How far a part's axis moves between two variants: a rotation centre's
    shift, a slide's change of direction over the part's size."""
    if isinstance(a.axis, Rotation):
        return math.hypot(b.axis.center[0] - a.axis.center[0],
                          b.axis.center[1] - a.axis.center[1])
    d = np.subtract(b.axis.direction, a.axis.direction)
    return float(np.hypot(*d)) * max(a.size, b.size)


def touching(near: NearPairs, U, u0, variant_pairs) -> np.ndarray:
    """(V,) bool: the variants (parameter vectors ``U``, their built pairs
    ``variant_pairs``, None for one that does not build) in which some near
    pair can touch, by the broad phase's test of the variant's own features."""
    V = len(U)
    out = np.zeros(V, dtype=bool)
    if not len(near):
        return out
    dU = np.abs(np.asarray(U, dtype=float) - np.asarray(u0, dtype=float))
    with np.errstate(invalid="ignore"):
        # inf * 0 (a parameter the variant keeps): no move
        closer = np.where(dU[:, :, None] > 0, dU[:, :, None] * near.reach[None], 0.0).sum(axis=1)
    vs, ks = np.nonzero(SAFETY * closer >= near.gaps[None, :])
    for v, k in zip(vs.tolist(), ks.tolist()):
        pv = variant_pairs[v]
        if out[v] or pv is None:
            continue
        ka, kb = near.keys[k]
        fa, fb = feature_by_key(pv.driver, ka), feature_by_key(pv.follower, kb)
        if fa is not None and fb is not None and pair_gap(fa, fb, pv) <= near.margin:
            out[v] = True
    return out
