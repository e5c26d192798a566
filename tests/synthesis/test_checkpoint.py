"""The checkpoint file: its canonical content hash, writing and reading back
bit for bit, and refusing content that does not match its hash."""

import json

import numpy as np
import pytest

from cspace.defects import DefectResult, Reason
from cspace.errors import FileFormatError
from synthesis.checkpoint import (HASH_KEY, checkpoint_text, content_hash, read_checkpoint,
                                  write_checkpoint)
from synthesis.result import IterationRecord, PartialIteration, SynthesisState

NAMES = ("crank", "pin_r", "half_width")


def _state(with_partial=True) -> SynthesisState:
    """A running state after one iteration, with tests of the second in progress."""
    u0 = np.array([20.0, 5.0, 5.03])
    t0 = np.array([0.02, 0.02, 0.02])
    u1 = u0 + np.array([0.0, -0.1 - 0.2, 0.3])     # floats that print with many digits
    rec = IterationRecord(1, u0, t0, {"checklist": 8, "seeds": 4}, 2, (3, 5), {"JAM": 2},
                          u1 - u0, ({"parameter": "pin_r", "old": 0.02, "new": 0.01},), False,
                          12, {"total": 1.25})
    partial = None
    if with_partial:
        r = DefectResult(True, (Reason.JAM,), float("inf"), 0.004, (0, 1.0, 2.0), (), (), "jam")
        partial = PartialIteration(2, u1, t0, ((u1 + 0.01, r, True, -0.5),
                                               (u1 - 0.01, r, False, float("nan"))))
    return SynthesisState("yoke", NAMES, u0, t0, u1, t0, {"name": "fast"}, 0.004,
                          history=(rec,), removed=(u0 + t0,), shifted=(("pin_r+", 1),),
                          partial=partial)


def test_checkpoint_text_carries_the_hash_of_the_rest():
    st = _state()
    doc = json.loads(checkpoint_text(st))
    assert len(doc[HASH_KEY]) == 64 and int(doc[HASH_KEY], 16) >= 0
    assert doc[HASH_KEY] == content_hash(doc)
    body = {k: v for k, v in doc.items() if k != HASH_KEY}
    assert body == json.loads(json.dumps(st.to_dict()))
    # the hash key itself is not hashed, whatever it holds
    assert content_hash(body) == content_hash(dict(body, **{HASH_KEY: "anything"}))


def test_content_hash_is_canonical():
    doc = {"b": [1.5, 2], "a": {"y": 0.1, "x": None}}
    flipped = {"a": {"x": None, "y": 0.1}, "b": [1.5, 2]}
    assert content_hash(doc) == content_hash(flipped)
    # numpy values and tuples hash as they are read back from the file
    as_numpy = {"a": {"y": np.float64(0.1), "x": None}, "b": np.array([1.5, 2.0])}
    assert content_hash(as_numpy) == content_hash({"a": {"y": 0.1, "x": None}, "b": [1.5, 2.0]})
    assert content_hash({"b": (1.5, 2), "a": {"y": 0.1, "x": None}}) == content_hash(doc)


def test_content_hash_sees_the_last_bit():
    doc = {"d": 0.004, "nominal": [20.0, 5.0]}
    h = content_hash(doc)
    assert content_hash(dict(doc, d=float(np.nextafter(0.004, 1.0)))) != h
    assert content_hash(dict(doc, nominal=[20.0, 5.0, 0.0])) != h
    assert content_hash(dict(doc, extra=None)) != h


@pytest.mark.parametrize("with_partial", [True, False])
def test_write_then_read_gives_the_state_bit_for_bit(tmp_path, with_partial):
    st = _state(with_partial)
    path = tmp_path / "run" / "checkpoint.json"
    written = write_checkpoint(path, st)
    assert written == path and path.is_file()
    # atomic: no temporary file is left beside it
    assert [p.name for p in path.parent.iterdir()] == ["checkpoint.json"]
    back, verified = read_checkpoint(path)
    assert verified
    assert back.to_dict() == st.to_dict()
    assert back.nominal.tobytes() == st.nominal.tobytes()
    assert back.history[0].shift.tobytes() == st.history[0].shift.tobytes()
    if with_partial:
        (u, r, c, m), (u2, _, c2, m2) = back.partial.tests
        assert u.tobytes() == st.partial.tests[0][0].tobytes()
        assert r.reasons == (Reason.JAM,) and c is True and m == -0.5
        assert c2 is False and np.isnan(m2)
    else:
        assert back.partial is None


def test_a_checkpoint_without_a_hash_is_read_unverified(tmp_path):
    st = _state()
    path = tmp_path / "checkpoint.json"
    path.write_text(json.dumps(st.to_dict()))
    back, verified = read_checkpoint(path)
    assert not verified and back.to_dict() == st.to_dict()


def test_the_hash_may_be_written_in_capitals(tmp_path):
    doc = json.loads(checkpoint_text(_state()))
    doc[HASH_KEY] = doc[HASH_KEY].upper()
    path = tmp_path / "checkpoint.json"
    path.write_text(json.dumps(doc))
    assert read_checkpoint(path)[1]


def test_changed_content_is_refused_and_left_as_it_is(tmp_path):
    doc = json.loads(checkpoint_text(_state()))
    doc["d"] = 0.005                  # a valid value, but not the one hashed
    path = tmp_path / "checkpoint.json"
    text = json.dumps(doc)
    path.write_text(text)
    with pytest.raises(FileFormatError, match=r"damaged checkpoint: its content does not match "
                                              r"its sha256 .*--fresh") as e:
        read_checkpoint(path)
    assert e.value.path == str(path) and str(e.value).startswith(str(path))
    assert path.read_text() == text


@pytest.mark.parametrize("value", ["f" * 63, 42, ["0" * 64]])
def test_a_malformed_hash_is_refused(tmp_path, value):
    doc = json.loads(checkpoint_text(_state()))
    doc[HASH_KEY] = value
    path = tmp_path / "checkpoint.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(FileFormatError, match="'sha256' must be 64 hex digits"):
        read_checkpoint(path)


def test_other_files_are_refused(tmp_path):
    path = tmp_path / "checkpoint.json"
    path.write_text(json.dumps({"format": "cspace-synthesis-report", "version": 1}))
    with pytest.raises(FileFormatError, match="expected a 'cspace-synthesis-checkpoint' "
                                              "document, got 'cspace-synthesis-report'"):
        read_checkpoint(path)
    path.write_text("[1, 2")
    with pytest.raises(FileFormatError):
        read_checkpoint(path)
    with pytest.raises(FileFormatError, match="no such file"):
        read_checkpoint(tmp_path / "missing.json")
