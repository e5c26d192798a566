"""Running defect tests on executors: results in submission order whatever
the completion order, the per-process cache of nominal references, and the
defect tasks against the full test (on the Scotch yoke of
``tests/cspace/batch/yoke.py``)."""

import threading
import time
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace

import numpy as np
import pytest

import synthesis.executors as executors
from cspace.accuracy import as_accuracy
from cspace.defects import is_defective, reference
from cspace.errors import InputError
from synthesis.executors import (BatchStats, SerialExecutor, batch_task, check_executor,
                                 defect_task, design_key, make_executor, remember_reference,
                                 run_batched, run_ordered, search_margin, search_task)

from ..cspace.batch.yoke import yoke

ACC = as_accuracy("fast")
D = 5e-4          # a crank 0.02 longer deviates by 0.02 / 25 = 8e-4: defective
#: healthy, pin wider than the slot (jams), crank 0.02 longer (deviates)
VECTORS = np.array([[20.0, 5.0, 5.03], [20.0, 5.04, 5.03], [20.02, 5.0, 5.03],
                    [20.005, 5.0, 5.03]])
VERDICTS = [False, True, True, False]


@pytest.fixture(scope="module")
def model():
    return yoke(deviation=D)


@pytest.fixture(scope="module")
def ref(model):
    return reference(model, ACC)


@pytest.fixture
def refs(monkeypatch, model, ref):
    """A fresh per-process reference cache holding the yoke's reference; a
    reference computed anew fails the test."""
    monkeypatch.setattr(executors, "_REFS", OrderedDict())
    remember_reference(model, ACC, ref.d, ref)

    def no(*a, **k):
        raise AssertionError("the reference was computed again")
    monkeypatch.setattr("cspace.defects.reference", no)
    return executors._REFS


# ------------------------------------------------------------------ executors
def test_serial_executor_runs_at_submission():
    ran = []
    ex = SerialExecutor()
    f = ex.submit(lambda x, y=1: ran.append(x) or x + y, 2, y=5)
    assert ran == [2] and f.done() and f.result() == 7
    # an error is kept in the future, raised by result()
    g = ex.submit(lambda: 1 / 0)
    assert g.done() and isinstance(g.exception(), ZeroDivisionError)
    with pytest.raises(ZeroDivisionError):
        g.result()


def test_serial_executor_lets_an_interrupt_through():
    def stop():
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        SerialExecutor().submit(stop)


@pytest.mark.parametrize("kind, workers, scheduler, message", [
    ("threads", None, None, r"executor must be one of \['process', 'serial', 'dask'\], got "
                            r"'threads'"),
    ("process", 0, None, "workers"),
    ("process", 2.5, None, "workers"),
    ("serial", True, None, "workers"),
    ("process", 10 ** 7, None, r"workers must be at most 4 per CPU available"),
    ("dask", None, None, r"the dask executor needs a scheduler address \(--scheduler ADDR\)"),
    ("dask", None, "", "scheduler address"),
])
def test_make_executor_checks_its_arguments(kind, workers, scheduler, message):
    with pytest.raises(InputError, match=message):
        with make_executor(kind, workers, scheduler):
            pass


def test_make_executor_serial_and_process():
    with make_executor("serial") as ex:
        assert isinstance(ex, SerialExecutor)
    with make_executor("process", workers=1) as ex:
        assert run_ordered(ex, pow, [(2, 10), (3, 3)]) == [1024, 27]


def test_check_executor():
    assert check_executor(None) is None
    ex = SerialExecutor()
    assert check_executor(ex) is ex
    duck = SimpleNamespace(submit=lambda fn, *a: None)
    assert check_executor(duck) is duck
    with pytest.raises(InputError, match=r"executor must be a concurrent.futures.Executor or "
                                         r"None, got 'process'; for one of .* use 'with "
                                         r"make_executor\(kind\) as ex: ... executor=ex'"):
        check_executor("process")


def test_make_executor_passed_itself_says_to_use_it_in_a_with_statement():
    """The docs and the WorkerError once said to pass
    executor=make_executor("serial"), which is the context manager, not the
    executor: the message says how to use it (and the docs now do)."""
    cm = make_executor("serial")
    with pytest.raises(InputError, match=r"got a context manager .*'with make_executor\(kind\) "
                                         r"as ex: ... executor=ex'.*SerialExecutor\(\)"):
        check_executor(cm)
    from synthesis import synthesize
    from mechanisms.models import reciprocating_cam
    with pytest.raises(InputError, match="got a context manager"):
        synthesize(reciprocating_cam(), "fast", executor=make_executor("serial"))
    from cspace.errors import WorkerError
    assert "executor=SerialExecutor()" in str(WorkerError())


# ------------------------------------------------------------------ run_ordered
def test_run_ordered_keeps_submission_order():
    """The tasks finish in reverse order; the results come back in order, and
    every completion is reported."""
    seen, ticks = [], []

    def task(i):
        time.sleep(0.1 * (4 - i))
        return i * i

    with ThreadPoolExecutor(max_workers=5) as ex:
        out = run_ordered(ex, task, [(i,) for i in range(5)],
                          progress=lambda done, total: ticks.append((done, total, len(seen))),
                          on_result=lambda i, r: seen.append((i, r)))
    assert out == [0, 1, 4, 9, 16]
    assert [i for i, _ in seen] == [4, 3, 2, 1, 0]          # completion order
    assert all(r == i * i for i, r in seen)
    # progress after each result
    assert ticks == [(k, 5, k) for k in range(1, 6)]


def test_run_ordered_of_nothing():
    assert run_ordered(SerialExecutor(), pow, []) == []


def test_run_ordered_cancels_what_has_not_started_and_raises():
    ran = []
    gate = threading.Event()

    def task(i):
        if i == 0:
            gate.wait(5)
            raise ValueError("the first task failed")
        time.sleep(0.1)
        ran.append(i)
        return i

    with ThreadPoolExecutor(max_workers=1) as ex:
        threading.Timer(0.2, gate.set).start()
        with pytest.raises(ValueError, match="first task failed"):
            run_ordered(ex, task, [(i,) for i in range(20)])
    # one worker: the queued tasks were cancelled (at most the next one had started)
    assert ran in ([], [1])


# ------------------------------------------------------------------ references
def test_design_key_identifies_a_design(model):
    k = design_key(model, ACC, D)
    assert design_key(yoke(deviation=D), ACC, D) == k
    assert design_key(model.with_nominal(model.nominal + [0, 0, 1e-12]), ACC, D) != k
    assert design_key(model.with_tolerances(0.01), ACC, D) != k
    assert design_key(model, as_accuracy("default"), D) != k
    assert design_key(model, ACC, D * 2) != k


def test_the_reference_cache_keeps_the_three_last_used(monkeypatch, model):
    monkeypatch.setattr(executors, "_REFS", OrderedDict())
    for d in (1.0, 2.0, 3.0):
        remember_reference(model, ACC, d, f"ref{d}")
    assert executors.cached_reference(model, ACC, 1.0) == "ref1.0"  # now the most recent
    remember_reference(model, ACC, 4.0, "ref4.0")                   # evicts ref2.0
    assert len(executors._REFS) == 3
    assert design_key(model, ACC, 2.0) not in executors._REFS
    assert design_key(model, ACC, 1.0) in executors._REFS
    computed = []

    def fake(m, acc, d):
        computed.append(d)
        return f"new{d}"
    monkeypatch.setattr("cspace.defects.reference", fake)
    assert executors.cached_reference(model, ACC, 2.0) == "new2.0" and computed == [2.0]
    assert executors.cached_reference(model, ACC, 2.0) == "new2.0" and computed == [2.0]


# ------------------------------------------------------------------ defect tasks
def test_defect_task_is_the_full_test_without_match_details(refs, model, ref):
    for u, want in zip(VECTORS, VERDICTS):
        r = defect_task(model, u, ACC, ref.d)
        full = is_defective(model, u, ref=ref)
        assert r.defective == full.defective == want
        assert r.matches == () and r.reasons == full.reasons and r.where == full.where
        assert r.max_deviation == full.max_deviation and r.message == full.message


def test_search_task_gives_the_verdict(refs, model, ref):
    assert [search_task(model, u, ACC, ref.d) for u in VECTORS] == VERDICTS
    assert search_task(model, VECTORS[1], ACC, ref.d, first_pair=0) is True
    with pytest.raises(InputError, match="first_pair"):
        search_task(model, VECTORS[1], ACC, ref.d, first_pair=1)


def test_batch_task_results_and_counts(refs, model, ref):
    results, stats = batch_task(model, VECTORS, ACC, ref.d)
    assert [r.defective for r in results] == VERDICTS
    assert all(r.matches == () for r in results)
    assert len(stats["certified_rows"]) == len(stats["margin_rows"]) == len(VECTORS)
    assert stats["variants"] == len(VECTORS)
    assert stats["certified"] == sum(stats["certified_rows"])
    # the healthy nominal has a positive search margin, the jam a negative one
    assert stats["margin_rows"][0] > 0 > stats["margin_rows"][1]


def test_search_margin_is_the_smaller_of_channel_and_deviation():
    m = np.array([[0.3, -9.0, 0.1], [-0.2, 5.0, 0.4], [np.nan, 1.0, 0.2], [0.1, 1.0, np.inf]])
    out = search_margin(SimpleNamespace(margins=lambda: m))
    np.testing.assert_array_equal(out[:2], [0.1, -0.2])      # the sequence margin is left out
    assert np.isnan(out[2:]).all()


def test_run_batched_is_independent_of_the_chunk(refs, model, ref, monkeypatch):
    U = np.vstack([VECTORS, VECTORS[::-1] + [0.001, 0.0, 0.0]])
    calls, margins = [], []
    stats = BatchStats()
    whole = run_batched(SerialExecutor(), model, U, ACC, ref.d,
                        progress=lambda *a: calls.append(a), stats=stats, margins=margins)
    n_def = sum(r.defective for r in whole)
    assert [r.defective for r in whole[:4]] == VERDICTS
    assert calls == [(len(U), len(U), n_def)]                 # one chunk, one report
    assert stats["variants"] == len(U) and stats["certified"] + stats["fallback"] == len(U)
    assert len(margins) == len(U) and margins[0] > 0 > margins[1]
    # chunks of 3: the same results and margins, a report per chunk
    monkeypatch.setattr(executors, "TASK_CHUNK", 3)
    small, small_margins = [], []
    parts = run_batched(SerialExecutor(), model, U, ACC, ref.d,
                        progress=lambda *a: small.append(a), margins=small_margins)
    assert [r.to_dict() for r in parts] == [r.to_dict() for r in whole]
    np.testing.assert_array_equal(small_margins, margins)
    # (in the order the chunks complete)
    done = [a[0] for a in small]
    assert sorted(np.diff([0] + done).tolist()) == [2, 3, 3]
    assert small[-1] == (8, 8, n_def) and all(a[1] == 8 for a in small)


def test_run_batched_gives_each_row_s_margins(refs, model, ref):
    """``tables``: every margin of each row, the numbers of defect_margins
    (a repeated row gets its first's, a row the memo answers None)."""
    from cspace.batch.margins import defect_margins
    from synthesis.memo import TestMemo
    U = np.vstack([VECTORS, VECTORS[1:2]])
    tables: list = []
    out = run_batched(SerialExecutor(), model, U, ACC, ref.d, tables=tables)
    mb = defect_margins(model, U, ref, fallback=False)
    assert len(tables) == len(U)
    for v, t in enumerate(tables):
        np.testing.assert_array_equal(t["channel"], mb.channel[v])
        np.testing.assert_array_equal(t["sequence"], mb.sequence[v])
        np.testing.assert_array_equal(t["start"], mb.start[v])
        assert t["deviation"] == mb.deviation[v]
    memo = TestMemo(1, model.nominal, model.tol)
    for u, r in zip(U, out):
        memo.put(u, r, True, 0.0)
    again: list = []
    run_batched(SerialExecutor(), model, U[:2], ACC, ref.d, memo=memo, tables=again)
    assert again == [None, None]
    for kw in ({"tables": ()}, {"margins": {}}):
        with pytest.raises(InputError, match="must be a list"):
            run_batched(SerialExecutor(), model, U[:2], ACC, ref.d, **kw)


def test_run_batched_of_no_vectors(refs, model, ref):
    called = []
    assert run_batched(SerialExecutor(), model, np.zeros((0, 3)), ACC, ref.d,
                       progress=lambda *a: called.append(a)) == []
    assert called == []


# ------------------------------------------------------------------ counts
def test_batch_stats_add_up():
    s = BatchStats()
    s.add({"variants": 5, "certified": 4, "fallback": 1, "other": 9})
    s.add_vector(True)
    s.add_vector(False)
    assert s == {"variants": 7, "certified": 5, "fallback": 2}
    s.add({})
    assert s == {"variants": 7, "certified": 5, "fallback": 2}


def test_task_rows_take_an_eighth_of_the_batch_within_bounds(monkeypatch):
    from synthesis.executors import TASK_ROWS, task_rows
    lo, hi = TASK_ROWS
    assert task_rows(1) == lo and task_rows(8 * lo) == lo
    assert task_rows(620) == 78                     # a Geneva check list: 8 tasks
    assert task_rows(10 ** 6) == hi
    monkeypatch.setattr(executors, "TASK_CHUNK", 3)
    assert task_rows(620) == 3


def test_task_rows_give_every_worker_a_share_in_few_tasks():
    """With the worker count known: a multiple of it in tasks, as few as
    TASK_ROWS[1] allows, the rows spread evenly."""
    from concurrent.futures import ProcessPoolExecutor

    from synthesis.executors import TASK_ROWS, SerialExecutor, executor_workers, task_rows
    hi = TASK_ROWS[1]
    assert task_rows(60, 2) == 30 and task_rows(620, 2) == 104       # 2 and 6 tasks
    assert task_rows(620, 1) == 124 and task_rows(1, 2) == 1 and task_rows(3, 4) == 1
    for n in (1, 2, 7, 33, 64, 65, 256, 257, 620, 2000):
        for w in (1, 2, 3, 8):
            size = task_rows(n, w)
            rounds = -(-n // (w * hi))            # tasks per worker
            assert 1 <= size <= hi and -(-n // size) <= w * rounds, (n, w, size)
            # no worker gets a task more than another
            assert size * w * (rounds - 1) < n or rounds == 1, (n, w, size)
    assert executor_workers(None) == 1 and executor_workers(SerialExecutor()) == 1
    with ProcessPoolExecutor(max_workers=2) as ex:
        assert executor_workers(ex) == 2
    assert executor_workers(object()) is None


def test_run_batched_tests_a_vector_repeated_in_its_batch_once(refs, model, ref, monkeypatch):
    """Repeats (the same bits) in one batch are tested once; every row gets the
    result, the counts and the progress count every row."""
    U = np.vstack([VECTORS, VECTORS[2], VECTORS[0], VECTORS[2]])
    sent = []
    real = executors.batch_task

    def spy(model_, U_, *a):
        sent.append(len(U_))
        return real(model_, U_, *a)

    monkeypatch.setattr(executors, "batch_task", spy)
    calls, margins = [], []
    stats = BatchStats()
    res = run_batched(SerialExecutor(), model, U, ACC, ref.d,
                      progress=lambda *a: calls.append(a), stats=stats, margins=margins)
    assert sum(sent) == len(VECTORS)
    assert [r.to_dict() for r in res] == [r.to_dict() for r in
                                           res[:len(VECTORS)] + [res[2], res[0], res[2]]]
    assert [r.defective for r in res[:4]] == VERDICTS
    assert margins[-3:] == [margins[2], margins[0], margins[2]]
    n_def = sum(r.defective for r in res)
    assert calls[-1] == (len(U), len(U), n_def)
    assert stats["variants"] == len(U)


def test_a_process_pool_starts_its_workers_at_once(monkeypatch):
    """Every worker starts (and imports the library's hot modules) as the pool
    is made, not at the first task; the warm-up tasks are the modules'
    imports."""
    seen = []
    real = executors._warm_up

    def spy(ex, workers):
        seen.append(workers)
        real(ex, workers)

    monkeypatch.setattr(executors, "_warm_up", spy)
    with make_executor("process", 2) as ex:
        assert seen == [2]
        assert len(ex._processes) == 2        # started before any task of ours
        assert ex.submit(executors._import_modules, executors.WARM_MODULES).result() is None
    with make_executor("serial") as ex:
        assert seen == [2]                    # nothing to start


def test_a_pool_whose_workers_stopped_is_a_typed_error():
    """``BrokenProcessPool`` (a script without the ``__main__`` guard, a worker
    killed for memory) reaches the caller as a WorkerError that names the
    likely cause and what to do."""
    from concurrent.futures import Future
    from concurrent.futures.process import BrokenProcessPool

    from cspace.errors import CSpaceError, WorkerError

    class Broken(ThreadPoolExecutor):
        def submit(self, fn, *args, **kwargs):
            f = Future()
            f.set_exception(BrokenProcessPool("terminated abruptly"))
            return f

    with Broken(1) as ex, pytest.raises(WorkerError) as e:
        executors.run_ordered(ex, max, [(1, 2), (3, 4)])
    assert isinstance(e.value, CSpaceError) and isinstance(e.value, RuntimeError)
    assert "BrokenProcessPool: terminated abruptly" in str(e.value)
    assert 'if __name__ == "__main__":' in str(e.value)
    assert 'executor=SerialExecutor()' in str(e.value)
    import pickle
    assert str(pickle.loads(pickle.dumps(e.value))) == str(e.value)


def _held(model, acc, d):
    """In a worker: what its reference cache holds for the design (its
    private caches' names), or None."""
    got = executors._REFS.get(design_key(model, acc, d))
    return None if got is None else sorted(k for k in vars(got) if k.startswith("_"))


def _gc_thresholds():
    import gc
    return gc.get_threshold()


def test_a_pool_worker_collects_garbage_less_often(monkeypatch):
    """A worker's collector runs at WORKER_GC_THRESHOLDS (CSPACE_GC=0: as
    Python sets it); the caller's own is left alone."""
    import gc
    mine = gc.get_threshold()
    with make_executor("process", 1) as ex:
        assert ex.submit(_gc_thresholds).result() == executors.WORKER_GC_THRESHOLDS
    assert gc.get_threshold() == mine
    monkeypatch.setenv("CSPACE_GC", "0")
    with make_executor("process", 1) as ex:
        assert ex.submit(_gc_thresholds).result() == (700, 10, 10)


def test_a_shared_reference_reaches_the_worker_without_its_caches(model, ref):
    """share_reference hands a process pool's worker the caller's Reference:
    its cache holds it (the worker builds none), without what the caller
    cached on it (its path plans), and the caller's keeps them."""
    from cspace.batch.margins import plans_of
    plans_of(ref)                                 # cached on the caller's Reference
    assert "_plans" in vars(ref)
    with make_executor("process", 1) as ex:
        assert ex.submit(_held, model, ACC, ref.d).result() is None
        executors.share_reference(ex, model, ACC, ref.d, ref)
        assert ex.submit(_held, model, ACC, ref.d).result() == []
    assert "_plans" in vars(ref)


def test_sharing_a_reference_does_nothing_off_a_process_pool(monkeypatch, model, ref):
    monkeypatch.setattr(executors, "_REFS", OrderedDict())
    executors.share_reference(SerialExecutor(), model, ACC, ref.d, ref)
    executors.share_reference(None, model, ACC, ref.d, ref)
    assert not executors._REFS


def _stops_at_three(k):
    if k == 3:
        raise KeyboardInterrupt
    return k * k


def test_a_serial_run_keeps_each_result_as_its_task_ends():
    """A serial executor runs a task as it is submitted: its result is kept
    and reported then, so that an interrupt in a later task (Ctrl-C in a long
    serial yield estimate) loses none of the tasks before it."""
    kept, ticks = {}, []
    with pytest.raises(KeyboardInterrupt):
        run_ordered(SerialExecutor(), _stops_at_three, [(k,) for k in range(6)],
                    progress=lambda i, n: ticks.append((i, n)),
                    on_result=lambda i, r: kept.update({i: r}))
    assert kept == {0: 0, 1: 1, 2: 4}
    assert ticks == [(1, 6), (2, 6), (3, 6)]
    # uninterrupted: every result, in order, each reported once
    kept.clear()
    ticks.clear()
    out = run_ordered(SerialExecutor(), pow, [(k, 2) for k in range(4)],
                      progress=lambda i, n: ticks.append(i),
                      on_result=lambda i, r: kept.update({i: r}))
    assert out == [0, 1, 4, 9] and kept == {0: 0, 1: 1, 2: 4, 3: 9} and ticks == [1, 2, 3, 4]


def test_a_model_that_cannot_reach_the_workers_is_a_typed_error():
    """A builder defined as a lambda cannot be pickled: on a process pool (or
    the pool a run makes by default) synthesize, monte_carlo and
    yield_estimate say so and what to do before any work; a serial run
    takes it."""
    import dataclasses

    from synthesis import monte_carlo, synthesize, yield_estimate
    from synthesis.executors import check_sendable

    from ..cspace.batch.yoke import build_yoke
    m = dataclasses.replace(yoke(deviation=1.0), builder=lambda v: build_yoke(v))
    with make_executor("process", 1) as ex:
        for run in (lambda: synthesize(m, "fast", executor=ex, max_iter=1),
                    lambda: monte_carlo(m, 10, seed=1, accuracy="fast", executor=ex),
                    lambda: yield_estimate(m, 10, seed=1, accuracy="fast", executor=ex)):
            with pytest.raises(InputError, match="cannot be sent to the worker processes.*"
                                                 "SerialExecutor"):
                run()
    with pytest.raises(InputError, match="cannot be sent"):
        check_sendable(None, m)
    check_sendable(SerialExecutor(), m)
    check_sendable(None, yoke(), None)
    assert synthesize(m, "fast", executor=SerialExecutor(), max_iter=1).nit == 1
