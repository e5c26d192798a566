"""Progress reporting of the synthesis loop: silent, a log, or a bar.

The loop calls ``begin(iteration)``, ``task(phase, done, total, defective=None)``
and ``end(record)``; :func:`progress_for` picks a bar on a terminal and a log
otherwise.  Output goes to stderr.

Off a terminal (CI, ``nohup``, a notebook) the log prints one line per
iteration and, while a phase runs, one line per batch of finished tests at most
every ``interval`` seconds (10 s by default)::

    iteration 1 defect tests: 310/622 tests (50 %), 41 defective so far, 2 min 5 s elapsed, ETA 2 min 6 s

``defective`` is the number of defective vectors among the finished tests; it
is shown when the caller passes it.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress", "LogProgress", "BarProgress", "progress_for", "duration"]


def duration(seconds: float) -> str:
    """``75.2`` -> ``"1 min 15 s"``: a span for a log line."""
    s = int(round(max(seconds, 0.0)))
    if s < 60:
        return f"{s} s"
    m, s = divmod(s, 60)
    if m < 60:
        return f"{m} min {s} s"
    h, m = divmod(m, 60)
    return f"{h} h {m} min"


class Progress:
    """Reports nothing."""

    def begin(self, iteration: int) -> None:
        pass

    def task(self, phase: str, done: int, total: int, defective: int | None = None) -> None:
        pass

    def end(self, record) -> None:
        pass

    def note(self, text: str) -> None:
        pass


class LogProgress(Progress):
    """One line per iteration, and a line per batch of tests at most every
    ``interval`` seconds while a phase runs (for logs and pipes).

    Parameters
    ----------
    stream : file, optional
        Default stderr.
    interval : float
        Seconds between two lines of one phase (s); the last batch of a phase
        that printed a line is always printed, so the log ends at 100 %.
    clock : callable, optional
        ``clock() -> seconds`` (default ``time.monotonic``; tests pass a fake).
    """

    def __init__(self, stream=None, interval: float = 10.0, clock=None):
        self.stream = stream or sys.stderr
        self.interval = float(interval)
        self.clock = clock or time.monotonic
        self.iteration = 0
        self._phase = None
        self._t_iter = self._t_line = None
        self._t_phase, self._d_phase = 0.0, 0
        self._printed = False

    def begin(self, iteration: int | None) -> None:
        """A new iteration (None: a phase outside the iterations, such as the
        final Monte Carlo check, whose lines name no iteration)."""
        self.iteration = iteration
        self._phase = None
        self._t_iter = self._t_line = self.clock()

    def _where(self) -> str:
        """``"iteration N "``, or "" outside the iterations."""
        return "" if self.iteration is None else f"iteration {self.iteration} "

    def _track(self, phase, done):
        """Note the start of a new phase (time and tests done then)."""
        now = self.clock()
        if phase != self._phase:
            self._phase, self._t_phase, self._d_phase, self._printed = phase, now, done, False
            if self._t_iter is None:
                self._t_iter = self._t_line = now
        return now

    def _eta(self, now, done, total):
        """Seconds left in this phase at the rate measured since it began."""
        rate = (done - self._d_phase) / max(now - self._t_phase, 1e-9)
        return (total - done) / rate if rate > 0 and done < total else None

    def task(self, phase: str, done: int, total: int, defective: int | None = None) -> None:
        now = self._track(phase, done)
        last = total > 0 and done >= total
        # a line when the log has been silent for an interval (also at the first
        # report of a phase after a long silent stage), and the closing one
        if not (now - self._t_line >= self.interval or (last and self._printed)):
            return
        self._t_line, self._printed = now, True
        self._line(self.status(phase, done, total, defective, now - self._t_iter,
                               self._eta(now, done, total)))

    def status(self, phase, done, total, defective, elapsed, eta=None) -> str:
        """``iteration 1 defect tests: 310/622 tests (50 %), ...`` (one log line;
        ``elapsed`` counts from the start of the iteration)."""
        pct = f" ({100.0 * done / total:.0f} %)" if total else ""
        text = f"{self._where()}{phase}: {done}/{total} tests{pct}"
        if defective is not None:
            text += f", {defective} defective so far"
        text += f", {duration(elapsed)} elapsed"
        if eta is not None:
            text += f", ETA {duration(eta)}"
        return text

    def _line(self, text):
        print(text, file=self.stream, flush=True)
        if self._t_line is not None:
            self._t_line = self.clock()

    def end(self, record) -> None:
        c = record.counts
        shift = int((record.shift != 0).sum())
        why = [f"{k.lower()} {v}" for k, v in sorted(record.reasons.items(),
                                                    key=lambda kv: (-kv[1], kv[0]))]
        why = ", ".join(why)
        if sum(record.reasons.values()) > record.n_defects:
            why += "; a vector may have several reasons"
        if c.get("two_sided"):
            why += f"; {c['two_sided']} also at the mirror"
        self._line(f"iteration {record.iteration}: check list {c.get('seeds', 0)} seeds -> "
                   f"{c.get('checklist', 0)} vectors, {record.n_defects} defective"
                   f"{f' ({why})' if why else ''}, "
                   f"{shift} parameter(s) shifted, {len(record.shrinks)} shrink(s)"
                   f"{', cycle refused' if record.cycle else ''} "
                   f"({record.times.get('total', 0.0):.1f} s)")

    def note(self, text: str) -> None:
        self._line(text)


class BarProgress(LogProgress):
    """A one-line bar per phase, redrawn in place (terminals)."""

    WIDTH = 28

    def __init__(self, stream=None, clock=None):
        super().__init__(stream, interval=0.1, clock=clock)
        self._last = -1e300

    def task(self, phase: str, done: int, total: int, defective: int | None = None) -> None:
        now = self._track(phase, done)
        if done < total and now - self._last < self.interval:
            return
        self._last = now
        frac = done / total if total else 1.0
        n = int(round(frac * self.WIDTH))
        bar = "#" * n + "-" * (self.WIDTH - n)
        extra = f", {defective} defective" if defective is not None else ""
        eta = self._eta(now, done, total)
        if eta is not None:
            extra += f", ETA {duration(eta)}"
        self.stream.write(f"\r[{bar}] {self._where()}{phase} {done}/{total}{extra}\x1b[K")
        self.stream.flush()
        if done >= total and self.iteration is None:
            # outside the iterations no iteration line follows to clear it
            self.stream.write("\r\x1b[K")

    def _line(self, text):
        self.stream.write("\r\x1b[K")
        super()._line(text)


def progress_for(stream=None) -> Progress:
    """A bar when ``stream`` (default stderr) is a terminal, else a log with a
    line per batch of tests at most every 10 s."""
    stream = stream or sys.stderr
    isatty = getattr(stream, "isatty", None)
    return BarProgress(stream) if isatty is not None and isatty() else LogProgress(stream)
