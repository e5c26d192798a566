"""The output folder of a synthesis run: the command that repeats it, the
Markdown summary and the files written (without the figures)."""

import dataclasses
import json

import numpy as np
import pytest

from cspace.io import load_pair
from mechanisms.models import reciprocating_cam
from mechanisms.userfile import load_model
from synthesis.cli.report import (_defect_text, _required_by, deviation_scales,
                                  markdown_report, reproduce_command, write_outputs)
from synthesis.result import IterationRecord, SynthesisResult, SynthesisStatus
from synthesis.verify import MonteCarloResult

from ...cspace.batch.yoke import yoke

NAMES = ("crank", "pin_r", "half_width")
U0 = np.array([20.0, 5.0, 5.03])
T0 = np.array([0.02, 0.02, 0.04])


def _record(i, shift, defective, reasons, shrinks=(), required=(), total=1.5):
    return IterationRecord(i, U0.copy(), T0.copy(), {"checklist": 8 * i}, 3 - i,
                           tuple(defective), dict(reasons), np.array(shift, dtype=float),
                           tuple(shrinks), False, 5 * i, {"total": total}, tuple(required))


def _result(**kw):
    req = ({"parameter": "half_width", "change": "shift", "vector": 3, "mirror": False,
            "pair": 0, "kind": ["jam"], "q1": 0.5, "q2": 20.0, "message": "jam"},
           {"parameter": "pin_r", "change": "cut", "vector": 6, "mirror": True, "pair": 0,
            "kind": ["deviation"], "q1": None, "margin": "deviation", "both_sides": True})
    cut = {"parameter": "pin_r", "old": 0.02, "new": 0.01, "vector": 6, "reason": "spread"}
    hist = (_record(1, [0.0, 0.0, 0.01], [3, 6], {"JAM": 1, "DEVIATION": 2}, (cut,), req, 2.0),
            _record(2, [0.0, 0.0, 0.0], [], {}, total=2.4))
    base = dict(success=True, status=SynthesisStatus.CONVERGED,
                message=SynthesisStatus.CONVERGED.value, nit=2, model="yoke", names=NAMES,
                units="mm", initial_nominal=U0, initial_tol=T0,
                nominal=U0 + [0.0, 0.0, 0.01], tol=T0 * [1.0, 0.5, 1.0], e=0.01,
                overlaps=({"pair": 0},), d=0.004, accuracy={"name": "fast"}, history=hist)
    base.update(kw)
    return SynthesisResult(**base)


# ------------------------------------------------------------------ reproduce
def test_reproduce_command_of_a_default_run():
    cmd = reproduce_command(_result())
    assert cmd == ("cspace-tol synthesize model_initial.json --out again --preset fast "
                   "--patience 4 --no-two-sided --deviation 0.004 --removal greedy")


def test_reproduce_command_follows_the_settings():
    r = _result(accuracy={"name": "custom"}, two_sided=True, removal="lp", patience=2,
                status=SynthesisStatus.MAX_ITER, nit=7, d=0.1 + 0.2)
    mc = MonteCarloResult(200, 100, (), {}, np.zeros((200, 3)), 42)
    cmd = reproduce_command(r, model_file="m.json", out="o2", verification={"final": mc})
    # no preset for a custom accuracy; d to the last bit; the cap that stopped it
    assert cmd == ("cspace-tol synthesize m.json --out o2 --patience 2 "
                   f"--deviation {0.1 + 0.2!r} --max-iter 7 --verify 200 --seed 42")
    assert "--preset" not in cmd and "--no-two-sided" not in cmd and "--removal" not in cmd


# ------------------------------------------------------------------ report.md
def test_markdown_report_of_a_converged_run():
    text = markdown_report(_result(), files=["pair.json", "report.md"],
                           command="cspace-tol synthesize yoke --out o")
    lines = text.splitlines()
    assert lines[0] == "# Tolerance synthesis of yoke"
    assert ("**Status: CONVERGED** after 2 iteration(s). Converged: no defective vector in "
            "the check list.") in lines
    assert "Defective check-list vectors per iteration: 2, 0; 15 defect tests in 4 s." in lines
    # e against the largest (0.04) and the smallest (0.02) initial tolerance
    assert ("- e = max |u0' - u0| = 0.01 mm: 0.25 x the largest initial tolerance (0.04 mm), "
            "0.50 x the smallest (0.02 mm).") in lines
    assert "- 1 of 3 nominal dimensions shifted, 1 tolerance(s) cut." in lines
    assert "- Smallest tolerance kept: 50 % of its initial value (pin_r)." in lines
    # every parameter cut that far is named (it named one of several)
    tied = markdown_report(_result(tol=T0 * [0.5, 0.5, 0.75]), files=[], command="c")
    assert "- Smallest tolerance kept: 50 % of its initial value (crank, pin_r)." in \
        tied.splitlines()
    # the changed dimensions only, with the defect that required each change
    rows = [ln for ln in lines if ln.startswith("| pin_r |") or ln.startswith("| half_width |")
            or ln.startswith("| crank |")]
    assert len(rows) == 2 and not any(r.startswith("| crank |") for r in rows)
    hw = next(r for r in rows if r.startswith("| half_width |"))
    assert "| 5.03 | 5.04 | +0.01 | 0.04 | 0.04 |" in hw
    assert "shift in iteration 1: vector 3 (pair 0, jam, q1 = 0.5)" in hw
    pr = next(r for r in rows if r.startswith("| pin_r |"))
    assert ("cut in iteration 1: vector 6 (at its mirror, pair 0, deviation, linearised "
            "deviation margin, defective at both sides: the vector and its mirror)") in pr
    # per iteration, reasons by count
    assert "| 1 | 8 | 2 | deviation 2, jam 1 | - | 2 | 1 | 1 | 5 | 2.0 |" in lines
    assert "| 2 | 16 | 0 | - | - | 1 | 0 | 0 | 10 | 2.4 |" in lines
    assert "## Zone overlaps are not defects" in lines
    assert any("The final design has 1 zone overlap(s) and 0 defective vector(s)." in ln
               for ln in lines)
    assert "cspace-tol synthesize yoke --out o" in lines
    assert text.endswith("## Files\n\n- `pair.json`\n- `report.md`\n")
    assert "## Monte Carlo check" not in lines


def test_markdown_report_of_an_interrupted_run_without_changes():
    r = _result(status=SynthesisStatus.INTERRUPTED, message=SynthesisStatus.INTERRUPTED.value,
                success=False, nominal=U0, tol=T0, e=0.0,
                history=(_record(1, [0, 0, 0], [1], {"JAM": 1}),),
                interrupted={"iteration": 2, "tests": 10, "defective": 1})
    text = markdown_report(r)
    assert "**Status: INTERRUPTED** after 2 iteration(s). Interrupted: stopped" in text
    assert "The design below is the one iteration 2 was testing." in text
    assert "No dimension or tolerance changed." in text
    assert "- 0 of 3 nominal dimensions shifted, 0 tolerance(s) cut." in text
    assert "Zone overlaps are not defects" not in text
    assert "## Files" not in text


def test_markdown_report_with_a_monte_carlo_check():
    init = MonteCarloResult(400, 200, (1, 2, 3, 250), {"JAM": 4}, np.zeros((400, 3)), 9)
    final = MonteCarloResult(400, 200, (), {}, np.zeros((400, 3)), 9)
    text = markdown_report(_result(), verification={"initial": init, "final": final})
    assert "| initial | 400 | 200 | 4 | 1.00 % | 9 |" in text
    assert "| final | 400 | 200 | 0 | 0.00 % | 9 |" in text
    assert "--verify 400 --seed 9" in text
    assert "Where the first defective samples" not in text
    # a failed final box says where its first defective samples fail
    bad = MonteCarloResult(400, 200, (7, 301), {"TOPOLOGY": 2}, np.zeros((400, 3)), 9, 0,
                           ("p: contact sequence changed at q1 = 3.59 (...)",
                            "p: output deviates by 0.05 > d = 0.025"))
    text = markdown_report(_result(), verification={"initial": init, "final": bad})
    assert "- sample 7: p: contact sequence changed at q1 = 3.59 (...)" in text
    assert "- sample 301: p: output deviates by 0.05 > d = 0.025" in text
    assert bad.to_dict()["first_defective_messages"] == list(bad.messages)


def test_without_tolerances_no_ratio_is_given():
    r = _result(initial_tol=np.zeros(3), tol=np.zeros(3))
    text = markdown_report(r)
    assert "- e = max" not in text and "Smallest tolerance kept" not in text


# ------------------------------------------------------------------ provenance
def test_defect_text():
    r = {"vector": 4, "mirror": True, "pair": 1, "kind": ["jam", "topology"], "q1": 1.23456,
         "margin": "channel", "both_sides": True, "iteration": 1}
    assert _defect_text(r, 2) == ("vector 4 of iteration 1 (at its mirror, pair 1, jam & "
                                  "topology, q1 = 1.235, linearised channel margin, defective "
                                  "at both sides: the vector and its mirror)")
    # the iteration's own check list is not named; nothing known, nothing said
    assert _defect_text(dict(r, iteration=2), 2).startswith("vector 4 (at its mirror")
    assert _defect_text({"vector": 0}) == "vector 0"


def test_required_by_for_records_without_provenance():
    """Records written before each change named its defect: the iterations
    whose defects shifted a parameter, and the vector each cut cured."""
    cut = {"parameter": "pin_r", "old": 0.02, "new": 0.01, "vector": 6, "reason": "spread"}
    hist = (_record(1, [0.0, 0.0, 0.01], [3, 6], {"JAM": 2}, (cut,)),
            _record(2, [0.0, 0.0, 0.005], [2], {"JAM": 1}),
            _record(3, [0.0, 0.0, 0.0], [], {}))
    why = _required_by(_result(history=hist))
    assert why == {"half_width": "shifts in iterations 1, 2 (2, 1 defective)",
                   "pin_r": "cut in iteration 1 for check-list vector 6 (spread)"}


# ------------------------------------------------------------------ the folder
def test_write_outputs_of_a_python_model(tmp_path):
    """A model made in Python: pairs and reports, no model files (its geometry is code)."""
    m = yoke()
    r = _result()
    out = tmp_path / "o"
    paths = write_outputs(r, m, out, plots=False, command="cmd")
    names = [p.name for p in paths]
    assert names == ["pair.json", "pair_initial.json", "report.md", "report.json"]
    assert all(p.parent == out and p.is_file() for p in paths)
    # the final and the initial design
    final = load_pair(out / "pair.json")
    initial = load_pair(out / "pair_initial.json")
    face = final.follower.loops[1].segments[3]
    assert face.start[0] == pytest.approx(5.04) and \
        initial.follower.loops[1].segments[3].start[0] == pytest.approx(5.03)
    rep = json.loads((out / "report.json").read_text())
    expect = r.to_dict()
    assert {k: rep[k] for k in expect} == json.loads(json.dumps(expect))
    # only the files the folder holds (no checkpoint.json, no model files)
    assert rep["files"] == ["pair.json", "pair_initial.json", "report.json", "report.md"]
    assert sorted(rep["files"]) == sorted(p.name for p in out.iterdir())
    L = m.build().char_length
    assert rep["units_note"] == (f"lengths in mm, angles in rad (each parameter's unit: "
                                 f"parameter_units); d in the C-space metric (rad, or slide / "
                                 f"characteristic length; L = {L:.6g} mm for 'yoke')")
    assert "verification" not in rep
    md = (out / "report.md").read_text()
    assert md == markdown_report(r, files=rep["files"], command="cmd",
                                 scales=deviation_scales(m))
    # d in the follower's own unit: a slide of d L
    assert deviation_scales(m) == (("yoke", "mm", L),)
    assert f"for 'yoke': a slide of {r.d * L:.4g} mm (d times the pair's characteristic " \
           f"length L = {L:.4g} mm)" in md
    # no model_initial.json to run the command line on: the Python call instead
    assert "model_initial.json" not in md and "cspace-tol synthesize" not in md
    assert "checkpoint.json" not in md
    assert ("```python\nfrom synthesis import synthesize\n"
            f"result = synthesize(model, 'fast', d={r.d!r}, patience={r.patience}, "
            "two_sided=False, removal='greedy')\n```") in md
    assert "The command that ran:\n\n```sh\ncmd\n```" in md


def test_the_python_reproduction_of_a_python_model_runs(tmp_path):
    """The Reproduce section's Python code, run on the model, repeats the
    settings of the run it describes (and its Monte Carlo check)."""
    from synthesis.cli.report import reproduce_python
    r = dataclasses.replace(_result(), status=SynthesisStatus.MAX_ITER)
    mc = MonteCarloResult(10, 5, (2,), {"JAM": 1}, np.zeros((10, 3)), 7)
    code = reproduce_python(r, verification={"initial": mc, "final": mc})
    assert f"synthesize(model, 'fast', d={r.d!r}, patience={r.patience}, two_sided=False, " \
           f"removal='greedy', max_iter={r.nit})" in code
    assert "check_final = monte_carlo(final, 10, seed=7, accuracy='fast', d=result.d, " \
           "intent=model)" in code
    # run with stand-ins that check the arguments against the real signatures
    import inspect

    import synthesis
    calls = []

    def standin(name, ret):
        def f(*a, **k):
            inspect.signature(getattr(synthesis, name)).bind(*a, **k)
            calls.append((name, a, k))
            return ret
        return f
    head, body = code.split("\n", 1)
    assert head == "from synthesis import monte_carlo, synthesize"
    exec(body, {"synthesize": standin("synthesize", r), "model": yoke(),
                "monte_carlo": standin("monte_carlo", mc)})
    (_, a, k), *checks = calls
    assert a[1] == "fast" and k == {"d": r.d, "patience": r.patience, "two_sided": False,
                                    "removal": "greedy", "max_iter": r.nit}
    assert [c[0] for c in checks] == ["monte_carlo"] * 2


def test_the_checkpoint_is_listed_when_the_folder_holds_it(tmp_path):
    (tmp_path / "checkpoint.json").write_text("{}")
    write_outputs(_result(), yoke(), tmp_path, plots=False)
    rep = json.loads((tmp_path / "report.json").read_text())
    assert rep["files"][-1] == "checkpoint.json"
    assert sorted(rep["files"]) == sorted(p.name for p in tmp_path.iterdir())
    assert "- `checkpoint.json`" in (tmp_path / "report.md").read_text()


def test_a_report_of_lengths_and_angles_gives_each_its_unit():
    """With an angle among the parameters: e over the lengths, the angles'
    largest shift apart, and a unit column in the table of changes."""
    r = _result(param_units=("mm", "mm", "rad"), e=0.0, e_angle=0.01)
    md = markdown_report(r)
    assert "- e = max |u0' - u0| (over the lengths) = 0 mm" in md
    assert "- The largest shift of an angle: 0.01 rad (0.573 deg)." in md
    assert "| parameter | unit | initial | final | delta | tolerance before | " in md
    assert f"| {NAMES[2]} | rad | " in md and f"| {NAMES[1]} | mm | " in md
    # lengths only: the units in the header, as before
    plain = markdown_report(_result())
    assert "| parameter | initial [mm] |" in plain and "(over the lengths)" not in plain


def test_the_deviation_threshold_of_a_rotating_follower_is_an_angle():
    from mechanisms.models import geneva
    scales = deviation_scales(geneva())
    assert scales == (("geneva", "rad", None),)
    md = markdown_report(_result(), scales=scales)
    assert f"for 'geneva': an output angle of {_result().d:.4g} rad (" in md


def test_write_outputs_of_a_built_in_model_writes_its_model_files(tmp_path):
    m = reciprocating_cam()
    final = m.nominal + np.where(np.arange(m.n) == 0, m.tol, 0.0)
    cut = m.tol * np.where(np.arange(m.n) == 1, 0.5, 1.0)
    r = dataclasses.replace(_result(), model=m.name, names=m.names, units=m.units,
                            initial_nominal=m.nominal, initial_tol=m.tol, nominal=final,
                            tol=cut, history=())
    mc = MonteCarloResult(10, 5, (2,), {"JAM": 1}, np.zeros((10, m.n)), 1)
    paths = write_outputs(r, m, tmp_path, plots=False, verification={"final": mc})
    names = {p.name for p in paths}
    assert {"model.json", "model_initial.json"} <= names
    again = load_model(tmp_path / "model.json")
    np.testing.assert_array_equal(again.nominal, final)
    np.testing.assert_array_equal(again.tol, cut)
    first = load_model(tmp_path / "model_initial.json")
    np.testing.assert_array_equal(first.nominal, m.nominal)
    np.testing.assert_array_equal(first.tol, m.tol)
    rep = json.loads((tmp_path / "report.json").read_text())
    assert rep["verification"] == {"final": json.loads(json.dumps(mc.to_dict()))}
    assert "model.json" in rep["files"]
    assert sorted(rep["files"]) == sorted(p.name for p in tmp_path.iterdir())
    # the command line repeats the run from the model file written beside it
    md = (tmp_path / "report.md").read_text()
    assert "cspace-tol synthesize model_initial.json --out again" in md
    assert "```python" not in md


def test_failure_retests_on_an_executor_are_the_full_tests(tmp_path, monkeypatch):
    """failures.png's re-tests as tasks of an executor: the full test's
    verdicts and places, in order, at most MAX_FAILURE_MARKS; _failure_plots
    takes them instead of testing again."""
    import synthesis.cli.report as report
    from cspace.defects import is_defective, reference
    from synthesis.executors import SerialExecutor
    m = yoke()
    r = _result(d=reference(m, "fast").d)
    removed = [np.array([20.0, 5.04, 5.03]), np.array([20.02, 5.0, 5.03]),
               np.array([20.0, 5.0, 5.03])]
    got = report.failure_retests(r, m, removed, "fast", SerialExecutor())
    ref = reference(m, "fast", r.d)
    want = [is_defective(m, u, ref=ref) for u in removed]
    assert [(g.defective, g.where) for g in got] == [(w.defective, w.where) for w in want]
    assert got[0].defective and not got[2].defective
    monkeypatch.setattr(report, "MAX_FAILURE_MARKS", 2)
    assert len(report.failure_retests(r, m, removed, "fast", SerialExecutor())) == 2
    # given, they are used as they are: nothing is tested again
    monkeypatch.setattr("cspace.defects.is_defective",
                        lambda *a, **k: pytest.fail("tested again"))
    spaces = reference(m, "fast").spaces
    r = dataclasses.replace(r, spaces_initial=spaces)
    paths, marked = report._failure_plots(r, m, tmp_path, [""], removed[:2], "fast", got[:2])
    assert [p.name for p in paths] == ["failures.png"] and paths[0].is_file()
    assert marked == list(got[:2])
    # report.md lists the marks with why and where each fails
    text = "\n".join(report._failure_lines(r, marked))
    assert "## Where the marked defects fail" in text and "| r0 |" in text and "| r1 |" in text
