"""Smoke test of the benchmark scripts: the C-space measurement functions run at
minimal sizes and return finite figures; the synthesis benchmark's tables render
from given figures (no synthesis is run); the report assembly and the run plan of
``run_all.py`` work.  No timing target is asserted here."""

import importlib.util
import json
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


# ------------------------------------------- report assembly, synthesis rendering, run_all

def _load(name):
    spec = importlib.util.spec_from_file_location(name, SCRIPT.parent / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def bench_syn():
    return _load("bench_synthesis")


def _syn_rows():
    def row(model, preset, workers, wall, e=0.0077):
        return {"model": model, "preset": preset, "workers": workers, "wall": wall,
                "pool_start": 1.5, "status": "CONVERGED", "nit": 3, "defects": [8, 8, 0],
                "checklist": [20, 20, 20], "e": e, "tol": 0.02, "units": "cm",
                "phases": {"reference": 0.2, "zones": 0.4, "checklist": 0.01, "defects": 4.0,
                           "search": 10.0, "plan": 0.001},
                "iter_total": 15.0, "tests": 188, "tests_per_s": 13.4}
    return [row("reciprocating_cam", "fast", 1, 15.0), row("reciprocating_cam", "fast", 2, 10.0),
            row("geneva", "default", 1, 80.0), row("geneva", "default", 2, 45.0, e=0.003)]


def test_synthesis_rendering(bench_syn):
    rows = _syn_rows()
    reuse = [{"model": "geneva", "preset": "default", "checklist": 40, "n": 10, "t_on": 1.0,
              "t_off": 2.5, "ratio": 2.5, "hits": 90, "misses": 10, "hit_rate": 0.9,
              "cache": {"entries": 200}, "defective": 0, "mismatch": [], "max_dev_diff": 0.0}]
    sp = bench_syn.speedups(rows)
    assert sp[("reciprocating_cam", "fast", 2)] == pytest.approx(1.5)
    same = bench_syn.consistency(rows)
    assert same[("reciprocating_cam", "fast", 2)] and not same[("geneva", "default", 2)]
    tab = bench_syn.synthesis_table(rows)
    assert len(tab) == 2 + len(rows) and "1.50×" in tab[3] and "**no**" in tab[5]
    split = bench_syn.split_table(rows)
    assert all(line.count("|") == split[0].count("|") for line in split)
    assert "66.7 %" in split[2]                      # search 10 of 15 s
    assert "2.50×" in bench_syn.reuse_table(reuse)[2]
    assert "45.00 s" in bench_syn.target_line(rows) and ": met." in bench_syn.target_line(rows)
    assert "NOT met" in bench_syn.target_line([dict(rows[3], wall=75.0)])
    assert "not measured" in bench_syn.target_line(rows[:2])

    class A:
        quick, models, presets, workers, reuse_vectors = False, ["geneva"], ["default"], [1, 2], 10
    info = {"date": "d", "nproc": 2, "platform": "p", "python": "3", "numpy": "2"}
    text = bench_syn.report(rows, reuse, info, A, ((3.0, 2.0, 1.0), (3.5, 2.0, 1.0)), 99.0)
    assert text.startswith("# Benchmark:") and "## Target" in text and "## Notes" in text
    assert "healthy variants only" in text and "should not change it" in text


def test_assemble(tmp_path):
    asm = _load("assemble")
    src = tmp_path / "parts"
    src.mkdir()
    (src / "synthesis.md").write_text(
        "# Benchmark: synthesis\n\n- date: 2026-01-02 03:04 UTC\n\n## Method\n\nx\n\n"
        "## Target\n\n- Target: under a minute — met.\n")
    (src / "cspace.md").write_text(
        "# Benchmark: C-space\n\n## Method\n\nSee [fig](img/a.png) and [web](https://x.org).\n\n"
        "```\n# not a heading\n```\n")
    (src / "zz_extra.md").write_text("# Extra\n\n## Method\n")
    cases = tmp_path / "case_studies.json"
    cases.write_text(json.dumps({
        "reciprocating_cam": {"preset": "fast", "nit": 3, "defects": [8, 8, 0], "e": 0.0077,
                              "tol": 0.02, "units": "cm", "wall_s": 20.5,
                              "mc_initial": {"defective": 40, "samples": 200},
                              "mc_final": {"defective": 0, "samples": 200}},
        "geneva": {"preset": "fast", "nit": 5}}))
    out = tmp_path / "out" / "BENCHMARKS.md"
    assert asm.main(["--src", str(src), "--out", str(out), "--case-studies", str(cases)]) == 0
    text = out.read_text()
    assert [p.name for p in out.parent.iterdir()] == ["BENCHMARKS.md"]
    heads = [line for line in text.splitlines() if line.startswith("#")]
    assert heads[:3] == ["# Benchmarks", "## Contents", "## How to reproduce"]
    assert "## Benchmark: C-space" in heads and "### Method" in heads
    assert heads.index("## Benchmark: C-space") < heads.index("## Benchmark: synthesis") \
        < heads.index("## Extra") < heads.index("## Synthesis case studies")
    assert "```\n# not a heading\n```" in text                 # code blocks untouched
    assert "[fig](../parts/img/a.png)" in text and "(https://x.org)" in text
    # every contents link points at an anchor of the document
    anchors = {a for _, a in asm.anchors(text)}
    toc = text.split("## How to reproduce")[0]
    links = [s.split(")")[0] for s in toc.split("](#")[1:]]
    assert len(links) == 4 and set(links) <= anchors
    assert "measured 2026-01-02 03:04 UTC" in toc and "  - Target: under a minute — met." in toc
    assert "| reciprocating_cam | fast | 3 | 8, 8, 0 | 0.0077 / 0.02 cm | 40 / 200 | 0 / 200 |" \
        " 20.5 s |" in text
    assert "| geneva | fast | 5 | — |" in text
    # duplicate headings get numbered anchors
    assert [a for t, a in asm.anchors(text) if t == "Method"] == ["method", "method-1",
                                                                  "method-2"]


def test_assemble_without_parts(tmp_path):
    asm = _load("assemble")
    out = tmp_path / "B.md"
    asm.main(["--src", str(tmp_path / "none"), "--out", str(out),
              "--case-studies", str(tmp_path / "none.json")])
    assert "(no benchmark reports found)" in out.read_text()


def test_run_all_plan():
    run_all = _load("run_all")
    names = [p.name for p, _ in run_all.plan(False)]
    assert names[:4] == ["bench_cspace.py", "bench_fourbar.py", "bench_spatial.py",
                         "bench_synthesis.py"]
    assert all(a == [] for _, a in run_all.plan(False))
    quick = {p.name: a for p, a in run_all.plan(True)}
    assert quick["bench_cspace.py"] == ["--quick"] and quick["bench_synthesis.py"] == ["--quick"]
    assert quick["bench_fourbar.py"] == [] and quick["bench_spatial.py"] == []
