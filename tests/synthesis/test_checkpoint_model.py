"""A checkpoint remembers the model it was started with: ``--resume`` with another
model file (geometry, parameters, operating point, deviation threshold) is
refused, naming what differs; the same model (or its ``model_initial.json``)
resumes, and a checkpoint written before the fingerprint was kept resumes with a
note."""

import copy
import json

import pytest

from cspace.errors import CSpaceError, FileFormatError, InputError
from mechanisms.models import reciprocating_cam
from mechanisms.userfile import model_from_dict, model_to_dict
from synthesis.checkpoint import (FINGERPRINT_KEY, HASH_KEY, ModelMismatchError, check_model,
                                  content_hash, load_checkpoint, model_fingerprint,
                                  read_checkpoint, write_checkpoint)
from synthesis.cli import main
from synthesis.loop import initial_state

from ..mechanisms.test_userfile import small_doc

D = 0.0015


def _doc():
    """The model file of tests/mechanisms/test_userfile.py (a disk of radius r on
    a rotating axis against a sliding square follower), named, described and
    with its deviation threshold."""
    d = small_doc()
    d.update(name="disk", description="a disk", deviation=D)
    d["parameters"][0]["description"] = "radius"
    return d


def _changed(edit):
    d = copy.deepcopy(_doc())
    edit(d)
    return d


def _radius(d):
    d["pairs"][0]["parts"][0]["loops"][0][0]["radius"] = "r + 0.5"


def _ckpt(path, model, with_model=True):
    state, _ = initial_state(model, "fast", d=model.deviation)
    write_checkpoint(path, state, model=model if with_model else None)
    return load_checkpoint(path)


# ---------------------------------------------------------------------- fingerprint

def test_fingerprint_is_that_of_the_definition():
    base = model_fingerprint(model_from_dict(_doc()))
    assert set(base) == {"sha256", "sections", "deviation"} and base["deviation"] == D
    # the same model read again, written back, or with other descriptions
    assert model_fingerprint(model_from_dict(_doc())) == base
    assert model_fingerprint(model_from_dict(model_to_dict(model_from_dict(_doc())))) == base

    def desc(d):
        d["description"] = "another text"
        d["parameters"][0]["description"] = "r"
        d["let"][0]["description"] = "twice r"
    assert model_fingerprint(model_from_dict(_changed(desc))) == base
    # 2 and 2.0 are one number
    assert model_fingerprint(model_from_dict(_changed(
        lambda d: d["parameters"][0].update(nominal=2)))) == base


@pytest.mark.parametrize("edit, section", [
    (_radius, "geometry"),
    (lambda d: d["let"][0].update(value="2 * r + 0"), "geometry"),
    (lambda d: d.update(units="cm"), "geometry"),
    (lambda d: d["parameters"][1].update(tol=0.2), "parameters"),
    (lambda d: d["parameters"][1].update(fixed=True), "parameters"),
    (lambda d: d["parameters"][1].update(distribution={"kind": "normal", "cp": 1.33}),
     "parameters"),
    (lambda d: d.update(window=[0, "2*pi", -5, 5]), "operating_point"),
    (lambda d: d.update(q2_start=[4.5]), "operating_point"),
])
def test_fingerprint_sees_every_part_of_the_definition(edit, section):
    a = model_fingerprint(model_from_dict(_doc()))
    b = model_fingerprint(model_from_dict(_changed(edit)))
    assert a["sha256"] != b["sha256"]
    assert [k for k in a["sections"] if a["sections"][k] != b["sections"][k]] == [section]


def test_builtin_fingerprint_survives_its_model_file():
    m = reciprocating_cam()
    fp = model_fingerprint(m)
    assert model_fingerprint(reciprocating_cam()) == fp
    assert model_fingerprint(model_from_dict(model_to_dict(m))) == fp
    assert model_fingerprint(m.with_tolerances(m.tol * 2))["sha256"] != fp["sha256"]


# ------------------------------------------------------------------------ check_model

def test_checkpoint_stores_the_fingerprint_and_accepts_its_model(tmp_path):
    m = model_from_dict(_doc())
    ck = _ckpt(tmp_path / "checkpoint.json", m)
    doc = json.loads((tmp_path / "checkpoint.json").read_text())
    assert doc[FINGERPRINT_KEY] == model_fingerprint(m) == ck.fingerprint
    assert ck.verified and doc[HASH_KEY] == content_hash(doc)
    assert check_model(ck, model_from_dict(_doc())) is True
    assert check_model(ck, m, deviation=D) is True
    # read_checkpoint keeps its two values
    state, verified = read_checkpoint(tmp_path / "checkpoint.json")
    assert verified and state.d == D


def test_other_geometry_is_refused_naming_it(tmp_path):
    ck = _ckpt(tmp_path / "checkpoint.json", model_from_dict(_doc()))
    with pytest.raises(ModelMismatchError) as ei:
        check_model(ck, model_from_dict(_changed(_radius)))
    e = ei.value
    assert isinstance(e, InputError) and isinstance(e, CSpaceError)
    assert e.kind == "definition" and e.sections == ("geometry",)
    msg = str(e)
    assert "the model's definition differs from the checkpoint's" in msg
    assert "fingerprint" in msg and "geometry" in msg
    assert "--fresh" in msg and "another folder" in msg


def test_other_deviation_is_refused_with_both_values(tmp_path):
    ck = _ckpt(tmp_path / "checkpoint.json", model_from_dict(_doc()))
    with pytest.raises(ModelMismatchError,
                       match="deviation threshold d: checkpoint 0.0015, given 0.003") as ei:
        check_model(ck, model_from_dict(_changed(lambda d: d.update(deviation=0.003))))
    assert ei.value.kind == "deviation"
    with pytest.raises(ModelMismatchError, match="deviation threshold d: checkpoint 0.0015, "
                                                 "given 0.002 \\(--deviation\\)"):
        check_model(ck, model_from_dict(_doc()), deviation=0.002)
    with pytest.raises(ModelMismatchError, match="checkpoint 0.0015, given none"):
        check_model(ck, model_from_dict(_changed(lambda d: d.pop("deviation"))))


def test_other_model_name_is_refused(tmp_path):
    ck = _ckpt(tmp_path / "checkpoint.json", model_from_dict(_doc()))
    with pytest.raises(ModelMismatchError, match="model name: checkpoint 'disk', given 'x'"):
        check_model(ck, model_from_dict(_changed(lambda d: d.update(name="x"))))


def test_checkpoint_without_fingerprint_is_not_compared(tmp_path):
    ck = _ckpt(tmp_path / "checkpoint.json", model_from_dict(_doc()), with_model=False)
    assert ck.fingerprint is None and ck.verified
    assert check_model(ck, model_from_dict(_changed(_radius))) is False


@pytest.mark.parametrize("value", ["abc", {"sha256": "0" * 64}, {"sha256": 1, "sections": {}},
                                   {"sha256": "0" * 64, "sections": {"g": "x"}}])
def test_damaged_fingerprint_is_refused(tmp_path, value):
    p = tmp_path / "checkpoint.json"
    _ckpt(p, model_from_dict(_doc()))
    doc = json.loads(p.read_text())
    doc[FINGERPRINT_KEY] = value
    doc[HASH_KEY] = content_hash(doc)
    p.write_text(json.dumps(doc))
    with pytest.raises(FileFormatError, match="damaged checkpoint: 'model_fingerprint'"):
        load_checkpoint(p)


# ------------------------------------------------------------------------- the CLI

@pytest.fixture
def files(tmp_path):
    def write(name, doc):
        p = tmp_path / name
        p.write_text(json.dumps(doc))
        return str(p)
    return {"orig": write("orig.json", _doc()), "geo": write("geo.json", _changed(_radius)),
            "dev": write("dev.json", _changed(lambda d: d.update(deviation=0.003)))}


@pytest.fixture
def no_run(monkeypatch):
    """The run itself left out: these tests are about what --resume accepts."""
    import importlib
    cli = importlib.import_module("synthesis.cli.main")
    monkeypatch.setattr(cli, "_run_synthesis", lambda *a, **k: 0)


def _resume(model, out, *extra):
    return main(["synthesize", model, "--out", str(out), "--resume", "--executor", "serial",
                 "--no-plots", *extra])


@pytest.mark.parametrize("which, says", [
    ("geo", "the model's definition differs from the checkpoint's"),
    ("dev", "deviation threshold d: checkpoint 0.0015, given 0.003"),
])
def test_resume_with_another_model_file_is_refused(files, tmp_path, capsys, no_run, which,
                                                    says):
    out = tmp_path / "o"
    out.mkdir()
    ck = out / "checkpoint.json"
    _ckpt(ck, model_from_dict(_doc()))
    before = ck.read_text()
    assert _resume(files[which], out) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and says in err and "--fresh" in err
    assert ck.read_text() == before


def test_resume_with_the_same_model_is_accepted(files, tmp_path, capsys, no_run):
    out = tmp_path / "o"
    out.mkdir()
    _ckpt(out / "checkpoint.json", model_from_dict(_doc()))
    assert _resume(files["orig"], out) == 0
    err = capsys.readouterr().err
    assert "resuming 'disk'" in err and "fingerprint" not in err


def test_resume_of_an_old_checkpoint_notes_it_cannot_check(files, tmp_path, capsys, no_run):
    out = tmp_path / "o"
    out.mkdir()
    _ckpt(out / "checkpoint.json", model_from_dict(_doc()), with_model=False)
    assert _resume(files["geo"], out) == 0
    err = capsys.readouterr().err
    assert "has no model fingerprint" in err and "resuming 'disk'" in err


def test_resume_of_a_builtin_model(tmp_path, capsys, no_run):
    out = tmp_path / "o"
    out.mkdir()
    m = reciprocating_cam()
    state, _ = initial_state(m, "fast", d=0.01)
    write_checkpoint(out / "checkpoint.json", state, model=m)
    assert _resume("reciprocating_cam", out) == 0
    # its model_initial.json is the same model
    (tmp_path / "m.json").write_text(json.dumps(model_to_dict(m)))
    assert _resume(str(tmp_path / "m.json"), out) == 0
    assert "error" not in capsys.readouterr().err


def test_a_new_run_writes_the_fingerprint(tmp_path):
    """One short real run of the smallest built-in model."""
    out = tmp_path / "o"
    assert main(["synthesize", "reciprocating_cam", "--preset", "fast", "--executor", "serial",
                 "--no-plots", "--max-iter", "1", "--out", str(out)]) == 1
    ck = load_checkpoint(out / "checkpoint.json")
    assert ck.fingerprint == model_fingerprint(reciprocating_cam())
