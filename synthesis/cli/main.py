"""Command line: ``cspace-tol`` (or ``python -m synthesis``).

Subcommands
-----------
analyze MODEL --out DIR
    C-space of every pair: pair JSON, C-space JSON, C-space PNG, part drawing PNG,
    contact zones and the nominal motion.
synthesize MODEL --out DIR
    Tolerance synthesis ([Tolerance synthesis] §4): report.json, final and initial pair JSON,
    zones before/after PNGs, defects per iteration, and a checkpoint after every
    iteration (``--resume`` continues it).
import-dxf, export-dxf
    Profiles from and to DXF (extra ``dxf``).

MODEL is a built-in name (geneva, optical_filter, reciprocating_cam, eccentric_cam) or a JSON
file (pair instance, assembly, or parametric model).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import NamedTuple

from cspace.accuracy import PRESETS
from cspace.errors import CSpaceError, InputError

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="cspace-tol",
        description="Kinematic tolerance analysis and synthesis of planar mechanisms "
                    "by the configuration-space method.")
    p.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = p.add_subparsers(dest="command", required=True)
    a = sub.add_parser("analyze", help="C-space analysis of a model or pair",
                       description="Compute the C-space of every pair of MODEL and write "
                                   "JSON and PNG files into DIR.")
    a.add_argument("model", metavar="MODEL",
                   help=f"built-in name ({builtin_names()}) or a JSON file")
    a.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    a.add_argument("--preset", choices=sorted(PRESETS), default="default",
                   help="accuracy preset (default: default)")
    a.add_argument("--window", nargs=4, type=float, metavar=("Q1LO", "Q1HI", "Q2LO", "Q2HI"),
                   help="C-space window (rad for rotations, model units for slides); "
                        "default: the model's window, else one period / the touching range")
    a.add_argument("--no-plots", action="store_true", help="skip PNG output")
    a.add_argument("--q2-start", type=float, nargs="+", metavar="Q2",
                   help="follower start at the start of the drive, one per pair (or one for "
                        "all; rad, or model units for a slide): simulates a pair file that "
                        "states none, and overrides a model's")
    from .convert import PARAMS_HELP
    a.add_argument("--params", metavar="JSON",
                   help="analyse a parametric model at these parameter values instead of "
                        "its nominal (e.g. a defective vector of a synthesis run): "
                        + PARAMS_HELP)
    a.add_argument("--animate", action="store_true",
                   help="also write animation{_pair}.gif: the mechanism over its drive with "
                        "its C-space beside it; a jam, or (with --params) the first "
                        "deviation from the nominal motion by more than d, is marked")
    a.add_argument("--frames", type=int, default=48, metavar="N",
                   help="frames of --animate (default 48), evenly spaced over the drive "
                        "from its start to its end or jam; a marked jam or deviation is "
                        "one of them and is held 4 extra frames, so the GIF then has N + 4")
    a.set_defaults(func=cmd_analyze)
    _add_synthesize(sub)
    from . import convert, yield_command
    convert.register(sub)
    yield_command.register(sub)
    return p


def _version() -> str:
    """The installed distribution's version, else the package's own."""
    try:
        from importlib.metadata import version
        return version("cspace-tolerance")
    except Exception:  # not installed (a source tree on sys.path)
        import cspace
        return cspace.__version__


def _log(msg: str):
    print(msg, file=sys.stderr, flush=True)


def cmd_analyze(args) -> int:
    """``analyze``: check the input, compute every result, then write the files."""
    from mechanisms.analysis import pairs_of
    obj, drive, q2_start = _analysis_inputs(args)
    out = writable_dir(output_dir(args.out))
    t0 = time.perf_counter()
    obj, nominal_model, ref = _analysis_variant(obj, args)
    _log_unbuildable(obj)
    built = obj.build() if hasattr(obj, "build") else obj
    pairs = pairs_of(obj)
    spaces = _analysis_cspaces(obj, pairs, args)
    zones, sims = _zones_and_motion(obj, spaces, args, drive, q2_start)
    if nominal_model is not None:
        _log_variant_verdict(obj, nominal_model, ref)
    anims = _animations(obj, nominal_model, spaces, sims, args) if args.animate else None
    # every result is computed before the first file is written: a failed
    # run leaves an earlier run's files as they were
    _write_analysis(out, args, obj, built, pairs, spaces, zones, sims, anims)
    _log(f"wrote {out} in {time.perf_counter() - t0:.2f} s")
    return 0


def _analysis_inputs(args):
    """MODEL resolved and the options of ``analyze`` checked against it, before
    any work: ``(obj, drive, q2_start)``, the motion a pair file states with
    ``--q2-start`` over its start.  A pair file's window becomes
    ``args.window`` unless ``--window`` is given."""
    from mechanisms.analysis import pair_file_motion, pairs_of, resolve_model
    from mechanisms.models import Model
    obj = resolve_model(args.model)
    if args.frames < 2:
        raise InputError(f"--frames must be >= 2, got {args.frames}", name="--frames",
                         value=args.frames)
    n_pairs = len(pairs_of(obj)) if not isinstance(obj, Model) else None
    stated = (pair_file_motion(args.model, n_pairs) if n_pairs is not None
              else dict.fromkeys(("drive", "q2_start", "window")))
    drive, q2_start = stated["drive"], stated["q2_start"]
    if args.window is None and stated["window"] is not None:
        args.window = list(stated["window"])
    if args.q2_start is not None:
        q2_start = tuple(args.q2_start)
    if args.params is not None and not isinstance(obj, Model):
        raise InputError(f"--params needs a parametric model (a built-in name or a "
                         f"cspace-model file), got a fixed {type(obj).__name__}",
                         name="--params", value=args.params)
    if args.animate and not isinstance(obj, Model) and q2_start is None:
        raise InputError("--animate needs a motion: a parametric model, a pair file with "
                         "'q2_start' (and optionally 'drive'), or --q2-start",
                         name="--animate", value=True)
    return obj, drive, q2_start


def _analysis_variant(obj, args):
    """The design to analyse: a parametric model with ``--window`` and
    ``--q2-start`` applied and, with ``--params``, moved to those values.
    ``(obj, nominal_model, ref)``; ``nominal_model`` is the design before
    ``--params`` (None without it, and for a pair or assembly), ``ref`` its
    Reference (None without ``--params``, or when the nominal has none: its
    motion jams, or its start is blocked)."""
    import dataclasses

    from mechanisms.models import Model
    nominal_model = ref = None
    if isinstance(obj, Model):
        if args.window is not None:
            # the zones and the nominal motion use the same window as the C-space
            obj = dataclasses.replace(obj, window=tuple(args.window))
        if args.q2_start is not None:
            obj = dataclasses.replace(obj, q2_start=tuple(args.q2_start))
        if args.params is not None:
            from .convert import params_vector
            nominal_model = obj
            obj = obj.with_nominal(params_vector(obj, args.params))
            ref = _nominal_reference(nominal_model, args)
            obj = _seated(nominal_model, obj, ref, args)
    return obj, nominal_model, ref


def _nominal_reference(nominal_model, args):
    """The Reference of the design ``--params`` moves away from, or None when
    it has none (its motion jams, or its start is blocked: the analysis of
    the variant still runs and says what it finds)."""
    from cspace.defects import reference
    from cspace.errors import CSpaceError
    try:
        return reference(nominal_model, args.preset)
    except CSpaceError:
        return None


def _log_variant_verdict(variant, nominal_model, ref) -> None:
    """``--params``: the defect test of the variant against the nominal design
    (:func:`cspace.defects.is_defective`, the test synthesis and the Monte
    Carlo check run): a jam, a changed contact sequence, or an output that
    deviates from the nominal motion by more than d.  Without a Reference of
    the nominal (``ref`` None) there is nothing to test against, and the log
    says so."""
    from cspace.defects import Reason, is_defective
    if ref is None:
        _log(f"{variant.name}: no defect test of this vector: the nominal design has no "
             f"healthy motion to test it against (its motion jams or its start is blocked)")
        return
    r = is_defective(nominal_model, variant.nominal, ref=ref)
    verdict = "DEFECTIVE" if r.defective else "healthy"
    upto = " up to where it jams" if Reason.JAM in r.reasons else ""
    _log(f"{variant.name}: the defect test of this vector against the nominal design "
         f"(d = {ref.d:.4g}, C-space metric; largest output deviation{upto} "
         f"{r.max_deviation:.4g}): {verdict}"
         + (f" - {r.message}" if r.defective else ""))


def _seated(nominal_model, obj, ref, args):
    """The variant ``obj`` with its follower where the defect test assembles
    it (:func:`cspace.defects.assembled_start`): a stated start that the
    variant's channel has moved off goes to the nearest free point of it,
    and the log says so.  Unchanged where the nominal has no reference
    (``ref`` None: its motion jams, or its start is blocked; the analysis of
    the variant says what it finds)."""
    import dataclasses

    from cspace.defects import assembled_start
    from mechanisms.analysis import model_cspaces
    if getattr(nominal_model, "q2_start", None) is None or ref is None:
        return obj
    spaces = model_cspaces(obj, accuracy=args.preset, window=args.window)
    seats = [assembled_start(n, v, st) for n, v, st in zip(ref.spaces, spaces, ref.starts)]
    stated = [st[1] for st in ref.starts]
    if seats == stated:
        return obj
    for cs, a, b in zip(spaces, stated, seats):
        if a != b:
            _log(f"{cs.pair.name}: the stated start q2 = {a:.6g} is blocked in this variant; "
                 f"its follower starts at the nearest free point, q2 = {b:.6g}, as the "
                 "defect test assembles it")
    return dataclasses.replace(obj, q2_start=tuple(float(v) for v in seats))


def _analysis_cspaces(obj, pairs, args) -> list:
    """The C-space of every pair, timed in the log."""
    from mechanisms.analysis import model_cspaces
    what = getattr(obj, "name", "") or pairs[0].name
    _log(f"{what}: C-space of {len(pairs)} pair(s), preset {args.preset} ...")
    t = time.perf_counter()
    spaces = model_cspaces(obj, accuracy=args.preset, window=args.window)
    _log(f"{what}: C-space done ({time.perf_counter() - t:.1f} s)")
    return spaces


def _write_analysis(out, args, obj, built, pairs, spaces, zones, sims, anims) -> None:
    """The files of ``analyze``: pair JSON, per pair its C-space, zones, plots
    and animation (a suffix per pair when there are several), then the
    nominal motion; the statistics of each pair in the log."""
    from cspace.io import model_motion, save_cspace, save_pair
    multi = len(spaces) > 1
    out.mkdir(parents=True, exist_ok=True)
    # with the model's operating point: the file analysed again is the same
    save_pair(built, out / "pair.json", model_motion(obj))
    from .report import file_suffixes
    suffixes = file_suffixes([p.name for p in pairs]) if multi else [""] * len(pairs)
    for i, (pair, cs) in enumerate(zip(pairs, spaces)):
        sfx = suffixes[i]
        save_cspace(cs, out / f"cspace{sfx}.json")
        if zones is not None:
            from cspace.io import atomic_write, dumps
            atomic_write(out / f"zones{sfx}.json", dumps(zones[i].to_dict()))
            _log_overlaps(pair, zones[i], f"zones{sfx}.json")
        _log(f"{pair.name}: {cs.stats['curves']} contact curves, {cs.stats['boundary_pieces']} "
             f"boundary pieces, {cs.stats['free_faces']} free face(s), "
             f"{cs.stats['pruned']} feature pairs pruned")
        if not args.no_plots:
            from cspace.plotting import plot_cspace, plot_parts, save_figure
            motion = sims[i] if sims is not None else None
            save_figure(plot_cspace(cs, motion=motion, inset="auto"), out / f"cspace{sfx}.png")
            # the parts where the motion starts (the origin when it is not known)
            q0 = ((float(motion.q1[0]), float(motion.q2[0])) if motion is not None
                  else (0.0, 0.0))
            save_figure(plot_parts(pair, q0, label_segments=True), out / f"parts{sfx}.png")
            if zones is not None:
                from cspace.plotting import plot_zones
                save_figure(plot_zones(zones[i], cs, motion=motion,
                                       title=_zones_title(pair, zones[i])),
                            out / f"zones{sfx}.png")
        if anims is not None:
            anims[i](out / f"animation{sfx}.gif")
    if sims is not None and not args.no_plots:
        from cspace.plotting import plot_output, save_figure
        save_figure(plot_output(sims, title="Output functions (nominal)"), out / "simulation.png")
    if sims is not None:
        from cspace.io import atomic_write, dumps
        atomic_write(out / "simulation.json", dumps({"units": built_units(obj),
                                                      "pairs": [s.to_dict() for s in sims]}))


def output_dir(path: str) -> Path:
    """``--out`` as a folder path: an InputError when it names something else."""
    out = Path(path)
    if not str(path).strip():
        raise InputError("--out must name a folder, got an empty string", name="--out",
                         value=path)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out must name a folder (created if missing), but {out} is a "
                         f"file", name="--out", value=str(out))
    return out


def writable_dir(out: Path) -> Path:
    """Create ``out`` (and its parents) and prove that a file can be written
    there, before any work: a folder that cannot hold the results (``/proc/x``,
    a read-only disk, no permission) fails in a second, not after the run.
    An OSError becomes the one-line message of :func:`main`."""
    import tempfile
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out, prefix=".cspace-tol-probe-"):
            pass
    except OSError as e:
        raise InputError(f"--out must name a folder that can be created and written, got "
                         f"{str(out)!r}: {e.strerror or e}", name="--out",
                         value=str(out)) from None
    return out


def built_units(obj) -> str:
    return getattr(obj, "units", "")


def _motion_line(s) -> str:
    """The log's line of a simulated motion (no negative zero)."""
    return (f"{s.pair}: simulation {s.status.name}, output from {s.q2[0] + 0.0:.5g} to "
            f"{s.q2[-1] + 0.0:.5g}")


def _zones_and_motion(obj, spaces, args, drive=None, q2_start=None):
    """Zones of the operating region and the nominal motion of a parametric
    model; the motion alone of a pair or assembly whose start is known (its
    file's ``q2_start``/``drive`` or ``--q2-start``)."""
    from mechanisms.models import Model
    if not isinstance(obj, Model):
        if q2_start is None:
            _log("no motion: a pair file states no start; give it 'q2_start' (and "
                 "optionally 'drive') or pass --q2-start.  Zones need a parametric model "
                 "(tolerances)")
            return None, None
        from mechanisms.analysis import simulate_pairs
        _log(f"simulating the motion of {len(spaces)} pair(s) ...")
        sims = simulate_pairs(spaces, drive, q2_start)
        for s in sims:
            _log(_motion_line(s))
        for cs, s in zip(spaces, sims):
            if not s.success:
                _log(f"warning: {s.pair}: the motion does not complete its drive "
                     f"({s.status.name}): {s.message}{_start_hint(cs, s.q2[0])}")
        _log_operating_point(spaces, sims)
        _log("zones need a parametric model (tolerances); a fixed pair has none")
        return None, sims
    from cspace.defects import reference
    from cspace.errors import CSpaceError, JammedNominalError

    from ..loop import operating_zones
    t = time.perf_counter()
    _log(f"{obj.name}: {'motion of this vector' if args.params is not None else 'nominal motion'}"
         " ...")
    try:
        ref = reference(obj, args.preset)
    except JammedNominalError as e:
        # drawn where it jams; no zones (they bound the nominal's channel
        # along its whole drive), and a synthesis or yield refuses it
        for s in e.sims:
            _log(_motion_line(s))
        if args.params is None:
            _log(f"warning: {e}")
            _log(f"{obj.name}: no contact zones: the nominal motion does not complete its drive")
        else:
            s = next(s for s in e.sims if not s.success)
            _log(f"{obj.name}: this variant's motion jams ({s.message}): a defect; no zones")
        return None, list(e.sims)
    except CSpaceError as e:
        if args.params is None or isinstance(e, (JammedNominalError, InputError)):
            raise
        # a variant (--params) whose follower cannot start where the nominal's
        # does, nor at a free point near it: the defect test's blocked start
        _log(f"warning: {e}")
        _log(f"{obj.name}: this variant cannot start: the defect test finds it defective "
             "(its follower start is blocked); no motion or zones")
        return None, None
    for s in ref.sims:
        _log(_motion_line(s))
    _log_operating_point(ref.spaces, ref.sims, ref.start_choices)
    from mechanisms.analysis import deviation_note, tolerance_note
    for note in (deviation_note(obj, ref), tolerance_note(obj)):
        if note:
            _log(f"warning: {note[1]}")
    _log(f"{obj.name}: contact zones of the operating region ({obj.n} parameters) ...")
    # the same zones as the synthesis: the curves bounding the cells the nominal
    # motion passes through, so that the overlap counts agree
    zones = list(operating_zones(obj, ref, args.preset))
    _log(f"{obj.name}: motion and zones done ({time.perf_counter() - t:.1f} s)")
    return zones, list(ref.sims)


def _start_hint(cs, q2) -> str:
    """For a rotating follower whose start lies more than a turn outside its
    window: how far, and the start in radians if it was written in degrees."""
    import math
    if not cs.periodic[1]:
        return ""
    lo, hi = cs.window[2], cs.window[3]
    if lo - 2 * math.pi <= q2 <= hi + 2 * math.pi:
        return ""
    turns = (q2 - (lo if q2 < lo else hi)) / (2 * math.pi)
    return (f"; the start q2 = {q2:.6g} rad lies {abs(turns):.3g} turns outside the follower "
            f"window [{lo:.6g}, {hi:.6g}] rad: written in degrees? radians({q2:.6g}) = "
            f"{math.radians(q2):.6g} rad")


def _log_operating_point(spaces, sims, choices=None) -> None:
    from mechanisms.analysis import operating_point_notes
    for warn, text in operating_point_notes(spaces, sims, choices):
        _log(("warning: " if warn else "") + text)


def _zones_title(pair, zones) -> str:
    from cspace.plotting import plain_text
    return (f"Contact zones of {plain_text(pair.name)} (operating region): "
            f"{len(zones.overlaps)} zone overlap(s)")


#: Overlaps listed one per line by analyze; the rest are in zones.json.
SHOW_OVERLAPS = 5


def _log_overlaps(pair, zones, file):
    """A summary of the zone overlaps: count, units, meaning, the deepest few."""
    ov = sorted(zones.overlaps, key=lambda o: -o.depth)
    from mechanisms.analysis import follower_unit
    u = follower_unit(pair)
    if not ov:
        _log(f"{pair.name}: no zone overlap in the operating region")
        return
    _log(f"{pair.name}: {len(ov)} zone overlap(s) in the operating region: the zone bands of "
         f"the two curves bounding a channel overlap, so some variant in the tolerance box "
         f"may close it (a conservative bound, not a tested defect; docs/synthesis.md, "
         f"'Zone overlaps'); channel width and overlap depth in {u}")
    for o in ov[:SHOW_OVERLAPS]:
        at = f"at q1 in [{o.q1_range[0]:.4f}, {o.q1_range[1]:.4f}] rad"
        if o.kind == "closure":
            _log(f"  {o.lower_label} (its two branches) {at}: channel {o.gap:.4g} {u} closes: "
                 "a vector of the box leaves that contact no solution there, its features "
                 "overlapping")
        else:
            _log(f"  {o.lower_label} / {o.upper_label} {at}: channel {o.gap:.4g} {u}, "
                 f"overlap {o.depth:.4g} {u}")
    if len(ov) > SHOW_OVERLAPS:
        _log(f"  ... {len(ov) - SHOW_OVERLAPS} more in {file}")


def _animations(obj, nominal_model, spaces, sims, args):
    """One writer per pair: ``write(path)`` makes its GIF.  With --params the
    nominal design's motion is the reference of the deviation mark."""
    from cspace.plotting import animate_motion
    if sims is None:
        raise InputError("--animate needs a motion", name="--animate", value=True)
    nominal, d = [None] * len(spaces), None
    if nominal_model is not None:
        from cspace.defects import default_deviation
        from mechanisms.analysis import motion_at
        _log(f"{obj.name}: nominal motion for the deviation mark ...")
        sp0, nominal = motion_at(nominal_model, accuracy=args.preset)
        d = nominal_model.deviation
        if d is None:
            d = default_deviation(nominal_model, sp0, nominal)

    def writer(i):
        def write(path):
            a = animate_motion(spaces[i], sims[i], path, nominal=nominal[i], d=d,
                               frames=args.frames)
            _log(f"{a!r}")
        return write
    return [writer(i) for i in range(len(spaces))]


CHECKPOINT = "checkpoint.json"


def _add_synthesize(sub):
    """The ``synthesize`` subcommand: its options in the order of its help."""
    s = sub.add_parser(
        "synthesize", help="tolerance synthesis of a parametric model",
        description="Shift the nominal design (or shrink a tolerance) until no variant in "
                    "the tolerance box is defective, and write the report, the final "
                    "geometry and the zone plots into DIR.  A checkpoint is written after "
                    "every iteration; --resume continues it.  One run at a time may "
                    "use DIR.  Exit status: 0 target met, 1 not met (e.g. --max-iter "
                    "reached; with --target-yield also a run that removed every worst-case "
                    "defect but whose yield estimate does not confirm Y; also a final box "
                    "that fails its --verify Monte Carlo check), 2 bad input or DIR "
                    "in use, 130 stopped by SIGINT (Ctrl-C), "
                    "143 stopped by SIGTERM; a stopped run keeps a checkpoint with the "
                    "defect tests it had finished (also inside an iteration) and writes a "
                    "report with status INTERRUPTED.  A finished run already in DIR is "
                    "moved into DIR/previous/ (previous-2/, ... when taken) first.")
    _add_synthesize_inputs(s)
    _add_synthesize_run_control(s)
    _add_synthesize_guards(s)
    _add_synthesize_methods(s)
    _add_synthesize_yield_target(s)
    _add_synthesize_start_and_checkpoints(s)
    _add_synthesize_outputs(s)
    s.set_defaults(func=cmd_synthesize)


def _add_synthesize_inputs(s) -> None:
    """MODEL, ``--out``, ``--preset`` and where the defect tests run."""
    add_model_arguments(s)
    s.add_argument("--preset", choices=sorted(PRESETS), default=None,
                   help="accuracy preset (default: default; with --resume, the "
                        "checkpoint's)")
    add_executor_arguments(s)


def _add_synthesize_run_control(s) -> None:
    """How long a run goes, how it treats a defect, its threshold d, and
    whether it continues a checkpoint or starts over."""
    s.add_argument("--max-iter", type=int, default=30, metavar="N",
                   help="iteration cap, >= 1 (default 30); reaching it is a status, not an "
                        "error")
    s.add_argument("--patience", type=int, metavar="N",
                   help="removals of one check-list vector before its return is cured by a "
                        "tolerance cut instead of another shift (default 4; a resumed run "
                        "keeps its checkpoint's value). Smaller: fewer iterations and a "
                        "smaller nominal change, deeper cuts")
    s.add_argument("--two-sided", action=argparse.BooleanOptionalAction, default=None,
                   help="also test the mirror of every defective vector through the "
                        "nominal, and cut a defect found on both sides at once instead of "
                        "shifting it (default on; --no-two-sided: the paper's order, shift "
                        "first; a resumed run keeps its checkpoint's choice)")
    s.add_argument("--deviation", type=float, metavar="D",
                   help="output-deviation threshold d (rad, or slide / characteristic "
                        "length); default: the model's, else 5 * max(tol) / L")
    s.add_argument("--resume", action="store_true",
                   help=f"continue from DIR/{CHECKPOINT}")
    s.add_argument("--fresh", action="store_true",
                   help="start over even if DIR holds an unfinished checkpoint")


def _add_synthesize_guards(s) -> None:
    """The guard rails: how deep a cut may go, what may not move, what costs
    more."""
    s.add_argument("--min-keep", type=float, metavar="F",
                   help="smallest fraction of each initial tolerance a cut may keep, for "
                        "parameters whose model entry states no 'min_keep' (default 0.25); a "
                        "defect that needs a deeper cut ends the run INFEASIBLE")
    s.add_argument("--fixed", action="append", metavar="NAME[,NAME...]",
                   help="parameters whose nominal may not be shifted (also 'fixed': true "
                        "in the model file)")
    s.add_argument("--hard", action="append", metavar="NAME[,NAME...]",
                   help="parameters whose tolerance may not be cut (also 'hard': true in "
                        "the model file)")
    s.add_argument("--shift-cost", action="append", metavar="NAME=W",
                   help="relative cost of shifting a parameter (default 1): the cheaper "
                        "axis is shifted first")
    s.add_argument("--cut-cost", action="append", metavar="NAME=W",
                   help="relative cost of cutting a parameter's tolerance (default 1)")


def _add_synthesize_methods(s) -> None:
    """How transition points are found and how defects are removed."""
    from ..minimal import REMOVALS
    from ..removal import SEARCHES
    s.add_argument("--search", choices=SEARCHES, default=None,
                   help="transition-point search: margin (default; each test where the "
                        "batched margin interpolates to zero) or bisect (the paper's); a "
                        "resumed run keeps its checkpoint's")
    s.add_argument("--removal", choices=REMOVALS, default=None,
                   help="how defects are removed: lp (default; the smallest shift, else the "
                        "smallest cuts, that make every known defect's linearised margin "
                        "positive at the box corners) or greedy (the paper's Eqs. 3-5); a "
                        "resumed run keeps its checkpoint's")


def _add_synthesize_yield_target(s) -> None:
    """``--target-yield`` and how it estimates the yield."""
    s.add_argument("--target-yield", metavar="Y",
                   help="synthesis to a target yield: stop once the estimated failure rate "
                        "(upper 95 %% bound) is at most 1 - Y, instead of once no worst-case "
                        "corner fails; Y a yield (0 < Y < 1, e.g. 0.9999), a percentage "
                        "(99.99%%) or a failure rate (100ppm); a resumed run keeps its "
                        "checkpoint's.  With --yield-method is the target counts as met only "
                        "when a second estimate with seed + 1 agrees (its upper bound also at "
                        "most 1 - Y, the two intervals overlapping); else the estimate is "
                        "reported unconfirmed and the run goes on.  With mc, N samples can "
                        "confirm at best about 3.69/N: a target below that is refused")
    s.add_argument("--yield-samples", type=int, metavar="N",
                   help="samples of each yield estimate of --target-yield (default 2000)")
    s.add_argument("--yield-method", choices=("mc", "is"),
                   help="yield estimate of --target-yield: mc (plain Monte Carlo, default) "
                        "or is (design points and importance sampling, for targets of "
                        "100 ppm and below)")
    s.add_argument("--cp", type=float, metavar="CP",
                   help="process capability for --target-yield of every parameter whose "
                        "model entry states no distribution (sigma = tol / (3 CP), "
                        "truncated at the tolerance; default 1)")


def _add_synthesize_start_and_checkpoints(s) -> None:
    """Whether an unstated follower start may be chosen among several free
    intervals, and how often a checkpoint is written inside an iteration."""
    s.add_argument("--accept-start", action="store_true",
                   help="accept the default follower start (the middle of the widest free "
                        "interval) when the model states none and there are several free "
                        "intervals; without it such a run is refused")
    s.add_argument("--checkpoint-every", type=float, default=None, metavar="S",
                   help="seconds between checkpoints written inside an iteration, with the "
                        "defect tests finished so far (default 30; 0: after every batch "
                        "of tests); a stop always writes one")


def _add_synthesize_outputs(s) -> None:
    """The Monte Carlo check of the result, its seed, and the plots."""
    s.add_argument("--verify", type=int, default=0, metavar="N",
                   help="Monte Carlo check of the initial and final boxes with N samples "
                        "each (half corners, half interior; default 0: skip)")
    s.add_argument("--verify-rounds", type=int, default=2, metavar="K",
                   help="when the final box of a converged run fails its --verify check, "
                        "keep its defective samples as check-list vectors and go on, then "
                        "check again, at most K times (default 2; 0: only report)")
    s.add_argument("--seed", type=int, default=0,
                   help="seed of the Monte Carlo check and of the --target-yield "
                        "estimates (default 0)")
    s.add_argument("--no-plots", action="store_true", help="skip PNG output")


def builtin_names() -> str:
    """The built-in model names, for help texts."""
    from mechanisms.models import BUILTIN
    return ", ".join(BUILTIN)


def add_model_arguments(p) -> None:
    """``MODEL`` (a parametric model) and ``--out DIR``: the first arguments of
    a command that works on tolerances (``synthesize``, ``yield``)."""
    p.add_argument("model", metavar="MODEL",
                   help=f"built-in name ({builtin_names()}) or a "
                        "cspace-model JSON file")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")


def add_executor_arguments(p) -> None:
    """``--executor``, ``--scheduler`` and ``--workers``: where the defect tests
    of a command run (``synthesize``, ``yield``)."""
    from ..executors import EXECUTORS
    p.add_argument("--executor", choices=EXECUTORS, default="process",
                   help="where the defect tests run (default: a local process pool)")
    p.add_argument("--scheduler", metavar="ADDR",
                   help="dask scheduler address for --executor dask, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, metavar="N",
                   help="process-pool size (default: the CPUs available)")


class _Terminated(Exception):
    pass


def cmd_synthesize(args) -> int:
    held = []     # the output folder's lock, taken before the checkpoint is read
    try:
        return _synthesize(args, held)
    finally:
        for lock in held:
            lock.release()


def _synthesize(args, held) -> int:
    """``synthesize``: check the input, take DIR (and the checkpoint to resume),
    run, write the outputs; the exit status (0 target met, 1 not met, 130 or
    143 stopped by a signal)."""
    import warnings

    from mechanisms.analysis import OperatingPointWarning

    from .report import operating_point, write_outputs
    model = _synthesis_model(args)
    _check_synthesis_options(args)
    out, ckpt, state = _take_output(args, held, model)
    _log_unbuildable(model)
    with warnings.catch_warnings():
        # the progress log prints them, once; the caller's filters come back after
        warnings.filterwarnings("ignore", category=OperatingPointWarning)
        run = _run_synthesis(args, model, out, ckpt, state)
        if isinstance(run, int):
            return run
        result = run.result
        try:
            run.archive.ensure()
            written = write_outputs(result, model, out, plots=not args.no_plots,
                                    verification=run.verification, accuracy=args.preset,
                                    command=_command_line(args), removed=run.removed,
                                    failures=run.failures, previous=run.archive.moved_to,
                                    operating=operating_point(model, result, args.preset))
        except OSError:
            # the computing is kept: the checkpoint holds the finished run
            _log(f"could not write the outputs; {ckpt} holds the finished run: remove what "
                 f"is in the way and rerun with --resume to write them")
            raise
    _log_synthesis(result, run.verification, model)
    n = len(written) + int(ckpt.is_file() and ckpt.name not in {Path(w).name for w in written})
    _log(f"wrote {n} files to {out} in {time.perf_counter() - run.t0:.1f} s")
    verified = _log_verdict(result, run.verification)
    return 0 if result.success and _target_met(result) and verified else 1


def _log_verdict(result, verification) -> bool:
    """Whether the final box passed ``--verify``'s Monte Carlo check (True
    when none ran); a failed one is the log's last, prominent word."""
    from .report import verification_verdict
    verdict = verification_verdict(result, verification)
    if verdict is None or verdict["passed"]:
        return True
    bar = "!" * 72
    _log(bar)
    _log(f"WARNING: {verdict['text']}.")
    _log(f"The synthesis status ({result.status.name}) describes its check list only; "
         f"report.md and report.json (verification_failed: true) say so too; exit "
         f"status 1")
    _log(bar)
    return False


def _target_met(result) -> bool:
    """Whether a run reached what it aimed at: always for a worst-case run; for
    a target-yield run only when its last estimate meets (and, with ``is``,
    confirms) the target.  A target-yield run that removed every worst-case
    defect without confirming the target says so and exits 1."""
    if result.target is None:
        return True
    ye = result.yield_estimate
    if ye is not None and ye.get("met"):
        return True
    from ..target import ppm_text, samples_needed
    ppm = result.target.get("ppm")
    need = (f"plain Monte Carlo confirms {ppm_text(ppm)} ppm from "
            f"{samples_needed(ppm / 1e6):,} samples without a failure" if ppm else "")
    how = "more --yield-samples, or --yield-method is" + (f"; {need}" if need else "")
    if result.target.get("method") == "is":
        how = "more --yield-samples"
        if ye is not None and ye.get("plain"):
            how += ("; importance sampling found no failure region to sample around at the "
                    "final design, so its estimate was plain Monte Carlo" +
                    (f", and {need}" if need else "") + "; --verify N tests the final box "
                    "by Monte Carlo too")
    _log(f"target not met: the worst case is clean but the yield estimate does not confirm "
         f"the target ({how})")
    return False


def _log_unbuildable(model) -> None:
    """A warning per tolerance that reaches values the geometry cannot take."""
    from mechanisms.analysis import unbuildable_tolerances
    for _, _, text in unbuildable_tolerances(model):
        _log(f"warning: {text}")


def _synthesis_model(args):
    """MODEL resolved: a parametric model, or an InputError."""
    from mechanisms.analysis import resolve_model
    from mechanisms.models import Model
    model = resolve_model(args.model)
    if not isinstance(model, Model):
        raise InputError(f"synthesize needs a parametric model with tolerances (a built-in "
                         f"name or a cspace-model file), got a fixed "
                         f"{type(model).__name__} from {args.model!r}", name="MODEL",
                         value=args.model)
    return model


def check_executor_options(args) -> None:
    """``--executor``, ``--scheduler`` and ``--workers`` of a command, checked
    before it makes its output folder."""
    from ..executors import check_executor_kind
    if args.executor == "dask" and not args.scheduler:
        raise InputError("--executor dask needs --scheduler ADDR (e.g. tcp://host:8786)",
                         name="--scheduler", value=None)
    if args.scheduler and args.executor != "dask":
        raise InputError(f"--scheduler is for --executor dask, got --executor {args.executor}",
                         name="--scheduler", value=args.scheduler)
    check_executor_kind(args.executor, args.workers)


def _check_synthesis_options(args) -> None:
    """The options of ``synthesize`` checked on their own and against each
    other, before DIR is touched."""
    if args.max_iter < 1:
        raise InputError(f"--max-iter must be >= 1 (iterations to run; 0 would test no "
                         f"variant and write an empty report), got {args.max_iter}",
                         name="--max-iter", value=args.max_iter)
    if args.patience is not None and args.patience < 1:
        raise InputError(f"--patience must be >= 1, got {args.patience}", name="--patience",
                         value=args.patience)
    if args.verify < 0:
        raise InputError(f"--verify must be >= 0, got {args.verify}", name="--verify",
                         value=args.verify)
    if getattr(args, "verify_rounds", 0) < 0:
        raise InputError(f"--verify-rounds must be >= 0, got {args.verify_rounds}",
                         name="--verify-rounds", value=args.verify_rounds)
    check_executor_options(args)
    if args.resume and args.fresh:
        raise InputError("--resume and --fresh exclude each other: --resume continues the "
                         "checkpoint, --fresh starts over", name="--fresh", value=True)
    if args.deviation is not None and not (math.isfinite(args.deviation)
                                           and args.deviation > 0):
        raise InputError(f"--deviation must be a finite number > 0, got {args.deviation}",
                         name="--deviation", value=args.deviation)
    if args.checkpoint_every is not None and not (math.isfinite(args.checkpoint_every)
                                                  and args.checkpoint_every >= 0):
        raise InputError(f"--checkpoint-every must be a finite number of seconds >= 0, got "
                         f"{args.checkpoint_every}", name="--checkpoint-every",
                         value=args.checkpoint_every)
    from ..verify import check_samples, check_seed
    if args.verify:
        check_samples(args.verify)
    check_seed(args.seed)
    _target(args)       # a bad or unconfirmable --target-yield, before DIR is touched


def _take_output(args, held, model=None):
    """DIR locked for this run (the lock appended to ``held``) and the state
    to continue: ``(out, ckpt, state)``, ``state`` None for a new run.  Sets
    ``args.preset`` (the checkpoint's when resuming); a resumed checkpoint is
    checked against ``model`` (:func:`_check_resumed_model`)."""
    out = output_dir(args.out)
    ckpt = out / CHECKPOINT
    if out.is_dir() or not args.resume:
        from .outlock import OutputLock
        held.append(OutputLock(writable_dir(out)).acquire())
    state = None
    if args.resume:
        state = _resumed_state(args, ckpt, model)
    elif ckpt.is_file() and not args.fresh:
        _refuse_unfinished(out, ckpt)
    if args.preset is None:
        args.preset = "default"
    writable_dir(out)
    # a finished run resumed writes its outputs again (without what only its
    # run wrote: its Monte Carlo check), so its own are kept, as a new run
    # keeps them, but its checkpoint, which the resumed run continues; an
    # interrupted one continues in place
    from ..result import SynthesisStatus
    if not args.resume:
        earlier = _earlier_outputs(out)
    elif state.status is not SynthesisStatus.RUNNING:
        earlier = [n for n in _earlier_outputs(out) if n != CHECKPOINT]
    else:
        earlier = None
    args.archive = _Archive(out, earlier)
    _check_output_names(out)
    return out, ckpt, state


#: The files a synthesis run writes into DIR (and the figures' name patterns).
_OUTPUT_NAMES = ("checkpoint.json", "report.md", "report.json", "model.json",
                 "model_initial.json", "pair.json", "pair_initial.json", "changes.png",
                 "parts.png", "defects.png")


def _is_output_name(name: str) -> bool:
    return name in _OUTPUT_NAMES or (name.endswith(".png")
                                     and name.startswith(("zones", "failures")))


def _earlier_outputs(out) -> list:
    """The files of an earlier run in DIR that a new run would overwrite
    (empty when DIR holds no report or checkpoint: nothing of a run to keep)."""
    if not any((out / n).is_file() for n in ("report.json", "report.md", CHECKPOINT)):
        return []
    return sorted(p.name for p in out.iterdir() if p.is_file() and _is_output_name(p.name))


class _Archive:
    """The outputs of an earlier run in DIR, moved into a subfolder before the
    new run writes its first file (:meth:`ensure`), never overwritten:
    ``previous/``, or ``previous-2/``, ``previous-3/``, ... when that is taken
    (the higher the number, the later the run).  The files go into a hidden
    folder first, which is renamed when all are in: an interruption leaves them
    either there or in DIR, never lost."""

    def __init__(self, out, names):
        self.out, self.names = out, list(names or ())
        self.moved_to = None

    def ensure(self) -> None:
        import os
        import tempfile
        if not self.names or self.moved_to is not None:
            return
        k, dest = 1, self.out / "previous"
        while dest.exists():
            k += 1
            dest = self.out / f"previous-{k}"
        tmp = Path(tempfile.mkdtemp(dir=self.out, prefix=".previous-"))
        for n in self.names:
            if (self.out / n).is_file():
                os.replace(self.out / n, tmp / n)
        os.replace(tmp, dest)
        self.moved_to = dest.name
        _log(f"{self.out} held the outputs of an earlier run ({len(self.names)} files): moved "
             f"them to {dest} before this run writes its own")


def _resumed_state(args, ckpt, model=None):
    """The checkpoint ``--resume`` continues, with its preset in ``args.preset``;
    refused when ``model`` (or ``--deviation``) is not the one it was started
    with."""
    from ..checkpoint import load_checkpoint
    if not ckpt.is_file():
        raise InputError(f"--resume: no checkpoint {ckpt}; run without --resume to start",
                         name="--resume", value=str(ckpt))
    loaded = load_checkpoint(ckpt)
    state = loaded.state
    if not loaded.verified:
        _log(f"{ckpt} has no content hash (written by an earlier version): its values "
             f"are checked, its integrity cannot be")
    if model is not None:
        _check_resumed_model(loaded, model, args, ckpt)
    args.preset = resume_preset(state, args.preset)
    inside = ("" if state.partial is None else
              f", with {len(state.partial.tests)} finished defect test(s) of iteration "
              f"{state.partial.iteration}")
    _log(f"resuming {state.model!r} after iteration {state.iterations} "
         f"({state.status.name.lower()}, preset {args.preset}{inside})")
    return state


def _check_resumed_model(loaded, model, args, ckpt) -> None:
    """A :class:`synthesis.checkpoint.ModelMismatchError` when the model given (or
    ``--deviation``) is not the one the checkpoint was started with; a note
    when the checkpoint is too old to tell."""
    from ..checkpoint import check_model
    if not check_model(loaded, model, getattr(args, "deviation", None)):
        _log(f"{ckpt} has no model fingerprint (written by an earlier version): the model "
             f"given cannot be checked against the one the run was started with (only its "
             f"parameters' initial values are); make sure it is the same")


def _check_output_names(out) -> None:
    """An InputError, before the run, when a name ``synthesize`` writes in DIR
    is taken by a folder (writing it would fail after the computing)."""
    taken = sorted(p for p in out.iterdir() if p.is_dir() and _is_output_name(p.name))
    if taken:
        raise InputError(f"--out {out}: synthesize writes the file {taken[0].name} there, but "
                         f"{taken[0]} is a directory (expected a file, or nothing; "
                         f"directories in the way: {', '.join(p.name for p in taken)}); "
                         f"remove or rename it, or choose another --out", name="--out",
                         value=str(taken[0]))


def _refuse_unfinished(out, ckpt) -> None:
    """An InputError when the checkpoint in DIR is of a run that has not ended
    (or is damaged): a new run needs --resume or --fresh there."""
    from cspace.errors import FileFormatError

    from ..checkpoint import read_checkpoint
    from ..result import SynthesisStatus
    try:
        old, _ = read_checkpoint(ckpt)
        unfinished = old.status in (SynthesisStatus.RUNNING, SynthesisStatus.MAX_ITER)
        damage = ""
    except FileFormatError as e:
        unfinished, damage = True, f" that is damaged ({e})"
    if unfinished:
        raise InputError(f"{out} holds an unfinished run ({ckpt}){damage}; pass --resume "
                         f"to continue it or --fresh to start over", name="--out",
                         value=str(out))


class _Run(NamedTuple):
    """A synthesis run that ended by itself."""

    #: the SynthesisResult
    result: object
    #: --verify's Monte Carlo results by box ("initial", "final"), or None
    verification: object
    #: the defective vectors removed so far (last checkpoint), for the failure plots
    removed: tuple
    #: time.perf_counter() when the run started
    t0: float
    #: the failure plot's re-tests (report.failure_retests), or None
    failures: object = None
    #: the earlier run's outputs in DIR, moved aside before the first write (_Archive)
    archive: object = None


def _run_synthesis(args, model, out, ckpt, state):
    """The synthesis loop (and --verify's Monte Carlo check) with a checkpoint
    after every iteration and every ``--checkpoint-every`` seconds inside one.
    A :class:`_Run`, or the exit status (130, 143) of a run stopped by SIGINT or
    SIGTERM, which leaves its checkpoint and report (:func:`_stopped`)."""
    from ..checkpoint import write_checkpoint
    from ..executors import make_executor
    from ..loop import synthesize
    from ..memo import DEFAULT_CHECKPOINT_EVERY
    from ..progress import progress_for
    from ..stopping import StopSignals
    progress = progress_for(sys.stderr)
    last = {"state": state}
    archive = getattr(args, "archive", None) or _Archive(out, ())
    # what finished after the synthesis, for the report of a stop then
    after = {"result": None, "verification": {}, "phase": None}

    def checkpoint(st):
        archive.ensure()        # an earlier run's outputs go aside before the first write
        write_checkpoint(ckpt, st, model=model)
        last["state"] = st

    # bad guard options are refused before any signal handler is replaced
    guards = _guards(args, model)
    every = (DEFAULT_CHECKPOINT_EVERY if args.checkpoint_every is None
             else args.checkpoint_every)
    # SIGINT and SIGTERM stop the run within seconds (exit 130 or 143)
    stop = StopSignals(terminated=_Terminated).install()
    t0 = time.perf_counter()
    try:
        with make_executor(args.executor, args.workers, args.scheduler) as ex:
            rounds = getattr(args, "verify_rounds", 0) if args.verify else 0
            while True:
                result = synthesize(model, args.preset, d=args.deviation, executor=ex,
                                    max_iter=args.max_iter, state=state,
                                    on_iteration=checkpoint, progress=progress,
                                    patience=args.patience, two_sided=args.two_sided,
                                    on_partial=checkpoint, checkpoint_every=every,
                                    accept_start=args.accept_start, guards=guards,
                                    search=args.search, removal=args.removal,
                                    target_yield=_target(args))
                after["result"] = result
                verification = None
                if not args.verify:
                    break
                after["phase"] = "the Monte Carlo check (--verify)"
                verification = _verify(model, result, args, ex, done=after["verification"])
                state = _go_on_with_samples(result, verification, last["state"], rounds,
                                            model, args, ex)
                if state is None:
                    break
                rounds -= 1
                # the final box's check belonged to the box the run now leaves
                after["verification"].pop("final", None)
                checkpoint(state)
            # failures.png's re-tests on the pool, while it is open
            removed = last["state"].removed if last["state"] is not None else ()
            failures = None
            if not args.no_plots and len(removed):
                from .report import failure_retests
                after["phase"] = "the re-tests of failures.png"
                failures = failure_retests(result, model, removed, args.preset, ex)
            after["phase"] = "the shutdown of the worker pool (every check had finished)"
    except (KeyboardInterrupt, _Terminated) as e:
        what = "terminated" if isinstance(e, _Terminated) else "interrupted"
        archive.ensure()
        _stopped(what, last["state"], model, out, ckpt, args, after, archive.moved_to)
        return 130 if isinstance(e, KeyboardInterrupt) else 143
    finally:
        stop.restore()
    return _Run(result, verification, removed, t0, failures, archive)


def _log_synthesis(result, verification, model=None) -> None:
    """The outcome in the log: status, changes, e or the message, the yield
    estimate, deep cuts of a converged run, and the Monte Carlo counts.  With
    ``model`` each parameter's change is in the unit its model file states it
    in (degrees for ``"unit": "deg"``), as ``report.md`` gives it."""
    _log(f"{result.model}: {result.status.name.lower()} after {result.nit} iteration(s); "
         f"defects per iteration {result.defects_per_iteration()}")
    if model is not None:
        from .report import in_declared_units
        result = in_declared_units(result, model)
    unit = dict(zip(result.names, (result.unit_of(i) for i in range(len(result.names)))))
    for nm, dv in result.to_dict()["changed"].items():
        _log(f"  {nm}: {dv:+.6g} {unit[nm]}")
    for nm, (a, b) in result.to_dict()["shrunk"].items():
        _log(f"  tolerance of {nm}: {a:.6g} -> {b:.6g} {unit[nm]}")
    # a converged run's message states e itself
    _log(f"  {result.message}" if result.success
         else f"  e = {result.e:.6g} {result.units}; {result.message}")
    ye = result.yield_estimate
    if ye is not None:
        from ..target import ppm_text
        _log(f"  estimated yield: {ppm_text(ye['ppm'])} ppm defective (95 % interval "
             f"[{ppm_text(ye['ci_ppm'][0])}, {ppm_text(ye['ci_ppm'][1])}] ppm; target "
             f"{ppm_text(ye['target_ppm'])} ppm); worst case: "
             f"{result.history[-1].n_defects} defective check-list vector(s) left")
    from ..loop import deep_cuts
    low = deep_cuts(result.names, result.initial_tol, result.tol)
    if result.success and low:
        _log(f"warning: converged with {len(low)} tolerance(s) cut below half of their "
             f"initial value; the smallest: {low[0][0]} kept at {100 * low[0][1]:.0f} %")
    if verification:
        for k, v in verification.items():
            _log(f"  Monte Carlo ({k} box): {v.n_defective}/{v.n} defective")
        final = verification.get("final")
        for i, msg in zip(getattr(final, "defective", ()), getattr(final, "messages", ())):
            _log(f"    final box, sample {i}: {msg}")


def _target(args):
    """The --target-yield of the command line (None without it)."""
    from ..target import YieldTarget
    given = {k: v for k, v in (("samples", args.yield_samples), ("method", args.yield_method),
                                ("cp", args.cp)) if v is not None}
    if args.target_yield is None:
        if given:
            raise InputError("--cp, --yield-method and --yield-samples set how --target-yield "
                             "estimates the yield; give --target-yield too",
                             name="target_yield")
        return None
    target = YieldTarget.parse(args.target_yield, seed=args.seed, **given)
    from ..target import mc_floor, ppm_text, samples_needed
    if target.method == "mc" and mc_floor(target.samples) > target.failure:
        need = samples_needed(target.failure)
        raise InputError(f"--target-yield {args.target_yield} (at most "
                         f"{ppm_text(1e6 * target.failure)} ppm defective) can never be "
                         f"confirmed by plain Monte Carlo with --yield-samples "
                         f"{target.samples}: with no failing part its 95 % upper bound is "
                         f"{ppm_text(1e6 * mc_floor(target.samples))} ppm; allowed: "
                         f"--yield-samples {need} or more, or --yield-method is",
                         name="--yield-samples", value=target.samples)
    return target


def _guards(args, model):
    """The guard rails named on the command line (None when none is: a new run
    takes the model's and ``min_keep`` 0.25, a resumed one the checkpoint's)."""
    from ..guards import Guards
    if all(v is None for v in (args.min_keep, args.fixed, args.hard, args.shift_cost,
                               args.cut_cost)):
        return None

    def names(items):
        return [n.strip() for it in (items or []) for n in it.split(",") if n.strip()]

    def costs(items, flag):
        out = {}
        for it in items or []:
            name, sep, val = it.partition("=")
            try:
                w = float(val)
            except ValueError:
                w = math.nan
            if not sep or not name.strip() or not (math.isfinite(w) and w > 0):
                raise InputError(f"{flag} must be NAME=W with W a finite number > 0, got "
                                 f"{it!r}", name=flag, value=it)
            out[name.strip()] = w
        return out

    return Guards.of(model, min_keep=args.min_keep, fixed=names(args.fixed),
                     hard=names(args.hard), shift_cost=costs(args.shift_cost, "--shift-cost"),
                     cut_cost=costs(args.cut_cost, "--cut-cost"))


def _stopped(what, st, model, out, ckpt, args, after=None, previous=None) -> None:
    """What a run stopped by a signal leaves: the checkpoint (already written
    by the loop) and a report with status INTERRUPTED, written before the
    cheap plots (no zones: they take computing).  A stop inside an iteration
    reports the design that iteration was testing; a stop after the synthesis
    ended (in the Monte Carlo check or the re-tests of the failure plot;
    ``after``) reports the synthesis's final design, what of the check had
    finished, and that ``--resume`` finishes the rest."""
    from ..loop import interrupted_result
    from .report import write_outputs
    from ..result import SynthesisStatus
    if st is None:
        _log(f"{what} before the first iteration started; nothing to resume")
        return
    after = after or {}
    done = None
    if st.status is not SynthesisStatus.RUNNING:
        if after.get("result") is None:
            _log(f"{what} after the synthesis ended ({st.status.name.lower()}); {ckpt} holds "
                 f"it: rerun with --resume to write its outputs")
            return
        res, done = _stopped_after_synthesis(after)
        _log(f"{what} during {res.interrupted['phase']}, after the synthesis ended "
             f"({st.status.name.lower()}); {ckpt} holds it: rerun with --resume to finish "
             f"{res.interrupted['phase']} and write the complete outputs")
    else:
        k = st.iterations + 1
        n = len(st.partial.tests) if st.partial is not None else 0
        _log(f"{what} in iteration {k}: {ckpt} holds {n} finished defect test(s) of it and "
             f"the state after iteration {st.iterations}; rerun with --resume to continue")
    try:
        from .report import operating_point
        if done is None:
            res = interrupted_result(st, model)
        kw = dict(accuracy=args.preset, command=_command_line(args), zone_plots=False,
                  verification=done or None, previous=previous,
                  operating=operating_point(model, res, args.preset))
        write_outputs(res, model, out, plots=False, **kw)
        if not args.no_plots:
            write_outputs(res, model, out, plots=True, **kw)
        _log(f"wrote the report of the stopped run (status INTERRUPTED) to {out}")
    except (CSpaceError, OSError, ImportError) as e:
        _log(f"could not write the report of the stopped run: {type(e).__name__}: {e}")


def _stopped_after_synthesis(after):
    """The report of a run stopped after its synthesis ended: ``(result,
    verification)``, the result with status INTERRUPTED (``interrupted``
    names the phase and the synthesis's own status) and the Monte Carlo
    checks that had finished (by box)."""
    import dataclasses

    from ..result import SynthesisStatus
    result, done = after["result"], dict(after.get("verification") or {})
    phase = after.get("phase") or "the writing of the outputs"
    checked = ", ".join(f"the {k} box ({v.n_defective}/{v.n} defective)"
                        for k, v in done.items())
    msg = (f"stopped during {phase}, after the synthesis ended "
           f"{result.status.name.lower()} after {result.nit} iteration(s) ({result.message})"
           + (f"; Monte Carlo check finished for {checked}" if checked else "")
           + "; rerun with --resume to finish")
    res = dataclasses.replace(result, status=SynthesisStatus.INTERRUPTED, success=False,
                              message=msg,
                              interrupted={"phase": phase,
                                           "after_synthesis": result.status.name,
                                           "checked_boxes": list(done)})
    return res, done


def resume_preset(state, asked):
    """The preset a resumed run uses: the checkpoint's, as with ``patience`` and
    ``two_sided``.  An explicit ``--preset`` that names another one is refused."""
    saved = state.accuracy.get("name")
    if asked is None:
        if saved not in PRESETS:
            raise InputError(f"--resume: the checkpoint's accuracy {saved!r} is not a preset "
                             f"(allowed: {', '.join(sorted(PRESETS))}); continue it from "
                             f"Python with synthesize(..., accuracy=Accuracy(...))",
                             name="--preset", value=saved)
        return saved
    if asked != saved:
        raise InputError(f"--preset {asked} conflicts with the checkpoint, which was made "
                         f"with preset {saved!r}; drop --preset to resume with the "
                         f"checkpoint's, or start over with --fresh", name="--preset",
                         value=asked)
    return asked


def _command_line(args) -> str:
    """The synthesize command as a user would type it (for report.md)."""
    import shlex
    argv = getattr(args, "argv", None)
    if argv is None:
        argv = sys.argv[1:]
    return "cspace-tol " + " ".join(shlex.quote(str(a)) for a in argv)


#: The most defective samples of one Monte Carlo check kept as check-list vectors.
MAX_KEPT_SAMPLES = 50


def _go_on_with_samples(result, verification, state, rounds, model, args, executor):
    """The state to continue a converged run whose final box failed its
    Monte Carlo check: its defective samples (the first
    :data:`MAX_KEPT_SAMPLES`), each reduced to its support (the parameters
    its defect needs, :func:`synthesis.removal.defect_support`: a sample
    moves every parameter, and the removal must not move those its defect
    does not depend on), kept as check-list vectors
    (:func:`synthesis.result.with_samples`); None when there is nothing to
    go on with (the check passed, no round is left, or the run did not
    converge: it ended with defects it knew of)."""
    import numpy as np

    from ..executors import run_batched
    from ..removal import defect_support
    from ..result import SynthesisStatus, with_samples
    final = (verification or {}).get("final")
    if (final is None or not final.n_defective or rounds <= 0 or state is None
            or result.status is not SynthesisStatus.CONVERGED or result.target is not None):
        return None
    kept = final.samples[list(final.defective[:MAX_KEPT_SAMPLES])]
    _log(f"the final box failed its Monte Carlo check ({final.n_defective}/{final.n} "
         f"defective): {len(kept)} of its defective samples, each reduced to the parameters "
         f"its defect needs, join the check list and the run goes on ({rounds} round(s) of "
         f"--verify-rounds left)")
    intent = model.with_nominal(result.initial_nominal).with_tolerances(result.initial_tol)

    def defective(vectors, hints=None):
        return [r.defective for r in run_batched(executor, intent, np.asarray(vectors),
                                                 args.preset, result.d)]

    kept = defect_support(np.asarray(result.nominal, dtype=float), list(kept), defective)
    return with_samples(state, kept, result.nominal, result.tol)


def _verify(model, result, args, executor, done=None, stream=None) -> dict:
    """``--verify``: the Monte Carlo check of the initial and the final box,
    with a progress line per batch at most every 10 s off a terminal (a bar
    on one).  Each finished check goes into ``done`` (by box) at once, for
    the report of a run stopped during the next."""
    from ..verify import monte_carlo
    out = {} if done is None else done
    intent = model.with_nominal(result.initial_nominal).with_tolerances(result.initial_tol)
    for which, nom, tol in (("initial", result.initial_nominal, result.initial_tol),
                            ("final", result.nominal, result.tol)):
        if which == "initial" and "initial" in out:
            continue      # a round after --verify-rounds: the same initial box
        design = model.with_nominal(nom).with_tolerances(tol)
        _log(f"Monte Carlo check of the {which} box ({args.verify} samples)")
        # both boxes against the initial design, as the synthesis tested them
        r = monte_carlo(design, args.verify, seed=args.seed, accuracy=args.preset,
                        d=result.d, executor=executor, intent=intent,
                        progress=phase_progress(stream or sys.stderr),
                        phase=f"Monte Carlo check of the {which} box")
        out[which] = r
        _log(f"Monte Carlo check of the {which} box: {r.n_defective}/{r.n} defective")
    return out


def phase_progress(stream=None, interval: float = 10.0, clock=None):
    """The progress of a phase outside the iterations (the Monte Carlo check):
    the log's or the bar's lines (:func:`synthesis.progress.progress_for`),
    without an iteration number."""
    from ..progress import BarProgress, LogProgress
    stream = stream or sys.stderr
    isatty = getattr(stream, "isatty", None)
    p = (BarProgress(stream, clock=clock) if isatty is not None and isatty()
         else LogProgress(stream, interval=interval, clock=clock))
    p.begin(None)
    return p


def _format_warning(message, category, filename, lineno, line=None):
    """A warning on the command line: ``warning: <message>``, without the
    Python source location that says nothing to a user (the library's own
    warnings; others keep Python's format)."""
    from cspace.io import UnitWarning
    from mechanisms.analysis import OperatingPointWarning
    if issubclass(category, (UnitWarning, OperatingPointWarning)):
        return f"warning: {message}\n"
    return _PYTHON_FORMAT(message, category, filename, lineno, line)


_PYTHON_FORMAT = None


def main(argv=None) -> int:
    import warnings
    global _PYTHON_FORMAT
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    _PYTHON_FORMAT = old = warnings.formatwarning
    warnings.formatwarning = _format_warning
    try:
        return _run_command(args)
    finally:
        warnings.formatwarning = old


def _run_command(args) -> int:
    try:
        return int(args.func(args) or 0)
    except CSpaceError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        # a file or folder that cannot be read or written (exists as a file,
        # no permission, disk full): the operating system's words, one line
        where = f" {e.filename!r}" if getattr(e, "filename", None) else ""
        print(f"error: cannot use{where}: {e.strerror or e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
