"""Limits of the JSON reader: deep nesting and huge integer literals are typed
errors (issue 23, items 1 and 2), at the loader and through the command line."""

import json

import pytest

from cspace.errors import FileFormatError, InputError
from cspace.io import MAX_JSON_DEPTH, load_json, load_pair, parse_json_text
from synthesis.cli import main


def _err(capsys):
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    return err


@pytest.mark.parametrize("depth", [MAX_JSON_DEPTH + 1, 990, 5000, 100000])
def test_deep_nesting_is_a_file_format_error(tmp_path, depth):
    p = tmp_path / "d.json"
    p.write_text("[" * depth + "]" * depth)
    with pytest.raises(FileFormatError, match=f"nest at most {MAX_JSON_DEPTH} levels"):
        load_json(p)


def test_deep_nesting_inside_loops(tmp_path):
    deep = "[" * 3000 + "]" * 3000
    p = tmp_path / "pair.json"
    p.write_text('{"format": "cspace-pair", "version": 1, "units": "mm", "parts": [{"name": '
                 '"a", "axis": {"type": "rotation", "center": [0, 0]}, "loops": ' + deep
                 + '}]}')
    with pytest.raises(FileFormatError, match="nest at most"):
        load_pair(p)


def test_nesting_at_the_limit_is_read():
    doc = parse_json_text("[" * MAX_JSON_DEPTH + "]" * MAX_JSON_DEPTH)
    assert isinstance(doc, list)


@pytest.mark.parametrize("digits", [4301, 5000, 100000])
def test_huge_integer_literal_is_a_file_format_error(tmp_path, digits):
    p = tmp_path / "h.json"
    p.write_text('{"format": "cspace-pair", "version": ' + "7" * digits + "}")
    with pytest.raises(FileFormatError, match=f"integer literal of {digits} digits"):
        load_json(p)


def test_integer_of_400_digits_still_reaches_the_value_check(tmp_path):
    p = tmp_path / "h.json"
    part = {"name": "a", "axis": {"type": "rotation", "center": [0, 0]},
            "loops": [[{"type": "arc", "center": [10 ** 400, 0], "radius": 1,
                        "start_angle": 0, "end_angle": 6.283185307179586}]]}
    d = {"format": "cspace-pair", "version": 1, "units": "mm",
         "parts": [part, dict(part, name="b")]}
    p.write_text(json.dumps(d))
    with pytest.raises(FileFormatError, match="finite number"):
        load_pair(p)


@pytest.mark.parametrize("text", ["[" * 100000 + "]" * 100000,
                                  '{"format": ' + "9" * 5000 + "}"])
@pytest.mark.parametrize("cmd", [["analyze", "--no-plots"],
                                 ["synthesize", "--executor", "serial", "--no-plots"]])
def test_cli_refuses_with_one_line(tmp_path, capsys, text, cmd):
    p = tmp_path / "bad.json"
    p.write_text(text)
    assert main([cmd[0], str(p), *cmd[1:], "--out", str(tmp_path / "o")]) == 2
    assert "error:" in _err(capsys)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("text", ["[" * 100000 + "]" * 100000, "[" + "9" * 5000 + "]"])
def test_params_option_refuses_deep_and_huge(text):
    from synthesis.cli.convert import parse_params
    with pytest.raises(InputError):
        parse_params(text)


def test_a_key_repeated_in_one_object_is_refused(tmp_path):
    """JSON lets a key repeat and the last value wins: a pasted line would
    change a tolerance unseen.  Every input file is refused instead, naming
    the key; the same key in different objects is fine."""
    from mechanisms.userfile import load_model
    p = tmp_path / "m.json"
    p.write_text('{"format": "cspace-model", "parameters": '
                 '[{"name": "a", "nominal": 1.0, "tol": 0.01, "tol": 0.5}]}')
    with pytest.raises(FileFormatError, match=r"key 'tol' appears more than once"):
        load_model(p)
    with pytest.raises(FileFormatError, match=r"keys 'a', 'b' appear more than once"):
        parse_json_text('{"a": 1, "b": 2, "a": 3, "b": 4}')
    assert parse_json_text('[{"a": 1}, {"a": 2}]') == [{"a": 1}, {"a": 2}]
