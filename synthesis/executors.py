"""Running defect tests on any :class:`concurrent.futures.Executor`.

The unit of work is :func:`defect_task`, a pure function of (model, vector,
accuracy, d) that returns a :class:`cspace.defects.DefectResult`.  Each worker
process builds the nominal :class:`cspace.defects.Reference` of a design once
and keeps it (a small LRU keyed by the design's values), so only the model and
one vector travel with a task.

Executors
---------
``process`` (default)
    :class:`concurrent.futures.ProcessPoolExecutor` with one worker per CPU
    (``os.process_cpu_count``/``os.cpu_count``).  Workers ignore SIGINT so that
    Ctrl-C reaches only the main process, which cancels the pool cleanly.
    Workers end when the main process dies, even by SIGKILL
    (:func:`_exit_with_parent`).
``serial``
    :class:`SerialExecutor`: runs each task at submission, in the caller.
``dask``
    ``distributed.Client(address).get_executor()`` (extra ``dask``).

Results never depend on the executor, the worker count or the completion order:
:func:`run_ordered` collects them by submission index.
"""

from __future__ import annotations

import contextlib
import copy
import os
import signal
import threading
from collections import OrderedDict
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed

import numpy as np

from cspace.argcheck import getint
from cspace.errors import InputError, MissingExtraError, cancelled_on_failure

__all__ = ["SerialExecutor", "make_executor", "run_ordered", "defect_task", "search_task",
           "batch_task", "margins_task", "run_batched", "BatchStats", "design_key",
           "share_reference", "cached_reference", "margin_rows", "check_executor",
           "check_sendable",
           "check_executor_kind",
           "search_margin",
           "remember_reference", "EXECUTORS"]

EXECUTORS = ("process", "serial", "dask")

_REFS: OrderedDict = OrderedDict()
_REFS_MAX = 3
#: A process pool larger than this many workers per CPU is refused.
MAX_WORKERS_PER_CPU = 4
_LOCK = threading.Lock()


class SerialExecutor(Executor):
    """Runs every task when it is submitted (debugging, small jobs)."""

    def submit(self, fn, /, *args, **kwargs):
        f = Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as e:  # noqa: BLE001 - re-raised by result()
            if isinstance(e, (KeyboardInterrupt, SystemExit)):
                raise
            f.set_exception(e)
        return f


def design_key(model, accuracy, d) -> tuple:
    """What identifies a nominal Reference: the design's values and settings."""
    return (model.name, model.units, tuple(model.names), model.nominal.tobytes(),
            model.tol.tobytes(), repr(model.window), repr(model.drive),
            repr(model.q2_start), accuracy, float(d))


def remember_reference(model, accuracy, d, ref) -> None:
    """Store an already computed Reference in this process's cache."""
    with _LOCK:
        _REFS[design_key(model, accuracy, d)] = ref
        while len(_REFS) > _REFS_MAX:
            _REFS.popitem(last=False)


def cached_reference(model, accuracy, d):
    """The nominal :class:`cspace.defects.Reference` of a design for the tasks
    of this process: taken from the process's small LRU cache (keyed by
    :func:`design_key`) when there, else built by
    :func:`cspace.defects.reference` and remembered
    (:func:`remember_reference`), so that a worker builds each design's
    Reference once however many tasks it runs."""
    from cspace.defects import reference
    key = design_key(model, accuracy, d)
    with _LOCK:
        ref = _REFS.get(key)
        if ref is not None:
            _REFS.move_to_end(key)
            return ref
    ref = reference(model, accuracy, d)
    remember_reference(model, accuracy, d, ref)
    return ref


def share_reference(executor, model, accuracy, d, ref) -> None:
    """Hand a Reference this process built to every worker of a process pool
    (:func:`remember_reference` in each), so that no worker builds it again:
    on the Geneva pair (``fast``) each worker built the initial design's in
    its first task, some 0.3 s, after the caller had built it; sent, it is
    0.2 MB.  What a process caches on a Reference as it uses it (the batch's
    path plans, 9 MB) stays behind: each worker makes its own.  Nothing
    waits for these tasks, one per worker: an idle pool's workers take one
    each; a worker still busy when another has taken them all builds its own
    when it needs it, as without them.  On another executor nothing is
    done."""
    from concurrent.futures import ProcessPoolExecutor
    if not isinstance(executor, ProcessPoolExecutor):
        return
    bare = copy.copy(ref)
    for k in [k for k in vars(bare) if k.startswith("_")]:
        del vars(bare)[k]
    for _ in range(executor_workers(executor) or 0):
        executor.submit(remember_reference, model, accuracy, d, bare)


def defect_task(model, u, accuracy, d):
    """Defect test of one vector: a pure function of its arguments.

    Parameters
    ----------
    model : mechanisms.models.Model
        The current design (nominal and tolerances).
    u : (n,) float
        The variant (model units).
    accuracy : cspace.accuracy.Accuracy
    d : float
        Output-deviation threshold (C-space metric).

    Returns
    -------
    cspace.defects.DefectResult (without the match details, which stay in the
    worker).
    """
    import dataclasses

    from cspace.defects import is_defective
    ref = cached_reference(model, accuracy, d)
    r = is_defective(model, np.asarray(u, dtype=float), ref=ref)
    return dataclasses.replace(r, matches=())


def search_task(model, u, accuracy, d, first_pair=None) -> bool:
    """Whether one vector is defective, stopping at the first defect found
    (:func:`cspace.defects.is_defective` with ``stop_early``; the same verdict
    as :func:`defect_task`).  ``first_pair``: the pair to test first.  The unit
    of work of the transition-point search, which needs only the verdict."""
    from cspace.defects import is_defective
    ref = cached_reference(model, accuracy, d)
    return bool(is_defective(model, np.asarray(u, dtype=float), ref=ref, stop_early=True,
                             first_pair=first_pair).defective)


def batch_task(model, U, accuracy, d):
    """Defect tests of a chunk of vectors in one batched pass
    (:func:`cspace.batch.margins.defect_margins`; a vector whose margins the
    batch cannot certify gets the full per-variant test in this worker).

    Returns ``(results, stats)``: one DefectResult per row of ``U`` (without
    match details) and the batch's counts, with ``certified_rows``, per row
    whether the margins decided it."""
    import dataclasses

    from cspace.batch.margins import defect_margins
    ref = cached_reference(model, accuracy, d)
    mb = defect_margins(model, np.asarray(U, dtype=float), ref)
    stats = dict(mb.stats)
    stats["certified_rows"] = [bool(c) for c in mb.certified]
    stats["margin_rows"] = [float(m) for m in search_margin(mb)]
    stats["table_rows"] = margin_rows(mb)
    return [dataclasses.replace(r, matches=()) for r in mb.results], stats


def margin_rows(mb) -> list:
    """Every margin of each row of a MarginBatch, one dict per row:
    ``"channel"``, ``"sequence"``, ``"start"`` ((P,) arrays, start NaN where
    the batch has none) and ``"deviation"`` (a float); the numbers
    :func:`synthesis.minimal.margin_sensitivities` reads of the vectors it
    differences, so that a vector the check list tested is not evaluated
    again there."""
    from .minimal import _margin_tables
    t = _margin_tables(mb)
    return [{"channel": t["channel"][v].copy(), "sequence": t["sequence"][v].copy(),
             "deviation": float(t["deviation"][v, 0]), "start": t["start"][v].copy()}
            for v in range(len(mb.defective))]


def margins_task(model, U, accuracy, d) -> np.ndarray:
    """The batched margins of a chunk of vectors without verdicts
    (:meth:`cspace.batch.margins.MarginBatch.margins`: channel, sequence and
    deviation per row), against the nominal Reference of ``model`` (kept per
    worker): what :func:`synthesis.checklist.motion_scale` reads."""
    from cspace.batch.margins import defect_margins
    ref = cached_reference(model, accuracy, d)
    return defect_margins(model, np.asarray(U, dtype=float), ref, fallback=False).margins()


def search_margin(mb) -> np.ndarray:
    """The scalar margin the transition-point search interpolates
    (:func:`synthesis.removal.transition_points`): per variant, the smaller of
    the narrowest channel margin and the deviation margin (C-space metric;
    NaN where the batch could not compute them).  Both are continuous in the
    parameters and cross zero where the drive jams or the output deviates by
    d; the sequence margin is left out, as it jumps, and so is the start
    margin (``MarginBatch.start``), which has a kink where the start sits
    midway in its channel: a start-blocked point then contradicts its margin
    and the search bisects there."""
    m = mb.margins()
    with np.errstate(invalid="ignore"):
        out = np.fmin(m[:, 0], m[:, 2])
    return np.where(np.isfinite(m[:, 0]) & np.isfinite(m[:, 2]), out, np.nan)


class BatchStats(dict):
    """Counts of batched defect tests: ``variants``, ``certified`` (decided by
    the margins), ``fallback`` (decided by the full per-variant test)."""

    def add(self, st: dict) -> None:
        for k in ("variants", "certified", "fallback"):
            self[k] = self.get(k, 0) + int(st.get(k, 0))

    def add_vector(self, certified: bool) -> None:
        """Count one vector's test (one reused from a :class:`~synthesis.memo.TestMemo`
        counts as when it was run)."""
        self.add({"variants": 1, "certified": int(bool(certified)),
                  "fallback": int(not certified)})


#: Vectors per batched task, or None: :func:`task_rows` chooses.
TASK_CHUNK = None

#: The fewest and the most vectors :func:`task_rows` gives a task.
TASK_ROWS = (32, 128)


def task_rows(n: int, workers: int | None = None) -> int:
    """Vectors per task for a batch of ``n``.

    With the executor's ``workers`` known: the batch in as few tasks as a
    multiple of the worker count allows, at most ``TASK_ROWS[1]`` vectors
    each (a batch evaluates 128 variants in one pass,
    :data:`cspace.batch.margins.CHUNK`).  A batched call costs about as much
    as 5 to 12 vectors before its first (Geneva, ``default`` and ``fast``:
    the walk over the candidate curves), so every task fewer saves that, and
    every worker gets a share: 60 vectors on two workers are two tasks of 30,
    not one of 32 and one of 28 run one after the other, nor one of 60 while
    a worker waits.
    Otherwise (unknown workers): about an eighth of the batch, within
    :data:`TASK_ROWS`.  :data:`TASK_CHUNK` fixes it.  Results do not depend on
    it."""
    if TASK_CHUNK is not None:
        return TASK_CHUNK
    lo, hi = TASK_ROWS
    if workers is None or n < 1:
        return min(hi, max(lo, -(-n // 8)))
    k = workers * -(-n // (workers * hi))
    return max(1, -(-n // min(k, n)))


def executor_workers(executor) -> int | None:
    """How many tasks ``executor`` runs at once: 1 for None or a
    :class:`SerialExecutor`, a process pool's worker count, None when it
    does not say (a dask cluster)."""
    if executor is None or isinstance(executor, SerialExecutor):
        return 1
    n = getattr(executor, "_max_workers", None)
    return n if isinstance(n, int) and n > 0 else None



def run_batched(executor, model, U, accuracy, d, progress=None, stats=None,
                memo=None, margins=None, tables=None) -> list:
    """Defect results of every row of ``U`` (in order) by :func:`batch_task`
    on ``executor``, :func:`task_rows` rows a task.  A vector's result does not
    depend on the chunk it travels in, so results are the same for any
    executor and worker count.  ``stats`` (a :class:`BatchStats`) collects
    the counts; ``progress(done, total, defective)`` counts vectors, and the
    defective ones among them, as tasks complete.

    ``memo`` (a :class:`synthesis.memo.TestMemo`): rows it holds take their
    stored result and are not tested again; the result of every finished
    task goes into it as the task completes, and the memo may then save
    itself (:meth:`~synthesis.memo.TestMemo.tick`).

    A vector repeated in ``U`` (the same bits) is tested once and its result
    given to every row that holds it: a search asks again for a vector it
    asked for under another target (a defective vector whose mirror through
    the nominal is another defective check-list vector is searched from both;
    on the Geneva pair's first iteration (``fast``), 621 of the 1,429 vectors
    the search sent to be tested, past the memo, were such repeats).

    ``margins`` (a list): filled with each row's :func:`search_margin`.
    ``tables`` (a list): filled with each row's margins (:func:`margin_rows`;
    None for a row the memo answered)."""
    for nm, v in (("margins", margins), ("tables", tables)):
        if v is not None and not isinstance(v, list):
            raise InputError(f"{nm} must be a list (filled with one entry per row) or None, "
                             f"got {type(v).__name__}", name=nm)
    U = np.asarray(U, dtype=float)
    n = len(U)
    if n == 0:
        return []
    res: list = [None] * n
    cert: list = [False] * n
    marg: list = [float("nan")] * n
    tabs: list = [None] * n
    todo = []
    first: dict = {}      # a vector's bits -> the row tested for it
    same: dict = {}       # that row -> the later rows that repeat it
    hits = 0
    for i in range(n):
        hit = memo.get(U[i]) if memo is not None else None
        if hit is not None:
            res[i], cert[i], marg[i] = hit
            hits += 1
            continue
        j = first.setdefault(U[i].tobytes(), i)
        if j == i:
            todo.append(i)
        else:
            same.setdefault(j, []).append(i)
    size = task_rows(len(todo), executor_workers(executor))
    bounds = [todo[a:a + size] for a in range(0, len(todo), size)]
    seen = {"vectors": hits,
            "defective": sum(1 for i in range(n) if res[i] is not None and res[i].defective)}

    if progress is not None and seen["vectors"]:
        progress(seen["vectors"], n, seen["defective"])

    def count(k, out):
        rows = bounds[k]
        flags = out[1].get("certified_rows", [False] * len(rows))
        ms = out[1].get("margin_rows", [float("nan")] * len(rows))
        tb = out[1].get("table_rows", [None] * len(rows))
        for i, r, c, mg, t in zip(rows, out[0], flags, ms, tb):
            for i2 in [i] + same.get(i, []):
                res[i2], cert[i2], marg[i2], tabs[i2] = r, bool(c), float(mg), t
                seen["vectors"] += 1
                seen["defective"] += int(bool(r.defective))
            if memo is not None:
                memo.put(U[i], r, c, mg)
        if memo is not None:
            memo.tick()

    def tick(i, total):
        if progress is not None:
            progress(seen["vectors"], n, seen["defective"])

    run_ordered(executor, batch_task, [(model, U[rows], accuracy, d) for rows in bounds],
                tick, count)
    if stats is not None:
        for c in cert:
            stats.add_vector(c)
    if margins is not None:
        margins[:] = marg
    if tables is not None:
        tables[:] = tabs
    return res


def _ignore_sigint():
    signal.signal(signal.SIGINT, signal.SIG_IGN)


#: Seconds between a worker's checks that its parent is still alive (where the
#: kernel cannot be asked to signal the worker when the parent dies).
PARENT_POLL = 1.0
_PR_SET_PDEATHSIG = 1


def _exit_with_parent(parent: int, pdeathsig: bool = True) -> None:
    """Make this worker process end when ``parent`` (its creator) dies.

    A killed parent (SIGKILL, out of memory) cannot shut its pool down, and
    orphaned workers would compute for minutes holding its output pipes.  On
    Linux the kernel sends SIGKILL on the parent's death (``PR_SET_PDEATHSIG``);
    everywhere a daemon thread also checks every ``PARENT_POLL`` s that the
    parent is still this process's parent.  The kernel signal follows the
    *thread* that started the worker, so ``pdeathsig`` is set only for pools
    made in the main thread (a worker started from a thread that ends would be
    killed with it); others rely on the poll.
    """
    import sys
    if os.getppid() != parent:            # died before we got here
        os._exit(1)
    if pdeathsig and sys.platform.startswith("linux"):
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no prctl: the poll remains
            pass
        if os.getppid() != parent:
            os._exit(1)

    def watch():
        import time
        while True:
            time.sleep(PARENT_POLL)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def _stop_workers(ex: ProcessPoolExecutor, grace: float = 2.0) -> None:
    """End a process pool's workers now: queued tasks are cancelled, running
    ones are abandoned (SIGTERM, then SIGKILL after ``grace`` s)."""
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        try:
            p.terminate()
        except (OSError, ValueError, AttributeError):   # already gone or closed
            pass
    for p in procs:
        try:
            p.join(grace)
            if p.is_alive():
                p.kill()
                p.join(grace)
        except (OSError, ValueError, AttributeError):
            pass


#: The garbage collector's thresholds in a pool worker (:func:`_init_worker`;
#: Python's default is (700, 10, 10)).  A batched task allocates millions of
#: short-lived small objects (the tuples, dataclasses and array views of each
#: variant's build and of each candidate curve) and holds no reference cycles
#: that need collecting soon: a collection of the youngest objects every 700
#: net allocations walked them for nothing.  On the Geneva pair's margin
#: sensitivities (``fast``, one core) the task took 3 % less time; a worker's
#: memory does not grow with it (a collection still comes every 50,000).
#: ``CSPACE_GC=0`` leaves the worker's collector as Python sets it.
WORKER_GC_THRESHOLDS = (50000, 20, 100)


def _init_worker(parent: int, pdeathsig: bool) -> None:
    """Pool worker set-up: Ctrl-C reaches only the main process, the worker
    ends with its parent, its freed arrays are reused
    (:func:`cspace.batch.heap.keep`) and its garbage collector runs less
    often (:data:`WORKER_GC_THRESHOLDS`)."""
    _ignore_sigint()
    _exit_with_parent(parent, pdeathsig)
    from cspace.batch import heap
    heap.keep()
    if os.environ.get("CSPACE_GC", "1") != "0":
        import gc
        gc.set_threshold(*WORKER_GC_THRESHOLDS)


#: The modules a pool worker imports as it starts (:func:`_warm_up`): those of
#: the defect tests, the zones and the margin sensitivities.
WARM_MODULES = ("cspace.batch.margins", "cspace.defects", "cspace.zones", "synthesis.minimal")


def _import_modules(names) -> None:
    import importlib
    for nm in names:
        importlib.import_module(nm)
    from cspace.batch import fused, fused_bounds
    fused.warm_up()
    fused_bounds.warm_up()


def _warm_up(ex, workers: int) -> None:
    """Start every worker of a fresh pool now, each importing
    :data:`WARM_MODULES` and loading the compiled batched kernel and bounds
    (:func:`cspace.batch.fused.warm_up`, :func:`cspace.batch.fused_bounds.warm_up`;
    about a second in a new interpreter), while the
    caller goes on with its own first steps (a synthesis computes the nominal
    reference first): the first tasks then find the workers ready.  Nothing
    waits for these tasks."""
    for _ in range(workers):
        ex.submit(_import_modules, WARM_MODULES)


def _cpu_count() -> int:
    f = getattr(os, "process_cpu_count", None)
    n = f() if f else None
    if not n:
        try:
            n = len(os.sched_getaffinity(0))
        except (AttributeError, OSError):
            n = os.cpu_count()
    return max(1, int(n or 1))


def check_executor_kind(kind: str, workers: int | None = None) -> int | None:
    """The executor kind and worker count of :func:`make_executor`, checked
    (a caller may check them before it starts work): the worker count, or
    None."""
    if kind not in EXECUTORS:
        raise InputError(f"executor must be one of {list(EXECUTORS)}, got {kind!r}",
                         name="executor", value=kind)
    if workers is not None:
        workers = getint(workers, "workers", minimum=1)
    if workers is not None and kind == "process" and workers > MAX_WORKERS_PER_CPU * _cpu_count():
        raise InputError(f"workers must be at most {MAX_WORKERS_PER_CPU} per CPU available "
                         f"({MAX_WORKERS_PER_CPU * _cpu_count()} here): more processes than "
                         f"that only share the same cores; got {workers}",
                         name="workers", value=workers)
    return workers


@contextlib.contextmanager
def make_executor(kind: str = "process", workers: int | None = None,
                  scheduler: str | None = None):
    """An executor as a context manager; pending work is cancelled on exit.

    Parameters
    ----------
    kind : {"process", "serial", "dask"}
    workers : int, optional
        Process-pool size (default: the CPUs available).  Ignored otherwise.
    scheduler : str, optional
        Dask scheduler address, e.g. ``tcp://10.0.0.5:8786`` (required for
        ``dask``).
    """
    workers = check_executor_kind(kind, workers)
    if kind == "serial":
        yield SerialExecutor()
        return
    if kind == "process":
        import multiprocessing
        ctx = multiprocessing.get_context("spawn")
        ex = ProcessPoolExecutor(max_workers=workers or _cpu_count(), mp_context=ctx,
                                 initializer=_init_worker,
                                 initargs=(os.getpid(), threading.current_thread()
                                           is threading.main_thread()))
        _warm_up(ex, workers or _cpu_count())
        try:
            yield ex
        except BaseException:
            # an interrupt, SIGTERM or error: the running tasks' results are not
            # wanted, and waiting for them could take minutes
            _stop_workers(ex)
            raise
        finally:
            ex.shutdown(wait=True, cancel_futures=True)
        return
    if not scheduler:
        raise InputError("the dask executor needs a scheduler address (--scheduler ADDR)",
                         name="scheduler", value=scheduler)
    try:
        from distributed import Client
    except ImportError:
        raise MissingExtraError("distributed", "dask") from None
    try:
        client = Client(scheduler)
    except (ValueError, OSError, TimeoutError) as e:
        raise InputError(f"cannot connect to the dask scheduler at {scheduler!r} "
                         f"({type(e).__name__}: {e}); expected the address of a running "
                         f"scheduler, e.g. tcp://host:8786", name="scheduler",
                         value=scheduler) from None
    try:
        yield client.get_executor()
    finally:
        client.close()


def check_executor(executor):
    """``executor`` if it is None or has ``submit`` (a
    :class:`concurrent.futures.Executor`), else an InputError that names the
    kinds :func:`make_executor` builds."""
    if executor is None or callable(getattr(executor, "submit", None)):
        return executor
    if callable(getattr(executor, "__enter__", None)):
        # make_executor(kind) itself, not the executor it gives
        raise InputError(f"executor must be a concurrent.futures.Executor or None, got a "
                         f"context manager ({executor!r}): make_executor(kind) gives the "
                         f"executor in a with statement, 'with make_executor(kind) as ex: "
                         f"... executor=ex' (it shuts a pool down at the end), or pass "
                         f"SerialExecutor() to run in this process", name="executor",
                         value=executor)
    raise InputError(f"executor must be a concurrent.futures.Executor or None, got "
                     f"{executor!r}; for one of {list(EXECUTORS)} use 'with "
                     f"make_executor(kind) as ex: ... executor=ex', or SerialExecutor() to "
                     f"run in this process", name="executor", value=executor)


def check_sendable(executor, *models) -> None:
    """An InputError when a model cannot travel to the worker processes of a
    process pool (``executor``, or None: the pool a run makes by default):
    a builder defined as a lambda or inside a function cannot be pickled,
    and the first task would fail with pickle's own message."""
    from concurrent.futures import ProcessPoolExecutor
    if executor is not None and not isinstance(executor, ProcessPoolExecutor):
        return
    import pickle
    for m in models:
        if m is None:
            continue
        try:
            pickle.dumps(m)
        except Exception as e:      # noqa: BLE001 - pickle raises several kinds
            raise InputError(
                f"the model {getattr(m, 'name', '')!r} cannot be sent to the worker "
                f"processes ({type(e).__name__}: {e}): a process pool needs a builder "
                f"defined at the top level of a module it can import, not a lambda or a "
                f"function defined inside another; define it so, or run in this process "
                f"with executor=SerialExecutor() (on the command line, --executor "
                f"serial)", name="model") from None


def run_ordered(executor: Executor, fn, argsets, progress=None, on_result=None) -> list:
    """``[fn(*a) for a in argsets]`` on ``executor``, results in submission order.

    ``progress(done, total)`` is called as tasks complete, after
    ``on_result(index, result)``.  An exception (or an interrupt) cancels the
    tasks not yet started and propagates.
    """
    argsets = list(argsets)
    total = len(argsets)
    futures = []
    out: list = [None] * total
    handled: set = set()

    def handle(i, f):
        out[i] = f.result()
        handled.add(i)
        if on_result is not None:
            on_result(i, out[i])
        if progress is not None:
            progress(len(handled), total)

    with cancelled_on_failure(futures):
        for a in argsets:
            f = executor.submit(fn, *a)
            futures.append(f)
            if f.done():
                # an executor that runs a task as it is submitted (the serial
                # one): its result is kept (and reported) now, so that an
                # interrupt of a later task does not lose it
                handle(len(futures) - 1, f)
        where = {id(f): i for i, f in enumerate(futures)}
        for f in as_completed(futures):
            i = where[id(f)]
            if i not in handled:
                handle(i, f)
    return out
