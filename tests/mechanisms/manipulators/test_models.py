"""Model values of the planar translational parallel manipulators
(mechanisms.manipulators.models): builders, derived geometry, bad input."""

import math

import numpy as np
import pytest

from cspace.errors import InputError
from mechanisms.manipulators.models import (Arrangement, TwoPaP, TwoPPa, two_pap, two_ppa,
                                            two_ppa_parallel)


def test_two_pap_half_width_is_eq_6_in_either_unit():
    m = two_pap(100.0, 60, unit="deg", t=5.0, b=2.0)
    assert isinstance(m, TwoPaP) and m.arrangement is Arrangement.DECOUPLED_ROTARY
    assert m.theta_limit == pytest.approx(math.pi / 3, abs=1e-15)
    assert m.half_width == pytest.approx(100.0 * math.sqrt(3) / 2, rel=1e-15)
    assert two_pap(100.0, math.pi / 3) == m.__class__(100.0, math.pi / 3, 0.0, 0.0)
    assert m.to_dict() == {"kind": "2-PaP", "la": 100.0, "theta_limit": m.theta_limit,
                           "t": 5.0, "b": 2.0}
    assert "60 deg" in repr(m) and "w=86.6025" in repr(m)


def test_two_ppa_perpendicular_geometry():
    """Leg 1 along +x, leg 2 along +y, base points (b - a) e_i, laterals crossed,
    so that the loop p = g_i + d_i e_i + la s_i at theta = 0, d = a - b puts P at
    la e_i from the origin of each leg."""
    m = two_ppa(50.0, 20.0, 40.0, 30, b=5.0, unit="deg")
    assert isinstance(m, TwoPPa) and m.arrangement is Arrangement.PERPENDICULAR
    np.testing.assert_array_equal(m.g, [[-15.0, 0.0], [0.0, -15.0]])
    np.testing.assert_array_equal(m.e, np.eye(2))
    np.testing.assert_array_equal(m.lat, [[0.0, 1.0], [1.0, 0.0]])
    # e_i and l_i are unit and perpendicular for each leg
    assert np.allclose(np.linalg.norm(m.e, axis=1), 1) and np.allclose((m.e * m.lat).sum(1), 0)
    assert m.half_width == pytest.approx(25.0, rel=1e-15)            # 50 sin 30 deg
    assert (m.fk_branch, m.ik_sign, m.a, m.b) == (1, -1, 20.0, 5.0)
    d = m.to_dict()
    assert d["kind"] == "2-PPa perpendicular" and d["base"] == [[-15.0, 0.0], [0.0, -15.0]]


def test_two_ppa_parallel_geometry_and_default_offset():
    la, spacing, stroke = 50.0, 40.0, 30.0
    m = two_ppa_parallel(la, spacing, stroke, math.pi / 4)
    assert m.arrangement is Arrangement.PARALLEL
    off = stroke / 2 + la * math.sqrt(0.5)
    np.testing.assert_allclose(m.g, [[-20.0, -off], [20.0, -off]], rtol=1e-15)
    np.testing.assert_array_equal(m.e, [[0.0, 1.0], [0.0, 1.0]])
    np.testing.assert_array_equal(m.lat, [[1.0, 0.0], [-1.0, 0.0]])
    # mid-stroke at theta = 45 deg, each leg's loop equation lands on the x axis
    for i in range(2):
        s = math.cos(math.pi / 4) * m.e[i] + math.sin(math.pi / 4) * m.lat[i]
        p = m.g[i] + stroke / 2 * m.e[i] + la * s
        assert p[1] == pytest.approx(0.0, abs=1e-12)
    assert two_ppa_parallel(la, spacing, stroke, math.pi / 4, offset=3.0).g[0, 1] == -3.0


@pytest.mark.parametrize("call, name", [
    (lambda: two_pap(0.0, 0.5), "la"),
    (lambda: two_pap(-1.0, 0.5), "la"),
    (lambda: two_pap(1.0, 0.0), "theta_limit"),
    (lambda: two_pap(1.0, 90, unit="deg"), "theta_limit"),
    (lambda: two_pap(1.0, 0.5, t=-1.0), "t"),
    (lambda: two_ppa(1.0, 0.0, 1.0, 0.5), "a"),
    (lambda: two_ppa(1.0, 1.0, -2.0, 0.5), "stroke"),
    (lambda: two_ppa(1.0, 1.0, 1.0, 0.5, b=-0.1), "b"),
    (lambda: two_ppa_parallel(1.0, 2.0, 1.0, 0.5), "spacing"),
    (lambda: two_ppa_parallel(1.0, 1.0, 1.0, float("nan")), "theta_limit"),
])
def test_bad_input_is_a_typed_error_naming_the_argument(call, name):
    with pytest.raises(InputError) as e:
        call()
    assert e.value.name == name
    assert name in str(e.value)


def test_models_are_frozen_values():
    m = two_pap(1.0, 0.5)
    with pytest.raises(AttributeError):
        m.la = 2.0
    assert two_pap(1.0, 0.5) == m and hash(m) == hash(two_pap(1.0, 0.5))
