"""Model-level analysis: the C-space of every pair of a model (or a fixed pair),
with the model's window and parameter dependencies."""

from __future__ import annotations

from pathlib import Path

from cspace.accuracy import as_accuracy
from cspace.errors import InputError
from cspace.freespace import ConfigurationSpace, configuration_space
from cspace.geometry import Assembly, Pair
from cspace.io import load_json, pair_from_dict

from .models import BUILTIN, Model

__all__ = ["resolve_model", "model_cspaces", "pairs_of", "pair_file_start", "default_drive",
           "simulate_pairs", "motion_at", "MOTION_KEYS"]

#: Optional keys of a pair or assembly file that state its motion, as in a
#: model file: ``"drive": [q1_start, q1_end]`` and ``"q2_start": [one per pair]``
#: (rad, or model units for a slide).  ``analyze`` simulates such a file.
from cspace.io import MOTION_KEYS  # noqa: E402  (the keys a pair file may state)


def resolve_model(spec):
    """A Model, Pair or Assembly from a built-in name, a JSON file path, or a value.

    Built-in names: ``geneva``, ``optical_filter``, ``reciprocating_cam``.  A JSON
    file may hold a pair instance (``cspace-pair``), an assembly
    (``cspace-assembly``) or a parametric model (``cspace-model``).
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
        if isinstance(d, dict):
            d = {k: v for k, v in d.items() if k not in MOTION_KEYS}
        return pair_from_dict(d)
    raise InputError(f"unknown model {s!r}: expected one of {sorted(BUILTIN)} or a path to a "
                     ".json file")


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
    import math
    if not isinstance(spec, (str, Path)) or str(spec) in BUILTIN:
        return None, None
    p = Path(spec)
    if not p.is_file():
        return None, None
    d = load_json(p)
    if not isinstance(d, dict) or d.get("format") == "cspace-model":
        return None, None

    def numbers(key, n, what):
        v = d.get(key)
        if v is None:
            return None
        ok = (isinstance(v, list) and len(v) == n and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
            for x in v))
        if not ok:
            raise InputError(f"{p}: {key!r} must be {what} ({n} finite number(s)), got {v!r}",
                             name=key, value=v)
        return tuple(float(x) for x in v)

    drive = numbers("drive", 2, "[q1_start, q1_end]")
    if drive is not None and drive[0] == drive[1]:
        raise InputError(f"{p}: 'drive' must have two different ends, got {list(drive)}",
                         name="drive", value=list(drive))
    q2 = numbers("q2_start", n_pairs, f"one follower start per pair ({n_pairs})")
    return drive, q2


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
