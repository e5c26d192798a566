"""The synthesis command line: a failed Monte Carlo check, the operating point
in the report, a stop during the check, earlier results kept, failure labels
apart, progress of the check, and the report.json field reference."""

import io
import json
import re
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from synthesis.cli.main import main
from synthesis.verify import MonteCarloResult

ROOT = Path(__file__).resolve().parents[2]

#: A Scotch yoke that states no follower start: its default start is one of
#: three free intervals (a run needs --accept-start).
YOKE = {
    "format": "cspace-model", "version": 1, "name": "scotch_yoke", "units": "mm",
    "parameters": [
        {"name": "cx", "nominal": 0.0, "tol": 0.02}, {"name": "cy", "nominal": 0.0, "tol": 0.02},
        {"name": "R", "nominal": 10.0, "tol": 0.02}, {"name": "rp", "nominal": 2.0, "tol": 0.02},
        {"name": "wl", "nominal": 2.05, "tol": 0.06}, {"name": "wr", "nominal": 2.05, "tol": 0.06},
        {"name": "h", "nominal": 15.0, "tol": 1.0}, {"name": "ow", "nominal": 14.0, "tol": 0.5}],
    "let": [{"name": "H", "value": "h + 3"}],
    "window": [0, "2*pi", -30, 30],
    "drive": [0, "2*pi"],
    "pairs": [{"name": "yoke_pair", "parts": [
        {"name": "crank", "axis": {"type": "rotation", "center": ["cx", "cy"]},
         "loops": [[{"type": "arc", "name": "pin", "center": ["cx + R", "cy"], "radius": "rp",
                     "start_angle": 0, "end_angle": "2*pi"}]]},
        {"name": "yoke", "axis": {"type": "translation", "direction": [1, 0], "origin": [0, 0]},
         "loops": [{"polyline": [["-ow", "-H"], ["ow", "-H"], ["ow", "H"], ["-ow", "H"]],
                    "names": ["outer.bottom", "outer.right", "outer.top", "outer.left"]},
                   {"polyline": [["-wl", "-h"], ["-wl", "h"], ["wr", "h"], ["wr", "-h"]],
                    "names": ["slot.left", "slot.top", "slot.right", "slot.bottom"]}]}]}]}

def _result(**kw):
    from synthesis.result import SynthesisResult, SynthesisStatus
    u0, t0 = np.array([1.0, 2.0, 3.0]), np.array([0.1, 0.2, 0.1])
    base = dict(success=True, status=SynthesisStatus.CONVERGED, message="converged", nit=1,
                model="m", names=("a", "b", "c"), units="mm", initial_nominal=u0,
                initial_tol=t0, nominal=u0 + [0.0, 0.05, 0.0], tol=t0, e=0.05, history=(),
                overlaps=(), d=0.004, accuracy={"name": "fast"})
    base.update(kw)
    return SynthesisResult(**base)


FAST = ["--preset", "fast", "--executor", "serial", "--no-plots"]


def _fake_verify(final_defective):
    """A stand-in for --verify's check: the final box with ``final_defective``
    of 40 samples defective."""
    def fake(model, result, args, executor, done=None, stream=None):
        out = {} if done is None else done
        m = len(result.names)
        for which, k in (("initial", 7), ("final", final_defective)):
            out[which] = MonteCarloResult(40, 20, tuple(range(k)), {"JAM": k} if k else {},
                                          np.zeros((40, m)), args.seed)
        return out
    return fake


# -- 1. a final box that fails its Monte Carlo check --------------------------------

def test_a_failed_monte_carlo_check_of_the_final_box_is_loud_and_exits_1(tmp_path, monkeypatch,
                                                                         capsys):
    cli = sys.modules["synthesis.cli.main"]
    monkeypatch.setattr(cli, "_verify", _fake_verify(5))
    out = tmp_path / "o"
    # --verify-rounds 0: the failed check is reported, the run does not go on
    # with its samples (tests/synthesis/test_verify_rounds.py)
    assert main(["synthesize", "eccentric_cam", "--out", str(out), "--verify", "40",
                 "--verify-rounds", "0",
                 *FAST]) == 1
    err = capsys.readouterr().err
    assert "WARNING: the final box FAILED its Monte Carlo check: 5 of 40 samples" in err
    assert "must not be trusted" in err
    rep = json.loads((out / "report.json").read_text())
    # the loop's status stays: it converged on its check list
    assert rep["status"] == "CONVERGED" and rep["verification_failed"] is True
    assert "5 of 40 samples defective" in rep["verification_verdict"]
    md = (out / "report.md").read_text()
    head = md.split("## Result against the tolerances")[0]
    assert "**Warning: The final box FAILED its Monte Carlo check: 5 of 40 samples" in head
    assert "Verdict: the final box FAILED" in md


def test_a_clean_monte_carlo_check_passes(tmp_path, monkeypatch):
    cli = sys.modules["synthesis.cli.main"]
    monkeypatch.setattr(cli, "_verify", _fake_verify(0))
    out = tmp_path / "o"
    assert main(["synthesize", "eccentric_cam", "--out", str(out), "--verify", "40",
                 *FAST]) == 0
    rep = json.loads((out / "report.json").read_text())
    assert "verification_failed" not in rep and rep["status"] == "CONVERGED"
    assert "Warning" not in (out / "report.md").read_text()


def test_the_verdict_of_a_target_yield_run_allows_its_rate():
    from synthesis.cli.report import verification_verdict

    class R:
        target = {"ppm": 10000.0}
    mc = MonteCarloResult(1000, 500, (1, 2), {}, np.zeros((1000, 2)), 0)
    assert verification_verdict(R(), {"final": mc})["passed"]
    bad = MonteCarloResult(1000, 500, tuple(range(100)), {}, np.zeros((1000, 2)), 0)
    assert not verification_verdict(R(), {"final": bad})["passed"]
    assert verification_verdict(R(), None) is None


def test_the_verdict_of_a_run_that_stopped_with_defects_does_not_blame_the_check_list():
    from synthesis.cli.report import verification_verdict
    from synthesis.result import SynthesisStatus

    class R:
        target = None
        status = SynthesisStatus.INFEASIBLE
    bad = MonteCarloResult(400, 200, tuple(range(387)), {}, np.zeros((400, 2)), 0)
    v = verification_verdict(R(), {"final": bad})
    assert not v["passed"]
    assert "the run ended INFEASIBLE with defects left in its check list" in v["text"]
    assert "missed defects" not in v["text"] and "finer --preset" not in v["text"]
    R.status = SynthesisStatus.CONVERGED
    v = verification_verdict(R(), {"final": bad})
    assert "the check list missed defects the samples found" in v["text"]


# -- 2. the operating point --------------------------------------------------------

def test_the_operating_point_is_recorded_and_the_reproduction_runs(tmp_path, monkeypatch):
    model = tmp_path / "yoke.json"
    model.write_text(json.dumps(YOKE))
    out = tmp_path / "b"
    assert main(["synthesize", str(model), "--out", str(out), "--accept-start",
                 "--deviation", "0.005", "--max-iter", "1", *FAST]) in (0, 1)
    rep = json.loads((out / "report.json").read_text())
    (op,) = rep["operating_point"]
    assert op["start_source"] == "guessed" and op["q2_start"] == -18.0
    assert op["follower_unit"] == "mm" and op["driver_unit"] == "rad"
    assert op["drive"] == pytest.approx([0, 2 * np.pi]) and len(op["free_intervals"]) == 3
    assert op["window"] == pytest.approx([0, 2 * np.pi, -30, 30])
    md = (out / "report.md").read_text()
    assert "## Operating point" in md and "| yoke_pair | -18 mm | 0 rad | guessed" in md
    # the start the run used is stated in model_initial.json: the rerun needs no --accept-start
    assert json.loads((out / "model_initial.json").read_text())["q2_start"] == [-18.0]
    cmd = re.search(r"```sh\n(cspace-tol synthesize model_initial.json[^\n]*)\n", md).group(1)
    assert "--accept-start" not in cmd
    argv = cmd.split()[1:]
    argv[argv.index("--out") + 1] = str(tmp_path / "again")
    monkeypatch.chdir(out)
    assert main(argv + ["--executor", "serial", "--no-plots"]) in (0, 1)
    again = json.loads((tmp_path / "again" / "report.json").read_text())
    assert again["operating_point"][0]["start_source"] == "stated"
    assert again["operating_point"][0]["q2_start"] == -18.0
    assert again["final"] == rep["final"]


def test_the_python_reproduction_accepts_a_guessed_start():
    from synthesis.cli.report import reproduce_python
    op = [{"start_source": "guessed", "free_intervals": [[0, 1], [2, 3]]}]
    assert "accept_start=True" in reproduce_python(_result(), operating=op)
    assert "accept_start" not in reproduce_python(_result())


# -- 4. a finished run in --out is kept ------------------------------------------------

def test_rerunning_into_a_finished_run_moves_it_aside(tmp_path, capsys):
    out = tmp_path / "o"
    argv = ["synthesize", "eccentric_cam", "--out", str(out), *FAST]
    assert main(argv) == 0
    first = (out / "report.json").read_text()
    (out / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert main(argv) == 0
    assert "moved them to" in capsys.readouterr().err
    assert (out / "previous" / "report.json").read_text() == first
    assert {p.name for p in (out / "previous").iterdir()} >= {
        "report.md", "report.json", "checkpoint.json", "model.json"}
    assert (out / "notes.txt").read_text() == "mine"      # not an output: left alone
    rep = json.loads((out / "report.json").read_text())
    assert rep["previous_run"] == "previous"
    assert "moved to `previous/`" in (out / "report.md").read_text()
    assert main(argv) == 0
    assert (out / "previous-2" / "report.json").is_file()
    assert (out / "previous" / "report.json").read_text() == first
    assert not [p for p in out.iterdir() if p.name.startswith(".previous")]


def test_a_refused_rerun_moves_nothing(tmp_path):
    out = tmp_path / "o"
    assert main(["synthesize", "eccentric_cam", "--out", str(out), *FAST]) == 0
    assert main(["synthesize", "eccentric_cam", "--out", str(out), "--max-iter", "0",
                 *FAST]) == 2
    assert not (out / "previous").exists() and (out / "report.json").is_file()


# -- 5. failure labels apart -----------------------------------------------------------

def test_failure_labels_of_nearby_marks_do_not_overlap():
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    from types import SimpleNamespace

    from matplotlib.text import Annotation

    from cspace.defects import Reason, reference
    from cspace.plotting import plot_failures
    from mechanisms.models import eccentric_cam
    from synthesis.cli.plotting import separate_labels
    cs = reference(eccentric_cam(), "fast").spaces[0]
    x0, x1, y0, y1 = cs.window
    qx, qy = x0 + 0.05 * (x1 - x0), (y0 + y1) / 2
    span = max(x1 - x0, y1 - y0)
    res = [SimpleNamespace(defective=True, where=(0, qx, qy + k * 0.02 * span),
                           reasons=(Reason.DEVIATION,)) for k in (1, 0, 2)]
    ax = plot_failures(cs, res, labels=["r0", "r1", "r2"])
    separate_labels(ax)
    fig = ax.figure
    fig.canvas.draw()
    rnd = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(rnd) for t in ax.texts if isinstance(t, Annotation)]
    assert len(boxes) == 3
    for i in range(3):
        for j in range(i):
            assert not boxes[i].overlaps(boxes[j]), (boxes[i], boxes[j])


# -- 6. progress of the Monte Carlo check ----------------------------------------------

def test_the_monte_carlo_check_reports_progress_per_batch():
    from mechanisms.models import eccentric_cam
    from synthesis.cli.main import phase_progress
    from synthesis.executors import SerialExecutor
    from synthesis.verify import monte_carlo
    calls = []

    class Rec:
        def task(self, phase, done, total, defective=None):
            calls.append((phase, done, total, defective))

    m = eccentric_cam()
    monte_carlo(m, 12, accuracy="fast", executor=SerialExecutor(), progress=Rec(),
                phase="check X")
    assert calls and calls[-1][:3] == ("check X", 12, 12) and calls[-1][3] is not None
    # the command line's lines: a line per batch at most every interval, no iteration
    s = io.StringIO()
    p = phase_progress(s, interval=0.0)
    monte_carlo(m, 12, accuracy="fast", executor=SerialExecutor(), progress=p,
                phase="Monte Carlo check of the final box")
    lines = s.getvalue().splitlines()
    assert lines and lines[-1].startswith("Monte Carlo check of the final box: 12/12 tests "
                                          "(100 %), ")
    assert "defective so far" in lines[-1] and not any("iteration" in ln for ln in lines)
    # the old callable form still works
    seen = []
    monte_carlo(m, 4, accuracy="fast", executor=SerialExecutor(),
                progress=lambda d, t: seen.append((d, t)))
    assert seen[-1] == (4, 4)


# -- 7. the report.json field reference ------------------------------------------------

def _documented_fields():
    md = (ROOT / "docs" / "synthesis.md").read_text()
    sec = md.split("### report.json fields", 1)[1].split("\n## ", 1)[0].split("\n### ", 1)[0]
    return set(re.findall(r"^\| `([^`]+)` \|", sec, flags=re.M))


def _paths(d, prefix=""):
    """Every field of a report.json as documented: ``a``, ``a.b``, ``a[].b``;
    the entries of dicts keyed by parameter, box or reason collapse."""
    out = set()
    for k, v in d.items():
        p = f"{prefix}{k}"
        out.add(p)
        if k in ("changes", "changed", "shrunk", "reasons", "shift_by_name", "accuracy",
                 "guards", "overlaps", "target", "yield"):
            continue
        if k == "verification":
            for box in v.values():
                out |= _paths(box, p + ".*.")
        elif isinstance(v, dict):
            out |= _paths(v, p + ".")
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                out |= _paths(item, p + "[].")
    return out


def test_every_field_of_report_json_is_documented(tmp_path, monkeypatch):
    cli = sys.modules["synthesis.cli.main"]
    monkeypatch.setattr(cli, "_verify", _fake_verify(1))
    out = tmp_path / "o"
    main(["synthesize", "eccentric_cam", "--out", str(out), "--verify", "40",
          "--verify-rounds", "0", *FAST])
    rep = json.loads((out / "report.json").read_text())
    doc = _documented_fields()
    missing = sorted(p for p in _paths(rep) if p not in doc)
    assert not missing, f"report.json fields not in docs/synthesis.md: {missing}"


def test_e_over_tolerance_is_against_the_largest_length_tolerance():
    r = _result(param_units=("mm", "rad", "mm"), initial_tol=np.array([0.1, 5.0, 0.2]))
    assert r.to_dict()["e_over_tolerance"] == pytest.approx(r.e / 0.2)


# -- 3. a stop during the Monte Carlo check ----------------------------------------------

@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals as on Linux")
def test_a_stop_during_the_monte_carlo_check_writes_an_interrupted_report(tmp_path):
    from synthesis.checkpoint import read_checkpoint

    from .proc_util import interrupt, start_synthesize, wait_for
    out = tmp_path / "o"
    p = start_synthesize("eccentric_cam", out, "--verify", "200000")
    ck = out / "checkpoint.json"

    def converged():
        try:
            return read_checkpoint(ck)[0].status.name == "CONVERGED"
        except Exception:   # not there yet, or being replaced
            return False
    try:
        wait_for(lambda: p.poll() is not None or converged(), 300)
        assert p.poll() is None, "the run ended before its Monte Carlo check"
        time.sleep(2.0)             # inside the check of the initial box
        err = interrupt(p)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, err
    assert "Traceback" not in err and "during the Monte Carlo check" in err
    rep = json.loads((out / "report.json").read_text())
    assert rep["status"] == "INTERRUPTED" and rep["success"] is False
    assert rep["interrupted"]["after_synthesis"] == "CONVERGED"
    md = (out / "report.md").read_text()
    assert "**Status: INTERRUPTED**" in md and "--resume" in md
    # resume finishes the check (a smaller one) and writes the complete report
    assert main(["synthesize", "eccentric_cam", "--out", str(out), "--resume", "--verify",
                 "20", "--executor", "serial", "--no-plots"]) == 0
    rep = json.loads((out / "report.json").read_text())
    assert rep["status"] == "CONVERGED" and "verification_failed" not in rep


def test_the_command_line_prints_the_librarys_warnings_without_source_lines(tmp_path):
    import warnings

    import importlib
    cli = importlib.import_module("synthesis.cli.main")
    from cspace.io import UnitWarning
    from mechanisms.analysis import OperatingPointWarning
    before = warnings.formatwarning
    seen = {}

    def func(args):
        seen["format"] = warnings.formatwarning
        return 0

    args = cli.build_parser().parse_args(["yield", "geneva", "--out", str(tmp_path)])
    args.func = func
    orig = cli.build_parser
    try:
        cli.build_parser = lambda: type("P", (), {"parse_args": lambda self, a: args})()
        assert cli.main([]) == 0
    finally:
        cli.build_parser = orig
    # during a command the library's warnings print as one line, no source
    fmt = seen["format"]
    for cat in (UnitWarning, OperatingPointWarning):
        assert fmt("units: length unit 'furlong' is unknown", cat, "/x/y.py", 57,
                   "return f(d)") == "warning: units: length unit 'furlong' is unknown\n"
    # others keep Python's format; and Python's comes back after the command
    assert fmt("x", RuntimeWarning, "/x/y.py", 57, "line").startswith(
        "/x/y.py:57: RuntimeWarning: x")
    assert warnings.formatwarning is before
