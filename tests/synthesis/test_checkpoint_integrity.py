"""Checkpoint integrity: a content hash is stored, a checkpoint whose content does
not match it is refused and left as it is (issue 23, item 9)."""

import json

import pytest

from cspace.errors import FileFormatError
from synthesis.checkpoint import HASH_KEY, content_hash, read_checkpoint
from synthesis.cli import main


def _err(capsys):
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def one_iteration(tmp_path_factory):
    out = tmp_path_factory.mktemp("ck") / "o"
    assert main(["synthesize", "reciprocating_cam", "--preset", "fast", "--executor",
                 "serial", "--no-plots", "--max-iter", "1", "--out", str(out)]) == 1
    return (out / "checkpoint.json").read_text()


ARGS = ["synthesize", "reciprocating_cam", "--preset", "fast", "--executor", "serial",
        "--no-plots", "--max-iter", "2"]


def _one_digit_changed(text: str) -> str:
    d = json.loads(text)
    v = d["nominal"][0]
    s = repr(v)
    i = max(k for k, ch in enumerate(s) if ch.isdigit())
    changed = s[:i] + ("8" if s[i] == "9" else str(int(s[i]) + 1)) + s[i + 1:]
    assert float(changed) != v
    return text.replace(s, changed, 1)


def test_checkpoint_holds_a_matching_hash(one_iteration, tmp_path):
    d = json.loads(one_iteration)
    assert len(d[HASH_KEY]) == 64 and d[HASH_KEY] == content_hash(d)
    p = tmp_path / "checkpoint.json"
    p.write_text(one_iteration)
    state, verified = read_checkpoint(p)
    assert verified and state.iterations == 1


def test_one_digit_changed_is_refused_and_kept(one_iteration, tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    bad = _one_digit_changed(one_iteration)
    json.loads(bad)   # still valid JSON with valid values
    ck = out / "checkpoint.json"
    ck.write_text(bad)
    with pytest.raises(FileFormatError, match="does not match its sha256"):
        read_checkpoint(ck)
    assert main([*ARGS, "--resume", "--out", str(out)]) == 2
    err = _err(capsys)
    assert "does not match its sha256" in err and len(err.strip().splitlines()) == 1
    # without --resume it is not overwritten either
    assert main([*ARGS, "--out", str(out)]) == 2
    assert "damaged" in _err(capsys)
    assert ck.read_text() == bad


@pytest.mark.parametrize("value", ["abc", 12, None, "0" * 64])
def test_bad_hash_values_are_refused(one_iteration, tmp_path, value):
    d = json.loads(one_iteration)
    d[HASH_KEY] = value
    p = tmp_path / "checkpoint.json"
    p.write_text(json.dumps(d))
    with pytest.raises(FileFormatError, match="damaged checkpoint"):
        read_checkpoint(p)


def test_checkpoint_without_a_hash_resumes_with_a_notice(one_iteration, tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    d = json.loads(one_iteration)
    del d[HASH_KEY]
    (out / "checkpoint.json").write_text(json.dumps(d))
    assert main([*ARGS, "--resume", "--out", str(out)]) in (0, 1)
    assert "has no content hash" in _err(capsys)
    # the run rewrote it with a hash
    d2 = json.loads((out / "checkpoint.json").read_text())
    assert d2[HASH_KEY] == content_hash(d2)
