"""Model-level analysis: the C-space of every pair of a model (or a fixed pair),
with the model's window and parameter dependencies."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cspace.accuracy import as_accuracy
from cspace.errors import FileFormatError, InputError
from cspace.geom2d import degrees_hint
from cspace.freespace import ConfigurationSpace, configuration_space
from cspace.geometry import Assembly, Pair
from cspace.io import ASSEMBLY_FORMAT, PAIR_FORMAT, load_json, pair_from_dict

from .models import BUILTIN, Model

__all__ = ["resolve_model", "model_cspaces", "pairs_of", "pair_file_start", "pair_file_motion",
           "default_drive", "simulate_pairs", "motion_at", "operating_point_notes",
           "AmbiguousStartError", "OperatingPointWarning", "follower_unit", "MOTION_KEYS",
           "STILL_REL", "TOL_FLOOR_REL", "ToleranceResolutionWarning", "tolerance_note"]

#: Optional keys of a pair or assembly file that state its motion, as in a
#: model file: ``"drive": [q1_start, q1_end]`` and ``"q2_start": [one per pair]``
#: (rad, or model units for a slide).  ``analyze`` simulates such a file.
from cspace.io import MOTION_KEYS  # noqa: E402  (the keys a pair file may state)


def resolve_model(spec):
    """A Model, Pair or Assembly from a built-in name, a JSON file path, or a value.

    Built-in names: ``geneva``, ``optical_filter``, ``reciprocating_cam``,
    ``eccentric_cam``.  A JSON file may hold a pair instance (``cspace-pair``),
    an assembly (``cspace-assembly``) or a parametric model (``cspace-model``).
    A pair's ``"closure"`` (a spring-loaded follower) is part of the pair,
    not of the operating point (:data:`MOTION_KEYS`): it is read with it.
    """
    if isinstance(spec, (Model, Pair, Assembly)):
        return spec
    if not isinstance(spec, (str, Path)):
        raise InputError(f"model must be a built-in name, a JSON path or a Model/Pair, got "
                         f"{type(spec).__name__}")
    s = str(spec)
    if not s.strip():
        raise InputError(f"model must be a built-in name ({', '.join(sorted(BUILTIN))}) or the "
                         f"path of a .json file, got an empty string", name="model", value=s)
    if s in BUILTIN:
        return BUILTIN[s]()
    p = Path(s)
    if p.suffix.lower() == ".json" or p.exists():
        d = load_json(p)
        fmt = d.get("format") if isinstance(d, dict) else None
        if fmt == "cspace-model":
            from .userfile import model_from_dict
            return model_from_dict(d)
        if fmt not in (PAIR_FORMAT, ASSEMBLY_FORMAT):
            got = (f"format {fmt!r}" if isinstance(d, dict) and "format" in d else
                   "no 'format' key" if isinstance(d, dict) else f"a JSON {type(d).__name__}")
            raise FileFormatError(f"{p}: expected a JSON object whose 'format' is 'cspace-model' "
                                  f"(a parametric model), {PAIR_FORMAT!r} (a pair) or "
                                  f"{ASSEMBLY_FORMAT!r} (an assembly), got {got}", path="format")
        if isinstance(d, dict):
            d = {k: v for k, v in d.items() if k not in MOTION_KEYS}
        return pair_from_dict(d)
    raise InputError(f"unknown model {s!r}: expected one of {sorted(BUILTIN)} or a path to a "
                     ".json file")


def unbuildable_tolerances(model) -> list:
    """The tolerances of ``model`` that reach values its geometry cannot take:
    per parameter with a positive tolerance, each end of its range (the
    nominal moved by ``-tol`` and ``+tol``, the others at nominal) that does
    not build, as ``(name, value, reason)``, and a message a user can act on
    for each.  Every variant there is defective (invalid geometry) and only a
    cut can remove it, so a tolerance larger than the dimension it is on
    (a radius of 10 +- 30) shows here before a synthesis spends its time."""
    out = []
    if not isinstance(model, Model):
        return out
    u0 = model.nominal
    for i, p in enumerate(model.parameters):
        if not p.tol > 0:
            continue
        for sgn in (-1.0, 1.0):
            u = u0.copy()
            u[i] += sgn * p.tol
            try:
                model.build(u)
            except (ValueError, ArithmeticError) as e:
                out.append((p.name, float(u[i]),
                            f"{p.name} = {p.nominal:.6g} {'-' if sgn < 0 else '+'} {p.tol:.6g} = "
                            f"{u[i]:.6g} ({model.units}) does not build ({e}); its tolerance "
                            f"reaches values the geometry cannot take: synthesis must cut it "
                            f"or move its nominal away from there, possibly far (a 'fixed' "
                            f"parameter, --fixed {p.name}, is only cut)"))
    return out


def pairs_of(obj, params=None) -> tuple:
    if isinstance(obj, Model):
        return obj.pairs(params)
    if isinstance(obj, Assembly):
        return obj.pairs
    return (obj,)


def model_cspaces(obj, params=None, accuracy=None, window=None) -> list[ConfigurationSpace]:
    """The C-space of every pair of a model (at ``params``) or of a fixed pair/assembly.

    ``window`` overrides the model's window (``Model.window``)."""
    acc = as_accuracy(accuracy)
    if isinstance(obj, Model):
        deps = obj.dependencies()
        win = window if window is not None else obj.window
        return [configuration_space(p, acc, window=win, deps=d)
                for p, d in zip(obj.pairs(params), deps)]
    return [configuration_space(p, acc, window=window) for p in pairs_of(obj)]


def pair_file_start(spec, n_pairs: int):
    """``(drive, q2_start)`` stated by a pair or assembly file (:data:`MOTION_KEYS`),
    each None when absent (also for built-in names and model files, whose
    motion is part of the model).

    Returns
    -------
    drive : (float, float) or None
        Driver range (rad, or model units for a sliding driver).
    q2_start : tuple of float or None
        Follower start of each of the ``n_pairs`` pairs at ``drive[0]``.
    """
    m = pair_file_motion(spec, n_pairs)
    return m["drive"], m["q2_start"]


def pair_file_motion(spec, n_pairs: int) -> dict:
    """The operating point stated by a pair or assembly file (:data:`MOTION_KEYS`):
    ``{"drive", "q2_start", "window", "deviation"}``, each None when absent
    (all None for built-in names and model files, whose operating point is part
    of the model).  Every stated value is checked: finite numbers, the
    ``q2_start`` of each of the ``n_pairs`` pairs, a drive with two different
    ends, a window with ``q1_lo < q1_hi`` and ``q2_lo < q2_hi``, ``d > 0``."""
    import math
    none = dict.fromkeys(MOTION_KEYS)
    if not isinstance(spec, (str, Path)) or str(spec) in BUILTIN:
        return none
    p = Path(spec)
    if not p.is_file():
        return none
    d = load_json(p)
    if not isinstance(d, dict) or d.get("format") == "cspace-model":
        return none

    def finite(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)

    def numbers(key, n, what):
        v = d.get(key)
        if v is None:
            return None
        if not (isinstance(v, list) and len(v) == n and all(finite(x) for x in v)):
            hint = (f" (a JSON list, even of one: [{v!r}])"
                    if n == 1 and finite(v) and not isinstance(v, list) else "")
            raise InputError(f"{p}: {key!r} must be {what}: a JSON list of {n} finite "
                             f"number(s), got {v!r}{hint}", name=key, value=v)
        return tuple(float(x) for x in v)

    drive = numbers("drive", 2, "[q1_start, q1_end]")
    if drive is not None and drive[0] == drive[1]:
        raise InputError(f"{p}: 'drive' must have two different ends, got {list(drive)}",
                         name="drive", value=list(drive))
    window = numbers("window", 4, "[q1_lo, q1_hi, q2_lo, q2_hi]")
    if window is not None and not (window[0] < window[1] and window[2] < window[3]):
        raise InputError(f"{p}: 'window' must have q1_lo < q1_hi and q2_lo < q2_hi, got "
                         f"{list(window)}", name="window", value=list(window))
    dev = d.get("deviation")
    if dev is not None and not (finite(dev) and dev > 0):
        raise InputError(f"{p}: 'deviation' must be a finite number > 0 (C-space metric: rad, "
                         f"or slide / characteristic length), got {dev!r}", name="deviation",
                         value=dev)
    return {"drive": drive,
            "q2_start": numbers("q2_start", n_pairs, f"one follower start per pair ({n_pairs})"),
            "window": window, "deviation": None if dev is None else float(dev)}


def default_drive(cs: ConfigurationSpace) -> tuple:
    """One driver period from the window start (a rotating driver), else the
    window's driver range."""
    import math
    lo = cs.window[0]
    return (lo, lo + 2 * math.pi) if cs.periodic[0] else (cs.window[0], cs.window[1])


def simulate_pairs(spaces, drive=None, q2_start=None) -> list:
    """Simulate every pair's C-space over ``drive`` from ``q2_start``.

    Parameters
    ----------
    spaces : sequence of ConfigurationSpace
    drive : (q1_start, q1_end), optional
        Default :func:`default_drive` of the first C-space.
    q2_start : sequence of float, optional
        One follower start per pair (one value is used for all); default the
        middle of the widest free interval at ``drive[0]``.

    Returns
    -------
    list of cspace.simulate.SimulationResult
    """
    from cspace.simulate import simulate
    spaces = list(spaces)
    drive = default_drive(spaces[0]) if drive is None else tuple(float(x) for x in drive)
    if q2_start is None:
        q2s = [cs.default_start(drive[0]) for cs in spaces]
    else:
        q2s = [float(v) for v in q2_start]
        if len(q2s) == 1:
            q2s = q2s * len(spaces)
        if len(q2s) != len(spaces):
            raise InputError(f"q2_start must give one follower start per pair ({len(spaces)}) "
                             f"or one for all, got {len(q2s)}", name="q2_start", value=q2s)
    for cs, q2 in zip(spaces, q2s):
        lo2, hi2 = cs.window[2], cs.window[3]
        if not cs.periodic[1] and not lo2 <= q2 <= hi2:
            # refused as a model's is (a pair file's start was simulated as
            # blocked, with a warning)
            raise InputError(f"the follower start q2 = {q2:.6g} of pair {cs.pair.name!r} is "
                             f"outside the follower window [{lo2:.6g}, {hi2:.6g}]; q2_start "
                             f"must lie in the window", name="q2_start", value=q2)
    return [simulate(cs, drive[0], drive[1], q2) for cs, q2 in zip(spaces, q2s)]


def motion_at(model, params=None, accuracy=None):
    """C-spaces and simulated motion of a parametric model at a parameter vector
    (default the nominal), with the model's window, drive and follower starts.

    Unlike :func:`cspace.defects.reference` a blocked start is a result
    (``SimStatus.START_BLOCKED``), not an error: a defective variant can be
    looked at (:func:`cspace.plotting.animate_motion`).

    Returns
    -------
    spaces : list of ConfigurationSpace
    sims : list of SimulationResult
    """
    spaces = model_cspaces(model, params, accuracy)
    drive = tuple(model.drive) if model.drive is not None else None
    return spaces, simulate_pairs(spaces, drive, model.q2_start)


#: A nominal follower whose travel over the drive is below this share of its
#: window's q2 span "never moves" (:func:`operating_point_notes`).
STILL_REL = 1e-9


class OperatingPointWarning(UserWarning):
    """The operating point may not be the one the user means (a default start
    among several free intervals, a follower that never moves)."""


class ToleranceResolutionWarning(UserWarning):
    """Some tolerance is below what the engine resolves (:func:`tolerance_note`)."""


#: :func:`tolerance_note`: a nonzero tolerance below this share of the model's
#: size is below what the engine resolves.  Contacts, merges and curve ends are
#: placed to ``cspace.tolerances.SLACK`` (1e-9) of a part's size; a tolerance
#: a thousand times that keeps a margin's rounding below a tenth of a percent
#: of its change over the box.  Observed: a crank-and-lever model of 90 mm
#: synthesized to the same result with every tolerance scaled by 1e-2 (2.2e-6
#: of its size), but not by 1e-3 (2.2e-7): its cuts changed, and at 1e-4 the
#: synthesis no longer converged.
TOL_FLOOR_REL = 1e-6


def tolerance_note(model):
    """A warning ``(True, text)`` when some nonzero tolerance of ``model`` is
    below :data:`TOL_FLOOR_REL` of the model's size (the largest size of its
    nominal pairs): there the results depend on the engine's rounding slack,
    not on the tolerances (a synthesis may cut other parameters, or not
    converge, than at the same tolerances scaled up); else None."""
    tol = np.asarray(model.tol, dtype=float)
    if not len(tol) or not np.any(tol > 0):
        return None
    try:
        size = max(float(p.size) for p in model.pairs())
    except (ValueError, ArithmeticError):
        return None
    floor = TOL_FLOOR_REL * size
    small = np.nonzero((tol > 0) & (tol < floor))[0].tolist()
    if not small:
        return None
    named = ", ".join(f"{model.names[i]} +- {tol[i]:.3g}" for i in small[:5])
    more = f" and {len(small) - 5} more" if len(small) > 5 else ""
    return (True, f"{len(small)} tolerance(s) below {TOL_FLOOR_REL:g} of the model's size "
                  f"({size:.4g} {getattr(model, 'units', '')}".rstrip() + f"): {named}{more}.  "
                  "The engine places contacts to 1e-9 of a part's size, so results there "
                  "follow its rounding, not the tolerances (docs/limits.md, 'Supported "
                  "sizes'); tolerances that small are also below any manufacturing process")


class AmbiguousStartError(InputError):
    """The model states no follower start and the default one is one of several
    free intervals: synthesis would design a mechanism the user may not mean.

    Attributes
    ----------
    choices : tuple of cspace.freespace.StartChoice
        The ambiguous choices, one per pair concerned.
    """

    def __init__(self, message: str, choices=()):
        super().__init__(message, name="q2_start", value=None)
        self.choices = tuple(choices)


def operating_point_notes(spaces, sims, choices=None) -> list:
    """What a user must know about the operating point of a nominal motion.

    Parameters
    ----------
    spaces : sequence of ConfigurationSpace
    sims : sequence of SimulationResult
        The nominal motion of each pair.
    choices : sequence of StartChoice or None, optional
        Per pair, how its start was chosen when the model states none
        (:attr:`cspace.defects.Reference.start_choices`); None for a stated start.

    Returns
    -------
    list of (warning, text)
        ``warning`` is True for what can make the analysis another mechanism's:
        a default start among several free intervals, a follower that never
        moves over the drive (nothing pushes it from its start: a form-closed
        follower that starts away from the driver), or a spring-loaded
        follower that leaves the driver and rests on the window's edge.
        False: which start was chosen and why, and how far a spring-loaded
        follower travels (its first and last output are equal over a closed
        cam cycle), and where a follower that starts in the play of its channel
        has taken it up (a drive of whole turns that ends elsewhere than it
        started, and from there repeats).
    """
    out = []
    choices = list(choices) if choices is not None else [None] * len(spaces)
    out += _long_drive_note(spaces, sims)
    for cs, sim, ch in zip(spaces, sims, choices):
        unit = follower_unit(cs.pair)
        name = cs.pair.name
        bias = int(getattr(sim, "bias", 0))
        if ch is not None:
            text = ch.describe(unit)
            if ch.ambiguous:
                text += ("; state the start (model or pair file 'q2_start', "
                         "import-dxf --q2-start, analyze --q2-start)")
            out.append((ch.ambiguous, text))
        q2 = np.asarray(sim.q2, dtype=float)
        span = float(cs.window[3] - cs.window[2])
        moving = not (len(q2) > 1 and sim.success
                      and np.ptp(q2) <= STILL_REL * max(abs(span), 1e-300))
        way = "decreasing" if bias < 0 else "increasing"
        if not moving and bias:
            out.append((True, f"pair {name!r}: the nominal follower never moves over the "
                              f"drive (q2 stays at {q2[0]:.6g} {unit}): it is held toward "
                              f"{way} q2, and the bound it rests on does not move, so there "
                              f"is no motion to keep; check the closure's bias, the drive "
                              f"and the window"))
        elif not moving:
            out.append((True, f"pair {name!r}: the nominal follower never moves over "
                              f"the drive (q2 stays at {q2[0]:.6g} {unit}): nothing pushes it "
                              f"from its start, so there is no motion to keep and every defect "
                              f"test compares a follower at rest; start it where the driver "
                              f"pushes it (q2_start), make it spring-loaded (closure), or "
                              f"check the drive and the window"))
        elif bias and len(q2):
            out.append((False, f"pair {name!r}: spring-loaded follower (held toward {way} "
                               f"q2): it rides the driver, q2 from {np.min(q2) + 0.0:.6g} "
                               f"to {np.max(q2) + 0.0:.6g} {unit} over the drive"))
        if bias and not cs.periodic[1] and len(q2):
            off = np.array([c == "" for c in sim.contact], dtype=bool)
            if off.any():
                edge = cs.window[2] if bias < 0 else cs.window[3]
                out.append((True, f"pair {name!r}: the spring-loaded follower leaves the "
                                  f"driver over {np.mean(off):.1%} of the drive samples and "
                                  f"rests on the window's edge q2 = {edge:.6g} {unit}, taken "
                                  f"as its travel limit (a stop); widen the window where "
                                  f"it has none"))
        settle = _settling_note(cs, sim, name, unit)
        if settle:
            out.append((False, settle))
    return out


def _settling_note(cs, sim, name: str, unit: str):
    """A note when a drive of whole turns does not end where it starts but
    would from where it ends: the follower starts where nothing holds it (in
    the play of a form-closed channel) and the first turn takes the play up,
    a motion the running machine makes once, if ever; the defect test then
    compares every variant's take-up from that arbitrary start.  None when
    the motion closes (:func:`cspace.match.closed_motion`), when the drive
    is not whole turns of a turning driver, or when a second cycle does not
    close either (a Geneva wheel indexes on by design)."""
    from cspace.match import closed_motion, same_place, whole_turns
    from cspace.simulate import simulate
    if not whole_turns(cs, sim) or closed_motion(cs, sim):
        return None
    q1 = np.asarray(sim.q1, dtype=float)
    q2 = np.asarray(sim.q2, dtype=float)
    again = simulate(cs, float(q1[-1]), float(2 * q1[-1] - q1[0]), float(q2[-1]))
    if not closed_motion(cs, again):
        return None
    # where the first cycle first reaches the repeating motion
    there = same_place(cs, q2, np.interp(q1, np.asarray(again.q1) - (q1[-1] - q1[0]), again.q2))
    k = int(np.argmax(there)) if there.any() else len(q1) - 1
    end = float(q2[-1])
    if cs.periodic[1]:
        # the same place, in the window (the follower has turned)
        lo2 = float(cs.window[2])
        end = (end - lo2) % (2 * math.pi) + lo2
    return (f"pair {name!r}: the follower starts at q2 = {q2[0]:.6g} {unit}, in the play of "
            f"its channel, and ends the drive at {q2[-1]:.6g} {unit}, from where the motion "
            f"repeats: {_taken_up(q1, k)}.  The "
            f"defect test compares every variant's motion from this start, the take-up "
            f"included; to test the repeating motion alone, state q2_start = {end:.9g}")


def _taken_up(q1, k: int) -> str:
    """Where the motion's samples place the end of the take-up: between the
    sample before the first on the repeating motion (``k``) and that one."""
    b = abs(float(q1[k] - q1[0]))
    if k == 0:
        return "the play is taken up at once"
    a = abs(float(q1[k - 1] - q1[0]))
    return f"the play is taken up between {a:.4g} and {b:.4g} rad into the drive (its samples)"


#: A rotating driver's drive longer than this many turns is most often one
#: written in degrees (:func:`operating_point_notes`).
LONG_DRIVE_TURNS = 8


#: :func:`deviation_note`: a default deviation threshold at least this share
#: of the follower's travel over the drive is named in a warning.
LOOSE_D = 0.25


def deviation_note(model, ref):
    """A warning ``(True, text)`` when a stated deviation threshold is at least
    a pair's whole follower travel; or when the reference ``ref`` of ``model`` has
    the default deviation threshold (``5 * t / L``, t the largest tolerance of a
    parameter that moves a contact, :func:`cspace.defects.default_deviation`)
    is at least :data:`LOOSE_D` of some pair's nominal follower travel over
    the drive: a variant would have to move its output by that much before
    the deviation test saw it (one large tolerance, a radius of 10 +- 50, makes
    d a slide of 250 mm on a 20 mm stroke); else None."""
    from cspace.defects import default_deviation, deviation_parameter
    if not len(model.tol):
        return None
    if ref.d != default_deviation(model, ref.spaces, ref.sims):
        return _stated_deviation_note(ref)      # a threshold stated (model or caller)
    i, t = deviation_parameter(model, ref.spaces, ref.sims)
    which = f"{model.names[i]} +- {model.tol[i]:.4g}"
    if model.parameters[i].unit == "rad":
        which += f" rad, an arc of {t:.4g} {model.units} at L"
    loose = [f"{name!r}: d = {ref.d * L:.4g} {unit}, {ref.d / travel:.0%} of the "
             f"follower's travel {travel * L:.4g} {unit}"
             for name, unit, L, travel in _travels(ref) if ref.d >= LOOSE_D * travel]
    if not loose:
        return None
    return (True, f"the model states no deviation threshold, and the default, 5 times the "
                  f"largest tolerance of a parameter that moves a contact ({which}) at "
                  f"the reach L, "
                  "is loose: " + "; ".join(loose) + ".  A variant must move its output that "
                  "far before the deviation test sees it; state the model's 'deviation' "
                  "(synthesize --deviation)")


def _travels(ref):
    """Per pair whose nominal follower moves: ``(name, unit, L, travel)``, the
    follower's unit, the length that counts as 1 in the C-space metric and
    its whole travel over the drive in that metric."""
    for cs, sim in zip(ref.spaces, ref.sims):
        q2 = np.asarray(sim.q2, dtype=float)
        if len(q2) < 2:
            continue
        unit = follower_unit(cs.pair)
        L = 1.0 if unit == "rad" else float(cs.pair.char_length)
        travel = float(np.ptp(q2)) / L
        if travel > 0:
            yield cs.pair.name, unit, L, travel


def _stated_deviation_note(ref):
    """A warning ``(True, text)`` when a stated deviation threshold is at least
    a pair's whole nominal follower travel over the drive (no variant that
    follows the drive can deviate that far: the test never fires; most often a
    threshold in degrees or in another unit); else None."""
    big = []
    for name, unit, L, travel in _travels(ref):
        if ref.d >= travel:
            hint = (f" (d is in rad; written in degrees? {ref.d:.4g} deg is "
                    f"{math.radians(ref.d):.4g} rad)" if unit == "rad" else "")
            big.append(f"{name!r}: d = {ref.d * L:.4g} {unit}{hint}, "
                       f"{ref.d / travel:.3g} times the follower's whole travel "
                       f"{travel * L:.4g} {unit}")
    if not big:
        return None
    return (True, "the stated deviation threshold is at least the follower's whole travel: "
                  + "; ".join(big) + ".  No output can deviate that far while it follows "
                  "the drive, so the deviation test never finds a defect")


def _long_drive_note(spaces, sims) -> list:
    """A warning when a rotating driver's drive spans more than
    :data:`LONG_DRIVE_TURNS` turns: the drive is in rad, and a drive written in
    degrees (``[0, 360]``) is 57 turns."""
    from cspace.geometry import Rotation
    if not spaces or not sims or not isinstance(spaces[0].pair.driver.axis, Rotation):
        return []
    q1 = np.asarray(sims[0].q1, dtype=float)
    if len(q1) < 2:
        return []
    a, b = float(q1[0]), float(q1[-1])
    turns = abs(b - a) / (2 * np.pi)
    if turns <= LONG_DRIVE_TURNS:
        return []
    whole = abs(turns - round(turns)) <= 1e-9 * turns
    return [(True, f"the drive runs the driver {turns:.4g} turns (q1 from {a:.6g} to "
                   f"{b:.6g} rad); drive angles are in rad"
                   + ("" if whole else degrees_hint(a, b, span=(0.0, math.inf))))]


def follower_unit(pair) -> str:
    """The unit of a pair's follower coordinate q2: ``"rad"`` for a rotating
    follower, else the pair's length unit."""
    from cspace.geometry import Rotation
    return "rad" if isinstance(pair.follower.axis, Rotation) else pair.units
