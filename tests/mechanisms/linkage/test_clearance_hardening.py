"""Input checks, ground inference and the reproducibility of the free-flight
results of the clearance-dynamics module (docs/fourbar.md, free flight)."""

import inspect
import math
import warnings

import numpy as np
import pytest

from cspace.errors import InputError, NonFiniteError, NumericalError
from mechanisms.linkage.clearance import (ClearanceLinkage, FlightStatus, continuous_contact,
                                          free_flight, hertz_stiffness, infer_ground,
                                          rocker_zero_acceleration)


@pytest.fixture(scope="module")
def link():
    return ClearanceLinkage.reference()


@pytest.fixture(scope="module")
def flight(link):
    """The documented default run: 100 rpm, 100 um."""
    return free_flight(link, 100, 100e-6)


# ---------------------------------------------------------------------------
# free flight: transient, episode window, reproducibility
# ---------------------------------------------------------------------------

def test_default_run_is_the_documented_one(flight):
    """Three revolutions, the first discarded as start-up transient."""
    params = inspect.signature(free_flight).parameters
    assert params["revolutions"].default == 3
    assert params["transient"].default == 1
    assert flight.status is FlightStatus.OK
    assert (flight.revolutions, flight.transient, flight.analysed) == (3, 1, 2)
    assert {e.revolution for e in flight.events} <= {1, 2}
    d = flight.to_dict()
    assert (d["revolutions"], d["transient"]) == (3, 1)
    assert d["events"][0]["revolution"] >= 1


def test_near_zero_episode_is_reported_whole(flight):
    """An episode is reported from its separation, not from where an analysis
    window happens to cut its impact train (the near-0 deg train used to be
    split at the start angle of the run, 15.6 deg at 100 rpm)."""
    near = [e for e in flight.events
            if abs(math.remainder(e.separation, 2 * math.pi)) < math.radians(30)]
    assert len(near) == flight.analysed                     # one per analysed revolution
    for e in near:
        sep = math.degrees(math.remainder(e.separation, 2 * math.pi))
        assert -1.5 < sep < -0.5                             # just before 0 deg
        first = math.degrees(math.remainder(e.first_impact, 2 * math.pi))
        last = math.degrees(math.remainder(e.last_impact, 2 * math.pi))
        strongest = math.degrees(math.remainder(e.strongest_impact, 2 * math.pi))
        assert sep < first <= strongest <= last
        assert e.impacts >= 5


def test_a_run_is_the_beginning_of_a_longer_one(link, flight):
    """The events of a revolution do not depend on how many follow it."""
    short = free_flight(link, 100, 100e-6, revolutions=2)
    assert short.events
    assert short.events == flight.events[:len(short.events)]
    assert {e.revolution for e in short.events} == {1}


def test_halving_rtol_keeps_separation_and_first_impact(link, flight):
    """The impact train is sensitive (its strongest impact jumps between the
    impacts of the train), but the separation and the first impact converge:
    halving rtol moves their medians by less than 0.3 and 1.0 deg."""
    half = free_flight(link, 100, 100e-6, rtol=flight_rtol() / 2)
    a, b = flight.spread(0.0, unit="deg"), half.spread(0.0, unit="deg")
    assert a["episodes"] == b["episodes"] == 2
    assert abs(a["separation"][1] - b["separation"][1]) < 0.3
    assert abs(a["first_impact"][1] - b["first_impact"][1]) < 1.0
    for s in (a, b):
        # the measured spread of docs/fourbar.md (20 revolutions, 4 tolerances)
        assert -1.5 < s["separation"][0] and s["separation"][2] < -0.5
        assert 3.5 < s["first_impact"][0] and s["first_impact"][2] < 6.0
        assert 4.0 < s["strongest_impact"][0] and s["strongest_impact"][2] < 26.0
        assert 0.015 < s["impact_velocity"][0] and s["impact_velocity"][2] < 0.060


def flight_rtol():
    return inspect.signature(free_flight).parameters["rtol"].default


def test_spread_of_nothing_and_its_arguments(flight):
    s = flight.spread(200.0, window=5.0, unit="deg")
    assert s["episodes"] == 0 and s["revolutions"] == 2 and s["first_impact"] is None
    with pytest.raises(InputError, match=r"window must lie in \(0, pi\]"):
        flight.spread(0.0, window=0.0)
    with pytest.raises(InputError, match="unit must be one of"):
        flight.spread(0.0, unit="grad")


@pytest.mark.slow
def test_slow_documented_spread_at_100rpm(link):
    """The 100 rpm row of the free-flight table of docs/fourbar.md (20 analysed
    revolutions) and its convergence in rtol."""
    stats = [free_flight(link, 100, 100e-6, revolutions=22, transient=2, rtol=r)
             .spread(0.0, window=30.0, unit="deg") for r in (1e-8, 5e-9)]
    for s in stats:
        assert s["episodes"] == 20
        assert -1.3 < s["separation"][0] and s["separation"][2] < -0.7
        assert 3.5 < s["first_impact"][0] and s["first_impact"][2] < 5.5
        assert 4.5 < s["strongest_impact"][0] and s["strongest_impact"][2] < 26.0
    assert abs(stats[0]["separation"][1] - stats[1]["separation"][1]) < 0.1
    assert abs(stats[0]["first_impact"][1] - stats[1]["first_impact"][1]) < 0.3


# ---------------------------------------------------------------------------
# free flight: numerical controls
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("kw, match", [
    ({"samples": "a"}, "samples must be an int >= 2"),
    ({"samples": 1}, "samples must be an int >= 2"),
    ({"min_flight": "a"}, "min_flight must be a real number"),
    ({"min_flight": -0.1}, "min_flight must be >= 0"),
    ({"min_flight": 10.0}, r"min_flight must be a crank angle in \[0, 2 pi\] rad"),
    ({"cluster_gap": "a"}, "cluster_gap must be a real number"),
    ({"rtol": -1}, r"rtol must be a relative tolerance in \[1e-13, 1\)"),
    ({"rtol": 0.0}, r"rtol must be a relative tolerance in \[1e-13, 1\)"),
    ({"rtol": 1.0}, r"rtol must be a relative tolerance in \[1e-13, 1\)"),
    ({"rtol": "a"}, "rtol must be a real number"),
    ({"max_events": 0}, "max_events must be an int >= 1"),
    ({"transient": 3}, r"transient must be smaller than revolutions \(3\)"),
    ({"transient": -1}, "transient must be an int >= 0"),
    ({"revolutions": 1}, r"transient must be smaller than revolutions \(1\)"),
])
def test_free_flight_controls_are_checked_before_integrating(link, kw, match):
    with warnings.catch_warnings():
        warnings.simplefilter("error")                      # no solver warning instead
        with pytest.raises(InputError, match=match):
            free_flight(link, 100, 100e-6, **kw)


def test_free_flight_nan_rtol_is_non_finite(link):
    with pytest.raises(NonFiniteError):
        free_flight(link, 100, 100e-6, rtol=float("nan"))


# ---------------------------------------------------------------------------
# Hertz stiffness
# ---------------------------------------------------------------------------

def test_hertz_stiffness_default_value(link):
    # (4/3) E* sqrt(R*), steel on steel, 13 mm bush, 100 um: about 9.8e10 N/m^1.5
    assert hertz_stiffness(link, 100e-6) == pytest.approx(9.781e10, rel=1e-3)
    assert math.isfinite(hertz_stiffness(link, 100e-6, nu=0.5))
    assert math.isfinite(hertz_stiffness(link, 100e-6, nu=-0.5))


@pytest.mark.parametrize("args, kw, match", [
    ((-1,), {}, "clearance must be > 0, got -1"),
    ((0.0,), {}, "clearance must be > 0"),
    ((0.01,), {}, r"smaller than the bush radius \(0.0065 m\)"),
    (("a",), {}, "clearance must be a real number"),
    ((1e-4,), {"E": -1}, "E must be > 0"),
    ((1e-4,), {"E": 0}, "E must be > 0"),
    ((1e-4,), {"nu": 1.0}, r"nu must be a Poisson's ratio in \(-1, 0.5\]"),
    ((1e-4,), {"nu": 0.6}, r"nu must be a Poisson's ratio in \(-1, 0.5\]"),
    ((1e-4,), {"nu": -1.0}, r"nu must be a Poisson's ratio in \(-1, 0.5\]"),
    ((1e-4,), {"nu": "a"}, "nu must be a real number"),
])
def test_hertz_stiffness_refuses_arguments_out_of_range(link, args, kw, match):
    with pytest.raises(InputError, match=match):
        hertz_stiffness(link, *args, **kw)


def test_hertz_stiffness_needs_a_linkage():
    with pytest.raises(InputError, match="expected a ClearanceLinkage"):
        hertz_stiffness("link", 1e-4)


# ---------------------------------------------------------------------------
# ground inference
# ---------------------------------------------------------------------------

def test_infer_ground_reads_radians_by_default(link):
    assert inspect.signature(infer_ground).parameters["unit"].default == "rad"
    deg = infer_ground(link, 119.0, unit="deg")
    assert deg.success
    assert infer_ground(link).ground == pytest.approx(deg.ground, abs=1e-9)
    rad = infer_ground(link, 2.08)                          # 119.2 deg
    assert rad.success and 0.100 < rad.ground < 0.140
    assert math.degrees(rad.target) == pytest.approx(119.18, abs=0.01)
    assert np.degrees(rad.zeros[0]) == pytest.approx(119.18, abs=0.05)


def test_infer_ground_refuses_degrees_read_as_radians(link):
    with pytest.raises(InputError, match=r"target must be a crank angle in \(0, pi\) rad.*"
                                         r"unit='deg'"):
        infer_ground(link, 119.0)


def test_infer_ground_failure_is_loud(link):
    """No ground in the bracket puts the zero at 100 deg: an error that gives the
    bracket and what was found at its ends, not the bracket end."""
    with pytest.raises(NumericalError, match=r"100.00 deg: with the bracket \(0.1, 0.14\) m "
                                             r"the first zero .* lies at 111.\d\d and "):
        infer_ground(link, 100.0, unit="deg")


@pytest.mark.parametrize("bracket, match", [
    (0.1, r"bracket must be two ground lengths \(lo, hi\) in m, got 0.1"),
    ((0.1,), "bracket must be two ground lengths"),
    ("ab", "bracket must be two ground lengths"),
    ((0.1, -0.2), "bracket must be > 0"),
    ((0.1, 0.1), "bracket must be two different ground lengths"),
    ((0.10, 0.35), "bracket end 0.35 m is no ground length of this linkage"),
])
def test_infer_ground_bracket_is_checked(link, bracket, match):
    with pytest.raises(InputError, match=match):
        infer_ground(link, bracket=bracket)


def test_infer_ground_bracket_in_either_order(link):
    assert infer_ground(link, bracket=(0.14, 0.10)).ground == \
        pytest.approx(infer_ground(link).ground, abs=1e-9)


# ---------------------------------------------------------------------------
# other typed errors
# ---------------------------------------------------------------------------

def test_percentile_range(link):
    c = continuous_contact(link, 100, 100e-6, n=3600)
    assert c.percentile(100) == pytest.approx(c.R.max())
    for q in (200, -1, 100.5):
        with pytest.raises(InputError, match=r"q must be a percentile in \[0, 100\]"):
            c.percentile(q)
    with pytest.raises(InputError, match="q must be a real number"):
        c.percentile("50")


def test_rocker_zero_acceleration_checks_n_and_the_turn(link):
    with pytest.raises(InputError, match="n must be an int >= 360, got 'a'"):
        rocker_zero_acceleration(link, n="a")
    with pytest.raises(InputError, match="n must be an int >= 360, got 1"):
        rocker_zero_acceleration(link, n=1)
    from dataclasses import replace
    with pytest.raises(InputError, match=r"assembles over \d+ % of it"):
        rocker_zero_acceleration(replace(link, ground=0.35))


def test_reference_refuses_unknown_fields():
    with pytest.raises(InputError, match=r"unknown field\(s\) foo; the fields that can be "
                                         r"changed are crank, .*bush_radius, assembly"):
        ClearanceLinkage.reference(foo=1)
    assert ClearanceLinkage.reference(gravity=0.0).gravity == 0.0


def test_an_inertia_below_m_r_squared_is_refused():
    from mechanisms.linkage.clearance import ClearanceLinkage
    args = dict(crank=0.03, coupler=0.09, rocker=0.07, ground=0.1, m_coupler=0.2,
                m_rocker=0.15, J_coupler=5.4e-4, J_rocker=2.45e-4, cg_coupler=0.045,
                cg_rocker=0.035)
    ClearanceLinkage(**args)
    # about B: 0.2 kg at 45 mm needs at least 4.05e-4 kg m^2
    with pytest.raises(InputError, match=r"J_coupler is the moment of inertia about B, at "
                                         r"least m r\^2 = 0.000405 kg m\^2"):
        ClearanceLinkage(**dict(args, J_coupler=1e-9))
    # about D: the centre of mass is 70 - 35 mm from D
    with pytest.raises(InputError, match="J_rocker is the moment of inertia about D"):
        ClearanceLinkage(**dict(args, J_rocker=1e-4))
