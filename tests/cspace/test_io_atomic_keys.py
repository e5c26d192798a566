"""Messages that point the right way: an atomic write names its target (not the
temporary file) and says when a directory is in the way; a pair file's
misspelt key is named with the closest allowed key."""

import errno
import json
import os

import pytest

from cspace.errors import FileFormatError
from cspace.io import (atomic_write, key_suggestions, missing_key_message, pair_from_dict,
                       pair_to_dict)
from mechanisms.models import reciprocating_cam


def test_atomic_write_onto_a_directory_names_it(tmp_path):
    target = tmp_path / "report.md"
    target.mkdir()
    with pytest.raises(IsADirectoryError) as ei:
        atomic_write(target, "text")
    e = ei.value
    assert e.filename == str(target) and e.errno == errno.EISDIR
    assert "directory" in str(e) and "expected a file" in str(e)
    assert os.listdir(tmp_path) == ["report.md"]       # no temporary file left


def test_atomic_write_errors_name_the_target_not_the_temporary_file(tmp_path, monkeypatch):
    target = tmp_path / "out.json"

    def replace(src, dst):
        raise IsADirectoryError(errno.EISDIR, "Is a directory", str(src))
    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(IsADirectoryError) as ei:
        atomic_write(target, b"x")
    assert ei.value.filename == str(target) and ".tmp" not in str(ei.value)
    assert "found a directory" in str(ei.value)
    assert os.listdir(tmp_path) == []


def test_a_folder_that_takes_no_files_is_named_as_the_target(tmp_path, monkeypatch):
    """The temporary file itself could not be made (export-dxf --out
    /proc/x.dxf named '/proc/.x.dxf.3h_fw7yo.tmp')."""
    import tempfile
    target = tmp_path / "out.dxf"

    def mkstemp(prefix="", suffix="", dir=None):
        raise FileNotFoundError(errno.ENOENT, "No such file or directory",
                                os.path.join(dir, prefix + "abc" + suffix))
    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    with pytest.raises(FileNotFoundError) as ei:
        atomic_write(target, b"x")
    assert ei.value.filename == str(target) and ".tmp" not in str(ei.value)


def test_key_suggestions():
    assert key_suggestions({"tolerance"}, ["name", "nominal", "tol"], ["tol"]) == \
        " (did you mean 'tol'?)"
    assert key_suggestions({"strt"}, ["type", "start", "end"]) == " (did you mean 'start'?)"
    assert key_suggestions({"zzz"}, ["type", "start", "end"]) == ""
    two = key_suggestions({"strt", "ed"}, ["type", "start", "end"])
    assert "'start' for 'strt'" in two and "'end' for 'ed'" in two
    msg = missing_key_message("tol", {"name": 1, "tolerance": 2}, ["name", "tol"])
    assert msg == ("missing required key 'tol'; found unknown key(s) ['tolerance'] "
                   "(did you mean 'tol'?); allowed keys: ['name', 'tol']")
    assert missing_key_message("tol", {"name": 1}, ["name", "tol"]) == \
        "missing required key 'tol'"


def _pair():
    return json.loads(json.dumps(pair_to_dict(reciprocating_cam().build())))


def _rename(d, old, new):
    d[new] = d.pop(old)


@pytest.mark.parametrize("edit, path, says", [
    (lambda d: _rename(d["parts"][0], "name", "nme"), "parts[0]",
     r"missing required key 'name' \(part name\); found unknown key\(s\) \['nme'\] "
     r"\(did you mean 'name'\?\); allowed keys: \['axis', 'loops', 'name'\]"),
    (lambda d: _rename(d["parts"][0]["axis"], "type", "typ"), "parts[0].axis",
     r"missing required key 'type'.*\['typ'\] \(did you mean 'type'\?\)"),
    (lambda d: _rename(d["parts"][0]["loops"][0][0], "type", "tpye"), "parts[0].loops[0][0]",
     r"missing required key 'type'.*\['tpye'\] \(did you mean 'type'\?\)"),
    (lambda d: _rename(d["parts"][0]["loops"][0][0], "start", "strt"), "parts[0].loops[0][0]",
     r"unknown keys \['strt'\] for a line \(did you mean 'start'\?\); allowed"),
    (lambda d: _rename(d, "units", "unit"), "pair",
     r"unknown keys \['unit'\] in a pair \(did you mean 'units'\?\)"),
    (lambda d: d.update(closure={"bais": 1}), "closure",
     r"unknown keys \['bais'\] in a closure \(did you mean 'bias'\?\)"),
])
def test_a_misspelt_pair_key_is_named(edit, path, says):
    d = _pair()
    edit(d)
    with pytest.raises(FileFormatError, match=says) as ei:
        pair_from_dict(d)
    assert ei.value.path == path
