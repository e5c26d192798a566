"""The built-in eccentric cam (``mechanisms.models.eccentric``): its profile,
the closed-form lower bound of its free space and the dependencies of its
segments.  The simulated lift and the defect test are checked in
``tests/mechanisms/test_spring_cam.py``.

A flat face normal to the slide rests on the disc's top point, ``disc_r`` above
its centre ``(cam_x + ecc sin q1, cam_y - ecc cos q1)``: the follower fits for

    q2 >= cam_y + disc_r - face - ecc cos q1

and nothing bounds it from above inside the window.
"""

import math

import numpy as np
import pytest

from cspace.errors import InvalidModelError
from cspace.geometry import Arc, Rotation, Translation
from mechanisms.analysis import model_cspaces
from mechanisms.models import eccentric_cam
from mechanisms.models.eccentric import ECCENTRIC_TOL


def lift(v, q1):
    return v["cam_y"] + v["disc_r"] - v["face"] - v["ecc"] * np.cos(q1)


@pytest.fixture(scope="module")
def model():
    return eccentric_cam()


def test_model_values(model):
    assert model.n == 7 and model.units == "cm" and ECCENTRIC_TOL == 0.01
    assert model.names == ("cam_x", "cam_y", "ecc", "disc_r", "face", "half_w", "thick")
    np.testing.assert_array_equal(eccentric_cam(0.03).tol, np.full(7, 0.03))
    assert model.window == (0.0, 2 * math.pi, -0.5, 2.0)
    assert model.drive == (0.0, 2 * math.pi) and model.q2_start == (1.0,)
    assert model.deviation == 0.012
    v = model.values()
    # the nominal face touches the disc's top at q1 = 0: a lift ecc (1 - cos q1)
    assert v["face"] == v["cam_y"] + v["disc_r"] - v["ecc"]


def test_profile(model):
    u = model.vector({"cam_x": 0.3, "cam_y": -0.2, "ecc": 0.45, "half_w": 0.7, "thick": 0.9})
    v = model.values(u)
    pair = model.build(u)
    assert pair.bias == -1 and pair.name == "eccentric_cam" and pair.units == "cm"
    ((disc,),) = (lp.segments for lp in pair.driver.loops)
    assert isinstance(disc, Arc) and disc.name == "disc"
    assert disc.center == (0.3, -0.2 - 0.45) and disc.radius == v["disc_r"]
    assert isinstance(pair.driver.axis, Rotation) and pair.driver.axis.center == (0.3, -0.2)
    ax = pair.follower.axis
    assert isinstance(ax, Translation) and ax.direction == (0.0, 1.0)
    assert ax.origin == (0.0, v["face"])
    (block,) = pair.follower.loops
    segs = {s.name: s for s in block.segments}
    assert segs["face"].start == (-0.7, v["face"]) and segs["face"].end == (0.7, v["face"])
    assert segs["back"].start[1] == v["face"] + 0.9


@pytest.mark.parametrize("seed", [None, 1, 2, 3])
def test_free_space_lower_bound_is_the_lift(model, seed):
    u = None if seed is None else \
        model.nominal + model.tol * np.random.default_rng(seed).uniform(-1, 1, model.n)
    v = model.values(u)
    (cs,) = model_cspaces(model, u, accuracy="fast")
    for x in np.linspace(0.0, 2 * math.pi, 25):
        ((lo, hi, _),) = cs.free_intervals(x)
        assert lo == pytest.approx(lift(v, x), abs=1e-9)
        assert hi == model.window[3]


def test_cam_x_and_the_face_width_do_not_change_the_lift(model):
    x = np.linspace(0.0, 2 * math.pi, 9)
    base = model_cspaces(model, accuracy="fast")[0]
    for values in ({"cam_x": 0.01}, {"half_w": 0.59}, {"thick": 0.81}):
        (cs,) = model_cspaces(model, values, accuracy="fast")
        for xi in x:
            assert cs.free_intervals(xi)[0][0] == pytest.approx(base.free_intervals(xi)[0][0],
                                                                abs=1e-9)


def test_dependencies_follow_the_construction(model):
    (deps,) = model.dependencies()
    got = {k: set(v) for k, v in deps.items()}
    assert got == {
        (0, "axis"): {"cam_x", "cam_y"},
        (0, 0, 0): {"cam_x", "cam_y", "ecc", "disc_r"},
        (1, "axis"): {"face"},
        (1, 0, 0): {"face", "half_w"},                     # the face
        (1, 0, 1): {"face", "half_w", "thick"},            # right side
        (1, 0, 2): {"face", "half_w", "thick"},            # back
        (1, 0, 3): {"face", "half_w", "thick"},            # left side
    }


@pytest.mark.parametrize("values, match", [
    ({"ecc": 2.0}, r"need disc_r > ecc >= 0 \(the axis inside the disc\), got disc_r = 2.0, "
                   r"ecc = 2.0"),
    ({"ecc": -0.1}, "need disc_r > ecc >= 0"),
    ({"half_w": 0.0}, "needs half_w > 0 and thick > 0"),
    ({"thick": -0.2}, "needs half_w > 0 and thick > 0"),
])
def test_impossible_variants_are_invalid_models(model, values, match):
    with pytest.raises(InvalidModelError, match=match):
        model.build(values)
