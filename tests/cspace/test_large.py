"""Large drawings (issue 23, item 4): the broad phase is near-linear in segments
for parts that mostly do not touch, and a pair beyond the supported size is an
InputError unless asked for explicitly."""

import math

import numpy as np
import pytest

import cspace.equations as equations
import cspace.features as feats
import cspace.overlap as overlap
import cspace.pruning as pruning
from cspace.errors import InputError
from cspace.freespace import MAX_SEGMENTS, configuration_space
from cspace.geometry import Line, Loop, Pair, Part, Rotation

from .shapes import rr_pair, rt_pair


def _ngon(cx, cy, r, n, tooth=False):
    pts = []
    for i in range(n):
        a = 2 * math.pi * i / n
        rr = 1.4 * r if tooth and i in (1, 2) else r
        pts.append((cx + rr * math.cos(a), cy + rr * math.sin(a)))
    return Loop(tuple(Line(pts[i], pts[(i + 1) % n]) for i in range(n)))


def toothed(n):
    """A detailed outline with one tooth beside a detailed follower: only the
    tooth's few segments reach the follower."""
    return Pair(Part("d", (_ngon(0, 0, 1.0, n // 2, tooth=True),), Rotation((0.0, 0.0))),
                Part("f", (_ngon(2.3, 0, 1.0, n // 2),), Rotation((2.3, 0.0))), "mm",
                f"toothed{n}")


def _pairwise(pair):
    """The broad phase as it was: every feature pair through _can_touch."""
    fa_all, fb_all = feats.features(pair.driver, 0), feats.features(pair.follower, 1)
    margin = 1e-6 * pair.size
    out, pruned = [], 0
    for fa in fa_all:
        for fb in fb_all:
            ts = equations.equation_types(fa, fb)
            if ts and not pruning._can_touch(fa, fb, pair, margin):
                pruned += len(ts)
            elif ts:
                out += [(fa.key, fa.kind, fb.key, fb.kind, *t) for t in ts]
    return out, pruned


@pytest.mark.parametrize("make", [rr_pair, rt_pair, lambda: toothed(60),
                                  lambda: Pair(rt_pair().follower, rt_pair().driver, "mm",
                                               "slide-drives")])
def test_indexed_broad_phase_keeps_the_same_pairs(make, models):
    pair = make()
    got, pruned = pruning.feature_pairs(pair)
    assert ([(a.key, a.kind, b.key, b.kind, *t) for a, b, *t in got], pruned) == _pairwise(pair)


def test_indexed_broad_phase_on_builtin_pairs(models):
    from mechanisms.analysis import pairs_of
    for m in models.values():
        for pair in pairs_of(m):
            got, pruned = pruning.feature_pairs(pair)
            want = _pairwise(pair)
            assert ([(a.key, a.kind, b.key, b.kind, *t) for a, b, *t in got], pruned) == want


def test_broad_phase_work_is_near_linear(monkeypatch):
    calls = {"radial": 0, "crosses": 0}
    radial, crosses = feats.radial_range, overlap._crosses

    def count_radial(*a):
        calls["radial"] += 1
        return radial(*a)

    def count_crosses(*a):
        calls["crosses"] += 1
        return crosses(*a)

    monkeypatch.setattr(pruning, "radial_range", count_radial)
    monkeypatch.setattr(overlap, "_crosses", count_crosses)
    n = 400
    pair = toothed(n)
    pruning.feature_pairs(pair)
    # features: one vertex and one edge per segment; pairwise would be 2 n1 n2
    assert calls["radial"] <= 4 * n
    q = np.column_stack([np.linspace(0, 6, 50), np.linspace(-3, 3, 50)])
    overlap.parts_overlap(pair, q)
    assert calls["crosses"] <= 10 * n


def test_beyond_the_supported_size_needs_an_explicit_limit(monkeypatch):
    big = toothed(MAX_SEGMENTS + 2)
    with pytest.raises(InputError, match=rf"{MAX_SEGMENTS + 2} segments; the supported size "
                                         rf"is {MAX_SEGMENTS}.*max_segments="):
        configuration_space(big, "fast")
    small = rr_pair()
    n = sum(len(lp.segments) for p in small.parts for lp in p.loops)
    with pytest.raises(InputError, match="supported size is 5"):
        configuration_space(small, "fast", max_segments=5)
    configuration_space(small, "fast", max_segments=n)
    monkeypatch.setenv("CSPACE_MAX_SEGMENTS", "5")
    with pytest.raises(InputError, match="CSPACE_MAX_SEGMENTS"):
        configuration_space(small, "fast")
    monkeypatch.setenv("CSPACE_MAX_SEGMENTS", "lots")
    with pytest.raises(InputError, match="positive integer"):
        configuration_space(small, "fast")
    with pytest.raises(InputError, match=r"max_segments must be an int >= 1, got 0"):
        configuration_space(small, "fast", max_segments=0)


def test_large_toothed_pair_is_correct():
    from tests.conftest import brute_overlap
    pair = toothed(200)
    cs = configuration_space(pair, "fast")
    rng = np.random.default_rng(1)
    lo1, hi1, lo2, hi2 = cs.window
    q = np.column_stack([rng.uniform(lo1, hi1, 300), rng.uniform(lo2, hi2, 300)])
    st = cs.classify(q)
    from cspace.freespace import Status
    sure = st != Status.CONTACT
    assert np.array_equal((st[sure] == Status.BLOCKED), brute_overlap(pair, q[sure]))
