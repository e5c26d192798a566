"""The checkpoint file of ``cspace-tol synthesize``: its content hash.

A checkpoint is the JSON of :meth:`SynthesisState.to_dict` plus the key
``"sha256"``: the SHA-256 of the rest of the document in a canonical form (keys
sorted, no spaces, floats by ``repr``, which JSON reads back bit for bit).  A
checkpoint whose content no longer matches its hash (a digit changed by hand, a
disk error that left valid JSON) is refused with a
:class:`~cspace.errors.FileFormatError` that says so, and is left as it is.

The hash guards against damage, not against a deliberate edit: anyone can
recompute it.  A checkpoint without ``"sha256"`` was written before the hash
was kept; it is read with the content checks of :meth:`SynthesisState.from_dict`
only (:func:`read_checkpoint` reports it through ``verified``).

A checkpoint written with the model (``write_checkpoint(path, state, model=...)``,
as ``cspace-tol synthesize`` does) also holds ``"model_fingerprint"``
(:func:`model_fingerprint`): hashes of a canonical form of the model's
definition (geometry, parameters, operating point) and its deviation threshold.
:func:`check_model` compares it with the model a resumed run is given and raises
:class:`ModelMismatchError`, naming what differs, when the model is not the one
the run was started with.  A checkpoint without it (written before it was kept)
is checked for the model's name and an explicitly asked d only.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import pickle

import numpy as np

from cspace.errors import FileFormatError, InputError
from cspace.io import atomic_write, dumps, load_json

from .result import SynthesisState

__all__ = ["content_hash", "checkpoint_text", "write_checkpoint", "read_checkpoint",
           "load_checkpoint", "Checkpoint", "model_fingerprint", "check_model",
           "ModelMismatchError", "HASH_KEY", "FINGERPRINT_KEY"]

#: The key of the content hash in a checkpoint document.
HASH_KEY = "sha256"

#: The key of the model's fingerprint (:func:`model_fingerprint`) in a checkpoint.
FINGERPRINT_KEY = "model_fingerprint"


def content_hash(doc: dict) -> str:
    """SHA-256 (hex) of a checkpoint document without its ``HASH_KEY``."""
    body = {k: v for k, v in doc.items() if k != HASH_KEY}
    # through JSON once so that numpy values and tuples hash as they are read back
    canon = json.dumps(json.loads(dumps(body)), sort_keys=True, separators=(",", ":"),
                       allow_nan=False)
    return hashlib.sha256(canon.encode("utf-8")).hexdigest()


def checkpoint_text(state: SynthesisState, model=None) -> str:
    """The checkpoint file's text: the state's JSON with its content hash and,
    when ``model`` is given, the model's fingerprint (:func:`model_fingerprint`)."""
    d = state.to_dict()
    if model is not None:
        d[FINGERPRINT_KEY] = model_fingerprint(model)
    d[HASH_KEY] = content_hash(d)
    return dumps(d)


def write_checkpoint(path, state: SynthesisState, model=None):
    """Write ``state`` to ``path`` atomically, with its content hash and, when
    ``model`` (the model the run was started with) is given, its fingerprint."""
    return atomic_write(path, checkpoint_text(state, model))


@dataclasses.dataclass(frozen=True)
class Checkpoint:
    """A checkpoint file read by :func:`load_checkpoint`.

    Attributes
    ----------
    state : SynthesisState
    verified : bool
        False for a checkpoint written before hashes were kept (no ``"sha256"``).
    fingerprint : dict or None
        The fingerprint of the model the run was started with
        (:func:`model_fingerprint`); None for a checkpoint written without it.
    """

    state: SynthesisState
    verified: bool
    fingerprint: dict | None = None


def read_checkpoint(path) -> tuple[SynthesisState, bool]:
    """The state in a checkpoint file and whether its hash was verified.

    Returns
    -------
    state : SynthesisState
    verified : bool
        False for a checkpoint written before hashes were kept (no ``"sha256"``).

    Raises
    ------
    FileFormatError
        Not a checkpoint, damaged content, or content that does not match its
        hash.
    """
    ck = load_checkpoint(path)
    return ck.state, ck.verified


def load_checkpoint(path) -> Checkpoint:
    """The checkpoint file at ``path``: its state, whether its hash was verified,
    and the fingerprint of the model it was started with (see
    :func:`read_checkpoint`; a damaged fingerprint is a :class:`FileFormatError`)."""
    doc = load_json(path)
    state = SynthesisState.from_dict(doc, path=str(path))
    fingerprint = _stored_fingerprint(doc.get(FINGERPRINT_KEY), str(path))
    if not isinstance(doc, dict) or HASH_KEY not in doc:
        return Checkpoint(state, False, fingerprint)
    stored = doc[HASH_KEY]
    if not isinstance(stored, str) or len(stored) != 64:
        raise FileFormatError(f"damaged checkpoint: {HASH_KEY!r} must be 64 hex digits, got "
                              f"{str(stored)[:70]!r}", path=str(path))
    actual = content_hash(doc)
    if stored.lower() != actual:
        raise FileFormatError(f"damaged checkpoint: its content does not match its "
                              f"{HASH_KEY} (stored {stored[:12]}..., content gives "
                              f"{actual[:12]}...); the file was changed after it was written. "
                              f"It is left as it is: restore it, or start over with --fresh",
                              path=str(path))
    return Checkpoint(state, True, fingerprint)


# ------------------------------------------------------------------ model fingerprint

#: The sections of a model's fingerprint and what each covers (for messages).
FINGERPRINT_SECTIONS = {
    "geometry": "geometry (parts, profiles, expressions, let values, closure, units)",
    "parameters": "parameters (names, units, nominal values, tolerances, guards, "
                  "distributions)",
    "operating_point": "operating point (window, drive, follower start)",
}


def _canon(v):
    """``v`` as plain JSON values: numbers as floats (1 and 1.0 alike), tuples as
    lists, dataclasses and mappings as objects with string keys."""
    if isinstance(v, (bool, np.bool_)) or v is None or isinstance(v, str):
        return bool(v) if isinstance(v, np.bool_) else v
    if isinstance(v, (int, float, np.integer, np.floating)):
        return float(v)
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        v = {f.name: getattr(v, f.name) for f in dataclasses.fields(v)}
    if isinstance(v, dict):
        return {str(k): _canon(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_canon(x) for x in v]
    raise TypeError(f"cannot fingerprint a {type(v).__name__}")


def _digest(v) -> str:
    text = json.dumps(_canon(v), sort_keys=True, separators=(",", ":"), allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _geometry(model):
    """What builds the model's geometry: a model file's pairs and ``let`` block
    (their descriptions left out), else the builder's import name (built-in
    models: their code), else its pickle."""
    from mechanisms.userfile import ModelFileBuilder
    b = model.builder
    if isinstance(b, ModelFileBuilder):
        doc = json.loads(b.document)
        lets = [{k: x for k, x in item.items() if k != "description"}
                if isinstance(item, dict) else item for item in doc.get("let", [])]
        return {"file": {"units": b.units, "let": lets, "pairs": doc.get("pairs")},
                "units": model.units}
    name = getattr(b, "__qualname__", None)
    module = getattr(b, "__module__", None)
    if isinstance(name, str) and isinstance(module, str) and "<" not in name:
        return {"code": f"{module}.{name}", "units": model.units}
    try:
        code = hashlib.sha256(pickle.dumps(b, protocol=4)).hexdigest()
    except Exception:   # noqa: BLE001 - an unpicklable builder: its repr
        code = f"{type(b).__module__}.{type(b).__qualname__}:{b!r}"
    return {"object": code, "units": model.units}


def model_fingerprint(model) -> dict:
    """The fingerprint of a model's definition, as a checkpoint stores it.

    ``{"sha256": ..., "sections": {"geometry": ..., "parameters": ...,
    "operating_point": ...}, "deviation": d or None}``: SHA-256 hashes of a
    canonical serialisation of each part of the definition (keys sorted,
    numbers as floats) and the model's own deviation threshold.  Everything
    that changes results is covered; only descriptions are left out.  A
    built-in model's geometry is its code, named by its builder.
    """
    params = []
    for p in model.parameters:
        e = _canon(p)
        e.pop("description", None)
        params.append(e)
    op = {k: getattr(model, k) for k in ("window", "drive", "q2_start")}
    sections = {"geometry": _digest(_geometry(model)), "parameters": _digest(params),
                "operating_point": _digest(op)}
    dev = None if model.deviation is None else float(model.deviation)
    return {"sha256": _digest({"sections": sections, "deviation": dev}),
            "sections": sections, "deviation": dev}


def _is_hex(v) -> bool:
    return (isinstance(v, str) and len(v) == 64
            and all(c in "0123456789abcdef" for c in v.lower()))


def _stored_fingerprint(v, path: str) -> dict | None:
    """A checkpoint's fingerprint entry, checked (None when absent)."""
    if v is None:
        return None
    ok = (isinstance(v, dict) and _is_hex(v.get("sha256"))
          and isinstance(v.get("sections"), dict)
          and all(isinstance(k, str) and _is_hex(h) for k, h in v["sections"].items())
          and (v.get("deviation") is None
               or (isinstance(v["deviation"], (int, float))
                   and not isinstance(v["deviation"], bool))))
    if not ok:
        raise FileFormatError(f"damaged checkpoint: {FINGERPRINT_KEY!r} must be an object with "
                              f"'sha256', 'sections' and 'deviation', got {str(v)[:120]!r}",
                              path=path)
    return v


class ModelMismatchError(InputError):
    """A checkpoint is resumed with a model (or a deviation threshold) other than
    the one its run was started with.

    Attributes
    ----------
    kind : str
        What differs: ``"name"``, ``"deviation"`` or ``"definition"``.
    saved, given
        The checkpoint's value and the given one (for ``"definition"``, the
        fingerprints' hashes).
    sections : tuple of str
        For ``"definition"``: the sections of :func:`model_fingerprint` that
        differ.
    """

    def __init__(self, message: str, *, kind: str, saved=None, given=None,
                 sections: tuple = ()):
        super().__init__(message, name="model", value=given)
        self.kind = kind
        self.saved = saved
        self.given = given
        self.sections = tuple(sections)


_REMEDY = ("To continue this run, give the model it was started with (the same file, "
           "unchanged); to run the given model, start a new run in another folder (--out), "
           "or here with --fresh, which discards this run")


def _mismatch(what: str, **kw) -> ModelMismatchError:
    return ModelMismatchError(f"--resume: the model given is not the one the checkpoint was "
                              f"started with: {what}. {_REMEDY}", **kw)


def _other_setting(what: str, flag: str, **kw) -> ModelMismatchError:
    return ModelMismatchError(f"--resume: this run asks for another setting than the "
                              f"checkpoint's: {what}. Drop {flag} to resume with the "
                              f"checkpoint's value; to run with the new value, start a new run "
                              f"in another folder (--out), or here with --fresh, which "
                              f"discards this run", **kw)


def _d_text(v) -> str:
    return "none (the library default)" if v is None else repr(float(v))


def check_model(checkpoint: Checkpoint, model, deviation: float | None = None) -> bool:
    """Refuse to resume ``checkpoint`` with ``model`` (and the deviation threshold
    ``deviation`` asked for, None: the checkpoint's) when they are not those the
    run was started with.

    Returns True when the model's definition was compared with the checkpoint's
    fingerprint, False for a checkpoint written without one (only the name and
    ``deviation`` are checked then).

    Raises
    ------
    ModelMismatchError
        Another model name, another deviation threshold (``deviation``, or the
        model's own ``"deviation"``), or another definition (geometry,
        parameters, operating point); the message says which and what to do.
    """
    state = checkpoint.state
    if state.model != model.name:
        raise _mismatch(f"model name: checkpoint {state.model!r}, given {model.name!r}",
                        kind="name", saved=state.model, given=model.name)
    if deviation is not None and float(deviation) != state.d:
        raise _other_setting(f"deviation threshold d: checkpoint {state.d!r}, given "
                             f"{float(deviation)!r} (--deviation)", "--deviation",
                             kind="deviation", saved=state.d, given=float(deviation))
    stored = checkpoint.fingerprint
    if stored is None:
        return False
    now = model_fingerprint(model)
    saved_d = stored.get("deviation")
    if (None if saved_d is None else float(saved_d)) != now["deviation"]:
        uses = ("" if deviation is not None or saved_d is None or float(saved_d) == state.d
                else f"; the run uses d = {state.d!r}")
        raise _mismatch(f"deviation threshold d: checkpoint {_d_text(saved_d)}, given "
                        f"{_d_text(now['deviation'])} (the model's \"deviation\"{uses})",
                        kind="deviation", saved=saved_d, given=now["deviation"])
    if str(stored["sha256"]).lower() == now["sha256"]:
        return True
    old = stored["sections"]
    differ = tuple(k for k in now["sections"] if old.get(k) != now["sections"][k])
    where = ("; what differs: its " + " and its ".join(FINGERPRINT_SECTIONS[k] for k in differ)
             if differ else "")
    raise _mismatch(f"the model's definition differs from the checkpoint's (its fingerprint: "
                    f"checkpoint {str(stored['sha256'])[:12]}..., given "
                    f"{now['sha256'][:12]}...){where}", kind="definition",
                    saved=stored["sha256"], given=now["sha256"], sections=differ)
