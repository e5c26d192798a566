"""import-dxf and export-dxf subcommands, end to end."""

import json
import math
from pathlib import Path

import pytest
from numpy.testing import assert_allclose

ezdxf = pytest.importorskip("ezdxf")

from cspace.io import load_pair
from mechanisms.analysis import pairs_of, resolve_model
from mechanisms.models import reciprocating_cam
from synthesis.cli import main
from synthesis.cli.convert import parse_part

EXAMPLE = Path(__file__).resolve().parents[3] / "docs" / "examples" / "flat_follower_cam.json"
RECIP_PARTS = ["--part", "cam:cam:rotation:0,0", "--part", "yoke:yoke:translation:1,0:0,0"]


def test_parse_part():
    assert parse_part("L1:cam:rotation:1.5,-2") == {
        "layer": "L1", "name": "cam", "axis": {"type": "rotation", "center": [1.5, -2.0]}}
    assert parse_part("F:f:translation:0,1")["axis"] == {
        "type": "translation", "direction": [0.0, 1.0], "origin": [0.0, 0.0]}
    assert parse_part("F:f:translation:0,1:3,4")["axis"]["origin"] == [3.0, 4.0]


@pytest.mark.parametrize("spec", ["cam:rotation:0,0", "L:c:spin:0,0", "L:c:rotation:0",
                                  "L:c:rotation:a,b", "L:c:rotation:0,0:1,1", "L:c:rotation:nan,0",
                                  "L:c:translation:0,1:0,0:9"])
def test_bad_part_specs_fail_clearly(tmp_path, capsys, spec):
    code = main(["import-dxf", str(tmp_path / "x.dxf"), "--out", str(tmp_path / "o.json"),
                 "--part", spec, "--part", "B:b:rotation:0,0"])
    assert code == 2
    assert "--part" in capsys.readouterr().err


def test_export_then_import_pair_and_model(tmp_path, capsys):
    dxf = tmp_path / "recip.dxf"
    assert main(["export-dxf", "reciprocating_cam", "--out", str(dxf)]) == 0
    assert dxf.is_file()
    # it names the layers and what the drawing does not hold
    err = capsys.readouterr().err
    assert "one layer per part, cam, yoke." in err and "give each part's axis again" in err
    pair_json = tmp_path / "pair.json"
    assert main(["import-dxf", str(dxf), "--out", str(pair_json), *RECIP_PARTS]) == 0
    d = json.loads(pair_json.read_text())
    assert d["format"] == "cspace-pair" and d["units"] == "cm"
    pair = load_pair(pair_json)
    ref = reciprocating_cam().build()
    assert_allclose(pair.driver.loops[0].area, ref.driver.loops[0].area, rtol=1e-12)
    model_json = tmp_path / "model.json"
    assert main(["import-dxf", str(dxf), "--out", str(model_json), *RECIP_PARTS,
                 "--tol", "0.01", "--name", "recip_drawn"]) == 0
    err = capsys.readouterr().err
    assert "parameters (+/- 0.01 cm)" in err
    # the cam's finger tips meet their flanks tangentially: said, with where to read why
    assert "warning: 6 join(s) of part 'cam' are tangent;" in err
    assert "(docs/model_file.md, 'bulges stay fixed')" in err
    m = resolve_model(str(model_json))
    assert m.name == "recip_drawn" and m.units == "cm"
    assert "cam_L0_P0_x" in m.names and "cam_axis_x" in m.names
    assert_allclose(m.tol, 0.01, atol=0)
    # the model file analyses like any model
    assert main(["analyze", str(model_json), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast", "--window", "0", str(2 * math.pi), "-1", "1"]) == 0
    assert json.loads((tmp_path / "a" / "cspace.json").read_text())["stats"]["free_faces"] >= 1
    # a window analyze would refuse (degrees) is refused before a file is written
    bad = tmp_path / "deg.json"
    capsys.readouterr()
    for extra in ([], ["--tol", "0.01"]):
        assert main(["import-dxf", str(dxf), "--out", str(bad), *RECIP_PARTS, *extra,
                     "--window", "0", "360", "-1", "1"]) == 2
        assert capsys.readouterr().err.strip().splitlines()[-1] == (
            "error: window for rotating coordinate q1 spans 360 rad; at most one period (2 pi) "
            "is allowed; written in degrees? radians(0) and radians(360) are 0 and 6.28319 rad")
        assert not bad.exists()


def test_import_states_the_followers_closure(tmp_path):
    """A drawing cannot say that the follower is spring-loaded: --bias does,
    into the pair file and into the model file's pair."""
    dxf = tmp_path / "recip.dxf"
    assert main(["export-dxf", "reciprocating_cam", "--out", str(dxf)]) == 0
    for extra, where in (([], lambda d: d), (["--tol", "0.01"], lambda d: d["pairs"][0])):
        out = tmp_path / f"o{len(extra)}.json"
        assert main(["import-dxf", str(dxf), "--out", str(out), *RECIP_PARTS, *extra,
                     "--bias", "-1"]) == 0
        assert where(json.loads(out.read_text()))["closure"] == {"bias": -1}
        assert pairs_of(resolve_model(str(out)))[0].bias == -1
    # form closure (the default) writes none
    assert main(["import-dxf", str(dxf), "--out", str(tmp_path / "f.json"), *RECIP_PARTS]) == 0
    assert "closure" not in json.loads((tmp_path / "f.json").read_text())


def test_import_with_units_conversion(tmp_path):
    dxf = tmp_path / "recip.dxf"
    main(["export-dxf", "reciprocating_cam", "--out", str(dxf)])
    out = tmp_path / "mm.json"
    assert main(["import-dxf", str(dxf), "--out", str(out), *RECIP_PARTS, "--units", "mm"]) == 0
    mm = load_pair(out)
    ref = reciprocating_cam().build()
    assert mm.units == "mm"
    assert_allclose(mm.driver.loops[0].area, 100 * ref.driver.loops[0].area, rtol=1e-12)


def test_export_model_file_with_params(tmp_path):
    a, b = tmp_path / "a.dxf", tmp_path / "b.dxf"
    assert main(["export-dxf", str(EXAMPLE), "--out", str(a)]) == 0
    assert main(["export-dxf", str(EXAMPLE), "--out", str(b), "--params", '{"rb": 21}']) == 0
    pfile = tmp_path / "p.json"
    pfile.write_text(json.dumps({"rb": 21}))
    c = tmp_path / "c.dxf"
    assert main(["export-dxf", str(EXAMPLE), "--out", str(c), "--params", str(pfile)]) == 0

    def base_radius(path):
        arcs = ezdxf.readfile(path).modelspace().query('ARC[layer=="cam"]')
        return max(e.dxf.radius for e in arcs)
    assert base_radius(a) == 20.0 and base_radius(b) == 21.0 and base_radius(c) == 21.0
    doc = ezdxf.readfile(a)
    assert doc.header["$INSUNITS"] == 4
    assert {e.dxf.layer for e in doc.modelspace()} == {"cam", "follower"}


def test_export_errors(tmp_path, capsys):
    out = tmp_path / "x.dxf"
    assert main(["export-dxf", "geneva", "--out", str(out), "--params", "{bad json"]) == 2
    assert "--params" in capsys.readouterr().err
    assert main(["export-dxf", "geneva", "--out", str(out), "--params", '{"nope": 1}']) == 2
    assert "no parameter 'nope'" in capsys.readouterr().err
    assert main(["export-dxf", "geneva", "--out", str(out), "--params", "3"]) == 2
    assert not out.exists()


def test_import_errors(tmp_path, capsys):
    assert main(["import-dxf", str(tmp_path / "none.dxf"), "--out", str(tmp_path / "o.json"),
                 *RECIP_PARTS]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["import-dxf", str(tmp_path / "none.dxf"), "--out", str(tmp_path / "o.json"),
                 "--part", "cam:cam:rotation:0,0"]) == 2
    assert "exactly twice" in capsys.readouterr().err
