"""Conversion of user input at the public boundary: integers, seeds and angles."""

import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_array_equal

from cspace.argcheck import MAX_ANGLE, getangle, getangles, getint, getseed
from cspace.errors import InputError


@pytest.mark.parametrize("x", [0, 7, np.int64(7), np.int32(-3), np.uint8(200), 10 ** 30])
def test_getint_accepts_python_and_numpy_integers_as_int(x):
    v = getint(x, "n")
    assert v == x and type(v) is int


@pytest.mark.parametrize("x", [True, False, np.bool_(True), 3.0, 2.5, "3", None, [3],
                               np.array(3), np.float64(3.0)])
def test_getint_refuses_what_is_not_an_integer(x):
    with pytest.raises(InputError, match=r"^n must be an int, got ") as e:
        getint(x, "n")
    assert e.value.name == "n" and e.value.value is x


@pytest.mark.parametrize("kw, x, allowed", [
    ({"minimum": 2}, 1, "an int >= 2"),
    ({"maximum": 5}, 6, "an int <= 5"),
    ({"minimum": 1, "maximum": 5}, 0, r"an int in \[1, 5\]"),
    ({"minimum": 1, "maximum": 5}, 6, r"an int in \[1, 5\]"),
    ({"minimum": 1, "maximum": 5}, 2.0, r"an int in \[1, 5\]"),
])
def test_getint_message_says_expected_got_and_allowed(kw, x, allowed):
    with pytest.raises(InputError, match=rf"^frames must be {allowed}, got {x!r}$"):
        getint(x, "frames", **kw)


def test_getint_bounds_are_inclusive():
    assert getint(1, minimum=1, maximum=5) == 1
    assert getint(5, minimum=1, maximum=5) == 5


def test_getint_label_names_the_value_in_the_message_and_name_stays():
    with pytest.raises(InputError,
                       match=r"^Accuracy\.zone_samples must be an int >= 0, got -1$") as e:
        getint(-1, "zone_samples", minimum=0, label="Accuracy.zone_samples")
    assert e.value.name == "zone_samples"


def test_getint_error_is_a_value_error():
    with pytest.raises(ValueError):
        getint("x", "n")


@given(st.integers(-10 ** 6, 10 ** 6), st.integers(-50, 50), st.integers(0, 100))
def test_getint_passes_exactly_the_range(x, lo, width):
    hi = lo + width
    if lo <= x <= hi:
        assert getint(x, minimum=lo, maximum=hi) == x
    else:
        with pytest.raises(InputError):
            getint(x, minimum=lo, maximum=hi)


def test_getseed_int_gives_the_default_rng_stream():
    a = getseed(42).uniform(size=5)
    assert_array_equal(a, np.random.default_rng(42).uniform(size=5))
    assert_array_equal(getseed(np.int64(42)).uniform(size=5), a)


def test_getseed_passes_a_generator_through_and_none_draws_fresh():
    g = np.random.default_rng(1)
    assert getseed(g) is g
    assert isinstance(getseed(None), np.random.Generator)
    # fresh entropy: two unseeded streams differ
    assert getseed(None).integers(2 ** 62) != getseed(None).integers(2 ** 62)


@pytest.mark.parametrize("seed", [-1, 1.5, 3.0, True, "7", [1], np.random.RandomState(0)])
def test_getseed_refuses_other_input_naming_what_is_allowed(seed):
    with pytest.raises(InputError, match=r"^seed must be an int >= 0, a numpy\.random\.Generator "
                                         r"or None, got ") as e:
        getseed(seed)
    assert e.value.name == "seed"


# ------------------------------------------------------------------ angles
@pytest.mark.parametrize("a, unit", [(MAX_ANGLE, "rad"), (-MAX_ANGLE, "rad"), (720.0, "deg"),
                                     (1e6, "rad"), (np.degrees(MAX_ANGLE), "deg")])
def test_angles_up_to_the_bound_are_read(a, unit):
    f = np.pi / 180 if unit == "deg" else 1.0
    assert getangle(a, unit, "theta") == a * f
    assert_array_equal(getangles([0.0, a], unit, "theta"), np.array([0.0, a]) * f)


@pytest.mark.parametrize("a, unit, got", [(1e20, "rad", r"got 1e\+20 rad"),
                                          (np.nextafter(MAX_ANGLE, np.inf), "rad", "got 4.1943"),
                                          (-1e9, "deg", r"got 1e\+09 deg \(1.74533e\+07 rad\)")])
def test_an_angle_too_large_to_give_a_direction_is_refused(a, unit, got):
    """Beyond MAX_ANGLE neighbouring doubles lie more than 1e-9 rad apart (at
    1e20 rad, 16384 rad): the message says the bound, the value and the
    spacing, and how to reduce it."""
    assert np.spacing(MAX_ANGLE) < 1e-9 < np.spacing(np.nextafter(4 * MAX_ANGLE, 0))
    for f in (getangle, lambda x, u, n: getangles([0.0, x], u, n)):
        with pytest.raises(InputError, match="theta must be an angle of at most 4194304 rad") as e:
            f(a, unit, "theta")
        assert e.value.name == "theta"
        msg = str(e.value)
        assert re.search(got, msg) and "apart" in msg and "math.remainder" in msg


def test_numbers_that_are_not_directions_skip_the_bound():
    assert getangles([1e20], "rad", "slide", direction=False)[0] == 1e20
