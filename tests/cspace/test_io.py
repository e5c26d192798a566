import json

import pytest

from cspace.errors import FileFormatError, NonPositiveRadiusError, OpenLoopError
from cspace.io import (atomic_write, dumps, load_pair, pair_from_dict, pair_to_dict, save_cspace,
                       save_pair)

from .shapes import rr_pair, rt_pair


@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam"])
def test_model_pairs_round_trip_exactly(models, name, tmp_path):
    obj = models[name].build()
    p = save_pair(obj, tmp_path / "p.json")
    back = load_pair(p)
    assert back == obj
    assert dumps(pair_to_dict(back)) == p.read_text()


@pytest.mark.parametrize("make", [rr_pair, rt_pair])
def test_synthetic_round_trip(make, tmp_path):
    obj = make()
    assert load_pair(save_pair(obj, tmp_path / "x.json")) == obj


def _doc():
    return json.loads(dumps(pair_to_dict(rr_pair())))


@pytest.mark.parametrize("mutate, err, path", [
    (lambda d: d["parts"][1]["loops"][0][1].__setitem__("radius", -2), NonPositiveRadiusError,
     "parts[1].loops[0][1]"),
    (lambda d: d["parts"][1]["loops"][0][1].__setitem__("radius", "big"), FileFormatError,
     "parts[1].loops[0][1].radius"),
    (lambda d: d["parts"][0]["loops"][0][0].__setitem__("end", [9, 9]), OpenLoopError,
     "parts[0].loops[0]"),
    (lambda d: d["parts"][0]["loops"][0][0].__setitem__("type", "spline"), FileFormatError,
     "parts[0].loops[0][0].type"),
    (lambda d: d["parts"][0]["axis"].__setitem__("type", "screw"), FileFormatError,
     "parts[0].axis.type"),
    (lambda d: d["parts"].pop(), FileFormatError, "parts"),
    (lambda d: d.__setitem__("version", 7), FileFormatError, "version"),
    (lambda d: d["parts"][0]["loops"][0][0].__setitem__("colour", "red"), FileFormatError,
     "parts[0].loops[0][0]"),
])
def test_bad_files_name_the_failing_path(mutate, err, path):
    d = _doc()
    mutate(d)
    with pytest.raises(err) as ei:
        pair_from_dict(d)
    assert path in str(ei.value)


def test_not_json_and_non_finite(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text("{not json")
    with pytest.raises(FileFormatError, match="not valid JSON"):
        load_pair(p)
    p.write_text(json.dumps(_doc()).replace('"radius": 0.25', '"radius": NaN', 1))
    with pytest.raises(FileFormatError, match="non-finite"):
        load_pair(p)
    with pytest.raises(FileFormatError, match="no such file"):
        load_pair(tmp_path / "missing.json")


def test_atomic_write_keeps_old_file_on_failure(tmp_path):
    p = tmp_path / "a.txt"
    atomic_write(p, "old")

    class Boom(str):
        def __len__(self):
            raise RuntimeError("boom")

    with pytest.raises(Exception):
        atomic_write(p, b"x" if False else object())  # not writable data
    assert p.read_text() == "old"
    assert [f.name for f in tmp_path.iterdir()] == ["a.txt"]


def test_cspace_json(cspaces, tmp_path):
    cs = cspaces["geneva"][0]
    d = json.loads(save_cspace(cs, tmp_path / "c.json").read_text())
    assert d["format"] == "cspace-cspace" and d["units"] == "cm"
    assert [c["unit"] for c in d["coordinates"]] == ["rad", "rad"]
    assert any(f["free"] for f in d["faces"]) and any(not f["free"] for f in d["faces"])
    assert sum(len(f["polygons"]) for f in d["faces"]) >= 2
    assert all(len(pl) >= 2 for c in d["curves"] for pl in c["polylines"])
    assert {c["label"] for c in d["curves"] if c["boundary"]} == {b.label for b in cs.boundary}
    b = next(c for c in d["curves"] if c["boundary"])
    assert b["depends"] and all(isinstance(x, str) for x in b["depends"])


def test_atomic_write_gives_ordinary_permissions(tmp_path):
    import os
    import stat

    from cspace.io import atomic_write
    umask = os.umask(0o022)
    try:
        p = atomic_write(tmp_path / "a.json", "{}")
        assert stat.S_IMODE(p.stat().st_mode) == 0o644
        os.chmod(p, 0o640)
        atomic_write(p, "[]")  # an existing file keeps its mode
        assert stat.S_IMODE(p.stat().st_mode) == 0o640
    finally:
        os.umask(umask)


def test_a_pair_file_may_state_its_motion(tmp_path):
    """``drive`` and ``q2_start`` (read by ``cspace-tol analyze``) load with the
    pair; any other unknown key is still refused, naming the allowed ones."""
    import json

    from cspace.errors import FileFormatError
    from cspace.io import load_pair, pair_to_dict
    from mechanisms.models import reciprocating_cam
    d = pair_to_dict(reciprocating_cam().build())
    d.update(drive=[0.0, 6.0], q2_start=[0.0])
    p = tmp_path / "p.json"
    p.write_text(json.dumps(d))
    assert load_pair(p).name == "reciprocating_cam"
    d["bogus"] = 1
    p.write_text(json.dumps(d))
    with pytest.raises(FileFormatError, match=r"unknown keys \['bogus'\].*'q2_start'"):
        load_pair(p)
