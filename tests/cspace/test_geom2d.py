"""Shared 2-D geometry: wrapping, rigid motions and the circle/line
intersections with their branch convention (left of c1 -> c2 is +1)."""

import math

import numpy as np
import pytest

from cspace.geom2d import (TWO_PI, IntersectionKind, circle_circle, cross2, dot2, line_circle,
                           norm2, perp, rot, rotate, transform, unit, wrap_2pi, wrap_pi)


# ------------------------------------------------------------------ wrapping
def test_wrap_pi_lands_in_the_half_open_range_and_keeps_the_angle():
    a = np.array([-7.0, -math.pi, -1.0, 0.0, 1.0, math.pi, 3 * math.pi, 10.0, 123.4])
    w = wrap_pi(a)
    assert np.all(w >= -math.pi) and np.all(w < math.pi)
    # the same direction: a whole number of turns apart
    k = (a - w) / TWO_PI
    np.testing.assert_allclose(k, np.round(k), atol=1e-12)
    # pi itself maps to -pi (the range is [-pi, pi))
    assert wrap_pi(math.pi) == pytest.approx(-math.pi)
    assert wrap_pi(0.5) == 0.5


def test_wrap_2pi_lands_in_zero_to_two_pi():
    a = np.array([-TWO_PI, -0.25, 0.0, 0.25, TWO_PI, 7.0])
    w = wrap_2pi(a)
    assert np.all(w >= 0) and np.all(w < TWO_PI)
    np.testing.assert_allclose(w, [0.0, TWO_PI - 0.25, 0.0, 0.25, 0.0, 7.0 - TWO_PI],
                               atol=1e-12)


# ------------------------------------------------------------------ rigid motions
def test_rot_is_a_proper_rotation_and_composes():
    t = np.array([0.0, 0.3, -1.2, 2.5])
    R = rot(t)
    assert R.shape == (4, 2, 2)
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(2), R.shape),
                               atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-15)
    np.testing.assert_allclose(rot(0.3) @ rot(-1.2), rot(0.3 - 1.2), atol=1e-15)
    # counter-clockwise: x turns into y by a quarter turn
    np.testing.assert_allclose(rot(math.pi / 2) @ [1.0, 0.0], [0.0, 1.0], atol=1e-15)


def test_rotate_about_a_center():
    p = np.array([[3.0, 1.0], [1.0, 2.0]])
    out = rotate(p, math.pi / 2, center=(1.0, 1.0))
    np.testing.assert_allclose(out, [[1.0, 3.0], [0.0, 1.0]], atol=1e-15)
    # distances to the centre are kept, and the centre stays
    np.testing.assert_allclose(norm2(out - [1.0, 1.0]), norm2(p - [1.0, 1.0]), atol=1e-15)
    np.testing.assert_allclose(rotate([1.0, 1.0], 0.7, center=(1.0, 1.0)), [1.0, 1.0])


def test_rotate_broadcasts_theta_against_the_points():
    theta = np.array([0.0, math.pi / 2, math.pi])
    out = rotate(np.array([2.0, 0.0]), theta)
    np.testing.assert_allclose(out, [[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0]], atol=1e-15)
    # the same as rotating each point with the matrix of its angle
    np.testing.assert_allclose(out, np.einsum("nij,j->ni", rot(theta), [2.0, 0.0]), atol=1e-15)


def test_transform_rotates_about_the_origin_then_translates():
    out = transform([[1.0, 0.0]], math.pi / 2, (5.0, -1.0))
    np.testing.assert_allclose(out, [[5.0, 0.0]], atol=1e-15)


def test_vector_products():
    a = np.array([[1.0, 0.0], [2.0, 3.0]])
    b = np.array([[0.0, 1.0], [4.0, -1.0]])
    np.testing.assert_array_equal(cross2(a, b), [1.0, 2.0 * -1.0 - 3.0 * 4.0])
    np.testing.assert_array_equal(dot2(a, b), [0.0, 8.0 - 3.0])
    # perp is a quarter turn counter-clockwise: cross(v, perp v) = |v|^2, dot = 0
    np.testing.assert_array_equal(perp(a), [[-0.0, 1.0], [-3.0, 2.0]])
    np.testing.assert_allclose(cross2(a, perp(a)), dot2(a, a))
    np.testing.assert_array_equal(dot2(a, perp(a)), [0.0, 0.0])
    np.testing.assert_allclose(norm2([[3.0, 4.0], [1e200, 1e200]]), [5.0, math.sqrt(2) * 1e200])


def test_unit_vectors_and_the_zero_vector():
    u = unit([[3.0, 4.0], [0.0, -2.0], [0.0, 0.0]])
    np.testing.assert_allclose(u, [[0.6, 0.8], [0.0, -1.0], [1.0, 0.0]])
    assert np.all(np.isfinite(u))


# ------------------------------------------------------------------ circle/circle
def test_circle_circle_branches_of_a_3_4_5_triangle():
    """Circles of radius 3 about the origin and 4 about (5, 0) meet where the
    3-4-5 right triangle has its right angle: (9/5, +-12/5)."""
    p, k = circle_circle((0.0, 0.0), 3.0, (5.0, 0.0), 4.0, branch=1)
    np.testing.assert_allclose(p, [1.8, 2.4], atol=1e-14)
    assert k == IntersectionKind.TWO
    p, k = circle_circle((0.0, 0.0), 3.0, (5.0, 0.0), 4.0, branch=-1)
    np.testing.assert_allclose(p, [1.8, -2.4], atol=1e-14)
    # swapping the circles swaps left and right
    p, _ = circle_circle((5.0, 0.0), 4.0, (0.0, 0.0), 3.0, branch=1)
    np.testing.assert_allclose(p, [1.8, -2.4], atol=1e-14)


def test_circle_circle_branch_is_left_of_the_line_of_centres():
    rng = np.random.default_rng(4)
    c1 = rng.uniform(-5, 5, (50, 2))
    c2 = rng.uniform(-5, 5, (50, 2))
    d = norm2(c2 - c1)
    r1 = rng.uniform(0.6, 1.0, 50) * d
    r2 = rng.uniform(0.6, 1.0, 50) * d           # r1 + r2 > d > |r1 - r2|: they meet
    branch = rng.choice([-1.0, 1.0], 50)
    p, k = circle_circle(c1, r1, c2, r2, branch)
    assert np.all(k == IntersectionKind.TWO)
    np.testing.assert_allclose(norm2(p - c1), r1, rtol=1e-12)
    np.testing.assert_allclose(norm2(p - c2), r2, rtol=1e-12)
    assert np.all(np.sign(cross2(c2 - c1, p - c1)) == branch)


def test_circle_circle_tangent_cases():
    # external tangency: the touching point on the line of centres
    p, k = circle_circle((0.0, 0.0), 1.0, (3.0, 0.0), 2.0)
    assert k == IntersectionKind.TANGENT
    np.testing.assert_allclose(p, [1.0, 0.0], atol=1e-15)
    # internal tangency
    p, k = circle_circle((0.0, 0.0), 3.0, (1.0, 0.0), 2.0, branch=-1)
    assert k == IntersectionKind.TANGENT
    np.testing.assert_allclose(p, [3.0, 0.0], atol=1e-15)
    # a discriminant within tol * (r1 + r2)^2 of zero counts as tangent
    _, k = circle_circle((0.0, 0.0), 1.0, (3.0 + 1e-9, 0.0), 2.0, tol=1e-6)
    assert k == IntersectionKind.TANGENT
    _, k = circle_circle((0.0, 0.0), 1.0, (3.0 + 1e-3, 0.0), 2.0, tol=1e-6)
    assert k == IntersectionKind.NONE


def test_circle_circle_without_intersection_is_finite():
    c1 = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [1.0, 1.0]])
    c2 = np.array([[10.0, 0.0], [1.0, 0.0], [1.0, 1.0], [1.0, 1.0]])
    r1 = np.array([1.0, 5.0, 2.0, 2.0])
    r2 = np.array([2.0, 1.0, 2.0, 1.0])
    p, k = circle_circle(c1, r1, c2, r2)
    assert np.all(np.isfinite(p))
    assert k.tolist() == [IntersectionKind.NONE, IntersectionKind.NONE,
                          IntersectionKind.COINCIDENT, IntersectionKind.NONE]
    # apart: a point on the segment between the two circles, on the line of centres
    assert p[0, 1] == 0.0 and 1.0 <= p[0, 0] <= 8.0
    # concentric: the common centre
    np.testing.assert_array_equal(p[2:], [[1.0, 1.0], [1.0, 1.0]])


def test_circle_circle_nested_without_intersection_gives_the_radical_axis_foot():
    # the circle about (1, 0) of radius 1 lies inside the one about the origin of
    # radius 5: no intersection; the point returned is the foot of the radical
    # axis on the line of centres, a = (d^2 + r1^2 - r2^2) / (2 d) = 12.5
    p, k = circle_circle((0.0, 0.0), 5.0, (1.0, 0.0), 1.0)
    assert k == IntersectionKind.NONE
    np.testing.assert_allclose(p, [12.5, 0.0], atol=1e-12)


def test_circle_circle_vectorises_over_leading_dimensions():
    c2 = np.zeros((3, 4, 2))
    c2[..., 0] = 5.0
    p, k = circle_circle(np.zeros(2), np.full((3, 4), 3.0), c2, 4.0,
                         branch=np.where(np.arange(4) % 2 == 0, 1, -1))
    assert p.shape == (3, 4, 2) and k.shape == (3, 4)
    np.testing.assert_allclose(p[:, 0], np.broadcast_to([1.8, 2.4], (3, 2)), atol=1e-14)
    np.testing.assert_allclose(p[:, 1], np.broadcast_to([1.8, -2.4], (3, 2)), atol=1e-14)


# ------------------------------------------------------------------ line/circle
def test_line_circle_parameters_are_sorted_and_exact():
    # the line y = 0 from (-5, 0) with direction (2, 0) meets the unit circle at x = -1, 1
    t, k = line_circle((-5.0, 0.0), (2.0, 0.0), (0.0, 0.0), 1.0)
    assert k == IntersectionKind.TWO
    np.testing.assert_allclose(t, [2.0, 3.0], atol=1e-15)
    # reversed direction: still t[0] <= t[1]
    t, _ = line_circle((5.0, 0.0), (-1.0, 0.0), (0.0, 0.0), 1.0)
    np.testing.assert_allclose(t, [4.0, 6.0], atol=1e-15)
    # the points lie on the circle
    p0, v = np.array([0.3, -2.0]), np.array([0.2, 1.0])
    t, _ = line_circle(p0, v, (0.5, 0.5), 1.5)
    pts = p0 + t[:, None] * v
    np.testing.assert_allclose(norm2(pts - [0.5, 0.5]), 1.5, rtol=1e-13)


def test_line_circle_tangent_and_missing():
    t, k = line_circle((-3.0, 1.0), (1.0, 0.0), (0.0, 0.0), 1.0)
    assert k == IntersectionKind.TANGENT
    np.testing.assert_allclose(t, [3.0, 3.0], atol=1e-7)
    # no intersection: both parameters at the foot of the perpendicular from the centre
    t, k = line_circle((-3.0, 2.0), (2.0, 0.0), (1.0, 0.0), 1.0)
    assert k == IntersectionKind.NONE
    assert t[0] == t[1] == pytest.approx(2.0)


def test_line_circle_vectorises():
    r = np.array([0.5, 1.0, 2.0])
    t, k = line_circle(np.array([0.0, 1.0]), np.array([1.0, 0.0]), np.zeros(2), r)
    assert k.tolist() == [IntersectionKind.NONE, IntersectionKind.TANGENT, IntersectionKind.TWO]
    np.testing.assert_allclose(t[2], [-math.sqrt(3), math.sqrt(3)])


def test_radical_foot_recovers_both_intersections_of_random_circles():
    from cspace.geom2d import radical_foot
    rng = np.random.default_rng(3)
    c1, c2 = rng.uniform(-5, 5, (1000, 2)), rng.uniform(-5, 5, (1000, 2))
    d = norm2(c2 - c1)
    r1 = rng.uniform(0.1, 5, 1000)
    r2 = np.abs(d - r1) + rng.uniform(1e-3, 1, 1000) * (d + r1 - np.abs(d - r1))
    base, n, h2 = radical_foot(c1, r1, c2, r2)
    assert np.all(h2 > 0)
    for sgn in (1, -1):
        x = base + sgn * np.sqrt(h2)[:, None] * n
        np.testing.assert_allclose(norm2(x - c1), r1, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(norm2(x - c2), r2, rtol=1e-9, atol=1e-9)
    # +n is the left of c1 -> c2
    assert np.all(cross2(c2 - c1, n) > 0)
    # the same centre: no point, finite numbers
    b, nn, hh = radical_foot((1.0, 2.0), 1.0, (1.0, 2.0), 1.0)
    assert hh == -1.0 and np.allclose(b, [1.0, 2.0]) and np.all(np.isfinite(nn))


def test_line_line_and_the_quadratic_recover_random_meeting_points():
    from cspace.geom2d import line_circle_quadratic, line_line
    rng = np.random.default_rng(4)
    p, r, q, s = (rng.uniform(-3, 3, (1000, 2)) for _ in range(4))
    t, u, rxs = line_line(p, r, q, s)
    np.testing.assert_allclose(p + t[:, None] * r, q + u[:, None] * s, atol=1e-6)
    t, u, rxs = line_line((0, 0), (1, 0), (0, 1), (2, 0))
    assert rxs == 0 and t == 0 and u == 0                    # parallel: flagged, finite
    c, rad = rng.uniform(-1, 1, (1000, 2)), rng.uniform(0.5, 2, 1000)
    a, b, disc = line_circle_quadratic(p, r, c, rad)
    ok = disc >= 0
    for sgn in (-1, 1):
        tt = (-b + sgn * np.sqrt(np.where(ok, disc, 0))) / (2 * a)
        x = p + tt[:, None] * r
        np.testing.assert_allclose(norm2(x - c)[ok], rad[ok], rtol=1e-8)


def test_wrap_pi_is_the_remainder_formula_bit_for_bit():
    """wrap_pi computes (a + pi) % 2 pi - pi without numpy's division: the same
    bits, on random angles of every size, exact multiples of pi and zeros."""
    rng = np.random.default_rng(11)
    a = np.concatenate([rng.normal(size=20000) * s for s in (1.0, 10.0, 1e3, 1e9)]
                       + [np.arange(-40, 41) * math.pi, [0.0, -0.0, 5e-324, -5e-324]])
    ref = (a + math.pi) % TWO_PI - math.pi
    got = wrap_pi(a)
    assert got.dtype == ref.dtype and np.array_equal(got, ref)
    assert np.array_equal(np.signbit(got), np.signbit(ref))
    assert type(wrap_pi(7.0)) is type((7.0 + math.pi) % TWO_PI - math.pi + np.float64(0))


@pytest.mark.parametrize("scale", [0.5, 1.0, 3.0, 6.0, 10.0])
def test_wrap_pi_is_the_remainder_formula_bit_for_bit_on_each_range(scale):
    """The same bits whether or not every angle of the array lies within a
    turn of the range (where fmod is skipped): arrays of one size of angle
    each, the ends of the range, and arrays holding a NaN or an infinity."""
    rng = np.random.default_rng(int(scale * 10))
    edges = [-math.pi, math.pi, TWO_PI - math.pi, -TWO_PI - math.pi,
             np.nextafter(TWO_PI - math.pi, 0.0), np.nextafter(-TWO_PI - math.pi, 0.0)]
    for a in (rng.uniform(-scale * math.pi, scale * math.pi, 5000),
              rng.uniform(-scale * math.pi, scale * math.pi, (7, 9)),
              np.array(edges), np.array([0.0, -0.0]), np.zeros(0)):
        ref = (a + math.pi) % TWO_PI - math.pi
        got = wrap_pi(a)
        assert got.shape == ref.shape and np.array_equal(got, ref)
        assert np.array_equal(np.signbit(got), np.signbit(ref))
    with np.errstate(invalid="ignore"):
        for bad in (math.nan, math.inf, -math.inf):
            a = np.array([0.25, bad, -0.5])
            ref = (a + math.pi) % TWO_PI - math.pi
            assert np.array_equal(wrap_pi(a), ref, equal_nan=True)
    assert wrap_pi(0.25) == (0.25 + math.pi) % TWO_PI - math.pi
