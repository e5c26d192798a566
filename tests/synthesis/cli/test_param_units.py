"""A parameter stated in degrees in its model file (``"unit": "deg"``):
``--params`` reads a named value in degrees, a list as the library writes its
vectors (rad), and the synthesis report gives its values in degrees."""

import json
import math

import numpy as np
import pytest

from cspace.io import load_pair
from mechanisms.userfile import load_model
from synthesis.cli import main
from synthesis.cli.convert import declared_units, params_vector
from synthesis.cli.report import in_declared_units, markdown_report, write_outputs
from synthesis.result import IterationRecord, SynthesisResult, SynthesisStatus


def _doc():
    """An eccentric disc (radius r, its centre at distance ex in the direction
    ph, in degrees) turning about the origin under a flat follower sliding
    along y, spring-loaded down."""
    face = [[-20, "yf"], [20, "yf"], [20, "yf + 5"], [-20, "yf + 5"]]
    return {
        "format": "cspace-model", "version": 1, "name": "disc", "units": "mm",
        "parameters": [{"name": "r", "nominal": 10.0, "tol": 0.02},
                       {"name": "ex", "nominal": 3.0, "tol": 0.02},
                       {"name": "ph", "nominal": 30.0, "tol": 0.1, "unit": "deg"},
                       {"name": "yf", "nominal": 14.0, "tol": 0.02}],
        "window": [0, "2*pi", -9, 4], "drive": [0, "2*pi"], "q2_start": [2.0],
        "pairs": [{"closure": {"bias": -1}, "parts": [
            {"name": "disc", "axis": {"type": "rotation", "center": [0, 0]},
             "loops": [[{"type": "arc", "center": ["ex*cos(ph)", "ex*sin(ph)"], "radius": "r",
                         "start_angle": 0, "end_angle": "2*pi"}]]},
            {"name": "follower", "axis": {"type": "translation", "direction": [0, 1]},
             "loops": [{"polyline": face}]}]}]}


@pytest.fixture
def model_file(tmp_path):
    path = tmp_path / "disc.json"
    path.write_text(json.dumps(_doc()))
    return path


def _disc_angle(pair) -> float:
    """The direction of the disc's centre, in degrees."""
    c = pair.driver.loops[0].segments[0].center
    return math.degrees(math.atan2(c[1], c[0]))


def test_declared_units_name_the_degrees_of_the_model_file(model_file):
    m = load_model(model_file)
    assert m.param_units == ("mm", "mm", "rad", "mm")
    assert declared_units(m) == (("mm", 1.0), ("mm", 1.0), ("deg", math.pi / 180), ("mm", 1.0))
    # a built-in model states its own units
    from mechanisms.models import reciprocating_cam
    b = reciprocating_cam()
    assert declared_units(b) == tuple((u, 1.0) for u in b.param_units)


def test_a_named_value_is_read_in_the_parameters_own_unit(model_file, capsys):
    m = load_model(model_file)
    u = params_vector(m, '{"ph": 30.05, "r": 10.01}')
    np.testing.assert_allclose(u, [10.01, 3.0, math.radians(30.05), 14.0], rtol=1e-15)
    assert capsys.readouterr().err == ""          # inside the box: no warning
    # a file holding one reads the same
    f = model_file.parent / "p.json"
    f.write_text('{"ph": 30.05}')
    assert params_vector(m, str(f))[2] == pytest.approx(math.radians(30.05), rel=1e-15)
    assert params_vector(m, None) is None


def test_a_list_is_read_as_the_library_writes_its_vectors(model_file, capsys):
    """A vector of checkpoint.json or report.json (angles in rad) analyses
    that very design: it round-trips bit for bit."""
    m = load_model(model_file)
    v = [9.99, 3.01, math.radians(29.95), 14.02]
    f = model_file.parent / "defective.json"
    f.write_text(json.dumps(v))
    np.testing.assert_array_equal(params_vector(m, str(f)), v)
    assert capsys.readouterr().err == ""


def test_a_value_far_outside_its_box_is_warned_about_with_its_unit(model_file, capsys):
    m = load_model(model_file)
    # radians written for a parameter stated in degrees
    u = params_vector(m, '{"ph": 0.5236}')
    assert u[2] == pytest.approx(math.radians(0.5236))
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("warning: --params: ph = 0.5236 deg")
    assert "far outside its tolerance box 30 +/- 0.1 deg" in err
    # degrees in a list, which is read in rad
    params_vector(m, "[10, 3, 30, 14]")
    err = capsys.readouterr().err
    assert "ph = 30 rad" in err and "+/- 0.00174533 rad" in err and "give it in deg" in err
    # a length: its unit
    params_vector(m, '{"r": 11}')
    assert "r = 11 mm lies far outside its tolerance box 10 +/- 0.02 mm" in \
        capsys.readouterr().err


def test_analyze_reads_params_in_degrees(model_file, tmp_path, capsys):
    out = tmp_path / "a"
    assert main(["analyze", str(model_file), "--out", str(out), "--preset", "fast",
                 "--no-plots", "--params", '{"ph": 30.05}']) == 0
    assert _disc_angle(load_pair(out / "pair.json")) == pytest.approx(30.05, abs=1e-9)
    assert "warning: --params" not in capsys.readouterr().err


def test_export_dxf_reads_params_in_degrees(model_file, tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    out = tmp_path / "d.dxf"
    assert main(["export-dxf", str(model_file), "--out", str(out), "--params",
                 '{"ph": 30.05}']) == 0
    (c,) = ezdxf.readfile(out).modelspace().query('CIRCLE[layer=="disc"]')
    assert math.degrees(math.atan2(c.dxf.center[1], c.dxf.center[0])) == \
        pytest.approx(30.05, abs=1e-9)


# ------------------------------------------------------------------ the report
def _result(m):
    """A run that cut the tolerance of ph and shifted ph by 0.05 deg."""
    u0, t0 = m.nominal, m.tol
    shift = np.array([0.0, 0.0, math.radians(0.05), 0.0])
    cut = {"parameter": "ph", "old": float(t0[2]), "new": float(t0[2] / 2), "vector": 0}
    hist = (IterationRecord(1, u0, t0, {"checklist": 4}, 0, (0,), {"JAM": 1}, shift, (cut,),
                            False, 3, {"total": 1.0}),)
    return SynthesisResult(True, SynthesisStatus.CONVERGED, SynthesisStatus.CONVERGED.value,
                           2, m.name, m.names, m.units, u0, t0, u0 + shift,
                           t0 * [1, 1, 0.5, 1], 0.0, hist, (), 0.004, {"name": "fast"},
                           param_units=m.param_units, e_angle=float(shift[2]))


def test_the_report_gives_a_degree_parameter_in_degrees(model_file, tmp_path):
    m = load_model(model_file)
    r = _result(m)
    write_outputs(r, m, tmp_path / "s", plots=False)
    md = (tmp_path / "s" / "report.md").read_text()
    assert "| ph | deg | 30 | 30.05 | +0.05 | 0.1 | 0.05 |" in md
    assert "| ph | rad |" not in md
    rep = json.loads((tmp_path / "s" / "report.json").read_text())
    assert rep["parameter_units"] == ["mm", "mm", "deg", "mm"]
    ph = rep["changes"]["ph"]
    assert ph["initial"] == pytest.approx(30) and ph["final"] == pytest.approx(30.05)
    assert ph["tol_initial"] == pytest.approx(0.1) and ph["tol_final"] == pytest.approx(0.05)
    assert rep["changed"]["ph"] == pytest.approx(0.05)
    assert rep["shrunk"]["ph"] == pytest.approx([0.1, 0.05])
    # the vectors code reads back stay in rad, and say so
    assert rep["vector_units"] == ["mm", "mm", "rad", "mm"]
    assert rep["final"]["nominal"] == r.nominal.tolist()
    assert rep["history"][0]["nominal"] == r.initial_nominal.tolist()
    assert "ph in deg" in rep["units_note"] and "angles in rad (vector_units)" in \
        rep["units_note"]
    # the final design written back in degrees, and a vector of the report
    # passed to --params is that design again
    assert json.loads((tmp_path / "s" / "model.json").read_text())["parameters"][2][
        "nominal"] == pytest.approx(30.05)
    vec = tmp_path / "final.json"
    vec.write_text(json.dumps(rep["final"]["nominal"]))
    np.testing.assert_array_equal(params_vector(m, str(vec)), r.nominal)
    named = {k: c["final"] for k, c in rep["changes"].items()}
    np.testing.assert_allclose(params_vector(m, json.dumps(named)), r.nominal, rtol=1e-14)


def test_a_result_in_declared_units_keeps_its_vectors():
    """Only the reported values change unit; a model without degrees leaves
    the result as it is."""
    from mechanisms.userfile import model_from_dict
    m = model_from_dict(_doc())
    r = _result(m)
    shown = in_declared_units(r, m)
    assert shown.param_units == ("mm", "mm", "deg", "mm")
    assert [shown.vector_unit_of(i) for i in range(4)] == ["mm", "mm", "rad", "mm"]
    assert shown.nominal is r.nominal and shown.tol is r.tol
    assert shown.changes()["ph"]["delta"] == pytest.approx(0.05)
    assert r.changes()["ph"]["delta"] == pytest.approx(math.radians(0.05))
    assert "| ph | deg | 30 |" in markdown_report(shown)
    d = _doc()
    d["parameters"][2]["unit"] = "rad"
    d["parameters"][2]["nominal"] = 0.5
    plain = model_from_dict(d)
    assert in_declared_units(_result(plain), plain).param_scales == ()


def test_the_log_gives_a_degree_parameter_in_degrees(model_file, capsys):
    """The changes the log lists at the end of a run are in each parameter's
    declared unit, as in report.md."""
    import importlib
    cli = importlib.import_module("synthesis.cli.main")
    m = load_model(model_file)
    cli._log_synthesis(_result(m), None, m)
    lines = capsys.readouterr().err.splitlines()
    assert "  ph: +0.05 deg" in lines
    assert "  tolerance of ph: 0.1 -> 0.05 deg" in lines
    assert not any(ln.startswith("  ph:") and ln.endswith("rad") for ln in lines)
    assert not any("tolerance of ph" in ln and ln.endswith("rad") for ln in lines)


def test_synthesize_logs_a_degree_parameter_in_degrees(tmp_path, capsys):
    """End to end (about a second): the shrunk tolerance of ph is logged in
    degrees, with the values report.json gives."""
    d = _doc()
    d["deviation"] = 0.002
    d["parameters"][2]["tol"] = 1.0
    f = tmp_path / "disc.json"
    f.write_text(json.dumps(d))
    out = tmp_path / "s"
    main(["synthesize", str(f), "--out", str(out), "--preset", "fast", "--executor",
          "serial", "--no-plots", "--max-iter", "2"])
    lines = capsys.readouterr().err.splitlines()
    rep = json.loads((out / "report.json").read_text())
    assert "ph" in rep["shrunk"]
    a, b = rep["shrunk"]["ph"]
    assert a == pytest.approx(1.0)
    assert f"  tolerance of ph: {a:.6g} -> {b:.6g} deg" in lines
    for nm, dv in rep["changed"].items():
        assert f"  {nm}: {dv:+.6g} {rep['parameter_units'][rep['parameters'].index(nm)]}" \
            in lines
