"""Parametric model files: format, expression safety, errors, round trips."""

import copy
import json
import math
import pickle
from pathlib import Path

import pytest
from numpy.testing import assert_allclose

from cspace.errors import (CSpaceError, ExpressionError, FileFormatError, InputError,
                           InvalidModelError, NonPositiveRadiusError, OpenLoopError,
                           OrientationError, SelfIntersectionError)
from cspace.geometry import Arc, Assembly, Pair
from mechanisms.analysis import model_cspaces, resolve_model
from mechanisms.userfile import (compile_expression, load_model, model_from_dict,
                                 model_to_dict, parametric_model, save_model)

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "flat_follower_cam.json"


def square(x0="x0", y0="y0", s="s"):
    return [{"type": "line", "start": [x0, y0], "end": [f"{x0} + {s}", y0]},
            {"type": "line", "start": [f"{x0} + {s}", y0], "end": [f"{x0} + {s}", f"{y0} + {s}"]},
            {"type": "line", "start": [f"{x0} + {s}", f"{y0} + {s}"], "end": [x0, f"{y0} + {s}"]},
            {"type": "line", "start": [x0, f"{y0} + {s}"], "end": [x0, y0]}]


def small_doc():
    """A disk of radius r rotating about the origin against a sliding square."""
    return {
        "format": "cspace-model", "version": 1, "name": "small", "units": "mm",
        "parameters": [{"name": "r", "nominal": 2.0, "tol": 0.1},
                       {"name": "x0", "nominal": 3.0, "tol": 0.1, "description": "square x"},
                       {"name": "y0", "nominal": -1.0, "tol": 0.1},
                       {"name": "s", "nominal": 2.0, "tol": 0.0}],
        "let": [{"name": "r2", "value": "2 * r"}],
        "pairs": [{"parts": [
            {"name": "disk", "axis": {"type": "rotation", "center": [0, 0]},
             "loops": [[{"type": "arc", "center": ["r2 - r - 1", 0], "radius": "r",
                         "start_angle": 0, "end_angle": "2*pi", "ccw": True}]]},
            {"name": "block", "axis": {"type": "translation", "direction": [1, 0]},
             "loops": [square()]}]}]}


def at(d, path, value):
    """Copy of d with the item at a dotted/indexed path replaced."""
    d = copy.deepcopy(d)
    keys = [int(k) if k.isdigit() else k
            for k in path.replace("[", ".").replace("]", "").split(".")]
    node = d
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = value
    return d


# ------------------------------------------------------------------ the example file

def test_example_file_loads_builds_and_has_a_free_face():
    m = load_model(EXAMPLE)
    assert 5 <= m.n <= 10 and m.units == "mm"
    pair = m.build()
    assert isinstance(pair, Pair)
    assert [s.kind for s in pair.driver.loops[0].segments] == ["line", "arc", "line", "arc"]
    # the tangent cam: its lift from base circle to nose tip is d + rn - rb
    v = m.values()
    top = max(lp.bounds()[3] for lp in pair.driver.loops)
    assert_allclose(top, v["d"] + v["rn"], atol=1e-12)
    (cs,) = model_cspaces(m, accuracy="fast")
    assert cs.stats["free_faces"] >= 1
    # follower well above the nose is free, pressed into the cam is blocked
    st = cs.classify([[0.0, 15.0], [0.0, 5.0]])
    assert st[0] != st[1]
    deps = m.dependencies()[0]
    assert deps[(1, 0, 0)] == {"face", "half_w"}
    assert "rb" in deps[(0, 0, 3)] and "thick" not in deps[(0, 0, 3)]


def test_example_file_round_trips_exactly(tmp_path):
    d = json.loads(EXAMPLE.read_text())
    m = model_from_dict(d)
    assert model_to_dict(m) == d
    save_model(m, tmp_path / "m.json")
    assert json.loads((tmp_path / "m.json").read_text()) == d
    assert resolve_model(str(tmp_path / "m.json")).names == m.names


def test_minimal_document_round_trips_without_adding_keys():
    d = small_doc()
    d["parameters"][2]["description"] = ""
    assert model_to_dict(model_from_dict(d)) == d
    d["window"] = [0, "2 * pi", -1, 1]
    d["q2_start"] = [0.25]
    assert model_to_dict(model_from_dict(d)) == d
    d["deviation"] = 0.02
    m = model_from_dict(d)
    assert m.deviation == 0.02
    assert model_to_dict(m) == d


def test_shifted_model_saves_its_new_nominal_and_tolerances(tmp_path):
    m = load_model(EXAMPLE)
    m2 = m.with_nominal(m.nominal + 0.01).with_tolerances(0.005)
    save_model(m2, tmp_path / "m2.json")
    m3 = load_model(tmp_path / "m2.json")
    assert_allclose(m3.nominal, m.nominal + 0.01, atol=0)
    assert_allclose(m3.tol, 0.005, atol=0)
    a, b = m2.build().driver.loops[0].segments[0], m3.build().driver.loops[0].segments[0]
    assert a == b
    # window and drive expressions survive as written
    d = model_to_dict(m3)
    assert d["window"][1] == "2*pi" and d["drive"] == [0, "2*pi"]


def test_model_is_picklable_and_pure():
    m = load_model(EXAMPLE)
    m2 = pickle.loads(pickle.dumps(m))
    u = m.nominal + 0.01
    assert m2.build(u).driver.loops[0].segments == m.build(u).driver.loops[0].segments
    assert m.build().driver.loops[0].segments != m.build(u).driver.loops[0].segments


# ------------------------------------------------------------------ format features

def test_small_doc_builds_expected_geometry():
    m = model_from_dict(small_doc())
    p = m.build({"r": 1.5, "x0": 4.0})
    arc = p.driver.loops[0].segments[0]
    assert isinstance(arc, Arc) and arc.is_full_circle
    assert_allclose(arc.center, (2 * 1.5 - 1.5 - 1, 0), atol=1e-15)
    assert arc.radius == 1.5
    assert p.follower.loops[0].segments[0].start == (4.0, -1.0)
    assert p.name == "small" and p.units == "mm"
    assert m.q2_start is None and m.window is None and m.deviation is None


def test_polyline_loop_with_bulges_and_names():
    d = small_doc()
    d = at(d, "pairs[0].parts[1].loops[0]",
           {"polyline": [["x0", "y0"], ["x0 + s", "y0"], ["x0 + s", "y0 + s"], ["x0", "y0 + s"]],
            "bulges": [0, "tan(pi/8)", 0, 0], "names": ["a", "b", "c", "d"]})
    p = model_from_dict(d).build()
    segs = p.follower.loops[0].segments
    assert [s.kind for s in segs] == ["line", "arc", "line", "line"]
    assert segs[1].name == "b" and segs[1].ccw
    assert_allclose(segs[1].sweep, math.pi / 2, atol=1e-12)
    assert_allclose(segs[1].radius, 2 / math.sqrt(2), atol=1e-12)


def test_let_order_does_not_matter_and_functions_work():
    d = small_doc()
    d["let"] = [{"name": "r2", "value": "2 * r"}, {"name": "c", "value": "b + 1"}, {"name": "b", "value": "a * 2"},
                {"name": "a", "value": "hypot(3, 4) + atan2(0, 1) + max(1, 2, 3) - min(3, 4)"
                                       " + degrees(radians(0)) + abs(-0)"}]
    d = at(d, "pairs[0].parts[0].loops[0][0].radius", "c - 10 + r")
    m = model_from_dict(d)
    # a = 5 + 0 + 3 - 3 = 5, b = 10, c = 11 -> radius = r + 1
    assert_allclose(m.build().driver.loops[0].segments[0].radius, 3.0, atol=1e-15)


def test_multi_pair_file_is_an_assembly():
    d = small_doc()
    second = copy.deepcopy(d["pairs"][0])
    second["name"] = "second"
    d["pairs"].append(second)
    d["q2_start"] = [0.5, "pi"]
    m = model_from_dict(d)
    a = m.build()
    assert isinstance(a, Assembly) and [p.name for p in a.pairs] == ["small1", "second"]
    assert m.q2_start == (0.5, math.pi)


def test_assembly_drivers_must_share_one_axis():
    d = small_doc()
    second = copy.deepcopy(d["pairs"][0])
    second["parts"][0]["axis"]["center"] = [0, "r"]
    d["pairs"].append(second)
    with pytest.raises(InvalidModelError, match="share one axis"):
        model_from_dict(d)


def test_builder_repr_is_short():
    m = load_model(EXAMPLE)
    assert len(repr(m.builder)) < 120 and len(repr(m)) < 120


# ------------------------------------------------------------------ expression safety

@pytest.mark.parametrize("src, token", [
    ("__import__('os')", "__import__"),
    ("r.__class__", "r.__class__"),
    ("(lambda: 1)()", "lambda: 1"),
    ("[x for x in (1, 2)][0]", "[x for x in (1, 2)]"),
    ("sum(x for x in (1,))", "sum"),
    ("{1: 2}[1]", "{1: 2}"),
    ("open('f')", "open"),
    ("'abc'", "'abc'"),
    ("r if r else 1", "r if r else 1"),
    ("r < 1", "r < 1"),
    ("r % 2", "%"),
    ("r // 2", "//"),
    ("not r", "not"),
    ("sin(x=1)", "sin(x=1)"),
    ("sin(*[1])", "*[1]"),
    ("True + 1", "True"),
    ("(r := 2)", "r := 2"),
    ("f'{r}'", "f'{r}'"),
    ("math.sin(1)", "math.sin"),
    ("sin(1, 2)", "sin(1, 2)"),
    ("1 +", "1 +"),
])
def test_disallowed_expressions_are_rejected(src, token):
    d = at(small_doc(), "pairs[0].parts[0].loops[0][0].radius", src)
    with pytest.raises(ExpressionError) as ei:
        model_from_dict(d)
    assert ei.value.path == "pairs[0].parts[0].loops[0][0].radius"
    assert token.split("(")[0] in ei.value.token or ei.value.token in token
    assert isinstance(ei.value, FileFormatError) and isinstance(ei.value, ValueError)


def test_loading_never_executes_code(tmp_path):
    flag = tmp_path / "ran"
    src = f"__import__('pathlib').Path({str(flag)!r}).touch()"
    with pytest.raises(ExpressionError):
        model_from_dict(at(small_doc(), "let[0].value", src))
    assert not flag.exists()


def test_hostile_sizes_are_bounded():
    with pytest.raises(ExpressionError, match="longer than"):
        compile_expression("1+" * 2000 + "1", "p")
    for deep in ("(" * 900 + "1" + ")" * 900, "-" * 1900 + "1"):
        with pytest.raises(ExpressionError, match="nested|invalid expression"):
            compile_expression(deep, "p")
    with pytest.raises(ExpressionError, match="cannot evaluate"):
        model_from_dict(at(small_doc(), "let[0].value", "9 ** 9 ** 9"))


def test_unknown_name_is_reported_with_path_and_token():
    d = at(small_doc(), "pairs[0].parts[1].loops[0][2].end[1]", "y0 + sz")
    with pytest.raises(ExpressionError, match="unknown name 'sz'") as ei:
        model_from_dict(d)
    assert ei.value.path == "pairs[0].parts[1].loops[0][2].end[1]" and ei.value.token == "sz"
    with pytest.raises(ExpressionError, match="unknown name 'q'"):
        model_from_dict(at(small_doc(), "let[0].value", "q + 1"))


def test_let_cycle_and_duplicates():
    d = small_doc()
    d["let"] = [{"name": "a", "value": "b + 1"}, {"name": "b", "value": "c"},
                {"name": "c", "value": "a * r"}]
    with pytest.raises(ExpressionError, match="cycle: a -> b -> c -> a"):
        model_from_dict(d)
    d["let"] = [{"name": "a", "value": "a + 1"}]
    with pytest.raises(ExpressionError, match="cycle"):
        model_from_dict(d)
    d["let"] = [{"name": "r", "value": 1}]
    with pytest.raises(FileFormatError, match="duplicate name 'r'") as ei:
        model_from_dict(d)
    assert ei.value.path == "let[0].name"
    d = small_doc()
    d["parameters"].append({"name": "x0", "nominal": 1, "tol": 0})
    with pytest.raises(FileFormatError, match="duplicate parameter name 'x0'"):
        model_from_dict(d)
    d = small_doc()
    d["pairs"].append(copy.deepcopy(d["pairs"][0]))
    d["pairs"][0]["name"] = d["pairs"][1]["name"] = "p"
    with pytest.raises(FileFormatError, match="duplicate pair name"):
        model_from_dict(d)
    with pytest.raises(FileFormatError, match="duplicate part name"):
        model_from_dict(at(small_doc(), "pairs[0].parts[1].name", "disk"))


@pytest.mark.parametrize("name", ["pi", "sin", "lambda", "2x", "a-b", ""])
def test_bad_names(name):
    with pytest.raises(FileFormatError) as ei:
        model_from_dict(at(small_doc(), "parameters[0].name", name))
    assert ei.value.path == "parameters[0].name"


# ------------------------------------------------------------------ numbers

@pytest.mark.parametrize("path", ["parameters[1].nominal", "parameters[1].tol"])
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), "1.0", True])
def test_non_finite_or_non_numeric_parameters(path, bad):
    with pytest.raises(FileFormatError) as ei:
        model_from_dict(at(small_doc(), path, bad))
    assert ei.value.path == path


@pytest.mark.parametrize("bad", [float("nan"), float("-inf"), True, None, [1]])
def test_non_finite_geometry_numbers(bad):
    with pytest.raises(ExpressionError) as ei:
        model_from_dict(at(small_doc(), "pairs[0].parts[1].loops[0][0].start[0]", bad))
    assert ei.value.path == "pairs[0].parts[1].loops[0][0].start[0]"


def test_overflow_to_inf_and_domain_errors():
    with pytest.raises(ExpressionError, match="finite") as ei:
        model_from_dict(at(small_doc(), "let[0].value", "1e308 * 10"))
    assert ei.value.path == "let[0].value" and ei.value.token == "1e308 * 10"
    with pytest.raises(ExpressionError, match="math domain") as ei:
        model_from_dict(at(small_doc(), "let[0].value", "2 * sqrt(r - 5)"))
    assert ei.value.token == "sqrt(r - 5)"
    with pytest.raises(ExpressionError, match="division by zero"):
        model_from_dict(at(small_doc(), "let[0].value", "r / (s - 2)"))
    with pytest.raises(ExpressionError, match="fractional power"):
        model_from_dict(at(small_doc(), "let[0].value", "(-r) ** 0.5"))


def test_evaluation_failure_at_another_vector_is_an_invalid_model():
    m = model_from_dict(at(small_doc(), "let[0].value", "2 * sqrt(r - 1.95)"))
    with pytest.raises(InvalidModelError, match="sqrt"):
        m.build({"r": 1.9})
    assert isinstance(m.build({"r": 2.05}), Pair)


# ------------------------------------------------------------------ structure and geometry

@pytest.mark.parametrize("path, value, match, where", [
    ("format", "cspace-pair", "format must be", "format"),
    ("version", 2, "unsupported version", "version"),
    ("units", "", "non-empty", "units"),
    ("pairs", [], "non-empty", "pairs"),
    ("pairs[0].parts", [], "exactly 2 parts", "pairs[0].parts"),
    ("pairs[0].parts[0].axis", {"type": "screw"}, "rotation", "pairs[0].parts[0].axis.type"),
    ("pairs[0].parts[0].loops[0][0].type", "spline", "line' or 'arc", "pairs[0].parts[0].loops[0][0].type"),
    ("pairs[0].parts[0].loops[0][0].ccw", 1, "true or false", "pairs[0].parts[0].loops[0][0].ccw"),
    ("pairs[0].parts[1].loops[0][0].start", [1], "point", "pairs[0].parts[1].loops[0][0].start"),
    ("pairs[0].parts[1].loops[0]", {"polyline": [[0, 0], [1, 0]], "bulges": [0]}, "one bulge per edge",
     "pairs[0].parts[1].loops[0].bulges"),
    ("pairs[0].parts[1].loops[0]", {"points": []}, "missing required key 'polyline'",
     "pairs[0].parts[1].loops[0]"),
    ("window", [0, 1, 2], "q1_lo", "window"),
    ("window", [1, 0, 0, 1], "q1_lo < q1_hi", "window"),
    ("q2_start", [0, 1], r"one start value per pair \(1\): a list of 1, got a list of 2",
     "q2_start"),
    ("q2_start", 0, r"one start value per pair \(1\) as a JSON list, got int 0", "q2_start"),
    ("deviation", -0.1, "positive finite number", "deviation"),
    ("deviation", "1", "positive finite number", "deviation"),
    ("deviation", float("nan"), "positive finite number", "deviation"),
    ("extra", 1, "unknown key", ""),
])
def test_structure_errors_name_the_path(path, value, match, where):
    with pytest.raises(FileFormatError, match=match) as ei:
        model_from_dict(at(small_doc(), path, value))
    assert ei.value.path == where


def test_window_may_not_depend_on_parameters():
    with pytest.raises(ExpressionError, match="only the constants") as ei:
        model_from_dict(at(small_doc(), "window", [0, "2*pi", "-r", 3]))
    assert ei.value.path == "window[2]" and ei.value.token == "r"


@pytest.mark.parametrize("path, value, err", [
    ("pairs[0].parts[0].loops[0][0].radius", "r - 2", NonPositiveRadiusError),
    ("pairs[0].parts[1].loops[0][1].start[1]", "y0 + 0.5", OpenLoopError),
    ("pairs[0].parts[1].loops[0][2].end[0]", "x0 + 3", OpenLoopError),
])
def test_invalid_nominal_geometry_raises_typed_error_with_path(path, value, err):
    with pytest.raises(err) as ei:
        model_from_dict(at(small_doc(), path, value))
    seg_path = path.rsplit(".", 1)[0].split("[")[0]
    assert seg_path in str(ei.value)


@pytest.mark.parametrize("a0, a1, hint", [
    (0, 360, True), (-90, 270, True), ("0", "4*pi", False), ("2*pi", "-0.5", False)])
def test_arc_angles_more_than_a_turn_apart_are_refused(a0, a1, hint):
    """An arc's sweep is in (0, 2 pi]: angles farther apart than a turn are
    a slip (most often degrees), named with the segment's path; a full
    circle (a turn apart, to rounding) is an arc."""
    arc = "pairs[0].parts[0].loops[0][0]"
    d = at(at(small_doc(), f"{arc}.start_angle", a0), f"{arc}.end_angle", a1)
    with pytest.raises(InvalidModelError, match=r"lie [0-9.]+ rad apart, more than a turn") as e:
        model_from_dict(d)
    assert str(e.value).startswith(arc + ":")
    assert ("written in degrees? radians(" in str(e.value)) == hint
    full = at(at(small_doc(), f"{arc}.start_angle", "0.3"), f"{arc}.end_angle", "0.3 + 2*pi")
    assert isinstance(model_from_dict(full).build(), Pair)


def _with_angle(unit="deg", nominal=30, tol=0.5):
    """small_doc with a fifth parameter, the disk's start angle (the disk
    stays a full circle), stated in ``unit``."""
    d = small_doc()
    d["parameters"].append({"name": "a0", "nominal": nominal, "tol": tol, "unit": unit,
                            "distribution": {"kind": "normal", "sigma": 0.1}})
    arc = "pairs[0].parts[0].loops[0][0]"
    return at(at(d, f"{arc}.start_angle", "a0"), f"{arc}.end_angle", "a0 + 2*pi")


def test_an_angle_in_degrees_is_read_in_rad_and_written_back_in_degrees():
    d = _with_angle()
    m = model_from_dict(d)
    p = m.parameters[m.index("a0")]
    assert p.unit == "rad" and m.param_units == ("mm",) * 4 + ("rad",)
    assert p.nominal == pytest.approx(math.radians(30)) and p.tol == pytest.approx(
        math.radians(0.5)) and p.distribution.sigma == pytest.approx(math.radians(0.1))
    # read back, the file's own numbers
    assert model_to_dict(m) == d
    # a new value is written in the file's unit
    moved = model_to_dict(m.with_nominal({"a0": math.radians(31)}).with_tolerances(
        {"a0": math.radians(0.25)}))["parameters"][-1]
    assert moved["unit"] == "deg" and moved["nominal"] == pytest.approx(31)
    assert moved["tol"] == pytest.approx(0.25) and moved["distribution"] == d["parameters"][-1][
        "distribution"]
    again = model_from_dict(at(d, "parameters[4]", moved))
    assert again.parameters[-1].nominal == pytest.approx(math.radians(31))


@pytest.mark.parametrize("unit, nominal, angle", [("rad", 0.5, True), ("mm", 2.0, False)])
def test_a_parameter_unit_may_be_rad_or_the_models_own(unit, nominal, angle):
    m = model_from_dict(_with_angle(unit, nominal, 0.01))
    p = m.parameters[-1]
    assert (p.unit == "rad") == angle and p.nominal == nominal and p.tol == 0.01
    assert m.param_units[-1] == ("rad" if angle else "mm")


@pytest.mark.parametrize("unit", ["grad", "cm", 1, ""])
def test_other_parameter_units_are_refused(unit):
    with pytest.raises(FileFormatError, match=r"unit must be 'mm' \(a length, in the model's "
                                              r"unit\) or 'rad' or 'deg' \(an angle\), got") \
            as e:
        model_from_dict(_with_angle(unit))
    assert e.value.path == "parameters[4].unit"


def test_orientation_and_crossing_errors():
    d = small_doc()
    d = at(d, "pairs[0].parts[1].loops[0]", list(reversed(
        [{"type": "line", "start": s["end"], "end": s["start"]}
         for s in d["pairs"][0]["parts"][1]["loops"][0]])))
    with pytest.raises(OrientationError, match="pairs\\[0\\].parts\\[1\\]"):
        model_from_dict(d)
    bow = {"polyline": [["x0", "y0"], ["x0 + s", "y0 + s"], ["x0 + s", "y0"], ["x0", "y0 + s"]]}
    with pytest.raises(SelfIntersectionError):
        model_from_dict(at(small_doc(), "pairs[0].parts[1].loops[0]", bow))


def test_non_file_models_cannot_be_serialised():
    import dataclasses

    from mechanisms.models import reciprocating_cam
    from mechanisms.models.recip import build_recip
    # a built-in model is written as a document naming it; a model whose
    # builder is a user's own Python function cannot be written
    assert model_to_dict(reciprocating_cam())["builtin"] == "reciprocating_cam"
    own = dataclasses.replace(reciprocating_cam(), builder=_own_builder)
    assert own.build() == reciprocating_cam().build()
    with pytest.raises(InputError, match="cspace-model file or a built-in model"):
        model_to_dict(own)
    assert build_recip is not _own_builder


def _own_builder(values):
    from mechanisms.models.recip import build_recip
    return build_recip(values)


def test_load_errors(tmp_path):
    with pytest.raises(FileFormatError, match="no such file"):
        load_model(tmp_path / "none.json")
    (tmp_path / "nan.json").write_text('{"format": "cspace-model", "x": NaN}')
    with pytest.raises(FileFormatError, match="non-finite"):
        load_model(tmp_path / "nan.json")
    assert issubclass(ExpressionError, CSpaceError)


# ------------------------------------------------------------------ every dimension a parameter

def test_parametric_model_of_a_pair_reproduces_it_and_moves_each_vertex():
    from mechanisms.models import reciprocating_cam
    pair = reciprocating_cam().build()
    m = parametric_model(pair, 0.01)
    cam_loop = pair.driver.loops[0]
    assert m.n == 2 + 2 * len(cam_loop.segments) + 2 * 4 + 2 * 4
    assert_allclose(m.tol, 0.01, atol=0)
    got = m.build()
    for a_part, b_part in zip(pair.parts, got.parts):
        for la, lb in zip(a_part.loops, b_part.loops):
            assert len(la.segments) == len(lb.segments)
            for sa, sb in zip(la.segments, lb.segments):
                assert sa.kind == sb.kind and sa.name == sb.name
                assert_allclose(sb.start_point, sa.start_point, atol=1e-12)
                assert_allclose(sb.end_point, sa.end_point, atol=1e-12)
                if sa.kind == "arc":
                    assert_allclose(sb.center, sa.center, atol=1e-12)
                    assert_allclose(sb.radius, sa.radius, atol=1e-12)
    # moving one vertex moves exactly the two segments that share it, bulge kept
    u = m.values()
    u["cam_L0_P1_x"] += 0.01
    moved = m.build(u).driver.loops[0].segments
    changed = [i for i, (a, b) in enumerate(zip(got.driver.loops[0].segments, moved)) if a != b]
    assert changed == [0, 1]
    assert_allclose(moved[1].sweep, got.driver.loops[0].segments[1].sweep, atol=1e-12)
    assert "cam_axis_x" in m.names and "yoke_axis_x" not in m.names
    assert "cam_axis_x" not in parametric_model(pair, 0.01, param_mode="profile").names


def test_parametric_model_full_circle_and_errors():
    pair = model_from_dict(small_doc()).build()
    m = parametric_model(pair, 0.05)
    circle = m.build().driver.loops[0].segments
    assert [s.kind for s in circle] == ["arc", "arc"]
    assert_allclose([s.radius for s in circle], 2.0, atol=1e-12)
    with pytest.raises(InputError, match="tol"):
        parametric_model(pair, -1)
    with pytest.raises(InputError, match="param_mode"):
        parametric_model(pair, 0.1, param_mode="bulge")


def test_a_segment_name_used_twice_in_a_part_is_refused():
    """Segment names label a part's contacts (a vertex by its two segments),
    so two segments of one part may not share one; empty names, and the same
    name in the other part, are fine."""
    named = [dict(s, name=n) for s, n in zip(square(), ["bottom", "right", "top", "bottom"])]
    d = at(small_doc(), "pairs[0].parts[1].loops[0]", named)
    with pytest.raises(FileFormatError, match=r"'bottom' is used twice in part 'block'") as ei:
        model_from_dict(d)
    assert "loops[0][3].name" in str(ei.value) and "loops[0][0].name" in str(ei.value)
    named[3]["name"] = ""
    model_from_dict(at(small_doc(), "pairs[0].parts[1].loops[0]", named))
    disk = at(small_doc(), "pairs[0].parts[0].loops[0][0].name", "bottom")
    model_from_dict(at(disk, "pairs[0].parts[1].loops[0]", named))
    poly = {"polyline": [["x0", "y0"], ["x0 + s", "y0"], ["x0 + s", "y0 + s"], ["x0", "y0 + s"]],
            "names": ["a", "b", "a", ""]}
    with pytest.raises(FileFormatError, match="'a' is used twice"):
        model_from_dict(at(small_doc(), "pairs[0].parts[1].loops[0]", poly))
