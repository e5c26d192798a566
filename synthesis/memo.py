"""The defect tests of the iteration in progress, kept so that a stopped run
resumes inside its iteration.

Every defect test of a synthesis run compares a vector with the *initial*
design at one accuracy and one d (:mod:`synthesis.loop`, "The design
intent"), so its result depends on the vector alone.  :class:`TestMemo` keeps
the results of one iteration by the vector's exact bits; the loop runs every
batch of tests through it (:func:`synthesis.executors.run_batched`, ``memo``),
and hands its content to a callback at most every ``every`` seconds, where the
command line writes the checkpoint (:class:`~synthesis.result.PartialIteration`
in :attr:`SynthesisState.partial`).

A resumed run replays the iteration: the reference, the zones, the check list
and the search are computed again (they are deterministic), and every vector
found in the memo takes its stored result instead of being tested.  The
search's state (bisection intervals, refinement rounds) is recovered by that
replay, so the resumed iteration is the uninterrupted one.
"""

from __future__ import annotations

import time

import numpy as np

from .result import PartialIteration

__all__ = ["TestMemo", "DEFAULT_CHECKPOINT_EVERY"]

#: Seconds between checkpoints written within an iteration (``synthesize``,
#: ``checkpoint_every``; ``cspace-tol synthesize --checkpoint-every``).
DEFAULT_CHECKPOINT_EVERY = 30.0


class TestMemo:
    """Results of the finished defect tests of one iteration.

    Parameters
    ----------
    iteration : int
        The iteration (1-based).
    nominal, tol : (n,) float
        Its design.
    save : callable, optional
        ``save(partial)`` with a :class:`PartialIteration`; called by
        :meth:`tick` at most every ``every`` seconds and by :meth:`flush`.
    every : float
        Seconds between saves (0: after every finished batch of tests).
    partial : PartialIteration, optional
        Tests of this iteration already finished (a resumed run).
    """

    __test__ = False      # not a pytest class, despite the name

    def __init__(self, iteration: int, nominal, tol, save=None,
                 every: float = DEFAULT_CHECKPOINT_EVERY, partial: PartialIteration | None = None):
        self.iteration = int(iteration)
        self.nominal = np.array(nominal, dtype=float)
        self.tol = np.array(tol, dtype=float)
        self._save = save
        self.every = float(every)
        self._entries: dict = {}
        self.hits = 0
        self._resumed: set = set()
        self._reused: set = set()
        if partial is not None:
            for u, r, c, m in partial.tests:
                self._entries[_key(u)] = (np.array(u, dtype=float), r, bool(c), float(m))
            self._resumed = set(self._entries)
        self._last = time.monotonic()
        self._saved = len(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self):
        return (f"<TestMemo iteration {self.iteration}: {len(self)} test(s), {self.hits} "
                f"reused>")

    @property
    def reused(self) -> int:
        """Tests of the resumed checkpoint that this run has asked for (each
        once; :attr:`hits` counts every lookup that found a test, those of
        this run's own tests asked for again included)."""
        return len(self._reused)

    def get(self, u):
        """``(result, certified, margin)`` of vector ``u`` if it was tested, else
        None."""
        key = _key(u)
        hit = self._entries.get(key)
        if hit is None:
            return None
        self.hits += 1
        if key in self._resumed:
            self._reused.add(key)
        return hit[1], hit[2], hit[3]

    def put(self, u, result, certified: bool, margin: float = float("nan")) -> None:
        """Keep the result of one finished test (one dict insertion: an
        interrupt cannot leave half an entry); ``margin`` is its search margin
        (:func:`synthesis.executors.search_margin`, NaN when unknown)."""
        u = np.array(u, dtype=float)
        self._entries[_key(u)] = (u, result, bool(certified), float(margin))

    def partial(self) -> PartialIteration:
        """The finished tests as a checkpoint value."""
        return PartialIteration(self.iteration, self.nominal, self.tol,
                                tuple(self._entries.values()))

    def tick(self) -> None:
        """Save when ``every`` seconds have passed since the last save and there
        is something new."""
        if (self._save is not None and len(self._entries) > self._saved
                and time.monotonic() - self._last >= self.every):
            self.flush()

    def commit(self) -> None:
        """The iteration is over: its record is about to be written (the loop's
        ``on_iteration``).  From now on nothing is saved, so that a stop that
        arrives while the record is being written cannot overwrite it with the
        state from before the iteration."""
        self._save = None

    def flush(self) -> None:
        """Save now (when a saver was given and the iteration is not committed)."""
        if self._save is None:
            return
        n = len(self._entries)
        self._save(self.partial())
        self._saved = n
        self._last = time.monotonic()


def _key(u) -> bytes:
    return np.ascontiguousarray(u, dtype=float).tobytes()
