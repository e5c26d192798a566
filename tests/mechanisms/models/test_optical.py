"""The built-in optical-filter mechanism (``mechanisms.models.optical``).

Closed form of the swing
------------------------
The cams turn about the origin; cam k's pin centre lies at ``a (cos(pi + phi_k +
q1), sin(pi + phi_k + q1))`` with ``a = CD / sqrt(2)``, CD = 2 cm, phi_k =
``PHASES[k]``.  Seen from the follower pivot ``(CD, 0)`` it lies at angle
``beta`` and distance ``rho``; the slot points at ``5 pi/4 + q2``.  While the pin
pushes the slot's clockwise (right) side its centre lies ``c = slot_wr - pin_r``
(0.024 cm) from the slot's centre line, so

    q2(q1) = beta(q1) - 5 pi/4 + asin(c / rho(q1)).
"""

import math

import numpy as np
import pytest
from shapely import affinity
from shapely.geometry import Polygon

from cspace.errors import InvalidModelError
from cspace.geometry import Assembly
from cspace.simulate import SimStatus
from mechanisms.analysis import motion_at
from mechanisms.models import optical_filter
from mechanisms.models.optical import OPTICAL_TOL, PHASES

CD = 2.0
A = CD / math.sqrt(2.0)
CLEAR = 0.144 - 0.12


@pytest.fixture(scope="module")
def model():
    return optical_filter()


@pytest.fixture(scope="module")
def motion(model):
    return motion_at(model, accuracy="fast")


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def _poly(part, per_turn=720):
    return [Polygon(lp.sample(per_turn)) for lp in part.loops]


def test_model_values(model):
    assert model.n == 17 and model.units == "cm" and OPTICAL_TOL == 0.002
    np.testing.assert_array_equal(model.tol, np.full(17, 0.002))
    assert PHASES == (0.0, math.pi / 2, math.pi)
    assert model.window == (-math.pi / 2, 3 * math.pi / 2, 0.0, 2 * math.pi)
    assert model.drive == (-math.pi / 2, 3 * math.pi / 2)
    assert model.q2_start == (0.0, 0.0, 0.0) and model.deviation == 0.012
    asm = model.build()
    assert isinstance(asm, Assembly) and asm.name == "optical_filter"
    assert [p.name for p in asm.pairs] == ["filter1", "filter2", "filter3"]
    assert [(p.driver.name, p.follower.name) for p in asm.pairs] == \
        [("cam1", "follower1"), ("cam2", "follower2"), ("cam3", "follower3")]
    assert all(p.bias == 0 and p.units == "cm" for p in asm.pairs)
    # one shaft, one pivot
    assert {p.driver.axis.center for p in asm.pairs} == {(0.0, 0.0)}
    assert {p.follower.axis.center for p in asm.pairs} == {(CD, 0.0)}


def test_cams_are_one_profile_turned_by_their_phase(model):
    """Cam k is cam 1 turned by PHASES[k] about the shaft; the followers are equal."""
    pairs = model.build({"relief_r": 1.321, "crank": 1.415}).pairs
    base = _poly(pairs[0].driver)
    for k, p in enumerate(pairs):
        for b, g in zip(base, _poly(p.driver)):
            turned = affinity.rotate(b, PHASES[k], origin=(0.0, 0.0), use_radians=True)
            assert turned.hausdorff_distance(g) < 1e-9
        assert p.follower.loops == pairs[0].follower.loops
    # and not the same profile at another angle
    other = affinity.rotate(base[1], math.pi / 3, origin=(0.0, 0.0), use_radians=True)
    assert other.hausdorff_distance(_poly(pairs[1].driver)[1]) > 0.1


def test_follower_profile(model):
    fol = model.build().pairs[0].follower
    (loop,) = fol.loops
    names = [s.name for s in loop.segments]
    assert names == ["faceA", "slot.right", "slot.bottom", "slot.left", "faceB", "back"]
    segs = dict(zip(names, loop.segments))
    v = model.values()
    assert segs["faceA"].center == pytest.approx((CD - v["lockA_cd"], 0.0))
    assert segs["faceB"].center == pytest.approx((CD, -v["lockB_cd"]))
    assert segs["back"].radius == v["arm_r"] and segs["back"].center == (CD, 0.0)
    # the slot sides are parallel to the slot axis at 225 degrees, at +/- the half-widths
    u = np.array([math.cos(5 * math.pi / 4), math.sin(5 * math.pi / 4)])
    n = np.array([-u[1], u[0]])
    for name, off in (("slot.right", -v["slot_wr"]), ("slot.left", v["slot_wl"])):
        for p in (segs[name].start, segs[name].end):
            assert (np.array(p) - (CD, 0.0)) @ n == pytest.approx(off, abs=1e-12)


def test_each_follower_swings_by_the_closed_form(motion):
    _, sims = motion
    for k, sim in enumerate(sims):
        assert sim.status == SimStatus.OK
        q1, q2, contact = np.asarray(sim.q1), np.asarray(sim.q2), np.asarray(sim.contact)
        sel = contact == f"cam{k + 1}:pin|follower{k + 1}:slot.right"
        assert np.count_nonzero(sel) > 200
        x = q1[sel]
        ang = math.pi + PHASES[k] + x
        px, py = A * np.cos(ang), A * np.sin(ang)
        rho = np.hypot(px - CD, py)
        want = np.arctan2(py, px - CD) - 5 * math.pi / 4 + np.arcsin(CLEAR / rho)
        assert np.max(np.abs(_wrap(q2[sel] - want))) <= 1e-12


def test_swings_are_staggered_by_a_quarter_turn(motion):
    """Each follower swings clockwise by a quarter turn once; follower k's swing
    comes a quarter turn of the cam before follower k-1's."""
    _, sims = motion
    windows, ends = [], []
    for sim in sims:
        q1, q2 = np.asarray(sim.q1), np.asarray(sim.q2)
        moved = np.nonzero(np.diff(q2) != 0)[0] + 1
        windows.append((q1[moved].min(), q1[moved].max()))
        assert np.all(np.diff(q2) <= 0)              # clockwise only
        ends.append(q2[-1])
    step = 1e-2                                         # larger than a simulation step
    for k in (1, 2):
        assert windows[k][0] == pytest.approx(windows[0][0] - PHASES[k], abs=step)
        assert windows[k][1] == pytest.approx(windows[0][1] - PHASES[k], abs=step)
    # the same swing: a quarter turn less the lock play, equal for the three
    np.testing.assert_allclose(ends, ends[0], atol=1e-12)
    assert ends[0] == pytest.approx(-math.pi / 2, abs=0.04)


def test_cspaces_are_shifted_copies(motion):
    """Pair k's C-space is pair 1's shifted by PHASES[k] in q1."""
    spaces, sims = motion
    rng = np.random.default_rng(7)
    n = 1500
    q = np.column_stack([rng.uniform(-math.pi / 2, 3 * math.pi / 2, n),
                         rng.uniform(0.0, 2 * math.pi, n)])
    # and points around the nominal motion, where the free channel is
    s0 = sims[0]
    idx = rng.integers(0, len(s0.q1), n)
    near = np.column_stack([np.asarray(s0.q1)[idx],
                            np.asarray(s0.q2)[idx] + rng.uniform(-0.06, 0.06, n)])
    q = np.vstack([q, near])
    c0 = spaces[0].classify(q)
    assert 0 < np.count_nonzero(c0 == c0[0]) < len(q)        # both kinds are sampled
    for k in (1, 2):
        ck = spaces[k].classify(q - [PHASES[k], 0.0])
        np.testing.assert_array_equal(ck, c0)


@pytest.mark.parametrize("values, match", [
    ({"relief_r": 0.05}, "do not intersect"),
    ({"slot_depth": 1.4}, "slot is deeper than its mouth"),
    ({"slot_wr": 0.13}, "slot side does not meet its locking face"),
])
def test_impossible_variants_are_invalid_models(model, values, match):
    with pytest.raises(InvalidModelError, match=match):
        model.build(values)
