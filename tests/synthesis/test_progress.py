"""Progress reporting: the log line says how many vectors are defective and why."""

import io
from types import SimpleNamespace

import numpy as np

from synthesis.progress import BarProgress, LogProgress, progress_for


def _record(**kw):
    base = dict(iteration=1, counts={"seeds": 96, "checklist": 622}, n_defects=285,
                reasons={"DEVIATION": 122, "TOPOLOGY": 192}, shift=np.array([0.0, 0.1, -0.2]),
                shrinks=({},) * 17, cycle=True, times={"total": 296.14})
    base.update(kw)
    return SimpleNamespace(**base)


def test_log_line_states_reasons_and_mirrors():
    out = io.StringIO()
    LogProgress(out).end(_record(counts={"seeds": 96, "checklist": 622, "two_sided": 146}))
    assert out.getvalue() == (
        "iteration 1: check list 96 seeds -> 622 vectors, 285 defective (topology 192, "
        "deviation 122; a vector may have several reasons; 146 also at the mirror), "
        "2 parameter(s) shifted, 17 shrink(s), cycle refused (296.1 s)\n")
    out = io.StringIO()
    LogProgress(out).end(_record(n_defects=0, reasons={}, shift=np.zeros(3), shrinks=(),
                                 cycle=False, counts={"seeds": 96, "checklist": 630,
                                                      "two_sided": 0}))
    assert out.getvalue() == ("iteration 1: check list 96 seeds -> 630 vectors, 0 defective, "
                              "0 parameter(s) shifted, 0 shrink(s) (296.1 s)\n")


def test_bar_on_a_terminal_log_otherwise():
    class Tty(io.StringIO):
        def isatty(self):
            return True
    tty = Tty()
    bar = progress_for(tty)
    assert isinstance(bar, BarProgress)
    bar.begin(2)
    bar.task("defect tests", 5, 10)
    bar.end(_record(iteration=2))
    text = tty.getvalue()
    assert "iteration 2 defect tests 5/10" in text and "\r\x1b[K" in text
    assert text.endswith("cycle refused (296.1 s)\n")
    plain = progress_for(io.StringIO())
    assert type(plain) is LogProgress


class _Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_log_off_a_terminal_reports_batches_at_a_bounded_rate():
    out, clock = io.StringIO(), _Clock()
    log = LogProgress(out, interval=10.0, clock=clock)
    log.begin(1)
    clock.t = 100.0                      # reference and zones took 100 s
    for done in range(1, 601):           # one test finishes every 0.5 s
        clock.t += 0.5
        log.task("defect tests", done, 600, defective=done // 10)
    lines = out.getvalue().splitlines()
    # the first test after 100 silent seconds, then one line per 10 s of the
    # 300 s of tests, and the closing 100 % line
    assert 30 <= len(lines) <= 33
    assert lines[0] == ("iteration 1 defect tests: 1/600 tests (0 %), 0 defective so far, "
                        "1 min 40 s elapsed")
    assert lines[1] == ("iteration 1 defect tests: 21/600 tests (4 %), 2 defective so far, "
                        "1 min 50 s elapsed, ETA 4 min 50 s")
    # no two lines closer than the interval, except the closing one
    assert all("ETA" in ln for ln in lines[1:-1])
    assert lines[-1].startswith("iteration 1 defect tests: 600/600 tests (100 %), "
                                "60 defective so far, 6 min 40 s elapsed")
    assert "ETA" not in lines[-1]
    # a short phase prints nothing (no clutter below the interval)
    out2 = io.StringIO()
    quick = LogProgress(out2, clock=_Clock())
    quick.begin(1)
    for done in range(1, 11):
        quick.task("defect tests", done, 10)
    assert out2.getvalue() == ""
    # phases that only announce themselves (a bisection batch) still break a silence
    out3, c3 = io.StringIO(), _Clock()
    search = LogProgress(out3, clock=c3)
    search.begin(2)
    for s in range(4):
        c3.t += 12.0
        search.task(f"search batch {s + 1}", 0, 45)
    assert out3.getvalue().splitlines()[-1] == ("iteration 2 search batch 4: 0/45 tests (0 %), "
                                                "48 s elapsed")


def test_bar_shows_defective_and_eta():
    class Tty(io.StringIO):
        def isatty(self):
            return True
    clock = _Clock()
    bar = BarProgress(Tty(), clock=clock)
    bar.begin(1)
    bar.task("defect tests", 1, 100, defective=0)
    clock.t = 10.0
    bar.task("defect tests", 11, 100, defective=3)
    assert bar.stream.getvalue().endswith(
        "iteration 1 defect tests 11/100, 3 defective, ETA 1 min 29 s\x1b[K")


def test_duration():
    from synthesis.progress import duration
    assert [duration(x) for x in (0.4, 59.6, 75, 3725)] == ["0 s", "1 min 0 s", "1 min 15 s",
                                                             "1 h 2 min"]


def test_synthesize_refuses_a_progress_that_is_not_one():
    """A plain function given as ``progress`` (or a non-callable
    ``on_iteration``) is a typed error before the run starts, naming what a
    Progress needs, not an AttributeError on its first note."""
    import pytest

    from cspace.errors import InputError
    from mechanisms.models import reciprocating_cam
    from synthesis import SerialExecutor, synthesize
    from synthesis.progress import Progress
    m = reciprocating_cam()
    with pytest.raises(InputError, match=r"progress must be a synthesis.progress.Progress.*"
                                         r"has no begin, task, end, note"):
        synthesize(m, "fast", executor=SerialExecutor(), progress=lambda *a: None)
    with pytest.raises(InputError, match="on_iteration must be callable"):
        synthesize(m, "fast", executor=SerialExecutor(), on_iteration=3)

    class Phases(Progress):
        def task(self, phase, done, total, defective=None):
            seen.add(phase.split()[0])

    seen: set = set()
    synthesize(m, "fast", executor=SerialExecutor(), progress=Phases(), max_iter=1)
    assert "defect" in seen
