import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from cspace.errors import DegenerateGeometryError, InputError
from mechanisms.linkage import (Assembly, FourBar, GrashofType, PoseStatus, grashof,
                                input_range, solve)


def test_loop_closes_and_lengths_hold(crank_rocker):
    t = np.linspace(0, 2 * np.pi, 361)
    m = solve(crank_rocker, t)
    assert m.success and np.all(m.ok)
    assert_allclose(np.hypot(*(m.C - m.B).T), crank_rocker.coupler, atol=1e-12)
    assert_allclose(np.hypot(*(m.C - np.array(crank_rocker.D)).T), crank_rocker.rocker,
                    atol=1e-12)
    assert_allclose(np.hypot(*(m.P - m.B).T), crank_rocker.lp, atol=1e-12)


def test_velocity_and_acceleration_match_finite_differences(crank_rocker):
    w = 1.3
    t = np.linspace(0, 2 * np.pi, 4001)
    h = t[1] - t[0]
    m = solve(crank_rocker, t, omega2=w)
    inner = slice(2, -2)
    assert_allclose(m.omega3[inner], (np.gradient(m.theta3, h) * w)[inner], atol=1e-5)
    assert_allclose(m.omega4[inner], (np.gradient(m.theta4, h) * w)[inner], atol=1e-5)
    assert_allclose(m.alpha4[inner], (np.gradient(m.omega4, h) * w)[inner], atol=1e-5)
    assert_allclose(m.alpha3[inner], (np.gradient(m.omega3, h) * w)[inner], atol=1e-5)
    assert_allclose(m.vP[inner], (np.gradient(m.P, h, axis=0) * w)[inner], atol=1e-5)
    assert_allclose(m.aP[inner], (np.gradient(m.vP, h, axis=0) * w)[inner], atol=1e-5)


def test_angular_acceleration_input_term(crank_rocker):
    # with omega2 = 0 the output acceleration is alpha2 times the velocity ratio
    m0 = solve(crank_rocker, 0.7, omega2=1.0)
    m1 = solve(crank_rocker, 0.7, omega2=0.0, alpha2=2.0)
    assert_allclose(m1.alpha4, 2.0 * m0.omega4, atol=1e-12)
    assert_allclose(m1.omega4, 0.0, atol=0)


def test_branch_is_held_and_open_is_convex(crank_rocker):
    t = np.linspace(0, 4 * np.pi, 721)
    m = solve(crank_rocker, t)
    from cspace.geom2d import cross2
    side = np.sign(cross2(np.array(crank_rocker.D) - m.B, m.C - m.B))
    assert np.all(side == side[0])          # C never changes side of B -> D
    assert side[0] > 0                      # OPEN: C left of B -> D
    mc = solve(crank_rocker.replace(assembly=Assembly.CROSSED), t)
    from cspace.geom2d import cross2
    sc = np.sign(cross2(np.array(crank_rocker.D) - mc.B, mc.C - mc.B))
    assert np.all(sc < 0)
    # continuity: no jumps between successive samples
    assert np.max(np.hypot(*np.diff(m.C, axis=0).T)) < 0.2


@pytest.mark.parametrize("lengths, kind", [
    ((4.0, 1.5, 3.5, 3.0), GrashofType.CRANK_ROCKER),
    ((1.0, 3.0, 3.5, 3.0), GrashofType.DOUBLE_CRANK),
    ((3.0, 2.5, 1.5, 2.8), GrashofType.DOUBLE_ROCKER),
    ((3.0, 2.5, 2.8, 1.5), GrashofType.ROCKER_CRANK),
    ((2.0, 1.0, 2.0, 1.0), GrashofType.CHANGE_POINT),
    ((5.0, 2.0, 3.0, 2.5), GrashofType.TRIPLE_ROCKER),
])
def test_grashof(lengths, kind):
    assert grashof(FourBar.from_lengths(*lengths)) is kind


def test_unassemblable_and_toggle_are_statuses():
    fb = FourBar.from_lengths(5.0, 2.0, 3.0, 2.5)     # triple rocker
    assert grashof(fb) is GrashofType.TRIPLE_ROCKER
    rng = input_range(fb)
    assert not rng.full_turn
    lo, hi = rng.limits
    t = np.array([lo + 1e-9, 0.5 * (lo + hi), hi + 0.3, math.pi + fb.theta1])
    m = solve(fb, t)
    assert m.status[1] == PoseStatus.OK
    assert m.status[0] == PoseStatus.NEAR_TOGGLE
    assert m.status[2] == PoseStatus.UNASSEMBLABLE
    assert np.all(np.isfinite(m.omega4)) and np.all(np.isfinite(m.C))
    assert m.omega4[2] == 0.0 and not m.success


def test_dead_centre_flag(crank_rocker):
    # rocker extremes: crank and coupler collinear; omega4 changes sign there
    t = np.linspace(0, 2 * np.pi, 20001)
    m = solve(crank_rocker, t)
    flips = np.nonzero(np.diff(np.sign(m.omega4)))[0]
    assert len(flips) == 2
    for i in flips:
        assert m.dead_centre[i] or m.dead_centre[i + 1]


def test_degrees_only_through_unit(crank_rocker):
    a = solve(crank_rocker, 30.0, unit="deg")
    b = solve(crank_rocker, math.radians(30.0))
    assert_allclose(a.theta4, b.theta4, atol=1e-15)


def test_bad_input_raises_typed_errors(crank_rocker):
    with pytest.raises(InputError, match="crank must be > 0"):
        FourBar.from_lengths(4.0, -1.0, 3.5, 3.0)
    with pytest.raises(InputError, match="assembly must be"):
        FourBar.from_lengths(4.0, 1.0, 3.5, 3.0, assembly="sideways")
    with pytest.raises(DegenerateGeometryError, match="distinct"):
        FourBar((0, 0), (0, 0), 1.0, 1.0, 1.0)
    with pytest.raises(InputError, match="unit must be one of"):
        solve(crank_rocker, 1.0, unit="grad")
    with pytest.raises(InputError, match="finite"):
        solve(crank_rocker, [0.0, float("nan")])
    with pytest.raises(InputError, match="expects a FourBar"):
        solve("fourbar", 0.0)


def test_repr_and_to_dict(crank_rocker):
    m = solve(crank_rocker, [0.0, 1.0])
    assert "FourBarMotion(n=2" in repr(m)
    d = m.to_dict()
    assert d["status"] == ["OK", "OK"] and len(d["theta4"]) == 2
    assert FourBar(**{**crank_rocker.to_dict(), "assembly": "open"}) == crank_rocker


@settings(max_examples=60, deadline=None)
@given(l=st.lists(st.floats(0.5, 5.0), min_size=4, max_size=4),
       t=st.floats(-math.pi, math.pi), branch=st.sampled_from([1, -1]))
def test_random_poses_close_or_report(l, t, branch):
    if 2 * max(l) >= sum(l):
        # the loop closes at no angle: refused when built
        with pytest.raises(DegenerateGeometryError, match="closes at no crank angle"):
            FourBar.from_lengths(*l, assembly=branch)
        return
    fb = FourBar.from_lengths(*l, assembly=branch)
    m = solve(fb, t)
    if m.status[0] == PoseStatus.UNASSEMBLABLE:
        bd = math.hypot(m.B[0, 0] - fb.D[0], m.B[0, 1] - fb.D[1])
        assert bd > l[2] + l[3] - 1e-9 or bd < abs(l[2] - l[3]) + 1e-9
    else:
        # a tangent (toggle) pose is clamped to the double point: its residual is
        # ~sqrt(tangent_rel) of the link lengths; well-conditioned poses close exactly
        atol = 1e-9 if m.status[0] == PoseStatus.OK else 1e-5
        assert_allclose(np.hypot(*(m.C - np.array(fb.D)).T), l[3], atol=atol)
        assert_allclose(np.hypot(*(m.C - m.B).T), l[2], atol=atol)


def test_a_loop_that_never_closes_and_degree_angles_are_refused():
    """A four-bar whose longest link is as long as the other three together
    closes at no angle: refused when built.  A fixed angle beyond a turn in
    rad (38 meaning degrees) is refused with the unit='deg' hint; a string
    is not an angle."""
    with pytest.raises(DegenerateGeometryError, match=r"ground \(1000\) must be shorter"):
        FourBar.from_lengths(1000, 40, 120, 100)
    with pytest.raises(InputError, match=r"written in degrees\? pass unit='deg'"):
        FourBar.from_lengths(110, 40, 120, 100, lp=10, alpha=38)
    fb = FourBar.from_lengths(110, 40, 120, 100, lp=10, alpha=38, unit="deg")
    assert fb.alpha == pytest.approx(math.radians(38))
    with pytest.raises(InputError, match="must be numbers"):
        solve(fb, "60")
    with pytest.raises(InputError, match="must be numbers"):
        solve(fb, [True, False])


@pytest.mark.parametrize("lengths", [(100, 40, 100, 40), (120, 40, 100, 60)])
def test_a_linkage_that_touches_a_toggle_turns_fully(lengths):
    """A parallelogram (|BD| reaches both |l3 - l4| and l3 + l4) and a
    change-point linkage pass their toggles: every crank angle assembles, and
    input_range says so (it used to report a half turn or (-pi, pi))."""
    fb = FourBar.from_lengths(*lengths)
    t = np.linspace(-math.pi, math.pi, 721)
    assert np.all(solve(fb, t).status != PoseStatus.UNASSEMBLABLE)
    r = input_range(fb)
    assert r.full_turn and r.limits == ()


def test_a_two_dimensional_input_is_refused():
    """solve takes one angle or a 1-D array (it flattened a 2-D one)."""
    fb = FourBar.from_lengths(110, 40, 120, 100)
    with pytest.raises(InputError, match=r"1-D array of them, got an array of shape \(2, 2\)"):
        solve(fb, np.zeros((2, 2)))
    assert len(solve(fb, [0.1, 0.2]).status) == 2 and len(solve(fb, 0.1).status) == 1
