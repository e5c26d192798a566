"""User-input fixes: length-unit names (known units, aliases, unknown units warned),
DXF $INSUNITS for every unit, far-away axis coordinates on DXF import, model files
with a UTF-8 byte-order mark, and angle parameters used as lengths."""

import json
import warnings

import pytest

from cspace.io import UnitWarning, canonical_unit
from mechanisms.userfile import load_model, model_from_dict
from tests.cspace.slotted_yoke import yoke_document


def yoke(units="mm", **over):
    """A small Scotch-yoke model document (crank pin in a stadium slot)."""
    params = [{"name": "a", "nominal": 30.0, "tol": 0.02},
              {"name": "r", "nominal": 5.0, "tol": 0.01},
              {"name": "hw", "nominal": 5.1, "tol": 0.01},
              {"name": "s", "nominal": 40.0, "tol": 0.05},
              {"name": "B", "nominal": 60.0, "tol": 0.5},
              {"name": "H", "nominal": 60.0, "tol": 0.5}]
    for p in params:
        p.update(over.get(p["name"], {}))
    return yoke_document(params, units=units)


def unit_warnings(record):
    return [w for w in record if issubclass(w.category, UnitWarning)]


# ----------------------------------------------------------------- unit names

@pytest.mark.parametrize("name, canon", [("mm", "mm"), ("MM", "mm"), ("inch", "in"),
                                         ("Inches", "in"), ("in", "in"), ("ft", "ft"),
                                         ("feet", "ft"), ("millimetre", "mm"),
                                         ("meters", "m"), ("\u00b5m", "um"), ("\u03bcm", "um"),
                                         ("micron", "um"), ("um", "um"), ("cm", "cm"),
                                         ("parsec", None), ("", None), (5, None)])
def test_known_units_and_aliases(name, canon):
    assert canonical_unit(name) == canon


@pytest.mark.parametrize("units", ["parsec", "furlong"])
def test_an_unknown_model_unit_is_warned_but_loads(units):
    with pytest.warns(UnitWarning, match=rf"'{units}' is not one this library knows.*mm"):
        m = model_from_dict(yoke(units))
    assert m.units == units          # reports keep the user's own string


@pytest.mark.parametrize("units", ["mm", "inch", "millimetre", "\u00b5m"])
def test_a_known_unit_or_alias_loads_quietly_and_keeps_its_spelling(units):
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnitWarning)
        m = model_from_dict(yoke(units))
    assert m.units == units


def test_a_parameter_may_state_an_alias_of_the_model_unit():
    d = yoke("inch", r={"unit": "in"})
    m = model_from_dict(d)
    assert m.parameters[m.index("r")].unit == ""       # a length, not an angle


def test_an_unknown_pair_unit_is_warned_but_loads(tmp_path):
    from cspace.geometry import Arc, Line, Loop, Pair, Part, Rotation, Translation
    from cspace.io import load_pair, save_pair
    drv = Part("d", (Loop((Arc((3.0, 0.0), 1.0, 0.0, 6.283185307179586, True),)),),
               Rotation((0.0, 0.0)))
    sq = ((10, -2), (14, -2), (14, 2), (10, 2))
    fol = Part("f", (Loop(tuple(Line(sq[i], sq[(i + 1) % 4]) for i in range(4))),),
               Translation((1.0, 0.0)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnitWarning)
        save_pair(Pair(drv, fol, "parsec", "p"), tmp_path / "p.json")
    with pytest.warns(UnitWarning, match="units: length unit 'parsec'"):
        p = load_pair(tmp_path / "p.json")
    assert p.units == "parsec"


# ----------------------------------------------------------------- BOM

def test_a_model_file_with_a_utf8_bom_loads(tmp_path):
    f = tmp_path / "bom.json"
    f.write_bytes(b"\xef\xbb\xbf" + json.dumps(yoke()).encode("utf-8"))
    assert load_model(f).name == "yoke"


# ----------------------------------------------------------------- angle as a length

def test_an_angle_parameter_used_as_a_length_is_warned():
    d = yoke(a={"unit": "deg"})
    with pytest.warns(UnitWarning, match=r"loops\[0\]\[0\]\.center\[0\]: parameter 'a' is an "
                                         r"angle .*'deg'.* becomes a length in 'mm'"):
        model_from_dict(d)


def test_an_angle_parameter_used_as_a_length_through_a_let_is_warned():
    d = yoke(a={"unit": "rad", "nominal": 0.5})
    d["let"] = [{"name": "ax", "value": "a + 0"}]
    d["pairs"][0]["parts"][0]["loops"][0][0]["center"] = ["30 + ax", 0]
    with pytest.warns(UnitWarning, match="through let 'ax'"):
        model_from_dict(d)


def test_an_angle_inside_a_function_or_a_factor_is_not_warned():
    d = yoke()
    d["parameters"].append({"name": "th", "nominal": 10.0, "tol": 0.1, "unit": "deg"})
    d["pairs"][0]["parts"][0]["loops"][0][0]["center"] = ["a * cos(th)", "a * sin(th)"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnitWarning)
        model_from_dict(d)


# ----------------------------------------------------------------- DXF

ezdxf = pytest.importorskip("ezdxf")


def _parts(center=(0, 0)):
    return [{"layer": "crank", "name": "crank",
             "axis": {"type": "rotation", "center": list(center)}},
            {"layer": "yoke", "name": "yoke",
             "axis": {"type": "translation", "direction": [1, 0], "origin": [0, 0]}}]


def test_export_of_an_alias_unit_writes_its_code(tmp_path):
    from mechanisms.dxf import export_dxf, import_dxf
    m = model_from_dict(yoke("inch"))
    export_dxf(m, tmp_path / "y.dxf")
    assert ezdxf.readfile(str(tmp_path / "y.dxf")).header["$INSUNITS"] == 1
    p = import_dxf(tmp_path / "y.dxf", parts=_parts(), units="mm")
    pin = p.parts[0].loops[0].segments[0]
    assert pin.radius == pytest.approx(5 * 25.4)        # not 5000 mm


def test_export_of_an_unknown_unit_is_unitless_and_warned(tmp_path):
    from mechanisms.dxf import export_dxf, import_dxf
    with pytest.warns(UnitWarning):
        m = model_from_dict(yoke("parsec"))
    with pytest.warns(UnitWarning, match=r"\$INSUNITS = 0"):
        export_dxf(m, tmp_path / "y.dxf")
    assert ezdxf.readfile(str(tmp_path / "y.dxf")).header["$INSUNITS"] == 0
    p = import_dxf(tmp_path / "y.dxf", parts=_parts(), units="mm")
    assert p.parts[0].loops[0].segments[0].radius == pytest.approx(5.0)


def test_import_to_an_alias_unit_converts(tmp_path):
    from mechanisms.dxf import export_dxf, import_dxf
    export_dxf(model_from_dict(yoke("mm")), tmp_path / "y.dxf")
    p = import_dxf(tmp_path / "y.dxf", parts=_parts(), units="centimetre")
    assert p.units == "centimetre"
    assert p.parts[0].loops[0].segments[0].radius == pytest.approx(0.5)


def test_an_axis_far_outside_the_drawing_is_warned(tmp_path):
    from mechanisms.dxf import AxisWarning, export_dxf, import_dxf
    export_dxf(model_from_dict(yoke("mm")), tmp_path / "y.dxf")
    # the crank centre given in mm while the target unit is m: 1000 times too far
    with pytest.warns(AxisWarning, match=r"part 'crank'.*rotation centre \(0, 300\).*"
                                         r"drawing's unit 'mm'.*\(0, 0\.3\)"):
        import_dxf(tmp_path / "y.dxf", parts=_parts((0, 300)), units="m")
    with warnings.catch_warnings():
        warnings.simplefilter("error", AxisWarning)
        import_dxf(tmp_path / "y.dxf", parts=_parts((0, 0.3)), units="m")
        import_dxf(tmp_path / "y.dxf", parts=_parts((0, 300)), units="mm")
