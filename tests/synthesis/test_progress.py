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
        "deviation 122; 146 also at the mirror), 2 parameter(s) shifted, 17 shrink(s), "
        "cycle refused (296.1 s)\n")
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
