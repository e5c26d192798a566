"""The built-in four-slot Geneva pair (``mechanisms.models.geneva``).

Closed form of the indexing
---------------------------
The driver turns about the origin; its pin centre lies at ``-A (cos q1, sin q1)``
with ``A = C / sqrt(2)``, C = 5 cm the centre distance.  Seen from the wheel axis
``(C, 0)`` the pin lies at angle ``beta(q1) = atan2(-A sin q1, -A cos q1 - C)`` and
distance ``rho(q1)``.  Slot j points at ``pi/4 + j pi/2 + q2``.  While the pin
pushes the slot's clockwise (right) side, its centre lies ``c = s_wr - pin_r``
(0.06 cm) from the slot's centre line, so

    q2(q1) = beta(q1) - (pi/4 + j pi/2) + asin(c / rho(q1)).

The pin enters a slot at q1 = 3 pi/4 (mod 2 pi), where the crank is normal to
the slot, and leaves it at 5 pi/4: the wheel turns by -pi/2 per driver turn and
rests for the other three quarters of it.
"""

import math

import numpy as np
import pytest
from shapely import affinity
from shapely.geometry import Polygon

from cspace.errors import InvalidModelError
from cspace.geometry import Arc, Line, Rotation
from cspace.simulate import SimStatus
from mechanisms.analysis import model_cspaces, motion_at
from mechanisms.models import geneva
from mechanisms.models.geneva import GENEVA_TOL

from ...conftest import brute_overlap

C = 5.0
A = C / math.sqrt(2.0)
CLEAR = 0.36 - 0.30          # slot half-width minus pin radius (cm)


@pytest.fixture(scope="module")
def model():
    return geneva()


@pytest.fixture(scope="module")
def motion(model):
    spaces, sims = motion_at(model, accuracy="fast")
    return spaces[0], sims[0]


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def test_model_values(model):
    assert model.n == 26 and model.units == "cm" and GENEVA_TOL == 0.018
    np.testing.assert_array_equal(model.tol, np.full(26, 0.018))
    np.testing.assert_array_equal(geneva(0.005).tol, np.full(26, 0.005))
    assert model.window == (0.0, 2 * math.pi, -math.pi, math.pi)
    assert model.drive == (0.0, 8 * math.pi)               # the wheel's full cycle
    assert model.q2_start == (0.0,) and model.deviation == 0.06
    v = model.values()
    assert v["crank"] == pytest.approx(A, abs=1e-15)
    assert (v["whl_x"], v["whl_y"]) == (C, 0.0)
    pair = model.build()
    assert pair.bias == 0 and pair.units == "cm"
    assert isinstance(pair.driver.axis, Rotation) and pair.driver.axis.center == (0.0, 0.0)
    assert pair.follower.axis.center == (C, 0.0)


def test_driver_profile(model):
    v = model.values({"pin_r": 0.31, "crank": 3.6, "lock_r": 3.1})
    drv = model.build(v).driver
    (pin,), (disk, relief) = (lp.segments for lp in drv.loops)
    assert isinstance(pin, Arc) and pin.name == "pin"
    assert pin.center == pytest.approx((-3.6, 0.0)) and pin.radius == 0.31
    assert disk.name == "lock_disk" and disk.radius == 3.1 and disk.center == (0.0, 0.0)
    assert relief.name == "relief" and relief.radius == v["relief_r"]
    assert relief.center == pytest.approx((-v["relief_d"], 0.0))
    # the relief meets the locking disk where both circles cross
    for p in (relief.start_point, relief.end_point):
        assert math.hypot(*p) == pytest.approx(3.1, abs=1e-12)


def test_wheel_slots_point_at_45_plus_90k_degrees(model):
    u = model.nominal.copy()
    u[model.index("s1_depth")] = 1.3
    u[model.index("s3_wl")] = 0.37
    wheel = model.build(u).follower
    segs = {s.name: s for s in wheel.loops[0].segments}
    assert len(segs) == 16
    for k in range(4):
        psi = math.pi / 4 + k * math.pi / 2
        d = np.array([math.cos(psi), math.sin(psi)])
        n = np.array([-d[1], d[0]])
        right, left = segs[f"slot{k}.right"], segs[f"slot{k}.left"]
        assert isinstance(right, Line) and isinstance(left, Line)
        for side, off in ((right, -0.36), (left, 0.37 if k == 3 else 0.36)):
            for p in (side.start, side.end):
                rel = np.array(p) - (C, 0.0)
                assert rel @ n == pytest.approx(off, abs=1e-12)   # parallel to the slot axis
        bottom = segs[f"slot{k}.bottom"]
        depth = 1.3 if k == 1 else 1.2
        along = (np.array(bottom.center) - (C, 0.0)) @ d
        assert along == pytest.approx(depth, abs=1e-12)
        lock = segs[f"lock{k}"]
        assert lock.radius == 3.25
        assert lock.center == pytest.approx((C + C * math.cos(k * math.pi / 2),
                                             C * math.sin(k * math.pi / 2)), abs=1e-12)


def test_nominal_wheel_has_fourfold_symmetry(model):
    wheel = Polygon(model.build().follower.loops[0].sample(720))
    turned = affinity.rotate(wheel, 90, origin=(C, 0.0))
    assert wheel.hausdorff_distance(turned) < 1e-9
    # a variant slot breaks it
    odd = Polygon(model.build({"s0_depth": 1.3}).follower.loops[0].sample(720))
    assert odd.hausdorff_distance(affinity.rotate(odd, 90, origin=(C, 0.0))) > 0.05


def test_indexing_follows_the_closed_form(motion):
    """Wherever the pin pushes a slot side, the wheel angle is the closed form to
    rounding; the slots index in the order 2, 3, 0, 1."""
    _, sim = motion
    assert sim.status == SimStatus.OK
    q1, q2, contact = np.asarray(sim.q1), np.asarray(sim.q2), np.asarray(sim.contact)
    for turn in range(4):
        j = (2 + turn) % 4
        sel = contact == f"driver:pin|wheel:slot{j}.right"
        assert np.count_nonzero(sel) > 200
        x = q1[sel]
        assert np.all((x > 2 * math.pi * turn + 3 * math.pi / 4)
                      & (x < 2 * math.pi * turn + 5 * math.pi / 4))
        px, py = -A * np.cos(x), -A * np.sin(x)
        rho = np.hypot(px - C, py)
        want = np.arctan2(py, px - C) - (math.pi / 4 + j * math.pi / 2) + np.arcsin(CLEAR / rho)
        assert np.max(np.abs(_wrap(q2[sel] - want))) <= 1e-12
    # every slot is driven once in the cycle
    slots = {c.split("wheel:")[1].split(".")[0] for c in contact if "slot" in c and "^" not in c}
    assert slots == {"slot0", "slot1", "slot2", "slot3"}


def test_entry_is_normal_to_the_slot():
    """At q1 = 3 pi/4 the crank is normal to slot 2's axis (the Geneva condition)."""
    q1 = 3 * math.pi / 4
    pin = -A * np.array([math.cos(q1), math.sin(q1)])
    crank_dir = pin / A
    slot_dir = np.array([math.cos(5 * math.pi / 4), math.sin(5 * math.pi / 4)])
    assert crank_dir @ slot_dir == pytest.approx(0.0, abs=1e-15)
    assert np.arctan2(pin[1], pin[0] - C) == pytest.approx(-3 * math.pi / 4, abs=1e-15)


def test_wheel_moves_only_in_the_index_quarter_and_dwells_otherwise(motion):
    _, sim = motion
    q1, q2 = np.asarray(sim.q1), np.asarray(sim.q2)
    moved = np.nonzero(np.diff(q2) != 0)[0] + 1
    phase = q1[moved] % (2 * math.pi)
    assert np.all((phase > 3 * math.pi / 4) & (phase < 5 * math.pi / 4))
    rest = []
    for turn in range(4):
        dwell = (q1 > 2 * math.pi * turn + 5 * math.pi / 4) & \
                (q1 < 2 * math.pi * (turn + 1) + 3 * math.pi / 4)
        assert np.ptp(q2[dwell]) == 0.0
        rest.append(q2[dwell][0])
    # every index after the first turns the wheel by exactly a quarter, clockwise
    np.testing.assert_allclose(np.diff(rest), -math.pi / 2, atol=1e-12)
    assert q2[-1] == pytest.approx(-2 * math.pi, abs=0.05)


def test_lock_play_agrees_with_an_independent_overlap_test(model, motion):
    """The free channel of the locked wheel at q1 = 0, checked with shapely
    polygons rotated by hand."""
    cs, _ = motion
    ivs = [(lo, hi) for lo, hi, _ in cs.free_intervals(0.0)]
    assert len(ivs) == 4                            # one lock position per slot
    lo, hi = next(iv for iv in ivs if iv[0] < 0 < iv[1])
    assert lo == pytest.approx(-hi, abs=1e-9)       # symmetric about the locked pose
    pair = model.build()
    q = [[0.0, 0.99 * hi], [0.0, 0.99 * lo], [0.0, 1.01 * hi], [0.0, 1.01 * lo]]
    np.testing.assert_array_equal(brute_overlap(pair, q, per_turn=20000),
                                  [False, False, True, True])
    # the other lock positions are the same channel a quarter turn away
    for a, b in ivs:
        mid = 0.5 * (a + b)
        assert b - a == pytest.approx(hi - lo, abs=1e-9)
        assert abs(_wrap(mid * 4)) == pytest.approx(0.0, abs=1e-9)


def test_documented_lock_play(motion):
    """The module docstring's lock play: 0.0898 rad wide, +/-0.0449 rad about the
    locked pose."""
    cs, _ = motion
    lo, hi = next((a, b) for a, b, _ in cs.free_intervals(0.0) if a < 0 < b)
    assert hi - lo == pytest.approx(0.0898, abs=1e-4)
    assert hi == pytest.approx(0.0449, abs=1e-4)


@pytest.mark.parametrize("values, match", [
    ({"relief_r": 0.5}, "relief and locking disk circles do not intersect"),
    ({"relief_d": 9.0}, "relief and locking disk circles do not intersect"),
    ({"s0_depth": 4.0}, "slot 0 is deeper than its mouth"),
    ({"s2_wr": 0.2}, "slot 2 side does not meet locking arc 2"),
])
def test_impossible_variants_are_invalid_models(model, values, match):
    with pytest.raises(InvalidModelError, match=match):
        model.build(values)


def test_box_corners_keep_a_free_locked_start(model):
    """At every sampled corner of the tolerance box the locked start q = (0, 0)
    stays free (the variants differ in the marginal entry, not in the lock)."""
    rng = np.random.default_rng(4)
    for _ in range(3):
        u = model.nominal + model.tol * rng.choice([-1.0, 1.0], model.n)
        (cs,) = model_cspaces(model, u, accuracy="fast")
        assert any(lo < 0.0 < hi for lo, hi, _ in cs.free_intervals(0.0))
        assert not brute_overlap(model.build(u), [[0.0, 0.0]])[0]
