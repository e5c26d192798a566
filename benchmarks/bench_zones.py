"""Contact zones against a Monte Carlo band: time, containment, overestimation and
the first-order baseline.

Every figure is measured in one run of this script, and every ratio is against a
baseline measured in the same run.  Plain script::

    python benchmarks/bench_zones.py            # 1000 vectors per model and preset
    python benchmarks/bench_zones.py --quick    # 150 vectors, fewer presets

It prints the tables and writes them to ``docs/benchmarks/zones.md`` (atomically).

Measurements
------------
zones       ``cspace.zones.contact_zones(cs, model, pair, preset, faces=[operating
            face])``: the bands of the curves that bound the operating channel of
            every pair (what synthesis computes), wall time of one call.
Monte Carlo the band of equal coverage: ``--samples`` seeded vectors of the tolerance
            box (a quarter of them box corners, the rest uniform inside; seed 0),
            and for each vector and band the varied curve re-solved at the band's
            sample points (its displacement along the nominal normal, found as the
            intersection nearest to the nominal point, the same definition the
            zones use).  The Monte Carlo band is the envelope of these.  Its time is
            the wall time of building the variants and re-solving the curves.
containment for every vector, band and sample, how far the varied curve lies outside
            the computed band (metric units: rad, or slide / characteristic length).
            Reported: the largest excess, where (curve, sample, whether the sample
            is *reliable*, i.e. every one-parameter probe keeps the contact), the
            share of (vector, sample) cases outside by more than 1e-9, and the
            excess relative to the band width there.
overestimation  zone width against Monte Carlo width where the Monte Carlo band
            exists (the Monte Carlo band is an inner estimate, so this is an upper
            bound of the true overestimation).
linear      the first-order band (``ZoneBand.linear_*``) against the Monte Carlo
            band: the largest amount by which it falls short (misses variants) and
            its largest overestimate.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from benchlib import load_average  # noqa: E402
from cspace.defects import reference  # noqa: E402
from cspace.geometry import Assembly, trusted  # noqa: E402
from cspace.io import atomic_write  # noqa: E402
from cspace.zones import _band_evaluator, contact_zones  # noqa: E402
from mechanisms.models import BUILTIN  # noqa: E402

MODELS = ("reciprocating_cam", "geneva", "optical_filter")


def box_vectors(model, n: int, seed: int = 0) -> np.ndarray:
    """``n`` seeded vectors of the box: a quarter corners, the rest uniform."""
    rng = np.random.default_rng(seed)
    U = model.nominal + model.tol * rng.uniform(-1.0, 1.0, (n, model.n))
    nc = n // 4
    U[:nc] = model.nominal + model.tol * rng.choice([-1.0, 1.0], (nc, model.n))
    return U


def measure(model, preset: str, n: int, seed: int = 0) -> list:
    """One record per pair: zone time, Monte Carlo time and the comparisons."""
    ref = reference(model, preset)
    out = []
    for pi, cs in enumerate(ref.spaces):
        t = time.perf_counter()
        z = contact_zones(cs, model, pi, preset, faces=[ref.faces[pi]])
        t_zone = time.perf_counter() - t
        def build(u, pi=pi):
            with trusted():
                p = model.build(u)
            return p.pairs[pi] if isinstance(p, Assembly) else p

        evs = [(b, _band_evaluator(cs, b, build)) for b in z.bands]
        mc_hi = [np.full(len(b.q1), -np.inf) for b, _ in evs]
        mc_lo = [np.full(len(b.q1), np.inf) for b, _ in evs]
        worst = (-np.inf, None)
        cases = outside = 0
        t = time.perf_counter()
        for j, u in enumerate(box_vectors(model, n, seed)):
            for k, (b, ev) in enumerate(evs):
                tau, _ = ev(u)
                ok = np.isfinite(tau)
                mc_hi[k] = np.where(ok, np.maximum(mc_hi[k], np.where(ok, tau, -np.inf)), mc_hi[k])
                mc_lo[k] = np.where(ok, np.minimum(mc_lo[k], np.where(ok, tau, np.inf)), mc_lo[k])
                ok &= np.isfinite(b.upper)
                if not ok.any():
                    continue
                ex = np.where(ok, np.maximum(tau - b.upper, b.lower - tau), -np.inf)
                cases += int(ok.sum())
                outside += int((ex > 1e-9).sum())
                i = int(np.argmax(ex))
                if ex[i] > worst[0]:
                    width = float(b.upper[i] - b.lower[i])
                    worst = (float(ex[i]), {"curve": b.label, "branch": b.branch, "sample": i,
                                            "samples": len(b.q1),
                                            "reliable": bool(b.reliable[i]),
                                            "width": width, "vector": j})
        t_mc = time.perf_counter() - t
        over, lin_short, lin_over = [], 0.0, 0.0
        for k, (b, _) in enumerate(evs):
            hi, lo = mc_hi[k], mc_lo[k]
            ok = np.isfinite(hi) & np.isfinite(lo) & np.isfinite(b.upper) & np.isfinite(b.lower)
            wmc = (hi - lo)[ok]
            wz = (b.upper - b.lower)[ok]
            good = wmc > 1e-12
            over.extend((wz[good] - wmc[good]) / wmc[good])
            lu, ll = b.linear_upper[ok], b.linear_lower[ok]
            if ok.any():
                lin_short = max(lin_short, float(np.max(np.maximum(hi[ok] - lu, ll - lo[ok]))))
                lin_over = max(lin_over, float(np.max(np.maximum(lu - hi[ok], lo[ok] - ll))))
        over = np.array(over) if over else np.zeros(1)
        out.append({"model": model.name, "pair": cs.pair.name, "preset": preset,
                    "bands": len(z.bands), "evaluated": z.stats["vectors_evaluated"],
                    "t_zone": t_zone, "samples": n, "t_mc": t_mc,
                    "excess": max(worst[0], 0.0), "where": worst[1],
                    "outside_share": outside / cases if cases else 0.0,
                    "over_median": float(np.median(over)), "over_p95": float(np.percentile(over, 95)),
                    "lin_short": lin_short, "lin_over": lin_over})
    return out


def table(rows) -> str:
    head = ("| model | pair | preset | bands | zone time | vectors evaluated | Monte Carlo "
            "(vectors) | MC time | MC / zone | largest excess | at | outside share | "
            "width over MC, median | p95 | linear short of MC | linear over MC |")
    lines = [head, "|" + "---|" * 16]
    for r in rows:
        w = r["where"]
        at = ("—" if w is None or r["excess"] <= 1e-9 else
              f"`{w['curve']}` b{w['branch']:+d}, sample {w['sample']}/{w['samples']}"
              f"{'' if w['reliable'] else ' (unreliable)'}, {r['excess'] / w['width']:.0%} "
              f"of width" if w['width'] > 0 else "")
        lines.append(
            f"| {r['model']} | {r['pair']} | {r['preset']} | {r['bands']} | {r['t_zone']:.2f} s "
            f"| {r['evaluated']} | {r['samples']} | {r['t_mc']:.1f} s | "
            f"{r['t_mc'] / r['t_zone']:.1f}× | {r['excess']:.2e} | {at} | "
            f"{100 * r['outside_share']:.3f} % | {100 * r['over_median']:.1f} % | "
            f"{100 * r['over_p95']:.1f} % | {r['lin_short']:.2e} | {r['lin_over']:.2e} |")
    return "\n".join(lines)


def report(rows, args, wall, load0, load1) -> str:
    import numpy as _np
    import scipy
    import shapely
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return f"""# Benchmark: contact zones against a Monte Carlo band

Script: `benchmarks/bench_zones.py` (run `python benchmarks/bench_zones.py`).  Every figure
below was measured in one run of that script; every ratio is against a baseline measured in
the same run.

- date: {now}
- machine: {os.cpu_count()} cores ({platform.system()} {platform.machine()}), Python
  {platform.python_version()}, numpy {_np.__version__}, scipy {scipy.__version__}, shapely
  {shapely.__version__}
- mode: {'quick' if args.quick else 'full'}; {args.samples} vectors per model and preset;
  whole run {wall:.0f} s; load average (1, 5, 15 min) at the start {load0}, at the end {load1}

## Method

- **zones**: `contact_zones(cs, model, pair, preset, faces=[operating face])`, the bands of
  the curves bounding the operating channel of every pair, one call, wall time.
- **Monte Carlo band of equal coverage**: {args.samples} seeded vectors of the box (a quarter
  box corners, the rest uniform; seed 0); every band's varied curve re-solved at its sample
  points (displacement along the nominal normal, the intersection nearest the nominal point,
  as the zones define it); the envelope of these.  Time: building the variants and
  re-solving.
- **containment**: how far a varied curve lies outside the computed band (C-space metric:
  rad; a slide divided by the characteristic length).  *Outside share*: (vector, sample)
  cases outside by more than 1e-9.  *Unreliable* samples are those where some
  one-parameter probe loses the contact (near a trimmed curve end).
- **overestimation**: (zone width − Monte Carlo width) / Monte Carlo width over the samples
  where both exist; the Monte Carlo band is an inner estimate, so this bounds the true
  overestimation from above.
- **linear**: the first-order band (`ZoneBand.linear_*`, Σ|∂d/∂u_i| tol_i) against the Monte
  Carlo band: how far it falls short of a sampled variant, and how far it overshoots.

## Results

{table(rows)}

## Reading

- The reciprocating cam's curves are nearly linear in their parameters: the zones hold
  every sampled variant exactly, and the first-order band is close to them.
- The Geneva and optical-filter pin–vertex and relief curves depend on 11–12 parameters and
  are strongly nonlinear where they are steep and near their trimmed ends: there the
  first-order signs no longer name the extreme corner, and the `fast` preset (corner
  candidates only) misses variants.  The `default` and `precise` presets add a
  margin-constrained first-order guide, a corner hill-climb and a neighbour envelope where
  the guide fails (`Accuracy.zone_climb`); the remaining excess is listed above, with the
  curve, sample and share of the band width where it is largest.
- The Monte Carlo band needs the listed time for its coverage and is an inner estimate; the
  zones are cheaper by the ratio shown and, where they contain every sample, an outer one.
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="150 vectors, fast and default only")
    ap.add_argument("--samples", type=int)
    ap.add_argument("--presets", nargs="*")
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    ap.add_argument("--out", default=str(ROOT / "docs" / "benchmarks" / "zones.md"))
    a = ap.parse_args(argv)
    if a.samples is None:
        a.samples = 150 if a.quick else 1000
    presets = a.presets or (["fast", "default"] if a.quick else ["fast", "default", "precise"])
    load0 = load_average()
    t0 = time.perf_counter()
    rows = []
    for name in a.models:
        m = BUILTIN[name]()
        for p in presets:
            for r in measure(m, p, a.samples):
                rows.append(r)
                print(table([r]).splitlines()[-1], flush=True)
    wall = time.perf_counter() - t0
    load1 = load_average()
    text = report(rows, a, wall, load0, load1)
    atomic_write(Path(a.out), text)
    print(table(rows))
    return rows


if __name__ == "__main__":
    main()
