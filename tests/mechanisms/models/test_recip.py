"""The built-in reciprocating cam (``mechanisms.models.recip``).

Closed form of the free channel
-------------------------------
The yoke slides along x; its right face runs from ``(xr_b + q2, -H)`` to
``(xr_t + q2, H)``, i.e. ``x - k_r y = q2 + xr_b + k_r H`` with ``k_r = (xr_t -
xr_b) / 2H``, and the cam lies on its left.  The cam's convex hull is that of
its three tip circles (radius ``tip_r``, centres ``c_j`` at ``f_j`` from the axis,
finger j at ``q1 + 2 pi j / 3``; the hub lies inside it), so the largest value
of ``x - k_r y`` over the cam is ``max_j c_j . (1, -k_r) + tip_r sqrt(1 + k_r^2)``
and the yoke fits only for

    q2 >= max_j c_j . (1, -k_r) + tip_r sqrt(1 + k_r^2) - xr_b - k_r H.

The left face gives the upper bound the same way.  The faces reach
H = 3 cm, beyond the fingers (2.5 cm), so nothing else bounds the channel.
"""

import math

import numpy as np
import pytest

from cspace.errors import InvalidModelError
from cspace.freespace import Status
from cspace.geometry import Rotation, Translation
from cspace.simulate import SimStatus
from mechanisms.analysis import model_cspaces, motion_at
from mechanisms.models import reciprocating_cam
from mechanisms.models.recip import RECIP_TOL

H = 3.0


def channel(v, q1):
    """Closed-form bounds (lo, hi) of the yoke coordinate at driver angles q1."""
    q1 = np.asarray(q1, dtype=float)
    kr = (v["xr_t"] - v["xr_b"]) / (2 * H)
    kl = (v["xl_t"] - v["xl_b"]) / (2 * H)
    right, left = [], []
    for j in range(3):
        a = q1 + 2 * math.pi * j / 3
        cx = v["cam_x"] + v[f"f{j}"] * np.cos(a)
        cy = v["cam_y"] + v[f"f{j}"] * np.sin(a)
        right.append(cx - kr * cy)
        left.append(-cx + kl * cy)
    lo = np.max(right, 0) + v["tip_r"] * math.hypot(1.0, kr) - v["xr_b"] - kr * H
    hi = -(np.max(left, 0) + v["tip_r"] * math.hypot(1.0, kl)) - v["xl_b"] - kl * H
    return lo, hi


@pytest.fixture(scope="module")
def model():
    return reciprocating_cam()


@pytest.fixture(scope="module")
def variant(model):
    """A corner of the tolerance box, every parameter moved."""
    signs = np.array([1, -1, 1, -1, -1, 1, -1, -1, 1, 1, -1], dtype=float)
    return model.nominal + model.tol * signs


def test_model_values(model):
    assert model.n == 11 and model.units == "cm" and RECIP_TOL == 0.02
    np.testing.assert_array_equal(model.tol, np.full(11, 0.02))
    assert model.window == (0.0, 2 * math.pi, -1.0, 1.0)
    assert model.drive == (0.0, 2 * math.pi) and model.q2_start == (0.45,)
    assert model.deviation is None
    pair = model.build()
    assert pair.bias == 0 and pair.units == "cm"
    assert isinstance(pair.driver.axis, Rotation)
    assert isinstance(pair.follower.axis, Translation)
    assert pair.follower.axis.direction == (1.0, 0.0)


def test_cam_profile(model, variant):
    v = model.values(variant)
    (loop,) = model.build(variant).driver.loops
    segs = {s.name: s for s in loop.segments}
    assert len(segs) == 12
    o = np.array([v["cam_x"], v["cam_y"]])
    for k in range(3):
        a = 2 * math.pi * k / 3
        tip = segs[f"finger{k}.tip"]
        assert tip.radius == v["tip_r"]
        np.testing.assert_allclose(tip.center, o + v[f"f{k}"] * np.array([math.cos(a),
                                                                          math.sin(a)]),
                                   atol=1e-15)
        hub = segs[f"hub{k}"]
        assert hub.radius == v["hub_r"] and hub.center == tuple(o)
        # the finger sides are tangent to the tip: half a finger width off its axis
        n = np.array([-math.sin(a), math.cos(a)])
        for side, sgn in (("right", -1), ("left", 1)):
            s = segs[f"finger{k}.{side}"]
            for p in (s.start, s.end):
                assert (np.array(p) - o) @ n == pytest.approx(sgn * v["tip_r"], abs=1e-12)


def test_yoke_faces(model, variant):
    v = model.values(variant)
    outer, window = model.build(variant).follower.loops
    segs = {s.name: s for s in window.segments}
    assert segs["face.right"].start == (v["xr_t"], H) and segs["face.right"].end == (v["xr_b"], -H)
    assert segs["face.left"].start == (v["xl_b"], -H) and segs["face.left"].end == (v["xl_t"], H)
    xs = [p for s in outer.segments for p in (s.start[0], s.end[0])]
    assert max(xs) == 3.6 and min(xs) == -3.6


@pytest.mark.parametrize("which", ["nominal", "variant"])
def test_free_space_is_the_closed_form_channel(model, variant, which):
    u = None if which == "nominal" else variant
    v = model.values(u)
    (cs,) = model_cspaces(model, u, accuracy="fast")
    x = np.linspace(0.0, 2 * math.pi, 61)
    lo, hi = channel(v, x)
    for xi, a, b in zip(x, lo, hi):
        ((flo, fhi, _),) = cs.free_intervals(xi)          # exactly one free interval
        assert flo == pytest.approx(a, abs=1e-9) and fhi == pytest.approx(b, abs=1e-9)
    rng = np.random.default_rng(11)
    q = np.column_stack([rng.uniform(0, 2 * math.pi, 3000), rng.uniform(-1.0, 1.0, 3000)])
    lo, hi = channel(v, q[:, 0])
    want = np.where((q[:, 1] > lo) & (q[:, 1] < hi), Status.FREE, Status.BLOCKED)
    assert 0 < np.count_nonzero(want == Status.FREE) < len(q)
    np.testing.assert_array_equal(cs.classify(q), want)


def test_the_narrow_passage(model):
    """Between two cups the channel narrows to about 0.09 cm."""
    x = np.linspace(0.0, 2 * math.pi, 20001)
    lo, hi = channel(model.values(), x)
    assert np.all(hi > lo)
    assert round(float(np.min(hi - lo)), 2) == 0.09
    # the three fingers are alike: the channel repeats every third of a turn
    lo3, hi3 = channel(model.values(), x + 2 * math.pi / 3)
    np.testing.assert_allclose(lo3, lo, atol=1e-12)
    np.testing.assert_allclose(hi3, hi, atol=1e-12)


def test_the_yoke_rests_until_a_finger_pushes_it(model):
    _, (sim,) = motion_at(model, accuracy="fast")
    assert sim.status == SimStatus.OK
    q1, q2 = np.asarray(sim.q1), np.asarray(sim.q2)
    lo, hi = channel(model.values(), q1)
    assert np.all(q2 >= lo - 1e-12) and np.all(q2 <= hi + 1e-12)
    moved = np.nonzero(np.diff(q2) != 0)[0] + 1
    assert len(moved) > 100
    # where it moves it lies on a bound: pushed by a finger
    gap = np.minimum(np.abs(q2[moved] - lo[moved]), np.abs(hi[moved] - q2[moved]))
    assert np.max(gap) <= 1e-12
    faces = {c.split("|")[1] for c in sim.contact if c}
    assert faces == {"yoke:face.left", "yoke:face.right"}


@pytest.mark.parametrize("values, match", [
    ({"hub_r": 0.5}, "hub_r must exceed tip_r"),
    ({"f1": 0.8}, "finger 1 is shorter than the hub"),
])
def test_impossible_variants_are_invalid_models(model, values, match):
    with pytest.raises(InvalidModelError, match=match):
        model.build(values)
