"""Every field of a Model is checked when it is made (mechanisms.models.base):
q2_start, deviation, units, parameters, builder, window and drive, with a
message that says what is allowed; a rotating driver's drive written in
degrees is refused."""

import dataclasses
import math

import numpy as np
import pytest

from cspace.errors import InvalidModelError, ParameterError
from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from mechanisms.models import Model, Parameter, eccentric_cam
from mechanisms.models.base import MAX_DRIVE_SPAN

from .test_base import build_pin_block, small_model


def test_q2_start_one_number_is_the_start_of_every_pair():
    for q2 in (0.1, np.float32(0.1), np.array(0.1), [0.1], np.array([0.1]), (np.float64(0.1),)):
        m = small_model(q2_start=q2)
        assert m.q2_start == (pytest.approx(0.1),) and type(m.q2_start) is tuple
        assert all(type(v) is float for v in m.q2_start)
    assert small_model(q2_start=(0.5, 1)).q2_start == (0.5, 1.0)
    assert small_model().q2_start is None


@pytest.mark.parametrize("q2", ["0.1", (), (0.1, math.nan), (0.1, "a"), [[0.1]], True, {"a": 1},
                                math.inf])
def test_q2_start_refuses_what_is_not_finite_numbers(q2):
    with pytest.raises(InvalidModelError, match="q2_start must be None, one finite number, or "
                                                "a sequence of finite numbers"):
        small_model(q2_start=q2)


@pytest.mark.parametrize("dev", [0, -1, 0.0, "0.01", math.nan, math.inf, True, (0.01,)])
def test_deviation_must_be_a_finite_number_above_zero(dev):
    with pytest.raises(InvalidModelError, match=r"deviation must be None \(the library default"
                                                r".*or a finite number > 0.*got "):
        small_model(deviation=dev)


def test_deviation_is_stored_as_a_float():
    m = small_model(deviation=np.float32(0.25))
    assert m.deviation == 0.25 and type(m.deviation) is float
    assert small_model(deviation=1).deviation == 1.0


@pytest.mark.parametrize("units", [None, 5, "", b"mm"])
def test_units_must_be_a_non_empty_str(units):
    with pytest.raises(InvalidModelError, match="units must be a non-empty str.*such as 'mm'"):
        small_model(units=units)


def test_parameters_must_be_parameter_instances_and_the_message_says_how():
    with pytest.raises(ParameterError) as e:
        Model("x", (("a", 1, 0.1),), build_pin_block)
    msg = str(e.value)
    assert "parameters[0] must be a Parameter, got tuple ('a', 1, 0.1)" in msg
    assert "Parameter(name, nominal, tol)" in msg and "e.g. Parameter('a', 1, 0.1)" in msg
    with pytest.raises(ParameterError, match=r"parameters\[1\] must be a Parameter, got dict"):
        Model("x", (Parameter("a", 1, 0.1), {"name": "b"}), build_pin_block)
    for bad in ("abc", Parameter("a", 1, 0.1), 3):
        with pytest.raises(ParameterError, match="parameters must be a sequence of Parameter"):
            Model("x", bad, build_pin_block)
    # a list is a sequence: stored as a tuple
    m = Model("x", [Parameter("a", 1, 0.1)], build_pin_block)
    assert isinstance(m.parameters, tuple)


def test_builder_and_name_are_checked():
    ps = small_model().parameters
    with pytest.raises(InvalidModelError, match="builder must be a callable"):
        Model("x", ps, "build_pin_block")
    with pytest.raises(InvalidModelError, match="model name must be a non-empty str"):
        Model("", ps, build_pin_block)


@pytest.mark.parametrize("window", [(0, 1, 2), (0, 1, 2, math.nan), (1, 0, 0, 1), (0, 1, 1, 1),
                                    "0 1 0 1", (0, 1, 0, "1"), 5.0])
def test_window_must_be_four_finite_numbers_lo_below_hi(window):
    with pytest.raises(InvalidModelError, match=r"window must be None or four finite numbers "
                                                r"\(q1_lo, q1_hi, q2_lo, q2_hi\) with q1_lo < "
                                                r"q1_hi and q2_lo < q2_hi"):
        small_model(window=window)


def test_window_and_drive_are_stored_as_tuples_of_floats():
    m = small_model(window=np.array([0, 2 * np.pi, -5, 5]), drive=[np.float32(0), 6])
    assert m.window == (0.0, 2 * math.pi, -5.0, 5.0) and type(m.window) is tuple
    assert m.drive == (0.0, 6.0) and all(type(v) is float for v in m.drive)
    # dataclasses.replace (with_nominal, synthesis) checks again
    assert dataclasses.replace(m, q2_start=3).q2_start == (3.0,)
    with pytest.raises(InvalidModelError, match="deviation"):
        dataclasses.replace(m, deviation=0)


# ------------------------------------------------------------------ a drive in degrees

def test_a_rotating_drivers_drive_in_degrees_is_refused_with_the_hint():
    with pytest.raises(InvalidModelError) as e:
        small_model(drive=(0, 360))
    assert str(e.value) == (
        "model 'pin_block': the drive (0, 360) turns the rotating driver 360 rad (57.3 turns); "
        "drive angles are in rad, and a drive of 90 rad or more must be whole turns; written "
        "in degrees? radians(0) and radians(360) are 0 and 6.28319 rad")
    for drive in ((0, -90), (10, 100), (0, 720)):
        with pytest.raises(InvalidModelError, match="turns the rotating driver"):
            small_model(drive=drive)
    # several turns are fine (a Geneva wheel's cycle is four), and many whole
    # turns too (a 16-slot wheel's is 16)
    assert small_model(drive=(0, 8 * math.pi)).drive == (0.0, 8 * math.pi)
    assert small_model(drive=(0, MAX_DRIVE_SPAN - 1e-9)).drive[1] < MAX_DRIVE_SPAN
    assert small_model(drive=(0, 32 * math.pi)).drive == (0.0, 32 * math.pi)


def _build_slider_driver(v):
    """A block sliding along x (the driver) beside a pin on a crank."""
    w = v["w"]
    block = Loop.from_bulges([(w, -20.0), (w + 3.0, -20.0), (w + 3.0, 20.0), (w, 20.0)])
    pin = Loop((Arc((10.0, 0.0), 2.0, 0.0, 2 * math.pi, name="pin"),))
    return Pair(Part("block", (block,), Translation((1.0, 0.0))),
                Part("crank", (pin,), Rotation((0.0, 0.0))), units="mm")


def test_a_sliding_drivers_long_drive_is_a_length():
    m = Model("slide", (Parameter("w", 15.0, 0.1),), _build_slider_driver, drive=(0.0, 360.0))
    assert m.drive == (0.0, 360.0)


def test_a_model_that_cannot_be_built_leaves_the_drive_to_its_first_build():
    def broken(v):
        raise KeyError("no such value")
    m = Model("broken", small_model().parameters, broken, drive=(0.0, 360.0))
    with pytest.raises(KeyError):
        m.build()


def test_the_built_in_models_pass_their_own_checks():
    m = eccentric_cam()
    assert m.q2_start == (1.0,) and m.deviation == 0.012 and m.units == "cm"


def test_a_one_number_start_simulates_like_its_tuple():
    from mechanisms.analysis import motion_at
    m = dataclasses.replace(eccentric_cam(), q2_start=1.0)
    (_,), (sim,) = motion_at(m, accuracy="fast")
    (_,), (sim0,) = motion_at(eccentric_cam(), accuracy="fast")
    assert sim.success and np.array_equal(sim.q2, sim0.q2)


# ------------------------------------------------------------------ a rotating follower's window

def _build_pin_lever(v):
    """A pin on a crank and a block turning about a pivot at (40, 0)."""
    R, w = v["R"], v["w"]
    pin = Loop((Arc((R, 0.0), 2.0, 0.0, 2 * math.pi, name="pin"),))
    block = Loop.from_bulges([(w, -20.0), (w + 3.0, -20.0), (w + 3.0, 20.0), (w, 20.0)])
    return Pair(Part("crank", (pin,), Rotation((0.0, 0.0))),
                Part("lever", (block,), Rotation((40.0, 0.0))), units="mm")


def test_a_rotating_followers_window_spans_two_pi_documented_and_checked_at_its_cspace():
    """Which part rotates is known only from a build: the model takes the window,
    its docstring says the rule, and the first C-space says what is expected."""
    from cspace.errors import InputError
    from mechanisms.analysis import model_cspaces
    assert "a rotating follower's exactly one" in Model.__doc__
    ps = (Parameter("R", 10.0, 0.1), Parameter("w", 15.0, 0.1))
    m = Model("lever", ps, _build_pin_lever, window=(0, 2 * math.pi, -0.3, 0.6))
    with pytest.raises(InputError, match=r"the follower window of a rotating follower must be "
                                         r"one full period \(2 pi\), .* a span of 0.9"):
        model_cspaces(m, accuracy="fast")
    ok = dataclasses.replace(m, window=(0, 2 * math.pi, -math.pi, math.pi))
    assert model_cspaces(ok, accuracy="fast")[0].periodic == (True, True)
