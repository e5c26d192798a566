import math

import numpy as np
import pytest

from cspace.errors import InvalidModelError, ParameterError
from cspace.geometry import Assembly, Pair, Rotation, Translation
from mechanisms.models import Model, Parameter


@pytest.mark.parametrize("name, n, tol, units", [("geneva", 26, 0.018, "cm"),
                                                 ("optical_filter", 17, 0.002, "cm"),
                                                 ("reciprocating_cam", 11, 0.02, "cm")])
def test_builtin_models(models, name, n, tol, units):
    m = models[name]
    assert m.n == n and m.units == units
    np.testing.assert_allclose(m.tol, tol)
    built = m.build()
    assert isinstance(built, (Pair, Assembly))
    assert all(p.units == units for p in m.pairs())


def test_every_parameter_moves_some_geometry(models):
    for m in models.values():
        used = set().union(*(set().union(*d.values()) for d in m.dependencies()))
        assert used == set(m.names), set(m.names) - used


def test_box_vectors_build(models):
    rng = np.random.default_rng(0)
    for m in models.values():
        for _ in range(20):
            u = m.nominal + m.tol * rng.choice([-1.0, 1.0], m.n)
            m.build(u)  # box corners are valid geometry


def test_kinds_of_pairs(models):
    g = models["geneva"].build()
    assert isinstance(g.driver.axis, Rotation) and isinstance(g.follower.axis, Rotation)
    r = models["reciprocating_cam"].build()
    assert isinstance(r.follower.axis, Translation)
    o = models["optical_filter"].build()
    assert isinstance(o, Assembly) and len(o.pairs) == 3
    # the three cams are one profile turned by 90 degrees on one shaft
    pins = [p.driver.loops[0].segments[0].center for p in o.pairs]
    angs = [math.degrees(math.atan2(y, x)) % 360 for x, y in pins]
    np.testing.assert_allclose(np.diff(angs) % 360, [90, 90], atol=1e-9)


def test_parameter_vectors_and_errors(models):
    m = models["reciprocating_cam"]
    u = m.vector({"f0": 2.01})
    assert u[m.index("f0")] == 2.01 and u[m.index("f1")] == 2.0
    with pytest.raises(ParameterError, match="no parameter 'nope'"):
        m.vector({"nope": 1.0})
    with pytest.raises(ParameterError, match="needs 11 parameter values"):
        m.vector([1.0, 2.0])
    with pytest.raises(ParameterError, match="finite"):
        m.vector({"f0": float("nan")})
    assert m.in_box(m.nominal + m.tol) and not m.in_box(m.nominal + 2 * m.tol)
    m2 = m.with_nominal(u)
    assert m2.nominal[m.index("f0")] == 2.01 and m.nominal[m.index("f0")] == 2.0
    with pytest.raises(ParameterError):
        Parameter("x", 1.0, -0.1)
    # a parameter is a length (the model's unit) or an angle in rad
    assert m.param_units == ("cm",) * m.n
    assert Parameter("a", 0.5, 0.01, unit="rad").unit == "rad"
    # a preset name where the parameters go (model_cspaces(m, "fast")) says where it goes
    with pytest.raises(ParameterError, match=r"got 'fast' \(the name of an accuracy preset: "
                                             r"pass it as accuracy='fast'\)"):
        m.vector("fast")
    with pytest.raises(ParameterError, match=r"got 'abc'$"):
        m.vector("abc")
    with pytest.raises(ParameterError, match=r"unit must be '' \(the model's length unit\) "
                                             r"or 'rad' \(an angle\), got 'deg'"):
        Parameter("a", 30.0, 0.5, unit="deg")
    with pytest.raises(InvalidModelError, match="duplicate"):
        Model("m", (Parameter("a", 1, 0), Parameter("a", 2, 0)), lambda v: None)


def test_invalid_variant_is_a_typed_error(models):
    m = models["geneva"]
    with pytest.raises(InvalidModelError, match="invalid geometry|does not meet|deeper"):
        m.build({"lock2_r": 1.0})


def test_nominal_designs_have_a_connected_operating_channel(cspaces):
    """Locked, mid-index and re-locked configurations lie in one free face."""
    from cspace.freespace import Status
    g = cspaces["geneva"][0]
    q = [[0.0, 0.0], [math.pi, -math.pi / 4], [5.0, -math.pi / 2], [5.0, math.pi]]
    assert list(g.classify(q)) == [Status.FREE] * 4
    assert len(set(g.face_at(q))) == 1
    r = cspaces["reciprocating_cam"][0]
    q = [[0.0, 0.4], [1.05, -0.4], [2.1, 0.4], [3.14, -0.4], [4.2, 0.4]]
    assert list(r.classify(q)) == [Status.FREE] * 5 and len(set(r.face_at(q))) == 1
    for k, cs in enumerate(cspaces["optical_filter"]):
        mid = 3 * math.pi / 4 + math.pi / 4 - k * math.pi / 2  # mid-swing of pair k
        q = [[-math.pi / 2, 0.0], [mid, -math.pi / 4], [3 * math.pi / 2 - 0.01, -math.pi / 2]]
        assert list(cs.classify(q)) == [Status.FREE] * 3, k
        assert len(set(cs.face_at(q))) == 1, k
