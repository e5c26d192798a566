"""How a ``synthesize`` run stops on SIGINT and SIGTERM.

The first SIGINT (Ctrl-C, or ``kill -INT`` to the main process alone) raises
``KeyboardInterrupt`` in the main thread, the first SIGTERM the run's
``terminated`` exception: the run cancels its pool (the workers are ended, not
waited for), keeps the checkpoint of its last finished iteration and exits with
status 130 (SIGINT) or 143 (SIGTERM).

Winding down must not hang: an interrupt that lands inside the pool's own
book-keeping could leave a lock held.  So the first signal also arms a timer:
if the run has not wound down within :data:`HARD_EXIT_AFTER` seconds, or a
second signal arrives, the process ends at once with the same status.  The
checkpoint is still valid then, since it is only ever replaced by an atomic
rename; the workers end with their parent (:mod:`synthesis.executors`).
"""

from __future__ import annotations

import os
import signal
import sys
import threading

__all__ = ["StopSignals", "HARD_EXIT_AFTER", "STATUS"]

#: Seconds a run may take to wind down after its first SIGINT or SIGTERM.
HARD_EXIT_AFTER = 8.0

#: Exit status per signal (128 + the signal number, as a shell reports it).
STATUS = {signal.SIGINT: 130, signal.SIGTERM: 143}


class StopSignals:
    """SIGINT and SIGTERM handlers for one run (install, then restore).

    Parameters
    ----------
    terminated : type
        Exception raised on SIGTERM (SIGINT raises ``KeyboardInterrupt``).
    after : float
        Seconds until a hard exit once the first signal arrived.
    """

    def __init__(self, terminated: type, after: float = HARD_EXIT_AFTER):
        self.terminated = terminated
        self.after = after
        self._old = {}
        self._timer = None

    def install(self) -> "StopSignals":
        for s in STATUS:
            self._old[s] = signal.signal(s, self._handle)
        return self

    def restore(self) -> None:
        """Put the previous handlers back and disarm the timer (the run wound
        down in time)."""
        for s, h in self._old.items():
            signal.signal(s, h)
        self._old = {}
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _handle(self, signum, frame):
        status = STATUS.get(signum, 128 + signum)
        if self._timer is not None:          # a second signal: stop now
            _hard_exit(status, "second signal")
        self._timer = threading.Timer(self.after, _hard_exit,
                                      (status, f"not wound down {self.after:g} s after the "
                                               f"signal"))
        self._timer.daemon = True
        self._timer.start()
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise self.terminated()


def _hard_exit(status: int, why: str) -> None:
    try:
        sys.stderr.write(f"stopped hard ({why}); the checkpoint holds the last finished "
                         f"iteration, if any\n")
        sys.stderr.flush()
    except Exception:  # noqa: BLE001 - nothing may keep the process alive here
        pass
    os._exit(status)
