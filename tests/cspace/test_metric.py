"""The C-space metric: a slide of one characteristic length counts as one
radian; a rotating follower's angles are placed in the window."""

import math

import numpy as np
import pytest

from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from cspace.metric import coord_scale, driver_scale, follower_scale, split_wrapped, wrap_to

TWO_PI = 2 * math.pi


def _disc(name, center, r, axis):
    return Part(name, (Loop((Arc(center, r, 0.0, TWO_PI, name=f"{name}.rim"),)),), axis)


def _square(name, x0, y0, s, axis):
    return Part(name, (Loop.from_bulges([(x0, y0), (x0 + s, y0), (x0 + s, y0 + s),
                                         (x0, y0 + s)]),), axis)


def test_coord_scale_is_one_for_a_rotation_and_L_for_a_slide():
    assert coord_scale(Rotation((3.0, 4.0)), 25.0) == 1.0
    assert coord_scale(Translation((0.0, 1.0)), 25.0) == 25.0


def test_scales_of_a_crank_and_slider():
    """A disc of radius 1 centred 4 from its rotation centre reaches 5: L = 5,
    so the slider's coordinate counts in fives, the crank's in radians."""
    crank = _disc("crank", (4.0, 0.0), 1.0, Rotation((0.0, 0.0)))
    slider = _square("slider", 6.0, -1.0, 2.0, Translation((1.0, 0.0)))
    pair = Pair(crank, slider)
    assert pair.char_length == pytest.approx(5.0)
    assert driver_scale(pair) == 1.0
    assert follower_scale(pair) == pytest.approx(5.0)
    # the roles swapped: a sliding driver
    back = Pair(slider, crank)
    assert driver_scale(back) == pytest.approx(5.0) and follower_scale(back) == 1.0


def test_two_slides_count_in_the_larger_part_size():
    a = _square("a", 0.0, 0.0, 3.0, Translation((1.0, 0.0)))       # diagonal 3 sqrt 2
    b = _square("b", 5.0, 0.0, 1.0, Translation((0.0, 1.0)))
    pair = Pair(a, b)
    assert driver_scale(pair) == follower_scale(pair) == pytest.approx(3 * math.sqrt(2))


def test_wrap_to_lands_in_one_turn_from_lo():
    x = np.array([-10.0, -math.pi, 0.0, 1.0, 2 * math.pi, 20.0])
    for lo in (0.0, -math.pi, 0.25, -7.0):
        w = wrap_to(x, lo)
        assert np.all(w >= lo) and np.all(w < lo + TWO_PI)
        k = (x - w) / TWO_PI
        np.testing.assert_allclose(k, np.round(k), atol=1e-12)
    assert wrap_to(1.0, 0.0) == 1.0
    assert wrap_to(-1.0, 0.0) == pytest.approx(TWO_PI - 1.0)


def test_split_wrapped_leaves_a_non_periodic_polyline_alone():
    pl = np.array([[0.0, 0.0], [1.0, 10.0], [2.0, -10.0]])
    out = split_wrapped(pl, 0.0, False)
    assert len(out) == 1 and out[0] is pl


def test_split_wrapped_cuts_where_the_wrapped_angle_jumps():
    # q2 rises through 2 pi (the window's top) once: two pieces, both in the window
    q1 = np.linspace(0.0, 1.0, 11)
    q2 = np.linspace(5.0, 8.0, 11)
    out = split_wrapped(np.stack([q1, q2], 1), 0.0, True)
    assert len(out) == 2
    for piece in out:
        assert np.all((piece[:, 1] >= 0.0) & (piece[:, 1] < TWO_PI))
        assert np.all(np.abs(np.diff(piece[:, 1])) <= math.pi)
    # every point kept, in order, at its wrapped angle
    joined = np.vstack(out)
    np.testing.assert_array_equal(joined[:, 0], q1)
    np.testing.assert_allclose(joined[:, 1], q2 % TWO_PI)
    n_before = int(np.sum(q2 < TWO_PI))
    assert len(out[0]) == n_before


def test_split_wrapped_drops_single_point_pieces():
    # the middle point alone lies across the seam: it forms no piece
    pl = np.array([[0.0, 6.0], [1.0, 6.2], [2.0, 6.4], [3.0, 6.0], [4.0, 6.1]])
    out = split_wrapped(pl, 0.0, True)
    assert [len(p) for p in out] == [2, 2]
    np.testing.assert_array_equal(out[0][:, 0], [0.0, 1.0])
    np.testing.assert_array_equal(out[1][:, 0], [3.0, 4.0])


def test_split_wrapped_without_a_jump_is_one_piece():
    pl = np.array([[0.0, -3.0], [1.0, -2.5], [2.0, -2.0]])
    out = split_wrapped(pl, -math.pi, True)
    assert len(out) == 1
    np.testing.assert_allclose(out[0], pl)
