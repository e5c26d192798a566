"""The named tolerances: each one absorbs the rounding it is meant for and
stays far below anything physical."""

import math
import sys

import numpy as np
import pytest

from cspace import tolerances as T


def test_every_named_tolerance_is_a_small_positive_float_with_a_note():
    src = open(T.__file__).read()
    for name in T.__all__:
        v = getattr(T, name)
        assert isinstance(v, float) and 0 < v < 1e-5, name
        assert f"#: " in src.split(f"\n{name} =")[0].rsplit("\n\n", 1)[-1], name


def test_tiny_guards_a_division_without_changing_a_real_quotient():
    assert T.TINY > sys.float_info.min                       # a normal number
    assert math.isfinite(1.0 / T.TINY)
    x = np.array([0.0, 1e-200, 3.0])
    q = 2.0 / np.maximum(x, T.TINY)
    assert np.all(np.isfinite(q)) and q[2] == 2.0 / 3.0 and q[1] == 2.0 / 1e-200


def test_rounding_absorbs_a_full_turn_of_summed_steps_but_not_a_real_step():
    steps = np.full(100, 2 * math.pi / 100)
    total = 0.0
    for s in steps:
        total += s
    assert abs(total - 2 * math.pi) <= T.ROUNDING
    assert 2 * math.pi / 1e6 > 1e3 * T.ROUNDING               # a micro-radian step is not rounding


def test_probe_step_is_above_the_square_root_of_machine_epsilon():
    assert T.PROBE_REL > math.sqrt(np.finfo(float).eps)
    # a one-sided difference of sin at 1 with this step is good to 1e-7
    h = T.PROBE_REL
    assert (math.sin(1 + h) - math.sin(1)) / h == pytest.approx(math.cos(1), abs=1e-6)


def test_the_central_difference_step_keeps_both_errors_small():
    h = T.FD_REL
    d = (math.exp(1 + h) - math.exp(1 - h)) / (2 * h)
    assert d == pytest.approx(math.e, rel=1e-9)


def test_parallel_and_full_circle_slacks_are_rounding_level():
    r, s = np.array([1.0, 0.1]), np.array([3.0, 0.3])          # parallel up to rounding
    rxs = r[0] * s[1] - r[1] * s[0]
    assert abs(rxs) <= T.PARALLEL_REL * np.hypot(*r) * np.hypot(*s)
    assert abs(math.atan2(0.0, -1.0) - math.pi) <= T.FULL_CIRCLE_SLACK
    assert T.EQUAL_REL < T.ROUNDING < T.SLACK
