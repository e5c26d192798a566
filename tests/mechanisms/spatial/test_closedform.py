"""The closed-form input-output equations (``mechanisms.spatial.closedform``),
checked against the constraints they solve and against geometry constructed
by hand, without the HD solver."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mechanisms.spatial import closedform as cf


def _circle_meet(b, rb, d, rd):
    """Both intersections of the circles about b (radius rb) and d (radius rd)."""
    v = d - b
    dist = math.hypot(*v)
    x = (dist ** 2 + rb ** 2 - rd ** 2) / (2 * dist)
    h2 = rb ** 2 - x ** 2
    if h2 < 0:
        return None
    u = v / dist
    n = np.array([-u[1], u[0]])
    return b + x * u + math.sqrt(h2) * n, b + x * u - math.sqrt(h2) * n


@pytest.mark.parametrize("A, B, C", [(1.0, 2.0, 0.5), (-3.0, 0.5, 2.9), (0.0, -1.0, 0.99),
                                     (2.0, 0.0, -2.0)])
def test_solve_harmonic_roots(A, B, C):
    roots = []
    for br in (1, -1):
        x, ok = cf.solve_harmonic(A, B, C, br)
        assert ok
        assert A * math.cos(x) + B * math.sin(x) == pytest.approx(C, abs=1e-12)
        roots.append(x)
    # the branches are the two roots, mirrored about atan2(B, A)
    mid = math.atan2(B, A)
    assert roots[0] - mid == pytest.approx(mid - roots[1], abs=1e-12)


def test_solve_harmonic_without_a_root():
    x, ok = cf.solve_harmonic(1.0, 1.0, 1.5, 1)           # |C| > sqrt(2)
    assert not ok and math.isfinite(x)
    assert cf.solve_harmonic(0.0, 0.0, 0.0, 1) == (0.0, False)
    # rounding at an exact limit position still counts as a root
    r = math.hypot(3.0, 4.0)
    x, ok = cf.solve_harmonic(3.0, 4.0, r * (1 + 1e-13), -1)
    assert ok and x == pytest.approx(math.atan2(4.0, 3.0), abs=1e-6)
    assert not cf.solve_harmonic(3.0, 4.0, r * (1 + 1e-9), 1)[1]


@pytest.mark.parametrize("a, b, c, d", [(2.0, 7.0, 9.0, 6.0), (1.0, 3.0, 2.5, 3.2),
                                        (5.0, 4.0, 3.0, 4.5)])
def test_freudenstein_is_the_four_bar_by_trigonometry(a, b, c, d):
    """A at the origin, D = (d, 0), B = a (cos theta, sin theta); C lies b from B and
    c from D; phi is the angle of DC from AD."""
    D = np.array([d, 0.0])
    for th in np.linspace(0.0, 2 * math.pi, 37):
        B = a * np.array([math.cos(th), math.sin(th)])
        meet = _circle_meet(B, b, D, c)
        sols = [cf.freudenstein(a, b, c, d, th, br) for br in (1, -1)]
        if meet is None:
            assert not sols[0][1] and not sols[1][1]
            continue
        assert sols[0][1] and sols[1][1]
        want = sorted(math.atan2(C[1], C[0] - d) % (2 * math.pi) for C in meet)
        got = sorted(phi % (2 * math.pi) for phi, _ in sols)
        assert_allclose(np.cos(got), np.cos(want), atol=1e-10)
        assert_allclose(np.sin(got), np.sin(want), atol=1e-10)


def test_the_non_grashof_four_bar_has_gaps():
    """5, 4, 3, 4.5: the crank cannot pass where |B - D| > b + c."""
    ok = [cf.freudenstein(5.0, 4.0, 3.0, 4.5, th, 1)[1] for th in np.linspace(0, math.pi, 91)]
    assert any(ok) and not all(ok)


@pytest.mark.parametrize("alphas", [(0.5, 1.5, 1.0, 1.2), (0.3, 1.2, 0.9, 1.0)])
def test_spherical_4r_closes_the_coupler(alphas):
    a0, a1, a2, a3 = alphas
    z0 = np.array([0.0, 0.0, 1.0])
    z3 = np.array([0.0, math.sin(a3), math.cos(a3)])
    assert z0 @ z3 == pytest.approx(math.cos(a3))
    for th in np.linspace(0.0, 2 * math.pi, 13):
        z1 = np.array([math.sin(th) * math.sin(a0), -math.cos(th) * math.sin(a0), math.cos(a0)])
        for br in (1, -1):
            psi, ok = cf.spherical_4r_psi(alphas, th, br)
            assert ok
            z2 = cf.spherical_4r_z2(alphas, psi)
            assert np.linalg.norm(z2) == pytest.approx(1.0, abs=1e-14)
            assert z1 @ z2 == pytest.approx(math.cos(a1), abs=1e-12)      # the coupler
            assert z2 @ z3 == pytest.approx(math.cos(a2), abs=1e-14)      # the output link
        # the two branches are two assemblies, apart at every input of a full turn
        zp = cf.spherical_4r_z2(alphas, cf.spherical_4r_psi(alphas, th, 1)[0])
        zm = cf.spherical_4r_z2(alphas, cf.spherical_4r_psi(alphas, th, -1)[0])
        assert np.linalg.norm(zp - zm) > 1e-3


def test_spherical_4r_without_assembly():
    # a coupler arc (2.5 rad) longer than the other three can span at theta = 0
    assert not cf.spherical_4r_psi((0.2, 2.5, 0.2, 0.3), 0.0, 1)[1]


def test_rssr_geometry():
    geo = cf.RSSRGeometry(crank=1.0, crank_height=0.5, coupler=3.0, rocker=2.0, offset=2.5,
                          twist=math.radians(60), rocker_height=0.5)
    u = geo.axis
    e1, e2 = geo.basis
    assert_allclose([u @ u, e1 @ e1, e2 @ e2, u @ e1, u @ e2, e1 @ e2], [1, 1, 1, 0, 0, 0],
                    atol=1e-15)
    # the axes are 60 deg apart and 2.5 apart: the common normal is the x-axis
    assert math.acos(u @ [0.0, 0.0, 1.0]) == pytest.approx(math.radians(60), abs=1e-15)
    p_out = np.array([-2.5, 0.0, 0.0])
    n = np.cross([0.0, 0.0, 1.0], u)
    assert abs(p_out @ n) / np.linalg.norm(n) == pytest.approx(2.5, abs=1e-15)
    assert_allclose(geo.rocker_centre, p_out - 0.5 * u, atol=1e-15)
    for phi in np.linspace(-3.0, 3.0, 7):
        c = geo.rocker_pin(phi)
        assert np.linalg.norm(c - geo.rocker_centre) == pytest.approx(2.0, abs=1e-14)
        assert (c - geo.rocker_centre) @ u == pytest.approx(0.0, abs=1e-14)
        assert geo.phi_of(c) == pytest.approx(phi, abs=1e-14)
    assert_allclose(geo.crank_pin(0.5), [math.cos(0.5), math.sin(0.5), 0.5], atol=1e-15)
    for th in np.linspace(0.0, 2 * math.pi, 19):
        for br in (1, -1):
            phi, ok = cf.rssr_phi(geo, th, br)
            assert ok
            d = np.linalg.norm(geo.crank_pin(th) - geo.rocker_pin(phi))
            assert d == pytest.approx(3.0, abs=1e-12)                     # the coupler
    short = cf.RSSRGeometry(1.0, 0.5, 0.5, 2.0, 2.5, 1.0, 0.5)
    assert not cf.rssr_phi(short, 0.3, 1)[1]


def test_rccc_pose_closes_in_rotation_and_translation():
    al = tuple(math.radians(v) for v in (30, 80, 60, 70))
    a = (1.0, 3.0, 2.5, 3.5)
    s0 = 0.5
    for th in np.linspace(0.0, 2 * math.pi, 13):
        sol = cf.rccc(al, a, s0, th, 1)
        assert sol.ok
        z, x, o = sol.z, sol.x, sol.origins
        # the rotations are the spherical indicatrix's
        assert sol.psi == pytest.approx(cf.spherical_4r_psi(al, th, 1)[0], abs=1e-15)
        assert_allclose(z[2], cf.spherical_4r_z2(al, sol.psi), atol=1e-15)
        for i in range(4):
            j = (i + 1) % 4
            assert z[i] @ z[j] == pytest.approx(math.cos(al[i]), abs=1e-12)
            # x_j is the unit common normal of axes i and j
            assert np.linalg.norm(x[j]) == pytest.approx(1.0, abs=1e-12)
            assert x[j] @ z[i] == pytest.approx(0.0, abs=1e-12)
            assert x[j] @ z[j] == pytest.approx(0.0, abs=1e-12)
        # the chain of offsets and link lengths returns to the start
        end = o[3] + sol.slides[2] * z[3] + a[3] * x[0]
        assert_allclose(end, 0.0, atol=1e-12)
        assert_allclose(o[1], s0 * z[0] + a[0] * x[1], atol=1e-15)
        assert_allclose(o[2] - o[1], sol.slides[0] * z[1] + a[1] * x[2], atol=1e-12)
