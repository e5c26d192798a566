"""Guard rails of synthesis (issue 22, "Cost and guard rails"): fixed
parameters are never shifted, hard tolerances never cut, no cut goes below
min_keep, costs pick the cheaper axis, a defect only a forbidden change could
remove ends the run INFEASIBLE (never CONVERGED), and a converged run with
deep cuts warns."""

import json

import numpy as np
import pytest

from cspace.errors import FileFormatError, InputError, ParameterError
from mechanisms.models import Parameter, reciprocating_cam
from mechanisms.userfile import load_model, save_model
from synthesis import synthesize
from synthesis.checkpoint import checkpoint_text
from synthesis.cli import main
from synthesis.executors import SerialExecutor
from synthesis.guards import DEFAULT_MIN_KEEP, Guards
from synthesis.loop import _result, deep_cuts
from synthesis.removal import Action, Transition, plan_removal
from synthesis.result import SynthesisState, SynthesisStatus


class _M:
    """A stand-in model: names and parameters only."""

    def __init__(self, n, **kw):
        self.names = tuple(f"u{i}" for i in range(n))
        self.parameters = tuple(Parameter(nm, 0.0, 1.0, **kw.get(nm, {})) for nm in self.names)


def _tr(u_w, lam=0.5, index=0):
    u_w = np.asarray(u_w, dtype=float)
    return Transition(index, u_w, lam * u_w, (lam + 0.01) * u_w, (lam, lam + 0.01), 3)


def test_a_fixed_axis_is_never_shifted():
    u0, tol = np.zeros(2), np.ones(2)
    tr = _tr([1.0, 1.0], 0.8)          # both axes cost the same: axis 0 by default
    free = plan_removal(u0, tol, [tr])
    assert free.delta[0] != 0 and free.delta[1] == 0
    g = Guards.of(_M(2), fixed=["u0"])
    p = plan_removal(u0, tol, [tr], guards=g)
    assert p.delta[0] == 0 and p.delta[1] != 0


def test_shift_cost_picks_the_cheaper_axis():
    u0, tol = np.zeros(2), np.ones(2)
    tr = _tr([1.0, 1.0], 0.6)          # |d| = 0.4 on both axes
    g = Guards.of(_M(2), shift_cost={"u0": 3.0})
    p = plan_removal(u0, tol, [tr], guards=g)
    assert p.delta[0] == 0 and p.delta[1] == pytest.approx(-0.4)


def test_cuts_respect_hard_floor_and_cost():
    u0, tol = np.zeros(2), np.ones(2)
    tr = _tr([1.0, 1.0], 0.6)
    # every axis fixed: the vector conflicts and is cut, cheapest relative cut
    g = Guards.of(_M(2), fixed=["u0", "u1"], min_keep=0.0)
    p = plan_removal(u0, tol, [tr], guards=g)
    assert [s.axis for s in p.shrinks] == [0] and p.shrinks[0].new == pytest.approx(0.6)
    g = Guards.of(_M(2), fixed=["u0", "u1"], hard=["u0"], min_keep=0.0)
    p = plan_removal(u0, tol, [tr], guards=g)
    assert [s.axis for s in p.shrinks] == [1]
    g = Guards.of(_M(2), fixed=["u0", "u1"], cut_cost={"u0": 2.0}, min_keep=0.0)
    assert [s.axis for s in plan_removal(u0, tol, [tr], guards=g).shrinks] == [1]
    # the floor: a cut to 0.6 of the tolerance is below min_keep 0.7 on both axes
    g = Guards.of(_M(2), fixed=["u0", "u1"], min_keep=0.7)
    p = plan_removal(u0, tol, [tr], guards=g)
    assert p.shrinks == () and len(p.infeasible) == 1
    assert set(p.infeasible[0]["parameters"]) == {"u0", "u1"}
    assert "fixed" in p.infeasible[0]["parameters"]["u0"]
    assert "min_keep 0.7" in p.infeasible[0]["parameters"]["u0"]
    # the floor is a fraction of the *initial* tolerance
    p = plan_removal(u0, tol, [tr], guards=g, initial_tol=np.array([0.8, 2.0]))
    assert [s.axis for s in p.shrinks] == [0] and p.infeasible == ()


def test_a_returning_vector_on_a_hard_axis_gets_a_single_allowed_cut():
    u0, tol = np.zeros(3), np.ones(3)
    tr = _tr([1.0, 1.0, 1.0], 0.6)
    spread = plan_removal(u0, tol, [tr], returning=[0])
    assert sorted(s.axis for s in spread.shrinks) == [0, 1, 2]
    g = Guards.of(_M(3), hard=["u1"], min_keep=0.0)
    p = plan_removal(u0, tol, [tr], returning=[0], guards=g)
    assert [s.axis for s in p.shrinks] == [0]
    assert p.placements[0].action is Action.CONFLICT


def test_guards_validate_and_round_trip():
    m = _M(3, u2={"fixed": True, "min_keep": 0.5, "cut_cost": 2.0})
    g = Guards.of(m, hard=["u0"], shift_cost={"u1": 4.0})
    assert g.fixed.tolist() == [False, False, True] and g.hard.tolist() == [True, False, False]
    assert g.min_keep.tolist() == [DEFAULT_MIN_KEEP, DEFAULT_MIN_KEEP, 0.5]
    assert g.shift_cost.tolist() == [1.0, 4.0, 1.0] and g.cut_cost.tolist() == [1.0, 1.0, 2.0]
    assert Guards.from_dict(json.loads(json.dumps(g.to_dict())), m.names).same_as(g)
    with pytest.raises(InputError, match="'nope' is not a parameter"):
        Guards.of(m, fixed=["nope"])
    with pytest.raises(InputError, match="min_keep must be a fraction"):
        Guards.of(m, min_keep=1.5)
    with pytest.raises(InputError, match="shift_cost of 'u0' must be a finite number > 0"):
        Guards.of(m, shift_cost={"u0": 0})
    for bad in ({"fixed": 1}, {"shift_cost": -1.0}, {"min_keep": 2.0}, {"cut_cost": float("nan")}):
        with pytest.raises(ParameterError):
            Parameter("a", 0.0, 1.0, **bad)


def test_model_files_keep_the_guard_keys(tmp_path):
    m = reciprocating_cam()
    ps = tuple(Parameter(p.name, p.nominal, p.tol, p.description, fixed=p.name == "f0",
                         hard=p.name == "tip_r", cut_cost=3.0 if p.name == "f1" else 1.0,
                         min_keep=0.6 if p.name == "f2" else None) for p in m.parameters)
    import dataclasses
    m2 = dataclasses.replace(m, parameters=ps)
    save_model(m2, tmp_path / "m.json")
    doc = json.loads((tmp_path / "m.json").read_text())
    entry = {e["name"]: e for e in doc["parameters"]}
    assert entry["f0"]["fixed"] is True and entry["tip_r"]["hard"] is True
    assert entry["f1"]["cut_cost"] == 3.0 and entry["f2"]["min_keep"] == 0.6
    assert "fixed" not in entry["f1"]
    back = load_model(tmp_path / "m.json")
    g = Guards.of(back)
    assert g.same_as(Guards.of(m2))
    entry["f0"]["fixed"] = "yes"
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    with pytest.raises(FileFormatError, match="fixed must be true or false"):
        load_model(tmp_path / "bad.json")


@pytest.fixture(scope="module")
def cam_free():
    return synthesize(reciprocating_cam(), "fast", executor=SerialExecutor(), max_iter=8)


def test_synthesis_never_shifts_a_fixed_parameter(cam_free):
    m = reciprocating_cam()
    moved = [nm for nm, c in cam_free.changes().items() if c["delta"] != 0]
    assert moved, "the unguarded run shifts something"
    g = Guards.of(m, fixed=moved[:1])
    r = synthesize(m, "fast", executor=SerialExecutor(), max_iter=8, guards=g)
    assert r.changes()[moved[0]]["delta"] == 0
    assert r.guards["fixed"] == moved[:1]
    assert r.to_dict()["guards"]["fixed"] == moved[:1]


def test_a_defect_no_allowed_change_removes_is_infeasible(tmp_path, capsys):
    m = reciprocating_cam()
    g = Guards.of(m, fixed=m.names, min_keep=0.9)
    r = synthesize(m, "fast", executor=SerialExecutor(), max_iter=8, guards=g)
    assert r.status is SynthesisStatus.INFEASIBLE and not r.success
    assert "guard rails forbid" in r.message and "check-list vector" in r.message
    assert "channel closes" in r.message and "min_keep 0.9" in r.message
    assert np.array_equal(r.nominal, m.nominal) and np.array_equal(r.tol, m.tol)
    # the command line: exit 1, the report says why
    out = tmp_path / "o"
    code = main(["synthesize", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--executor", "serial", "--no-plots", "--min-keep", "0.9", "--fixed",
                 ",".join(m.names)])
    assert code == 1
    rep = json.loads((out / "report.json").read_text())
    assert rep["status"] == "INFEASIBLE" and rep["guards"]["min_keep"] == [0.9] * m.n
    assert "INFEASIBLE" in (out / "report.md").read_text()
    # a resume that asks for other guards is refused
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--min-keep", "0.5", "--no-plots"]) == 2
    assert "guards" in capsys.readouterr().err


def test_cli_guard_flags_are_checked(tmp_path, capsys):
    for extra, what in ((["--min-keep", "2"], "min_keep must be a fraction"),
                        (["--fixed", "nope"], "'nope' is not a parameter"),
                        (["--shift-cost", "f0"], "--shift-cost must be NAME=W"),
                        (["--cut-cost", "f0=-1"], "--cut-cost must be NAME=W")):
        assert main(["synthesize", "reciprocating_cam", "--out", str(tmp_path / "x"),
                     "--executor", "serial", "--no-plots", *extra]) == 2
        assert what in capsys.readouterr().err


def test_a_checkpoint_keeps_its_guards_and_refuses_damaged_ones():
    m = reciprocating_cam()
    g = Guards.of(m, hard=["f0"], min_keep=0.4)
    st = SynthesisState(m.name, tuple(m.names), m.nominal, m.tol, m.nominal, m.tol,
                        {"name": "fast"}, 0.1, guards=g.to_dict())
    doc = json.loads(checkpoint_text(st))
    back = SynthesisState.from_dict(doc)
    assert Guards.from_dict(back.guards, m.names).same_as(g)
    doc["guards"]["min_keep"][0] = 7.0
    with pytest.raises(FileFormatError, match="damaged checkpoint"):
        SynthesisState.from_dict(doc)


def test_converged_with_deep_cuts_warns():
    m = reciprocating_cam()
    tol = m.tol.copy()
    tol[2] *= 0.3
    st = SynthesisState(m.name, tuple(m.names), m.nominal, m.tol, m.nominal, tol,
                        {"name": "fast"}, 0.1, status=SynthesisStatus.CONVERGED)
    r = _result(st, m, None, None, None, None)
    assert r.success and "warning: 1 tolerance(s) kept below 50 %" in r.message
    assert "f0 30 %" in r.message
    assert deep_cuts(m.names, m.tol, m.tol) == []
