"""The synthesis loop end to end on the reciprocating cam (fast preset), with
executors, checkpoint/resume, the iteration cap and Monte Carlo verification.
The Geneva and optical-filter runs are marked slow."""

import dataclasses
import json

import numpy as np
import pytest

from cspace.errors import FileFormatError, InputError
from synthesis import executors as ex_mod
from synthesis.executors import make_executor
from synthesis.loop import synthesize
from synthesis.result import SynthesisState, SynthesisStatus
from synthesis.verify import box_samples, monte_carlo


def _plain(result):
    """A result's JSON without timings (what must be identical between runs)."""
    return json.dumps(result.to_dict(timing=False), sort_keys=True)


@pytest.fixture(scope="module")
def recip():
    from mechanisms.models import reciprocating_cam
    return reciprocating_cam()


@pytest.fixture(scope="module")
def recip_run(recip):
    with make_executor("serial") as ex:
        return synthesize(recip, "fast", executor=ex)


def test_recip_synthesis_converges_to_zero_defects(recip, recip_run):
    r = recip_run
    assert r.success and r.status is SynthesisStatus.CONVERGED
    ds = r.defects_per_iteration()
    assert ds[0] > 0 and ds[-1] == 0
    assert r.nit == len(r.history) >= 2
    # the nominal moved, by less than the largest tolerance here
    assert 0 < r.e <= float(np.max(recip.tol))
    assert r.e == pytest.approx(float(np.max(np.abs(r.nominal - recip.nominal))))
    d = r.to_dict()
    assert d["format"] == "cspace-synthesis-report" and d["units"] == "cm"
    assert d["defects_per_iteration"] == ds and d["changed"]
    h = d["history"][0]
    assert {"seeds", "checklist"} <= set(h["counts"]) and h["defects"] == ds[0]
    assert {"zones", "defects", "search", "total"} <= set(h["times"])
    # the synthesized passage is wider: both follower faces moved outward
    c = r.changes()
    assert c["xr_b"]["delta"] >= 0 and c["xl_b"]["delta"] <= 0
    assert r.zones_initial is not None and r.zones_final is not None


def test_monte_carlo_finds_defects_before_and_none_after(recip, recip_run):
    r = recip_run
    final = recip.with_nominal(r.nominal).with_tolerances(r.tol)
    with make_executor("serial") as ex:
        before = monte_carlo(recip, 200, seed=3, accuracy="fast", d=r.d, executor=ex)
        after = monte_carlo(final, 200, seed=3, accuracy="fast", d=r.d, executor=ex,
                            intent=recip)
    assert before.n_defective > 0
    assert after.n_defective == 0, after.to_dict()["first_defective"]
    assert before.to_dict()["samples"] == 200 and 0 < before.rate < 1


class _Recording(ex_mod.SerialExecutor):
    """A serial executor that keeps the design every task compared with."""

    def __init__(self):
        self.designs = []
        self.zoned = []
        self.vectors = 0

    def submit(self, fn, /, *args, **kwargs):
        from cspace.zones import _zones_of_curves
        if fn is _zones_of_curves:      # the zones of the iteration's own design
            self.zoned.append(args[1].nominal.copy())
            return super().submit(fn, *args, **kwargs)
        self.designs.append(args[0].nominal.copy())
        if fn is ex_mod.batch_task:     # not the margin sensitivities of removal="lp"
            self.vectors += len(np.atleast_2d(args[1]))   # a task tests a chunk of vectors
        return super().submit(fn, *args, **kwargs)


def test_every_defect_test_compares_with_the_initial_design(recip, recip_run):
    """The check list and the search of every iteration test variants against
    the initial design, not against the iteration's shifted nominal (which the
    output-deviation reference would otherwise follow)."""
    ex = _Recording()
    r = synthesize(recip, "fast", executor=ex, max_iter=2)
    assert r.nit == 2 and np.any(r.history[1].nominal != recip.nominal)
    # a vector asked for twice in one iteration (a mirror or a search point met
    # again) is tested once: its repeat takes the stored result
    # (synthesis.memo), and h.tests counts both
    assert 0.9 * sum(h.tests for h in r.history) <= ex.vectors <= sum(h.tests
                                                                      for h in r.history)
    assert all(np.array_equal(u, recip.nominal) for u in ex.designs)
    # the zones, on the same executor, are those of each iteration's design
    assert {tuple(u) for u in ex.zoned} == {tuple(h.nominal) for h in r.history}
    # and the final nominal of the whole run drives as the initial design does
    from cspace.defects import is_defective
    final = is_defective(recip, recip_run.nominal, recip_run.d, accuracy="fast")
    assert not final.defective and final.max_deviation <= recip_run.d


def test_a_shifted_nominal_that_is_itself_defective_stops_the_run(recip, monkeypatch):
    """A shift that makes the nominal itself defective against the initial
    design stops the run with that reason (no bisection can start from it)."""
    import synthesis.loop as loop
    real = loop.plan_with_refinement

    def plan(u0, tol, *a, **kw):
        p, trs = real(u0, tol, *a, **kw)
        bad = np.zeros_like(u0)
        bad[recip.names.index("xr_b")] = -5 * float(np.max(tol))   # closes the passage
        return dataclasses.replace(p, delta=bad), trs

    monkeypatch.setattr(loop, "plan_with_refinement", plan)
    with make_executor("serial") as ex:     # the removal that calls plan_with_refinement
        r = synthesize(recip, "fast", executor=ex, removal="greedy")
    assert r.status is SynthesisStatus.STALLED and not r.success
    assert "shifted nominal is itself defective" in r.message
    # it stopped at the first iteration whose nominal is defective, before any search
    from cspace.defects import is_defective
    flags = [is_defective(recip, h.nominal, r.d, accuracy="fast").defective for h in r.history]
    assert flags[-1] and not any(flags[:-1]) and r.nit >= 2
    assert r.history[-1].times["search"] == 0.0 and not np.any(r.history[-1].shift)
    assert json.loads(json.dumps(r.to_dict()))["status"] == "STALLED"


def test_monte_carlo_intent_must_be_the_same_model(recip):
    from mechanisms.models import geneva
    with pytest.raises(InputError, match="same model"):
        monte_carlo(recip, 4, intent=geneva(), executor=ex_mod.SerialExecutor())


def test_box_samples_are_seeded_corners_then_interior():
    s = box_samples(np.zeros(3), np.array([1.0, 2.0, 0.0]), 10, seed=5)
    assert np.array_equal(s, box_samples(np.zeros(3), np.array([1.0, 2.0, 0.0]), 10, seed=5))
    assert np.all(np.abs(s[:5, :2]) == [1.0, 2.0]) and np.all(s[:, 2] == 0)
    assert np.all(np.abs(s[5:, 0]) <= 1.0) and np.all(np.abs(s[5:, 1]) <= 2.0)
    with pytest.raises(InputError):
        box_samples(np.zeros(3), np.ones(3), 0)


def test_executors_give_identical_results(recip, recip_run):
    with make_executor("process", workers=2) as ex:
        r2 = synthesize(recip, "fast", executor=ex)
    assert _plain(r2) == _plain(recip_run)


def test_dask_local_cluster_gives_identical_result(recip, recip_run):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        with make_executor("dask", scheduler=cluster.scheduler_address) as ex:
            r3 = synthesize(recip, "fast", executor=ex)
    assert _plain(r3) == _plain(recip_run)


class _Stop(Exception):
    pass


def test_resume_after_interrupt_reproduces_the_result(recip, recip_run, tmp_path):
    saved = []

    def on_iteration(state):
        # a checkpoint goes through JSON, as the CLI writes it
        saved.append(json.loads(json.dumps(state.to_dict())))
        raise _Stop()

    with make_executor("serial") as ex, pytest.raises(_Stop):
        synthesize(recip, "fast", executor=ex, on_iteration=on_iteration)
    state = SynthesisState.from_dict(saved[-1])
    assert state.iterations == 1 and state.status is SynthesisStatus.RUNNING
    with make_executor("serial") as ex:
        r = synthesize(recip, "fast", executor=ex, state=state)
    assert _plain(r) == _plain(recip_run)


def test_iteration_cap_is_a_status_and_resumes(recip, recip_run):
    with make_executor("serial") as ex:
        r1 = synthesize(recip, "fast", executor=ex, max_iter=1)
        assert r1.status is SynthesisStatus.MAX_ITER and not r1.success and r1.nit == 1
        assert "cap" in r1.message
        state = [None]
        r2 = synthesize(recip, "fast", executor=ex, max_iter=1,
                        on_iteration=lambda s: state.__setitem__(0, s))
        r3 = synthesize(recip, "fast", executor=ex, state=state[0], max_iter=30)
    assert _plain(r3) == _plain(recip_run)
    assert r2.nit == 1


def test_bad_inputs_are_typed(recip, recip_run):
    with pytest.raises(InputError, match="parametric model"):
        synthesize(recip.build(), "fast")
    with pytest.raises(InputError, match="no positive tolerance"):
        synthesize(recip.with_tolerances(0.0), "fast")
    with pytest.raises(InputError, match="max_iter"):
        synthesize(recip, "fast", max_iter=-1)
    for bad in (-1.0, 0.0, float("inf"), float("nan"), "x", True):
        with pytest.raises(InputError, match="d must be a finite number > 0"):
            synthesize(recip, "fast", d=bad)
    with pytest.raises(InputError, match="executor must be a concurrent.futures.Executor"):
        synthesize(recip, "fast", executor="serial")
    with pytest.raises(InputError, match="state must be a SynthesisState"):
        synthesize(recip, "fast", state="x")
    st = SynthesisState.from_dict(json.loads(json.dumps(
        SynthesisState("x", tuple(recip.names), recip.nominal, recip.tol, recip.nominal,
                       recip.tol, {"name": "default"}, 0.04).to_dict())))
    with pytest.raises(InputError, match="accuracy"):
        synthesize(recip, "fast", state=st)
    other = dataclasses.replace(st, initial_nominal=recip.nominal + 1)
    with pytest.raises(InputError, match="another design"):
        synthesize(recip, "fast", state=other)
    with pytest.raises(FileFormatError):
        SynthesisState.from_dict({"format": "nope"})
    with pytest.raises(FileFormatError, match="version 1.*initial design.*--fresh"):
        SynthesisState.from_dict(dict(st.to_dict(), version=1))
    with pytest.raises(FileFormatError, match="damaged"):
        d = st.to_dict()
        del d["nominal"]
        SynthesisState.from_dict(d)
    with pytest.raises(InputError, match="executor"):
        with make_executor("threads"):
            pass
    with pytest.raises(InputError, match="scheduler"):
        with make_executor("dask"):
            pass


def test_worker_cache_is_bounded(recip):
    for k in range(ex_mod._REFS_MAX + 2):
        m = recip.with_nominal(recip.nominal + 1e-4 * k)
        ex_mod.remember_reference(m, "fast", 0.04, object())
    assert len(ex_mod._REFS) <= ex_mod._REFS_MAX


@pytest.mark.slow
@pytest.mark.parametrize("name", ["geneva", "optical_filter"])
def test_case_study_converges_and_verifies(models, name):
    m = models[name]
    with make_executor("process") as ex:
        r = synthesize(m, "fast", executor=ex)
        assert r.success, r
        final = m.with_nominal(r.nominal).with_tolerances(r.tol)
        after = monte_carlo(final, 2000, seed=1, accuracy="fast", d=r.d, executor=ex,
                            intent=m)
        before = monte_carlo(m, 2000, seed=1, accuracy="fast", d=r.d, executor=ex)
    assert after.n_defective == 0 and before.n_defective > 0


def test_patience_is_checked_recorded_and_kept_on_resume(recip, recip_run):
    for bad in (0, -1, True, 2.0, "2"):
        with pytest.raises(InputError, match="patience must be an int >= 1"):
            synthesize(recip, "fast", patience=bad)
    saved = []

    def stop_after_first(state):
        saved.append(json.loads(json.dumps(state.to_dict())))
        raise _Stop()

    with make_executor("serial") as ex:
        # patience counts the removals of the paper's greedy (removal="greedy")
        whole = synthesize(recip, "fast", executor=ex, patience=1, max_iter=2,
                           removal="greedy")
        with pytest.raises(_Stop):
            synthesize(recip, "fast", executor=ex, patience=1, max_iter=2,
                       on_iteration=stop_after_first, removal="greedy")
        state = SynthesisState.from_dict(saved[-1])
        assert state.patience == 1 and saved[-1]["patience"] == 1
        with pytest.raises(InputError, match="checkpoint used patience 1"):
            synthesize(recip, "fast", executor=ex, state=state, max_iter=2, patience=4)
        # without it, a resume keeps the checkpoint's value
        resumed = synthesize(recip, "fast", executor=ex, state=state, max_iter=2)
    assert _plain(resumed) == _plain(whole)
    assert whole.patience == 1 and whole.to_dict()["patience"] == 1
    assert recip_run.patience == 4
    # the cam's vectors come back in the second iteration: with patience 1 their
    # return is cut at once, with the default 4 it is shifted again
    assert whole.history[0].shrinks == recip_run.history[0].shrinks == ()
    assert whole.history[1].shrinks and not recip_run.history[1].shrinks
    # a checkpoint written before the setting was recorded ran with 4
    old = dict(saved[-1])
    del old["patience"]
    assert SynthesisState.from_dict(old).patience == 4
    with pytest.raises(FileFormatError, match="patience"):
        SynthesisState.from_dict(dict(saved[-1], patience=0))


def test_two_sided_defects_are_cut_at_once(recip):
    # d = 0.02: every check-list vector of the cam deviates on both sides of
    # the nominal, which no shift cures; the spread shrink is the paper's greedy's
    kw = dict(d=0.02, max_iter=1, max_checklist=12, removal="greedy")
    with pytest.raises(InputError, match="two_sided must be True, False or None"):
        synthesize(recip, "fast", two_sided="yes", **kw)
    saved = []
    with make_executor("serial") as ex:
        two = synthesize(recip, "fast", executor=ex, two_sided=True,
                         on_iteration=lambda s: saved.append(json.loads(json.dumps(s.to_dict()))),
                         **kw)
        one = synthesize(recip, "fast", executor=ex, two_sided=False, **kw)
        default = synthesize(recip, "fast", executor=ex, **kw)
    # on by default for a new run
    assert default.to_dict(timing=False) == two.to_dict(timing=False)
    h2, h1 = two.history[0], one.history[0]
    assert h2.n_defects == h1.n_defects > 0
    assert h2.counts["mirror_tests"] == h2.n_defects and "mirror_tests" not in h1.counts
    assert 0 < h2.counts["two_sided"] <= h2.n_defects
    # the mirrors are tested on top of the same search: both searches ask the
    # same distinct points (an answer the search has is not asked again)
    assert h2.tests == h1.tests + h2.counts["mirror_tests"]
    # cut at once (a spread shrink) instead of shifted first
    assert any(s["reason"] == "spread" for s in h2.shrinks)
    assert not any(s["reason"] == "spread" for s in h1.shrinks)
    assert np.any(two.tol < recip.tol)
    assert two.to_dict()["two_sided"] is True and one.to_dict()["two_sided"] is False
    # kept in the checkpoint; a resume keeps it, asking for the other is an error
    st = SynthesisState.from_dict(saved[-1])
    assert st.two_sided is True and saved[-1]["two_sided"] is True
    with pytest.raises(InputError, match="checkpoint used two_sided True"):
        synthesize(recip, "fast", state=st, two_sided=False, d=0.02, max_iter=2)
    # a checkpoint written before the option existed ran one-sided, and resumes so
    old = dict(saved[-1])
    del old["two_sided"]
    assert SynthesisState.from_dict(old).two_sided is False
    with pytest.raises(FileFormatError, match="two_sided"):
        SynthesisState.from_dict(dict(saved[-1], two_sided="yes"))


def test_max_checklist_is_checked_recorded_and_kept_on_resume(recip):
    for bad in (0, -3, True, 12.0, "12"):
        with pytest.raises(InputError, match="max_checklist must be an int >= 1"):
            synthesize(recip, "fast", max_checklist=bad)
    saved = []
    with make_executor("serial") as ex:
        r = synthesize(recip, "fast", executor=ex, max_iter=1, max_checklist=12,
                       on_iteration=lambda s: saved.append(json.loads(json.dumps(s.to_dict()))))
    # the cap truncates the cam's list (94 vectors uncapped) and says so
    assert r.history[0].counts["checklist"] == 12 and r.history[0].counts["truncated"]
    assert r.max_checklist == 12 and r.to_dict()["max_checklist"] == 12
    st = SynthesisState.from_dict(saved[-1])
    assert st.max_checklist == 12 and saved[-1]["max_checklist"] == 12
    with pytest.raises(InputError, match="checkpoint used max_checklist 12"):
        synthesize(recip, "fast", state=st, max_checklist=4000, max_iter=2)
    # a checkpoint written before the setting was kept ran with the fixed cap
    old = dict(saved[-1])
    del old["max_checklist"]
    assert SynthesisState.from_dict(old).max_checklist == 4000
    with pytest.raises(FileFormatError, match="max_checklist must be an int >= 1"):
        SynthesisState.from_dict(dict(saved[-1], max_checklist=0))


def test_progress_reports_the_defective_vectors_so_far(recip, monkeypatch):
    """The check-list pass reports tests done and defective so far, in batches;
    its last report is the iteration's count.  (Tasks of 32 vectors: on one
    worker, task_rows would test the cam's 94 in one task.)"""
    from synthesis import executors
    from synthesis.progress import Progress
    monkeypatch.setattr(executors, "TASK_CHUNK", 32)

    class Seen(Progress):
        def __init__(self):
            self.calls = []

        def task(self, phase, done, total, defective=None):
            self.calls.append((phase, done, total, defective))

    seen = Seen()
    with make_executor("serial") as ex:
        r = synthesize(recip, "fast", executor=ex, max_iter=1, progress=seen)
    tests = [c for c in seen.calls if c[0] == "defect tests"]
    assert len(tests) >= 2 and all(c[3] is not None for c in tests)
    assert [c[1] for c in tests] == sorted(c[1] for c in tests)
    assert tests[-1][1] == tests[-1][2] == r.history[0].counts["checklist"]
    assert tests[-1][3] == len(r.history[0].defective)
    assert r.history[0].counts["batch_tests"] >= r.history[0].counts["checklist"]


def test_e_is_over_the_lengths_and_an_angles_shift_is_apart(recip, recip_run):
    """A parameter marked an angle (unit rad) is left out of e, whose unit is
    the model's length unit, and its shift is reported apart (rad); the
    synthesis itself does not read units: the same design (with the same d:
    the default d counts an angle's tolerance as an arc)."""
    k = int(np.argmax(np.abs(recip_run.nominal - recip_run.initial_nominal)))
    ps = list(recip.parameters)
    ps[k] = dataclasses.replace(ps[k], unit="rad")
    m = dataclasses.replace(recip, parameters=tuple(ps), deviation=recip_run.d)
    with make_executor("serial") as ex:
        r = synthesize(m, "fast", executor=ex)
    assert np.array_equal(r.nominal, recip_run.nominal) and np.array_equal(r.tol, recip_run.tol)
    shift = np.abs(r.nominal - r.initial_nominal)
    assert r.param_units[k] == "rad" and r.unit_of(k - 1 if k else 1) == "cm"
    assert r.e_angle == shift[k] > 0
    assert r.e == np.max(np.delete(shift, k)) < recip_run.e
    assert "the largest angle shift" in r.message


def test_the_message_weighs_each_shift_against_its_own_tolerance():
    """The closing message names the shift that is the largest share of its
    own parameter's initial tolerance (not e against the largest tolerance,
    which may be a parameter the defects do not touch)."""
    from types import SimpleNamespace

    from synthesis.loop import _shift_yardstick
    st = SimpleNamespace(nominal=np.array([1.0, 2.005, 3.0]),
                         initial_nominal=np.array([1.0, 2.0, 3.02]),
                         initial_tol=np.array([1.0, 0.01, 0.1]), names=("big", "small", "mid"))
    text = _shift_yardstick(st, np.ones(3, dtype=bool), "mm")
    assert "small by 0.005 mm, 0.5 of its initial +- 0.01" in text
    st.nominal = st.initial_nominal.copy()
    assert _shift_yardstick(st, np.ones(3, dtype=bool), "mm") == ""
    st.initial_tol = np.array([1.0, 0.0, 0.1])
    st.nominal = np.array([1.0, 2.001, 3.02])
    assert "small moved 0.001 mm with no tolerance of its own" in \
        _shift_yardstick(st, np.ones(3, dtype=bool), "mm")
