"""Synthesis to a target yield (synthesis.target)."""

import json

import numpy as np
import pytest

from cspace.errors import InputError
from synthesis import SynthesisStatus, synthesize, yield_estimate
from synthesis.executors import SerialExecutor
from synthesis.target import YieldTarget, as_target

from ..cspace.batch.yoke import yoke


@pytest.mark.parametrize("text, want", [("0.9999", 0.9999), ("99.99%", 0.9999),
                                        ("100ppm", 0.9999), (" 250 ppm", 0.99975)])
def test_a_target_is_a_yield_a_percentage_or_a_failure_rate(text, want):
    assert YieldTarget.parse(text).target == pytest.approx(want, rel=0, abs=1e-15)
    assert as_target(text).failure == pytest.approx(1 - want, abs=1e-15)


@pytest.mark.parametrize("bad", ["1.5", "0", "100", "lots", "-5ppm", "120%"])
def test_a_bad_target_is_an_input_error_that_says_what_is_allowed(bad):
    with pytest.raises(InputError, match="target yield must be"):
        YieldTarget.parse(bad)


@pytest.mark.parametrize("kw", [{"samples": 10}, {"method": "exact"}, {"cp": 0.0},
                                {"seed": -1}])
def test_bad_estimate_settings_are_input_errors(kw):
    with pytest.raises(InputError):
        YieldTarget(0.99, **kw)


def test_a_target_survives_its_dict():
    t = YieldTarget(0.999, samples=700, method="is", cp=1.33, seed=4)
    assert YieldTarget.from_dict(t.to_dict()) == t


@pytest.fixture(scope="module")
def runs():
    """The pin in a slot (interference 0.01 at the worst corner, about 700 ppm
    at Cp 1) synthesized worst case and to a 99 % yield."""
    m = yoke()
    ex = SerialExecutor()
    worst = synthesize(m, "fast", executor=ex, max_iter=6)
    target = YieldTarget(0.99, samples=600, seed=3)
    aimed = synthesize(m, "fast", executor=ex, max_iter=6, target_yield=target)
    return m, worst, aimed, target


def test_the_target_run_stops_with_the_improbable_defects_left(runs):
    m, worst, aimed, target = runs
    assert worst.status is SynthesisStatus.CONVERGED and worst.e > 0
    assert aimed.status is SynthesisStatus.TARGET_YIELD and aimed.success
    # nothing changed: the interference corner is improbable at Cp 1
    assert aimed.nit == 1 and aimed.e == 0.0
    np.testing.assert_array_equal(aimed.tol, m.tol)
    assert aimed.history[-1].n_defects > 0          # the worst case is not clean
    ye = aimed.yield_estimate
    assert ye["met"] and ye["ci"][1] <= target.failure
    assert "worst case" in aimed.message and "target yield reached" in aimed.message


def test_an_independent_seeded_run_confirms_the_estimate(runs):
    m, _, aimed, target = runs
    final = m.with_nominal(aimed.nominal).with_tolerances(aimed.tol)
    check = yield_estimate(final, 2000, seed=11, accuracy="fast", executor=SerialExecutor(),
                           intent=m, search=False)
    lo, hi = check.ci
    assert hi <= target.failure
    ye = aimed.yield_estimate
    # the two estimates' intervals overlap
    assert lo <= ye["ci"][1] and ye["ci"][0] <= hi


def test_a_target_plain_monte_carlo_cannot_confirm_runs_to_the_worst_case(runs):
    """0.99999 needs a 95 % upper bound under 10 ppm: 600 plain samples cannot
    show it, so the run removes every worst-case defect and says the target
    is not met."""
    m = runs[0]
    r = synthesize(m, "fast", executor=SerialExecutor(), max_iter=6,
                   target_yield=YieldTarget(0.99999, samples=600, seed=3))
    assert r.status is SynthesisStatus.CONVERGED
    assert r.history[-1].n_defects == 0
    assert r.yield_estimate is not None and not r.yield_estimate["met"]


def test_the_report_states_the_target_the_estimate_and_the_worst_case(runs, tmp_path):
    from synthesis.cli.report import markdown_report
    _, _, aimed, _ = runs
    text = markdown_report(aimed)
    assert "## Target yield" in text and "Worst case:" in text and "ppm" in text
    d = aimed.to_dict()
    assert d["status"] == "TARGET_YIELD" and d["yield"]["met"]
    assert d["worst_case"]["defective_left"] > 0 and d["target"]["target"] == 0.99
    json.dumps(d)


def test_a_resumed_run_keeps_its_target_and_refuses_another(runs):
    from synthesis.result import SynthesisState
    m = runs[0]
    target = YieldTarget(0.99999, samples=300, seed=3)      # not met: the run goes on
    states = []
    first = synthesize(m, "fast", executor=SerialExecutor(), max_iter=1, target_yield=target,
                       on_iteration=states.append)
    assert first.status is SynthesisStatus.MAX_ITER
    st = SynthesisState.from_dict(json.loads(json.dumps(states[-1].to_dict())))
    assert st.target == target.to_dict()
    with pytest.raises(InputError, match="target yield"):
        synthesize(m, "fast", executor=SerialExecutor(), max_iter=6, state=st,
                   target_yield=YieldTarget(0.999))
    r = synthesize(m, "fast", executor=SerialExecutor(), max_iter=6, state=st)
    assert r.target == target.to_dict() and r.status is SynthesisStatus.CONVERGED
    assert [h.yield_estimate is not None for h in r.history] == [True] * r.nit


def test_the_command_line_runs_to_a_target(tmp_path):
    """``--target-yield 90%`` on the cam: its check list's defects are improbable
    at Cp 1, so the run stops at once with them left and says so."""
    from synthesis.cli import main
    out = tmp_path / "out"
    code = main(["synthesize", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--executor", "serial", "--no-plots", "--target-yield", "90%",
                 "--yield-samples", "300", "--seed", "3"])
    rep = json.loads((out / "report.json").read_text())
    assert code == 0 and rep["status"] == "TARGET_YIELD" and rep["success"]
    assert rep["target"]["ppm"] == pytest.approx(1e5)
    assert rep["worst_case"]["defective_left"] > 0 and rep["yield"]["met"]
    assert "## Target yield" in (out / "report.md").read_text()


def test_estimate_settings_without_a_target_are_refused(tmp_path):
    from synthesis.cli import main
    assert main(["synthesize", "reciprocating_cam", "--out", str(tmp_path / "o"),
                 "--cp", "1.33"]) == 2


def test_ppm_reads_as_whole_numbers_from_ten_up():
    from synthesis.target import ppm_text
    assert ppm_text(20000.00000000001) == "20000" and ppm_text(9180.2) == "9180"
    assert ppm_text(1.2345) == "1.23" and ppm_text(0.0) == "0"
