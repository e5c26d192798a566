import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError
from mechanisms.linkage import FourBar, PoseStatus, input_range, solve
from mechanisms.linkage.clearance import (ClearanceLinkage, FlightStatus, LossKind,
                                          continuous_contact, free_flight, infer_ground,
                                          rocker_zero_acceleration)


@pytest.fixture(scope="module")
def link():
    return ClearanceLinkage.reference()


def test_inferred_ground_puts_rocker_zero_acceleration_at_119(link):
    inf = infer_ground(link)
    assert inf.success
    assert 0.115 < inf.ground < 0.125            # DESIGN: "about 120 mm"
    assert_allclose(link.ground, inf.ground, atol=1e-9)
    z = np.degrees(rocker_zero_acceleration(link))
    assert_allclose(z, [119.0, 358.0], atol=0.5)  # paper Fig. 5: 119 and 355 deg


def test_zero_clearance_force_is_the_magnitude(link):
    # Eq. 3 with delta = 0 and alpha from Eq. 7 must return |R| of Eq. 6
    c = continuous_contact(link, 100, 0.0, n=3600)
    assert c.status is PoseStatus.OK
    assert_allclose(c.R, c.R0, rtol=1e-9, atol=1e-9)
    assert np.all(c.R > 0)
    assert not c.loss_angles(LossKind.NEGATIVE_FORCE).size


def test_kinematics_of_the_loop_agree_with_fourbar_solver(link):
    from mechanisms.linkage.clearance import _kinematics
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    z = np.zeros_like(t)
    w = 3.0
    th2, th3, th2d, th3d, th2dd, th3dd, ok = _kinematics(link, t, w, 0.0, z, z, z)
    m = solve(link.fourbar(), t, omega2=w)
    assert np.all(ok)
    assert_allclose(np.cos(th3 - (m.theta4 + np.pi)), 1.0, atol=1e-12)
    assert_allclose(th2d, m.omega3, atol=1e-9)
    assert_allclose(th3dd, m.alpha4, atol=1e-9)


def test_two_losses_at_100um_50rpm(link):
    c = continuous_contact(link, 50, 100e-6)
    assert len(c.losses) == 2
    kinds = {loss.kind for loss in c.losses}
    assert kinds == {LossKind.NEGATIVE_FORCE, LossKind.FORCE_REVERSAL}
    first = [x for x in c.losses if x.kind is LossKind.NEGATIVE_FORCE][0]
    second = [x for x in c.losses if x.kind is LossKind.FORCE_REVERSAL][0]
    assert 150.0 < first.angle_deg < 170.0       # paper: 158 deg
    assert -6.0 < second.signed_deg < 3.0        # paper: -3 deg


def test_loss_positions_over_speed(link):
    firsts, seconds = [], []
    for rpm in (50, 100, 200, 300):
        c = continuous_contact(link, rpm, 100e-6)
        assert len(c.losses) == 2
        firsts.append(c.loss_angles(LossKind.NEGATIVE_FORCE)[0])
        seconds.append(math.remainder(c.loss_angles(LossKind.FORCE_REVERSAL)[0], 2 * math.pi))
    assert np.all(np.diff(firsts) < 0)                       # moves earlier with speed
    assert np.ptp(np.degrees(seconds)) < 2.0                 # stays put near 0 deg
    assert np.all(np.abs(np.degrees(seconds)) < 5.0)


def test_loss_positions_do_not_depend_on_clearance(link):
    a = [continuous_contact(link, 100, d).losses for d in (50e-6, 100e-6, 150e-6)]
    ang = np.array([[x.angle for x in ls] for ls in a])
    assert np.degrees(np.ptp(ang, axis=0)).max() < 1.0


def test_force_grows_with_speed_and_clearance(link):
    for d in (50e-6, 100e-6, 150e-6):
        med = [continuous_contact(link, rpm, d).percentile(50) for rpm in (50, 100, 200, 300)]
        p99 = [continuous_contact(link, rpm, d).percentile(99) for rpm in (50, 100, 200, 300)]
        assert np.all(np.diff(med) > 0) and np.all(np.diff(p99) > 0)
    for rpm in (50, 100, 300):
        cs = [continuous_contact(link, rpm, d) for d in (50e-6, 100e-6, 150e-6)]
        rev = cs[0].loss_angles(LossKind.FORCE_REVERSAL)[0]
        peaks = [c.peak_near(rev) for c in cs]
        assert np.all(np.diff(peaks) > 0)                    # near 0 deg (paper Fig. 4)
        assert np.all(np.diff([c.percentile(50) for c in cs]) > 0)


def test_resolution_converged(link):
    a = continuous_contact(link, 100, 100e-6, n=36000)
    b = continuous_contact(link, 100, 100e-6, n=72000)
    assert_allclose([x.angle for x in a.losses], [x.angle for x in b.losses], atol=2e-3)
    assert_allclose(a.percentile(50), b.percentile(50), rtol=1e-3)


def test_bad_inputs(link):
    with pytest.raises(InputError, match="speed_unit must be"):
        continuous_contact(link, 50, 1e-4, speed_unit="hz")
    with pytest.raises(InputError, match="clearance must be >= 0"):
        continuous_contact(link, 50, -1e-4)
    with pytest.raises(InputError, match="speed must be > 0"):
        continuous_contact(link, 0.0, 1e-4)
    with pytest.raises(InputError, match="expected a ClearanceLinkage"):
        continuous_contact("linkage", 50, 1e-4)
    with pytest.raises(InputError, match="restitution must lie"):
        free_flight(link, 50, 1e-4, restitution=1.5)


def test_free_flight_separates_near_zero_and_impacts_late(link):
    f = free_flight(link, 100, 100e-6, revolutions=2)
    assert f.status is FlightStatus.OK and f.n_switches > 0
    # penetration stays a tiny fraction of the clearance; the pin never leaves it
    assert f.gap.max() < 0.1 * f.clearance
    assert f.gap.min() >= -2.0 * f.clearance - 1e-12
    c = continuous_contact(link, 100, 100e-6)
    rev = c.loss_angles(LossKind.FORCE_REVERSAL)[0]
    near = [e for e in f.events
            if abs(math.remainder(e.separation - rev, 2 * math.pi)) < math.radians(10)]
    assert near, f.events
    e = near[0]
    late = math.degrees(math.remainder(e.strongest_impact - rev, 2 * math.pi))
    assert 0.0 < late < 30.0           # paper: measured impacts ~15 deg late
    assert repr(f).startswith("FreeFlightResult(100 rpm")
    assert f.to_dict()["status"] == "OK"


@pytest.mark.slow
def test_slow_free_flight_over_speeds(link):
    # every speed integrates to the end and finds at least one contact-loss episode
    for rpm in (50, 100, 200, 300):
        f = free_flight(link, rpm, 100e-6, revolutions=3)
        assert f.status is FlightStatus.OK
        assert len(f.events) >= 1
        assert f.gap.max() < 0.2 * f.clearance


def test_a_crank_that_cannot_turn_and_a_clearance_in_other_units_are_refused(link):
    """The analyses drive the crank through a whole turn: a linkage that
    assembles over part of it is refused, with where it does; a clearance as
    large as the crank or the bush (micrometres typed as metres) too."""
    rocker = ClearanceLinkage(crank=.06, coupler=.05, rocker=.04, ground=.11, m_coupler=.3,
                              m_rocker=.25, J_coupler=.0014, J_rocker=.0008, cg_coupler=.03,
                              cg_rocker=.02)
    with pytest.raises(InputError, match=r"assembles over \d+ % of it; it assembles for "
                                         r"crank angles in \["):
        continuous_contact(rocker, 200, 50e-6)
    with pytest.raises(InputError, match=r"smaller than the bush radius .*50 um is 5e-05"):
        continuous_contact(link, 200, 50)
    with pytest.raises(InputError, match="smaller than the bush radius"):
        free_flight(link, 200, 0.01)


def test_a_change_point_linkage_is_flagged_near_toggle():
    # crank 30 + ground 100 = coupler 70 + rocker 60: coupler and rocker come in
    # line at crank angle 180 deg, where the rates and the force are unbounded
    cp = ClearanceLinkage(0.03, 0.07, 0.06, 0.1, 0.2, 0.15, 5.4e-4, 2.45e-4, 0.035, 0.03)
    c = continuous_contact(cp, 300, 0.0, n=3600)
    assert c.status is PoseStatus.NEAR_TOGGLE
    assert "NEAR_TOGGLE" in repr(c)
    i = int(np.argmin(np.abs(c.crank_angle - np.pi)))
    # the same pose through the kinematic solver: a toggle there too
    sol = solve(FourBar((0.0, 0.0), (0.1, 0.0), 0.03, 0.07, 0.06), c.crank_angle[i])
    assert PoseStatus(int(sol.status[0])) is PoseStatus.NEAR_TOGGLE
    # a linkage that stays clear of it keeps OK
    ok = ClearanceLinkage(0.03, 0.09, 0.07, 0.1, 0.2, 0.15, 5.4e-4, 2.45e-4, 0.045, 0.035)
    c = continuous_contact(ok, 300, 0.0, n=3600)
    assert c.status is PoseStatus.OK and "OK" not in repr(c)


def test_with_a_clearance_a_change_point_linkage_reads_no_loss_at_its_gap():
    """The pin's offset opens the loop near the change point: those crank
    angles do not assemble (status UNASSEMBLABLE, R = 0 there), and the edges
    of that gap are no contact losses."""
    cp = ClearanceLinkage(0.03, 0.07, 0.06, 0.1, 0.2, 0.15, 5.4e-4, 2.45e-4, 0.035, 0.03)
    c = continuous_contact(cp, 300, 50e-6, n=3600)
    assert c.status is PoseStatus.UNASSEMBLABLE
    gap = c.crank_angle[(c.R == 0.0)]
    assert len(gap) and np.all(np.abs(gap - np.pi) < np.radians(10))
    for loss in c.losses:
        assert np.min(np.abs(np.angle(np.exp(1j * (gap - loss.angle))))) > np.radians(5)


def test_a_change_point_where_b_lies_on_d_is_refused_as_such():
    """Ground = crank and coupler = rocker: at crank angle 0 B lies on D and the
    loop can fold either way.  The linkage assembles at every crank angle
    (input_range), so the refusal names the change point, not a partial
    assembly."""
    link = ClearanceLinkage.reference(ground=0.07, crank=0.07, coupler=0.2, rocker=0.2)
    assert input_range(link.fourbar()).full_turn
    with pytest.raises(InputError, match=r"change point at crank angle\(s\) 0 deg.*B lies on D"):
        continuous_contact(link, 100, 1e-5)


def test_free_flight_never_passes_the_pin_through_the_wall():
    # a clearance near the crank length: a grazing separation used to start a
    # flight on the wall, whose impact event never fired, and the pin ran 72 mm
    # into the bush with no force and status OK
    lk = ClearanceLinkage(0.03, 0.09, 0.07, 0.1, 0.2, 0.15, 5.4e-4, 2.45e-4, 0.045, 0.035,
                          bush_radius=0.05)
    f = free_flight(lk, 300, 0.029, revolutions=2, samples=720)
    deep = f.gap > 1e-3 * f.clearance
    # in contact the Hertz penetration is microns; none without a force
    assert f.status is FlightStatus.OK or "impact was missed" in f.message
    assert not np.any(deep & (f.force == 0.0))
    assert f.gap.max() < 1e-3 * f.clearance
