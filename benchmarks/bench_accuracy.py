"""Speed/accuracy trade of every approximating knob (the "Pareto" benchmark).

Every figure is measured in one run of this script, every error is against a
reference computed in the same run, and every time ratio is against a baseline
measured in the same run.  Plain script::

    python benchmarks/bench_accuracy.py           # full run, about 10 minutes on 2 cores
    python benchmarks/bench_accuracy.py --quick   # fewer settings and repeats, about 2 minutes

It prints the tables and writes them to ``docs/benchmarks/accuracy.md``, and the
Pareto plot (time against error, one panel per quantity) to
``docs/img/pareto.png`` (both written to a temporary file, then renamed).

Settings
--------
For the quantities computed with :class:`cspace.accuracy.Accuracy`, every preset
(``fast``, ``default``, ``precise``) and every knob of the quantity varied alone,
the others at ``default`` (``Accuracy.preset("default").replace(knob=value)``).
A sweep value equal to the default's is the ``default`` row itself.  The four-bar
and spatial-loop modules do not read ``Accuracy``; their own knobs are swept
around their library defaults.

Measurements
------------
C-space boundary    Geneva pair and reciprocating cam.  Time: median wall time of
                    ``configuration_space(pair, acc, window=model.window,
                    deps=...)`` followed by ``cs.curve_polylines(boundary_only=
                    True)`` (the polylines are built on demand, so ``chord`` is
                    paid there).  Error (C-space metric: rad, or slide / the
                    pair's characteristic length): the larger of (1) the largest
                    distance, normal to the segment, between the boundary
                    polylines and the exact curves at 7 interior points of every
                    segment and (2) the Hausdorff distance (max-norm) between the
                    boundary-piece end points and those of a reference C-space
                    finer than ``precise`` (chord 2e-6, max_step 0.005, root_tol
                    1e-14, scan_step 0.0025).  The vertical (q2) polyline error
                    is tabulated beside it.  Knobs: chord, max_step, root_tol,
                    scan_step.
zone bands          ``contact_zones(cs, model, 0, acc, curves=...)`` on the
                    nominal ``precise`` C-space (the same curves for every
                    setting): the reciprocating cam's operating-channel curves,
                    and three Geneva curves of different kinds (full mode only;
                    the whole Geneva channel takes about 20 s per setting).
                    Reference: the same call with many more samples, every box
                    corner up to 1024 (the cam: all 64), extra random corners and
                    more local optimisation.  Error: the setting's upper and
                    lower bands, read as piecewise linear in q1 between its
                    samples, against the reference bands at the reference's
                    samples (the largest absolute difference, C-space metric);
                    the difference at the setting's own samples (reference
                    interpolated there) is tabulated beside it.  Knobs:
                    zone_samples, zone_opt_iter, zone_opt_samples,
                    zone_max_corners, zone_random_corners, zone_climb.
transition point    ``synthesis.removal.transition_points`` from the cam's nominal
                    towards two defective iteration-1 check-list vectors, serial
                    defect tests against a nominal reference (its curve cache
                    refilled with the nominal curves before every timed search, so
                    that no search reuses another's variants).  Error: max-norm
                    distance (cm) of the healthy bracket end from the transition
                    found with search_eps = 1e-6 (the knob sweep: at default
                    accuracy; the presets: at ``precise`` accuracy, so their
                    error includes that of their defect test).  Knob: search_eps.
synthesis           ``synthesize(reciprocating_cam(), preset, executor=pool)`` on a
                    process pool of 2 workers started before the clock; wall time.
                    Error: max |u_final - u_final(precise)| (cm); in quick mode
                    ``precise`` is not run and ``default`` is the reference.
four-bar            the largest exact output-angle error over the pin angle of
                    the four-bar of [Shin & Choi 1995] (clearance 0.1 at
                    pin B, crank at 62.935 deg), as in ``bench_fourbar.py``:
                    reference a 36 000-point sweep refined by bounded
                    maximisation.  Knobs:
                    sweep density, ``monte_carlo`` sample count (pins on the
                    clearance circle; error averaged over seeds), ``worst_case``
                    maxiter; ``harmonic_max`` has none (3 evaluations).
spatial loops       ``solve_path`` over one input revolution of the RSSR and the
                    spherical 4R of the tests; time summed over both.  Error: the
                    largest output-angle difference from the closed-form
                    input-output equations (``closedform.rssr_phi``,
                    ``spherical_4r_psi``); the largest loop residual beside it.
                    Knobs: ``SolverOptions`` tol, max_step, max_iter.

Knee
----
The Pareto front of a quantity is the set of measured settings that no other
setting beats in both time and error.  In log10(time)-log10(error) space the
knee is the front point farthest from the chord between the front's extreme
points (fastest and most accurate), on the side of the origin.  ``default`` is
called *at the knee* when it is the knee point, or lies within a factor 2 of the
knee in time and in error (timing noise on a busy machine is of that order, so a
setting that beats ``default`` only by noise does not move it off the knee).
Errors below 1e-15 count as 1e-15 on the log axis.

Times are wall times (``time.perf_counter``): process-pool work is not visible
to ``time.process_time``.  The machine may be loaded by other work; the load
average at the start and the end is in the report.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import io
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchlib import endpoint_error, load_average, polyline_error, start_pool  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
for _p in (str(ROOT), str(HERE)):
    if _p not in sys.path:
        sys.path.insert(0, _p)

from cspace.accuracy import Accuracy  # noqa: E402
from synthesis.accuracy import PRESETS  # noqa: E402
from cspace.io import atomic_write  # noqa: E402

DOC = ROOT / "docs" / "benchmarks" / "accuracy.md"
IMG = ROOT / "docs" / "img" / "pareto.png"
PRESET_NAMES = ("fast", "default", "precise")
FLOOR = 1e-15            # errors below count as this on log axes
KNEE_FACTOR = 2.0        # "at the knee": within this factor of the knee in time and error

#: reference settings, finer than ``precise``
CSPACE_REF = dict(chord=2e-6, max_step=0.005, root_tol=1e-14, scan_step=0.0025)
ZONES_REF = {"full": dict(zone_samples=385, zone_opt_iter=4, zone_opt_samples=16,
                          zone_max_corners=1024, zone_random_corners=256, zone_climb=48),
             "quick": dict(zone_samples=97, zone_opt_iter=2, zone_opt_samples=4,
                           zone_max_corners=1024, zone_random_corners=128, zone_climb=24)}
GENEVA_ZONE_REF = dict(zone_samples=193, zone_opt_iter=3, zone_opt_samples=8,
                       zone_max_corners=1024, zone_random_corners=256, zone_climb=24)
SEARCH_REF_EPS = {"full": 1e-6, "quick": 1e-5}

#: knob sweeps (coarse to fine); each includes the default value
SWEEPS = {
    "full": {
        "cspace": {"chord": (4e-3, 1e-3, 2e-4, 5e-5, 2e-5, 5e-6),
                   "max_step": (0.16, 0.08, 0.04, 0.02, 0.01, 0.005),
                   "root_tol": (1e-5, 1e-7, 1e-9, 1e-11, 1e-13),
                   "scan_step": (0.08, 0.04, 0.02, 0.01, 0.005, 0.0025)},
        "zones": {"zone_samples": (12, 24, 48, 96, 192),
                  "zone_opt_iter": (0, 1, 2, 4),
                  "zone_opt_samples": (0, 1, 2, 4, 8),
                  "zone_max_corners": (16, 32, 64, 256),
                  "zone_random_corners": (0, 8, 32, 128),
                  "zone_climb": (0, 1, 4, 12)},
        "zones_geneva": {"zone_samples": (24, 48, 96),
                         "zone_opt_iter": (0, 1, 2),
                         "zone_opt_samples": (0, 1, 4),
                         "zone_max_corners": (16, 64, 1024),
                         "zone_random_corners": (0, 8, 32, 128),
                         "zone_climb": (0, 4, 12)},
        "search": {"search_eps": (2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 3e-5)},
    },
    "quick": {
        "cspace": {"chord": (1e-3, 2e-4, 2e-5), "max_step": (0.04, 0.02, 0.01),
                   "root_tol": (1e-7, 1e-11, 1e-13), "scan_step": (0.04, 0.01, 0.005)},
        "zones": {"zone_samples": (24, 48, 96), "zone_opt_iter": (0, 1), "zone_opt_samples": (1, 4),
                  "zone_max_corners": (32, 64), "zone_random_corners": (0, 8),
                  "zone_climb": (0, 4)},
        "search": {"search_eps": (2e-2, 1e-3, 2e-4)},
    },
}
#: the direction in which each knob is finer
FINER = {"chord": -1, "max_step": -1, "root_tol": -1, "scan_step": -1, "search_eps": -1,
         "zone_samples": 1, "zone_opt_iter": 1, "zone_opt_samples": 1, "zone_max_corners": 1,
         "zone_random_corners": 1, "zone_climb": 1, "sweep points": 1, "monte_carlo n": 1,
         "worst_case maxiter": 1, "tol": -1, "max_step (solver)": -1, "max_iter": 1}

#: two defective iteration-1 check-list vectors of the reciprocating cam (default
#: preset), as multiples of the tolerances: finger 0 tip on the right face pushed in
#: with finger 1 (vector 12) or finger 2 (vector 14) on the left face
SEARCH_PATTERNS = ((1, -1, 1, 1, 0, 1, 0, -1, -1, 1, 1),
                   (-1, 1, 1, 0, 1, 1, 0, -1, -1, 1, 1))
#: Geneva zone curves: one of each kind of contact on the operating channel
GENEVA_CURVES = ("driver:pin|wheel:slot0.right", "driver:lock_disk|wheel:lock0^slot0.right",
                 "driver:relief|wheel:lock0^slot0.right")


# ----------------------------------------------------------------------- helpers

def median_time(fn, repeat: int):
    """Median wall time (s) of ``fn()`` over ``repeat`` calls, all the times and the
    last result."""
    times, out = [], None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), times, out


def auto_time(fn, repeat: int = 5, min_loop: float = 0.05):
    """Median seconds per call for short calls: an inner loop of at least
    ``min_loop`` seconds, ``repeat`` times."""
    number = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        if time.perf_counter() - t0 > min_loop or number >= 1 << 16:
            break
        number *= 2
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return float(np.median(times)), times


def machine() -> dict:
    import scipy
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "nproc": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "scipy": scipy.__version__,
            "platform": f"{platform.system()} {platform.machine()}", "load": load_average(),
            "code": code_state()}


def code_state() -> str | None:
    """The commit measured and the library files changed in the working tree."""
    import subprocess
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                              capture_output=True, timeout=10).stdout.strip()
        st = subprocess.run(["git", "status", "--porcelain", "--", "cspace", "mechanisms",
                             "synthesis"], cwd=ROOT, text=True, capture_output=True,
                            timeout=10).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    if not head:
        return None
    changed = sorted(line[3:] for line in st.splitlines() if line.strip())
    return f"commit {head}" + (f", with uncommitted changes to {', '.join(changed)}"
                               if changed else "")


def _row(label, kind, time_s, times, error, knob=None, value=None, **extra) -> dict:
    return {"label": label, "kind": kind, "knob": knob, "value": value, "time": float(time_s),
            "times": [float(t) for t in times], "error": float(error), "extra": extra}


def accuracy_settings(sweeps: dict) -> list:
    """(label, kind, knob, value, Accuracy) of the presets and the one-knob variants
    of ``default``; a sweep value equal to the default's is not repeated."""
    out = [(p, "preset", None, None, PRESETS[p]) for p in PRESET_NAMES]
    d = PRESETS["default"]
    for knob, values in sweeps.items():
        if not hasattr(d, knob):
            continue
        for v in values:
            if v == getattr(d, knob):
                continue
            out.append((f"{knob}={v:g}", "knob", knob, v, d.replace(**{knob: v})))
    return out


def sweep_lines(rows: list, sweeps: dict, default_label: str = "default") -> dict:
    """knob -> row indices of its sweep (coarse to fine), the default row included."""
    dflt = next((i for i, r in enumerate(rows) if r["label"] == default_label), None)
    out = {}
    for knob, values in sweeps.items():
        idx = []
        for v in sorted(values, key=lambda v: FINER.get(knob, 1) * v):
            k = next((i for i, r in enumerate(rows) if r["knob"] == knob and r["value"] == v),
                     None)
            if k is None and dflt is not None and rows[dflt].get("defaults", {}).get(knob) == v:
                k = dflt
            if k is not None:
                idx.append(k)
        if idx:
            out[knob] = idx
    return out


def _defaults_of(acc: Accuracy, knobs) -> dict:
    return {k: getattr(acc, k) for k in knobs}


# ------------------------------------------------------------------- knee

def pareto_front(points) -> list:
    """Indices of the non-dominated points of (time, error) pairs, by time."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def knee(points) -> dict:
    """Pareto front and knee of (time, error) pairs (see the module docstring).

    Returns ``front`` (indices by time), ``knee`` (index or None) and ``dist``
    (index -> distance below the chord in decades, front points only)."""
    pts = [(max(t, 1e-12), max(e, FLOOR)) for t, e in points]
    front = pareto_front(pts)
    res = {"front": front, "knee": None, "dist": {}, "why": None}
    if len(front) < 3:
        res["why"] = "few"
        return res
    L = [(math.log10(pts[i][0]), math.log10(pts[i][1])) for i in front]
    (x0, y0), (x1, y1) = L[0], L[-1]
    dx, dy = x1 - x0, y1 - y0
    n = math.hypot(dx, dy)
    if n == 0:
        return res
    best, k = 0.0, None
    for i, (x, y) in zip(front, L):
        # positive on the side of the origin (below the chord from top-left to bottom-right)
        d = ((x - x0) * dy - (y - y0) * dx) / n
        res["dist"][i] = d
        if d > best + 1e-12:
            best, k = d, i
    res["knee"] = k
    if k is None:
        res["why"] = "concave"
    return res


def knee_verdict(rows: list, default_label: str = "default") -> dict:
    """Knee of a quantity's rows and where ``default`` lies relative to it."""
    pts = [(r["time"], r["error"]) for r in rows]
    kn = knee(pts)
    dflt = next((i for i, r in enumerate(rows) if r["label"] == default_label), None)
    out = {"front": [rows[i]["label"] for i in kn["front"]],
           "knee": rows[kn["knee"]]["label"] if kn["knee"] is not None else None,
           "knee_index": kn["knee"], "default": default_label if dflt is not None else None,
           "default_on_front": dflt in kn["front"] if dflt is not None else False,
           "at_knee": None, "time_factor": None, "error_factor": None,
           "default_dist": kn["dist"].get(dflt), "knee_dist": kn["dist"].get(kn["knee"]),
           "why": kn["why"]}
    if kn["knee"] is None or dflt is None:
        return out
    k = rows[kn["knee"]]
    d = rows[dflt]
    tf = d["time"] / k["time"]
    ef = max(d["error"], FLOOR) / max(k["error"], FLOOR)
    out["time_factor"], out["error_factor"] = tf, ef
    # within the factor in both: a setting that beats default only by timing noise
    # (same error, a few per cent faster) does not move default off the knee
    out["at_knee"] = bool(dflt == kn["knee"] or (
        1 / KNEE_FACTOR <= tf <= KNEE_FACTOR and 1 / KNEE_FACTOR <= ef <= KNEE_FACTOR))
    return out


def sweep_findings(q: dict) -> list:
    """Knobs with no effect on the error, and errors that grow with a finer setting."""
    out = []
    rows = q["rows"]
    for knob, idx in q.get("lines", {}).items():
        if len(idx) < 2:
            continue
        vals = [rows[i]["value"] if rows[i]["knob"] == knob else
                rows[i].get("defaults", {}).get(knob) for i in idx]
        errs = [rows[i]["error"] for i in idx]
        times = [rows[i]["time"] for i in idx]
        lo, hi = min(errs), max(errs)
        if hi <= 1.05 * lo or hi - lo <= FLOOR:
            out.append(("flat", knob, f"`{knob}` has no effect on the error over "
                        f"{_fmt_v(vals[0])} … {_fmt_v(vals[-1])} (all {lo:.3g}); time "
                        f"{_fmt_t(min(times))} … {_fmt_t(max(times))}."))
            continue
        for a in range(len(idx) - 1):
            if errs[a + 1] > 1.2 * errs[a] and errs[a + 1] - errs[a] > FLOOR:
                out.append(("up", knob, f"`{knob}`: the error grows from {errs[a]:.3g} at "
                            f"{_fmt_v(vals[a])} to {errs[a + 1]:.3g} at the finer "
                            f"{_fmt_v(vals[a + 1])}."))
    return out


# ------------------------------------------------------- (1) C-space boundary

def _metric(cs) -> float:
    """Scale of q2 into the C-space metric (1 for rotation, 1/L for a slide)."""
    return 1.0 if cs.periodic[1] else 1.0 / cs.pair.char_length


def cspace_quantity(factory, sweeps: dict, repeat: int, log=print) -> dict:
    """Time and boundary error of every setting on one model's first pair."""
    from cspace.freespace import configuration_space
    m = factory()
    pair, deps = m.build(), m.dependencies()[0]

    def run(acc):
        cs = configuration_space(pair, acc, window=m.window, deps=deps)
        cs.curve_polylines(boundary_only=True)
        return cs

    run(PRESETS["default"])                      # first-call costs of this process
    t_ref, _, ref = median_time(lambda: run(PRESETS["precise"].replace(**CSPACE_REF)), 1)
    rows = []
    for label, kind, knob, value, acc in accuracy_settings(sweeps):
        t, ts, cs = median_time(lambda: run(acc), repeat)
        s2 = _metric(cs)
        pe = polyline_error(cs, s2)
        ee = endpoint_error(cs, ref, s2)
        r = _row(label, kind, t, ts, max(pe["max_normal"], ee), knob, value,
                 vertical=pe["max"], normal=pe["max_normal"], endpoints=ee,
                 endpoints_q1=endpoint_error(cs, ref, s2, q1_only=True),
                 segments=pe["segments"], pieces=len(cs.boundary), ref_pieces=len(ref.boundary))
        r["defaults"] = _defaults_of(acc, sweeps)
        rows.append(r)
        log(f"  {m.name} {label:<22} {t:8.3f} s  error {r['error']:.3g}")
    unit = "rad" if ref.periodic[1] else f"{pair.units} / {pair.char_length:.4g} {pair.units}"
    lines = sweep_lines(rows, sweeps)
    notes = []
    fold = [r for r in rows if r["extra"]["endpoints"] > 100 * max(r["extra"]["endpoints_q1"],
                                                                    1e-16)]
    if fold:
        worst = max(fold, key=lambda r: r["extra"]["endpoints"])
        notes.append(
            f"In {len(fold)} of {len(rows)} settings the end-point error is more than 100× its"
            f" q1 part (worst: `{worst['label']}`, {_fmt_e(worst['extra']['endpoints'])} against"
            f" {_fmt_e(worst['extra']['endpoints_q1'])} in q1).  Those end points are folds, where"
            " the two branches of a curve meet with a vertical tangent: q2 there moves as the"
            " square root of the q1 error, so an end located to 1e-12 in q1 is uncertain by about"
            " 1e-7 in q2, in the reference too.  This is why the end-point column does not fall"
            " steadily along the `scan_step` sweep"
            + ("; no event is missed (every setting has the reference's piece count)."
               if all(r["extra"]["pieces"] == r["extra"]["ref_pieces"] for r in rows) else "."))
    for knob in ("root_tol", "scan_step"):
        if knob in lines:
            vals = [rows[i]["value"] if rows[i]["knob"] == knob else rows[i]["defaults"][knob]
                    for i in lines[knob]]
            notes.append(f"End-point error alone along the `{knob}` sweep: " + ", ".join(
                f"{_fmt_v(v)} → {_fmt_e(rows[i]['extra']['endpoints'])}"
                for v, i in zip(vals, lines[knob])) + ".")
    return {"rows": rows, "lines": lines, "baseline": "fast",
            "unit": unit, "ref_time": t_ref, "model": m.name,
            "ref_pieces": len(ref.boundary), "notes": notes}


# ------------------------------------------------------------ (2) zone bands

def _interp_nan(x, xp, fp):
    """Linear interpolation that propagates NaN from either bracketing sample."""
    x = np.asarray(x, dtype=float)
    j = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, len(xp) - 2)
    w = (x - xp[j]) / (xp[j + 1] - xp[j])
    return fp[j] * (1 - w) + fp[j + 1] * w


def band_error(z, zref) -> dict:
    """Band error of a ZoneAnalysis against a reference one on the same curves."""
    refs = {b.curve: b for b in zref.bands}
    worst = at_samples = narrower = wider = 0.0
    worst_curve = None
    uncovered = 0
    width = 0.0
    for b in z.bands:
        r = refs[b.curve]
        with np.errstate(invalid="ignore"):
            width = max(width, float(np.nanmax(np.append(r.upper - r.lower, 0.0))))
        for side, sgn in (("upper", 1.0), ("lower", -1.0)):
            fb, fr = getattr(b, side), getattr(r, side)
            # the setting's band read as piecewise linear, at the reference samples
            yi = _interp_nan(r.q1, b.q1, fb)
            ok = np.isfinite(yi) & np.isfinite(fr)
            uncovered += int(np.sum(np.isfinite(fr) & ~np.isfinite(yi)))
            if ok.any():
                d = yi[ok] - fr[ok]
                if float(np.max(np.abs(d))) > worst:
                    worst, worst_curve = float(np.max(np.abs(d))), f"{b.label} ({b.branch:+d})"
                narrower = max(narrower, float(np.max(-sgn * d)))
                wider = max(wider, float(np.max(sgn * d)))
            # at the setting's own samples (reference interpolated there)
            ri = _interp_nan(b.q1, r.q1, fr)
            ok = np.isfinite(ri) & np.isfinite(fb)
            if ok.any():
                at_samples = max(at_samples, float(np.max(np.abs(fb[ok] - ri[ok]))))
    return {"error": worst, "at_samples": at_samples, "narrower": max(narrower, 0.0),
            "wider": max(wider, 0.0), "uncovered": uncovered, "ref_width": width,
            "worst_curve": worst_curve}


def zones_quantity(factory, sweeps: dict, ref_knobs: dict, repeat: int, curve_labels=None,
                   log=print) -> dict:
    """Time and band error of every zone setting on a fixed nominal C-space."""
    from cspace.defects import reference
    from cspace.zones import contact_zones
    m = factory()
    nom = reference(m, "precise")
    cs, face = nom.spaces[0], nom.faces[0]
    curves = sorted({b.curve for b in cs.boundary if b.free_face == face})
    if curve_labels is not None:
        chosen = []
        for lab in curve_labels:
            k = next((c for c in curves if cs.curves[c].label == lab), None)
            if k is None:
                raise RuntimeError(f"{m.name}: no operating-channel curve {lab!r}")
            chosen.append(k)
        curves = chosen

    def run(acc):
        return contact_zones(cs, m, 0, acc, curves=curves)

    run(PRESETS["fast"])                         # first-call costs of this process
    ref_knobs = {k: v for k, v in ref_knobs.items() if hasattr(PRESETS["precise"], k)}
    ref_acc = PRESETS["precise"].replace(**ref_knobs)
    t_ref, _, zref = median_time(lambda: run(ref_acc), 1)
    ref_floor = 0.0
    for b in zref.bands:
        for side in ("upper", "lower"):
            f = getattr(b, side)
            half = _interp_nan(b.q1[1::2], b.q1[::2], f[::2])
            ok = np.isfinite(half) & np.isfinite(f[1::2])
            if ok.any():
                ref_floor = max(ref_floor, float(np.max(np.abs(half[ok] - f[1::2][ok]))) / 4)
    log(f"  {m.name} zone reference {t_ref:.1f} s ({zref.stats['vectors_evaluated']} vectors)")
    rows = []
    for label, kind, knob, value, acc in accuracy_settings(sweeps):
        t, ts, z = median_time(lambda: run(acc), repeat)
        e = band_error(z, zref)
        r = _row(label, kind, t, ts, e["error"], knob, value, at_samples=e["at_samples"],
                 narrower=e["narrower"], wider=e["wider"], uncovered=e["uncovered"],
                 vectors=z.stats["vectors_evaluated"], ref_width=e["ref_width"],
                 worst_curve=e["worst_curve"])
        r["defaults"] = _defaults_of(acc, sweeps)
        rows.append(r)
        log(f"  {m.name} {label:<26} {t:8.3f} s  error {e['error']:.3g} "
            f"(at samples {e['at_samples']:.3g})")
    deps = [len(cs.curves[c].depends) for c in curves]
    notes = []
    d = PRESETS["default"]
    notes.append(f"The reference band read as piecewise linear is itself off by about"
                 f" {ref_floor:.2g} between its samples (a quarter of the error of every other"
                 " reference sample): the floor of the `at own samples` column.")
    if 2 ** max(deps) <= d.zone_max_corners:
        notes.append(f"Every curve here depends on at most {max(deps)} parameters: at"
                     f" `default` (zone_max_corners {d.zone_max_corners}) all"
                     f" {2 ** max(deps)} box corners are evaluated, so"
                     " `zone_random_corners` (used only for larger dependency sets) cannot"
                     " act, and `zone_max_corners` acts only below"
                     f" {2 ** max(deps)}.")
    elif 2 ** min(deps) > d.zone_max_corners:
        notes.append(f"Every curve here depends on {min(deps)}–{max(deps)} parameters"
                     f" (2^m ≥ {2 ** min(deps)} corners): below that `zone_max_corners`"
                     " changes nothing, the bands come from the linearly extreme corners plus"
                     " `zone_random_corners` seeded ones.")
    dr = next(r["extra"] for r in rows if r["label"] == "default")
    if dr["wider"] > 2 * dr["narrower"]:
        notes.append(f"At `default` the error is mostly the band reaching beyond the reference's"
                     f" (by up to {dr['wider']:.3g}; it falls inside it by at most"
                     f" {dr['narrower']:.3g}), worst on `{dr['worst_curve']}`: the conservative"
                     " side, which shrinks with denser samples.")
    nc = next((r["extra"] for r in rows if r["knob"] == "zone_climb" and r["value"] == 0), None)
    if nc is not None and nc["narrower"] > 2 * max(dr["narrower"], 1e-300):
        notes.append(f"Without the corner hill-climb (`zone_climb=0`) the band falls inside the"
                     f" reference's by up to {nc['narrower']:.3g} (at `default`:"
                     f" {dr['narrower']:.3g}): there the climb finds extremes the linear guide"
                     " misses.")
    pu = cs.pair.units
    unit = "rad" if cs.periodic[1] else f"{pu} / {cs.pair.char_length:.4g} {pu}"
    return {"rows": rows, "lines": sweep_lines(rows, sweeps), "baseline": "fast", "unit": unit,
            "ref_time": t_ref, "model": m.name, "curves": [cs.curves[c].label for c in curves],
            "deps": deps, "ref_knobs": dict(ref_knobs), "notes": notes,
            "ref_vectors": zref.stats["vectors_evaluated"]}


# ------------------------------------------------------- (3) transition point

def _fresh_ref(m, ref):
    """The reference with a new curve cache holding only the nominal curves."""
    from cspace.cache import CurveCache
    from cspace.freespace import configuration_space
    cache = CurveCache()
    for pair, deps in zip(m.pairs(), m.dependencies()):
        configuration_space(pair, ref.accuracy, window=m.window, deps=deps, cache=cache)
    return dataclasses.replace(ref, cache=cache)


def search_once(m, ref, targets, eps_rel: float):
    """(seconds, defect tests, transitions) of one bisection with serial defect tests."""
    from cspace.defects import is_defective
    from synthesis.removal import transition_points
    r = _fresh_ref(m, ref)
    n = [0]

    def batch(us):
        n[0] += len(us)
        return [is_defective(m, u, ref=r).defective for u in us]

    t0 = time.perf_counter()
    trs = transition_points(m.nominal, targets, batch, eps_rel * float(np.max(m.tol)))
    return time.perf_counter() - t0, n[0], trs


def search_quantity(sweeps: dict, n_vectors: int, ref_eps: float = 1e-6, log=print) -> dict:
    """Time and transition-point error of the presets and the search_eps sweep."""
    from cspace.defects import is_defective, reference
    from mechanisms.models import reciprocating_cam
    m = reciprocating_cam()
    targets = [m.nominal + np.array(p, dtype=float) * m.tol for p in SEARCH_PATTERNS[:n_vectors]]
    refs = {p: reference(m, p) for p in PRESET_NAMES}
    for p, ref in refs.items():
        for j, u in enumerate(targets):
            if not is_defective(m, u, ref=ref).defective:
                raise RuntimeError(f"search target {j} is healthy at preset {p}")
    truth = {}
    for p in ("default", "precise"):
        t, n, trs = search_once(m, refs[p], targets, ref_eps)
        truth[p] = [0.5 * (tr.healthy + tr.defective) for tr in trs]
        log(f"  transition reference at {p}: {t:.1f} s, {n} defect tests, "
            f"lambda {[round(0.5 * sum(tr.lam), 7) for tr in trs]}")

    def err(trs, key):
        return max(float(np.max(np.abs(tr.healthy - x))) for tr, x in zip(trs, truth[key]))

    rows = []
    for label, kind, knob, value, acc in accuracy_settings(sweeps):
        ref = refs[label] if kind == "preset" else refs["default"]
        key = "precise" if kind == "preset" else "default"
        t, n, trs = search_once(m, ref, targets, acc.search_eps)
        r = _row(label, kind, t, [t], err(trs, key), knob, value, tests=n,
                 steps=max(tr.steps for tr in trs), against=key,
                 err_default=err(trs, "default"),
                 lam=[round(tr.lam[0], 7) for tr in trs])
        r["defaults"] = _defaults_of(acc, sweeps)
        rows.append(r)
        log(f"  search {label:<20} {t:7.2f} s  {n:3d} tests  error {r['error']:.3g} cm")
    shift = max(float(np.max(np.abs(a - b))) for a, b in zip(truth["default"], truth["precise"]))
    return {"rows": rows, "lines": sweep_lines(rows, sweeps), "baseline": "fast", "unit": "cm",
            "vectors": len(targets), "truth_shift": shift, "ref_eps": ref_eps}


# ---------------------------------------------------------------- (4) synthesis

def synthesis_quantity(presets, workers: int = 2, log=print) -> dict:
    """Wall time, e, iterations and final nominal of a synthesis per preset."""
    from mechanisms.models import reciprocating_cam
    from synthesis import make_executor, synthesize
    runs = {}
    with make_executor("process", workers) as ex:
        t_pool = start_pool(ex, workers)
        for p in presets:
            t0 = time.perf_counter()
            r = synthesize(reciprocating_cam(), p, executor=ex)
            wall = time.perf_counter() - t0
            runs[p] = {"wall": wall, "status": r.status.name, "nit": r.nit, "e": float(r.e),
                       "u": np.array(r.nominal, dtype=float), "tol": np.array(r.tol, dtype=float),
                       "defects": list(r.defects_per_iteration()),
                       "tests": int(sum(h.tests for h in r.history))}
            log(f"  synthesis {p:<8} {wall:7.2f} s  {r.status.name} in {r.nit} iterations, "
                f"e {r.e:.5g}")
    key = "precise" if "precise" in runs else presets[-1]
    model = reciprocating_cam()
    rows = []
    for p, d in runs.items():
        e = float(np.max(np.abs(d["u"] - runs[key]["u"])))
        rows.append(_row(p, "reference" if p == key else "preset", d["wall"], [d["wall"]], e,
                         status=d["status"], nit=d["nit"], e=d["e"], defects=d["defects"],
                         tests=d["tests"], dtol=float(np.max(np.abs(d["tol"] - runs[key]["tol"]))),
                         u=d["u"].tolist()))
    return {"rows": rows, "lines": {}, "baseline": "fast", "unit": "cm", "reference": key,
            "pool_start": t_pool, "workers": workers, "names": list(model.names),
            "tol0": float(np.max(model.tol))}


# ------------------------------------------------------------------ (5) four-bar

def fourbar_quantity(quick: bool, log=print) -> dict:
    """Time and error of the four-bar's ways to find the largest error over the pin."""
    from bench_fourbar import CRANK, FB, reference_max
    from mechanisms.linkage.error import (ToleranceSpec, exact_error, harmonic_max,
                                          monte_carlo, worst_case)
    r_cl = 0.1
    ref = reference_max(r_cl)
    spec = ToleranceSpec(clearances={"B": r_cl})
    rep = 3 if quick else 5
    rows = []

    def add(label, kind, knob, value, fn, seeds=None, default=False):
        if seeds:
            vals = [fn(s) for s in seeds]
            e = float(np.mean([abs(v - ref) for v in vals]))
            t, ts = auto_time(lambda: fn(seeds[0]), repeat=rep)
        else:
            v = fn(None)
            e = abs(v - ref)
            t, ts = auto_time(lambda: fn(None), repeat=rep)
        row = _row(label, kind, t, ts, e, knob, value, rel=e / ref, library_default=default)
        rows.append(row)
        log(f"  four-bar {label:<24} {t * 1e3:9.3f} ms  error {e:.3g} rad")

    add("harmonic_max", "method", None, None,
        lambda s: harmonic_max(FB, CRANK, "B", r_cl).max_value)

    def h1(_):
        h = harmonic_max(FB, CRANK, "B", r_cl)
        return float(exact_error(FB, CRANK, joint="B", radius=r_cl,
                                 delta=h.delta_max).d_theta4[0])
    add("harmonic_max + 1 exact", "method", None, None, h1)
    for n in ((8, 36, 360) if quick else (8, 16, 36, 90, 360, 3600)):
        d = np.linspace(0, 2 * math.pi, n, endpoint=False)
        add(f"sweep {n}", "knob", "sweep points", n,
            lambda s, d=d: float(exact_error(FB, CRANK, joint="B", radius=r_cl,
                                             delta=d).d_theta4.max()))
    seeds = list(range(5 if quick else 10))
    for n in ((10, 100, 1000) if quick else (10, 100, 1000, 10000, 100000)):
        add(f"monte_carlo n={n}", "knob", "monte_carlo n", n,
            lambda s, n=n: monte_carlo(FB, CRANK, spec, n, seed=s).maximum, seeds=seeds,
            default=(n == 1000))
    for it in ((1, 3, 200) if quick else (1, 2, 3, 5, 200)):
        add(f"worst_case maxiter={it}", "knob", "worst_case maxiter", it,
            lambda s, it=it: worst_case(FB, CRANK, spec, maxiter=it).exact_max,
            default=(it == 200))
    lines = {}
    for knob in ("sweep points", "monte_carlo n", "worst_case maxiter"):
        lines[knob] = sorted((i for i, r in enumerate(rows) if r["knob"] == knob),
                             key=lambda i: rows[i]["value"])
    return {"rows": rows, "lines": lines, "baseline": None, "unit": "rad", "reference_value": ref,
            "clearance": r_cl, "seeds": len(seeds)}


# --------------------------------------------------------------- (6) spatial loops

SPH_ALPHAS = (0.5, 1.5, 1.0, 1.2)
RSSR_ARGS = dict(crank=1.0, crank_height=0.5, coupler=3.0, rocker=2.0, offset=2.5,
                 twist=math.radians(60), rocker_height=0.5)


def _spatial_cases(n_inputs: int):
    from mechanisms.spatial import closedform as cf
    from mechanisms.spatial import frame_transforms, rssr, spherical_4r
    geo = cf.RSSRGeometry(*(RSSR_ARGS[k] for k in ("crank", "crank_height", "coupler", "rocker",
                                                   "offset", "twist", "rocker_height")))
    z3 = np.array([0.0, math.sin(SPH_ALPHAS[3]), math.cos(SPH_ALPHAS[3])])
    ux = np.array([1.0, 0.0, 0.0])

    def out_sph(lk, q):
        z2 = (lk.ground @ frame_transforms(lk.loop, q))[2][:3, 2]
        return math.atan2(z2 @ np.cross(z3, ux), z2 @ ux)

    def out_rssr(lk, q):
        return geo.phi_of((lk.ground @ frame_transforms(lk.loop, q))[4][:3, 3])

    cases = []
    for name, lk, out, closed in (
            ("spherical 4R", spherical_4r(SPH_ALPHAS, 0.3), out_sph,
             lambda x: cf.spherical_4r_psi(SPH_ALPHAS, x, 1)[0]),
            ("RSSR", rssr(**RSSR_ARGS, theta=0.3), out_rssr, lambda x: cf.rssr_phi(geo, x, 1)[0])):
        xs = lk.q0[lk.loop.input] + np.linspace(0.0, 2 * math.pi, n_inputs)
        cases.append((name, lk, xs, out, np.array([closed(x) for x in xs])))
    return cases


def spatial_quantity(quick: bool, repeat: int, log=print) -> dict:
    """Time, output error and loop residual of the loop solver per SolverOptions."""
    from mechanisms.spatial import SolverOptions, loop_residual, solve_path
    n_inputs = 91 if quick else 361
    cases = _spatial_cases(n_inputs)
    D = SolverOptions()
    settings = [("default", "preset", None, None, D)]
    sw = ({"tol": (1e-2, 1e-6, 1e-12, 1e-14), "max_step (solver)": (0.05, 0.5),
           "max_iter": (1, 50)} if quick else
          {"tol": (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14),
           "max_step (solver)": (0.05, 0.5, 2.0), "max_iter": (1, 2, 50)})
    field_of = {"tol": "tol", "max_step (solver)": "max_step", "max_iter": "max_iter"}
    for knob, values in sw.items():
        for v in values:
            if v == getattr(D, field_of[knob]):
                continue
            settings.append((f"{field_of[knob]}={v:g}", "knob", knob, v,
                             dataclasses.replace(D, **{field_of[knob]: v})))
    for name, lk, xs, out, ref in cases:      # first-call costs
        solve_path(lk.loop, xs[:5], lk.q0)
    rows = []
    for label, kind, knob, value, opts in settings:
        total, times, err, res, its, bad = 0.0, [], 0.0, 0.0, 0, 0
        per = {}
        for name, lk, xs, out, ref in cases:
            t, ts, path = median_time(lambda: solve_path(lk.loop, xs, lk.q0, options=opts), repeat)
            hd = np.array([out(lk, q) for q in path.q])
            e = float(np.max(np.abs((hd - ref + math.pi) % (2 * math.pi) - math.pi)))
            rr = max(loop_residual(lk.loop, q) for q in path.q)
            total += t
            times.append(ts)
            err, res = max(err, e), max(res, rr)
            its += int(path.iterations.sum())
            bad += int(np.sum(path.status > 1))
            per[name] = {"time": t, "error": e, "residual": rr}
        r = _row(label, kind, total, [sum(x) for x in zip(*times)], err, knob, value,
                 residual=res, iterations=its, failed=bad, per=per)
        r["defaults"] = {"tol": D.tol, "max_step (solver)": D.max_step, "max_iter": D.max_iter}
        rows.append(r)
        log(f"  spatial {label:<16} {total:7.3f} s  error {err:.3g} rad, residual {res:.3g}")
    return {"rows": rows, "lines": sweep_lines(rows, sw), "baseline": "default", "unit": "rad",
            "inputs": n_inputs}


# ------------------------------------------------------------------- report

def _fmt_t(s) -> str:
    if s is None or not math.isfinite(s):
        return "—"
    if s < 0.9995e-3:
        return f"{s * 1e6:.3g} µs"
    if s < 0.9995:
        return f"{s * 1e3:.3g} ms"
    return f"{s:.3g} s"


def _fmt_v(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, (int, np.integer)):
        return str(v)
    return f"{v:g}"


def _fmt_e(e) -> str:
    if e is None:
        return "—"
    if not math.isfinite(e):
        return "∞"
    return "0" if e == 0 else f"{e:.3g}"


TITLES = {
    "cspace_geneva": "C-space boundary, Geneva",
    "cspace_cam": "C-space boundary, reciprocating cam",
    "zones_cam": "Zone bands, reciprocating cam",
    "zones_geneva": "Zone bands, Geneva (3 curves)",
    "search": "Transition point (search_eps), reciprocating cam",
    "synthesis": "Synthesized nominal, reciprocating cam",
    "fourbar": "Four-bar: largest error over the pin angle",
    "spatial": "Spatial loops: RSSR and spherical 4R",
}
ORDER = tuple(TITLES)


def _baseline_time(q: dict):
    b = q.get("baseline")
    r = next((r for r in q["rows"] if r["label"] == b), None)
    return (b, r["time"]) if r else (None, None)


def _ratio(q, r) -> str:
    _, tb = _baseline_time(q)
    return "—" if not tb else f"{r['time'] / tb:.2f}×"


def quantity_table(key: str, q: dict) -> list:
    """Markdown lines of one quantity's table."""
    base, _ = _baseline_time(q)
    rc = f"time / {base}" if base else "time ratio"
    rows = q["rows"]
    L = []
    if key.startswith("cspace"):
        L += [f"| setting | time (median) | repeats | {rc} | error ({q['unit']}) |"
              " polyline, normal | polyline, vertical | end points | end points, q1 only |"
              " boundary pieces |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for r in rows:
            x = r["extra"]
            L.append(f"| {r['label']} | {_fmt_t(r['time'])} | {len(r['times'])} | {_ratio(q, r)} | "
                     f"{_fmt_e(r['error'])} | {_fmt_e(x['normal'])} | {_fmt_e(x['vertical'])} | "
                     f"{_fmt_e(x['endpoints'])} | {_fmt_e(x['endpoints_q1'])} | "
                     f"{x['pieces']} / {x['ref_pieces']} |")
    elif key.startswith("zones"):
        L += [f"| setting | time (median) | repeats | {rc} | error ({q['unit']}) |"
              " at own samples | narrower than ref. | wider than ref. | vectors |"
              + (" worst curve |" if len({r["extra"].get("worst_curve") for r in rows}) > 1
                 or len(q.get("curves", ())) > 1 else ""),
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
              + ("---|" if len({r["extra"].get("worst_curve") for r in rows}) > 1
                 or len(q.get("curves", ())) > 1 else "")]
        wc = L[-2].endswith("worst curve |")
        for r in rows:
            x = r["extra"]
            L.append(f"| {r['label']} | {_fmt_t(r['time'])} | {len(r['times'])} | {_ratio(q, r)} | "
                     f"{_fmt_e(r['error'])} | {_fmt_e(x['at_samples'])} | "
                     f"{_fmt_e(x['narrower'])} | {_fmt_e(x['wider'])} | {x['vectors']} |"
                     + (f" `{x.get('worst_curve')}` |" if wc else ""))
    elif key == "search":
        L += [f"| setting | search time | {rc} | defect tests | bisection steps |"
              " error (cm) | against | error vs default-accuracy transition |",
              "|---|---:|---:|---:|---:|---:|---|---:|"]
        for r in rows:
            x = r["extra"]
            L.append(f"| {r['label']} | {_fmt_t(r['time'])} | {_ratio(q, r)} | {x['tests']} | "
                     f"{x['steps']} | {_fmt_e(r['error'])} | {x['against']} | "
                     f"{_fmt_e(x['err_default'])} |")
    elif key == "synthesis":
        L += [f"| preset | wall time | {rc} | status | iterations | defects per iteration |"
              f" defect tests | e (cm) | error: max abs(u − u_{q['reference']}) (cm) |"
              " max abs(t − t_ref) (cm) |",
              "|---|---:|---:|---|---:|---|---:|---:|---:|---:|"]
        for r in rows:
            x = r["extra"]
            L.append(f"| {r['label']}{' (reference)' if r['kind'] == 'reference' else ''} | "
                     f"{_fmt_t(r['time'])} | {_ratio(q, r)} | {x['status']} | {x['nit']} | "
                     f"{', '.join(map(str, x['defects']))} | {x['tests']} | {x['e']:.5g} | "
                     f"{_fmt_e(r['error'])} | {_fmt_e(x['dtol'])} |")
    elif key == "fourbar":
        L += ["| method / setting | time per call (median) | error (rad) | relative error |"
              " library default |",
              "|---|---:|---:|---:|---|"]
        for r in rows:
            x = r["extra"]
            L.append(f"| {r['label']} | {_fmt_t(r['time'])} | {_fmt_e(r['error'])} | "
                     f"{x['rel']:.3g} | {'yes' if x['library_default'] else ''} |")
    elif key == "spatial":
        L += [f"| SolverOptions | time, both paths (median) | {rc} | output error (rad) |"
              " loop residual | Newton iterations | poses not converged |",
              "|---|---:|---:|---:|---:|---:|---:|"]
        for r in rows:
            x = r["extra"]
            L.append(f"| {r['label']} | {_fmt_t(r['time'])} | {_ratio(q, r)} | "
                     f"{_fmt_e(r['error'])} | {_fmt_e(x['residual'])} | {x['iterations']} | "
                     f"{x['failed']} |")
    return L


def _knee_text(key: str, q: dict) -> str:
    v = q["knee"]
    rows = q["rows"]
    if v["knee"] is None:
        if v["why"] == "concave":
            return (f"front {', '.join(v['front'])}: no front point lies below the chord between"
                    " its ends (in log-log the front bends the other way: each further decade"
                    " of accuracy costs less time than the one before), so there is no knee.")
        return (f"front {', '.join(v['front']) or '—'}: fewer than 3 front points, no knee"
                " computed.")
    k = rows[v["knee_index"]]
    ft = [r["time"] for r in rows if r["label"] in v["front"]]
    s = (f"front {len(v['front'])} of {len(rows)} settings, spanning {max(ft) / min(ft):.3g}× in"
         f" time; knee **{v['knee']}**"
         f" ({_fmt_t(k['time'])}, error {_fmt_e(k['error'])}, {v['knee_dist']:.2f} decades"
         " below the chord" + ("; a weak knee: the front is nearly straight, and times this"
                               " close are within the noise" if v["knee_dist"] < 0.1 else "")
         + ")")
    if v["default"] is None:
        return s + "."
    if v["at_knee"]:
        if v["knee"] == v["default"]:
            return s + f" — `{v['default']}` **is the knee**."
        where = ("on the front" if v["default_on_front"] else
                 "not on the front (beaten by noise-level margins)")
        return (s + f" — `{v['default']}` is {where}, within {KNEE_FACTOR:g}× of the knee"
                f" (time ×{v['time_factor']:.2f}, error ×{v['error_factor']:.2g}):"
                " **at the knee**.")
    where = "on the front" if v["default_on_front"] else "**not on the front** (dominated)"
    return (s + f" — `{v['default']}` is {where}, time ×{v['time_factor']:.2f} and error"
            f" ×{v['error_factor']:.2g} of the knee: **not at the knee**.")


def _sweep_knees(q: dict) -> list:
    """Per knob sweep: its own knee and where the default value lies."""
    out = []
    rows = q["rows"]
    for knob, idx in q.get("lines", {}).items():
        sub = [rows[i] for i in idx]
        if len(sub) < 3:
            continue
        kn = knee([(r["time"], r["error"]) for r in sub])
        if kn["knee"] is None:
            out.append(f"`{knob}`: no knee (" + ("its front bends the other way"
                       if kn["why"] == "concave" else f"{len(kn['front'])} front point(s)") + ")")
            continue
        kr = sub[kn["knee"]]
        val = kr["value"] if kr["knob"] == knob else kr.get("defaults", {}).get(knob)
        dv = next((r.get("defaults", {}).get(knob) for r in rows if r["label"] == "default"),
                  None)
        lib = [r for r in sub if r["extra"].get("library_default")]
        if lib:
            dv = lib[0]["value"]
        out.append(f"`{knob}` knee at {_fmt_v(val)}" + (f" (default {_fmt_v(dv)})"
                                                        if dv is not None else ""))
    return out


def report(qs: dict, info: dict, quick: bool, total: float, loads: tuple,
           img_rel: str = "../img/pareto.png") -> str:
    L: list = []
    P = L.append
    P("# Benchmark: speed/accuracy trade of the approximating knobs (Pareto)")
    P("")
    P("Script: `benchmarks/bench_accuracy.py` (run `python benchmarks/bench_accuracy.py`"
      + (", here with `--quick`" if quick else "") + ").  Every figure below was measured in"
      " one run of that script; every error is against a reference computed in the same run"
      " and every time ratio against a baseline measured in the same run.")
    P("")
    P(f"- date: {info['date']}")
    P(f"- machine: {info['nproc']} cores ({info['platform']}), Python {info['python']},"
      f" numpy {info['numpy']}, scipy {info['scipy']}")
    if info.get("code"):
        P(f"- code: {info['code']}")
    P(f"- mode: {'quick' if quick else 'full'}; whole run {total:.0f} s")
    P(f"- load average (1, 5, 15 min) at the start {loads[0]}, at the end {loads[1]}")
    P("")
    P(f"![time against error, one panel per quantity]({img_rel})")
    P("")
    P("## Method")
    P("")
    P("- **Settings.** For the quantities computed with `cspace.accuracy.Accuracy`: the three"
      " presets, and each knob of the quantity varied alone with the others at `default`"
      " (`Accuracy.preset(\"default\").replace(knob=value)`, rows `knob=value`; the sweep value"
      " equal to the default's is the `default` row).  The four-bar and spatial-loop modules do"
      " not read `Accuracy`; their own knobs are swept around the library defaults, and their"
      " time ratios are against that default.")
    P("- **Times** are wall times (`time.perf_counter`), the median of the stated number of"
      " calls after a first-call warm-up of the process; the synthesis runs on a process pool,"
      " whose work `time.process_time` would not see.  Other work shared the 2 cores (load"
      " average above), so the times are noisy: differences below about 20 % are not"
      " significant.")
    P("- **C-space boundary** (Geneva pair; reciprocating cam): time of `configuration_space("
      "pair, acc, window=model.window, deps=...)` plus `cs.curve_polylines(boundary_only=True)`"
      " (polylines are built on demand; `chord` and `max_step` act there).  Error, in the"
      " C-space metric (rad; for the cam's slide, cm divided by the characteristic length"
      " 2.5 cm): the larger of the largest polyline-to-exact-curve distance normal to the"
      " segment (7 interior points per segment) and the Hausdorff distance of the"
      " boundary-piece end points from a reference C-space finer than `precise` (chord 2e-6,"
      " max_step 0.005, root_tol 1e-14, scan_step 0.0025).  The vertical (q2) polyline error"
      " is listed beside it.")
    zc = qs.get("zones_cam")
    if zc:
        P("- **Zone bands**: `contact_zones(cs, model, 0, acc, curves=...)` on the model's nominal"
          " `precise` C-space, the same curves for every setting (the cam: its"
          f" {len(zc['curves'])} operating-channel curves, dependency sets of"
          f" {min(zc['deps'])}–{max(zc['deps'])} parameters"
          + (f"; Geneva: {', '.join('`' + c + '`' for c in qs['zones_geneva']['curves'])},"
             f" {min(qs['zones_geneva']['deps'])}–{max(qs['zones_geneva']['deps'])} parameters"
             if qs.get("zones_geneva") else "") + ").  Reference: `precise` with "
          + ", ".join(f"{k} {v}" for k, v in zc["ref_knobs"].items())
          + (" (Geneva: " + ", ".join(f"{k} {v}" for k, v
                                       in qs["zones_geneva"]["ref_knobs"].items())
             + ")" if qs.get("zones_geneva") else "")
          + ".  Error: the setting's upper and lower bands, read as piecewise linear between its"
          " samples, against the reference bands at the reference's samples (largest absolute"
          " difference, C-space metric).  `at own samples`: the same difference at the setting's"
          " samples (reference interpolated), which leaves out the sampling of the band;"
          " `narrower`/`wider`: by how much the band falls inside / reaches beyond the"
          " reference's (a wider band means the reference missed an extreme).")
    sq = qs.get("search")
    if sq:
        P("- **Transition point**: `synthesis.removal.transition_points` from the cam's nominal"
          f" towards {sq['vectors']} defective iteration-1 check-list vectors (cam fingers"
          " against the yoke faces; ± tolerance patterns in the script), serial defect tests"
          " against a nominal reference whose curve cache is refilled with only the nominal"
          " curves before every search (no search reuses another's variants).  The time is that"
          " of the search alone (the nominal reference is built outside the clock); the"
          " number of defect tests is a noise-free measure of the same cost.  Error: max-norm"
          " distance (cm) of the healthy bracket end from the transition point found with"
          f" search_eps = {sq['ref_eps']:g} — at default accuracy for the `search_eps` rows, at"
          " `precise` accuracy for the presets (so a preset's error includes the shift of its"
          " own defect test).")
    syq = qs.get("synthesis")
    if syq:
        P("- **Synthesis**: `synthesize(reciprocating_cam(), preset, executor=pool)`, one run"
          f" per preset on one process pool of {syq['workers']} workers, started (and warmed)"
          f" before the clock ({syq['pool_start']:.1f} s).  Error: max |u_final −"
          f" u_final({syq['reference']})| in cm"
          + ("; `precise` was not run in quick mode, so `default` is the reference." if
             syq["reference"] != "precise" else ".")
          + f"  The initial tolerances are ±{syq['tol0']:g} cm.")
    fq = qs.get("fourbar")
    if fq:
        P("- **Four-bar**: the largest exact output-angle error max over δ of dθ4(δ) of the"
          " four-bar of [Shin & Choi 1995](../references.md#shin--choi-1995) with a clearance"
          f" {fq['clearance']:g} at pin B (the case of"
          " `bench_fourbar.py`); reference: a 36 000-point sweep refined by bounded maximisation"
          f" ({fq['reference_value']:.10e} rad).  Monte Carlo: pins on the clearance circle,"
          f" error averaged over {fq['seeds']} seeds.  Times per call: median of repeated loops"
          " of at least 50 ms.")
    spq = qs.get("spatial")
    if spq:
        P(f"- **Spatial loops**: `solve_path` over one input revolution ({spq['inputs']} inputs)"
          " of the spherical 4R (arcs 0.5, 1.5, 1.0, 1.2 rad) and the RSSR of the tests, time"
          " summed over both.  Error: the largest difference of the output angle from the"
          " closed-form input-output equations (`closedform.spherical_4r_psi`, `rssr_phi`),"
          " over both; the largest loop residual (`loop_residual`) beside it.")
    P(f"- **Knee**: the Pareto front is the set of settings no other setting beats in both"
      " time and error.  In log10(time)–log10(error) space, the knee is the front point"
      " farthest below the chord joining the front's extreme points (fastest and most"
      f" accurate).  `default` is *at the knee* when it is the knee point or lies within"
      f" {KNEE_FACTOR:g}× of the knee in both time and error (whether or not it is on the front:"
      " a setting that beats it only by timing noise does not move it off the knee).  Errors"
      f" below {FLOOR:g} count as that on the log axes.")
    P("")

    P("## Knobs")
    P("")
    zk = list(qs["zones_cam"]["lines"]) if qs.get("zones_cam") else []
    P("- Measured here: `chord`, `max_step`, `root_tol`, `scan_step` (C-space); "
      + ", ".join(f"`{k}`" for k in zk) + " (zones); `search_eps` (transition point); all of"
      " them together through the presets in the synthesis.")
    P("- `Accuracy` knobs not swept: `merge_rel` and `contact_rel` (identity and contact"
      " thresholds, not approximations with a time cost), `sim_step` (output sampling of the"
      " simulation), `filter_eps` (check-list filter) and `handover_reach` (check-list"
      " hand-over partners); they act in the synthesis only through the presets.")
    P("- The four-bar error module (`mechanisms.linkage.error`) has no `Accuracy` and no"
      " preset: its approximating knobs are function arguments — the pin-angle sweep density"
      " (the `delta` array passed to `exact_error`), `monte_carlo(n=1000)` and"
      " `worst_case(maxiter=200)`; `harmonic_max` has none (always 3 evaluations).  Its"
      " `LinkageTolerances` are classification thresholds (toggle, tangency), not"
      " approximations.")
    P("- The spatial solver (`mechanisms.spatial`) has no `Accuracy` either: its knobs are"
      " `SolverOptions` (tol 1e-12, max_step 0.5, max_iter 50 by default; `max_halvings`,"
      " `max_subdivisions`, `jump_factor` and `singular_rel` are robustness and"
      " classification settings, not swept).")
    P("")

    P("## Summary")
    P("")
    P("| quantity | error unit | fast: time / error | default: time / error |"
      " precise: time / error | knee | default at the knee? |")
    P("|---|---|---|---|---|---|---|")
    for key in ORDER:
        q = qs.get(key)
        if not q:
            continue
        cells = []
        for p in PRESET_NAMES:
            r = next((r for r in q["rows"] if r["label"] == p), None)
            cells.append("—" if r is None else f"{_fmt_t(r['time'])} / {_fmt_e(r['error'])}")
        v = q["knee"]
        if key == "fourbar":
            verdict = "no presets (library defaults: see below)"
        elif v["knee"] is None:
            verdict = "no knee"
        else:
            verdict = "yes" if v["at_knee"] else "no"
            if v["knee_dist"] is not None and v["knee_dist"] < 0.1:
                verdict += " (weak knee)"
        P(f"| {TITLES[key]} | {q['unit']} | " + " | ".join(cells)
          + f" | {v['knee'] or '—'} | {verdict} |")
    P("")

    for key in ORDER:
        q = qs.get(key)
        if not q:
            continue
        P(f"## {TITLES[key]}")
        P("")
        L.extend(quantity_table(key, q))
        P("")
        P("- Knee: " + _knee_text(key, q))
        sk = _sweep_knees(q)
        if sk:
            P("- Knee of each knob's own sweep: " + "; ".join(sk) + ".")
        for _, _, text in q.get("findings", ()):
            P("- " + text)
        for note in q.get("notes", ()):
            P("- " + note)
        P("")

    notes = notes_lines(qs, info, loads)
    if notes:
        P("## Notes")
        P("")
        L.extend(notes)
        P("")
    return "\n".join(L) + "\n"


def notes_lines(qs: dict, info: dict, loads: tuple) -> list:
    out = []
    nproc = info.get("nproc") or 1
    busy = [la for la in loads if la is not None and la[0] >= 0.5 * nproc]
    if busy:
        out.append(f"- The machine carried other load during the run (1-minute load average"
                   f" {', '.join(str(la[0]) for la in busy)} on {nproc} cores): the times are"
                   " upper bounds and their ratios are noisy.")
    sq = qs.get("search")
    if sq:
        if sq["truth_shift"] > 0:
            out.append(f"- The transition point at `precise` accuracy lies"
                       f" {sq['truth_shift']:.3g} cm (max-norm) from the one at `default`"
                       f" accuracy (both with search_eps {sq['ref_eps']:g}): the defect test's"
                       " own accuracy moves the transition by that much, whatever the search"
                       " stop length.")
        else:
            out.append(f"- The bisections at `default` and at `precise` accuracy (search_eps"
                       f" {sq['ref_eps']:g}) take the same decisions at every step: at this"
                       " resolution the defect test's accuracy does not move the transition"
                       " point, so the presets' errors are those of their search_eps alone.")
    syq = qs.get("synthesis")
    if syq:
        rows = {r["label"]: r for r in syq["rows"]}
        nits = {k: r["extra"]["nit"] for k, r in rows.items()}
        if len(set(nits.values())) > 1:
            out.append("- The presets reach different final designs along different paths"
                       " (iterations " + ", ".join(f"{k} {v}" for k, v in nits.items())
                       + "): the synthesized nominal is not a continuous function of the"
                       " accuracy, so its error against the reference is a difference between"
                       " designs, not a discretisation error that shrinks smoothly.")
        names = syq.get("names")
        ref = rows.get(syq["reference"])
        if names and ref:
            for k, r in rows.items():
                if k == syq["reference"] or r["error"] <= 0:
                    continue
                d = np.array(r["extra"]["u"]) - np.array(ref["extra"]["u"])
                i = int(np.argmax(np.abs(d)))
                out.append(f"- {k}: the largest difference from {syq['reference']} is in"
                           f" `{names[i]}` ({r['extra']['u'][i]:+.6g} against"
                           f" {ref['extra']['u'][i]:+.6g} cm).")
    return out


# --------------------------------------------------------------------- plot

_PRESET_STYLE = {"fast": ("v", "tab:red"), "default": ("s", "black"), "precise": ("o", "tab:blue"),
                 "reference": ("o", "tab:blue")}


def plot(qs: dict, dpi: int = 90) -> bytes:
    """The Pareto plot as PNG bytes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    keys = list(ORDER)
    fig, axes = plt.subplots(2, 4, figsize=(20, 9.5))
    for ax, key in zip(axes.ravel(), keys):
        q = qs.get(key)
        ax.set_title(TITLES[key], fontsize=10)
        if not q:
            ax.text(0.5, 0.5, "not measured in this run", ha="center", va="center",
                    transform=ax.transAxes, color="0.4")
            ax.set_xticks([])
            ax.set_yticks([])
            continue
        rows = q["rows"]
        pos = [r["error"] for r in rows if r["error"] > 0 and math.isfinite(r["error"])]
        floor = max(FLOOR, 0.3 * min(pos)) if pos else FLOOR
        E = lambda r: min(max(r["error"], floor), 1e300)  # noqa: E731
        cmap = plt.get_cmap("tab10")
        for c, (knob, idx) in enumerate(q.get("lines", {}).items()):
            xs = [rows[i]["time"] for i in idx]
            ys = [E(rows[i]) for i in idx]
            ax.plot(xs, ys, "-", marker=".", color=cmap((c + 2) % 10), lw=1.2, ms=6, label=knob,
                    alpha=0.85)
        for r in rows:
            if r["kind"] in ("preset", "reference") and r["label"] in _PRESET_STYLE:
                mk, col = _PRESET_STYLE[r["label"]]
                ax.plot([r["time"]], [E(r)], mk, color=col, ms=9, mfc="none" if
                        r["kind"] == "reference" else col, mew=1.5, zorder=5)
                tag = r["label"] + (" (reference, error 0)" if r["kind"] == "reference" else "")
                ax.annotate(tag, (r["time"], E(r)), textcoords="offset points", xytext=(6, 4),
                            fontsize=8, color=col)
            elif r["kind"] == "method":
                ax.plot([r["time"]], [E(r)], "D", color="tab:purple", ms=7, zorder=5)
                ax.annotate(r["label"], (r["time"], E(r)), textcoords="offset points",
                            xytext=(6, 4), fontsize=8, color="tab:purple")
            elif r["extra"].get("library_default"):
                ax.plot([r["time"]], [E(r)], "s", color="black", ms=8, mfc="none", mew=1.5,
                        zorder=5)
                ax.annotate("default", (r["time"], E(r)), textcoords="offset points",
                            xytext=(6, -10), fontsize=8)
        k = q["knee"]["knee_index"]
        if k is not None:
            ax.plot([rows[k]["time"]], [E(rows[k])], "o", ms=18, mfc="none", mec="tab:green",
                    mew=2, zorder=4, label="knee")
        ax.set_xscale("log")
        ax.set_yscale("log")
        xs = [r["time"] for r in rows]
        ax.set_xlim(min(xs) / 1.3, max(xs) * 1.3)
        ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel(f"error ({q['unit']})")
        ax.grid(True, which="major", alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="best")
    fig.suptitle("Time against error: presets marked, one-knob sweeps as lines, knee circled",
                 fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    return buf.getvalue()


# ------------------------------------------------------------------------ main

def analyze(qs: dict) -> None:
    """Knee and sweep findings of every quantity, in place."""
    for key, q in qs.items():
        default = "default"
        if not any(r["label"] == default for r in q["rows"]):
            default = None
        rows = [r for r in q["rows"] if r["kind"] != "reference"]
        v = knee_verdict(rows, default) if default else knee_verdict(rows, "\0")
        # indices back into q["rows"]
        if v["knee_index"] is not None:
            v["knee_index"] = q["rows"].index(rows[v["knee_index"]])
        if default is None:
            v["default"] = None
        q["knee"] = v
        q["findings"] = sweep_findings(q)


def _write(path: Path, data) -> None:
    atomic_write(path, data)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="fewer settings and repeats; synthesis fast and default only")
    ap.add_argument("--out", type=Path, default=DOC, help="markdown report (default: %(default)s)")
    ap.add_argument("--img", type=Path, default=IMG, help="Pareto plot (default: %(default)s)")
    args = ap.parse_args(argv)
    mode = "quick" if args.quick else "full"
    sw = SWEEPS[mode]
    t_start = time.perf_counter()
    load0 = load_average()
    info = machine()
    print(f"accuracy benchmark ({mode}): {info['nproc']} cores, Python {info['python']}, "
          f"load {load0}", flush=True)

    def log(s):
        print(s, flush=True)

    from mechanisms.models import geneva, reciprocating_cam
    qs: dict = {}
    rep_cs = 1 if args.quick else 3
    log("C-space boundary ...")
    qs["cspace_geneva"] = cspace_quantity(geneva, sw["cspace"], rep_cs, log)
    qs["cspace_cam"] = cspace_quantity(reciprocating_cam, sw["cspace"], 1 if args.quick else 5,
                                       log)
    log("zone bands ...")
    qs["zones_cam"] = zones_quantity(reciprocating_cam, sw["zones"], ZONES_REF[mode],
                                     1 if args.quick else 2, log=log)
    if not args.quick:
        qs["zones_geneva"] = zones_quantity(geneva, sw["zones_geneva"], GENEVA_ZONE_REF, 1,
                                            curve_labels=GENEVA_CURVES, log=log)
    log("transition point ...")
    qs["search"] = search_quantity(sw["search"], 1 if args.quick else 2, SEARCH_REF_EPS[mode],
                                   log)
    log("four-bar ...")
    qs["fourbar"] = fourbar_quantity(args.quick, log)
    log("spatial loops ...")
    qs["spatial"] = spatial_quantity(args.quick, 1 if args.quick else 2, log)
    log("synthesis ...")
    qs["synthesis"] = synthesis_quantity(("fast", "default") if args.quick else PRESET_NAMES,
                                         log=log)
    analyze(qs)
    load1 = load_average()
    rel = os.path.relpath(args.img, args.out.parent).replace(os.sep, "/")
    text = report(qs, info, args.quick, time.perf_counter() - t_start, (load0, load1), rel)
    print(text)
    _write(args.img, plot(qs))
    _write(args.out, text)
    for p in (args.img, args.out):
        print(f"written: {p.relative_to(ROOT) if p.is_relative_to(ROOT) else p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
