"""Exact overlap and distance tests on lines and arcs, against closed forms for
discs, squares and a ring, and against an independent polygon test."""

import math

import numpy as np
import pytest

from cspace.geometry import Arc, Line, Loop, Pair, Part, Rotation, Translation, place_points
from cspace.overlap import local_point, min_distance, parts_overlap, place_part

from ..conftest import brute_overlap
from . import shapes

TWO_PI = 2 * math.pi


def _circle(name, c, r, ccw=True):
    end = TWO_PI if ccw else -TWO_PI
    return Loop((Arc(c, r, 0.0, end, ccw=ccw, name=name),))


def _crank(R=3.0, r=0.5):
    """A pin of radius r at distance R from the rotation centre (the origin)."""
    return Part("crank", (_circle("pin", (R, 0.0), r),), Rotation((0.0, 0.0)))


def _slider_disc(r):
    return Part("disc", (_circle("rim", (0.0, 0.0), r),), Translation((1.0, 0.0)))


def _ring():
    """A square plate 8 x 8 with a bore of radius 2, sliding along x."""
    outer = Loop.from_bulges([(-4.0, -4.0), (4.0, -4.0), (4.0, 4.0), (-4.0, 4.0)],
                             names=["bot", "right", "top", "left"])
    return Part("ring", (outer, _circle("bore", (0.0, 0.0), 2.0, ccw=False)),
                Translation((1.0, 0.0)))


def _pin_centres(q1, R=3.0):
    return np.stack([R * np.cos(q1), R * np.sin(q1)], -1)


# ------------------------------------------------------------------ two discs
def test_two_discs_overlap_and_distance_in_closed_form():
    """Pin (radius 0.5 at 3 from the origin) and a sliding disc of radius 1
    centred at (q2, 0): they overlap where the centres are closer than 1.5,
    and their boundaries are | |c1 - c2| - 1.5 | apart."""
    pair = Pair(_crank(), _slider_disc(1.0))
    rng = np.random.default_rng(3)
    q = np.column_stack([rng.uniform(0, TWO_PI, 300), rng.uniform(-6, 6, 300)])
    dc = np.hypot(*(_pin_centres(q[:, 0]) - np.column_stack([q[:, 1], 0 * q[:, 1]])).T)
    sure = np.abs(dc - 1.5) > 1e-9
    assert np.array_equal(parts_overlap(pair, q)[sure], (dc < 1.5)[sure])
    d = min_distance(pair, q)
    apart = dc > 1.5
    np.testing.assert_allclose(d[apart], dc[apart] - 1.5, atol=1e-12)
    # overlapping, neither inside the other: the boundaries cross
    cross = (dc < 1.5) & (dc > 0.5)
    assert cross.any() and np.all(d[cross] == 0.0)


def test_a_disc_inside_another_overlaps_without_crossing():
    """The pin inside a large sliding disc (radius 3): no boundary crosses, the
    containment test finds the overlap, and the boundaries are
    3 - (|c1 - c2| + 0.5) apart."""
    pair = Pair(_crank(), _slider_disc(3.0))
    q1 = np.linspace(-0.4, 0.4, 9)
    c = _pin_centres(q1)
    q = np.column_stack([q1, c[:, 0] - 1.0])     # the disc centre 1 left of the pin's
    off = np.hypot(c[:, 0] - q[:, 1], c[:, 1])
    assert np.all(off + 0.5 < 3.0)
    assert parts_overlap(pair, q).all()
    np.testing.assert_allclose(min_distance(pair, q), 3.0 - off - 0.5, atol=1e-12)


def test_a_single_configuration_gives_one_answer():
    pair = Pair(_crank(), _slider_disc(1.0))
    assert parts_overlap(pair, [0.0, 3.0]).tolist() == [True]
    assert parts_overlap(pair, [0.0, 10.0]).tolist() == [False]
    np.testing.assert_allclose(min_distance(pair, [0.0, 10.0]), [10.0 - 3.0 - 1.5])


# ------------------------------------------------------------------ lines
def test_pin_against_a_square_in_closed_form():
    """A 2 x 2 square sliding along x (centre (q2, 0)) and the pin: distance
    from the pin's centre to the square minus its radius."""
    sq = Part("square", (Loop.from_bulges([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0),
                                           (-1.0, 1.0)]),), Translation((1.0, 0.0)))
    pair = Pair(_crank(), sq)
    rng = np.random.default_rng(5)
    q = np.column_stack([rng.uniform(0, TWO_PI, 300), rng.uniform(-6, 6, 300)])
    c = _pin_centres(q[:, 0])
    dx = np.maximum(np.abs(c[:, 0] - q[:, 1]) - 1.0, 0.0)
    dy = np.maximum(np.abs(c[:, 1]) - 1.0, 0.0)
    to_square = np.hypot(dx, dy)        # 0 inside the square
    gap = to_square - 0.5
    sure = np.abs(gap) > 1e-9
    assert np.array_equal(parts_overlap(pair, q)[sure], (gap < 0)[sure])
    d = min_distance(pair, q)
    apart = gap > 0
    assert apart.sum() > 100
    np.testing.assert_allclose(d[apart], gap[apart], atol=1e-12)


def test_a_pin_in_the_bore_of_a_plate_does_not_overlap():
    """Even-odd containment: in the bore the pin is free, in the plate's
    material it overlaps, beyond the plate it is free again."""
    pair = Pair(_crank(), _ring())
    #          in the bore,  in material,  crossing the edge,  apart
    q = np.array([[0.0, 2.0], [0.0, 0.0], [0.0, 6.5], [0.0, 12.0], [0.0, -3.0]])
    assert parts_overlap(pair, q).tolist() == [False, True, True, False, False]
    # bore edge 2 - 1 - 0.5; bore edge and plate edge both 0.5; crossing; 12 - 4 - 3.5;
    # plate edge at x = 1 from the pin's left side at 2.5
    np.testing.assert_allclose(min_distance(pair, q), [0.5, 0.5, 0.0, 4.5, 1.5], atol=1e-12)


def test_distance_of_a_pin_centred_in_a_bore():
    pair = Pair(_crank(), _ring())
    # the bore's centre on the pin's centre: a clearance of 2 - 0.5 all round
    assert parts_overlap(pair, [0.0, 3.0]).tolist() == [False]
    np.testing.assert_allclose(min_distance(pair, [0.0, 3.0]), [1.5], atol=1e-12)


def test_distance_of_a_line_through_an_arc_centre():
    a = math.radians(30.0)
    # a segment of a disc: the arc from -30 to 30 deg about the origin and its chord
    seg = Loop((Arc((0.0, 0.0), 1.0, -a, a, name="arc"),
                Line((math.cos(a), math.sin(a)), (math.cos(a), -math.sin(a)), name="chord")))
    bar = Loop.from_bulges([(-0.2, -1.0), (0.0, -1.0), (0.0, 1.0), (-0.2, 1.0)])
    pair = Pair(Part("segment", (seg,), Rotation((0.0, 0.0))),
                Part("bar", (bar,), Translation((1.0, 0.0))))
    # the bar's right edge x = 0 runs through the arc's centre; the chord is cos 30 away
    np.testing.assert_allclose(min_distance(pair, [0.0, 0.0]), [math.cos(a)], atol=1e-12)


# ------------------------------------------------------------------ independent reference
def test_rotating_pair_agrees_with_a_polygon_overlap_test():
    """Two rotating parts with every segment type (the broad phase prunes by
    swept annuli): the same verdict as shapely polygons, away from contact."""
    pair = shapes.rr_pair()
    rng = np.random.default_rng(11)
    q = rng.uniform(-math.pi, math.pi, (400, 2))
    d = min_distance(pair, q)
    sure = d > 1e-3
    ours = parts_overlap(pair, q)
    assert ours.any() and (~ours).any()
    assert np.array_equal(ours[sure], brute_overlap(pair, q[sure]))
    # where the boundaries are apart and the parts overlap, one lies inside the other
    assert np.all(d[ours & sure] > 0)


def test_rotating_driver_sliding_follower_agrees_with_a_polygon_overlap_test():
    pair = shapes.rt_pair()
    rng = np.random.default_rng(12)
    q = np.column_stack([rng.uniform(-math.pi, math.pi, 300), rng.uniform(-2.0, 2.0, 300)])
    sure = min_distance(pair, q) > 1e-3
    ours = parts_overlap(pair, q)
    assert ours.any() and (~ours).any()
    assert np.array_equal(ours[sure], brute_overlap(pair, q[sure]))


# ------------------------------------------------------------------ placing parts
def test_place_part_moves_lines_and_arcs():
    sq = Loop.from_bulges([(1.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0)])
    rot_part = Part("r", (sq, _circle("pin", (-2.0, 0.0), 0.5)), Rotation((0.0, 0.0)))
    q = np.array([0.0, math.pi / 2])
    segs = place_part(rot_part, q)
    assert [s[0] for s in segs] == ["line"] * 4 + ["arc"]
    kind, a, b = segs[0]
    np.testing.assert_allclose(a, [[1.0, 0.0], [0.0, 1.0]], atol=1e-15)
    np.testing.assert_allclose(b, [[2.0, 0.0], [0.0, 2.0]], atol=1e-15)
    kind, c, r, mid, half = segs[4]
    np.testing.assert_allclose(c, [[-2.0, 0.0], [0.0, -2.0]], atol=1e-15)
    arc = rot_part.loops[1].segments[0]
    assert r == 0.5 and half == pytest.approx(math.pi)
    # a rotating part's arcs turn with it
    np.testing.assert_allclose(mid, arc.mid_angle + q)
    slide = Part("s", (sq, _circle("pin", (-2.0, 0.0), 0.5)), Translation((0.0, 1.0)))
    segs = place_part(slide, q)
    np.testing.assert_allclose(segs[0][1], [[1.0, 0.0], [1.0, math.pi / 2]])
    # a sliding part's arcs keep their angles
    np.testing.assert_allclose(segs[4][3], [arc.mid_angle] * 2)


@pytest.mark.parametrize("axis", [Rotation((0.5, -1.0)), Translation((3.0, 4.0))],
                         ids=["rotation", "translation"])
def test_local_point_undoes_the_motion(axis):
    part = Part("p", (_circle("rim", (4.0, 0.0), 1.0),), axis)
    rng = np.random.default_rng(2)
    body = rng.uniform(-5, 5, (20, 2))
    q = rng.uniform(-3, 3, 20)
    world = place_points(axis, q, body)
    np.testing.assert_allclose(local_point(part, q, world), body, atol=1e-12)
    if isinstance(axis, Translation):
        # a unit slide along (0.6, 0.8)
        np.testing.assert_allclose(world - body, q[:, None] * np.array([[0.6, 0.8]]),
                                   atol=1e-12)
