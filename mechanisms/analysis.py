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

__all__ = ["resolve_model", "model_cspaces", "pairs_of"]


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
