"""The command line for a new user (issue 24): --version, checks before work,
--resume taking the checkpoint's preset, progress off a terminal."""

import json
from pathlib import Path

import pytest

from synthesis.cli import main

FAST = ["--executor", "serial", "--preset", "fast", "--no-plots"]


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    import cspace
    assert capsys.readouterr().out.strip() == f"cspace-tol {cspace.__version__}"


def _no_work(monkeypatch):
    import mechanisms.analysis as an

    def boom(*a, **k):
        raise AssertionError("computed before checking the output folder")
    monkeypatch.setattr(an, "model_cspaces", boom)
    import cspace.defects as de
    monkeypatch.setattr(de, "reference", boom)


@pytest.mark.parametrize("where", ["under-a-file", "proc"])
def test_unusable_out_fails_before_any_work(tmp_path, capsys, monkeypatch, where):
    if where == "proc":
        if not Path("/proc/self").is_dir():
            pytest.skip("no /proc")
        out = "/proc/x"
    else:
        (tmp_path / "f").write_text("")
        out = str(tmp_path / "f" / "x")
    _no_work(monkeypatch)
    assert main(["analyze", "reciprocating_cam", "--out", out]) == 2
    err = capsys.readouterr().err
    assert "--out must name a folder that can be created and written" in err and out in err
    assert main(["synthesize", "reciprocating_cam", "--out", out, *FAST]) == 2
    assert "--out must name a folder" in capsys.readouterr().err


def test_max_iter_zero_is_refused_and_writes_nothing(tmp_path, capsys, monkeypatch):
    _no_work(monkeypatch)
    out = tmp_path / "o"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--max-iter", "0",
                 *FAST]) == 2
    assert "--max-iter must be >= 1" in capsys.readouterr().err
    assert not out.exists()


def test_resume_takes_the_preset_from_the_checkpoint(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--max-iter", "1",
                 *FAST]) == 1
    capsys.readouterr()
    # no --preset: the checkpoint's ("fast"), not the parser's default
    no_preset = ["--executor", "serial", "--no-plots"]
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--max-iter", "1", *no_preset]) == 1
    err = capsys.readouterr().err
    assert "preset fast" in err and "accuracy" not in err
    assert json.loads((out / "report.json").read_text())["accuracy"]["name"] == "fast"
    # the same preset named explicitly is fine, another one is refused by flag
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--max-iter", "1", "--preset", "fast", *no_preset]) == 1
    capsys.readouterr()
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--preset", "default", *no_preset]) == 2
    err = capsys.readouterr().err
    assert "--preset default conflicts with the checkpoint" in err and "'fast'" in err
    assert err.count("\n") == 1        # one line, not an accuracy diff


def test_analyze_says_what_it_does_and_animates(tmp_path, capsys):
    from PIL import Image
    out = tmp_path / "a"
    assert main(["analyze", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--animate", "--frames", "6"]) == 0
    err = capsys.readouterr().err
    for step in ("C-space of 1 pair(s), preset fast ...", "nominal motion ...",
                 "contact zones of the operating region (11 parameters) ..."):
        assert step in err, step
    assert Image.open(out / "animation.gif").n_frames == 6
    assert "<AnimationFile animation.gif: 6 frames, no jam or deviation>" in err
    # units and meaning of a zone overlap, and a short list
    assert "zone overlap(s) in the operating region" in err and "not a tested defect" in err
    assert "channel 0.09" in err and " cm, overlap " in err
    assert "... 1 more in zones.json" in err


def test_animate_a_parameter_vector_marks_the_deviation(tmp_path, capsys):
    from PIL import Image

    from mechanisms.models import reciprocating_cam
    m = reciprocating_cam()
    u = {nm: float(v + 6 * t * (1 if i % 2 else -1))
         for i, (nm, v, t) in enumerate(zip(m.names, m.nominal, m.tol))}
    out = tmp_path / "v"
    assert main(["analyze", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--no-plots", "--animate", "--frames", "8", "--params", json.dumps(u)]) == 0
    err = capsys.readouterr().err
    assert "8 frames" not in err           # the held event frames come on top
    assert "deviation at frame" in err
    n = Image.open(out / "animation.gif").n_frames
    assert n == 8 + 4
    sim = json.loads((out / "simulation.json").read_text())["pairs"][0]
    assert sim["status"] == "JAMMED"


def test_overlap_counts_agree_between_analyze_and_synthesis(short_run, tmp_path, capsys):
    a = tmp_path / "a"
    assert main(["analyze", "reciprocating_cam", "--out", str(a), "--preset", "fast",
                 "--no-plots"]) == 0
    n_analyze = len(json.loads((a / "zones.json").read_text())["overlaps"])
    rep = json.loads((short_run[1] / "report.json").read_text())
    assert n_analyze == rep["history"][0]["overlaps"] > 0
    # the zone plots and report.md give both counts: overlaps (a bound) and defects
    md = (short_run[1] / "report.md").read_text()
    assert f"| 1 | {rep['history'][0]['counts']['checklist']} | " in md


def _pair_file(tmp_path, **extra):
    from cspace.io import pair_to_dict
    from mechanisms.models import reciprocating_cam
    d = pair_to_dict(reciprocating_cam().build())
    d.update(extra)
    p = tmp_path / "pair.json"
    p.write_text(json.dumps(d))
    return p


def test_pair_file_is_simulated_when_it_states_its_start(tmp_path, capsys):
    p = _pair_file(tmp_path)
    out = tmp_path / "o"
    assert main(["analyze", str(p), "--out", str(out), "--preset", "fast", "--no-plots"]) == 0
    assert "give it 'q2_start'" in capsys.readouterr().err
    assert not (out / "simulation.json").exists()
    # --q2-start
    assert main(["analyze", str(p), "--out", str(out), "--preset", "fast", "--no-plots",
                 "--q2-start", "0.45"]) == 0
    sim = json.loads((out / "simulation.json").read_text())["pairs"][0]
    assert sim["status"] == "OK" and sim["q2"][0] == 0.45
    # the file's own start and drive, as in a model file
    p2 = _pair_file(tmp_path, q2_start=[0.45], drive=[0, 3.0])
    out2 = tmp_path / "o2"
    assert main(["analyze", str(p2), "--out", str(out2), "--preset", "fast",
                 "--animate", "--frames", "4"]) == 0
    sim2 = json.loads((out2 / "simulation.json").read_text())["pairs"][0]
    assert sim2["q1"][0] == 0 and abs(sim2["q1"][-1] - 3.0) < 1e-12
    assert (out2 / "simulation.png").exists() and (out2 / "animation.gif").exists()
    # bad start keys are clear errors; --animate without a start is refused up front
    p3 = _pair_file(tmp_path, q2_start=[0.1, 0.2])
    capsys.readouterr()
    assert main(["analyze", str(p3), "--out", str(tmp_path / "o3"), "--no-plots"]) == 2
    assert "'q2_start' must be one follower start per pair (1)" in capsys.readouterr().err
    # a start outside the window is refused, as a model's is (it was
    # simulated as blocked, with a warning and exit 0)
    p6 = _pair_file(tmp_path, q2_start=[5.0], window=[0, 6.283185307179586, -1, 1])
    assert main(["analyze", str(p6), "--out", str(tmp_path / "o6"), "--no-plots"]) == 2
    assert ("the follower start q2 = 5 of pair 'reciprocating_cam' is outside the follower "
            "window [-1, 1]") in capsys.readouterr().err
    # a single number where a list of one is read says how to write it
    p5 = _pair_file(tmp_path, q2_start=0.45)
    assert main(["analyze", str(p5), "--out", str(tmp_path / "o5"), "--no-plots"]) == 2
    assert ("a JSON list of 1 finite number(s), got 0.45 (a JSON list, even of one: [0.45])"
            in capsys.readouterr().err)
    assert main(["analyze", str(_pair_file(tmp_path)), "--out", str(tmp_path / "o4"),
                 "--animate"]) == 2
    assert "--animate needs a motion" in capsys.readouterr().err
    assert not (tmp_path / "o4").exists()


def test_a_pair_files_blocked_start_is_a_warning_with_a_degrees_hint(tmp_path, capsys):
    """A start that does not complete its drive is a warning line (not only the
    status in a progress line), and a rotating follower's start many turns out
    of its window is read as degrees."""
    from cspace.io import pair_to_dict
    from mechanisms.models import geneva
    p = tmp_path / "g.json"
    p.write_text(json.dumps(pair_to_dict(geneva().build())))
    assert main(["analyze", str(p), "--out", str(tmp_path / "o"), "--preset", "fast",
                 "--no-plots", "--q2-start", "180"]) == 0
    err = capsys.readouterr().err
    assert "warning: geneva: the motion does not complete its drive (START_BLOCKED)" in err
    assert "lies 27.6 turns outside the follower window" in err
    assert "radians(180) = 3.14159 rad" in err


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("syn") / "recip2"
    # the paper's removal: the cam still has defects after two iterations
    rc = main(["synthesize", "reciprocating_cam", "--out", str(out), "--executor", "serial",
               "--preset", "fast", "--max-iter", "2", "--verify", "6", "--seed", "1",
               "--removal", "greedy"])
    return rc, out


def test_report_md_summarises_the_run(short_run):
    rc, out = short_run
    assert rc == 1                       # the cap is reached with defects left
    md = (out / "report.md").read_text()
    rep = json.loads((out / "report.json").read_text())
    assert md.startswith("# Tolerance synthesis of reciprocating_cam")
    assert "**Status: MAX_ITER** after 2 iteration(s)" in md
    assert f"e = max |u0' - u0| = {rep['e']:.4g} cm" in md
    # the changed dimensions with initial, final, delta, tolerances and why
    assert ("| parameter | initial [cm] | final [cm] | delta [cm] | tolerance before [cm] | "
            "tolerance after [cm] | required by |") in md
    for nm, dv in rep["changed"].items():
        row = next(line for line in md.splitlines() if line.startswith(f"| {nm} |"))
        assert f"{dv:+.4g}" in row and "shift" in row and "iteration" in row
    # defects per iteration and the Monte Carlo figures
    for h in rep["history"]:
        assert f"| {h['iteration']} | {h['counts']['checklist']} | {h['defects']} |" in md
    v = rep["verification"]["final"]
    assert f"| final | 6 | {v['corners']} | {v['defective']} |" in md and "| 1 |" in md
    assert "Zone overlaps are not defects" in md
    assert ("cspace-tol synthesize model_initial.json --out again --preset fast --patience 4 "
            f"--deviation {rep['d']!r} --removal greedy --max-iter 2 --verify 6 --seed 1") in md
    assert "report.md" in rep["files"]
    for f in ("changes.png", "parts.png", "failures.png", "model.json", "model_initial.json"):
        assert (out / f).is_file(), f


def test_final_and_initial_model_files_are_accepted_everywhere(short_run, tmp_path, capsys):
    import numpy as np

    from mechanisms.analysis import resolve_model
    _, out = short_run
    rep = json.loads((out / "report.json").read_text())
    final = resolve_model(str(out / "model.json"))
    initial = resolve_model(str(out / "model_initial.json"))
    assert np.array_equal(final.nominal, rep["final"]["nominal"])
    assert np.array_equal(final.tol, rep["final"]["tol"])
    assert np.array_equal(initial.nominal, rep["initial"]["nominal"])
    from cspace.io import load_pair
    assert final.build() == load_pair(out / "pair.json")
    assert main(["analyze", str(out / "model.json"), "--out", str(tmp_path / "a"),
                 "--preset", "fast", "--no-plots"]) == 0
    pytest.importorskip("ezdxf")
    assert main(["export-dxf", str(out / "model.json"), "--out", str(tmp_path / "f.dxf")]) == 0
    # the reproduce command of report.md repeats the run from model_initial.json
    again = tmp_path / "again"
    assert main(["synthesize", str(out / "model_initial.json"), "--out", str(again),
                 "--executor", "serial", "--preset", "fast", "--patience", "4",
                 "--deviation", repr(rep["d"]), "--removal", "greedy", "--max-iter", "2",
                 "--no-plots"]) == 1
    rep2 = json.loads((again / "report.json").read_text())
    assert rep2["final"] == rep["final"]
    assert rep2["defects_per_iteration"] == rep["defects_per_iteration"]


def test_resuming_a_finished_run_keeps_its_outputs(tmp_path, capsys):
    """--resume of a converged run writes its outputs again from the
    checkpoint; its Monte Carlo check (--verify) was dropped from the new
    report without a word.  The finished run's outputs now go to previous/
    first, as for a new run into DIR."""
    out = tmp_path / "f"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--verify", "20",
                 *FAST]) == 0
    first = json.loads((out / "report.json").read_text())
    assert first["verification"]
    capsys.readouterr()
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--executor", "serial", "--no-plots"]) == 0
    err = capsys.readouterr().err
    assert "moved them to" in err and "previous" in err
    kept = json.loads((out / "previous" / "report.json").read_text())
    assert kept == first
    again = json.loads((out / "report.json").read_text())
    assert again["previous_run"] == "previous" and again["final"] == first["final"]


def test_a_pair_file_written_from_a_model_keeps_its_operating_point(tmp_path, capsys):
    """analyze's pair.json held the geometry only: analysed again it got the
    default window (q2 in [-6.71, 6.71] instead of the model's [-1, 1]), 32
    curves instead of 9, and no motion (no start).  It now states the model's
    drive, starts and window: the same C-space and motion."""
    out, again = tmp_path / "a", tmp_path / "b"
    assert main(["analyze", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--no-plots"]) == 0
    doc = json.loads((out / "pair.json").read_text())
    assert doc["window"] == [0.0, pytest.approx(6.283185307179586), -1.0, 1.0]
    assert doc["q2_start"] == [0.45] and len(doc["drive"]) == 2
    first = capsys.readouterr().err
    assert main(["analyze", str(out / "pair.json"), "--out", str(again), "--preset", "fast",
                 "--no-plots"]) == 0
    second = capsys.readouterr().err
    line = [ln for ln in first.splitlines() if "contact curves" in ln][0]
    assert line.split(": ", 1)[1] in second
    assert "no motion" not in second
    assert json.loads((again / "cspace.json").read_text())["window"] == \
        json.loads((out / "cspace.json").read_text())["window"]
