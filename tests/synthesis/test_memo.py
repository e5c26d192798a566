"""The memo of the finished defect tests of one iteration: keyed by the
vector's exact bits, restored from a checkpoint, saved at most every
``every`` seconds."""

import math

import numpy as np
import pytest

from cspace.defects import DefectResult, Reason
from synthesis.memo import DEFAULT_CHECKPOINT_EVERY, TestMemo
from synthesis.result import PartialIteration

JAM = DefectResult(True, (Reason.JAM,), math.inf, 0.1, (0, 1.0, 2.0), (), (), "jam")
OK = DefectResult(False, (), 0.01, 0.1, None, (), (), "healthy")


def test_default_interval():
    m = TestMemo(1, [0.0], [1.0])
    assert m.every == DEFAULT_CHECKPOINT_EVERY == 30.0


def test_get_returns_what_put_stored_and_counts_reuse():
    m = TestMemo(3, [1.0, 2.0], [0.1, 0.1])
    assert m.get([1.0, 2.0]) is None and m.hits == 0
    m.put([1.0, 2.05], JAM, True, -0.5)
    m.put(np.array([0.9, 2.0]), OK, False)
    assert len(m) == 2
    assert m.get(np.array([1.0, 2.05])) == (JAM, True, -0.5)
    res, cert, margin = m.get([0.9, 2.0])
    assert res is OK and cert is False and math.isnan(margin)     # margin unknown
    assert m.hits == 2
    # integers are the same vector as their floats
    m.put([1, 2], OK, True, 0.25)
    assert m.get(np.array([1.0, 2.0])) == (OK, True, 0.25)
    assert repr(m) == "<TestMemo iteration 3: 3 test(s), 3 reused>"


def test_a_vector_tested_again_replaces_its_entry():
    m = TestMemo(1, [0.0], [1.0])
    m.put([0.5], OK, False, 0.1)
    m.put([0.5], JAM, True, -0.1)
    assert len(m) == 1 and m.get([0.5]) == (JAM, True, -0.1)


def test_keys_are_exact_bits():
    m = TestMemo(1, [0.0], [1.0])
    m.put([0.0], OK, True, 0.0)
    # -0.0 equals 0.0 but has other bits: another key
    assert m.get([-0.0]) is None
    assert m.get([np.nextafter(0.0, 1.0)]) is None
    assert m.get([0.0]) is not None


def test_stored_vectors_are_copies():
    m = TestMemo(1, [0.0, 0.0], [1.0, 1.0])
    u = np.array([0.25, 0.5])
    m.put(u, OK, True, 1.0)
    u[0] = 9.0                                  # the caller reuses its array
    (stored, r, c, mg), = m.partial().tests
    np.testing.assert_array_equal(stored, [0.25, 0.5])
    assert m.get([0.25, 0.5]) == (OK, True, 1.0)


def test_partial_holds_every_finished_test_and_the_design():
    nominal, tol = np.array([1.0, 2.0]), np.array([0.1, 0.2])
    m = TestMemo(2, nominal, tol)
    nominal[0] = 5.0                            # the memo keeps its own copy
    m.put([1.0, 2.1], JAM, True, -0.2)
    m.put([1.1, 2.0], OK, False, 0.3)
    p = m.partial()
    assert isinstance(p, PartialIteration) and p.iteration == 2
    np.testing.assert_array_equal(p.nominal, [1.0, 2.0])
    np.testing.assert_array_equal(p.tol, tol)
    assert [(u.tolist(), r, c, mg) for u, r, c, mg in p.tests] == [
        ([1.0, 2.1], JAM, True, -0.2), ([1.1, 2.0], OK, False, 0.3)]


def test_a_resumed_memo_serves_the_checkpointed_tests():
    first = TestMemo(1, [1.0, 2.0], [0.1, 0.1])
    first.put([1.1, 2.1], JAM, True, -1.0)
    first.put([0.9, 1.9], OK, False, float("nan"))
    # through the checkpoint's JSON form and back
    partial = PartialIteration.from_dict(first.partial().to_dict())
    again = TestMemo(1, [1.0, 2.0], [0.1, 0.1], partial=partial)
    assert len(again) == 2 and again.hits == 0
    r, c, mg = again.get([1.1, 2.1])
    assert r.reasons == (Reason.JAM,) and c is True and mg == -1.0
    r, c, mg = again.get([0.9, 1.9])
    assert not r.defective and c is False and math.isnan(mg)


class _Clock:
    def __init__(self):
        self.t = 1000.0

    def __call__(self):
        return self.t


@pytest.fixture
def clock(monkeypatch):
    c = _Clock()
    monkeypatch.setattr("synthesis.memo.time.monotonic", c)
    return c


def test_tick_saves_only_new_tests_and_only_after_the_interval(clock):
    saved = []
    m = TestMemo(1, [0.0], [1.0], save=saved.append, every=10.0)
    m.tick()
    assert saved == []                          # nothing new
    m.put([0.1], OK, True, 0.5)
    clock.t += 9.0
    m.tick()
    assert saved == []                          # too early
    clock.t += 1.0
    m.tick()
    assert len(saved) == 1 and len(saved[0].tests) == 1
    m.put([0.2], OK, True, 0.5)
    clock.t += 5.0
    m.tick()
    assert len(saved) == 1                      # new, but the interval restarted at the save
    clock.t += 5.0
    m.tick()
    assert len(saved) == 2 and len(saved[1].tests) == 2
    clock.t += 100.0
    m.tick()
    assert len(saved) == 2                      # nothing new since the save
    m.put([0.3], OK, True, 0.5)
    m.tick()                                    # the interval passed long ago
    assert len(saved) == 3 and len(saved[2].tests) == 3


def test_every_zero_saves_after_each_new_test(clock):
    saved = []
    m = TestMemo(1, [0.0], [1.0], save=saved.append, every=0.0)
    for k in range(3):
        m.put([float(k)], OK, True, 0.0)
        m.tick()
    assert [len(p.tests) for p in saved] == [1, 2, 3]


def test_a_restored_memo_does_not_save_what_it_was_given(clock):
    saved = []
    partial = PartialIteration(1, np.zeros(1), np.ones(1), ((np.array([0.3]), OK, True, 0.0),))
    m = TestMemo(1, [0.0], [1.0], save=saved.append, every=0.0, partial=partial)
    m.tick()
    assert saved == []
    m.flush()                                   # flush saves regardless
    assert len(saved) == 1 and len(saved[0].tests) == 1


def test_flush_without_a_saver_does_nothing():
    m = TestMemo(1, [0.0], [1.0])
    m.put([0.5], OK, True, 0.0)
    m.flush()
    m.tick()
    assert len(m) == 1


def test_a_committed_memo_saves_nothing_more(clock):
    """Once the iteration's record is being written, a stop must not overwrite
    it with the state from before the iteration: commit ends the saving, and
    the tests stay readable."""
    saved = []
    m = TestMemo(1, [0.0], [1.0], save=saved.append, every=0.0)
    m.put([0.1], OK, True, 0.0)
    m.tick()
    assert len(saved) == 1
    m.commit()
    m.put([0.2], JAM, True, -1.0)
    m.tick()
    m.flush()
    assert len(saved) == 1
    assert m.get([0.2])[0] is JAM and len(m) == 2


def test_a_stop_after_the_iteration_record_keeps_it(monkeypatch, tmp_path):
    """The loop commits the memo before ``on_iteration``: a stop raised while the
    record is written leaves the record, not the state before the iteration."""
    from mechanisms.models import BUILTIN
    from synthesis import SerialExecutor, synthesize
    m = BUILTIN["reciprocating_cam"]()
    written = []

    def on_iteration(state):
        written.append(("iteration", len(state.history)))
        raise KeyboardInterrupt        # a stop that arrives while the record is written

    def on_partial(state):
        written.append(("partial", len(state.history)))

    with pytest.raises(KeyboardInterrupt):
        synthesize(m, "fast", executor=SerialExecutor(), on_iteration=on_iteration,
                   on_partial=on_partial, checkpoint_every=1e9)
    assert written[-1] == ("iteration", 1)


def test_reused_counts_the_resumed_tests_asked_for_once_each():
    """:attr:`TestMemo.reused`: of a resumed checkpoint's tests, those asked
    for (each once); this run's own tests asked for again count in ``hits``
    only (a resumed yield logged 3919 reused of 3569 kept)."""
    from synthesis.result import PartialIteration
    ok = DefectResult(False, (), 0.0, 0.1, None, (), (), "healthy")
    kept = PartialIteration(1, np.zeros(2), np.ones(2),
                            ((np.array([1.0, 0.0]), ok, True, 0.5),
                             (np.array([2.0, 0.0]), ok, True, 0.5)))
    memo = TestMemo(1, np.zeros(2), np.ones(2), partial=kept)
    memo.put(np.array([3.0, 0.0]), ok, True)
    for _ in range(3):
        assert memo.get(np.array([1.0, 0.0])) is not None
        assert memo.get(np.array([3.0, 0.0])) is not None
    assert memo.get(np.array([4.0, 0.0])) is None
    assert memo.hits == 6 and memo.reused == 1
