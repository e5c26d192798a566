"""File-conversion subcommands of the command line (model files, DXF).

import-dxf FILE --out MODEL.json --part LAYER:NAME:rotation:CX,CY
           --part LAYER:NAME:translation:DX,DY[:OX,OY] [--units U] [--tol T]
           [--q2-start Q2] [--drive Q1START Q1END] [--window Q1LO Q1HI Q2LO Q2HI]
           [--deviation D]
    A DXF drawing (one layer per part, driver first) to a pair-instance JSON, or
    with ``--tol`` to a parametric model JSON in which every dimension is a
    parameter with tolerance T; the operating point (follower start, drive,
    window, deviation threshold) is written into either file.

export-dxf MODEL --out FILE.dxf [--params JSON-or-file]
    A built-in model, a pair/assembly JSON or a model JSON to DXF (one layer per
    part), at the nominal or a given parameter vector (:func:`params_vector`:
    named values in each parameter's own unit, a list in the library's units).
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from cspace.errors import InputError

#: How ``--params`` reads its values (the help of ``analyze`` and ``export-dxf``).
PARAMS_HELP = ("a JSON object {name: value}, each value in the parameter's own unit as "
               "its model file states it (degrees for \"unit\": \"deg\"), or a list of all "
               "values in the library's units (lengths in the model's unit, angles in "
               "rad), as report.json stores vectors ('verification' samples, "
               "'history') and checkpoint.json ('removed'); inline or in a file holding "
               "one")

#: A ``--params`` value farther than this many tolerance half-widths from its
#: nominal is named in a warning (most often a value in another unit).
FAR_OUTSIDE = 10.0

__all__ = ["register", "parse_part", "cmd_import_dxf", "cmd_export_dxf", "parse_params",
           "params_vector", "declared_units", "PARAMS_HELP"]


def register(sub) -> None:
    """Add the file-conversion subcommands to the ``cspace-tol`` sub-parser."""
    from .main import builtin_names
    a = sub.add_parser(
        "import-dxf", help="DXF drawing -> pair JSON (or parametric model JSON with --tol)",
        description="Read LINE, ARC, CIRCLE and LWPOLYLINE entities, one layer per part "
                    "(driver first), chain them into closed loops and write a cspace-pair "
                    "JSON, or with --tol a cspace-model JSON in which every vertex "
                    "coordinate and rotation centre is a parameter.")
    a.add_argument("file", metavar="FILE", help="DXF file")
    a.add_argument("--out", required=True, metavar="MODEL.json", help="output JSON file")
    a.add_argument("--part", action="append", required=True, metavar="SPEC",
                   help="LAYER:NAME:rotation:CX,CY or LAYER:NAME:translation:DX,DY[:OX,OY]; "
                        "give it twice, driver first; CX,CY and OX,OY are in the --units "
                        "length unit (the output's), not the drawing's")
    a.add_argument("--units", help="length unit of the output (default: the drawing's "
                                   "$INSUNITS); a drawing in other known units is converted, "
                                   "and the --part centres and origins are read in this unit")
    a.add_argument("--tol", type=float, metavar="T",
                   help="make every dimension a parameter with tolerance T (model units)")
    a.add_argument("--param-mode", choices=("all", "profile"), default="all",
                   help="with --tol: also parametrise rotation centres (all, default) or not")
    a.add_argument("--name", help="pair/model name (default: the file name)")
    a.add_argument("--q2-start", type=float, metavar="Q2",
                   help="follower start at the start of the drive (rad, or model units for "
                        "a slide); without it analyze and synthesize choose the middle of the "
                        "widest free interval and say so, and synthesize refuses a choice "
                        "among several intervals")
    a.add_argument("--drive", nargs=2, type=float, metavar=("Q1START", "Q1END"),
                   help="driver range of the motion (default: one turn from the window start, "
                        "or the window's range for a slide)")
    a.add_argument("--bias", type=int, choices=(-1, 0, 1), default=0,
                   help="the follower's closure: 0 form-closed (default), -1 or +1 held "
                        "toward decreasing or increasing q2 (a spring; the drawing cannot "
                        "say)")
    a.add_argument("--window", nargs=4, type=float, metavar=("Q1LO", "Q1HI", "Q2LO", "Q2HI"),
                   help="C-space window (rad for rotations, model units for slides)")
    a.add_argument("--deviation", type=float, metavar="D",
                   help="output-deviation threshold d of the defect test (rad, or slide / "
                        "characteristic length)")
    a.set_defaults(func=cmd_import_dxf)

    e = sub.add_parser("export-dxf", help="model or pair -> DXF drawing",
                       description="Write every part of MODEL as a DXF layer (LINE, ARC, "
                                   "CIRCLE), at the nominal or a given parameter vector.")
    e.add_argument("model", metavar="MODEL",
                   help=f"built-in name ({builtin_names()}) or a JSON file")
    e.add_argument("--out", required=True, metavar="FILE.dxf", help="output DXF file")
    e.add_argument("--params", metavar="JSON",
                   help="draw the model at these parameter values instead of its nominal: "
                        + PARAMS_HELP)
    e.set_defaults(func=cmd_export_dxf)


def _floats(text: str, n: int, what: str, spec: str) -> list:
    items = text.split(",")
    try:
        vals = [float(v) for v in items]
    except ValueError:
        vals = None
    if vals is None or len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise InputError(f"--part {spec!r}: {what} must be {n} finite numbers separated by "
                         f"commas, got {text!r}", name="part", value=spec)
    return vals


def parse_part(spec: str) -> dict:
    """``LAYER:NAME:rotation:CX,CY`` or ``LAYER:NAME:translation:DX,DY[:OX,OY]`` ->
    ``{"layer", "name", "axis"}`` with a pair-JSON axis dict."""
    f = spec.split(":")
    if len(f) < 4 or f[2] not in ("rotation", "translation") or not f[0] or not f[1]:
        raise InputError(f"--part must be LAYER:NAME:rotation:CX,CY or "
                         f"LAYER:NAME:translation:DX,DY[:OX,OY], got {spec!r}",
                         name="part", value=spec)
    if f[2] == "rotation":
        if len(f) != 4:
            raise InputError(f"--part {spec!r}: a rotation takes one centre CX,CY",
                             name="part", value=spec)
        axis = {"type": "rotation", "center": _floats(f[3], 2, "the centre", spec)}
    else:
        if len(f) > 5:
            raise InputError(f"--part {spec!r}: a translation takes DX,DY and an optional "
                             "origin OX,OY", name="part", value=spec)
        axis = {"type": "translation", "direction": _floats(f[3], 2, "the direction", spec),
                "origin": _floats(f[4], 2, "the origin", spec) if len(f) == 5 else [0.0, 0.0]}
    return {"layer": f[0], "name": f[1], "axis": axis}


def cmd_import_dxf(args) -> int:
    from cspace.io import save_pair
    from mechanisms.dxf import import_dxf
    from mechanisms.userfile import save_model
    parts = [parse_part(s) for s in args.part]
    if len(parts) != 2:
        raise InputError(f"give --part exactly twice (driver, then follower), got {len(parts)}",
                         name="part", value=args.part)
    motion = _operating_point(args)
    obj = import_dxf(args.file, parts=parts, units=args.units, tol=args.tol,
                     param_mode=args.param_mode, name=args.name, bias=args.bias)
    if "window" in motion:
        # the window checked against the parts, before a file that analyze
        # would refuse is written
        from cspace.contact import _check_window
        from mechanisms.analysis import pairs_of
        for pair in pairs_of(obj):
            _check_window(pair, motion["window"])
    if args.tol is None:
        save_pair(obj, args.out, motion)
        what = "pair"
    else:
        import dataclasses
        obj = dataclasses.replace(obj, **motion)
        save_model(obj, args.out)
        what = f"model with {obj.n} parameters (+/- {args.tol:g} {obj.units})"
    stated = ", ".join(motion) or "no operating point (give --q2-start to state the start)"
    print(f"wrote {what} to {args.out}; stated: {stated}", file=sys.stderr)
    if args.tol is not None:
        for name, n in tangent_joins(obj.build()).items():
            print(f"warning: {n} join(s) of part {name!r} are tangent; with every vertex a "
                  f"parameter a variant has a corner there, which a follower running over it "
                  f"touches for a moment: a change of the contact sequence (docs/model_file.md, "
                  f"'bulges stay fixed')", file=sys.stderr)
    return 0


#: Two segments meet tangentially when the sine of the angle between their
#: tangents is at most this (and they run the same way).
TANGENT_SINE = 1e-6


def tangent_joins(obj) -> dict:
    """Per part name of a pair or assembly, how many of its joins between two
    segments are tangent (the count where there are any)."""
    from mechanisms.analysis import pairs_of
    out: dict = {}
    for pair in pairs_of(obj):
        for part in (pair.driver, pair.follower):
            n = 0
            for lp in part.loops:
                segs = lp.segments
                if len(segs) < 2:
                    continue
                for prev, seg in zip((segs[-1],) + tuple(segs[:-1]), segs):
                    a, b = prev.end_tangent(), seg.start_tangent()
                    sine, cosine = a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1]
                    if abs(sine) <= TANGENT_SINE and cosine > 0:
                        n += 1
            if n:
                out[part.name] = out.get(part.name, 0) + n
    return out


def _operating_point(args) -> dict:
    """The operating point given to ``import-dxf`` (the keys of a model file),
    checked before the drawing is read."""
    out = {}

    def finite(vals, flag, what):
        if not all(math.isfinite(v) for v in vals):
            raise InputError(f"{flag} must be {what}, finite numbers, got "
                             f"{' '.join(str(v) for v in vals)}", name=flag, value=vals)
        return tuple(float(v) for v in vals)

    if args.q2_start is not None:
        out["q2_start"] = finite([args.q2_start], "--q2-start", "one follower start")
    if args.drive is not None:
        dr = finite(args.drive, "--drive", "Q1START Q1END")
        if dr[0] == dr[1]:
            raise InputError(f"--drive must have two different ends, got {dr[0]} {dr[1]}",
                             name="--drive", value=list(dr))
        out["drive"] = dr
    if args.window is not None:
        w = finite(args.window, "--window", "Q1LO Q1HI Q2LO Q2HI")
        if not (w[0] < w[1] and w[2] < w[3]):
            raise InputError(f"--window must have Q1LO < Q1HI and Q2LO < Q2HI, got "
                             f"{' '.join(str(v) for v in w)}", name="--window", value=list(w))
        out["window"] = w
    if args.deviation is not None:
        if not (math.isfinite(args.deviation) and args.deviation > 0):
            raise InputError(f"--deviation must be a finite number > 0 (rad, or slide / "
                             f"characteristic length), got {args.deviation}",
                             name="--deviation", value=args.deviation)
        out["deviation"] = float(args.deviation)
    return out


def _params_int(text):
    from cspace.io import MAX_INT_DIGITS
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise InputError(f"--params values must be numbers that fit a float, got an integer "
                         f"of {len(text.lstrip('-'))} digits", name="params", value=text[:20])
    return int(text)


def _unique_keys(pairs):
    keys = [k for k, _ in pairs]
    dup = sorted({k for k in keys if keys.count(k) > 1})
    if dup:
        raise InputError(f"--params names {dup} more than once; give each parameter once",
                         name="params", value=dup)
    return dict(pairs)


def parse_params(text: str | None):
    """``--params`` -> the parameter values it gives: a JSON object
    ``{name: value}`` or list, inline or in the file ``text`` names (None when
    ``text`` is None).  Anything else, a repeated name or an integer too long
    for a float is an InputError naming ``--params``."""
    if text is None:
        return None
    p = Path(text)
    src = text
    if not text.lstrip().startswith(("{", "[")):
        if not p.is_file():
            raise InputError(f"--params must be a JSON object or list, or the path of a file "
                             f"holding one; {text[:60]!r} is neither (no such file)",
                             name="params", value=text)
        try:
            src = p.read_text(encoding="utf-8-sig")
        except UnicodeDecodeError as e:
            raise InputError(f"--params file {p} is not UTF-8 text ({e.reason})",
                             name="params", value=text) from None
    try:
        v = json.loads(src, object_pairs_hook=_unique_keys, parse_int=_params_int)
    except json.JSONDecodeError as e:
        raise InputError(f"--params must be a JSON object or list, or a file holding one; "
                         f"{e.msg} in {text[:60]!r}", name="params", value=text) from None
    except RecursionError:
        raise InputError(f"--params must be a JSON object or list of numbers, got nesting "
                         f"too deep to parse in {text[:60]!r}", name="params",
                         value=text[:60]) from None
    if not isinstance(v, (dict, list)):
        raise InputError(f"--params must be a JSON object {{name: value}} or a list of values, "
                         f"got {type(v).__name__}", name="params", value=text)
    return v


def declared_units(model) -> tuple:
    """Per parameter of ``model``: ``(unit, factor)``, the unit its values are
    stated in and what one of that unit is in the library's units
    (:func:`mechanisms.userfile.stated_units`: the unit of its entry in the
    model file the model was read from, ``"deg"`` with factor pi/180 for
    ``"unit": "deg"``; else :attr:`Model.param_units`, factor 1)."""
    from mechanisms.userfile import stated_units
    return stated_units(model)


def params_vector(model, text: str | None):
    """``--params`` of a parametric model -> its parameter vector in the
    library's units (None when ``text`` is None).

    Named values (``{name: value}``) are read in each parameter's own unit,
    as its model file states its nominal (:func:`declared_units`: degrees
    for ``"unit": "deg"``), and converted; the others keep their nominal.  A
    list of all values is a vector as the library writes it (``checkpoint.json``,
    ``report.json``): in the library's units, lengths in the model's unit and
    angles in rad.  A value more than :data:`FAR_OUTSIDE` tolerances from its
    nominal gets a warning on stderr naming it, its box and its unit."""
    given = parse_params(text)
    if given is None:
        return None
    u = model.vector(given)     # names, numbers and finiteness checked
    own = declared_units(model)
    if isinstance(given, dict):
        idx, units = [model.index(k) for k in given], own
        for i in idx:
            if units[i][1] != 1.0:
                u[i] = u[i] * units[i][1]
    else:
        idx, units = range(model.n), tuple((x, 1.0) for x in model.param_units)
    nom, tol = model.nominal, model.tol
    for i in idx:
        if not abs(u[i] - nom[i]) > FAR_OUTSIDE * max(tol[i], 1e-9 * max(1.0, abs(nom[i]))):
            continue
        unit, k = units[i]
        name = model.names[i]
        if own[i][0] != unit:
            how = (f" (a list is read in the library's units; name the value, "
                   f"{{\"{name}\": ...}}, to give it in {own[i][0]})")
        else:
            how = " (read in the parameter's own unit, as in the model file)"
        print(f"warning: --params: {name} = {u[i] / k:.10g} {unit} lies far outside its "
              f"tolerance box {nom[i] / k:.10g} +/- {tol[i] / k:.6g} {unit}{how}",
              file=sys.stderr)
    return u


def cmd_export_dxf(args) -> int:
    from mechanisms.analysis import resolve_model
    from mechanisms.dxf import export_dxf
    from mechanisms.models import Model
    from mechanisms.dxf import part_layers
    obj = resolve_model(args.model)
    params = (params_vector(obj, args.params) if isinstance(obj, Model)
              else parse_params(args.params))
    export_dxf(obj, args.out, params)
    built = obj.build(params) if isinstance(obj, Model) else obj
    layers = [layer if layer == name else f"{layer} (part {name!r})"
              for _, name, layer in part_layers(built)]
    print(f"wrote {args.out}: one layer per part, {', '.join(layers)}.  A drawing holds the "
          f"profiles only: on import give each part's axis again (--part LAYER:NAME:AXIS), and "
          f"the operating point and tolerances of a model (--q2-start, --drive, --window, "
          f"--deviation, --tol)", file=sys.stderr)
    return 0
