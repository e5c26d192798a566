import json
import subprocess
import sys


from synthesis.cli import main


def test_analyze_builtin(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["analyze", "reciprocating_cam", "--out", str(out), "--preset", "fast"]) == 0
    names = {p.name for p in out.iterdir()}
    assert {"pair.json", "cspace.json", "cspace.png", "parts.png"} <= names
    d = json.loads((out / "cspace.json").read_text())
    assert d["units"] == "cm" and d["coordinates"][1]["unit"] == "cm"
    assert "free face" in capsys.readouterr().err


def test_analyze_pair_file(tmp_path):
    out = tmp_path / "a"
    assert main(["analyze", "reciprocating_cam", "--out", str(out), "--no-plots"]) == 0
    out2 = tmp_path / "b"
    a = json.loads((out / "cspace.json").read_text())
    w = [str(x) for x in a["window"]]
    assert main(["analyze", str(out / "pair.json"), "--out", str(out2), "--no-plots",
                 "--window", *w]) == 0
    b = json.loads((out2 / "cspace.json").read_text())
    assert [c["label"] for c in a["curves"]] == [c["label"] for c in b["curves"]]
    assert [f["free"] for f in a["faces"]] == [f["free"] for f in b["faces"]]


def test_bad_model_is_a_clear_error(tmp_path, capsys):
    assert main(["analyze", "nope", "--out", str(tmp_path)]) == 2
    assert "unknown model 'nope'" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "cspace-pair", "version": 1, "units": "mm", "parts": []}')
    assert main(["analyze", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "parts" in capsys.readouterr().err


def test_module_entry_point():
    r = subprocess.run([sys.executable, "-m", "synthesis", "--help"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0 and "analyze" in r.stdout
