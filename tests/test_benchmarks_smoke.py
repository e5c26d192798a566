"""Smoke test of the C-space benchmark script: its measurement functions run at
minimal sizes and return finite figures.  No timing target is asserted here."""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_cspace.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_cspace", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def geneva_fast(bench):
    from mechanisms.models import geneva
    m = geneva()
    pair = m.build()
    t, times, cs = bench.time_cspace(pair, "fast", m.window, m.dependencies()[0],
                                     repeat=1, warmup=0)
    return m, pair, t, times, cs


def test_timing_and_accuracy(bench, geneva_fast):
    m, pair, t, times, cs = geneva_fast
    assert len(times) == 1 and math.isfinite(t) and t > 0
    acc = bench.boundary_accuracy(cs, cs)
    for key in ("polyline", "polyline_mid", "polyline_normal", "error", "error_normal"):
        assert math.isfinite(acc[key]) and acc[key] > 0, key
    assert acc["endpoints"] == 0.0          # against itself
    # the normal distance is the vertical one times the cosine of the segment slope
    assert acc["polyline_normal"] <= acc["polyline"] + 1e-15


def test_grid_baseline_and_ratio(bench, geneva_fast):
    m, pair, t, _, cs = geneva_fast
    h = 0.05
    q1, q2, blocked, tg = bench.run_grid(pair, m.window, h)
    assert blocked.shape == (len(q1), len(q2)) and tg > 0
    e = bench.grid_error(cs, q1, q2, blocked, h)
    assert e["grid_crossings"] > 0 and e["exact_crossings"] > 0
    # every crossing the grid finds is within half a cell of the exact boundary
    assert 0 < e["grid_to_exact"] <= 0.5 * h * (1 + 1e-9)
    assert e["normal_grid_to_exact"] <= e["grid_to_exact"] + 1e-15
    rate = blocked.size / tg
    eq = bench.equal_grid(pair, m.window, cs, 0.1, rate, 0.05, t)
    assert np.isfinite(eq["full_time"]) and eq["ratio"] > 0 and eq["scale"] >= 1.0
    n = bench.grid_configs(m.window, 2 * bench.boundary_accuracy(cs, cs)["error"])
    assert n > 0 and n / rate / t > 0


def test_report_writes_atomically(bench, tmp_path):
    out = tmp_path / "sub" / "r.md"
    bench.write_atomic(out, "x\n")
    bench.write_atomic(out, "y\n")
    assert out.read_text() == "y\n"
    assert [p.name for p in out.parent.iterdir()] == ["r.md"]
