"""Parametric model files (``"format": "cspace-model"``): a user's own mechanism as
JSON, with named parameters, tolerances and geometry written as expressions.

The full format is documented in ``docs/model_file.md``; in short::

    {"format": "cspace-model", "version": 1, "name": "flat_follower_cam",
     "units": "mm",
     "parameters": [{"name": "rb", "nominal": 20, "tol": 0.02,
                     "description": "base circle radius"}, ...],
     "let": [{"name": "t", "value": "asin((rb - rn) / d)"}],
     "window": [0, "2*pi", -3, 20], "drive": [0, "2*pi"], "q2_start": [12.5],
     "pairs": [{"name": "cam", "closure": {"bias": -1}, "parts": [
        {"name": "cam", "axis": {"type": "rotation", "center": ["cam_x", "cam_y"]},
         "loops": [[{"type": "arc", "center": ["cam_x", "cam_y"], "radius": "rb",
                     "start_angle": 0, "end_angle": "2*pi", "ccw": true}]]},
        {"name": "follower",
         "axis": {"type": "translation", "direction": [0, 1], "origin": [0, 0]},
         "loops": [{"polyline": [["-w", "face"], ["w", "face"], ...],
                    "bulges": [0, 0, 0, 0]}]}]}]}

A pair's optional ``"closure": {"bias": -1}`` (or ``1``) makes its follower
spring-loaded: held against the driver toward decreasing (increasing) q2
(:attr:`cspace.geometry.Pair.bias`); without it the follower moves only when
pushed.

Every number of the geometry may be a JSON number or an expression string over the
parameter and ``let`` names.  Expressions are parsed with :mod:`ast` and checked
against a whitelist (numbers, names, ``+ - * / **``, unary minus and plus,
parentheses, the constants ``pi`` and ``e`` and the functions in
:data:`FUNCTIONS`); anything else is rejected with
:class:`~cspace.errors.ExpressionError` naming the JSON path and the offending
token.  Loading never executes code from the file.

A file may instead name a built-in model and give its parameter values, e.g. the
result of a synthesis of one (``synthesize`` writes such a ``model.json``)::

    {"format": "cspace-model", "version": 1, "builtin": "geneva", "name": "geneva",
     "units": "cm", "parameters": [{"name": "drv_x", "nominal": 0.0021, "tol": 0.012},
     ...]}

Its geometry is the library's built-in code (exactly, not an approximation);
every parameter of the built-in model must be listed once.

Functions
---------
model_from_dict(d) -> Model
load_model(path) -> Model
model_to_dict(model) -> dict        (models from files and built-in models)
save_model(model, path)             (atomic)

The expression language is :mod:`mechanisms.expressions`;
:func:`mechanisms.dimensions.parametric_model` makes every dimension of a fixed
pair a parameter (``import-dxf --tol``).
"""

from __future__ import annotations

import json
import keyword
import math
import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from cspace.errors import (CSpaceError, DegenerateGeometryError, ExpressionError,
                           FileFormatError, InputError, InvalidModelError, ParameterError)
from cspace.geom2d import TWO_PI, degrees_hint
from cspace.geometry import Arc, Assembly, Line, Loop, Pair, Part, Rotation, Translation
from cspace.io import (UnitWarning, atomic_write, canonical_unit, check_units,
                       closure_from_dict, dumps, json_float, key_suggestions, load_json,
                       missing_key_message, number_text)

from .expressions import CONSTANTS, FUNCTIONS, Expr, compile_expression, evaluate
from .models.base import Model, Parameter

__all__ = ["MODEL_FORMAT", "FUNCTIONS", "CONSTANTS", "ModelFileBuilder", "model_from_dict",
           "load_model", "model_to_dict", "save_model", "compile_expression", "stated_units"]


def __getattr__(name):
    # parametric_model and PARAM_MODES live in mechanisms.dimensions (which
    # imports this module); still importable from here
    if name in ("parametric_model", "PARAM_MODES"):
        from . import dimensions
        return getattr(dimensions, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

MODEL_FORMAT = "cspace-model"

#: Longest expression string accepted.  Bounds the parser's work and recursion
#: depth on hostile input; real dimensions are far shorter.
# ----------------------------------------------------------------------- structure

def _err(msg, path):
    return FileFormatError(msg, path=path)


def _join(path, key):
    return f"{path}.{key}" if path else key


def _keys(d, path, required, optional=()):
    """``d`` is an object with every ``required`` key and no key outside
    ``required`` and ``optional``; a missing key's message also names the
    unknown keys found (a misspelling) and the closest allowed key."""
    if not isinstance(d, dict):
        raise _err(f"expected an object, got {type(d).__name__}", path)
    allowed = set(required) | set(optional)
    for k in required:
        if k not in d:
            raise _err(missing_key_message(k, d, allowed), path)
    extra = set(d) - allowed
    if extra:
        missing = sorted(k for k in optional if k not in d)
        raise _err(f"unknown key(s) {sorted(extra)}{key_suggestions(extra, allowed, missing)}"
                   f"; allowed: {sorted(allowed)}", path)


def _str(v, path, what, *, empty=False):
    if not isinstance(v, str) or (not empty and not v):
        raise _err(f"{what} must be a {'' if empty else 'non-empty '}string, got {v!r}", path)
    return v


def _finite(v, path):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise _err(f"expected a number, got {type(v).__name__} {v!r}", path)
    if not math.isfinite(json_float(v)):
        raise _err(f"expected a finite number, got {number_text(v)}", path)
    return float(v)


def _slot(v, path, exprs):
    """A number or an expression string -> float or Expr (recorded in ``exprs``)."""
    if isinstance(v, str):
        x = compile_expression(v, path)
        exprs.append(x)
        return x
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ExpressionError(f"expected a number or an expression string, got "
                              f"{type(v).__name__} {v!r}", path=path, token=repr(v))
    if not math.isfinite(json_float(v)):
        raise ExpressionError(f"expected a finite number, got {number_text(v)}", path=path,
                              token=number_text(v))
    return float(v)


def _pt(v, path, exprs):
    if not isinstance(v, list) or len(v) != 2:
        raise _err(f"expected a point [x, y], got {v!r}", path)
    return (_slot(v[0], f"{path}[0]", exprs), _slot(v[1], f"{path}[1]", exprs))


def _check_identifier(name, path, what):
    _str(name, path, what)
    if not name.isidentifier() or keyword.iskeyword(name):
        raise _err(f"{what} {name!r} must be an identifier (letters, digits, _; not a "
                   "Python keyword)", path)
    if name in CONSTANTS or name in FUNCTIONS:
        raise _err(f"{what} {name!r} clashes with a built-in constant or function name "
                   f"({', '.join(CONSTANTS)}, {', '.join(FUNCTIONS)})", path)
    return name


@dataclass(frozen=True)
class SegmentSpec:
    kind: str          # "line" or "arc"
    values: tuple      # line: (sx, sy, ex, ey); arc: (cx, cy, r, a0, a1)
    ccw: bool
    name: str
    path: str


@dataclass(frozen=True)
class LoopSpec:
    path: str
    segments: tuple = ()       # SegmentSpec, for the segment-list form
    points: tuple = ()         # ((x, y), ...), for the polyline form
    bulges: tuple = ()
    names: tuple | None = None

    @property
    def is_polyline(self) -> bool:
        return bool(self.points)


@dataclass(frozen=True)
class PartSpec:
    name: str
    axis_kind: str
    axis: tuple        # rotation: (cx, cy); translation: (dx, dy, ox, oy)
    loops: tuple
    path: str


@dataclass(frozen=True)
class PairSpec:
    name: str
    parts: tuple
    path: str
    bias: int = 0      # the follower's closure (cspace.geometry.Pair.bias)


def _segment(d, path, exprs) -> SegmentSpec:
    if not isinstance(d, dict):
        raise _err(f"expected a segment object, got {type(d).__name__}", path)
    t = d.get("type")
    if t == "line":
        _keys(d, path, ("type", "start", "end"), ("name",))
        vals = _pt(d["start"], _join(path, "start"), exprs) + _pt(d["end"], _join(path, "end"),
                                                                   exprs)
        ccw = True
    elif t == "arc":
        _keys(d, path, ("type", "center", "radius", "start_angle", "end_angle"), ("ccw", "name"))
        vals = _pt(d["center"], _join(path, "center"), exprs) + tuple(
            _slot(d[k], _join(path, k), exprs) for k in ("radius", "start_angle", "end_angle"))
        ccw = d.get("ccw", True)
        if not isinstance(ccw, bool):
            raise _err(f"'ccw' must be true or false, got {ccw!r}", _join(path, "ccw"))
    else:
        if "type" not in d:
            _keys(d, path, ("type",), ("start", "end", "center", "radius", "start_angle",
                                       "end_angle", "ccw", "name"))
        raise _err(f"segment type must be 'line' or 'arc', got {t!r}", _join(path, "type"))
    name = _str(d.get("name", ""), _join(path, "name"), "segment name", empty=True)
    return SegmentSpec(t, vals, ccw, name, path)


def _loop(d, path, exprs) -> LoopSpec:
    if isinstance(d, list):
        if not d:
            raise _err("a loop must be a non-empty list of segments", path)
        return LoopSpec(path, segments=tuple(_segment(s, f"{path}[{j}]", exprs)
                                             for j, s in enumerate(d)))
    if isinstance(d, dict):
        _keys(d, path, ("polyline",), ("bulges", "names"))
        pts = d["polyline"]
        pp = _join(path, "polyline")
        if not isinstance(pts, list) or len(pts) < 2:
            raise _err(f"a polyline loop needs a list of at least 2 points, got {pts!r}", pp)
        points = tuple(_pt(p, f"{pp}[{i}]", exprs) for i, p in enumerate(pts))
        n = len(points)
        bl = d.get("bulges", [0] * n)
        bp = _join(path, "bulges")
        if not isinstance(bl, list) or len(bl) != n:
            raise _err(f"need one bulge per edge ({n}, the last edge closes the loop), got "
                       f"{bl!r}", bp)
        bulges = tuple(_slot(b, f"{bp}[{i}]", exprs) for i, b in enumerate(bl))
        names = None
        if "names" in d:
            nm = d["names"]
            np_ = _join(path, "names")
            if not isinstance(nm, list) or len(nm) != n:
                raise _err(f"need one name per edge ({n}), got {nm!r}", np_)
            names = tuple(_str(s, f"{np_}[{i}]", "edge name", empty=True)
                          for i, s in enumerate(nm))
        return LoopSpec(path, points=points, bulges=bulges, names=names)
    raise _err("a loop must be a list of segments or a {\"polyline\": ...} object, got "
               f"{type(d).__name__}", path)


def _part(d, path, exprs) -> PartSpec:
    _keys(d, path, ("name", "axis", "loops"))
    name = _str(d["name"], _join(path, "name"), "part name")
    ap = _join(path, "axis")
    ax = d["axis"]
    if not isinstance(ax, dict):
        raise _err(f"expected an axis object, got {type(ax).__name__}", ap)
    if ax.get("type") == "rotation":
        _keys(ax, ap, ("type", "center"))
        kind, vals = "rotation", _pt(ax["center"], _join(ap, "center"), exprs)
    elif ax.get("type") == "translation":
        _keys(ax, ap, ("type", "direction"), ("origin",))
        kind = "translation"
        vals = (_pt(ax["direction"], _join(ap, "direction"), exprs)
                + _pt(ax.get("origin", [0, 0]), _join(ap, "origin"), exprs))
    else:
        if "type" not in ax:
            _keys(ax, ap, ("type",), ("center", "direction", "origin"))
        raise _err(f"axis type must be 'rotation' or 'translation', got {ax.get('type')!r}",
                   _join(ap, "type"))
    lp = _join(path, "loops")
    loops = d["loops"]
    if not isinstance(loops, list) or not loops:
        raise _err("'loops' must be a non-empty list of closed loops", lp)
    specs = tuple(_loop(x, f"{lp}[{i}]", exprs) for i, x in enumerate(loops))
    _unique_segment_names(name, specs)
    return PartSpec(name, kind, vals, specs, path)


def _unique_segment_names(part: str, loops) -> None:
    """Refuse two segments of one part with the same (non-empty) name: the
    names label the part's contacts in every report and plot (a vertex is
    named by its two segments, ``lock1^slot1.right``), so a repeated one
    makes two contacts read alike."""
    seen: dict = {}
    for lp in loops:
        if lp.is_polyline:
            named = [(n, f"{lp.path}.names[{i}]") for i, n in enumerate(lp.names or ())]
        else:
            named = [(s.name, _join(s.path, "name")) for s in lp.segments]
        for nm, where in named:
            if not nm:
                continue
            if nm in seen:
                raise _err(f"segment name {nm!r} is used twice in part {part!r} (also at "
                           f"{seen[nm]}); segment names label the part's contacts in reports "
                           "and must be unique within a part: rename one, or leave it empty "
                           "for an automatic name", where)
            seen[nm] = where


def _pair(d, path, default_name, exprs) -> PairSpec:
    _keys(d, path, ("parts",), ("name", "closure"))
    name = _str(d.get("name", default_name), _join(path, "name"), "pair name")
    parts = d["parts"]
    if not isinstance(parts, list) or len(parts) != 2:
        raise _err(f"a pair has exactly 2 parts (driver, follower), got "
                   f"{len(parts) if isinstance(parts, list) else parts!r}", _join(path, "parts"))
    specs = tuple(_part(p, f"{_join(path, 'parts')}[{i}]", exprs) for i, p in enumerate(parts))
    if specs[0].name == specs[1].name:
        raise _err(f"duplicate part name {specs[0].name!r}; the two parts of a pair need "
                   "distinct names", _join(path, "parts[1].name"))
    bias = closure_from_dict(d["closure"], _join(path, "closure")) if "closure" in d else 0
    return PairSpec(name, specs, path, bias)


def _const_list(v, path, n=None, what="list"):
    """A list of numbers or constant-only expressions (no parameter names)."""
    if not isinstance(v, list):
        raise _err(f"expected {what} as a JSON list, got {type(v).__name__} {v!r}", path)
    if n is not None and len(v) != n:
        raise _err(f"expected {what}: a list of {n}, got a list of {len(v)}: {v!r}", path)
    out = []
    for i, x in enumerate(v):
        ex = []
        s = _slot(x, f"{path}[{i}]", ex)
        if ex:
            bad = sorted(ex[0].names - set(CONSTANTS))
            if bad:
                raise ExpressionError(f"{path} is fixed for the model and may use only the "
                                      f"constants pi and e, not {bad[0]!r}",
                                      path=f"{path}[{i}]", token=bad[0])
            s = evaluate(s, CONSTANTS)
        out.append(s)
    return tuple(out)


# ----------------------------------------------------------------------- builder

def _geom(fn, path, *args):
    try:
        return fn(*args)
    except DegenerateGeometryError as e:
        raise type(e)(f"{path}: {e}", where=path) from None
    except ExpressionError:
        raise
    except CSpaceError as e:
        raise InvalidModelError(f"{path}: {e}") from None


@dataclass(frozen=True)
class ModelFileBuilder:
    """The builder of a model read from a file: ``builder(values) -> Pair | Assembly``.

    A module-level frozen value holding the compiled file, so that models pickle
    for process pools.  ``document`` is the file's JSON text (for
    :func:`model_to_dict`).
    """

    units: str
    name: str
    lets: tuple = field(repr=False)       # ((name, slot), ...) in evaluation order
    pairs: tuple = field(repr=False)      # PairSpec
    document: str = field(repr=False)

    def __call__(self, values: dict):
        env = dict(CONSTANTS)
        env.update(values)
        for name, x in self.lets:
            env[name] = evaluate(x, env)
        try:
            built = tuple(self._pair(p, env) for p in self.pairs)
        except KeyError as e:
            raise ParameterError(f"model {self.name!r}: no value for parameter {e.args[0]!r}") \
                from None
        if len(built) == 1:
            return built[0]
        return _geom(Assembly, "pairs", built, self.name)

    def _pair(self, p: PairSpec, env):
        return Pair(self._part(p.parts[0], env), self._part(p.parts[1], env), self.units,
                    p.name, p.bias)

    def _part(self, p: PartSpec, env):
        vals = [evaluate(x, env) for x in p.axis]
        ap = _join(p.path, "axis")
        if p.axis_kind == "rotation":
            axis = _geom(Rotation, ap, tuple(vals))
        else:
            axis = _geom(Translation, ap, tuple(vals[:2]), tuple(vals[2:]))
        loops = tuple(self._loop(lp, env) for lp in p.loops)
        return _geom(Part, p.path, p.name, loops, axis)

    def _loop(self, lp: LoopSpec, env):
        if lp.is_polyline:
            pts = [(evaluate(x, env), evaluate(y, env)) for x, y in lp.points]
            bl = [evaluate(b, env) for b in lp.bulges]
            return _geom(Loop.from_bulges, lp.path, pts, bl, lp.names)
        segs = []
        for s in lp.segments:
            v = [evaluate(x, env) for x in s.values]
            if s.kind == "line":
                segs.append(_geom(Line, s.path, (v[0], v[1]), (v[2], v[3]), s.name))
            else:
                _check_turn(v[3], v[4], s.path)
                segs.append(_geom(Arc, s.path, (v[0], v[1]), v[2], v[3], v[4], s.ccw, s.name))
        return _geom(Loop, lp.path, tuple(segs))


#: How far (relative) an arc's angles may differ by more than a turn: rounding
#: of ``start + 2*pi`` only.
_TURN_SLACK = 1e-9


def _check_turn(a0: float, a1: float, path: str) -> None:
    """Refuse an arc whose stated angles lie more than a turn apart: its sweep
    is in (0, 2 pi] (the angles are read modulo a turn), so a larger
    difference is a slip, most often angles written in degrees."""
    diff = abs(a1 - a0)
    if math.isfinite(diff) and diff > TWO_PI * (1 + _TURN_SLACK):
        raise InvalidModelError(
            f"{path}: start_angle {a0:.6g} and end_angle {a1:.6g} rad lie {diff:.6g} rad apart, "
            f"more than a turn (2*pi = {TWO_PI:.6g}); an arc's sweep is in (0, 2*pi] and its "
            f"angles are in rad (end_angle = start_angle + 2*pi is a full circle)"
            f"{degrees_hint(a0, a1)}")


def _order_lets(lets, params):
    """Evaluation order of the let entries: dependencies first; cycles and unknown
    names raise ExpressionError."""
    index = {name: i for i, (name, _, _) in enumerate(lets)}
    known = set(params) | set(index) | set(CONSTANTS)
    for name, x, path in lets:
        if isinstance(x, Expr):
            for n in sorted(x.names - known):
                raise ExpressionError(_unknown_msg(n, x, params, index), path=path, token=n)
    order, state = [], {}

    def deps(i):
        x = lets[i][1]
        return [index[n] for n in sorted(x.names & set(index))] if isinstance(x, Expr) else []

    # depth first, with an explicit stack (a chain of thousands of lets must
    # not exhaust the interpreter's recursion limit)
    for root in range(len(lets)):
        if state.get(root) == 2:
            continue
        path_ = [root]
        todo = [iter(deps(root))]
        state[root] = 1
        while todo:
            nxt = next(todo[-1], None)
            if nxt is None:
                i = path_.pop()
                todo.pop()
                state[i] = 2
                order.append((lets[i][0], lets[i][1]))
                continue
            if state.get(nxt) == 2:
                continue
            if state.get(nxt) == 1:
                names = [lets[j][0] for j in path_]
                nm = lets[nxt][0]
                cyc = names[names.index(nm):] + [nm]
                raise ExpressionError(f"'let' definitions form a cycle: {' -> '.join(cyc)}",
                                      path=lets[nxt][2], token=nm)
            state[nxt] = 1
            path_.append(nxt)
            todo.append(iter(deps(nxt)))
    return tuple(order)


def _unknown_msg(n, x, params, lets):
    return (f"unknown name {n!r} in expression {x.src!r}; known names: parameters "
            f"{sorted(params)}, let {sorted(lets)}, constants {sorted(CONSTANTS)}")


#: Optional keys of a parameter entry that guard it in synthesis
#: (:class:`mechanisms.models.Parameter`): ``fixed`` (no shift), ``hard`` (no
#: cut), ``shift_cost`` and ``cut_cost`` (relative costs, default 1) and
#: ``min_keep`` (the smallest fraction of its tolerance to keep).
GUARD_KEYS = ("fixed", "hard", "shift_cost", "cut_cost", "min_keep")

#: Optional key of a parameter entry that states how its made values spread
#: (:class:`mechanisms.models.Distribution`), for statistical yield.
DISTRIBUTION_KEY = "distribution"
#: Optional keys of a parameter entry.
PARAM_OPTIONAL = ("description", "unit") + GUARD_KEYS + (DISTRIBUTION_KEY,)

#: The angle units a parameter entry may state (``"unit"``), and what one of
#: its values is in rad.
ANGLE_UNITS = {"rad": 1.0, "deg": math.pi / 180}


def _param_unit(p: dict, path: str, units: str) -> tuple:
    """The unit of one parameter entry: ``(Parameter.unit, factor)``, its
    values times ``factor`` in the library's units (rad for an angle)."""
    if "unit" not in p:
        return "", 1.0
    u = p["unit"]
    if u == units or canonical_unit(u) is not None and canonical_unit(u) == canonical_unit(units):
        return "", 1.0
    if isinstance(u, str) and u in ANGLE_UNITS:
        return "rad", ANGLE_UNITS[u]
    raise _err(f"unit must be {units!r} (a length, in the model's unit) or 'rad' or 'deg' "
               f"(an angle), got {u!r}", _join(path, "unit"))


def stated_units(model) -> tuple:
    """Per parameter of ``model``: ``(unit, factor)``, the unit its model file
    states its values in and what one of that unit is in the library's units
    (``("deg", pi / 180)`` for ``"unit": "deg"``, :data:`ANGLE_UNITS`); for a
    model read from no file, or a parameter in the library's unit,
    :attr:`~mechanisms.models.Model.param_units` with factor 1."""
    out = [(u, 1.0) for u in model.param_units]
    b = getattr(model, "builder", None)
    if not isinstance(b, ModelFileBuilder):
        return tuple(out)
    stated = {e.get("name"): e.get("unit") for e in json.loads(b.document)["parameters"]}
    for i, p in enumerate(model.parameters):
        u = stated.get(p.name)
        if p.unit == "rad" and ANGLE_UNITS.get(u, 1.0) != 1.0:
            out[i] = (u, ANGLE_UNITS[u])
    return tuple(out)


def _scaled(guards: dict, factor: float) -> dict:
    """A parameter entry's checked guard keys with a stated distribution's
    sigma in the library's units."""
    dist = guards.get("distribution")
    if factor != 1.0 and dist is not None and dist.sigma is not None:
        guards = dict(guards, distribution=dataclasses.replace(dist, sigma=dist.sigma * factor))
    return guards


def _guards(p: dict, path: str) -> dict:
    """The guard keys of one parameter entry, checked."""
    out = {}
    for k in ("fixed", "hard"):
        if k in p:
            if not isinstance(p[k], bool):
                raise _err(f"{k} must be true or false, got {p[k]!r}", _join(path, k))
            out[k] = p[k]
    for k in ("shift_cost", "cut_cost"):
        if k in p:
            v = _finite(p[k], _join(path, k))
            if not v > 0:
                raise _err(f"{k} must be a number > 0 (a relative cost, default 1), got {v}",
                           _join(path, k))
            out[k] = v
    if "min_keep" in p:
        v = _finite(p["min_keep"], _join(path, "min_keep"))
        if not 0.0 <= v <= 1.0:
            raise _err(f"min_keep must be a fraction in [0, 1] of the initial tolerance, got "
                       f"{v}", _join(path, "min_keep"))
        out["min_keep"] = v
    if DISTRIBUTION_KEY in p:
        out["distribution"] = _distribution(p[DISTRIBUTION_KEY], _join(path, DISTRIBUTION_KEY))
    return out


def _distribution(v, path: str):
    """A parameter entry's ``distribution`` object, checked."""
    from .models.base import Distribution
    if not isinstance(v, dict):
        raise _err("expected an object such as {'kind': 'normal', 'cp': 1.33}, got "
                   f"{type(v).__name__} {v!r}"[:300], path)
    for k in ("sigma", "cp", "limit"):
        if k in v:
            _finite(v[k], _join(path, k))
    try:
        return Distribution.from_dict(v)
    except ParameterError as e:
        raise _err(str(e), path) from None


def guard_entries(p, factor: float = 1.0) -> dict:
    """The guard keys (and the distribution) of a Parameter that differ from
    their defaults; a distribution's sigma divided by ``factor`` (written in
    the file's unit of an angle stated in degrees)."""
    out = {}
    if p.fixed:
        out["fixed"] = True
    if p.hard:
        out["hard"] = True
    if p.shift_cost != 1.0:
        out["shift_cost"] = p.shift_cost
    if p.cut_cost != 1.0:
        out["cut_cost"] = p.cut_cost
    if p.min_keep is not None:
        out["min_keep"] = p.min_keep
    if p.distribution is not None:
        dist = p.distribution
        if factor != 1.0 and dist.sigma is not None:
            dist = dataclasses.replace(dist, sigma=dist.sigma / factor)
        out["distribution"] = dist.to_dict()
    return out


def model_from_dict(d: dict) -> Model:
    """A :class:`Model` from a ``cspace-model`` document (already parsed JSON).

    Validates the whole document and builds it once at the nominal parameters, so
    every error surfaces here with the path of the failing item.

    Raises
    ------
    FileFormatError
        Structure: missing or unknown keys, wrong types, duplicate names.
    ExpressionError
        A disallowed construct, an unknown name, a ``let`` cycle, or an expression
        that cannot be evaluated at the nominal parameters.
    DegenerateGeometryError (and subclasses)
        The nominal geometry is invalid (open loop, crossing, zero length, ...).
    InvalidModelError
        Other inconsistencies (e.g. drivers of several pairs on different axes).
    """
    if not isinstance(d, dict):
        raise _err(f"a model file holds a JSON object, got {type(d).__name__}", "")
    if "builtin" in d:
        return _builtin_from_dict(d)
    _keys(d, "", ("format", "version", "name", "units", "parameters", "pairs"),
          ("description", "let", "window", "drive", "q2_start", "deviation"))
    _check_format(d)
    name = _str(d["name"], "name", "model name")
    units = _str(d["units"], "units", "length unit (e.g. 'mm')")
    check_units(units, "units")
    desc = _str(d.get("description", ""), "description", "description", empty=True)
    seen: dict = {}
    params = _parameters(d["parameters"], seen, units)
    pnames = [p.name for p in params]
    lets = _lets(d.get("let", []), seen)
    order = _order_lets(lets, pnames)
    pairs = _pairs(d["pairs"], name, pnames, lets)
    window, drive, q2, deviation = _operating_point(d, len(pairs))
    _warn_angles_as_lengths(d["parameters"], params, order, pairs, units)
    builder = ModelFileBuilder(units, name, order, pairs, json.dumps(d))
    builder({p.name: p.nominal for p in params})  # validate at the nominal vector
    return Model(name, tuple(params), builder, units=units, description=desc, window=window,
                 drive=drive, q2_start=q2, deviation=deviation)


def _additive_names(tree) -> set:
    """The names an expression tree adds up as they are: the expression itself,
    a term of a sum or difference, or a negation of one (not a factor, a divisor,
    a power or a function's argument, where an angle may well make a length,
    as in ``r * cos(theta)`` or ``r * theta``)."""
    kind = tree[0]
    if kind == "name":
        return {tree[2]}
    if kind == "neg":
        return _additive_names(tree[2])
    if kind == "bin" and tree[2] in ("+", "-"):
        return _additive_names(tree[3]) | _additive_names(tree[4])
    return set()


def _length_slots(pairs):
    """The expression slots of the pairs' geometry that hold lengths: point
    coordinates, radii, rotation centres and translation origins."""
    for pr in pairs:
        for part in pr.parts:
            yield from (part.axis if part.axis_kind == "rotation" else part.axis[2:])
            for lp in part.loops:
                for pt in lp.points:
                    yield from pt
                for sg in lp.segments:
                    yield from (sg.values if sg.kind == "line" else sg.values[:3])


def _warn_angles_as_lengths(raw, params, order, pairs, units: str) -> None:
    """A :class:`~cspace.io.UnitWarning` for each angle parameter (``"unit"``
    ``"deg"`` or ``"rad"``) that a length of the geometry takes as it is (see
    :func:`_additive_names`; directly or through ``let`` names): its value in
    rad would become a length, most often a length marked ``"deg"`` by mistake."""
    import warnings
    angles = {p.name: (p, e.get("unit")) for p, e in zip(params, raw) if p.unit == "rad"}
    if not angles:
        return
    via = {n: {n} for n in angles}          # name -> the angle parameters it adds up
    for ln, x in order:
        if isinstance(x, Expr):
            got = set().union(*(via.get(n, set()) for n in _additive_names(x.tree)))
            if got:
                via[ln] = got
    told = set()
    for x in _length_slots(pairs):
        if not isinstance(x, Expr):
            continue
        for n in sorted(_additive_names(x.tree)):
            for a in sorted(via.get(n, ())):
                if a in told:
                    continue
                told.add(a)
                p, stated = angles[a]
                through = f" (through let {n!r})" if n != a else ""
                warnings.warn(
                    f"{x.path}: parameter {a!r} is an angle (\"unit\": {stated!r}) but the "
                    f"length {x.src!r} takes it as it is{through}: its value in rad "
                    f"({p.nominal:.6g}) becomes a length in {units!r}; if {a!r} is a length, "
                    f"drop its \"unit\" (a length is in the model's unit {units!r}), else "
                    f"use it in a length through a function or a factor (e.g. r * cos({a}))",
                    UnitWarning, stacklevel=4)


def _check_format(d: dict) -> None:
    """The document's ``format`` and ``version``."""
    if d["format"] != MODEL_FORMAT:
        raise _err(f"format must be {MODEL_FORMAT!r}, got {d['format']!r}", "format")
    if isinstance(d["version"], bool) or d["version"] != 1:
        raise _err(f"unsupported version {d['version']!r}; this library reads version 1",
                   "version")


def _parameters(plist, seen: dict, units: str) -> list:
    """The :class:`Parameter` list of ``parameters`` (their names entered in
    ``seen``, name -> index)."""
    if not isinstance(plist, list):
        raise _err(f"'parameters' must be a list, got {type(plist).__name__}", "parameters")
    params = []
    for i, p in enumerate(plist):
        path = f"parameters[{i}]"
        _keys(p, path, ("name", "nominal", "tol"), PARAM_OPTIONAL)
        pn = _check_identifier(p["name"], _join(path, "name"), "parameter name")
        if pn in seen:
            raise _err(f"duplicate parameter name {pn!r} (first at parameters[{seen[pn]}])",
                       _join(path, "name"))
        seen[pn] = i
        nom = _finite(p["nominal"], _join(path, "nominal"))
        tol = _finite(p["tol"], _join(path, "tol"))
        if tol < 0:
            raise _err(f"tolerance must be >= 0, got {tol}", _join(path, "tol"))
        pd = _str(p.get("description", ""), _join(path, "description"), "description",
                  empty=True)
        unit, k = _param_unit(p, path, units)
        params.append(Parameter(pn, nom * k, tol * k, pd, unit=unit,
                                **_scaled(_guards(p, path), k)))
    return params


def _lets(raw_lets, seen: dict) -> list:
    """``[(name, expression slot, path)]`` of ``let`` (names entered in ``seen``)."""
    if not isinstance(raw_lets, list):
        raise _err("'let' must be a list of {\"name\", \"value\"} objects", "let")
    lets = []
    for i, item in enumerate(raw_lets):
        path = f"let[{i}]"
        _keys(item, path, ("name", "value"), ("description",))
        ln = _check_identifier(item["name"], _join(path, "name"), "let name")
        if ln in seen:
            where = (f"parameters[{seen[ln]}]" if isinstance(seen[ln], int) else seen[ln])
            raise _err(f"duplicate name {ln!r} (already defined at {where})", _join(path, "name"))
        seen[ln] = path
        _str(item.get("description", ""), _join(path, "description"), "description", empty=True)
        ex = []
        lets.append((ln, _slot(item["value"], _join(path, "value"), ex), _join(path, "value")))
    return lets


def _pairs(prs, name: str, pnames, lets) -> tuple:
    """The pair templates of ``pairs``, each name unique and every name their
    expressions use known (a parameter, a ``let`` or a constant)."""
    if not isinstance(prs, list) or not prs:
        raise _err("'pairs' must be a non-empty list of pairs", "pairs")
    exprs = []
    pairs = tuple(_pair(p, f"pairs[{i}]", name if len(prs) == 1 else f"{name}{i + 1}", exprs)
                  for i, p in enumerate(prs))
    pair_names = [p.name for p in pairs]
    for i, pn in enumerate(pair_names):
        if pair_names.index(pn) != i:
            raise _err(f"duplicate pair name {pn!r}", f"pairs[{i}].name")
    known = set(pnames) | {n for n, _, _ in lets} | set(CONSTANTS)
    for x in exprs:
        for n in sorted(x.names - known):
            raise ExpressionError(_unknown_msg(n, x, pnames, [l[0] for l in lets]),
                                  path=x.path, token=n)
    return pairs


def _operating_point(d: dict, n_pairs: int) -> tuple:
    """``(window, drive, q2_start, deviation)`` of the document, each None when
    not stated."""
    window = _const_list(d["window"], "window", 4, "[q1_lo, q1_hi, q2_lo, q2_hi]") \
        if "window" in d else None
    drive = _const_list(d["drive"], "drive", 2, "[q1_start, q1_end]") if "drive" in d else None
    q2 = (_const_list(d["q2_start"], "q2_start", n_pairs, f"one start value per pair "
                      f"({n_pairs})") if "q2_start" in d else None)
    deviation = None
    if "deviation" in d:
        dv = d["deviation"]
        if isinstance(dv, bool) or not isinstance(dv, (int, float)) \
                or not math.isfinite(json_float(dv)) or dv <= 0:
            raise _err(f"deviation must be a positive finite number (C-space metric: rad, or "
                       f"slide / characteristic length), got {number_text(dv)}", "deviation")
        deviation = float(dv)
    if window is not None and not (window[0] < window[1] and window[2] < window[3]):
        raise _err(f"window must have q1_lo < q1_hi and q2_lo < q2_hi, got {list(window)}",
                   "window")
    return window, drive, q2, deviation


def _builtin_names() -> dict:
    """Builder function -> built-in model name."""
    from .models import BUILTIN
    return {f().builder: k for k, f in BUILTIN.items()}


def _builtin_from_dict(d: dict) -> Model:
    """A built-in model with the parameter values, name, window, drive, start and
    deviation of a ``"builtin"`` model document."""
    import dataclasses

    from .models import BUILTIN
    _keys(d, "", ("format", "version", "builtin", "parameters"),
          ("name", "units", "description", "window", "drive", "q2_start", "deviation"))
    _check_format(d)
    b = d["builtin"]
    if not isinstance(b, str) or b not in BUILTIN:
        raise _err(f"builtin must name a built-in model, one of {sorted(BUILTIN)}, got {b!r}",
                   "builtin")
    base = BUILTIN[b]()
    if "units" in d and d["units"] != base.units:
        raise _err(f"the built-in model {b!r} is in {base.units!r}, the file says "
                   f"{d['units']!r}; its values must be in the model's own units", "units")
    plist = d["parameters"]
    if not isinstance(plist, list):
        raise _err(f"'parameters' must be a list, got {type(plist).__name__}", "parameters")
    given = {}
    for i, p in enumerate(plist):
        path = f"parameters[{i}]"
        _keys(p, path, ("name", "nominal", "tol"), PARAM_OPTIONAL)
        pn = p["name"]
        if pn not in base.names:
            raise _err(f"{pn!r} is not a parameter of the built-in model {b!r}; its "
                       f"parameters are {list(base.names)}", _join(path, "name"))
        if pn in given:
            raise _err(f"duplicate parameter name {pn!r}", _join(path, "name"))
        tol = _finite(p["tol"], _join(path, "tol"))
        if tol < 0:
            raise _err(f"tolerance must be >= 0, got {tol}", _join(path, "tol"))
        unit, k = _param_unit(p, path, base.units)
        own = base.parameters[base.index(pn)].unit
        if unit != own:
            raise _err(f"{pn!r} of the built-in model {b!r} is "
                       f"{'an angle (rad)' if own else 'a length, in ' + repr(base.units)}, the "
                       f"file says unit {p['unit']!r}", _join(path, "unit"))
        given[pn] = (_finite(p["nominal"], _join(path, "nominal")) * k, tol * k,
                     _scaled(_guards(p, path), k))
    missing = [n for n in base.names if n not in given]
    if missing:
        raise _err(f"the built-in model {b!r} needs every parameter; missing {missing}",
                   "parameters")
    params = tuple(Parameter(q.name, given[q.name][0], given[q.name][1], q.description,
                             unit=q.unit, **given[q.name][2])
                   for q in base.parameters)
    kw = {"parameters": params}
    if "name" in d:
        kw["name"] = _str(d["name"], "name", "model name")
    if "description" in d:
        kw["description"] = _str(d["description"], "description", "description", empty=True)
    stated = zip(("window", "drive", "q2_start", "deviation"),
                 _operating_point(d, len(base.pairs())))
    kw.update({key: value for key, value in stated if key in d})
    model = dataclasses.replace(base, **kw)
    model.build()   # validate at the nominal vector
    return model


def _builtin_to_dict(model: Model, name: str) -> dict:
    d = {"format": MODEL_FORMAT, "version": 1, "builtin": name, "name": model.name,
         "units": model.units}
    if model.description:
        d["description"] = model.description
    d["parameters"] = [{"name": p.name, "nominal": p.nominal, "tol": p.tol,
                        **({"unit": "rad"} if p.unit else {}), **guard_entries(p)}
                       for p in model.parameters]
    for key in ("window", "drive", "q2_start"):
        v = getattr(model, key)
        if v is not None:
            d[key] = [float(x) for x in v]
    if model.deviation is not None:
        d["deviation"] = float(model.deviation)
    return d


def load_model(path) -> Model:
    """Read a ``cspace-model`` JSON file (see :func:`model_from_dict`)."""
    return model_from_dict(load_json(path))


def _same(a, b) -> bool:
    return a is None and b is None or (a is not None and b is not None
                                        and len(a) == len(b)
                                        and all(float(x) == float(y) for x, y in zip(a, b)))


def model_to_dict(model: Model) -> dict:
    """The ``cspace-model`` document of a model read from a file, or of a built-in
    model (a ``"builtin"`` document naming it, with its parameter values).

    The geometry, ``let`` block and any expressions are the file's own; the name,
    description, parameters (nominal values and tolerances, e.g. after synthesis),
    window, drive and follower start come from ``model``.  A document read with
    :func:`model_from_dict` comes back equal to itself.

    Raises
    ------
    InputError
        ``model`` was not built from a model file (built-in models are Python code).
    InvalidModelError
        The model's parameter names or units no longer match its file.
    """
    b = getattr(model, "builder", None)
    if isinstance(model, Model) and not isinstance(b, ModelFileBuilder):
        builtin = _builtin_names().get(b)
        if builtin is not None:
            return _builtin_to_dict(model, builtin)
    if not isinstance(model, Model) or not isinstance(b, ModelFileBuilder):
        raise InputError("model_to_dict needs a Model read from a cspace-model file or a "
                         "built-in model; other models are Python code (save a pair "
                         "instance with cspace.io.save_pair instead)", name="model",
                         value=model)
    d = json.loads(b.document)
    old = d["parameters"]
    if [p["name"] for p in old] != list(model.names):
        raise InvalidModelError(f"model {model.name!r}: parameter names {list(model.names)} do "
                                f"not match its file's {[p['name'] for p in old]}")
    if model.units != b.units:
        raise InvalidModelError(f"model {model.name!r}: units {model.units!r} differ from its "
                                f"file's {b.units!r}; geometry is in the file's units")
    newp = []
    for p, o in zip(model.parameters, old):
        # in the file's unit (an angle stated in degrees is written in degrees)
        k = _param_unit(o, "", b.units)[1] if "unit" in o else 1.0
        e = {"name": p.name,
             "nominal": p.nominal / k if float(o["nominal"]) * k != p.nominal else o["nominal"],
             "tol": p.tol / k if float(o["tol"]) * k != p.tol else o["tol"]}
        if "unit" in o:
            e["unit"] = o["unit"]
        if "description" in o or p.description:
            e["description"] = p.description
        e.update(guard_entries(p, k))
        if "distribution" in e and "distribution" in o \
                and _scaled({"distribution": _distribution(o["distribution"], "")},
                            k)["distribution"] == p.distribution:
            e["distribution"] = o["distribution"]     # the file's own spelling
        newp.append(e)
    d["parameters"] = newp
    d["name"] = model.name
    if model.description or "description" in d:
        d["description"] = model.description
    q2 = None if model.q2_start is None else tuple(model.q2_start)
    for key, val, default in (("window", model.window, None), ("drive", model.drive, None),
                              ("q2_start", q2, None)):
        if key in d:
            fixed = _const_list(d[key], key, None)
            if not _same(fixed, val):
                if val is None:
                    del d[key]
                else:
                    d[key] = [float(v) for v in val]
        elif not _same(val, default):
            d[key] = [float(v) for v in val]
    if model.deviation is None:
        d.pop("deviation", None)
    else:
        d["deviation"] = float(model.deviation)
    return d


def save_model(model: Model, path) -> Path:
    """Write a model read from a file as ``cspace-model`` JSON (atomically)."""
    return atomic_write(path, dumps(model_to_dict(model)))
