"""Values of the synthesis loop: iteration records, the resumable state and its
checks, and the final result's report dictionary."""

import json
import math

import numpy as np
import pytest

from cspace.defects import DefectResult
from cspace.errors import FileFormatError
from synthesis.result import (CHECKPOINT_FORMAT, REPORT_FORMAT, IterationRecord,
                              PartialIteration, SynthesisResult, SynthesisState,
                              SynthesisStatus)

NAMES = ("a", "b", "c")
U0 = np.array([1.0, 2.0, 3.0])
T0 = np.array([0.1, 0.2, 0.05])


def _record(i=1, shift=(0.0, 0.05, 0.0), defective=(0, 4), yld=None, total=2.5):
    return IterationRecord(i, U0.copy(), T0.copy(), {"checklist": 10 * i, "seeds": 3}, 1,
                           tuple(defective), {"JAM": len(defective)}, np.array(shift),
                           ({"parameter": "c", "old": 0.05, "new": 0.04},), False, 7,
                           {"total": total}, ({"parameter": "b", "change": "shift"},), yld)


def _state(**kw):
    base = dict(model="m", names=NAMES, initial_nominal=U0, initial_tol=T0,
                nominal=U0 + [0.0, 0.05, 0.0], tol=T0, accuracy={"name": "fast"}, d=0.01,
                history=(_record(),))
    base.update(kw)
    return SynthesisState(**base)


def _doc(**changes):
    d = json.loads(json.dumps(_state().to_dict()))
    d.update(changes)
    return d


# ------------------------------------------------------------------ IterationRecord
def test_iteration_record_dict_round_trip():
    rec = _record(yld={"ppm": 12.5, "met": True})
    assert rec.n_defects == 2
    d = rec.to_dict(NAMES)
    assert d["defects"] == 2 and d["defective"] == [0, 4]
    # only the parameters that moved, by name
    assert d["shift_by_name"] == {"b": 0.05}
    assert d["yield"] == {"ppm": 12.5, "met": True} and d["times"] == {"total": 2.5}
    back = IterationRecord.from_dict(json.loads(json.dumps(d)))
    assert back.to_dict(NAMES) == d
    assert back.shift.tobytes() == rec.shift.tobytes()
    assert repr(rec) == "<Iteration 1: 10 vectors, 2 defective, 1 shrink(s)>"


def test_iteration_record_without_timing_or_names():
    d = _record().to_dict(timing=False)
    assert "times" not in d and "shift_by_name" not in d and "yield" not in d
    back = IterationRecord.from_dict(d)
    assert back.times == {} and back.yield_estimate is None


# ------------------------------------------------------------------ PartialIteration
def test_partial_iteration_mismatch_says_why():
    p = PartialIteration(2, U0, T0, ())
    assert p.mismatch(1, U0.copy(), T0.copy()) == ""
    assert p.mismatch(2, U0, T0) == "the partial iteration must be the next one (3), got 2"
    assert "current design" in p.mismatch(1, U0 + [0, 0, 1e-12], T0)
    assert "current design" in p.mismatch(1, U0, T0 * 0.5)


def test_partial_iteration_dict_round_trip():
    r = DefectResult(False, (), 0.002, 0.01, None, (), (), "healthy")
    p = PartialIteration(1, U0, T0, ((U0 + 0.01, r, True, 0.25), (U0, r, False, math.nan)))
    d = p.to_dict()
    assert [t["margin"] for t in d["tests"]] == [0.25, None]
    back = PartialIteration.from_dict(json.loads(json.dumps(d)))
    assert back.to_dict() == d and repr(back) == "<PartialIteration 1: 2 test(s) finished>"
    assert math.isnan(back.tests[1][3])
    d["tests"][0]["certified"] = 1
    with pytest.raises(TypeError, match="certified must be true or false"):
        PartialIteration.from_dict(d)


# ------------------------------------------------------------------ SynthesisState
def test_state_round_trip_and_defaults_of_older_checkpoints():
    st = _state(partial=PartialIteration(2, U0 + [0.0, 0.05, 0.0], T0, ()), two_sided=True,
                patience=2, search="margin", removal="lp")
    d = json.loads(json.dumps(st.to_dict()))
    assert d["format"] == CHECKPOINT_FORMAT and d["version"] == 2
    back = SynthesisState.from_dict(d)
    assert back.to_dict() == st.to_dict() and back.iterations == 1
    # keys added over time: a checkpoint without them gets the values of its day
    for k in ("patience", "two_sided", "max_checklist", "partial", "guards", "search",
              "removal", "known", "target", "shifted", "note"):
        d.pop(k)
    old = SynthesisState.from_dict(d)
    assert (old.patience, old.two_sided, old.max_checklist) == (4, False, 4000)
    assert (old.search, old.removal, old.guards, old.target, old.known) == \
        ("bisect", "greedy", None, None, ())


def test_state_repr_shows_the_run():
    st = _state(tol=T0 * [1.0, 1.0, 0.5])
    assert repr(st) == ("<SynthesisState 'm': RUNNING after 1 iteration(s), defects [2], "
                        "e = 0.05, 1 tolerance(s) cut, d = 0.01>")


@pytest.mark.parametrize("change, message", [
    ({"version": 1}, r"version 1\) was made by an earlier version .* restart the run "
                     r"\(--fresh\)"),
    ({"version": 3}, "checkpoint version must be 2, got 3"),
    ({"format": "other"}, "expected a 'cspace-synthesis-checkpoint' document, got 'other'"),
    ({"nominal": [1.0, 2.0]}, r"nominal must hold 3 values \(one per parameter\), got shape"),
    ({"initial_tol": [0.1, -0.2, 0.05]}, "initial_tol must be >= 0"),
    ({"d": 0.0}, "d must be a positive finite number, got 0.0"),
    ({"d": "0.01x"}, "damaged checkpoint: ValueError"),
    ({"removed": [[1.0, 2.0]]}, r"removed\[0\] must be 3 finite values"),
    ({"status": "INTERRUPTED"}, "status INTERRUPTED is a report's"),
    ({"status": "NOT_A_STATUS"}, "damaged checkpoint: KeyError"),
    ({"patience": True}, "patience must be an int >= 1, got True"),
    ({"max_checklist": 0}, "max_checklist must be an int >= 1, got 0"),
    ({"two_sided": "yes"}, "two_sided must be true or false, got 'yes'"),
    ({"search": "random"}, r"search must be one of \['margin', 'bisect'\]"),
    ({"guards": {"fixed": ["zz"], "hard": [], "shift_cost": [1, 1, 1], "cut_cost": [1, 1, 1],
                 "min_keep": [0.25, 0.25, 0.25]}}, "damaged checkpoint: ValueError: fixed "
                                                   "names 'zz'"),
    ({"target": {"target": 1.5}}, "damaged checkpoint: InputError: target yield"),
    ({"target": [0.99]}, "target must be an object or null"),
    ({"known": {}}, "damaged checkpoint: TypeError: known must be a list"),
])
def test_damaged_states_are_refused_with_a_reason(change, message):
    with pytest.raises(FileFormatError, match=message) as e:
        SynthesisState.from_dict(_doc(**change), path="run/checkpoint.json")
    assert e.value.path == "run/checkpoint.json"


def test_non_finite_values_are_refused():
    d = _doc()
    d["tol"] = [0.1, math.inf, 0.05]
    with pytest.raises(FileFormatError, match="tol must be finite"):
        SynthesisState.from_dict(d)
    with pytest.raises(FileFormatError, match="expected a 'cspace-synthesis-checkpoint' "
                                              "document, got 'list'"):
        SynthesisState.from_dict([d])


def test_only_a_running_state_has_a_partial_iteration():
    st = _state(status=SynthesisStatus.CONVERGED,
                partial=PartialIteration(2, U0 + [0.0, 0.05, 0.0], T0, ()))
    with pytest.raises(FileFormatError, match="only a running state has a partial iteration"):
        SynthesisState.from_dict(json.loads(json.dumps(st.to_dict())))
    # of another design than the state's current one
    st = _state(partial=PartialIteration(2, U0, T0, ()))
    with pytest.raises(FileFormatError, match="must be of the current design"):
        SynthesisState.from_dict(json.loads(json.dumps(st.to_dict())))


# ------------------------------------------------------------------ SynthesisResult
def _result(**kw):
    final = U0 + [0.0, 0.05, -0.02]
    base = dict(success=True, status=SynthesisStatus.CONVERGED,
                message=SynthesisStatus.CONVERGED.value, nit=2, model="m", names=NAMES,
                units="mm", initial_nominal=U0, initial_tol=T0, nominal=final,
                tol=T0 * [1.0, 0.5, 1.0], e=0.05, overlaps=({"pair": 0},), d=0.01,
                accuracy={"name": "fast"},
                history=(_record(1, total=2.0), _record(2, defective=(), total=3.5)))
    base.update(kw)
    return SynthesisResult(**base)


def test_result_changes_per_parameter():
    ch = _result().changes()
    assert list(ch) == list(NAMES)
    assert ch["a"] == {"initial": 1.0, "final": 1.0, "delta": 0.0, "tol_initial": 0.1,
                       "tol_final": 0.1}
    assert ch["b"]["delta"] == pytest.approx(0.05) and ch["b"]["tol_final"] == 0.1
    assert ch["c"]["delta"] == pytest.approx(-0.02) and ch["c"]["tol_final"] == 0.05


def test_result_report_dictionary():
    r = _result()
    d = r.to_dict()
    assert d["format"] == REPORT_FORMAT and d["status"] == "CONVERGED" and d["success"]
    assert d["e_over_tolerance"] == pytest.approx(0.05 / 0.2)
    assert d["defects_per_iteration"] == [2, 0] and d["checklist_sizes"] == [10, 20]
    assert set(d["changed"]) == {"b", "c"}
    assert d["shrunk"] == {"b": [0.2, 0.1]}
    assert d["time"] == 5.5 and d["history"][0]["shift_by_name"] == {"b": 0.05}
    assert d["search"] == "bisect" and d["removal"] == "greedy"
    assert "interrupted" not in d and "guards" not in d and "target" not in d
    quiet = r.to_dict(timing=False)
    assert "time" not in quiet and all("times" not in h for h in quiet["history"])
    # JSON as it is
    assert json.loads(json.dumps(d)) == d
    assert repr(r) == "<SynthesisResult 'm': CONVERGED, 2 iteration(s), defects [2, 0], " \
                      "e = 0.05 mm>"


def test_result_states_each_parameters_unit_and_the_angles_shift_apart():
    r = _result()
    assert r.to_dict()["parameter_units"] == ["mm"] * 3 and "e_angle" not in r.to_dict()
    a = _result(param_units=("mm", "rad", "mm"), e_angle=0.05, e=0.02)
    d = a.to_dict()
    assert d["parameter_units"] == ["mm", "rad", "mm"] and d["e_angle"] == 0.05
    assert [a.unit_of(i) for i in range(3)] == ["mm", "rad", "mm"]


def test_result_without_tolerances_has_no_ratio():
    d = _result(initial_tol=np.zeros(3), tol=np.zeros(3)).to_dict()
    assert d["e_over_tolerance"] is None and d["shrunk"] == {}


def test_result_of_a_target_yield_run():
    hist = (_record(1, yld={"ppm": 900.0}), _record(2, defective=(1,), yld={"ppm": 80.0}),
            _record(3, defective=(1,)))
    r = _result(history=hist, target={"target": 0.9999, "ppm": 100.0},
                status=SynthesisStatus.TARGET_YIELD, interrupted={"iteration": 4},
                guards={"fixed": ["a"]})
    # the last iteration that estimated the yield
    assert r.yield_estimate == {"ppm": 80.0}
    d = r.to_dict()
    assert d["yield"] == {"ppm": 80.0} and d["worst_case"] == {"defective_left": 1}
    assert d["target"]["target"] == 0.9999
    assert d["interrupted"] == {"iteration": 4} and d["guards"] == {"fixed": ["a"]}
    assert _result().yield_estimate is None
