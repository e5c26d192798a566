"""The operating point made explicit (issue 22, "Operating point"): import-dxf
writes the start, drive, window and deviation into the file; a model that
states no start is told which one was chosen and why; an ambiguous default
start is refused by synthesis unless accepted; a follower that never moves is
reported."""

import json
import warnings

import pytest

ezdxf = pytest.importorskip("ezdxf")

from cspace.defects import reference  # noqa: E402
from cspace.freespace import StartChoice  # noqa: E402
from mechanisms.analysis import (AmbiguousStartError, OperatingPointWarning,  # noqa: E402
                                 operating_point_notes, resolve_model)
from synthesis import synthesize  # noqa: E402
from synthesis.cli import main  # noqa: E402
from synthesis.executors import SerialExecutor  # noqa: E402

PARTS = ["--part", "CAM:cam:rotation:0,0", "--part", "FOL:follower:translation:0,1"]


@pytest.fixture(scope="module")
def drawing(tmp_path_factory):
    """An eccentric disc cam (radius 20 about (5, 0), turning about the origin)
    and a flat-faced block above it that slides along y.  At q1 = 0 the block
    can sit above the cam or below it: two free intervals of equal width in the
    touching window, and the default start takes the lower one, on the far side
    of the cam from where it is drawn."""
    d = tmp_path_factory.mktemp("op")
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    msp.add_circle((5, 0), 20, dxfattribs={"layer": "CAM"})
    msp.add_lwpolyline([(-15, 30), (15, 30), (15, 40), (-15, 40)], close=True,
                       dxfattribs={"layer": "FOL"})
    path = d / "cam.dxf"
    doc.saveas(path)
    return path


def _import(drawing, out, *extra):
    return main(["import-dxf", str(drawing), "--out", str(out), *PARTS, *extra])


def test_import_dxf_writes_the_operating_point(drawing, tmp_path):
    out = tmp_path / "m.json"
    assert _import(drawing, out, "--tol", "0.02", "--q2-start", "-9.9", "--drive", "0", "6",
                   "--window", "0", "6.283185307179586", "-70", "0", "--deviation", "0.05") == 0
    doc = json.loads(out.read_text())
    assert doc["q2_start"] == [-9.9] and doc["drive"] == [0, 6]
    assert doc["window"] == [0, 6.283185307179586, -70, 0] and doc["deviation"] == 0.05
    m = resolve_model(str(out))
    assert m.q2_start == (-9.9,) and m.drive == (0.0, 6.0) and m.deviation == 0.05
    # a pair file (no --tol) carries the same keys, and analyze reads them
    pair = tmp_path / "p.json"
    assert _import(drawing, pair, "--q2-start", "-9.9", "--window", "0", "6.283185307179586",
                   "-70", "0", "--deviation", "0.05") == 0
    doc = json.loads(pair.read_text())
    assert doc["q2_start"] == [-9.9] and doc["window"][2:] == [-70, 0]
    assert doc["deviation"] == 0.05
    assert main(["analyze", str(pair), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast"]) == 0
    cs = json.loads((tmp_path / "a" / "cspace.json").read_text())
    assert cs["window"][2:] == [-70, 0]
    sim = json.loads((tmp_path / "a" / "simulation.json").read_text())["pairs"][0]
    assert sim["q2"][0] == -9.9 and max(sim["q2"]) > -9.9


@pytest.mark.parametrize("extra, what", [
    (["--q2-start", "nan"], "--q2-start"),
    (["--drive", "1", "1"], "--drive must have two different ends"),
    (["--window", "0", "1", "5", "2"], "--window must have"),
    (["--deviation", "0"], "--deviation must be a finite number > 0"),
    (["--deviation", "inf"], "--deviation"),
])
def test_import_dxf_refuses_a_bad_operating_point(drawing, tmp_path, capsys, extra, what):
    out = tmp_path / "m.json"
    assert _import(drawing, out, "--tol", "0.02", *extra) == 2
    assert what in capsys.readouterr().err
    assert not out.exists()


def test_a_pair_file_with_a_bad_stated_window_is_refused(drawing, tmp_path, capsys):
    pair = tmp_path / "p.json"
    assert _import(drawing, pair, "--q2-start", "-9.9") == 0
    doc = json.loads(pair.read_text())
    doc["window"] = [0, 1, 3, 2]
    pair.write_text(json.dumps(doc))
    assert main(["analyze", str(pair), "--out", str(tmp_path / "a"), "--no-plots"]) == 2
    assert "'window' must have" in capsys.readouterr().err


def test_the_default_start_is_explained_and_an_ambiguous_one_refused(drawing, tmp_path,
                                                                     capsys):
    out = tmp_path / "m.json"
    assert _import(drawing, out, "--tol", "0.02") == 0
    assert "no operating point" in capsys.readouterr().err
    assert main(["analyze", str(out), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast"]) == 0
    err = capsys.readouterr().err
    assert "warning: pair 'cam' states no follower start" in err
    assert "one of 2 free intervals" in err and "widest" in err
    # synthesis refuses it, with what to do
    assert main(["synthesize", str(out), "--out", str(tmp_path / "s"), "--no-plots",
                 "--preset", "fast", "--executor", "serial", "--max-iter", "1"]) == 2
    err = capsys.readouterr().err
    assert "ambiguous" in err and "--accept-start" in err and "q2_start" in err
    # ... unless the user accepts it
    assert main(["synthesize", str(out), "--out", str(tmp_path / "s"), "--no-plots",
                 "--preset", "fast", "--executor", "serial", "--max-iter", "1",
                 "--accept-start"]) in (0, 1)
    assert "states no follower start" in capsys.readouterr().err


def test_library_synthesize_refuses_an_ambiguous_default_start(drawing, tmp_path):
    out = tmp_path / "m.json"
    assert _import(drawing, out, "--tol", "0.02") == 0
    m = resolve_model(str(out))
    ref = reference(m, "fast")
    (ch,) = ref.start_choices
    assert isinstance(ch, StartChoice) and ch.ambiguous and len(ch.intervals) == 2
    lo, hi = ch.intervals[ch.chosen]
    assert ch.q2 == pytest.approx(0.5 * (lo + hi))
    with pytest.warns(OperatingPointWarning), pytest.raises(AmbiguousStartError) as e:
        synthesize(m, "fast", executor=SerialExecutor(), max_iter=1)
    assert e.value.choices == (ch,) or e.value.choices[0].q2 == ch.q2
    with pytest.warns(OperatingPointWarning, match="one of 2 free intervals"):
        synthesize(m, "fast", executor=SerialExecutor(), max_iter=1, accept_start=True)


def test_a_stated_start_is_not_questioned(drawing, tmp_path):
    out = tmp_path / "m.json"
    assert _import(drawing, out, "--tol", "0.02", "--q2-start", "-9.9") == 0
    m = resolve_model(str(out))
    ref = reference(m, "fast")
    assert ref.start_choices == (None,)
    notes = operating_point_notes(ref.spaces, ref.sims, ref.start_choices)
    # no warning (a note says where the motion repeats from: the follower's
    # stated start lies in the play of its channel)
    assert [t for w, t in notes if w] == []
    assert all("in the play of its channel" in t for _, t in notes)
    with warnings.catch_warnings():
        warnings.simplefilter("error", OperatingPointWarning)
        r = synthesize(m, "fast", executor=SerialExecutor(), max_iter=2)
    assert r.nit >= 1


def test_a_follower_that_never_moves_is_reported(drawing, tmp_path, capsys):
    pair = tmp_path / "p.json"
    # drawn 5 mm above the cam's reach: nothing ever pushes it
    assert _import(drawing, pair, "--q2-start", "30", "--window", "0", "6.283185307179586",
                   "-70", "40") == 0
    assert main(["analyze", str(pair), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast"]) == 0
    err = capsys.readouterr().err
    assert "never moves over the drive (q2 stays at 30 mm)" in err
    # a follower that the cam pushes is not reported
    assert _import(drawing, pair, "--q2-start", "-9.9", "--window", "0", "6.283185307179586",
                   "-70", "40") == 0
    assert main(["analyze", str(pair), "--out", str(tmp_path / "b"), "--no-plots",
                 "--preset", "fast"]) == 0
    assert "never moves" not in capsys.readouterr().err


def test_save_pair_writes_only_motion_keys(tmp_path):
    from cspace.errors import InputError
    from cspace.io import load_json, save_pair
    from mechanisms.models import reciprocating_cam
    pair = reciprocating_cam().build()
    save_pair(pair, tmp_path / "p.json", {"q2_start": (0.45,), "drive": (0.0, 1.0)})
    doc = load_json(tmp_path / "p.json")
    assert doc["q2_start"] == [0.45] and doc["drive"] == [0.0, 1.0]
    with pytest.raises(InputError, match="motion keys must be among"):
        save_pair(pair, tmp_path / "q.json", {"start": 1.0})
    assert not (tmp_path / "q.json").exists()


def test_an_imported_cam_with_a_stated_start_synthesizes_sensibly(drawing, tmp_path):
    """The cam of the issue, imported with every dimension toleranced and its
    start stated: synthesis ends with a success, keeps every tolerance at 25 %
    or more, and neither shifts nor cuts the block's far corners (y = 40),
    which never touch the cam."""
    out = tmp_path / "m.json"
    assert _import(drawing, out, "--tol", "0.02", "--q2-start", "-9.9") == 0
    m = resolve_model(str(out))
    r = synthesize(m, "fast", executor=SerialExecutor(), max_iter=8)
    assert r.success, r.message
    kept = r.tol / m.tol
    assert kept.min() >= 0.25 - 1e-12
    far = [i for i, nm in enumerate(m.names) if nm.startswith("follower")
           and nm.endswith("_y") and abs(m.nominal[i] - 40.0) < 1e-9]
    assert far, m.names
    for i in far:
        assert r.tol[i] == m.tol[i] and r.nominal[i] == m.nominal[i], m.names[i]
