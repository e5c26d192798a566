"""Parametric model values (``mechanisms.models.base``): Distribution,
Parameter and Model, on a small pin-and-block model whose dependencies are
known by construction."""

import dataclasses
import math

import numpy as np
import pytest

from cspace.errors import CSpaceError, InvalidModelError, ParameterError, ZeroLengthSegmentError
from cspace.geometry import Arc, Assembly, Loop, Pair, Part, Rotation, Translation
from mechanisms.models.base import (DEFAULT_DISTRIBUTION, DISTRIBUTION_KINDS, Distribution,
                                    Model, Parameter)


def build_pin_block(v):
    """A pin of radius ``r`` on a crank ``R`` and a block whose face lies at x = ``w``.

    Segment 0 of the block (the face) depends on ``w`` and ``h``; the back on
    ``w``, ``t`` and ``h``; the two ends on ``w``, ``t`` and ``h``.  ``spare``
    moves nothing."""
    R, r, w, t, h = v["R"], v["r"], v["w"], v["t"], v["h"]
    if r <= 0:
        raise ValueError("pin radius must be > 0")
    pin = Loop((Arc((R, 0.0), r, 0.0, 2 * math.pi, name="pin"),))
    block = Loop.from_bulges([(w, -h), (w + t, -h), (w + t, h), (w, h)],
                             names=["end.low", "back", "end.high", "face"])
    return Pair(Part("crank", (pin,), Rotation((0.0, 0.0))),
                Part("block", (block,), Translation((1.0, 0.0))), units="mm", name="pin_block")


PARAMS = (("R", 10.0, 0.1), ("r", 2.0, 0.05), ("w", 15.0, 0.1), ("t", 3.0, 0.0),
          ("h", 20.0, 0.2), ("spare", 1.0, 0.5))


def small_model(**kw):
    return Model("pin_block", tuple(Parameter(n, v, t) for n, v, t in PARAMS), build_pin_block,
                 **kw)


# ------------------------------------------------------------------ Distribution

def test_distribution_spreads_by_kind():
    tol = 0.3
    assert DEFAULT_DISTRIBUTION == Distribution("truncated_normal", cp=1.0)
    assert Distribution("uniform").std(tol) == pytest.approx(tol / math.sqrt(3))
    assert Distribution("uniform").half_width(tol) == tol
    assert Distribution("normal").std(tol) == pytest.approx(0.1)            # cp 1
    assert Distribution("normal", cp=2.0).std(tol) == pytest.approx(0.05)
    assert Distribution("normal", sigma=0.07).std(tol) == 0.07
    assert Distribution("normal").half_width(tol) == math.inf
    assert Distribution("truncated_normal").half_width(tol) == tol
    assert Distribution("truncated_normal", limit=1.5).half_width(tol) == pytest.approx(0.45)
    assert Distribution("truncated_normal", sigma=0.0).std(tol) == 0.0     # held at nominal


@pytest.mark.parametrize("d", [
    {"kind": "uniform"},
    {"kind": "normal"},
    {"kind": "normal", "cp": 1.33},
    {"kind": "normal", "sigma": 0.02},
    {"kind": "truncated_normal", "cp": 0.8, "limit": 2.0},
    {"kind": "truncated_normal", "sigma": 0.01},
])
def test_distribution_dict_round_trip(d):
    dist = Distribution.from_dict(d)
    assert dist.to_dict() == d
    assert Distribution.from_dict(dist) is dist
    assert Distribution.from_dict(dist.to_dict()) == dist


@pytest.mark.parametrize("kw, match", [
    ({"kind": "poisson"}, "kind must be one of"),
    ({"kind": "uniform", "sigma": 0.1}, "takes no sigma"),
    ({"kind": "normal", "limit": 2.0}, "only a truncated_normal distribution takes a limit"),
    ({"kind": "normal", "sigma": True}, "sigma must be a finite number >= 0"),
    ({"kind": "normal", "sigma": -0.1}, "sigma must be a finite number >= 0"),
    ({"kind": "normal", "cp": 0.0}, "cp must be a finite number > 0"),
    ({"kind": "normal", "cp": float("nan")}, "cp must be a finite number > 0"),
    ({"kind": "truncated_normal", "limit": float("inf")}, "limit must be a finite number > 0"),
])
def test_distribution_rejects_bad_values(kw, match):
    with pytest.raises(ParameterError, match=match):
        Distribution(**kw)


def test_distribution_kinds_table_matches_the_constructor():
    for kind, keys in DISTRIBUTION_KINDS.items():
        for k in ("sigma", "cp"):
            if k in keys:
                assert getattr(Distribution(kind, **{k: 0.5}), k) == 0.5
            else:
                with pytest.raises(ParameterError):
                    Distribution(kind, **{k: 0.5})


# ------------------------------------------------------------------ Parameter

def test_parameter_normalises_its_values():
    p = Parameter("a", np.float32(1.5), np.int64(0), fixed=np.bool_(True),
                  min_keep=0, distribution={"kind": "uniform"})
    assert type(p.nominal) is float and type(p.tol) is float and p.tol == 0.0
    assert p.fixed is True and p.hard is False
    assert p.min_keep == 0.0 and type(p.min_keep) is float
    assert p.distribution == Distribution("uniform") and p.spread is p.distribution
    assert Parameter("b", 1.0, 0.1).spread is DEFAULT_DISTRIBUTION


@pytest.mark.parametrize("kw, match", [
    ({"name": "2x"}, "identifier"),
    ({"name": "a b"}, "identifier"),
    ({"nominal": True}, "nominal must be a number"),
    ({"nominal": "1"}, "nominal must be a number"),
    ({"tol": float("inf")}, "tol must be finite"),
    ({"tol": -0.01}, "tol must be >= 0"),
    ({"fixed": 1}, "fixed must be True or False"),
    ({"hard": "yes"}, "hard must be True or False"),
    ({"shift_cost": 0.0}, "shift_cost must be a finite number > 0"),
    ({"cut_cost": True}, "cut_cost must be a finite number > 0"),
    ({"min_keep": 1.5}, r"min_keep must be a fraction in \[0, 1\]"),
    ({"min_keep": -0.1}, r"min_keep must be a fraction in \[0, 1\]"),
    ({"distribution": {"kind": "normal", "cp": 1, "sigma": 1}}, r"parameter 'a': .*not both"),
])
def test_parameter_rejects_bad_values(kw, match):
    args = {"name": "a", "nominal": 1.0, "tol": 0.1, **kw}
    with pytest.raises(ParameterError, match=match):
        Parameter(**args)


# ------------------------------------------------------------------ Model vectors

def test_model_vectors_and_values():
    m = small_model()
    assert m.n == 6 and m.names == ("R", "r", "w", "t", "h", "spare")
    np.testing.assert_array_equal(m.nominal, [10.0, 2.0, 15.0, 3.0, 20.0, 1.0])
    np.testing.assert_array_equal(m.tol, [0.1, 0.05, 0.1, 0.0, 0.2, 0.5])
    assert m.index("w") == 2
    np.testing.assert_array_equal(m.vector(None), m.nominal)
    u = m.vector({"w": 15.05, "R": 9.9})
    np.testing.assert_array_equal(u, [9.9, 2.0, 15.05, 3.0, 20.0, 1.0])
    assert m.values(u) == dict(zip(m.names, u.tolist()))
    np.testing.assert_array_equal(m.vector(tuple(u)), u)
    assert repr(m) == "<Model 'pin_block': 6 parameters, units mm>"


def test_model_vector_errors_name_what_is_allowed():
    m = small_model()
    with pytest.raises(ParameterError, match=r"no parameter 'x'; allowed: \['R', 'r', 'w'"):
        m.index("x")
    with pytest.raises(ParameterError, match=r"needs 6 parameter values, got shape \(2, 3\)"):
        m.vector(np.zeros((2, 3)))
    with pytest.raises(ParameterError, match="finite"):
        m.vector([1.0, 2.0, 3.0, 4.0, math.inf, 6.0])
    with pytest.raises(ParameterError, match="must be a number, got bool"):
        m.vector({"w": True})
    with pytest.raises(ParameterError, match="mapping or a sequence of 6 numbers"):
        m.vector(["a"] * 6)


def test_in_box_includes_its_faces():
    m = small_model()
    assert m.in_box(m.nominal + m.tol) and m.in_box(m.nominal - m.tol)
    u = m.nominal.copy()
    u[m.index("t")] += 1e-9             # a zero tolerance admits the nominal only
    assert not m.in_box(u)
    u = m.nominal + m.tol
    u[0] += 1e-6
    assert not m.in_box(u)


# ------------------------------------------------------------------ building

def test_build_and_pairs():
    m = small_model()
    pair = m.build({"w": 16.0})
    assert isinstance(pair, Pair)
    face = next(s for s in pair.follower.loops[0].segments if s.name == "face")
    assert face.start[0] == 16.0 and face.end[0] == 16.0
    assert m.pairs() == (m.build(),)
    asm = Model("two", m.parameters, lambda v: Assembly((build_pin_block(v),) * 2))
    assert len(asm.pairs()) == 2 and isinstance(asm.build(), Assembly)


def test_build_turns_builder_failures_into_invalid_model_errors():
    m = small_model()
    with pytest.raises(InvalidModelError, match="cannot be built at this parameter vector: "
                                                "ValueError: pin radius must be > 0") as e:
        m.build({"r": -1.0})
    assert isinstance(e.value.__cause__, ValueError)
    # geometry the library refuses (a zero-length face) is chained as well
    with pytest.raises(InvalidModelError, match="builds invalid geometry") as e:
        m.build({"h": 0.0})
    assert isinstance(e.value.__cause__, CSpaceError)
    assert isinstance(e.value.__cause__, ZeroLengthSegmentError)

    own = InvalidModelError("my own words")

    def raises_own(v):
        raise own

    with pytest.raises(InvalidModelError) as e:
        Model("m", m.parameters, raises_own).build()
    assert e.value is own
    with pytest.raises(InvalidModelError, match="builder returned int, expected Pair or Assembly"):
        Model("m", m.parameters, lambda v: 3).build()


@pytest.mark.parametrize("drive", [(1.0, 1.0), (0.0,), (0.0, math.inf), ("a", 1.0), 5.0])
def test_model_rejects_a_bad_drive(drive):
    with pytest.raises(InvalidModelError, match="drive must be two different finite"):
        small_model(drive=drive)


def test_model_rejects_duplicate_names():
    ps = (Parameter("a", 1, 0), Parameter("b", 1, 0), Parameter("a", 2, 0), Parameter("b", 3, 0))
    with pytest.raises(InvalidModelError, match=r"duplicate parameter names \['a', 'b'\]"):
        Model("m", ps, build_pin_block)


# ------------------------------------------------------------------ derived models

def test_with_nominal_and_with_tolerances_make_new_models():
    m = small_model(drive=(0.0, 6.0), q2_start=(10.0,))
    m2 = m.with_nominal({"w": 15.5})
    assert m2.nominal[2] == 15.5 and m.nominal[2] == 15.0
    assert m2.drive == (0.0, 6.0) and m2.q2_start == (10.0,) and m2.builder is m.builder
    np.testing.assert_array_equal(m2.tol, m.tol)
    t = m.with_tolerances(0.01)
    np.testing.assert_array_equal(t.tol, np.full(6, 0.01))
    np.testing.assert_array_equal(t.nominal, m.nominal)
    t = m.with_tolerances({"h": 0.3})
    np.testing.assert_array_equal(t.tol, [0.1, 0.05, 0.1, 0.0, 0.3, 0.5])
    t = m.with_tolerances(np.arange(6) * 0.1)
    np.testing.assert_allclose(t.tol, np.arange(6) * 0.1)
    with pytest.raises(ParameterError, match="finite and >= 0"):
        m.with_tolerances(-0.1)
    with pytest.raises(ParameterError, match="one number or 6 numbers"):
        m.with_tolerances([0.1, 0.2])
    with pytest.raises(ParameterError, match="no parameter 'zz'"):
        m.with_tolerances({"zz": 0.1})
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.name = "other"


# ------------------------------------------------------------------ dependencies

def test_dependencies_are_those_of_the_construction():
    m = small_model()
    (deps,) = m.dependencies()
    want = {(0, "axis"): set(),
            (0, 0, 0): {"R", "r"},
            (1, "axis"): set(),
            (1, 0, 0): {"w", "t", "h"},      # end.low
            (1, 0, 1): {"w", "t", "h"},      # back
            (1, 0, 2): {"w", "t", "h"},      # end.high
            (1, 0, 3): {"w", "h"}}           # face
    got = {k: set(v) for k, v in deps.items()}
    assert got == {k: v for k, v in want.items() if v}
    # ``t`` has no tolerance and is found by the small step; ``spare`` moves nothing
    assert "spare" not in set().union(*got.values())
    assert m.dependencies() is m.dependencies()        # cached on the value


def test_dependencies_probe_the_other_side_where_one_cannot_be_built():
    def one_sided(v):
        if v["w"] > 15.0:
            raise ValueError("the block may not move out")
        return build_pin_block(v)

    m = Model("m", small_model().parameters, one_sided)
    (deps,) = m.dependencies()
    assert "w" in deps[(1, 0, 3)]


def test_dependencies_refuse_a_parameter_that_cannot_move():
    def rigid(v):
        if v["R"] != 10.0:
            raise ValueError("R is fixed by the builder")
        return build_pin_block(v)

    with pytest.raises(InvalidModelError, match="parameter 'R' cannot move by"):
        Model("m", small_model().parameters, rigid).dependencies()


def test_dependencies_refuse_a_topology_change():
    def grows(v):
        pair = build_pin_block(v)
        if v["spare"] > 1.0:
            extra = Loop((Arc((0.0, 0.0), 0.5, 0.0, 2 * math.pi, name="hub"),))
            drv = dataclasses.replace(pair.driver, loops=pair.driver.loops + (extra,))
            pair = dataclasses.replace(pair, driver=drv)
        return pair

    with pytest.raises(InvalidModelError, match="moving 'spare' changes the profile topology"):
        Model("m", small_model().parameters, grows).dependencies()
