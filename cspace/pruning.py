"""Broad-phase pruning: the feature pairs of two parts that can ever touch.

:func:`feature_pairs` lists, for every pair of a driver and a follower feature
with a contact equation (:func:`cspace.equations.equation_types`), those whose parts
can bring them together within the C-space window: radial annulus bounds for
rotating parts and slab bounds for sliding ones.
"""

from __future__ import annotations

import numpy as np

from .equations import equation_types
from .features import Feature, projection_range, radial_range, features
from .geometry import Pair, Rotation, Translation

__all__ = ["feature_pairs"]


def _can_touch(fa: Feature, fb: Feature, pair: Pair, margin: float) -> bool:
    """Broad phase: can feature fa of the driver ever touch fb of the follower?"""
    ax_a, ax_b = pair.driver.axis, pair.follower.axis
    if isinstance(ax_a, Rotation) and isinstance(ax_b, Rotation):
        amin, amax, bmin, bmax, D = _radial_terms(fa, fb, pair)
        return (amax + bmax >= D - margin and amin - bmax <= D + margin
                and bmin - amax <= D + margin)
    if isinstance(ax_a, Rotation) and isinstance(ax_b, Translation):
        return _slab_reach(fa, ax_a.center, fb, ax_b.direction, margin)
    if isinstance(ax_a, Translation) and isinstance(ax_b, Rotation):
        return _slab_reach(fb, ax_b.center, fa, ax_a.direction, margin)
    # two translations: parallel slides can always be brought together if the
    # perpendicular slabs overlap
    return True


def _slab_reach(f_rot: Feature, center, f_slide: Feature, direction, margin: float) -> bool:
    """Slab bound: can feature ``f_rot`` of a part turning about ``center`` reach
    feature ``f_slide`` of a part sliding along ``direction``?  Across the
    slide the sliding feature is fixed: the slab [lo, hi] of its projection on
    the perpendicular must lie within the turning feature's largest radius (a
    feature entirely inside the inner radius would not touch either, but only
    where the slab lies within that band everywhere, which is rare: not
    tested)."""
    dist, rmax = _slab_terms(f_rot, center, f_slide, direction)
    return dist <= rmax + margin


def _radial_terms(fa: Feature, fb: Feature, pair: Pair) -> tuple:
    """``(amin, amax, bmin, bmax, D)`` of two turning parts' features: their
    radial ranges about their centres and the centres' distance."""
    amin, amax = radial_range(fa, pair.driver.axis.center)
    bmin, bmax = radial_range(fb, pair.follower.axis.center)
    D = float(np.hypot(*np.subtract(pair.driver.axis.center, pair.follower.axis.center)))
    return amin, amax, bmin, bmax, D


def _slab_terms(f_rot: Feature, center, f_slide: Feature, direction) -> tuple:
    """``(distance, rmax)`` of :func:`_slab_reach`: how far the sliding
    feature's slab lies from the turning centre across the slide, and the
    turning feature's largest radius."""
    e = np.array(direction)
    u = np.array([-e[1], e[0]])
    _, rmax = radial_range(f_rot, center)
    c = float(np.dot(center, u))
    lo, hi = projection_range(f_slide, u)
    return max(lo - c, c - hi, 0.0), rmax


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
            ts = equation_types(fa, fb_all[j])
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
    rr = np.array([radial_range(f, center) for f in rot_feats]).reshape(-1, 2)
    pp = np.array([projection_range(f, u) for f in slide_feats]).reshape(-1, 2)
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
        ra = np.array([radial_range(f, ax_a.center) for f in fa_all]).reshape(-1, 2)
        rb = np.array([radial_range(f, ax_b.center) for f in fb_all]).reshape(-1, 2)
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
    (``sum(len(equation_types(a, b)))`` over all pairs), counted by kind."""
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


def pair_gap(fa: Feature, fb: Feature, pair: Pair) -> float:
    """How far the broad phase's bounds keep driver feature ``fa`` from
    follower feature ``fb`` (model units): the amount by which the test of
    :func:`_can_touch` fails at margin 0, and 0 where it passes (two
    translations: always 0)."""
    ax_a, ax_b = pair.driver.axis, pair.follower.axis
    if isinstance(ax_a, Rotation) and isinstance(ax_b, Rotation):
        amin, amax, bmin, bmax, D = _radial_terms(fa, fb, pair)
        return max(D - (amax + bmax), amin - bmax - D, bmin - amax - D, 0.0)
    if isinstance(ax_a, Rotation) and isinstance(ax_b, Translation):
        dist, rmax = _slab_terms(fa, ax_a.center, fb, ax_b.direction)
    elif isinstance(ax_a, Translation) and isinstance(ax_b, Rotation):
        dist, rmax = _slab_terms(fb, ax_b.center, fa, ax_a.direction)
    else:
        return 0.0
    return max(dist - rmax, 0.0)
