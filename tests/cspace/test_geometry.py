import math

import numpy as np
import pytest

from cspace.errors import (CSpaceError, InputError, NonFiniteError, NonPositiveRadiusError,
                           OpenLoopError, OrientationError, SelfIntersectionError,
                           ZeroDirectionError, ZeroLengthSegmentError)
from cspace.geometry import Arc, Assembly, Line, Loop, Pair, Part, Rotation, Translation

SQ = [(0, 0), (1, 0), (1, 1), (0, 1)]


def square(s=1.0, x=0.0, y=0.0):
    p = [(x + s * a, y + s * b) for a, b in SQ]
    return Loop.from_bulges(p)


def test_square_area_orientation_and_containment():
    lp = square()
    assert lp.area == pytest.approx(1.0, abs=1e-15)
    assert lp.is_ccw
    assert lp.contains((0.5, 0.5)) and not lp.contains((1.5, 0.5))
    assert lp.reversed().area == pytest.approx(-1.0, abs=1e-15)


def test_full_circle_arc():
    c = Loop((Arc((2, 0), 0.5, 0.0, 2 * math.pi),))
    assert c.area == pytest.approx(math.pi * 0.25, rel=1e-14)
    assert c.segments[0].is_full_circle


def test_bulge_arc_geometry():
    lp = Loop.from_bulges([(0, 0), (2, 0)], [1.0, 1.0])  # two half circles: a disk
    assert lp.area == pytest.approx(math.pi, rel=1e-12)
    for s in lp.segments:
        assert s.radius == pytest.approx(1.0, rel=1e-14)


def test_open_loop():
    with pytest.raises(OpenLoopError, match="does not meet"):
        Loop((Line((0, 0), (1, 0)), Line((1, 0.1), (0, 1)), Line((0, 1), (0, 0))))
    with pytest.raises(OpenLoopError, match="does not close"):
        Loop((Line((0, 0), (1, 0)), Line((1, 0), (0, 1)), Line((0, 1), (0, 0.2))))


def test_zero_length_segment():
    with pytest.raises(ZeroLengthSegmentError, match="positive length"):
        Line((1, 1), (1, 1))
    with pytest.raises(ZeroLengthSegmentError):
        Arc((0, 0), 1.0, 0.3, 0.3)


def test_non_positive_radius():
    with pytest.raises(NonPositiveRadiusError, match="radius must be > 0, got -1"):
        Arc((0, 0), -1.0, 0, 1)
    with pytest.raises(NonPositiveRadiusError):
        Arc((0, 0), 0.0, 0, 1)


def test_self_intersection():
    with pytest.raises(SelfIntersectionError, match="crosses itself"):
        Loop.from_bulges([(0, 0), (1, 0), (0, 1), (1, 1)])


def test_loops_of_a_part_must_not_cross():
    with pytest.raises(SelfIntersectionError, match="loop 0 and loop 1"):
        Part("p", (square(), square(1, 0.5, 0.5)))


def test_wrong_orientation():
    hole = square(0.4, 0.3, 0.3)  # ccw, but it is a hole
    with pytest.raises(OrientationError, match="must run clockwise"):
        Part("p", (square(), hole))
    with pytest.raises(OrientationError, match="must run counter-clockwise"):
        Part("p", (square().reversed(),))
    ok = Part("p", (square(), hole.reversed()))
    assert ok.contains((0.1, 0.1)) and not ok.contains((0.5, 0.5))


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite(bad):
    with pytest.raises(NonFiniteError, match="finite"):
        Line((0, bad), (1, 1))
    with pytest.raises(NonFiniteError):
        Arc((0, 0), bad, 0, 1)
    with pytest.raises(NonFiniteError):
        Rotation((bad, 0))


def test_zero_direction():
    with pytest.raises(ZeroDirectionError, match="non-zero"):
        Translation((0.0, 0.0))
    t = Translation((3.0, 4.0))
    assert t.direction == pytest.approx((0.6, 0.8), abs=1e-15)


def test_errors_are_value_errors_and_rooted():
    for cls in (OpenLoopError, ZeroLengthSegmentError, NonPositiveRadiusError,
                SelfIntersectionError, OrientationError, ZeroDirectionError, NonFiniteError):
        assert issubclass(cls, CSpaceError) and issubclass(cls, ValueError)


def test_type_errors_are_typed():
    with pytest.raises(InputError, match="Line or Arc"):
        Loop(("not a segment",))
    with pytest.raises(InputError, match="Part"):
        Pair("a", "b")
    p = Part("a", (square(),))
    with pytest.raises(InputError, match="share one axis"):
        Assembly((Pair(p, Part("b", (square(1, 3, 0),))),
                  Pair(Part("c", (square(),), Rotation((1, 1))), p)))


def test_values_are_frozen_and_hashable():
    lp = square()
    with pytest.raises(Exception):
        lp.segments = ()
    assert hash(lp) == hash(square())
    assert lp == square()


def test_circle_circle_nearly_concentric_is_finite():
    from cspace.geom2d import IntersectionKind, circle_circle
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p, k = circle_circle([0, 0], 1.0, [1e-184, 0], 1.0)
        assert k == IntersectionKind.COINCIDENT and np.all(np.isfinite(p))
        p, k = circle_circle([0, 0], 1.0, [1e-184, 0], 2.0)
        assert k == IntersectionKind.NONE and np.all(np.isfinite(p))
        p, k = circle_circle([0, 0], 1.0, [1.0, 0], 1.0, branch=-1)
        np.testing.assert_allclose(p, [0.5, -math.sqrt(3) / 2], atol=1e-15)


def test_box_pairs_dense_and_tree_agree(monkeypatch):
    """The two ways of pre-selecting segment pairs for the validity checks give the
    same pairs in the same order."""
    from cspace import geometry as g
    rng = np.random.default_rng(3)
    segs = [g.Line(tuple(p), tuple(p + d)) for p, d in
            zip(rng.uniform(0, 10, (300, 2)), rng.normal(0, 0.5, (300, 2)))]
    segs += [g.Arc(tuple(c), 0.3, 0.0, 2.0, True) for c in rng.uniform(0, 10, (100, 2))]
    dense = g._box_pairs(segs, 1e-6)
    monkeypatch.setattr(g, "_BOX_PAIRS_DENSE", 0)
    tree = g._box_pairs(segs, 1e-6)
    assert dense == tree and len(dense) > 0
    assert all(i < j for i, j in dense) and dense == sorted(dense)


def test_nesting_depths_of_nested_rings():
    from cspace.geometry import Arc, Loop, nesting_depths
    rings = [Loop((Arc((0.0, 0.0), r, 0.0, 2 * np.pi, True),)) for r in (4.0, 3.0, 2.0, 1.0)]
    far = Loop((Arc((20.0, 0.0), 1.0, 0.0, 2 * np.pi, True),))
    assert nesting_depths(rings + [far]) == [0, 1, 2, 3, 0]


def test_from_bulges_needs_one_name_per_edge():
    from cspace.errors import InputError
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    with pytest.raises(InputError, match=r"need one name per edge \(4: edge i runs from point i "
                                         r"to point i \+ 1, the last back to the first\), got 2"):
        Loop.from_bulges(square, names=["a", "b"])
    assert [s.name for s in Loop.from_bulges(square, names="abcd").segments] == list("abcd")
