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
:func:`mechanisms.dimensions.parametric_model`).

Drawing noise is handled as CAD does, with ``join_rel`` (:data:`JOIN_REL`) times
the size of the layer as the rounding level: end points closer than that are one
vertex (a line's end is moved onto its neighbour, so loops close exactly); an
edge no longer than that is dropped; a polyline bulge whose arc rises no more
than that above its chord is a straight edge.  A bulge whose arc would be a full
circle to within that level, and any non-finite number, is a FileFormatError
naming the layer, the entity and the vertex.  End points are matched with a k-d
tree and the validity checks pre-select segments by bounding box, so drawings of
thousands of segments import in O(n log n).

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

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cspace.errors import (CSpaceError, DegenerateGeometryError, FileFormatError, InputError,
                           MissingExtraError, OpenLoopError)
from cspace.geometry import (Arc, Assembly, Line, Loop, Pair, Part, Rotation, Translation,
                             bounds_diagonal, bounds_of, nesting_depths)
from cspace.io import LENGTH_UNITS, UnitWarning, canonical_unit, check_units, known_units_text

__all__ = ["import_dxf", "dxf_to_model", "export_dxf", "JOIN_REL", "INSUNITS", "AxisWarning",
           "FAR_AXIS"]

#: Relative tolerance (to a layer's bounding-box diagonal) within which two segment
#: end points are taken as one vertex when chaining.  CAD programs write
#: coordinates with 12 to 16 significant digits, and some write only 6 decimals:
#: 1e-6 of the part size joins such round-off, yet is far below any manufacturing
#: tolerance, so distinct vertices are never merged.
JOIN_REL = 1e-6

#: Length units and their DXF ``$INSUNITS`` codes (canonical names; an alias
#: such as ``"inch"`` or ``"millimetre"`` maps to one, :func:`cspace.io.canonical_unit`).
INSUNITS = {"in": 1, "ft": 2, "mi": 3, "mm": 4, "cm": 5, "m": 6, "km": 7, "uin": 8, "mil": 9,
            "yd": 10, "nm": 12, "um": 13, "dm": 14, "dam": 15, "hm": 16}

#: A part's rotation centre (or a translation origin other than (0, 0)) farther
#: than this many times the drawing's size from the drawing's bounding box is
#: named in an :class:`AxisWarning` by :func:`import_dxf`.
FAR_AXIS = 100.0


class AxisWarning(UnitWarning):
    """A part's rotation centre or translation origin lies far outside the drawing
    (:data:`FAR_AXIS`): most often coordinates given in the drawing's unit while
    ``import_dxf`` takes them in the target unit ``units``."""
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


@dataclass(frozen=True)
class _Edge:
    """An edge read from the drawing, before its layer's join tolerance is known.

    ``arc`` is None for a straight edge from ``p`` to ``q``.  ``sagitta`` is set
    for a polyline edge with a bulge: the arc's height over its chord, below which
    the edge is drawn straight; the arc is made only once that is decided.
    """

    p: tuple
    q: tuple
    arc: object = None
    bulge: float = 0.0
    sagitta: float | None = None
    where: str = ""

    def chord_bounds(self):
        return (min(self.p[0], self.q[0]), min(self.p[1], self.q[1]),
                max(self.p[0], self.q[0]), max(self.p[1], self.q[1]))


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


def _bulge_limit(join_rel: float) -> float:
    """The largest |bulge| whose arc is not a full circle to within ``join_rel``.

    An arc of sweep 4 atan(b) has chord / diameter = sin(2 atan b) = 2 b / (1 + b^2):
    beyond this limit its end points are closer than ``join_rel`` times the diagonal
    of its circle's bounding box (2 sqrt(2) r), the join tolerance of a layer that
    held only that arc, so its two ends are one vertex and the arc cannot be told
    apart from a full circle; its radius (about chord * b / 4) is then also so large
    that it would set the join tolerance of the whole layer.
    """
    a = math.sqrt(2.0) * join_rel             # solve 2 b / (1 + b^2) = a for b > 1
    return (1.0 + math.sqrt(max(1.0 - a * a, 0.0))) / a


def _extrusion_sign(e, where):
    ex = tuple(e.dxf.get("extrusion", (0.0, 0.0, 1.0)))
    if abs(ex[0]) > 1e-12 or abs(ex[1]) > 1e-12 or abs(abs(ex[2]) - 1.0) > 1e-12:
        raise FileFormatError(f"entity is not in the XY plane (extrusion {ex}); only planar "
                              "drawings in XY can be imported", path=where)
    return 1.0 if ex[2] > 0 else -1.0


def _finite(where, what, *values):
    if not all(math.isfinite(v) for v in values):
        raise FileFormatError(f"{what} ({', '.join(f'{v:.10g}' for v in values)}) is not "
                              "finite; expected finite numbers", path=where)


def _entity_edges(e, k: float, where: str, join_rel: float) -> list:
    """Edges of one entity, lengths scaled by ``k`` (empty for skipped types).

    Entities with extrusion (0, 0, -1) are mirrored in x (their object coordinate
    system), which also reverses the sense of arcs and bulges.  Non-finite numbers
    and bulges whose arc cannot be represented are a FileFormatError naming
    ``where`` (layer and entity handle) and, for polylines, the vertex.
    """
    t = e.dxftype()
    if t == "LINE":
        s, f = e.dxf.start, e.dxf.end
        p, q = (k * s.x, k * s.y), (k * f.x, k * f.y)
        _finite(where, "start point", *p)
        _finite(where, "end point", *q)
        if p == q:
            return []
        return [_Edge(p, q, where=where)]
    if t in ("ARC", "CIRCLE"):
        sg = _extrusion_sign(e, where)
        c = e.dxf.center
        cx, cy, r = sg * k * c.x, k * c.y, k * e.dxf.radius
        _finite(where, "center and radius", cx, cy, r)
        if t == "CIRCLE":
            arc = Arc((cx, cy), r, 0.0, 2 * math.pi, True)
        else:
            a0, a1 = math.radians(e.dxf.start_angle), math.radians(e.dxf.end_angle)
            _finite(where, "start and end angles", a0, a1)
            if sg < 0:   # mirrored: the arc runs clockwise from pi - a0 to pi - a1
                arc = Arc((cx, cy), r, math.pi - a0, math.pi - a1, False)
            else:
                arc = Arc((cx, cy), r, a0, a1, True)
        sp, ep = arc.start_point, arc.end_point
        return [_Edge((float(sp[0]), float(sp[1])), (float(ep[0]), float(ep[1])), arc,
                      where=where)]
    if t == "LWPOLYLINE":
        sg = _extrusion_sign(e, where)
        pts = [(float(sg * k * x), float(k * y), float(sg * b)) for x, y, b in e.get_points("xyb")]
        n = len(pts)
        for i, (x, y, b) in enumerate(pts):
            _finite(f"{where}, vertex {i}", "coordinates", x, y)
        edges = n if e.closed else n - 1
        limit = _bulge_limit(join_rel)
        out = []
        for i in range(edges):
            x0, y0, b = pts[i]
            x1, y1, _ = pts[(i + 1) % n]
            p, q = (x0, y0), (x1, y1)
            if not math.isfinite(b):
                raise FileFormatError(
                    f"bulge {b} of the edge to vertex {(i + 1) % n} is not finite; expected a "
                    "finite number (bulge = tan(sweep / 4), 0 for a straight edge)",
                    path=f"{where}, vertex {i}")
            if p == q:
                continue
            if b == 0:
                out.append(_Edge(p, q, where=f"{where}, vertex {i}"))
                continue
            if abs(b) > limit:
                sweep = 4.0 * math.degrees(math.atan(abs(b)))
                raise FileFormatError(
                    f"bulge {b:.6g} of the edge {_fmt(p)} to {_fmt(q)} (vertex {(i + 1) % n}) "
                    f"makes an arc of {sweep:.12g} deg, a full circle to within the join "
                    f"tolerance (its end points are closer than {join_rel:g} of its size); "
                    f"expected |bulge| < {limit:.4g} (bulge = tan(sweep / 4), 1 for a half "
                    "circle)", path=f"{where}, vertex {i}")
            sagitta = 0.5 * abs(b) * math.hypot(x1 - x0, y1 - y0)
            out.append(_Edge(p, q, bulge=b, sagitta=sagitta, where=f"{where}, vertex {i}"))
        return out
    if t in _SKIPPED:
        return []
    raise FileFormatError(f"entity type {t} is not supported on a part layer; supported: "
                          f"{', '.join(_SUPPORTED)} (annotation types are skipped)", path=where)


def _edge_key(e: _Edge) -> tuple:
    """What makes two edges the same edge: their end points in either order,
    and for an arc its centre, radius and the side its middle lies on (a
    copy pasted in place has the same numbers)."""
    ends = tuple(sorted((tuple(e.p), tuple(e.q))))
    if e.arc is None:
        return ("line", ends, round(e.bulge, 12))
    a = e.arc
    mid = a.point_at(a.mid_angle)
    return ("arc", ends, tuple(a.center), a.radius,
            tuple(round(float(v - c) / a.radius, 9) for v, c in zip(mid, a.center)))


def _refuse_duplicates(edges: list) -> None:
    """A FileFormatError naming both entities where a layer holds the same edge
    twice (a copy pasted in place; the outline would otherwise be refused as
    three segment ends meeting at a point, or two loops meeting)."""
    seen: dict = {}
    for e in edges:
        key = _edge_key(e)
        first = seen.setdefault(key, e)
        if first is not e:
            ends = f"from ({e.p[0]:.6g}, {e.p[1]:.6g}) to ({e.q[0]:.6g}, {e.q[1]:.6g})"
            if e.arc is None:
                what = f"line {ends}"
            else:
                a = e.arc
                what = (f"{'circle' if a.is_full_circle else 'arc'} about "
                        f"({a.center[0]:.6g}, {a.center[1]:.6g}), radius {a.radius:.6g}"
                        + ("" if a.is_full_circle else f", {ends}"))
            raise FileFormatError(
                f"the same {what} as {first.where.split(': ', 1)[-1]} (a duplicate, often a "
                f"copy pasted in place); expected each edge of the layer's outline once: "
                f"delete one of them", path=e.where)


def _made(where: str, fn, *args, what: str = ""):
    """``fn(*args)`` with its errors naming ``where`` (layer, entity, vertex): an
    invalid-geometry error keeps its type, a value the geometry refuses is a
    FileFormatError (after ``what``)."""
    try:
        return fn(*args)
    except DegenerateGeometryError as err:
        raise type(err)(f"{where}: {err}", where=where) from None
    except InputError as err:
        raise FileFormatError(f"{what}{err}", path=where) from None


def _layer_pieces(edges: list, layer: str, join_rel: float):
    """Segments of a layer and its join tolerance (model units).

    Two tolerances are used.  ``tol0`` is ``join_rel`` times the size of the
    geometry the drawing states (vertices, lines, ARC and CIRCLE entities): a
    polyline edge whose arc rises no more than ``tol0`` above its chord is straight,
    and a segment no longer than ``tol0`` is round-off and is dropped (its end
    points are one vertex, as in CAD).  The join tolerance is ``join_rel`` times
    the bounding-box diagonal of all segments, bulged arcs included; a segment
    longer than ``tol0`` but not than that is an error, as its end points would be
    joined: bulge arcs then dwarf the rest of the drawing.
    """
    explicit = [ed.arc.bounds() if ed.arc is not None else ed.chord_bounds() for ed in edges]
    tol0 = join_rel * bounds_diagonal(explicit)
    segs = []
    for ed in edges:
        if ed.arc is not None:
            segs.append(dataclasses.replace(ed.arc, name=_segment_name(ed.where)))
        elif ed.sagitta is not None and ed.sagitta > tol0:
            segs.append(_made(ed.where, _bulge_arc, ed.p, ed.q, ed.bulge,
                              _segment_name(ed.where),
                              what=f"bulge {ed.bulge!r} makes no valid arc: "))
        else:
            segs.append(None)              # a straight edge
    bounds = np.array([s.bounds() if s is not None else ed.chord_bounds()
                       for s, ed in zip(segs, edges)])
    size = bounds_diagonal(bounds)
    if not math.isfinite(size):
        raise FileFormatError(f"the extent of the geometry overflows ({size}); expected "
                              "coordinates well within the range of floating point numbers",
                              path=f"layer {layer!r}")
    tol = join_rel * size
    pieces = []
    for s, ed in zip(segs, edges):
        if s is None:
            length = math.hypot(ed.q[0] - ed.p[0], ed.q[1] - ed.p[1])
        else:
            length = math.inf if s.is_full_circle else s.length
        if length <= tol0:
            continue
        if length <= tol:
            arcs = [k for k, e in enumerate(edges) if e.sagitta is not None and segs[k]]
            big = max(arcs, key=lambda k: bounds_diagonal(bounds[k]), default=None)
            why = "" if big is None else (
                f"; the layer is that large because bulge {edges[big].bulge:.6g} at "
                f"{edges[big].where} makes an arc of radius {segs[big].radius:.6g}")
            raise FileFormatError(
                f"a segment from {_fmt(ed.p)} to {_fmt(ed.q)} of length {length:.6g} is no "
                f"longer than the join tolerance {tol:.3g} ({join_rel:g} of the layer size "
                f"{size:.6g}), so its end points would be joined{why}; expected bulge arcs "
                "of about the drawing's size", path=ed.where)
        if s is None:
            s = _made(ed.where, Line, ed.p, ed.q, _segment_name(ed.where))
        pieces.append(_Piece(s, ed.where))
    return pieces, tol


def _fmt(p):
    return "(" + ", ".join(f"{float(v):.10g}" for v in p) + ")"


_WHERE = re.compile(r"layer '(?P<layer>.*)': (?P<type>\w+) #(?P<handle>[^,]*)"
                    r"(?:, vertex (?P<vertex>\d+))?$")


def _segment_name(where: str) -> str:
    """A segment's name from where it was read: layer, entity type and handle,
    and the vertex of a polyline, e.g. ``cam.LWPOLYLINE#2F.3``; it labels the
    contact curves of the segment (``cspace.contact``)."""
    m = _WHERE.match(where)
    if not m:
        return where
    name = f"{m['layer']}.{m['type']}#{m['handle']}"
    return name + (f".{m['vertex']}" if m["vertex"] is not None else "")


def _chain(pieces: list, layer: str, tol: float) -> list:
    """Closed chains of segments (each a list of segments) from an unordered pool.

    Segments are reversed as needed.  Where a line meets another segment within
    ``tol`` the line's end point is moved onto the other's, so each loop closes
    exactly; two arcs are left as drawn.  End points are found with a k-d tree,
    so chaining n segments takes O(n log n).
    """
    from scipy.spatial import cKDTree

    pool = []
    chains = []
    for pc in pieces:
        if isinstance(pc.seg, Arc) and pc.seg.is_full_circle:
            chains.append([pc.seg])
        else:
            pool.append(pc.seg)
    if not pool:
        return chains
    # ends[2 i] is the start point of pool[i], ends[2 i + 1] its end point
    ends = np.array([(s.start_point, s.end_point) for s in pool]).reshape(-1, 2)
    tree = cKDTree(ends)
    reach = tol * (1.0 + 1e-9)     # candidates for the exact test below
    free = np.ones(len(pool), dtype=bool)
    first = 0
    while True:
        while first < len(pool) and not free[first]:
            first += 1
        if first == len(pool):
            break
        free[first] = False
        chain = [pool[first]]
        start = chain[0].start_point
        while True:
            end = chain[-1].end_point
            if np.hypot(*(end - start)) <= tol and (len(chain) > 1 or isinstance(chain[0], Arc)):
                break
            near = tree.query_ball_point(end, reach, return_sorted=True)
            cands = [(m // 2, m % 2 == 1) for m in near
                     if free[m // 2] and np.hypot(*(ends[m] - end)) <= tol]
            if not cands:
                pts = np.vstack([start[None, :], ends[np.repeat(free, 2)]])
                gaps = np.hypot(pts[:, 0] - end[0], pts[:, 1] - end[1])
                j = int(np.argmin(gaps))
                gap = float(gaps[j])
                err = OpenLoopError(
                    f"layer {layer!r}: the outline is open: a chain of {len(chain)} segment(s) "
                    f"starting at {_fmt(start)} ends at {_fmt(end)}; the nearest free end point "
                    f"is {_fmt(pts[j])}, gap {gap:.6g} > join tolerance {tol:.3g}",
                    where=layer)
                err.layer, err.gap, err.point = layer, gap, tuple(float(v) for v in end)
                raise err
            if len({i for i, _ in cands}) > 1:
                raise FileFormatError(
                    f"{len(cands) + 1} segment ends meet at {_fmt(end)}; a part outline must "
                    "be a set of simple closed loops (no branches)", path=f"layer {layer!r}")
            i, flip = cands[0]
            free[i] = False
            chain.append(pool[i].reversed() if flip else pool[i])
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
    return [lp if lp.is_ccw == (d % 2 == 0) else lp.reversed()
            for lp, d in zip(loops, nesting_depths(loops))]


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


def _refuse_blocks_on_part_layers(doc, msp, parts, path) -> None:
    """A FileFormatError when a block reference (INSERT) placed on a layer that
    is no part's holds entities on a part's layer: blocks are not read, and
    the part would be imported without them (a hole, or the whole outline,
    missing).  An INSERT on a part's layer is refused as an unsupported
    entity of that layer."""
    want = {str(sp.get("layer", "")).lower() for sp in parts if isinstance(sp, dict)}
    for e in msp:
        if e.dxftype() != "INSERT" or _entity_layer(e, path) in want:
            continue
        name = e.dxf.get("name", "?")
        try:
            block = doc.blocks.get(name)
        except (LookupError, AttributeError, TypeError, ValueError):
            block = None
        if block is None:
            continue
        hit = sorted({_entity_layer(b, path, fold=False) for b in block
                      if _entity_layer(b, path) in want})
        if hit:
            raise FileFormatError(
                f"block {name!r} (INSERT #{e.dxf.get('handle', '?')} on layer "
                f"{_entity_layer(e, path, fold=False)!r}) holds entities on the part layer(s) "
                f"{hit}; blocks are not read, so the part would be imported without them: "
                f"explode the block in the CAD program (EXPLODE) and save the drawing again",
                path=f"{path}")


def _entity_layer(e, path, fold: bool = True) -> str:
    """The layer name of a modelspace entity (lower case with ``fold``).

    An entity type ezdxf does not know keeps its layer only among its raw group
    codes (code 8); an entity without any layer is a FileFormatError.
    """
    try:
        layer = e.dxf.layer
    except AttributeError:
        layer = None
        for tags in getattr(getattr(e, "xtags", None), "subclasses", ())[:1]:
            layer = next((t.value for t in tags if t.code == 8), None)
    if not isinstance(layer, str):
        raise FileFormatError(f"{path}: entity {e.dxftype()} #{e.dxf.get('handle', '?')} "
                              f"has no layer (DXF group code 8); expected every drawing "
                              f"entity to name its layer")
    return layer.lower() if fold else layer


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
    except (StopIteration, ValueError, LookupError, TypeError, AttributeError, ArithmeticError,
            RecursionError, AssertionError) as e:
        # the reader's own failures on a truncated or corrupted file (an
        # OverflowError, for one, from "inf" where it expects an integer)
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
               param_mode: str = "all", join_rel: float = JOIN_REL, name: str | None = None,
               bias: int = 0, q2_start=None, drive=None, window=None, deviation=None):
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
        read with ``units="cm"`` is scaled by 0.1); aliases such as ``"inch"``
        or ``"millimetre"`` are known (:func:`cspace.io.canonical_unit`), and a
        unit the library does not know is a :class:`~cspace.io.UnitWarning`
        (coordinates are then taken as they stand).  Axis coordinates are taken
        in ``units``: a rotation centre or translation origin more than
        :data:`FAR_AXIS` times the drawing's size away from it is an
        :class:`AxisWarning` (most often coordinates in the drawing's unit).
    tol : float, optional
        If given, return a Model in which every dimension is a parameter with
        this tolerance (model units); see :func:`mechanisms.dimensions.parametric_model`.
    param_mode : {"all", "profile"}
        With ``tol``: also make rotation centres parameters (``"all"``) or not.
    join_rel : float
        End-point matching tolerance relative to the layer size (:data:`JOIN_REL`).
    name : str, optional
        Pair name (default: the file name without suffix).
    bias : {0, -1, 1}
        The follower's closure (:attr:`cspace.geometry.Pair.bias`): 0 form
        closure (the default), -1 or +1 held toward decreasing or increasing
        q2 (a spring, gravity); a drawing does not say.
    q2_start, drive, window, deviation : optional
        With ``tol``: the model's operating point, as the ``import-dxf``
        options ``--q2-start``, ``--drive``, ``--window`` and ``--deviation``
        and the :class:`~mechanisms.models.Model` fields of the same names:
        the follower start at ``drive[0]`` (one number, or one per pair), the
        driver range ``(q1_start, q1_end)``, the C-space window ``(q1_lo,
        q1_hi, q2_lo, q2_hi)`` (rad for a rotating part, model units
        ``units`` for a sliding one) and the output-deviation threshold d
        (C-space metric).  The window is checked against the parts (a
        rotating follower's spans exactly 2 pi).  A Pair holds no operating
        point: without ``tol`` they are an InputError (write them into a pair
        file with :func:`cspace.io.save_pair`, ``motion=``).

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
    motion = {k: v for k, v in (("q2_start", q2_start), ("drive", drive), ("window", window),
                                ("deviation", deviation)) if v is not None}
    if motion and tol is None:
        raise InputError(f"{', '.join(motion)} given without tol: a Pair holds no operating "
                         f"point; pass tol= for a Model that holds it (dxf_to_model), or "
                         f"write it into a pair file with cspace.io.save_pair(pair, path, "
                         f"motion={{...}})", name=next(iter(motion)), value=motion)
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
    cu = canonical_unit(units)
    if fu is not None and units != fu and cu is None:
        raise InputError(f"cannot convert the drawing's {fu} to {units!r}; units must be one "
                         f"of {known_units_text()}, or the drawing's own unit", name="units",
                         value=units)
    if fu is None and cu is None:
        check_units(units, "units")
    m = LENGTH_UNITS       # metres per unit
    k = m[fu] / m[cu] if fu in m and cu in m else 1.0

    by_layer = {}
    try:
        msp = list(doc.modelspace())
    except (LookupError, AttributeError, TypeError, ValueError) as e:
        raise FileFormatError(f"{path} is not a valid DXF file (damaged: its model space "
                              f"cannot be read, {type(e).__name__}: {e})") from None
    for e in msp:
        by_layer.setdefault(_entity_layer(e, path), []).append(e)
    _refuse_blocks_on_part_layers(doc, msp, parts, path)
    names = [sp.get("name") for sp in parts if isinstance(sp, dict)]
    if len(names) == 2 and names[0] == names[1]:
        # a pair file needs them apart (cspace.io.load_pair refuses it)
        raise InputError(f"the driver and the follower need different names, both are "
                         f"{names[0]!r}; name each part after what it is (e.g. cam and "
                         f"follower)", name="parts", value=names[0])
    built, boxes = [], []
    for i, spec in enumerate(parts):
        if not isinstance(spec, dict) or not {"layer", "name", "axis"} <= set(spec):
            raise InputError(f"parts[{i}] must be a mapping with 'layer', 'name' and 'axis', "
                             f"got {spec!r}", name="parts", value=spec)
        layer = str(spec["layer"])
        if i == 1 and layer.lower() == str(parts[0]["layer"]).lower():
            raise InputError(f"the driver and the follower are both read from layer "
                             f"{layer!r} (layers match case-insensitively); each part needs "
                             f"a layer of its own: draw one part per layer", name="parts",
                             value=layer)
        ents = by_layer.get(layer.lower())
        if not ents:
            raise FileFormatError(f"layer {layer!r} has no entities; layers in the drawing: "
                                  f"{sorted({_entity_layer(e, path, fold=False) for v in by_layer.values() for e in v})}",
                                  path=f"parts[{i}].layer")
        edges = []
        for e in ents:
            where = f"layer {layer!r}: {e.dxftype()} #{e.dxf.get('handle', '?')}"
            try:
                edges += _made(where, _entity_edges, e, k, where, join_rel)
            except (AttributeError, TypeError, ValueError) as err:
                if isinstance(err, CSpaceError):
                    raise
                # an entity damaged past ezdxf's own repair (an attribute missing
                # or of the wrong type)
                raise FileFormatError(f"entity is damaged ({type(err).__name__}: {err}); "
                                      f"expected a complete {e.dxftype()} entity",
                                      path=where) from None
        _refuse_duplicates(edges)
        pieces, join_tol = _layer_pieces(edges, layer, join_rel) if edges else ([], 0.0)
        if not pieces:
            raise FileFormatError(f"layer {layer!r} holds no {'/'.join(_SUPPORTED)} geometry",
                                  path=f"parts[{i}].layer")
        boxes.append(bounds_of([pc.seg for pc in pieces]))
        chains = _chain(pieces, layer, join_tol)
        try:
            loops = _orient([Loop(tuple(c)) for c in chains])
            built.append(Part(spec["name"], tuple(loops), _axis(spec["axis"], f"parts[{i}].axis")))
        except DegenerateGeometryError as err:
            raise type(err)(f"layer {layer!r}: {err}", where=layer) from None
    _far_axes(built, parts, boxes, units, fu, k)
    pair = Pair(built[0], built[1], units, name or Path(path).stem, bias=bias)
    if tol is None:
        return pair
    from .dimensions import parametric_model
    model = parametric_model(pair, tol, param_mode=param_mode)
    if not motion:
        return model
    if "window" in motion:
        from cspace.contact import _check_window
        _check_window(pair, motion["window"])
    import dataclasses
    return dataclasses.replace(model, **motion)


def _far_axes(built, specs, boxes, units: str, fu, k: float) -> None:
    """An :class:`AxisWarning` per part whose rotation centre (or translation
    origin other than (0, 0)) lies more than :data:`FAR_AXIS` times the
    drawing's size (the diagonal of the bounding box ``boxes`` of both parts)
    from that box; with a drawing converted by the factor ``k`` from its unit
    ``fu`` to ``units``, it suggests the coordinates in ``units``."""
    import warnings
    b = np.asarray(boxes, dtype=float).reshape(-1, 4)
    x0, y0, x1, y1 = b[:, 0].min(), b[:, 1].min(), b[:, 2].max(), b[:, 3].max()
    size = bounds_diagonal(b)
    if not (math.isfinite(size) and size > 0):
        return
    for part, spec in zip(built, specs):
        ax = part.axis
        if isinstance(ax, Rotation):
            what, pt = "rotation centre", ax.center
        else:
            what, pt = "translation origin", ax.origin
            if pt[0] == 0 and pt[1] == 0:     # the default; it marks no place
                continue
        dist = math.hypot(max(x0 - pt[0], 0.0, pt[0] - x1), max(y0 - pt[1], 0.0, pt[1] - y1))
        if not dist > FAR_AXIS * size:
            continue
        if k != 1.0:
            hint = (f"; axis coordinates are taken in the target unit {units!r}, and these "
                    f"are probably in the drawing's unit {fu!r}: in {units!r} that point is "
                    f"{_fmt((pt[0] * k, pt[1] * k))}")
        else:
            hint = f"; check its coordinates (axis coordinates are taken in {units!r})"
        warnings.warn(f"part {part.name!r} (layer {spec.get('layer')!r}): its {what} "
                      f"{_fmt(pt)} lies {dist:.6g} {units} from the drawing, more than "
                      f"{FAR_AXIS:g} times the drawing's size ({size:.6g} {units}){hint}",
                      AxisWarning, stacklevel=3)


def dxf_to_model(path, *, parts, tol: float, units: str | None = None,
                 param_mode: str = "all", join_rel: float = JOIN_REL, name: str | None = None,
                 bias: int = 0, q2_start=None, drive=None, window=None, deviation=None):
    """A parametric Model from a DXF drawing: every vertex coordinate (and, with
    ``param_mode="all"``, every rotation centre) is a parameter of tolerance
    ``tol``, with the operating point ``q2_start``, ``drive``, ``window`` and
    ``deviation`` when given.  Same arguments as :func:`import_dxf`; save the result with
    :func:`mechanisms.userfile.save_model`."""
    if tol is None:
        raise InputError("dxf_to_model needs a tolerance tol (model units)", name="tol")
    return import_dxf(path, parts=parts, units=units, tol=tol, param_mode=param_mode,
                      join_rel=join_rel, name=name, bias=bias, q2_start=q2_start,
                      drive=drive, window=window, deviation=deviation)


# ---------------------------------------------------------------------- export

def _layer_name(s: str) -> str:
    out = "".join("_" if ch in _BAD_LAYER_CHARS or ord(ch) < 32 else ch for ch in s)
    return out or "_"


def part_layers(built) -> list:
    """``(part, name, layer)`` of every part of a built Pair or Assembly, in
    order: its name (``pair.part`` in an assembly) and the DXF layer
    :func:`export_dxf` writes it on (the name with the characters a layer
    name cannot hold replaced)."""
    multi = isinstance(built, Assembly)
    out = []
    for pair in (built.pairs if multi else (built,)):
        for part in pair.parts:
            name = f"{pair.name}.{part.name}" if multi else part.name
            out.append((part, name, _layer_name(name)))
    return out


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
    The unit goes into ``$INSUNITS`` when it is one of :data:`INSUNITS` or an
    alias of one (``"inch"``, ``"millimetre"``, :func:`cspace.io.canonical_unit`);
    any other unit is written unitless (``$INSUNITS = 0``, never ezdxf's default
    of metres) with a :class:`~cspace.io.UnitWarning`.
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
    doc = ezdxf.new(dxfversion)
    cu = canonical_unit(built.units)
    if cu in INSUNITS:
        doc.header["$INSUNITS"] = INSUNITS[cu]
        doc.header["$MEASUREMENT"] = 0 if cu in ("in", "ft", "mi", "yd", "mil", "uin") else 1
    else:
        # never ezdxf's default (metres) for a unit it cannot name: unitless
        doc.header["$INSUNITS"] = 0
        import warnings
        warnings.warn(f"export_dxf: length unit {built.units!r} has no DXF unit code, so the "
                      f"drawing is written unitless ($INSUNITS = 0) and its coordinates as "
                      f"they stand; units with a code: {known_units_text()}", UnitWarning,
                      stacklevel=2)
    msp = doc.modelspace()
    seen = set()
    for part, _, layer in part_layers(built):
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
