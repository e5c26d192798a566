"""Progress reporting of the synthesis loop: silent, a quiet log, or a bar.

The loop calls ``begin(iteration)``, ``task(phase, done, total)`` and
``end(record)``; :func:`progress_for` picks a bar on a terminal and one log line
per iteration otherwise.  Output goes to stderr.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress", "LogProgress", "BarProgress", "progress_for"]


class Progress:
    """Reports nothing."""

    def begin(self, iteration: int) -> None:
        pass

    def task(self, phase: str, done: int, total: int) -> None:
        pass

    def end(self, record) -> None:
        pass

    def note(self, text: str) -> None:
        pass


class LogProgress(Progress):
    """One line per iteration (for logs and pipes)."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr

    def _line(self, text):
        print(text, file=self.stream, flush=True)

    def end(self, record) -> None:
        c = record.counts
        shift = int((record.shift != 0).sum())
        why = [f"{k.lower()} {v}" for k, v in sorted(record.reasons.items(),
                                                    key=lambda kv: (-kv[1], kv[0]))]
        why = ", ".join(why)
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

    def __init__(self, stream=None):
        super().__init__(stream)
        self.iteration = 0
        self._last = 0.0

    def begin(self, iteration: int) -> None:
        self.iteration = iteration

    def task(self, phase: str, done: int, total: int) -> None:
        now = time.monotonic()
        if done < total and now - self._last < 0.1:
            return
        self._last = now
        frac = done / total if total else 1.0
        n = int(round(frac * self.WIDTH))
        bar = "#" * n + "-" * (self.WIDTH - n)
        self.stream.write(f"\r[{bar}] iteration {self.iteration} {phase} {done}/{total}\x1b[K")
        self.stream.flush()

    def _line(self, text):
        self.stream.write("\r\x1b[K")
        super()._line(text)


def progress_for(stream=None) -> Progress:
    """A bar when ``stream`` (default stderr) is a terminal, else a quiet log."""
    stream = stream or sys.stderr
    isatty = getattr(stream, "isatty", None)
    return BarProgress(stream) if isatty is not None and isatty() else LogProgress(stream)
