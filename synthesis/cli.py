"""Command line: ``cspace-tol`` (or ``python -m synthesis``).

Subcommands
-----------
analyze MODEL --out DIR
    C-space of every pair: pair JSON, C-space JSON, C-space PNG, part drawing PNG.

MODEL is a built-in name (geneva, optical_filter, reciprocating_cam) or a JSON
file (pair instance, assembly, or parametric model).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from cspace.accuracy import PRESETS
from cspace.errors import CSpaceError

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="cspace-tol",
        description="Kinematic tolerance analysis and synthesis of planar mechanisms "
                    "by the configuration-space method.")
    sub = p.add_subparsers(dest="command", required=True)
    a = sub.add_parser("analyze", help="C-space analysis of a model or pair",
                       description="Compute the C-space of every pair of MODEL and write "
                                   "JSON and PNG files into DIR.")
    a.add_argument("model", metavar="MODEL",
                   help="built-in name (geneva, optical_filter, reciprocating_cam) or a JSON file")
    a.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    a.add_argument("--preset", choices=sorted(PRESETS), default="default",
                   help="accuracy preset (default: default)")
    a.add_argument("--window", nargs=4, type=float, metavar=("Q1LO", "Q1HI", "Q2LO", "Q2HI"),
                   help="C-space window (rad for rotations, model units for slides); "
                        "default: the model's window, else one period / the touching range")
    a.add_argument("--no-plots", action="store_true", help="skip PNG output")
    a.set_defaults(func=cmd_analyze)
    from . import cli_io
    cli_io.register(sub)
    return p


def _log(msg: str):
    print(msg, file=sys.stderr, flush=True)


def cmd_analyze(args) -> int:
    from cspace.io import save_cspace, save_pair
    from mechanisms.analysis import model_cspaces, pairs_of, resolve_model
    obj = resolve_model(args.model)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    built = obj.build() if hasattr(obj, "build") else obj
    save_pair(built, out / "pair.json")
    spaces = model_cspaces(obj, accuracy=args.preset, window=args.window)
    pairs = pairs_of(obj)
    multi = len(spaces) > 1
    zones, sims = _zones_and_motion(obj, spaces, args)
    for i, (pair, cs) in enumerate(zip(pairs, spaces)):
        sfx = f"_{pair.name}" if multi else ""
        save_cspace(cs, out / f"cspace{sfx}.json")
        if zones is not None:
            from cspace.io import atomic_write, dumps
            atomic_write(out / f"zones{sfx}.json", dumps(zones[i].to_dict()))
            for o in zones[i].overlaps:
                _log(f"{pair.name}: zone overlap between {o.lower_label} and {o.upper_label} "
                     f"at q1 in [{o.q1_range[0]:.4f}, {o.q1_range[1]:.4f}] rad "
                     f"(channel {o.gap:.4g}, overlap {o.depth:.4g})")
        _log(f"{pair.name}: {cs.stats['curves']} contact curves, {cs.stats['boundary_pieces']} "
             f"boundary pieces, {cs.stats['free_faces']} free face(s), "
             f"{cs.stats['pruned']} feature pairs pruned")
        if not args.no_plots:
            from cspace.plotting import plot_cspace, plot_parts, save_figure
            save_figure(plot_cspace(cs), out / f"cspace{sfx}.png")
            save_figure(plot_parts(pair, (0.0, 0.0), label_segments=True), out / f"parts{sfx}.png")
            if zones is not None:
                from cspace.plotting import plot_zones
                save_figure(plot_zones(zones[i], cs), out / f"zones{sfx}.png")
    if sims is not None and not args.no_plots:
        from cspace.plotting import plot_output, save_figure
        save_figure(plot_output(sims, title="Output functions (nominal)"), out / "simulation.png")
    if sims is not None:
        from cspace.io import atomic_write, dumps
        atomic_write(out / "simulation.json", dumps({"units": built_units(obj),
                                                      "pairs": [s.to_dict() for s in sims]}))
    _log(f"wrote {out} in {time.perf_counter() - t0:.2f} s")
    return 0


def built_units(obj) -> str:
    return getattr(obj, "units", "")


def _zones_and_motion(obj, spaces, args):
    """Zones of the operating channels and the nominal motion (parametric models only)."""
    from mechanisms.models import Model
    if not isinstance(obj, Model):
        _log("zones and simulation need a parametric model (tolerances); a fixed pair has none")
        return None, None
    from cspace.defects import reference
    from cspace.zones import contact_zones
    ref = reference(obj, args.preset)
    zones = [contact_zones(cs, obj, i, faces=[f]) for i, (cs, f) in
             enumerate(zip(ref.spaces, ref.faces))]
    for s in ref.sims:
        _log(f"{s.pair}: simulation {s.status.name}, output from {s.q2[0]:.5g} to {s.q2[-1]:.5g}")
    return zones, list(ref.sims)


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except CSpaceError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
