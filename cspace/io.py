"""Files: the pair-instance JSON, the C-space JSON, and atomic writes.

Pair instance JSON (``"format": "cspace-pair"``)::

    {"format": "cspace-pair", "version": 1, "name": "geneva", "units": "cm",
     "parts": [
       {"name": "driver",
        "axis": {"type": "rotation", "center": [0, 0]},
        "loops": [[{"type": "arc", "center": [-3.5, 0], "radius": 0.3,
                    "start_angle": 0, "end_angle": 6.283185307179586, "ccw": true}], ...]},
       {"name": "wheel",
        "axis": {"type": "translation", "direction": [1, 0], "origin": [0, 0]}, ...}]}

* Segments are ``{"type": "line", "start": [x, y], "end": [x, y]}`` or
  ``{"type": "arc", "center": [x, y], "radius": r, "start_angle": a0,
  "end_angle": a1, "ccw": true}``, with an optional ``"name"``.
* Angles are radians; lengths are in ``units``.
* A loop's material lies to the left of travel (outer loops counter-clockwise,
  holes clockwise).  Coordinates are world coordinates at configuration 0.
* The first part is the driver (q1), the second the follower (q2).
* An optional ``"closure": {"bias": -1}`` (or ``1``) makes the follower
  force-closed (spring-loaded): held toward decreasing (increasing) q2 against
  the driver (:attr:`~cspace.geometry.Pair.bias`).  Without it the follower is
  form-closed: it moves only when pushed.

An assembly of pairs on one driver is ``{"format": "cspace-assembly", "version": 1,
"name": ..., "pairs": [<pair>, ...]}``.

Loading parses JSON only; nothing in a file is executed.  A bad file raises
:class:`~cspace.errors.FileFormatError` (or the geometry error its content
causes) whose ``path`` names the failing item, e.g. ``parts[1].loops[0][3].radius``.
"""

from __future__ import annotations

import errno
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import CSpaceError, DegenerateGeometryError, FileFormatError
from .geometry import BIASES, Arc, Assembly, Line, Loop, Pair, Part, Rotation, Translation

__all__ = ["pair_to_dict", "pair_from_dict", "save_pair", "load_pair", "cspace_to_dict", "dumps",
           "save_cspace", "atomic_write", "load_json", "parse_json_text", "json_depth",
           "json_float", "number_text", "closure_from_dict", "key_suggestions",
           "missing_key_message", "MAX_JSON_DEPTH", "MAX_INT_DIGITS", "LENGTH_UNITS",
           "UNIT_ALIASES", "canonical_unit", "check_units", "UnitWarning"]

PAIR_FORMAT = "cspace-pair"
ASSEMBLY_FORMAT = "cspace-assembly"
CSPACE_FORMAT = "cspace-cspace"

# ------------------------------------------------------------------- length units

#: The length units this library knows (their canonical names) and one of each
#: in metres: the units a DXF drawing states in ``$INSUNITS``
#: (:data:`mechanisms.dxf.INSUNITS`).
LENGTH_UNITS = {"in": 0.0254, "ft": 0.3048, "mi": 1609.344, "mm": 1e-3, "cm": 1e-2, "m": 1.0,
                "km": 1e3, "uin": 2.54e-8, "mil": 2.54e-5, "yd": 0.9144, "nm": 1e-9,
                "um": 1e-6, "dm": 0.1, "dam": 10.0, "hm": 100.0}


def _spellings(canon: str, *words: str) -> dict:
    out = {}
    for w in words:
        out[w] = canon
        if w.endswith(("meter", "metre")):
            out[w + "s"] = canon
    return out


#: Other names of the units in :data:`LENGTH_UNITS` (matched case-insensitively,
#: e.g. ``"inch"``, ``"millimetre"``, ``"µm"``), each to its canonical name.
UNIT_ALIASES = {
    **_spellings("mm", "millimeter", "millimetre"),
    **_spellings("cm", "centimeter", "centimetre"),
    **_spellings("m", "meter", "metre"),
    **_spellings("km", "kilometer", "kilometre"),
    **_spellings("dm", "decimeter", "decimetre"),
    **_spellings("dam", "decameter", "decametre", "dekameter", "dekametre"),
    **_spellings("hm", "hectometer", "hectometre"),
    **_spellings("nm", "nanometer", "nanometre"),
    **_spellings("um", "micrometer", "micrometre", "micron", "microns", "\u00b5m", "\u03bcm"),
    "inch": "in", "inches": "in", "foot": "ft", "feet": "ft", "mile": "mi", "miles": "mi",
    "yard": "yd", "yards": "yd", "mils": "mil", "thou": "mil",
    "microinch": "uin", "microinches": "uin", "\u00b5in": "uin", "\u03bcin": "uin",
}


def canonical_unit(units) -> str | None:
    """The canonical name (a key of :data:`LENGTH_UNITS`) of a length unit given
    by its name or an alias (case-insensitive, e.g. ``"Inch"`` -> ``"in"``,
    ``"µm"`` -> ``"um"``); None for a name this library does not know."""
    if not isinstance(units, str):
        return None
    u = units.strip()
    if u in LENGTH_UNITS:
        return u
    low = u.lower()
    if low in LENGTH_UNITS:
        return low
    return UNIT_ALIASES.get(low)


def known_units_text() -> str:
    """The known length units for a message: canonical names, then aliases."""
    return (f"{', '.join(LENGTH_UNITS)} (or an alias such as inch, feet, millimetre, "
            f"meter, micron, \u00b5m, thou; case-insensitive)")


class UnitWarning(UserWarning):
    """A file states a length unit this library does not know (:data:`LENGTH_UNITS`,
    :data:`UNIT_ALIASES`): its lengths are used as they stand, but cannot be
    converted, and a DXF drawing written from it is unitless."""


def check_units(units, where: str = "units") -> str | None:
    """The canonical name of ``units``; a :class:`UnitWarning` that names
    ``where`` and the known units when the library does not know it (the file
    still loads: legacy files may use any name)."""
    import warnings
    canon = canonical_unit(units)
    if canon is None:
        shown = repr(units)
        if len(shown) > 60:
            shown = f"{shown[:40]}... ({len(units)} characters)"
        warnings.warn(f"{where}: length unit {shown} is not one this library knows, so "
                      f"its lengths are used as they stand but cannot be converted, and a "
                      f"DXF drawing written from it states no unit ($INSUNITS = 0); "
                      f"expected one of {known_units_text()}", UnitWarning, stacklevel=3)
    return canon


def atomic_write(path, data) -> Path:
    """Write text or bytes to ``path`` atomically (temporary file, then rename).

    A crash or interrupt never leaves a half-written file at ``path``.  The file
    gets the permissions a plain ``open(path, "w")`` would give it (those of an
    existing file, else the default mode under the process umask).

    An :class:`OSError` names ``path`` (not the temporary file); a directory at
    ``path`` is an :class:`IsADirectoryError` that says so, and nothing is
    written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.is_dir():
        raise IsADirectoryError(errno.EISDIR, "expected a file (or nothing) to write there, "
                                "found a directory; remove or rename it", str(path))
    mode = "wb" if isinstance(data, (bytes, bytearray)) else "w"
    try:
        perm = path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        perm = 0o666 & ~umask
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as e:
        # the temporary file could not be made (a folder that takes no files):
        # the target is what the caller knows
        if e.errno is None:
            raise
        raise type(e)(e.errno, e.strerror, str(path)) from e
    try:
        with os.fdopen(fd, mode, **({} if mode == "wb" else {"encoding": "utf-8"})) as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, perm)
        os.replace(tmp, path)
    except BaseException as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(e, OSError) and e.filename == tmp and e.errno is not None:
            # the target is what the caller knows, not the temporary file
            what = ("found a directory, expected a file" if e.errno == errno.EISDIR
                    else e.strerror)
            raise type(e)(e.errno, what, str(path)) from e
        raise
    return path


def _json_default(o):
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (set, frozenset)):
        return sorted(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def dumps(obj) -> str:
    return json.dumps(obj, indent=1, default=_json_default, allow_nan=False)


#: Deepest nesting of arrays and objects accepted in a JSON input file.  The
#: deepest real document (a model file's expressions are strings) nests about 6
#: levels; the bound keeps hostile files from reaching the interpreter's
#: recursion limit in the parser or in code that walks the document.
MAX_JSON_DEPTH = 100

#: Longest integer literal read from a JSON input file, in digits.  A float
#: holds at most 309 integer digits, and the checks of each value refuse a
#: longer one as too large; beyond this many digits the parser refuses it by its
#: size (Python refuses to convert more than 4300 digits at all).
MAX_INT_DIGITS = 4000


def parse_json_text(text, what: str = "input"):
    """Parse JSON text with the limits of :func:`load_json`.

    Raises :class:`~cspace.errors.FileFormatError` for invalid JSON, NaN or
    Infinity, a key repeated in one object, an integer literal of more than
    ``MAX_INT_DIGITS`` digits, and nesting deeper than ``MAX_JSON_DEPTH``;
    ``what`` names the source in messages.
    """
    try:
        doc = json.loads(text, parse_constant=_reject_constant, parse_int=_parse_int,
                         object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as e:
        raise FileFormatError(f"{what} is not valid JSON: {e.msg} at line {e.lineno} "
                              f"column {e.colno}") from None
    except RecursionError:
        raise FileFormatError(f"{what}: arrays and objects may nest at most "
                              f"{MAX_JSON_DEPTH} levels deep, got far deeper nesting "
                              f"(beyond the parser's limit)") from None
    except FileFormatError as e:
        raise FileFormatError(f"{what}: {e}") from None
    depth = json_depth(doc, MAX_JSON_DEPTH)
    if depth > MAX_JSON_DEPTH:
        raise FileFormatError(f"{what}: arrays and objects may nest at most "
                              f"{MAX_JSON_DEPTH} levels deep, got more than {MAX_JSON_DEPTH}")
    return doc


def _unique_keys(pairs) -> dict:
    """An object whose keys are all different (JSON lets a key repeat, and the
    last one would silently win: a typo or a pasted line that changes a value
    unseen)."""
    out = dict(pairs)
    if len(out) < len(pairs):
        seen, dup = set(), []
        for k, _ in pairs:
            if k in seen and k not in dup:
                dup.append(k)
            seen.add(k)
        raise FileFormatError(f"the key{'s' if len(dup) > 1 else ''} "
                              f"{', '.join(repr(k) for k in dup)} appear"
                              f"{'' if len(dup) > 1 else 's'} more than once in one object "
                              f"(keys {list(out)[:8]}); JSON would keep the last value "
                              f"silently: give each key once")
    return out


def json_depth(doc, limit: int) -> int:
    """Nesting depth of a parsed JSON value (a scalar is 0), counted without
    recursion; stops once it exceeds ``limit``."""
    best = 0
    stack = [(doc, 0)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, (list, dict)):
            d += 1
            if d > best:
                best = d
                if best > limit:
                    return best
            stack.extend((x, d) for x in (v.values() if isinstance(v, dict) else v))
    return best


def load_json(path) -> dict:
    """Read a JSON file; errors become FileFormatError naming the file.

    The limits of :func:`parse_json_text` apply (nesting, integer length,
    non-finite constants).
    """
    p = Path(path)
    try:
        # utf-8-sig: a file saved with a byte-order mark (Windows Notepad) reads too
        text = p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise FileFormatError(f"no such file: {p}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise FileFormatError(f"cannot read {p}: {e}") from None
    return parse_json_text(text, str(p))


def _reject_constant(name):
    raise FileFormatError(f"non-finite number {name} is not allowed in model files")


def _parse_int(text):
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise FileFormatError(f"expected a number that fits a float (at most "
                              f"{MAX_INT_DIGITS} digits), got an integer literal of "
                              f"{digits} digits")
    return int(text)


# ------------------------------------------------------------------- pair <-> dict

def pair_to_dict(obj) -> dict:
    """JSON-ready dict of a Pair or Assembly."""
    if isinstance(obj, Assembly):
        return {"format": ASSEMBLY_FORMAT, "version": 1, "name": obj.name,
                "pairs": [pair_to_dict(p) for p in obj.pairs]}
    return obj.to_dict()


def key_suggestions(unknown, allowed, missing=()) -> str:
    """`` (did you mean 'tol'?)`` for unknown keys of a file's object that look
    like a misspelt allowed key (a missing required one first), else ``""``."""
    import difflib
    allowed = sorted(allowed)
    pairs = []
    for k in sorted(unknown):
        low = k.lower()
        near = difflib.get_close_matches(k, allowed, n=1, cutoff=0.6)
        near = near or [a for a in missing if low.startswith(a.lower())
                        or a.lower().startswith(low)]
        near = near or difflib.get_close_matches(k, list(missing), n=1, cutoff=0.4)
        near = near or [a for a in allowed if len(a) > 2 and len(low) > 2
                        and (low.startswith(a.lower()) or a.lower().startswith(low))]
        if near:
            pairs.append((k, near[0]))
    if not pairs:
        return ""
    if len(pairs) == 1 and len(unknown) == 1:
        return f" (did you mean {pairs[0][1]!r}?)"
    return " (did you mean " + ", ".join(f"{m!r} for {k!r}" for k, m in pairs) + "?)"


def missing_key_message(key, d, allowed, what: str = "") -> str:
    """``missing required key 'tol'``, with ``what`` it holds, and, when ``d``
    has keys that are not ``allowed``, those keys, the closest allowed key and
    the allowed ones: a misspelt key is named rather than silently dropped."""
    msg = f"missing required key {key!r}" + (f" ({what})" if what else "")
    extra = sorted(set(d) - set(allowed))
    if extra:
        missing = [k for k in allowed if k not in d]
        msg += (f"; found unknown key(s) {extra}"
                f"{key_suggestions(extra, allowed, [key] + [k for k in missing if k != key])}"
                f"; allowed keys: {sorted(allowed)}")
    return msg


def _get(d, key, path, types, what, allowed=None):
    if not isinstance(d, dict):
        raise FileFormatError(f"expected an object, got {type(d).__name__}", path=path)
    if key not in d:
        msg = (f"missing required key {key!r} ({what})" if allowed is None
               else missing_key_message(key, d, allowed, what))
        raise FileFormatError(msg, path=path)
    v = d[key]
    if types is not None and (not isinstance(v, types) or isinstance(v, bool) and bool not in
                              (types if isinstance(types, tuple) else (types,))):
        tn = types.__name__ if isinstance(types, type) else "/".join(t.__name__ for t in types)
        raise FileFormatError(f"{key!r} must be {tn} ({what}), got {type(v).__name__} {v!r}",
                              path=f"{path}.{key}" if path else key)
    return v


def json_float(v) -> float:
    """A JSON number as a float; an integer too large for a float is infinite."""
    try:
        return float(v)
    except OverflowError:
        return math.inf


def number_text(v) -> str:
    """A number for a message: a huge integer by its size, not its 400 digits."""
    t = repr(v)
    return t if len(t) <= 40 else f"{t[:12]}... ({len(t)} digits)"


def _num(v, path):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise FileFormatError(f"expected a number, got {type(v).__name__} {v!r}", path=path)
    f = json_float(v)
    if not math.isfinite(f):
        raise FileFormatError(f"expected a finite number, got {number_text(v)}", path=path)
    return f


def _point(v, path):
    if not isinstance(v, list) or len(v) != 2:
        raise FileFormatError(f"expected a point [x, y], got {v!r}", path=path)
    return (_num(v[0], f"{path}[0]"), _num(v[1], f"{path}[1]"))


def _geom(fn, path, *args, **kw):
    try:
        return fn(*args, **kw)
    except DegenerateGeometryError as e:
        raise type(e)(f"{path}: {e}", where=path) from None
    except CSpaceError as e:
        raise FileFormatError(str(e), path=path) from None


def _known_keys(d, allowed, what, path):
    """A FileFormatError naming the keys of ``d`` that a ``what`` does not have."""
    extra = set(d) - set(allowed)
    if extra:
        raise FileFormatError(f"unknown keys {sorted(extra)} in a {what}"
                              f"{key_suggestions(extra, allowed)}; allowed: "
                              f"{sorted(allowed)}", path=path or what)


def _name(d, key, default, path):
    v = d.get(key, default)
    if not isinstance(v, str) or not v.strip():
        raise FileFormatError(f"{key!r} must be a non-empty string, got {v!r}",
                              path=f"{path}.{key}" if path else key)
    return v


_SEGMENT_KEYS = {"line": {"type", "start", "end", "name"},
                 "arc": {"type", "center", "radius", "start_angle", "end_angle", "ccw", "name"}}


def _segment(d, path):
    allowed = _SEGMENT_KEYS
    t = _get(d, "type", path, str, "segment type 'line' or 'arc'",
             allowed=allowed["line"] | allowed["arc"])
    name = d.get("name", "")
    if not isinstance(name, str):
        raise FileFormatError("segment name must be a string", path=f"{path}.name")
    if t not in allowed:
        raise FileFormatError(f"segment type must be 'line' or 'arc', got {t!r}", path=f"{path}.type")
    extra = set(d) - allowed[t]
    if extra:
        raise FileFormatError(f"unknown keys {sorted(extra)} for a {t}"
                              f"{key_suggestions(extra, allowed[t], sorted(allowed[t] - set(d)))}"
                              f"; allowed: {sorted(allowed[t])}", path=path)
    if t == "line":
        s = _point(_get(d, "start", path, list, "start point"), f"{path}.start")
        e = _point(_get(d, "end", path, list, "end point"), f"{path}.end")
        return _geom(Line, path, s, e, name)
    c = _point(_get(d, "center", path, list, "centre"), f"{path}.center")
    r = _num(_get(d, "radius", path, None, "radius"), f"{path}.radius")
    a0 = _num(_get(d, "start_angle", path, None, "start angle in rad"), f"{path}.start_angle")
    a1 = _num(_get(d, "end_angle", path, None, "end angle in rad"), f"{path}.end_angle")
    ccw = d.get("ccw", True)
    if not isinstance(ccw, bool):
        raise FileFormatError(f"'ccw' must be true or false, got {ccw!r}", path=f"{path}.ccw")
    return _geom(Arc, f"{path}", c, r, a0, a1, ccw, name)


_AXIS_KEYS = {"rotation": ("type", "center"), "translation": ("type", "direction", "origin")}


def _axis(d, path):
    t = _get(d, "type", path, str, "'rotation' or 'translation'",
             allowed=set(_AXIS_KEYS["rotation"]) | set(_AXIS_KEYS["translation"]))
    if t in _AXIS_KEYS:
        _known_keys(d, _AXIS_KEYS[t], f"{t} axis", path)
    if t == "rotation":
        return _geom(Rotation, path, _point(_get(d, "center", path, list, "rotation centre"),
                                            f"{path}.center"))
    if t == "translation":
        dirn = _point(_get(d, "direction", path, list, "unit direction"), f"{path}.direction")
        org = _point(d.get("origin", [0.0, 0.0]), f"{path}.origin")
        return _geom(Translation, path, dirn, org)
    raise FileFormatError(f"axis type must be 'rotation' or 'translation', got {t!r}",
                          path=f"{path}.type")


def _part(d, path):
    name = _get(d, "name", path, str, "part name", allowed=("name", "axis", "loops"))
    _known_keys(d, ("name", "axis", "loops"), "part", path)
    ax = _axis(_get(d, "axis", path, dict, "motion axis"), f"{path}.axis")
    loops_raw = _get(d, "loops", path, list, "list of closed loops")
    loops = []
    for i, lr in enumerate(loops_raw):
        lp = f"{path}.loops[{i}]"
        if not isinstance(lr, list) or not lr:
            raise FileFormatError("a loop must be a non-empty list of segments", path=lp)
        segs = tuple(_segment(s, f"{lp}[{j}]") for j, s in enumerate(lr))
        loops.append(_geom(Loop, lp, segs))
    return _geom(Part, path, name, tuple(loops), ax)


#: Optional top-level keys of a pair or assembly file that state its operating
#: point, as in a model file (``"drive": [q1_start, q1_end]``, ``"q2_start":
#: [one per pair]``, ``"window": [q1_lo, q1_hi, q2_lo, q2_hi]``,
#: ``"deviation": d``): a Pair does not hold them; ``cspace-tol analyze`` reads
#: and checks them (:func:`mechanisms.analysis.pair_file_motion`).  A pair's
#: ``"closure"`` is not among them: it belongs to the pair (``Pair.bias``), is
#: read with its parts and written by ``Pair.to_dict``.
MOTION_KEYS = ("drive", "q2_start", "window", "deviation")


def pair_from_dict(d, path: str = ""):
    """A Pair (or Assembly) from its JSON dict; validates everything."""
    fmt = _get(d, "format", path, str, f"'{PAIR_FORMAT}' or '{ASSEMBLY_FORMAT}'")
    ver = _get(d, "version", path, int, "format version")
    if ver != 1:
        raise FileFormatError(f"unsupported version {ver}; this library reads version 1",
                              path=f"{path}.version" if path else "version")
    if fmt == ASSEMBLY_FORMAT:
        _known_keys(d, ("format", "version", "name", "pairs") + MOTION_KEYS, "assembly", path)
        prs = _get(d, "pairs", path, list, "list of pairs")
        pairs = tuple(pair_from_dict(p, f"{path}pairs[{i}]") for i, p in enumerate(prs))
        units = sorted({p.units for p in pairs})
        if len(units) > 1:
            raise FileFormatError(f"the pairs of an assembly share one length unit, got "
                                  f"{units}", path=f"{path}pairs" if path else "pairs")
        names = [p.name for p in pairs]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise FileFormatError(f"pair names in an assembly must differ, got {dup} more "
                                  f"than once", path=f"{path}pairs" if path else "pairs")
        return _geom(Assembly, path or "assembly", pairs, _name(d, "name", "assembly", path))
    if fmt != PAIR_FORMAT:
        raise FileFormatError(f"format must be {PAIR_FORMAT!r} or {ASSEMBLY_FORMAT!r}, got {fmt!r}",
                              path=f"{path}.format" if path else "format")
    _known_keys(d, ("format", "version", "name", "units", "parts", "closure")
                + (MOTION_KEYS if not path else ()), "pair", path)
    units = _get(d, "units", path, str, "length unit, e.g. 'mm'")
    check_units(units, f"{path}.units" if path else "units")
    name = _name(d, "name", "pair", path)
    parts = _get(d, "parts", path, list, "[driver, follower]")
    pre = f"{path}." if path else ""
    if len(parts) != 2:
        raise FileFormatError(f"a pair has exactly 2 parts (driver, follower), got {len(parts)}",
                              path=f"{pre}parts")
    drv = _part(parts[0], f"{pre}parts[0]")
    fol = _part(parts[1], f"{pre}parts[1]")
    if drv.name == fol.name:
        raise FileFormatError(f"the driver and the follower need different names, both are "
                              f"{drv.name!r}", path=f"{pre}parts")
    bias = closure_from_dict(d["closure"], f"{pre}closure") if "closure" in d else 0
    return Pair(drv, fol, units, name, bias)


def closure_from_dict(v, path: str = "closure") -> int:
    """The follower bias (:attr:`cspace.geometry.Pair.bias`) of a ``"closure"``
    entry: ``{"bias": -1}`` (held toward decreasing q2) or ``{"bias": 1}``
    (toward increasing q2) for a force-closed (spring-loaded) follower, ``{"bias":
    0}`` for form closure (the default when the entry is absent).  A bad entry
    raises :class:`~cspace.errors.FileFormatError` naming ``path``."""
    if not isinstance(v, dict):
        raise FileFormatError(f"expected an object {{\"bias\": -1, 0 or 1}}, got "
                              f"{type(v).__name__} {v!r}", path=path)
    _known_keys(v, ("bias",), "closure", path)
    if "bias" not in v:
        raise FileFormatError("missing required key 'bias' (-1: the follower is held toward "
                              "decreasing q2, +1: toward increasing q2, 0: form closure)",
                              path=path)
    b = v["bias"]
    if isinstance(b, bool) or not isinstance(b, (int, float)) or b not in BIASES:
        raise FileFormatError(f"expected -1 (follower held toward decreasing q2), 0 (form "
                              f"closure: moved only when pushed) or 1 (held toward "
                              f"increasing q2), got {type(b).__name__} "
                              f"{number_text(b) if isinstance(b, (int, float)) else repr(b)}",
                              path=f"{path}.bias")
    return int(b)


def model_motion(model, d=None) -> dict:
    """The operating point a parametric model states (:data:`MOTION_KEYS`:
    its drive, follower starts and window, and ``d`` or its deviation
    threshold), as :func:`save_pair` writes it: a pair file written from a
    model is analysed over the same window and motion (empty for an object
    that states none)."""
    out = {}
    for k in ("drive", "q2_start", "window"):
        v = getattr(model, k, None)
        if v is not None:
            out[k] = [float(x) for x in v]
    dev = getattr(model, "deviation", None) if d is None else d
    if dev is not None:
        out["deviation"] = float(dev)
    return out


def save_pair(obj, path, motion=None) -> Path:
    """Write a Pair or Assembly as JSON (atomically), with the operating point
    ``motion`` (a mapping of :data:`MOTION_KEYS`) when given."""
    doc = pair_to_dict(obj)
    for k, v in (motion or {}).items():
        if k not in MOTION_KEYS:
            from .errors import InputError
            raise InputError(f"motion keys must be among {list(MOTION_KEYS)}, got {k!r}",
                             name="motion", value=k)
        doc[k] = list(v) if isinstance(v, (tuple, list)) else v
    return atomic_write(path, dumps(doc))


def load_pair(path):
    """Read a Pair or Assembly JSON file."""
    return pair_from_dict(load_json(path))


# ------------------------------------------------------------------- C-space JSON

def _poly_dict(g):
    out = []
    for p in getattr(g, "geoms", [g]):
        if p.geom_type != "Polygon" or p.is_empty:
            continue
        out.append({"exterior": np.round(np.asarray(p.exterior.coords), 12).tolist(),
                    "holes": [np.round(np.asarray(h.coords), 12).tolist() for h in p.interiors]})
    return out


def cspace_to_dict(cs, *, boundary_only: bool = False) -> dict:
    """C-space JSON dict: faces as polygons flagged free/blocked, curves as polylines.

    Coordinates are (q1, q2): rad for rotations, model units for slides.
    """
    pair = cs.pair
    coords = []
    for i, part in enumerate(pair.parts):
        rot = isinstance(part.axis, Rotation)
        coords.append({"name": f"q{i + 1}", "part": part.name,
                       "kind": "rotation" if rot else "translation",
                       "unit": "rad" if rot else pair.units,
                       "periodic": bool(cs.periodic[i])})
    faces = []
    for fid, g in sorted(cs.face_polygons().items()):
        faces.append({"id": int(fid), "free": bool(cs.faces[fid]), "polygons": _poly_dict(g)})
    bset = {b.curve for b in cs.boundary}
    curves = []
    for i, c in enumerate(cs.curves):
        if boundary_only and i not in bset:
            continue
        from .metric import split_wrapped
        pl = c.polyline(cs.accuracy)
        curves.append({"index": i, "label": c.label, "kind": c.kind, "branch": c.branch,
                       "features": [list(f) for f in c.features], "depends": sorted(c.depends),
                       "q1_range": [c.q1_start, c.q1_end], "boundary": i in bset,
                       "polylines": [np.round(s, 12).tolist()
                                     for s in split_wrapped(pl, cs.window[2], cs.periodic[1])]})
    vertical = [{"label": v.label, "kind": v.kind, "q1": v.q1_value, "q2_range": [v.q2_lo, v.q2_hi],
                 "depends": sorted(v.depends)} for v in cs.vertical]
    boundary = [{"curve": b.curve, "label": b.label, "branch": b.branch,
                 "q1_range": [b.q1_start, b.q1_end], "free_above": b.free_above,
                 "free_face": b.free_face, "blocked_face": b.blocked_face,
                 "nodes": [b.u, b.v]} for b in cs.boundary]
    nodes = [{"id": int(n), "q": list(d["q"])} for n, d in cs.graph.nodes(data=True)]
    return {"format": CSPACE_FORMAT, "version": 1, "pair": pair.name, "units": pair.units,
            "char_length": pair.char_length, "coordinates": coords, "window": list(cs.window),
            "accuracy": cs.accuracy.to_dict(), "stats": dict(cs.stats), "faces": faces,
            "curves": curves, "vertical_curves": vertical, "boundary": boundary,
            "nodes": nodes}


def save_cspace(cs, path, **kw) -> Path:
    return atomic_write(path, dumps(cspace_to_dict(cs, **kw)))
