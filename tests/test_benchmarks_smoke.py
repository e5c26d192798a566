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
    bench.atomic_write(out, "x\n")
    bench.atomic_write(out, "y\n")
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
                "iter_total": 15.0, "tests": 188, "tests_per_s": 13.4, "patience": 4,
                "two_sided": True}
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
    capped = bench_syn.target_line([dict(rows[3], status="MAX_ITER", nit=2, wall=300.0)])
    assert "not measured to the end" in capped and "first 2 iteration(s)" in capped
    assert "NOT met" in capped

    class A:
        quick, models, presets, workers, reuse_vectors = False, ["geneva"], ["default"], [1, 2], 10
    info = {"date": "d", "nproc": 2, "platform": "p", "python": "3", "numpy": "2"}
    text = bench_syn.report(rows, reuse, info, A, ((3.0, 2.0, 1.0), (3.5, 2.0, 1.0)), 99.0)
    assert text.startswith("# Benchmark:") and "## Target" in text and "## Notes" in text
    assert "healthy variants only" in text and "should not change it" in text
    # no cap by default (a whole Geneva run takes well under a minute); a cap is stated
    assert "capped at" not in text
    capped_text = None
    old_caps = bench_syn.CAPS
    try:
        bench_syn.CAPS = {"geneva": 1}
        capped_text = bench_syn.report(rows, reuse, info, A, ((3.0, 2.0, 1.0), (3.5, 2.0, 1.0)),
                                       99.0)
    finally:
        bench_syn.CAPS = old_caps
    assert "geneva capped at 1 iteration(s)" in capped_text
    assert "settings (the defaults): patience 4, two-sided on\n" in text
    assert text.startswith("# Benchmark: tolerance synthesis time")
    assert "(run `python benchmarks/bench_synthesis.py`)" in text
    A.argv = ["--models", "geneva", "--title", "a b"]
    assert ("(run `python benchmarks/bench_synthesis.py --models geneva --title 'a b'`)"
            in bench_syn.report(rows, reuse, info, A, ((1, 1, 1), (1, 1, 1)), 9.0))
    A.title = "the whole run"
    assert bench_syn.report(rows, reuse, info, A, ((1, 1, 1), (1, 1, 1)), 9.0).startswith(
        "# Benchmark: the whole run\n")
    A.uncapped = True
    assert "capped" not in bench_syn.report(rows, reuse, info, A, ((1, 1, 1), (1, 1, 1)), 9.0)


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


# ------------------------------------------------------------------- scaling benchmark

def _scal_rows():
    def row(case, kind, workers, wall, sig="A", **kw):
        r = {"case": case, "kind": kind, "workers": workers, "start": 0.0 if kind == "serial"
             else 2.5, "warm_workers": 0 if kind == "serial" else workers, "wall": wall,
             "cpu": 0.9 * wall * workers, "load": 1.5, "signature": sig}
        r.update(kw)
        return r
    syn = {"status": "CONVERGED", "nit": 3, "defects": [8, 8, 0], "checklist": [20, 20, 20],
           "tests": 188, "e": 0.0077, "units": "cm",
           "phases": {"defects": 4.0, "search": 14.0, "total": 19.0}}
    a = json.dumps({"n": 40, "defective": [4], "reasons": {"X": 1}})
    b = json.dumps({"n": 40, "defective": [4, 7], "reasons": {"X": 2}})
    mc = {"n": 40, "n_defective": 1, "defective": [4]}
    return [row("syn", "serial", 1, 20.0, **syn), row("syn", "process", 1, 21.0, cpu=30.0, **syn),
            row("syn", "process", 2, 12.5, **syn), row("syn", "dask", 2, 16.0, **syn),
            row("mc", "serial", 1, 10.0, a, **mc), row("mc", "process", 2, 5.0, a, **mc),
            row("mc", "dask", 2, 6.0, b, **dict(mc, n_defective=2, defective=[4, 7]))]


def test_scaling_rendering():
    bench_scal = _load("bench_scaling")
    rows = _scal_rows()
    sc = bench_scal.scaling(rows)
    assert sc[("syn", "process", 2)]["speedup"] == pytest.approx(1.6)
    assert sc[("syn", "process", 2)]["efficiency"] == pytest.approx(0.8)
    assert sc[("syn", "serial", 1)]["same"] and sc[("syn", "dask", 2)]["same"]
    assert not sc[("mc", "dask", 2)]["same"]
    bad = bench_scal.mismatches(rows)
    assert [(r["case"], r["kind"]) for r, _ in bad] == [("mc", "dask")]
    assert any(".defective" in d for d in bad[0][1])
    tab = bench_scal.scaling_table(rows)
    assert len(tab) == 2 + len(rows)
    assert all(line.count("|") == tab[0].count("|") for line in tab)
    assert "(baseline)" in tab[2] and "1.60×" in tab[4] and "80 %" in tab[4]
    assert "**no**" in tab[8] and "1.67×" in tab[3]          # CPU 30 s vs serial 18 s
    share = bench_scal.serial_share(rows, {"mc": 1.0})
    assert share["syn"] == pytest.approx(0.1) and share["mc"] == pytest.approx(0.1)
    bounds = bench_scal.bound_table(rows, {"mc": 1.0}, [1, 2])
    assert "1.82×" in bounds[2] and "1.60×" in bounds[2] and "2.00×" in bounds[3]

    class A:
        quick, executors, workers, cam_samples, geneva_samples = True, ["process", "dask"], \
            [1, 2], 40, 6
    info = {"date": "d", "nproc": 2, "platform": "p", "python": "3", "numpy": "2",
            "distributed": "x"}
    text = bench_scal.report(rows, {"mc": 1.0}, info, A, ((3.0, 2.0, 1.0), (0.2, 0.1, 0.1)),
                             99.0)
    assert text.startswith("# Benchmark:") and "## Scaling on a cluster" in text
    assert "../synthesis.md#executors" in text and "this is a bug" in text
    assert "2 cores" in text and "other load" in text
    assert "20, 20, 20 vectors per iteration" in text
    assert "used 1.67× the CPU of the serial run" in text
    good = [r for r in rows if r["case"] == "syn"]
    assert "same result as the serial run" in bench_scal.report(good, {}, info, A,
                                                                (None, None), 1.0)


def test_scaling_serial_measurement(tmp_path):
    """One real measurement on the serial executor (no pool, no cluster)."""
    bench_scal = _load("bench_scaling")
    case = {"id": "mc", "job": "monte_carlo", "model": "reciprocating_cam", "preset": "fast",
            "samples": 3, "seed": 0}
    r = bench_scal.run_case(case, "serial", 1)
    assert r["kind"] == "serial" and r["workers"] == 1 and r["wall"] > 0 and r["n"] == 3
    assert json.loads(r["signature"])["n"] == 3
    assert r["cpu"] is None or r["cpu"] >= 0
    out = tmp_path / "s.md"
    bench_scal.atomic_write(out, "x\n")
    assert out.read_text() == "x\n" and [p.name for p in tmp_path.iterdir()] == ["s.md"]
    run_all = _load("run_all")
    assert dict((p.name, a) for p, a in run_all.plan(True))["bench_scaling.py"] == ["--quick"]


# ------------------------------------------------------------- accuracy (Pareto) benchmark

@pytest.fixture(scope="module")
def bench_acc():
    return _load("bench_accuracy")


def test_accuracy_knee(bench_acc):
    # an L-shaped front: the knee is the corner
    pts = [(1.0, 1e-1), (2.0, 1e-4), (10.0, 3e-5), (100.0, 1e-5), (5.0, 1e-1)]
    assert bench_acc.pareto_front(pts) == [0, 1, 2, 3]
    kn = bench_acc.knee(pts)
    assert kn["knee"] == 1 and kn["dist"][1] > 1.0
    # bent the other way: no point below the chord
    kn = bench_acc.knee([(1.0, 1e-1), (10.0, 5e-2), (20.0, 1e-6)])
    assert kn["knee"] is None and kn["why"] == "concave"
    assert bench_acc.knee([(1.0, 1.0), (2.0, 0.5)])["why"] == "few"
    rows = [bench_acc._row(lab, "preset", t, [t], e) for lab, (t, e) in
            zip(("fast", "default", "x", "precise"), [(1.0, 1e-1), (2.0, 1e-4), (10, 3e-5),
                                                      (100.0, 1e-5)])]
    v = bench_acc.knee_verdict(rows)
    assert v["knee"] == "default" and v["at_knee"]
    rows[1]["time"] = 50.0                      # default dominated by "x"
    v = bench_acc.knee_verdict(rows)
    assert v["knee"] == "x" and not v["default_on_front"] and v["at_knee"] is False
    rows[1]["time"], rows[1]["error"] = 12.0, 3e-5  # beaten by "x" only by noise
    v = bench_acc.knee_verdict(rows)
    assert v["knee"] == "x" and not v["default_on_front"] and v["at_knee"] is True


def test_accuracy_cspace_and_zone_errors(bench_acc):
    from cspace.zones import contact_zones
    from mechanisms.models import reciprocating_cam
    q = bench_acc.cspace_quantity(reciprocating_cam, {"chord": (1e-3, 2e-4)}, 1, log=lambda s: 0)
    rows = {r["label"]: r for r in q["rows"]}
    assert set(rows) == {"fast", "default", "precise", "chord=0.001"}
    assert all(math.isfinite(r["error"]) and r["error"] > 0 and r["time"] > 0
               for r in rows.values())
    assert rows["precise"]["error"] < rows["fast"]["error"]
    assert q["lines"]["chord"] == [3, 1]          # coarse to fine, through the default row
    # a zone analysis against itself has no error; against a finer one a finite error
    m = reciprocating_cam()
    cs = __import__("cspace.freespace", fromlist=["x"]).configuration_space(
        m.build(), "fast", window=m.window, deps=m.dependencies()[0])
    c = [cs.boundary[0].curve]
    z = contact_zones(cs, m, 0, "fast", curves=c)
    e = bench_acc.band_error(z, z)
    assert e["error"] == 0 and e["at_samples"] == 0 and e["uncovered"] == 0
    zf = contact_zones(cs, m, 0, bench_acc.PRESETS["fast"].replace(zone_samples=47), curves=c)
    e = bench_acc.band_error(z, zf)
    assert 0 < e["error"] < e["ref_width"] and math.isfinite(e["at_samples"])


def test_accuracy_search_and_spatial(bench_acc):
    from cspace.defects import reference
    from mechanisms.models import reciprocating_cam
    m = reciprocating_cam()
    u = m.nominal + np.array(bench_acc.SEARCH_PATTERNS[0], dtype=float) * m.tol
    t, n, trs = bench_acc.search_once(m, reference(m, "fast"), [u], 0.3)
    assert t > 0 and n == trs[0].steps >= 1 and trs[0].lam[0] < trs[0].lam[1]
    for name, lk, xs, out, ref in bench_acc._spatial_cases(7):
        from mechanisms.spatial import solve_path
        path = solve_path(lk.loop, xs, lk.q0)
        hd = np.array([out(lk, q) for q in path.q])
        assert np.max(np.abs((hd - ref + math.pi) % (2 * math.pi) - math.pi)) < 1e-9, name


def _acc_fake(bench_acc):
    R = bench_acc._row

    def acc_rows(extra):
        out = []
        for lab, kind, knob, val, t, e in (("fast", "preset", None, None, 1.0, 1e-3),
                                            ("default", "preset", None, None, 2.0, 1e-4),
                                            ("precise", "preset", None, None, 5.0, 1e-5),
                                            ("chord=0.001", "knob", "chord", 1e-3, 1.9, 1e-3)):
            r = R(lab, kind, t, [t], e, knob, val, **extra)
            r["defaults"] = {"chord": 2e-4 if lab != "chord=0.001" else 1e-3}
            out.append(r)
        return {"rows": out, "lines": {"chord": [3, 1]}, "baseline": "fast", "unit": "rad"}

    cs = acc_rows(dict(vertical=2e-3, normal=1e-3, endpoints=1e-7, endpoints_q1=1e-12,
                       segments=10, pieces=8, ref_pieces=8))
    zo = acc_rows(dict(at_samples=1e-6, narrower=1e-6, wider=0.0, uncovered=0, vectors=64,
                       ref_width=0.01))
    zo.update(curves=["a|b"], deps=[6], ref_knobs={"zone_samples": 385}, notes=["n"])
    se = acc_rows(dict(tests=8, steps=8, against="precise", err_default=1e-5, lam=[0.79]))
    se.update(vectors=1, truth_shift=0.0, ref_eps=1e-6)
    syn = {"rows": [R("fast", "preset", 20.0, [20.0], 1e-4, status="CONVERGED", nit=3,
                      e=0.0077, defects=[8, 8, 0], tests=188, dtol=0.0, u=[1.0, 2.0]),
                    R("default", "reference", 25.0, [25.0], 0.0, status="CONVERGED", nit=3,
                      e=0.0076, defects=[8, 8, 0], tests=220, dtol=0.0, u=[1.0, 2.0001])],
           "lines": {}, "baseline": "fast", "unit": "cm", "reference": "default",
           "pool_start": 1.0, "workers": 2, "names": ["a", "b"], "tol0": 0.02}
    fb = {"rows": [R("harmonic_max", "method", 1e-3, [1e-3], 1e-5, rel=1e-3,
                     library_default=False),
                   R("sweep 8", "knob", 1e-3, [1e-3], 1e-4, "sweep points", 8, rel=1e-2,
                     library_default=False),
                   R("sweep 360", "knob", 2e-3, [2e-3], 1e-7, "sweep points", 360, rel=1e-5,
                     library_default=False)],
          "lines": {"sweep points": [1, 2]}, "baseline": None, "unit": "rad",
          "reference_value": 8e-3, "clearance": 0.1, "seeds": 2}
    sp = {"rows": [R("default", "preset", 0.5, [0.5], 1e-12, residual=1e-12, iterations=360,
                     failed=0, per={}),
                   R("tol=0.01", "knob", 0.4, [0.4], 1e-3, "tol", 0.01, residual=1e-3,
                     iterations=0, failed=0, per={})],
          "lines": {"tol": [1, 0]}, "baseline": "default", "unit": "rad", "inputs": 9}
    sp["rows"][0]["defaults"] = {"tol": 1e-12}
    return {"cspace_geneva": cs, "cspace_cam": dict(cs), "zones_cam": zo, "search": se,
            "synthesis": syn, "fourbar": fb, "spatial": sp}


def test_accuracy_report_and_plot(bench_acc, tmp_path):
    qs = _acc_fake(bench_acc)
    bench_acc.analyze(qs)
    assert qs["cspace_geneva"]["knee"]["knee"] == "default"
    info = {"date": "d", "nproc": 2, "platform": "p", "python": "3", "numpy": "2", "scipy": "1"}
    text = bench_acc.report(qs, info, True, 9.0, ((3.0, 2.0, 1.0), (0.1, 0.1, 0.1)))
    assert text.startswith("# Benchmark:") and "](../img/pareto.png)" in text
    assert "## Summary" in text and "## Knobs" in text and "**is the knee**" in text
    for key, title in bench_acc.TITLES.items():
        assert (f"## {title}" in text) == (key in qs)
    tables = [ln for ln in text.splitlines() if ln.startswith("|")]
    assert tables and all(ln.endswith("|") for ln in tables)
    png = bench_acc.plot(qs, dpi=30)
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    out = tmp_path / "img" / "p.png"
    bench_acc._write(out, png)
    assert out.read_bytes() == png and [p.name for p in out.parent.iterdir()] == ["p.png"]


# ------------------------------------------------------------- zones benchmark
def test_zones_measure_and_report(tmp_path):
    """The zone benchmark on the reciprocating cam with a few vectors: zones hold
    every sampled variant there (its curves are nearly linear in the parameters),
    the Monte Carlo band is inside the zones, and the report is written."""
    bz = _load("bench_zones")
    rows = bz.main(["--models", "reciprocating_cam", "--presets", "fast", "--samples", "12",
                    "--out", str(tmp_path / "zones.md")])
    (r,) = rows
    assert r["bands"] > 0 and r["t_zone"] > 0 and r["t_mc"] > 0
    assert r["excess"] <= 1e-9 and r["outside_share"] == 0.0
    assert r["over_median"] >= -1e-9 and math.isfinite(r["over_p95"])
    text = (tmp_path / "zones.md").read_text()
    assert "| reciprocating_cam |" in text and "12 vectors" in text


def test_batch_benchmark_renders_its_table():
    """The batch benchmark's table renders from given figures (nothing timed)."""
    spec = importlib.util.spec_from_file_location(
        "bench_batch", SCRIPT.parent / "bench_batch.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    row = {"model": "geneva", "preset": "fast", "vectors": 619, "baseline": 40, "plan": 1.2,
           "full": 0.3, "batch": 0.03, "ratio": 10.0, "fallback": 33, "defective": 225,
           "agree": 40, "verified": (619, 619), "mc": 500, "mc_time": 20.0, "mc_fallback": 9,
           "mc_defective": 30, "compiled": 0.09, "one_row": 0.19, "fused_share": 0.75,
           "kernel_values": 1200,
           "zones": {"bands": 48, "stacked": 1.0, "single": 2.5, "same": 48, "worst": 1e-14,
                     "evaluated": 900, "fallbacks": 2}}
    text = mod.render([row], None)
    assert "| geneva | fast | 619 (225 defective) |" in text
    assert "| geneva | fast | 48 | 900 |" in text and "2.50x | 48/48 | 1.0e-14 | 2 |" in text
    assert "10.0x" in text and "619/619" in text and "| 500 |" in text
    assert f"| {mod.fmt_seconds(0.09)} | 33 |" in text    # the compiled kernel's time
    assert f"10.0x | {mod.fmt_seconds(0.19)} |" in text     # the one-row call
    assert "| 75.0 % of 1,200 |" in text                  # the fused kernel's share
    del row["compiled"]                                   # a run without numba
    assert "| — | 33 |" in mod.render([row], None)
    assert "On a process pool" not in text
    row["pool"] = {"workers": 2, "checklist": 3.5, "fallback": 1, "mc": 2000, "mc_time": 16.0,
                   "mc_defective": 112, "mc_fallback": 0}
    text = mod.render([row], None)
    assert (f"| geneva | fast | 2 | 619 | {mod.fmt_seconds(3.5)} | 1 | 2000 | "
            f"{mod.fmt_seconds(16.0)} | 112 | 0 |") in text
    del row["pool"]["mc"]                                 # no box samples on the pool
    assert "| 1 | — | — | — | — |" in mod.render([row], None)


def test_batch_verification_compares_and_renders():
    """The verification of the batched verdicts compares a few cam vectors
    (the full tests on an executor) and renders agreement and disagreement."""
    from synthesis.executors import SerialExecutor
    spec = importlib.util.spec_from_file_location(
        "verify_batch", SCRIPT.parent / "verify_batch.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    from cspace.defects import reference
    from mechanisms.models import reciprocating_cam
    from synthesis.verify import box_samples
    m = reciprocating_cam()
    U = box_samples(m.nominal, m.tol, 6, seed=1)
    r = mod.compare(m, U, reference(m, "fast"), SerialExecutor())
    assert r["vectors"] == 6 and r["certified"] + r["fallback"] == 6
    assert r["agree"] == r["certified"] and r["wrong"] == []
    row = {"model": "reciprocating_cam", "preset": "fast", "what": "Monte Carlo", **r}
    text = mod.render([row], 1.0)
    assert "every certified verdict agrees" in text and "| Monte Carlo (6) |" in text
    bad = dict(row, agree=row["agree"] - 1, wrong=[U[0].tolist()])
    text = mod.render([bad], 1.0)
    assert "DISAGREEMENTS" in text and "- wrong: reciprocating_cam fast Monte Carlo" in text


def test_case_study_search_comparison_table():
    cs = _load("case_studies")
    row = {"nit": 5, "tests": 589, "search_tests": 119, "e": 0.0072, "tol": 0.02,
           "units": "cm", "cuts": 0, "smallest_kept": 1.0, "volume_kept": 1.0,
           "time_synthesis_s": 12.0, "mc_final": {"defective": 0, "samples": 2000}}
    # the margin row is the greedy removal's run (the bisection runs with it)
    text = cs.comparison({"reciprocating_cam:greedy": row,
                          "reciprocating_cam": dict(row, tests=208),     # the LP: not here
                          "reciprocating_cam:bisect": dict(row, tests=741, search_tests=271),
                          "geneva:greedy": {"nit": 3}})     # an older record: left out
    lines = text.splitlines()
    assert len(lines) == 4
    assert lines[2].startswith("| reciprocating_cam | margin | 5 | 589 (119) | 0.0072 / 0.02 cm")
    assert lines[3].startswith("| reciprocating_cam | bisect (paper) | 5 | 741 (271) |")
    assert lines[2].endswith("| 100 % | 1 | 0.2 min | 0/2000 |")


def test_main_job_rendering():
    mod = _load("bench_main_job")
    split = {"reference": 0.5, "zones": 2.0, "checklist": 0.05, "defects": 10.0, "lp": 40.0,
             "search": 25.0, "plan (other)": 1.0, "other": 1.45}
    r = {"preset": "fast", "workers": 2, "wall": 90.0, "total": 80.0, "split": split,
         "iterations": 2, "status": "CONVERGED", "defects": [223, 0], "tests": 3357,
         "full": 0.3, "baseline": 20, "same": True, "tested_phases": 35.0}
    text = mod.render(r, None)
    assert "| fast | 2 | 90.00 s | 2 | 223, 0 | 3357 | yes |" in text
    assert "| lp | 40.00 s | 50 % |" in text
    # 3357 tests x 0.3 s over 2 workers = 503.55 s against 35 s of batched phases
    assert "14.4x the batched phases" in text
    both = mod.render([r, dict(r, preset="default", wall=200.0, same=False, case=[314, 0])], None)
    assert "| 3357 | no (case study: 314, 0) |" in both
    assert "## `fast`" in both and "## `default`" in both
    assert f"| default | 2 | {mod.fmt_seconds(200.0)} |" in both and "within 30 s at `default`" in both
    assert "re-tests of `failures.png`" not in both
    out = mod.render(dict(r, outputs={"retests": 1.5, "write": 6.0, "figures": 4.0}), None)
    assert f"| re-tests of `failures.png` | {mod.fmt_seconds(1.5)} |" in out
    assert f"| of which the figures | {mod.fmt_seconds(4.0)} |" in out
    assert f"| synthesis and outputs | {mod.fmt_seconds(97.5)} |" in out
