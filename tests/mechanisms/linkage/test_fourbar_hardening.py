"""Four-bar kinematics and mechanical error: units of angle deviations, both
input intervals, rates at a toggle, worst-case bounds near a toggle, and typed
errors for bad input."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError, NonFiniteError, NumericalError
from mechanisms.linkage import (ErrorStatus, FourBar, PoseStatus, ToleranceSpec,
                                coupler_ellipse, exact_error, harmonic_fit, harmonic_max,
                                input_range, linear_error, monte_carlo, rss, sensitivity,
                                solve, worst_case)
from mechanisms.linkage.error import clearance_b_closed_form


@pytest.fixture
def fb():
    return FourBar.from_lengths(10, 3, 8, 7, lp=4, alpha=0.5)


@pytest.fixture
def rocker():
    """Non-Grashof: the crank rocks between toggles, at |BD| = l3 + l4 and
    |BD| = |l3 - l4|."""
    return FourBar.from_lengths(5, 4, 3, 4.5)


# ---------------------------------------------------------------- 1. units


def test_angle_deviations_follow_the_call_unit(fb):
    a = exact_error(fb, 50, dl={"alpha": 1.0, "theta1": -0.5}, unit="deg")
    b = exact_error(fb, math.radians(50), dl={"alpha": math.radians(1.0),
                                              "theta1": math.radians(-0.5)})
    assert_allclose(a.dP, b.dP, atol=1e-15)
    assert_allclose(a.d_theta4, b.d_theta4, atol=1e-15)
    c = exact_error(fb, 50, dl={"alpha": 1.0}, unit="deg")
    assert_allclose(c.dP[0], [-0.0626094, 0.0308840], atol=1e-6)     # 1 deg, not 1 rad
    la = linear_error(fb, 50, dl={"alpha": 1.0}, unit="deg")
    lb = linear_error(fb, math.radians(50), dl={"alpha": math.radians(1.0)})
    assert_allclose(la.dP, lb.dP, atol=1e-15)
    # a length deviation is a length in either unit
    assert_allclose(exact_error(fb, 50, dl={"l2": 0.01}, unit="deg").dP,
                    exact_error(fb, math.radians(50), dl={"l2": 0.01}).dP, atol=1e-15)


def test_an_angle_deviation_beyond_a_turn_is_refused(fb):
    with pytest.raises(InputError, match=r"dl\['alpha'\] must lie within a turn.*unit='deg'"):
        exact_error(fb, 0.9, dl={"alpha": 100})
    with pytest.raises(InputError, match=r"dl\['theta1'\] must lie within a turn"):
        linear_error(fb, 50, dl={"theta1": 400}, unit="deg")
    with pytest.raises(InputError, match=r"lengths\['alpha'\] must lie within a turn"):
        ToleranceSpec(lengths={"alpha": 100})


def test_a_crank_angle_too_large_to_give_a_direction_is_refused(fb):
    """Many turns are a crank angle (720 deg is 0 deg); 1e20 rad is not: the
    doubles there lie 16384 rad apart, so the crank's direction is whichever
    double the value was rounded to.  It was solved without a word."""
    assert_allclose(solve(fb, 720, unit="deg").theta4, solve(fb, 0.0).theta4, atol=1e-12)
    for call in (lambda: solve(fb, 1e20), lambda: solve(fb, [0.5, -1e9], unit="deg"),
                 lambda: exact_error(fb, 1e20, dl={"l2": 0.01})):
        with pytest.raises(InputError, match=r"theta2 must be an angle of at most 4194304 rad "
                                             r".*no longer give a direction"):
            call()


def test_a_spec_carries_the_unit_of_its_angle_tolerances(fb):
    deg = ToleranceSpec(lengths={"alpha": 0.5, "theta1": 0.2, "l2": 0.01}, unit="deg")
    rad = ToleranceSpec(lengths={"alpha": math.radians(0.5), "theta1": math.radians(0.2),
                                 "l2": 0.01}, unit="rad")
    assert deg.lengths["alpha"] == pytest.approx(math.radians(0.5)) and deg.unit == "rad"
    t = math.radians(50)
    for spec in (deg, rad):
        # the call's unit is that of theta2 only: a spec means the same in both
        for call in ({"theta2": 50, "unit": "deg"}, {"theta2": t}):
            w = worst_case(fb, call["theta2"], spec, unit=call.get("unit", "rad"))
            assert w.linear_max == pytest.approx(worst_case(fb, t, rad).linear_max, rel=1e-12)
            r = rss(fb, call["theta2"], spec, unit=call.get("unit", "rad"))
            assert r.value == pytest.approx(rss(fb, t, rad).value, rel=1e-12)
            m = monte_carlo(fb, call["theta2"], spec, 50, seed=1,
                            unit=call.get("unit", "rad"))
            assert_allclose(m.samples, monte_carlo(fb, t, rad, 50, seed=1).samples,
                            atol=1e-14)
    # half a degree on alpha, not half a radian: lp sin(0.5 deg) of coupler-point error
    half_deg = worst_case(fb, t, ToleranceSpec(lengths={"alpha": 0.5}, unit="deg"),
                          quantity="px").linear_max
    assert half_deg < 0.1 * worst_case(fb, t, ToleranceSpec(lengths={"alpha": 0.5}),
                                       quantity="px").linear_max
    assert 0 < half_deg <= fb.lp * math.radians(0.5) * (1 + 1e-12)


def test_a_spec_without_a_unit_is_refused_by_a_call_in_degrees(fb):
    loose = ToleranceSpec(lengths={"alpha": 0.01})
    for f in (worst_case, rss, lambda *a, **k: monte_carlo(*a, 20, seed=1, **k)):
        with pytest.raises(InputError, match=r"angle tolerances \(alpha\) without a stated "
                                             r"unit.*unit='deg'"):
            f(fb, 50, loose, unit="deg")
        f(fb, math.radians(50), loose)                       # rad: as documented
    # lengths and clearances only: nothing to mistake
    f = ToleranceSpec(lengths={"l1": 0.01}, clearances={"B": 0.01})
    assert worst_case(fb, 50, f, unit="deg").status is ErrorStatus.OK


# ---------------------------------------------------------------- 2. input range


def test_both_mirror_intervals_are_reported():
    fb = FourBar.from_lengths(4.5, 5, 4, 3)
    r = input_range(fb)
    assert not r.full_turn and len(r.intervals) == 2
    assert r.limits == r.intervals[0]
    lo, hi = r.intervals[0]
    mlo, mhi = r.intervals[1]
    assert mlo == pytest.approx(2 * fb.theta1 - hi) and mhi == pytest.approx(2 * fb.theta1 - lo)
    assert "mirror interval" in repr(r) and r.to_dict()["intervals"][1] == [mlo, mhi]
    # the reported case: -50 deg assembles, and lies in the mirror interval
    assert solve(fb, math.radians(-50)).status[0] != PoseStatus.UNASSEMBLABLE
    assert r.contains(-50, unit="deg")
    # every angle assembles exactly when it lies in one of the intervals
    t = np.linspace(-math.pi, math.pi, 3601)
    m = solve(fb, t)
    near = np.min([np.abs(t - x) for iv in r.intervals for x in iv], axis=0) < 1e-6
    assembles = m.status != PoseStatus.UNASSEMBLABLE
    assert np.array_equal(assembles[~near], r.contains(t)[~near])
    assert assembles.any() and not assembles.all()
    # solving along the mirror interval works, and never crosses to the first
    ms = solve(fb, np.linspace(mlo + 1e-6, mhi - 1e-6, 200))
    assert ms.success


def test_a_single_interval_and_a_full_turn():
    r = input_range(FourBar.from_lengths(5.0, 2.0, 3.0, 2.5))
    assert len(r.intervals) == 1 and r.intervals[0] == r.limits and "mirror" not in repr(r)
    full = input_range(FourBar.from_lengths(4.0, 1.5, 3.5, 3.0))
    assert full.full_turn and full.intervals == () and bool(full.contains(1.234))


# ---------------------------------------------------------------- 3. rates at a toggle


def test_rates_at_an_exact_toggle_are_unbounded_not_plausible(rocker):
    lo, hi = input_range(rocker).limits
    for t, inside in ((lo, lo + 1e-9), (hi, hi - 1e-9)):
        m = solve(rocker, t, omega2=1.0, alpha2=0.3)
        assert m.toggle[0] and m.status[0] == PoseStatus.NEAR_TOGGLE
        assert np.all(np.isfinite(m.B)) and np.all(np.isfinite(m.C))    # positions valid
        near = solve(rocker, inside, omega2=1.0, alpha2=0.3)
        assert not near.toggle[0]
        for k in ("omega3", "omega4", "alpha3", "alpha4"):
            v = getattr(m, k)[0]
            assert np.isinf(v), (k, v)                       # was 0.735, 0.230 at lo
            assert np.sign(v) == np.sign(getattr(near, k)[0]), k   # the limit's sign
        assert not np.any(np.isnan(m.vP)) and not np.any(np.isnan(m.aP))
        assert "exactly at a toggle" in repr(m)
    # at rest at the toggle nothing moves
    rest = solve(rocker, lo, omega2=0.0, alpha2=0.0)
    assert rest.toggle[0] and rest.omega4[0] == 0.0 and rest.alpha4[0] == 0.0


def test_sensitivities_at_an_exact_toggle_are_unbounded(rocker):
    lo, _ = input_range(rocker).limits
    for src in ("l1", "l2", "l3", "l4", "B"):
        s = sensitivity(rocker, lo, src, [0.3])
        near = sensitivity(rocker, lo + 1e-9, src, [0.3])
        assert np.isinf(s.dtheta4[0]) and np.sign(s.dtheta4[0]) == np.sign(near.dtheta4[0])
        assert s.status is ErrorStatus.NEAR_TOGGLE
    li = linear_error(rocker, lo, joint="B", radius=1e-3, delta=[0.3, 2.0],
                      dl={"l2": 1e-3, "l3": -1e-3})
    assert np.all(np.isinf(li.d_theta4)) and not np.any(np.isnan(li.dP))
    h = harmonic_max(rocker, lo, "B", 1e-3, method="linear")
    assert h.status is ErrorStatus.NEAR_TOGGLE and h.amplitude == math.inf
    assert math.isfinite(h.phase)
    with pytest.raises(NumericalError, match="exactly at a toggle"):
        clearance_b_closed_form(rocker, lo, [0.0])
    with pytest.raises(NumericalError, match="exactly at a toggle"):
        coupler_ellipse(rocker.replace(lp=1.0), lo, "B", 1e-3)


# ---------------------------------------------------------------- 4. worst case near a toggle


@pytest.mark.parametrize("where", ["lo", "lo-in", "hi", "hi-in"])
def test_worst_case_near_a_toggle_bounds_monte_carlo(rocker, where):
    lo, hi = input_range(rocker).limits
    t2 = {"lo": lo, "lo-in": lo + 1e-4, "hi": hi, "hi-in": hi - 1e-4}[where]
    spec = ToleranceSpec(lengths={"l2": 1e-3}, clearances={"B": 1e-3})
    w = worst_case(rocker, t2, spec)
    assert w.exact_min <= 0.0 <= w.exact_max                    # never inverted
    assert w.partial and w.status is ErrorStatus.UNASSEMBLABLE and not w.success
    assert "assembling part" in repr(w) and "no bound" in repr(w)
    for pins in ("circle", "disc"):
        mc = monte_carlo(rocker, t2, spec, 4000, seed=7, pins=pins)
        assert mc.n_infeasible > 0
        assert w.exact_min <= mc.minimum and mc.maximum <= w.exact_max
    # the extremes are attained by variants in the box that assemble
    for arg, value in ((w.argmax, w.exact_max), (w.argmin, w.exact_min)):
        ex, ey = arg["B"]
        assert abs(arg["l2"]) <= 1e-3 and math.hypot(ex, ey) <= 1e-3 * (1 + 1e-12)
        c = exact_error(rocker, t2, joint="B", radius=math.hypot(ex, ey),
                        delta=math.atan2(ey, ex) - t2 - math.pi, dl={"l2": arg["l2"]})
        assert c.status[0] != ErrorStatus.UNASSEMBLABLE
        assert c.d_theta4[0] == pytest.approx(value, abs=1e-9)


def test_worst_case_far_from_a_toggle_is_unchanged(rocker):
    lo, hi = input_range(rocker).limits
    spec = ToleranceSpec(lengths={"l2": 1e-3}, clearances={"B": 1e-3})
    w = worst_case(rocker, 0.5 * (lo + hi), spec)
    assert w.status is ErrorStatus.OK and w.success and not w.partial
    assert w.exact_min < 0 < w.exact_max
    assert w.exact_max == pytest.approx(w.linear_max, rel=0.05)


def test_worst_case_of_an_unassemblable_nominal_shows_no_bounds():
    fb = FourBar.from_lengths(5, 4, 3, 4.5)
    w = worst_case(fb, 0.0, ToleranceSpec(lengths={"l2": 1e-3}))
    assert w.status is ErrorStatus.UNASSEMBLABLE and "no bounds" in repr(w)


# ---------------------------------------------------------------- 5-7. typed errors


def test_harmonic_fit_refuses_non_finite_and_non_numbers():
    with pytest.raises(NonFiniteError, match=r"finite values, got \[1.0, nan, 2.0\]"):
        harmonic_fit([1, float("nan"), 2])
    with pytest.raises(NonFiniteError):
        harmonic_fit([1, 2, 3], [0.0, 1.0, float("inf")])
    with pytest.raises(InputError, match="3 real numbers"):
        harmonic_fit(["a", "b", "c"])
    with pytest.raises(InputError, match="3 values at 3 angles"):
        harmonic_fit([1.0, 2.0])


def test_bad_arguments_raise_typed_errors(fb):
    spec = ToleranceSpec(lengths={"l2": 0.01}, clearances={"B": 0.01})
    with pytest.raises(InputError, match="delta must hold at least one angle"):
        exact_error(fb, 0.9, joint="B", radius=0.1, delta=[])
    with pytest.raises(InputError, match="segment_rel must be a real number"):
        coupler_ellipse(fb, 0.9, "B", 0.1, segment_rel="x")
    with pytest.raises(InputError, match=r"segment_rel must be a ratio in \(0, 1\)"):
        coupler_ellipse(fb, 0.9, "B", 0.1, segment_rel=2.0)
    with pytest.raises(InputError, match="input_range expects a FourBar, got tuple"):
        input_range((1, 2, 3, 4))
    with pytest.raises(InputError, match="tol must be a LinkageTolerances"):
        solve(fb, 1.0, tol=0.1)
    with pytest.raises(InputError, match="tol must be a LinkageTolerances"):
        worst_case(fb, 1.0, spec, tol=None)
    with pytest.raises(InputError, match=r"FourBar.replace takes the fields .*got 'foo'"):
        fb.replace(foo=1)
    assert fb.replace(crank=3.5).crank == 3.5


def test_wrong_input_is_not_silently_accepted(fb):
    spec = ToleranceSpec(lengths={"l2": 0.01}, clearances={"B": 0.01})
    with pytest.raises(InputError, match=r"1-D array of them, got an array of shape \(2, 2\)"):
        exact_error(fb, 0.9, joint="B", radius=0.1, delta=np.zeros((2, 2)))
    with pytest.raises(InputError, match=r"shape \(2, 2\)"):
        linear_error(fb, 0.9, joint="B", radius=0.1, delta=np.zeros((2, 2)))
    for bad in ("a", -1, 0, 2.5, True):
        with pytest.raises(InputError, match=r"maxiter must be an int >= 1, got"):
            worst_case(fb, 0.9, spec, maxiter=bad)


def test_the_linear_error_of_parts_that_cannot_be_assembled_says_so():
    """A coupler 7 mm longer (the ground 10, crank 3, coupler 8, rocker 7
    then cannot close at 0.5 rad): the first-order error is UNASSEMBLABLE and
    reads 0, as the exact one; a small change keeps its numbers and status."""
    from mechanisms.linkage import exact_error, linear_error
    fb = FourBar.from_lengths(10, 3, 8, 7)
    for f in (linear_error, exact_error):
        c = f(fb, 0.5, dl={"l3": 7.0})
        assert c.status.tolist() == [ErrorStatus.UNASSEMBLABLE]
        assert c.d_theta4.tolist() == [0.0]
    small = linear_error(fb, 0.5, dl={"l3": 0.05})
    assert small.status.tolist() == [ErrorStatus.OK] and small.d_theta4[0] != 0.0
    # a pin clearance: only the pin directions whose variant does not close
    pins = linear_error(fb, 0.5, joint="B", radius=0.05, delta=[0.0, 1.0, 2.0])
    assert (pins.status == ErrorStatus.OK).all()


def test_ragged_angles_are_a_typed_error(fb):
    from mechanisms.linkage import exact_error, solve
    with pytest.raises(InputError, match="every row of the same length"):
        solve(fb, [[0.1], [0.2, 0.3]])
    with pytest.raises(InputError, match="delta must be numbers"):
        exact_error(fb, 0.5, joint="B", radius=0.1, delta=[[0], [1, 2]])


def test_a_speed_that_is_not_finite_is_named_speed():
    from cspace.errors import CSpaceError
    from mechanisms.linkage import ClearanceLinkage, free_flight
    with pytest.raises(CSpaceError, match="speed"):
        free_flight(ClearanceLinkage.reference(), float("nan"), 100e-6)
