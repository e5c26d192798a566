"""A nominal design whose own motion jams: analyze draws it and warns;
synthesize and yield refuse it (there is no healthy motion to test variants
against), naming where it jams; a window drawn too small is named as the
place of the jam."""

import json

from synthesis.cli import main

#: A crank pin in the obround slot of a sliding yoke; the slot ends at y = +-sl.
YOKE = {
    "format": "cspace-model", "version": 1, "name": "scotch_yoke", "units": "mm",
    "parameters": [
        {"name": "cx", "nominal": 0.0, "tol": 0.02},
        {"name": "cy", "nominal": 0.0, "tol": 0.02},
        {"name": "r", "nominal": 10.0, "tol": 0.02},
        {"name": "pr", "nominal": 2.0, "tol": 0.01},
        {"name": "xs", "nominal": 10.0, "tol": 0.02},
        {"name": "hw", "nominal": 2.05, "tol": 0.02},
        {"name": "sl", "nominal": 13.0, "tol": 0.05}],
    "let": [{"name": "ox0", "value": "xs - 6"}, {"name": "ox1", "value": "xs + 6"}],
    "window": [0, "2*pi", -21, 1], "drive": [0, "2*pi"], "q2_start": [0.0],
    "pairs": [{"name": "yoke", "parts": [
        {"name": "crank", "axis": {"type": "rotation", "center": ["cx", "cy"]},
         "loops": [[{"type": "arc", "name": "pin", "center": ["cx + r", "cy"], "radius": "pr",
                     "start_angle": 0, "end_angle": "2*pi", "ccw": True}]]},
        {"name": "yoke", "axis": {"type": "translation", "direction": [1, 0],
                                  "origin": ["xs", 0]},
         "loops": [
             {"polyline": [["ox0", -20], ["ox1", -20], ["ox1", 20], ["ox0", 20]]},
             [{"type": "line", "name": "slot.left", "start": ["xs - hw", "-sl"],
               "end": ["xs - hw", "sl"]},
              {"type": "arc", "name": "slot.top", "center": ["xs", "sl"], "radius": "hw",
               "start_angle": "pi", "end_angle": 0, "ccw": False},
              {"type": "line", "name": "slot.right", "start": ["xs + hw", "sl"],
               "end": ["xs + hw", "-sl"]},
              {"type": "arc", "name": "slot.bottom", "center": ["xs", "-sl"], "radius": "hw",
               "start_angle": 0, "end_angle": "-pi", "ccw": False}]]}]}]}


def _model(tmp_path, name, **change):
    d = json.loads(json.dumps(YOKE))
    for k, v in change.items():
        if k == "sl":
            d["parameters"][6]["nominal"] = v
        else:
            d[k] = v
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(d))
    return path


def test_a_healthy_yoke_makes_a_reference(tmp_path):
    from cspace.defects import reference
    from mechanisms.userfile import load_model
    ref = reference(load_model(_model(tmp_path, "ok")), "fast")
    assert ref.sims[0].success


def test_short_slot_jams_analyze_warns_synthesize_and_yield_refuse(tmp_path, capsys):
    path = _model(tmp_path, "short", sl=7.0)        # the pin meets the slot's end
    assert main(["analyze", str(path), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast"]) == 0
    err = capsys.readouterr().err
    assert "simulation JAMMED" in err
    assert "warning: model 'scotch_yoke': the nominal design's motion jams" in err
    assert "no contact zones" in err
    assert (tmp_path / "a" / "simulation.json").exists()
    # a variant of it analyses too: there is no defect test to run, and the log says so
    assert main(["analyze", str(path), "--out", str(tmp_path / "p"), "--no-plots",
                 "--preset", "fast", "--params", '{"sl": 7.01}']) == 0
    err = capsys.readouterr().err
    assert ("no defect test of this vector: the nominal design has no healthy motion to "
            "test it against") in err
    for cmd in (["synthesize", str(path), "--out", str(tmp_path / "s"), "--no-plots",
                 "--preset", "fast"],
                ["yield", str(path), "--out", str(tmp_path / "y"), "--samples", "50"]):
        assert main(cmd) == 2
        err = capsys.readouterr().err
        assert "the nominal design's motion jams" in err and "driver blocked at q1 = 0.78" in err
        assert "Traceback" not in err


def test_a_window_too_small_is_named(tmp_path, capsys):
    path = _model(tmp_path, "small", window=[0, "2*pi", -13, 13])   # the stroke is -20..0
    assert main(["synthesize", str(path), "--out", str(tmp_path / "s"), "--no-plots",
                 "--preset", "fast"]) == 2
    err = capsys.readouterr().err
    assert "against the lower edge of the C-space window (q2 = -13)" in err
    assert "widen the window" in err


def test_analyze_params_seats_the_start_as_the_defect_test_does(tmp_path, capsys):
    """A variant whose slot moved off the stated start q2 = 0 (the free
    interval at q1 = 0 is [-0.13, -0.03] for xs = 10.08) starts at the
    nearest free point, as the defect test assembles it, and says so."""
    path = _model(tmp_path, "ok")
    assert main(["analyze", str(path), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast", "--params", '{"xs": 10.08}']) == 0
    err = capsys.readouterr().err
    assert ("the stated start q2 = 0 is blocked in this variant; its follower starts at the "
            "nearest free point, q2 = -0.03") in err
    sim = json.loads((tmp_path / "a" / "simulation.json").read_text())
    text = json.dumps(sim)
    assert "-0.03" in text
    # the defect test's verdict of the vector against the nominal design
    assert "the defect test of this vector against the nominal design (d = " in err
    line = next(ln for ln in err.splitlines() if "the defect test of this vector" in ln)
    assert line.endswith(": healthy") or ": DEFECTIVE - " in line


def test_analyze_params_of_a_variant_that_cannot_start_or_jams(tmp_path, capsys):
    path = _model(tmp_path, "ok")
    # the slot narrower than the pin: no free point near the stated start
    assert main(["analyze", str(path), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast", "--params", '{"hw": 1.99}']) == 0
    err = capsys.readouterr().err
    assert "this variant cannot start: the defect test finds it defective" in err
    assert (tmp_path / "a" / "cspace.json").exists()
    # the slot's end short of the pin's travel: the variant's motion jams
    assert main(["analyze", str(path), "--out", str(tmp_path / "b"), "--no-plots",
                 "--preset", "fast", "--params", '{"sl": 7.0}']) == 0
    err = capsys.readouterr().err
    assert "this variant's motion jams (driver blocked at q1 = 0.78" in err
    assert "warning: model" not in err
    line = next(ln for ln in err.splitlines() if "the defect test of this vector" in ln)
    assert ": DEFECTIVE - " in line
    # the deviation is read up to the jam, and the motion simulated is the variant's
    assert "largest output deviation up to where it jams " in line
    assert "motion of this vector ..." in err and "nominal motion ..." not in err
