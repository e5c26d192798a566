"""Broad-phase pruning (cspace.pruning): the feature pairs of two parts that can
ever touch are kept, those that never can are dropped."""

import math

from cspace.equations import equation_types
from cspace.features import features
from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from cspace.pruning import _n_compatible, feature_pairs

from .shapes import rr_pair, rt_pair


def _disc(c, r, name):
    return Loop((Arc(c, r, 0.0, 2 * math.pi, name=name),))


def test_rotating_parts_out_of_reach_keep_no_pair():
    """A pin 1 from its centre (reach 1.5) and a follower disc 1 from its own
    centre 10 away (reach 1.5): they can never touch; nor, just out of reach,
    a disc that reaches 1 from a centre 3 away (1.5 + 1 < 3)."""
    pair = Pair(Part("a", (_disc((1.0, 0.0), 0.5, "pin"),), Rotation((0.0, 0.0))),
                Part("b", (_disc((11.0, 0.0), 0.5, "disc"),), Rotation((10.0, 0.0))),
                name="far")
    kept, pruned = feature_pairs(pair)
    assert kept == [] and pruned == 1
    pair = Pair(Part("a", (_disc((1.0, 0.0), 0.5, "pin"),), Rotation((0.0, 0.0))),
                Part("b", (_disc((3.5, 0.0), 0.5, "disc"),), Rotation((3.0, 0.0))),
                name="just out of reach")
    assert feature_pairs(pair) == ([], 1)


def test_rotating_parts_within_reach_keep_their_pair():
    """The pin reaches 1.5 from its centre, the disc 1 from its own centre 2
    away: their annuli overlap."""
    pair = Pair(Part("a", (_disc((1.0, 0.0), 0.5, "pin"),), Rotation((0.0, 0.0))),
                Part("b", (_disc((2.5, 0.0), 0.5, "disc"),), Rotation((2.0, 0.0))),
                name="near")
    kept, pruned = feature_pairs(pair)
    assert pruned == 0 and len(kept) == 1
    fa, fb, eq, owner, r = kept[0]
    assert (fa.name, fb.name, r) == ("pin", "disc", 1.0)


def test_pruning_keeps_a_subset_of_the_compatible_pairs_and_counts_the_rest():
    for pair in (rr_pair(), rt_pair()):
        kept, pruned = feature_pairs(pair)
        everything, none = feature_pairs(pair, margin_rel=math.inf)
        assert none == 0
        n = _n_compatible(features(pair.driver, 0), features(pair.follower, 1))
        assert len(everything) == n == len(kept) + pruned
        keys = {(a.key, a.kind, b.key, b.kind, e, o) for a, b, e, o, _ in everything}
        assert {(a.key, a.kind, b.key, b.kind, e, o) for a, b, e, o, _ in kept} <= keys
        # every kept pair has a contact equation
        assert all((e, o, r) in equation_types(a, b) for a, b, e, o, r in kept)


def test_a_slide_that_never_brings_them_together_keeps_nothing():
    """A slider moving along y, 10 to the right of a pin that turns within
    radius 1.5: the slab of x it can reach never meets the pin."""
    pair = Pair(Part("a", (_disc((1.0, 0.0), 0.5, "pin"),), Rotation((0.0, 0.0))),
                Part("b", (Loop.from_bulges([(10, -1), (11, -1), (11, 1), (10, 1)]),),
                     Translation((0.0, 1.0))), name="slide")
    kept, pruned = feature_pairs(pair)
    assert kept == [] and pruned > 0
