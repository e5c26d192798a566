"""Result objects show their numbers in ``repr`` (issue 24)."""

import math
import re

import numpy as np

NUM = re.compile(r"-?\d+\.\d+|\d+")


def _numbers(text):
    return [float(x) for x in NUM.findall(text)]


def test_comparison_table_repr_shows_the_values():
    from mechanisms.manipulators.design import comparison_table, design
    t = comparison_table(design("2-PaP", 1.0, 60, unit="deg"),
                         design("2-PPa", 1.0, 30, unit="deg"), gdi_grid=7)
    r = repr(t)
    assert "rows=" not in r
    for name, vals in t.rows:
        line = next(ln for ln in r.splitlines() if ln.strip().startswith(name))
        for v in vals:
            if isinstance(v, float):
                assert f"{v:.3g}" in line, (name, v)


def test_closed_form_repr_shows_ranges():
    from mechanisms.linkage import FourBar
    from mechanisms.linkage.error import clearance_b_closed_form
    fb = FourBar.from_lengths(13.55, 8.0, 5.25, 13.3, lp=3.816, alpha=38.0,
                              assembly="crossed", unit="deg")
    beta = np.linspace(0, 2 * np.pi, 13) + math.radians(72) + math.pi
    cf = clearance_b_closed_form(fb, math.radians(72), beta)
    r = repr(cf)
    assert f"{cf.omega3.min():.4g}" in r and f"{cf.omega4.max():.4g}" in r


def test_simulation_and_state_reprs_show_numbers():
    from mechanisms.analysis import motion_at
    from mechanisms.models import reciprocating_cam
    from synthesis.loop import initial_state
    m = reciprocating_cam()
    _, (sim,) = motion_at(m, accuracy="fast")
    r = repr(sim)
    assert f"output {sim.q2[0]:.6g} -> {sim.q2[-1]:.6g}" in r
    st, _ = initial_state(m, "fast", 0.04)
    r = repr(st)
    assert r.startswith("<SynthesisState 'reciprocating_cam': RUNNING after 0 iteration(s)")
    assert "d = 0.04" in r and "e = 0" in r


def test_monte_carlo_repr():
    from synthesis.verify import MonteCarloResult
    r = repr(MonteCarloResult(20, 10, (1, 4), {"JAM": 2}, np.zeros((20, 3)), 7))
    assert "2/20 defective" in r and "seed 7" in r
