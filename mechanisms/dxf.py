"""DXF drawings in and out (extra ``dxf``: needs ezdxf, imported when first used).

Import
------
:func:`import_dxf` reads LINE, ARC, CIRCLE and LWPOLYLINE entities (with bulges,
open or closed), one layer per part, chains each layer's segments into closed
loops by matching end points, orients the loops so that the material lies to the
left (outer boundaries counter-clockwise, holes clockwise, by nesting) and
returns a :class:`~cspace.geometry.Pair` whose first part is the driver.  With a
tolerance ``tol`` it returns a parametric :class:`~mechanisms.models.Model`
instead, in which every dimension is a parameter (:func:`dxf_to_model`, see
:func:`mechanisms.userfile.parametric_model`).

Annotation entities (TEXT, MTEXT, DIMENSION, POINT, HATCH, LEADER, MLEADER,
ATTDEF) on a part's layer are skipped; any other entity type is an error, so a
SPLINE or ELLIPSE is never silently dropped from a profile.

Export
------
:func:`export_dxf` writes a Pair, an Assembly or a Model (at its nominal or a
given parameter vector): one layer per part (``pair.part`` for assemblies), LINE
and ARC entities, full circles as CIRCLE, the length unit in ``$INSUNITS``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cspace.errors import (DegenerateGeometryError, FileFormatError, InputError,
                           MissingExtraError, OpenLoopError)
from cspace.geometry import Arc, Assembly, Line, Loop, Pair, Part, Rotation, Translation

__all__ = ["import_dxf", "dxf_to_model", "export_dxf", "JOIN_REL", "INSUNITS"]

#: Relative tolerance (to a layer's bounding-box diagonal) within which two segment
#: end points are taken as one vertex when chaining.  CAD programs write
#: coordinates with 12 to 16 significant digits, and some write only 6 decimals:
#: 1e-6 of the part size joins such round-off, yet is far below any manufacturing
#: tolerance, so distinct vertices are never merged.
JOIN_REL = 1e-6

#: Length units and their DXF ``$INSUNITS`` codes.
INSUNITS = {"in": 1, "ft": 2, "mi": 3, "mm": 4, "cm": 5, "m": 6, "km": 7, "uin": 8, "mil": 9,
            "yd": 10, "nm": 12, "um": 13, "dm": 14, "dam": 15, "hm": 16}
_METRES = {"in": 0.0254, "ft": 0.3048, "mi": 1609.344, "mm": 1e-3, "cm": 1e-2, "m": 1.0,
           "km": 1e3, "uin": 2.54e-8, "mil": 2.54e-5, "yd": 0.9144, "nm": 1e-9, "um": 1e-6,
           "dm": 0.1, "dam": 10.0, "hm": 100.0}
_SKIPPED = {"TEXT", "MTEXT", "DIMENSION", "POINT", "HATCH", "LEADER", "MLEADER", "ATTDEF"}
_SUPPORTED = ("LINE", "ARC", "CIRCLE", "LWPOLYLINE")
_BAD_LAYER_CHARS = '<>/\\":;?*|=`'


def _ezdxf():
    try:
        import ezdxf
    except ImportError:
        raise MissingExtraError("ezdxf", "dxf") from None
    return ezdxf


# ---------------------------------------------------------------------- import

@dataclass(frozen=True)
class _Piece:
    """A segment read from the drawing, with where it came from (for messages)."""

    seg: object
    where: str


def _bulge_arc(p, q, b, name=""):
    """The arc from p to q with bulge b = tan(sweep / 4) (positive counter-clockwise)."""
    theta = 4.0 * math.atan(b)
    chord = (q[0] - p[0], q[1] - p[1])
    c = math.hypot(*chord)
    r = c / (2.0 * math.sin(abs(theta) / 2.0))
    left = (-chord[1] / c, chord[0] / c)
    d = (c / 2.0) / math.tan(theta / 2.0)
    cx = 0.5 * (p[0] + q[0]) + left[0] * d
    cy = 0.5 * (p[1] + q[1]) + left[1] * d
    return Arc((cx, cy), r, math.atan2(p[1] - cy, p[0] - cx), math.atan2(q[1] - cy, q[0] - cx),
               b > 0, name)


def _extrusion_sign(e, where):
    ex = tuple(e.dxf.get("extrusion", (0.0, 0.0, 1.0)))
    if abs(ex[0]) > 1e-12 or abs(ex[1]) > 1e-12 or abs(abs(ex[2]) - 1.0) > 1e-12:
        raise FileFormatError(f"entity is not in the XY plane (extrusion {ex}); only planar "
                              "drawings in XY can be imported", path=where)
    return 1.0 if ex[2] > 0 else -1.0


def _entity_segments(e, k: float, where: str) -> list:
    """Segments of one entity, lengths scaled by ``k`` (empty for skipped types).

    Entities with extrusion (0, 0, -1) are mirrored in x (their object coordinate
    system), which also reverses the sense of arcs and bulges.
    """
    t = e.dxftype()
    if t == "LINE":
        s, f = e.dxf.start, e.dxf.end
        p, q = (k * s.x, k * s.y), (k * f.x, k * f.y)
        if p == q:
            return []
        return [Line(p, q)]
    if t in ("ARC", "CIRCLE"):
        sg = _extrusion_sign(e, where)
        c = e.dxf.center
        cx, cy, r = sg * k * c.x, k * c.y, k * e.dxf.radius
        if t == "CIRCLE":
            return [Arc((cx, cy), r, 0.0, 2 * math.pi, True)]
        a0, a1 = math.radians(e.dxf.start_angle), math.radians(e.dxf.end_angle)
        if sg < 0:   # mirrored: the arc runs clockwise from pi - a0 to pi - a1
            return [Arc((cx, cy), r, math.pi - a0, math.pi - a1, False)]
        return [Arc((cx, cy), r, a0, a1, True)]
    if t == "LWPOLYLINE":
        sg = _extrusion_sign(e, where)
        pts = [(sg * k * x, k * y, sg * b) for x, y, b in e.get_points("xyb")]
        n = len(pts)
        edges = n if e.closed else n - 1
        out = []
        for i in range(edges):
            x0, y0, b = pts[i]
            x1, y1, _ = pts[(i + 1) % n]
            p, q = (float(x0), float(y0)), (float(x1), float(y1))
            if p == q:
                continue
            out.append(Line(p, q) if b == 0 else _bulge_arc(p, q, float(b)))
        return out
    if t in _SKIPPED:
        return []
    raise FileFormatError(f"entity type {t} is not supported on a part layer; supported: "
                          f"{', '.join(_SUPPORTED)} (annotation types are skipped)", path=where)


def _fmt(p):
    return "(" + ", ".join(f"{float(v):.10g}" for v in p) + ")"


def _chain(pieces: list, layer: str, tol: float) -> list:
    """Closed chains of segments (each a list of segments) from an unordered pool.

    Segments are reversed as needed.  Where a line meets another segment within
    ``tol`` the line's end point is moved onto the other's, so each loop closes
    exactly; two arcs are left as drawn.
    """
    pool = []
    chains = []
    for pc in pieces:
        if isinstance(pc.seg, Arc) and pc.seg.is_full_circle:
            chains.append([pc.seg])
        else:
            pool.append(pc)
    while pool:
        first = pool.pop(0)
        chain = [first.seg]
        start = first.seg.start_point
        while True:
            end = chain[-1].end_point
            if np.hypot(*(end - start)) <= tol and (len(chain) > 1 or isinstance(chain[0], Arc)):
                break
            cands = []
            for i, pc in enumerate(pool):
                for flip, pt in ((False, pc.seg.start_point), (True, pc.seg.end_point)):
                    if np.hypot(*(pt - end)) <= tol:
                        cands.append((i, flip))
            if not cands:
                free = [start] + [pt for pc in pool for pt in (pc.seg.start_point,
                                                                pc.seg.end_point)]
                gaps = [float(np.hypot(*(pt - end))) for pt in free]
                j = int(np.argmin(gaps))
                err = OpenLoopError(
                    f"layer {layer!r}: the outline is open: a chain of {len(chain)} segment(s) "
                    f"starting at {_fmt(start)} ends at {_fmt(end)}; the nearest free end point "
                    f"is {_fmt(free[j])}, gap {gaps[j]:.6g} > join tolerance {tol:.3g}",
                    where=layer)
                err.layer, err.gap, err.point = layer, gaps[j], tuple(float(v) for v in end)
                raise err
            if len({i for i, _ in cands}) > 1:
                raise FileFormatError(
                    f"{len(cands) + 1} segment ends meet at {_fmt(end)}; a part outline must "
                    "be a set of simple closed loops (no branches)", path=f"layer {layer!r}")
            i, flip = cands[0]
            seg = pool.pop(i).seg
            chain.append(seg.reversed() if flip else seg)
        chains.append(_snap(chain))
    return chains


def _snap(chain):
    n = len(chain)
    if n == 1:
        return chain
    segs = list(chain)
    for k in range(n):
        a, b = segs[k], segs[(k + 1) % n]
        pa, pb = a.end_point, b.start_point
        if pa[0] == pb[0] and pa[1] == pb[1]:
            continue
        if isinstance(a, Line) and isinstance(b, Line):
            p = tuple(0.5 * (pa + pb))
        elif isinstance(a, Line):
            p = tuple(pb)
        elif isinstance(b, Line):
            p = tuple(pa)
        else:
            continue
        if isinstance(a, Line):
            segs[k] = Line(a.start, p, a.name)
        if isinstance(b, Line):
            segs[(k + 1) % n] = Line(p, segs[(k + 1) % n].end, b.name)
    return segs


def _orient(loops: list) -> list:
    """Outer loops counter-clockwise, holes clockwise (by nesting depth)."""
    out = []
    for i, lp in enumerate(loops):
        probe = lp.segments[0].start_point
        depth = sum(1 for j, o in enumerate(loops) if j != i and o.contains(probe))
        out.append(lp if lp.is_ccw == (depth % 2 == 0) else lp.reversed())
    return out


def _axis(a, where):
    if isinstance(a, (Rotation, Translation)):
        return a
    if isinstance(a, dict) and a.get("type") == "rotation" and set(a) <= {"type", "center"}:
        return Rotation(tuple(a.get("center", (0.0, 0.0))))
    if isinstance(a, dict) and a.get("type") == "translation" \
            and set(a) <= {"type", "direction", "origin"} and "direction" in a:
        return Translation(tuple(a["direction"]), tuple(a.get("origin", (0.0, 0.0))))
    raise InputError(f"{where}: axis must be a Rotation, a Translation or a dict such as "
                     f"{{'type': 'rotation', 'center': [x, y]}}, got {a!r}", name="axis", value=a)


def _read(path):
    ezdxf = _ezdxf()
    p = Path(path)
    if p.is_dir():
        raise FileFormatError(f"{p} is a folder; expected a DXF file")
    if not p.is_file():
        raise FileFormatError(f"no such file: {p}")
    try:
        return ezdxf.readfile(str(p))
    except (OSError, UnicodeDecodeError) as e:
        raise FileFormatError(f"cannot read {p}: {e}") from None
    except ezdxf.DXFError as e:
        raise FileFormatError(f"{p} is not a valid DXF file: {e}") from None
    except (StopIteration, ValueError, KeyError, IndexError, TypeError, AttributeError) as e:
        # the reader's own failures on a truncated or corrupted file
        raise FileFormatError(f"{p} is not a valid DXF file (damaged or truncated: "
                              f"{type(e).__name__}: {e})") from None


def _file_units(doc, path):
    """The drawing's length unit from ``$INSUNITS`` (None when unitless)."""
    raw = doc.header.get("$INSUNITS", 0)
    try:
        code = int(raw)
    except (TypeError, ValueError):
        raise FileFormatError(f"{path}: $INSUNITS must be an integer unit code, got "
                              f"{raw!r}") from None
    if code == 0:
        return None
    for u, c in INSUNITS.items():
        if c == code:
            return u
    raise FileFormatError(f"{path}: drawing unit $INSUNITS = {code} is not one this reader "
                          f"converts; supported: {sorted(INSUNITS.items(), key=lambda t: t[1])}")


def import_dxf(path, *, parts, units: str | None = None, tol: float | None = None,
               param_mode: str = "all", join_rel: float = JOIN_REL, name: str | None = None):
    """Read a pair (or, with ``tol``, a parametric model) from a DXF drawing.

    Parameters
    ----------
    path : str or Path
    parts : sequence of 2 mappings ``{"layer": str, "name": str, "axis": axis}``
        Driver first, then follower.  ``axis`` is a :class:`Rotation`, a
        :class:`Translation` or its pair-JSON dict (``{"type": "rotation",
        "center": [x, y]}``).  Layer names match case-insensitively, as in CAD.
    units : str, optional
        Length unit of the result.  Default: the drawing's ``$INSUNITS``.  When
        both are known and differ, coordinates are converted (e.g. a drawing in mm
        read with ``units="cm"`` is scaled by 0.1).  Axis coordinates are taken
        in ``units``.
    tol : float, optional
        If given, return a Model in which every dimension is a parameter with
        this tolerance (model units); see :func:`mechanisms.userfile.parametric_model`.
    param_mode : {"all", "profile"}
        With ``tol``: also make rotation centres parameters (``"all"``) or not.
    join_rel : float
        End-point matching tolerance relative to the layer size (:data:`JOIN_REL`).
    name : str, optional
        Pair name (default: the file name without suffix).

    Returns
    -------
    Pair, or Model when ``tol`` is given.

    Raises
    ------
    MissingExtraError
        ezdxf is not installed.
    FileFormatError
        Unreadable file, unknown layer, unsupported entity, branching outline.
    OpenLoopError
        A layer's segments do not close (names the layer and the gap).
    DegenerateGeometryError
        Crossing loops and other invalid geometry.
    """
    if not isinstance(parts, (list, tuple)) or len(parts) != 2:
        raise InputError("parts must list exactly 2 parts (driver, follower), each "
                         "{'layer', 'name', 'axis'}", name="parts", value=parts)
    if not (isinstance(join_rel, (int, float)) and 0 < join_rel < 1e-2):
        raise InputError(f"join_rel must be in (0, 0.01), got {join_rel!r}", name="join_rel",
                         value=join_rel)
    doc = _read(path)
    fu = _file_units(doc, path)
    if units is None:
        if fu is None:
            raise FileFormatError(f"{path} does not state its length unit ($INSUNITS = "
                                  f"{doc.header.get('$INSUNITS', 0)}); pass units= one of "
                                  f"{sorted(INSUNITS)}")
        units = fu
    if not isinstance(units, str) or not units:
        raise InputError(f"units must be a non-empty str such as 'mm', got {units!r}",
                         name="units", value=units)
    if fu is not None and units != fu and units not in _METRES:
        raise InputError(f"cannot convert the drawing's {fu} to {units!r}; units must be one "
                         f"of {sorted(_METRES)} (or the drawing's own unit)", name="units",
                         value=units)
    k = _METRES[fu] / _METRES[units] if fu in _METRES and units in _METRES else 1.0

    by_layer = {}
    for e in doc.modelspace():
        by_layer.setdefault(e.dxf.layer.lower(), []).append(e)
    built = []
    for i, spec in enumerate(parts):
        if not isinstance(spec, dict) or not {"layer", "name", "axis"} <= set(spec):
            raise InputError(f"parts[{i}] must be a mapping with 'layer', 'name' and 'axis', "
                             f"got {spec!r}", name="parts", value=spec)
        layer = str(spec["layer"])
        ents = by_layer.get(layer.lower())
        if not ents:
            raise FileFormatError(f"layer {layer!r} has no entities; layers in the drawing: "
                                  f"{sorted({e.dxf.layer for v in by_layer.values() for e in v})}",
                                  path=f"parts[{i}].layer")
        pieces = []
        for e in ents:
            where = f"layer {layer!r}: {e.dxftype()} #{e.dxf.handle}"
            try:
                segs = _entity_segments(e, k, where)
            except DegenerateGeometryError as err:
                raise type(err)(f"{where}: {err}", where=where) from None
            pieces += [_Piece(s, where) for s in segs]
        if not pieces:
            raise FileFormatError(f"layer {layer!r} holds no {'/'.join(_SUPPORTED)} geometry",
                                  path=f"parts[{i}].layer")
        b = np.array([pc.seg.bounds() for pc in pieces])
        size = math.hypot(b[:, 2].max() - b[:, 0].min(), b[:, 3].max() - b[:, 1].min())
        chains = _chain(pieces, layer, join_rel * size)
        try:
            loops = _orient([Loop(tuple(c)) for c in chains])
            built.append(Part(spec["name"], tuple(loops), _axis(spec["axis"], f"parts[{i}].axis")))
        except DegenerateGeometryError as err:
            raise type(err)(f"layer {layer!r}: {err}", where=layer) from None
    pair = Pair(built[0], built[1], units, name or Path(path).stem)
    if tol is None:
        return pair
    from .userfile import parametric_model
    return parametric_model(pair, tol, param_mode=param_mode)


def dxf_to_model(path, *, parts, tol: float, units: str | None = None,
                 param_mode: str = "all", join_rel: float = JOIN_REL, name: str | None = None):
    """A parametric Model from a DXF drawing: every vertex coordinate (and, with
    ``param_mode="all"``, every rotation centre) is a parameter of tolerance
    ``tol``.  Same arguments as :func:`import_dxf`; save the result with
    :func:`mechanisms.userfile.save_model`."""
    if tol is None:
        raise InputError("dxf_to_model needs a tolerance tol (model units)", name="tol")
    return import_dxf(path, parts=parts, units=units, tol=tol, param_mode=param_mode,
                      join_rel=join_rel, name=name)


# ---------------------------------------------------------------------- export

def _layer_name(s: str) -> str:
    out = "".join("_" if ch in _BAD_LAYER_CHARS or ord(ch) < 32 else ch for ch in s)
    return out or "_"


def export_dxf(obj, path, params=None, *, dxfversion: str = "R2010") -> Path:
    """Write a Pair, Assembly or Model as a DXF drawing (atomically).

    Parameters
    ----------
    obj : Pair, Assembly or Model
    path : str or Path
    params : mapping or sequence, optional
        Parameter vector of a Model (default: nominal).  Not allowed for a fixed
        Pair or Assembly.
    dxfversion : str
        DXF version written by ezdxf.

    Returns
    -------
    Path

    Notes
    -----
    One layer per part: the part name for a single pair, ``pair.part`` for an
    assembly.  Lines become LINE, arcs ARC (always counter-clockwise in DXF, so a
    clockwise arc is written with its end points swapped), full circles CIRCLE.
    The unit goes into ``$INSUNITS`` when it is one of :data:`INSUNITS`.
    Coordinates are world coordinates at configuration 0; the motion axes are not
    stored (DXF has no place for them), so give them again on import.
    """
    ezdxf = _ezdxf()
    from .models.base import Model
    if isinstance(obj, Model):
        built = obj.build(params)
    elif isinstance(obj, (Pair, Assembly)):
        if params is not None:
            raise InputError("params apply only to a parametric Model, not a fixed "
                             f"{type(obj).__name__}", name="params", value=params)
        built = obj
    else:
        raise InputError(f"export_dxf needs a Pair, Assembly or Model, got "
                         f"{type(obj).__name__}", name="obj", value=obj)
    multi = isinstance(built, Assembly)
    pairs = built.pairs if multi else (built,)
    doc = ezdxf.new(dxfversion)
    if built.units in INSUNITS:
        doc.header["$INSUNITS"] = INSUNITS[built.units]
        doc.header["$MEASUREMENT"] = 0 if built.units in ("in", "ft", "mi", "yd") else 1
    msp = doc.modelspace()
    seen = set()
    for pair in pairs:
        for part in pair.parts:
            layer = _layer_name(f"{pair.name}.{part.name}" if multi else part.name)
            if layer.lower() in seen:
                raise InputError(f"two parts map to the DXF layer {layer!r}; part names must "
                                 "differ", name="obj", value=layer)
            seen.add(layer.lower())
            if layer not in doc.layers:   # "0" and "Defpoints" come with every drawing
                doc.layers.add(layer)
            att = {"layer": layer}
            for lp in part.loops:
                for s in lp.segments:
                    if isinstance(s, Line):
                        msp.add_line(s.start, s.end, dxfattribs=att)
                    elif s.is_full_circle:
                        msp.add_circle(s.center, s.radius, dxfattribs=att)
                    else:
                        a0 = s.start_angle
                        a1 = s.start_angle + s.signed_sweep
                        if not s.ccw:
                            a0, a1 = a1, a0
                        msp.add_arc(s.center, s.radius, math.degrees(a0), math.degrees(a1),
                                    dxfattribs=att)
    import io as _io

    from cspace.io import atomic_write
    buf = _io.StringIO()
    doc.write(buf)  # R2013: UTF-8 text
    return atomic_write(Path(path), buf.getvalue())
