"""A run stopped inside an iteration resumes from the tests it had finished and
gives the uninterrupted run's result (issue 24, "Checkpoint within an
iteration"; issue 23: a run stopped before its first iteration ends keeps a
checkpoint)."""

import numpy as np
import pytest

import synthesis.executors as executors
from cspace.errors import FileFormatError, InputError
from mechanisms.models import reciprocating_cam
from synthesis import synthesize
from synthesis.checkpoint import checkpoint_text, content_hash
from synthesis.executors import SerialExecutor
from synthesis.memo import TestMemo
from synthesis.progress import Progress
from synthesis.result import PartialIteration, SynthesisState, SynthesisStatus

MAX_ITER = 2


#: vectors actually tested (not reused), per iteration
TESTED: dict = {}
_CURRENT = [0]


def _counting_batch_task(model, U, accuracy, d, _real=executors.batch_task):
    TESTED[_CURRENT[0]] = TESTED.get(_CURRENT[0], 0) + len(U)
    return _real(model, U, accuracy, d)


class _StopAt(Progress):
    """Raises KeyboardInterrupt at the ``at``-th progress report (0-based)."""

    def __init__(self, at):
        self.at, self.calls = at, 0

    def begin(self, iteration):
        _CURRENT[0] = iteration

    def task(self, phase, done, total, defective=None):
        if self.calls == self.at:
            self.calls += 1
            raise KeyboardInterrupt
        self.calls += 1


class _Count(Progress):
    def __init__(self):
        self.calls = 0

    def begin(self, iteration):
        _CURRENT[0] = iteration

    def task(self, phase, done, total, defective=None):
        self.calls += 1


def _through_file(state):
    """The state as ``--resume`` reads it back from the checkpoint file."""
    import json
    doc = json.loads(checkpoint_text(state))
    assert doc["sha256"] == content_hash(doc)
    return SynthesisState.from_dict(doc)


@pytest.fixture(scope="module")
def small_chunks():
    # many finished batches inside one iteration: many places to stop
    old = executors.TASK_CHUNK, executors.batch_task
    executors.TASK_CHUNK = 4
    executors.batch_task = _counting_batch_task
    yield
    executors.TASK_CHUNK, executors.batch_task = old


@pytest.fixture(scope="module")
def uninterrupted(small_chunks):
    m = reciprocating_cam()
    count = _Count()
    saved = []
    TESTED.clear()
    r = synthesize(m, "fast", executor=SerialExecutor(), max_iter=MAX_ITER, progress=count,
                   on_partial=saved.append, checkpoint_every=0.0)
    return m, r, count.calls, saved, dict(TESTED)


def test_a_checkpoint_exists_from_the_first_iterations_start(uninterrupted):
    m, r, _, saved, _ = uninterrupted
    first = saved[0]
    assert first.iterations == 0 and first.status is SynthesisStatus.RUNNING
    assert first.partial is not None and first.partial.iteration == 1
    assert len(first.partial.tests) == 0
    # later saves of iteration 1 hold more and more finished tests
    sizes = [len(s.partial.tests) for s in saved if s.iterations == 0]
    assert sizes == sorted(sizes) and sizes[-1] >= r.history[0].counts["checklist"]


@pytest.mark.parametrize("frac", [0.05, 0.3, 0.55, 0.8, 0.97])
def test_resume_from_a_stop_inside_the_run_gives_the_same_result(uninterrupted, frac):
    m, r, calls, _, tested = uninterrupted
    at = int(frac * calls)
    saved = []
    with pytest.raises(KeyboardInterrupt):
        synthesize(m, "fast", executor=SerialExecutor(), max_iter=MAX_ITER,
                   progress=_StopAt(at), on_partial=saved.append, checkpoint_every=1e9)
    last = _through_file(saved[-1])
    assert last.partial is not None and last.status is SynthesisStatus.RUNNING
    TESTED.clear()
    r2 = synthesize(m, "fast", executor=SerialExecutor(), max_iter=MAX_ITER, state=last,
                    progress=_Count())
    assert r2.status is r.status
    a = r.to_dict(timing=False)
    b = r2.to_dict(timing=False)
    assert a == b
    # the resumed run tested only what the checkpoint did not hold
    k = last.partial.iteration
    assert TESTED.get(k, 0) == tested[k] - len(last.partial.tests)
    assert all(TESTED.get(i, 0) == tested[i] for i in tested if i > k)
    assert not any(TESTED.get(i, 0) for i in tested if i < k)


def test_the_stop_flush_keeps_every_finished_test(small_chunks):
    # with a long interval only the start and the stop write: the stop's save
    # holds the tests finished before the interrupt
    m = reciprocating_cam()
    saved = []
    with pytest.raises(KeyboardInterrupt):
        synthesize(m, "fast", executor=SerialExecutor(), max_iter=1, progress=_StopAt(10),
                   on_partial=saved.append, checkpoint_every=1e9)
    assert len(saved) == 2
    assert len(saved[0].partial.tests) == 0
    assert len(saved[-1].partial.tests) >= 10 * executors.TASK_CHUNK


def test_memo_reuses_by_exact_vector_and_saves_at_most_every_interval():
    from cspace.defects import DefectResult, Reason
    calls = []
    memo = TestMemo(1, np.zeros(2), np.ones(2), save=calls.append, every=1e9)
    r = DefectResult(True, (Reason.JAM,), float("inf"), 0.1, (0, 1.0, 2.0), (), (), "jam")
    memo.put(np.array([0.1, 0.2]), r, False, -0.25)
    memo.tick()
    assert calls == []                       # the interval has not passed
    assert memo.get(np.array([0.1, 0.2])) == (r, False, -0.25)
    assert memo.get(np.array([0.1, 0.2 + 1e-17])) == (r, False, -0.25)   # same double
    assert memo.get(np.array([0.1, np.nextafter(0.2, 1)])) is None
    memo.flush()
    assert len(calls) == 1 and len(calls[0].tests) == 1
    back = PartialIteration.from_dict(calls[0].to_dict())
    u, r2, c, mg = back.tests[0]
    assert np.array_equal(u, [0.1, 0.2]) and c is False and mg == -0.25
    assert r2.to_dict() == r.to_dict()


def test_a_partial_of_another_design_is_refused():
    m = reciprocating_cam()
    st = SynthesisState(m.name, tuple(m.names), m.nominal, m.tol, m.nominal, m.tol,
                        {"name": "fast"}, 0.1,
                        partial=PartialIteration(2, m.nominal, m.tol, ()))
    import json
    doc = json.loads(checkpoint_text(st))
    with pytest.raises(FileFormatError, match="partial iteration must be the next one"):
        SynthesisState.from_dict(doc)
    from synthesis.accuracy import as_synthesis_accuracy
    st = SynthesisState(m.name, tuple(m.names), m.nominal, m.tol, m.nominal, m.tol,
                        as_synthesis_accuracy("fast").to_dict(), 0.1,
                        partial=PartialIteration(1, m.nominal + 1e-3, m.tol, ()))
    with pytest.raises(InputError, match="partial iteration"):
        synthesize(m, "fast", executor=SerialExecutor(), state=st, max_iter=1)


def test_a_damaged_partial_test_is_refused():
    m = reciprocating_cam()
    from cspace.defects import DefectResult
    r = DefectResult(False, (), 0.01, 0.1, None)
    st = SynthesisState(m.name, tuple(m.names), m.nominal, m.tol, m.nominal, m.tol,
                        {"name": "fast"}, 0.1,
                        partial=PartialIteration(1, m.nominal, m.tol,
                                                 ((m.nominal, r, True, float("nan")),)))
    import json
    doc = json.loads(checkpoint_text(st))
    doc["partial"]["tests"][0]["result"]["reasons"] = ["not a reason"]
    with pytest.raises(FileFormatError, match="damaged checkpoint"):
        SynthesisState.from_dict(doc)
    doc = json.loads(checkpoint_text(st))
    doc["partial"]["tests"][0]["u"] = [1.0]
    with pytest.raises(FileFormatError, match="partial test 0"):
        SynthesisState.from_dict(doc)


def test_checkpoint_every_is_checked():
    m = reciprocating_cam()
    for bad in (-1, float("nan"), "30", True):
        with pytest.raises(InputError, match="checkpoint_every"):
            synthesize(m, "fast", executor=SerialExecutor(), max_iter=1, checkpoint_every=bad)


def test_run_batched_tests_a_repeated_vector_once(small_chunks):
    from cspace.accuracy import as_accuracy
    from cspace.defects import reference
    m = reciprocating_cam()
    acc = as_accuracy("fast")
    ref = reference(m, acc)
    executors.remember_reference(m, acc, ref.d, ref)
    rng = np.random.default_rng(1)
    U = m.nominal + m.tol * rng.uniform(-1, 1, (6, m.n))
    U = np.vstack([U, U[2], U[0]])
    memo = TestMemo(1, m.nominal, m.tol)
    TESTED.clear()
    _CURRENT[0] = 1
    stats = executors.BatchStats()
    res = executors.run_batched(SerialExecutor(), m, U[:6], acc, ref.d, stats=stats, memo=memo)
    res2 = executors.run_batched(SerialExecutor(), m, U, acc, ref.d, stats=stats, memo=memo)
    assert TESTED[1] == 6 and len(memo) == 6 and memo.hits == 8
    assert [r.defective for r in res2] == [r.defective for r in res] + [res[2].defective,
                                                                        res[0].defective]
    assert stats["variants"] == 14 and stats["certified"] + stats["fallback"] == 14
