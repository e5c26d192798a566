"""A model file's misspelt key is named, with the closest allowed key, whether a
required key is missing because of it or not (nothing is silently ignored)."""

import copy

import pytest

from cspace.errors import FileFormatError
from mechanisms.userfile import model_from_dict


def _doc():
    return {"format": "cspace-model", "version": 1, "name": "disk", "units": "mm",
            "parameters": [{"name": "r", "nominal": 2.0, "tol": 0.1, "description": "radius"}],
            "pairs": [{"parts": [
                {"name": "disk", "axis": {"type": "rotation", "center": [0, 0]},
                 "loops": [[{"type": "arc", "center": [0, 0], "radius": "r",
                             "start_angle": 0, "end_angle": "2*pi"}]]},
                {"name": "block", "axis": {"type": "translation", "direction": [1, 0]},
                 "loops": [[{"type": "line", "start": [3, -1], "end": [5, -1]},
                            {"type": "line", "start": [5, -1], "end": [5, 1]},
                            {"type": "line", "start": [5, 1], "end": [3, 1]},
                            {"type": "line", "start": [3, 1], "end": [3, -1]}]]}]}]}


def _rename(node, old, new):
    node[new] = node.pop(old)


P = "pairs[0].parts[1]"


@pytest.mark.parametrize("edit, path, says", [
    (lambda d: _rename(d["parameters"][0], "tol", "tolerance"), "parameters[0]",
     r"missing required key 'tol'; found unknown key\(s\) \['tolerance'\] \(did you mean "
     r"'tol'\?\); allowed keys: \[.*'nominal'.*'tol'"),
    (lambda d: _rename(d["pairs"][0]["parts"][1]["loops"][0][0], "start", "strt"),
     f"{P}.loops[0][0]", r"missing required key 'start'; found unknown key\(s\) \['strt'\] "
                         r"\(did you mean 'start'\?\); allowed keys: \['end', 'name', "
                         r"'start', 'type'\]"),
    (lambda d: _rename(d["pairs"][0]["parts"][1]["loops"][0][0], "type", "typ"),
     f"{P}.loops[0][0]", r"missing required key 'type'; found unknown key\(s\) \['typ'\] "
                         r"\(did you mean 'type'\?\)"),
    (lambda d: _rename(d["pairs"][0]["parts"][1]["axis"], "type", "tpye"), f"{P}.axis",
     r"missing required key 'type'; found unknown key\(s\) \['tpye'\] \(did you mean "
     r"'type'\?\)"),
    (lambda d: _rename(d["pairs"][0]["parts"][1], "name", "nmae"), P,
     r"missing required key 'name'.*\['nmae'\] \(did you mean 'name'\?\)"),
    # nothing required is missing: the unknown key is still an error, not ignored
    (lambda d: _rename(d["parameters"][0], "description", "descripton"), "parameters[0]",
     r"unknown key\(s\) \['descripton'\] \(did you mean 'description'\?\); allowed: "),
    (lambda d: d["pairs"][0]["parts"][1]["axis"].update(orign=[0, 0]), f"{P}.axis",
     r"unknown key\(s\) \['orign'\] \(did you mean 'origin'\?\)"),
    (lambda d: d.update(deviaton=0.01), "",
     r"unknown key\(s\) \['deviaton'\] \(did you mean 'deviation'\?\)"),
    (lambda d: d.update(colour="red"), "", r"unknown key\(s\) \['colour'\]; allowed: "),
])
def test_a_misspelt_key_is_named(edit, path, says):
    d = copy.deepcopy(_doc())
    model_from_dict(d)              # the document itself is good
    edit(d)
    with pytest.raises(FileFormatError, match=says) as ei:
        model_from_dict(d)
    assert ei.value.path == path


def test_builtin_document_names_a_misspelt_key():
    from mechanisms.models import reciprocating_cam
    from mechanisms.userfile import model_to_dict
    d = model_to_dict(reciprocating_cam())
    _rename(d["parameters"][0], "tol", "tolerance")
    with pytest.raises(FileFormatError, match=r"parameters\[0\]: missing required key 'tol'; "
                                              r"found unknown key\(s\) \['tolerance'\]"):
        model_from_dict(d)
