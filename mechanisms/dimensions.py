"""Every dimension of a fixed pair (or assembly) as a parameter: the model of
``import-dxf --tol``, for tolerance analysis of a drawing that comes without a
parametrisation.

Functions
---------
parametric_model(pair, tol, param_mode=...) -> Model
"""

from __future__ import annotations

import math

from cspace.errors import InputError, InvalidModelError
from cspace.geometry import Assembly, Line, Loop, Pair, Rotation
from cspace.io import json_float

from .models.base import Model
from .userfile import MODEL_FORMAT, model_from_dict

__all__ = ["parametric_model", "PARAM_MODES"]


#: What :func:`parametric_model` turns into parameters.
PARAM_MODES = ("all", "profile")


def _ident(s: str) -> str:
    out = "".join(ch if ch.isalnum() or ch == "_" else "_" for ch in s)
    if not out or not (out[0].isalpha() or out[0] == "_"):
        out = "p_" + out
    return out


def _loop_polyline(lp: Loop):
    """(points, bulges, names) of a loop: one vertex per segment start; a full
    circle becomes two half circles."""
    segs = lp.segments
    if len(segs) == 1:
        s = segs[0]
        p = s.start_point
        q = s.point_at(s.start_angle + 0.5 * s.signed_sweep)
        b = 1.0 if s.ccw else -1.0
        halves = [f"{s.name}.1", f"{s.name}.2"] if s.name else ["", ""]
        return [tuple(map(float, p)), tuple(map(float, q))], [b, b], halves
    pts, bl, names = [], [], []
    for s in segs:
        pts.append(tuple(map(float, s.start_point)))
        bl.append(0.0 if isinstance(s, Line) else math.tan(s.signed_sweep / 4.0))
        names.append(s.name)
    return pts, bl, names


def _unique_name(name: str, used: set) -> str:
    """``name``, or ``name.2``, ``name.3``, ... if a segment of the part already
    has it (a model file needs the segment names of a part unique); ``used``
    collects the part's names."""
    if not name:
        return name
    out, k = name, 1
    while out in used:
        k += 1
        out = f"{name}.{k}"
    used.add(out)
    return out


def parametric_model(obj, tol: float, *, param_mode: str = "all", name: str | None = None,
                     description: str = "") -> Model:
    """A model in which every dimension of a fixed Pair or Assembly is a parameter.

    Each loop becomes a closed polyline with bulges whose every vertex coordinate
    is a parameter ``<part>_L<loop>_P<vertex>_x`` / ``_y`` (``<pair>_<part>_...`` in
    an assembly); with ``param_mode="all"`` the rotation centres are parameters
    too (``<part>_axis_x`` / ``_y``; the drivers of an assembly share the first
    driver's).  Every parameter gets the tolerance ``tol``.

    Bulges stay fixed: an arc keeps its sweep angle while its end points move, and
    its radius follows the chord.  Every vector in the box therefore builds a
    valid arc (a free radius could make the chord longer than the diameter), and
    arcs that met tangentially stay nearly tangent.  Translation directions and
    origins are not dimensions of the profile and stay fixed.  A full circle
    becomes two half circles (bulge 1) so that it keeps its shape.  Each pair
    keeps its closure (``"closure"``, :attr:`cspace.geometry.Pair.bias`).

    Returns
    -------
    Model
        Built from a ``cspace-model`` document, so :func:`save_model` writes it.
    """
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) \
            or not math.isfinite(json_float(tol)) or tol < 0:
        raise InputError(f"tol must be a finite number >= 0 (model units), got {tol!r}",
                         name="tol", value=tol)
    if param_mode not in PARAM_MODES:
        raise InputError(f"param_mode must be one of {PARAM_MODES}, got {param_mode!r}",
                         name="param_mode", value=param_mode)
    if isinstance(obj, Assembly):
        pairs, multi = obj.pairs, True
    elif isinstance(obj, Pair):
        pairs, multi = (obj,), False
    else:
        raise InputError(f"parametric_model needs a Pair or Assembly, got {type(obj).__name__}",
                         name="obj", value=obj)
    params, seen = [], set()

    def par(pname, value, what):
        if pname in seen:
            raise InvalidModelError(f"two dimensions map to the parameter name {pname!r}; "
                                    "part names must differ")
        seen.add(pname)
        params.append({"name": pname, "nominal": float(value), "tol": float(tol),
                       "description": what})
        return pname

    drv_axis = None
    doc_pairs = []
    for pair in pairs:
        doc_parts = []
        for part in pair.parts:
            pre = _ident(f"{pair.name}_{part.name}" if multi else part.name)
            ax = part.axis
            if isinstance(ax, Rotation):
                if param_mode == "all" and part is pair.driver and multi and drv_axis:
                    center = drv_axis
                elif param_mode == "all":
                    center = [par(f"{pre}_axis_{c}", v, f"{part.name} rotation centre {c}")
                              for c, v in zip("xy", ax.center)]
                else:
                    center = [float(v) for v in ax.center]
                if part is pair.driver and drv_axis is None:
                    drv_axis = center
                axd = {"type": "rotation", "center": center}
            else:
                axd = {"type": "translation", "direction": [float(v) for v in ax.direction],
                       "origin": [float(v) for v in ax.origin]}
            loops = []
            used: set = set()      # the part's segment names so far
            for li, lp in enumerate(part.loops):
                pts, bl, names = _loop_polyline(lp)
                names = [_unique_name(nm, used) for nm in names]
                poly = [[par(f"{pre}_L{li}_P{k}_{c}", v, f"{part.name} loop {li} vertex {k} {c}")
                         for c, v in zip("xy", p)] for k, p in enumerate(pts)]
                ld = {"polyline": poly, "bulges": bl}
                if any(names):
                    ld["names"] = names
                loops.append(ld)
            doc_parts.append({"name": part.name, "axis": axd, "loops": loops})
        doc_pairs.append({"name": pair.name, "parts": doc_parts})
        if pair.bias:
            doc_pairs[-1]["closure"] = {"bias": pair.bias}
    d = {"format": MODEL_FORMAT, "version": 1,
         "name": name or (obj.name if isinstance(obj, Assembly) else pairs[0].name),
         "units": pairs[0].units, "parameters": params, "pairs": doc_pairs}
    if description:
        d["description"] = description
    return model_from_dict(d)
