"""DXF import/export: chaining, orientation, bulges, units, errors, round trips."""

import math
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

ezdxf = pytest.importorskip("ezdxf")

from cspace.errors import (FileFormatError, InputError, MissingExtraError, OpenLoopError,
                           SelfIntersectionError)
from cspace.geometry import Arc, Pair, Rotation, Translation
from mechanisms.analysis import model_cspaces
from mechanisms.dxf import dxf_to_model, export_dxf, import_dxf
from mechanisms.models import geneva, optical_filter, reciprocating_cam
from mechanisms.userfile import load_model, model_to_dict, save_model


def parts_of(pair):
    return [{"layer": p.name, "name": p.name, "axis": p.axis} for p in pair.parts]


def segment_key(s, scale):
    """Comparable description of a segment independent of its direction."""
    pts = sorted([tuple(np.round(s.start_point / scale, 9)), tuple(np.round(s.end_point / scale, 9))])
    if isinstance(s, Arc):
        return ("arc", tuple(pts), tuple(np.round(np.array(s.center) / scale, 9)),
                round(s.radius / scale, 9))
    return ("line", tuple(pts))


def assert_same_geometry(a: Pair, b: Pair):
    """Same loops (as sets of segments), end points and arcs to 1e-9 relative."""
    scale = a.size
    for pa, pb in zip(a.parts, b.parts):
        assert pa.name == pb.name and pa.axis == pb.axis
        assert sorted(len(lp.segments) for lp in pa.loops) == \
            sorted(len(lp.segments) for lp in pb.loops)
        sa = [s for lp in pa.loops for s in lp.segments]
        sb = [s for lp in pb.loops for s in lp.segments]
        unmatched = list(sb)
        for s in sa:
            hit = [t for t in unmatched if t.kind == s.kind and _close(s, t, scale)]
            assert hit, f"segment {s} of {pa.name} not found after the round trip"
            unmatched.remove(hit[0])
        # material side kept: same signed areas per part
        assert_allclose(sorted(lp.area for lp in pa.loops), sorted(lp.area for lp in pb.loops),
                        rtol=1e-9)


def _close(s, t, scale):
    tol = 1e-9 * scale
    fw = (np.hypot(*(s.start_point - t.start_point)) <= tol
          and np.hypot(*(s.end_point - t.end_point)) <= tol)
    bw = (np.hypot(*(s.start_point - t.end_point)) <= tol
          and np.hypot(*(s.end_point - t.start_point)) <= tol)
    if not (fw or bw):
        return False
    if isinstance(s, Arc):
        return (np.hypot(*(np.subtract(s.center, t.center))) <= tol
                and abs(s.radius - t.radius) <= tol and abs(s.sweep - t.sweep) <= 1e-9)
    return True


@pytest.mark.parametrize("factory", [geneva, reciprocating_cam])
def test_builtin_round_trip(factory, tmp_path):
    m = factory()
    pair = m.build()
    path = export_dxf(m, tmp_path / "m.dxf")
    back = import_dxf(path, parts=parts_of(pair))
    assert back.units == "cm"
    assert_same_geometry(pair, back)
    a = model_cspaces(pair, accuracy="fast", window=m.window)[0].stats
    b = model_cspaces(back, accuracy="fast", window=m.window)[0].stats
    assert a == b


def test_export_layers_entities_units_and_params(tmp_path):
    m = reciprocating_cam()
    export_dxf(m, tmp_path / "a.dxf")
    doc = ezdxf.readfile(tmp_path / "a.dxf")
    assert doc.header["$INSUNITS"] == 5
    msp = doc.modelspace()
    assert {e.dxf.layer for e in msp} == {"cam", "yoke"}
    kinds = sorted(e.dxftype() for e in msp.query('*[layer=="cam"]'))
    assert kinds == ["ARC"] * 6 + ["LINE"] * 6
    g = export_dxf(geneva(), tmp_path / "g.dxf")
    assert len(ezdxf.readfile(g).modelspace().query("CIRCLE")) == 1
    # a parameter vector moves the drawing
    new_xr_t = m.values()["xr_t"] + 0.05
    export_dxf(m, tmp_path / "b.dxf", {"xr_t": new_xr_t})
    pr = parts_of(m.build())
    a = import_dxf(tmp_path / "a.dxf", parts=pr)
    b = import_dxf(tmp_path / "b.dxf", parts=pr)
    xa = max(lp.bounds()[2] for lp in a.follower.loops[1:])
    xb = max(lp.bounds()[2] for lp in b.follower.loops[1:])
    assert_allclose(xa, max(m.values()["xr_t"], m.values()["xr_b"]), atol=1e-12)
    assert_allclose(xb, new_xr_t, atol=1e-12)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.dxf", "b.dxf", "g.dxf"]
    with pytest.raises(InputError, match="params apply only"):
        export_dxf(m.build(), tmp_path / "c.dxf", {"xr_t": new_xr_t})
    with pytest.raises(InputError, match="Pair, Assembly or Model"):
        export_dxf("geneva", tmp_path / "c.dxf")


def test_export_is_atomic(tmp_path, monkeypatch):
    target = tmp_path / "keep.dxf"
    target.write_text("old")

    def boom(self, *a, **k):
        raise RuntimeError("disk full")
    monkeypatch.setattr(ezdxf.document.Drawing, "write", boom)
    with pytest.raises(RuntimeError):
        export_dxf(reciprocating_cam(), target)
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.dxf"]


def test_assembly_export_prefixes_pair_names(tmp_path):
    m = optical_filter()
    export_dxf(m, tmp_path / "o.dxf")
    layers = {e.dxf.layer for e in ezdxf.readfile(tmp_path / "o.dxf").modelspace()}
    assert layers == {f"filter{k}.{r}{k}" for k in (1, 2, 3) for r in ("cam", "follower")}
    p2 = m.build().pairs[1]
    back = import_dxf(tmp_path / "o.dxf", parts=[
        {"layer": "filter2.cam2", "name": "cam2", "axis": p2.driver.axis},
        {"layer": "FILTER2.follower2", "name": "follower2", "axis": p2.follower.axis}])
    assert_same_geometry(p2, back)


# ------------------------------------------------------------------ hand-made drawings

def plate_drawing(path, *, gap=0.0, reverse_hole=True, shuffle=True):
    """Driver: a 40 x 20 plate with one rounded end (LINEs and an ARC, shuffled and
    partly reversed) and a slot-shaped hole (closed LWPOLYLINE with bulges).
    Follower: a circle (CIRCLE) on layer 'pin'."""
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    A = {"layer": "Plate"}
    ents = [
        lambda: msp.add_line((40, 20), (0, 20), dxfattribs=A),       # top, leftwards
        lambda: msp.add_line((0, 0), (0, 20), dxfattribs=A),         # left, reversed
        lambda: msp.add_arc((40, 10), 10, -90, 90, dxfattribs=A),    # right end, ccw
        lambda: msp.add_line((0 + gap, 0), (40, 0), dxfattribs=A),   # bottom
    ]
    order = [2, 0, 3, 1] if shuffle else [3, 2, 0, 1]
    for i in order:
        ents[i]()
    hole = [(10, 8, 0), (25, 8, 1), (25, 12, 0), (10, 12, 1)]        # ccw as drawn
    if reverse_hole:
        hole = [(10, 8, -1), (10, 12, 0), (25, 12, -1), (25, 8, 0)]  # cw as drawn
    msp.add_lwpolyline(hole, format="xyb", close=True, dxfattribs=A)
    msp.add_text("PLATE", dxfattribs=A)
    msp.add_circle((70, 10), 5, dxfattribs={"layer": "pin"})
    doc.saveas(path)
    return path


PARTS = [{"layer": "plate", "name": "plate", "axis": {"type": "rotation", "center": [0, 10]}},
         {"layer": "pin", "name": "pin", "axis": Translation((-1, 0))}]


@pytest.mark.parametrize("reverse_hole", [True, False])
@pytest.mark.parametrize("shuffle", [True, False])
def test_chaining_orientation_and_bulges(tmp_path, reverse_hole, shuffle):
    f = plate_drawing(tmp_path / "p.dxf", reverse_hole=reverse_hole, shuffle=shuffle)
    pair = import_dxf(f, parts=PARTS)
    assert pair.units == "mm" and pair.name == "p"
    assert pair.driver.axis == Rotation((0.0, 10.0))
    outer, hole = pair.driver.loops
    assert outer.is_ccw and not hole.is_ccw
    assert [s.kind for s in outer.segments].count("arc") == 1 and len(outer.segments) == 4
    assert_allclose(outer.area, 40 * 20 + math.pi * 100 / 2, rtol=1e-12)
    assert [s.kind for s in hole.segments] == ["line", "arc", "line", "arc"] or \
        sorted(s.kind for s in hole.segments) == ["arc", "arc", "line", "line"]
    assert_allclose(hole.area, -(15 * 4 + math.pi * 4), rtol=1e-12)
    arcs = [s for s in hole.segments if isinstance(s, Arc)]
    assert_allclose(sorted(a.center[0] for a in arcs), [10, 25], atol=1e-12)
    assert all(not a.ccw for a in arcs)          # concave, on a hole
    (circle,) = pair.follower.loops[0].segments
    assert circle.is_full_circle and circle.center == (70.0, 10.0) and circle.radius == 5.0
    assert pair.driver.contains((5, 5)) and not pair.driver.contains((15, 10))


def test_small_gaps_are_joined_exactly(tmp_path):
    f = plate_drawing(tmp_path / "g.dxf", gap=40 * 1e-8)
    outer = import_dxf(f, parts=PARTS).driver.loops[0]
    segs = outer.segments
    for a, b in zip(segs, segs[1:] + segs[:1]):
        assert tuple(a.end_point) == tuple(b.start_point) or isinstance(a, Arc) \
            or isinstance(b, Arc)


def test_open_outline_names_layer_and_gap(tmp_path):
    f = plate_drawing(tmp_path / "o.dxf", gap=0.5)
    with pytest.raises(OpenLoopError, match="layer 'plate'.*gap 0.5") as ei:
        import_dxf(f, parts=PARTS)
    assert ei.value.layer == "plate" and ei.value.where == "plate"
    assert_allclose(ei.value.gap, 0.5, atol=1e-12)
    with pytest.raises(OpenLoopError):
        import_dxf(f, parts=PARTS, join_rel=1e-3)     # 0.5 mm > 1e-3 x 49 mm
    assert len(import_dxf(f, parts=PARTS, join_rel=0.0099).driver.loops) == 2


def test_branch_unsupported_entity_and_layers(tmp_path):
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    for a, b in [((0, 0), (1, 0)), ((1, 0), (1, 1)), ((1, 1), (0, 0)), ((1, 0), (2, 0))]:
        msp.add_line(a, b, dxfattribs={"layer": "T"})
    msp.add_spline([(0, 0), (1, 1), (2, 0)], dxfattribs={"layer": "S"})
    msp.add_circle((5, 5), 1, dxfattribs={"layer": "C"})
    doc.saveas(tmp_path / "b.dxf")
    ax = Rotation()
    with pytest.raises(FileFormatError, match="segment ends meet"):
        import_dxf(tmp_path / "b.dxf", parts=[{"layer": "T", "name": "t", "axis": ax},
                                             {"layer": "C", "name": "c", "axis": ax}])
    with pytest.raises(FileFormatError, match="SPLINE is not supported") as ei:
        import_dxf(tmp_path / "b.dxf", parts=[{"layer": "S", "name": "s", "axis": ax},
                                             {"layer": "C", "name": "c", "axis": ax}])
    assert "layer 'S'" in ei.value.path
    with pytest.raises(FileFormatError, match="layer 'nope' has no entities") as ei:
        import_dxf(tmp_path / "b.dxf", parts=[{"layer": "nope", "name": "s", "axis": ax},
                                             {"layer": "C", "name": "c", "axis": ax}])
    assert ei.value.path == "parts[0].layer"
    with pytest.raises(InputError, match="exactly 2 parts"):
        import_dxf(tmp_path / "b.dxf", parts=[{"layer": "C", "name": "c", "axis": ax}])
    with pytest.raises(InputError, match="axis must be"):
        import_dxf(tmp_path / "b.dxf", parts=[{"layer": "C", "name": "c", "axis": (0, 0)},
                                             {"layer": "C", "name": "d", "axis": ax}])


def test_crossing_loops_are_reported(tmp_path):
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    msp.add_circle((0, 0), 2, dxfattribs={"layer": "A"})
    msp.add_circle((1, 0), 2, dxfattribs={"layer": "A"})
    msp.add_circle((9, 0), 1, dxfattribs={"layer": "B"})
    doc.saveas(tmp_path / "x.dxf")
    with pytest.raises(SelfIntersectionError, match="layer 'A'"):
        import_dxf(tmp_path / "x.dxf", parts=[{"layer": "A", "name": "a", "axis": Rotation()},
                                             {"layer": "B", "name": "b", "axis": Rotation()}])


def test_units_header_and_conversion(tmp_path):
    f = plate_drawing(tmp_path / "p.dxf")
    cm = import_dxf(f, parts=PARTS, units="cm")
    assert cm.units == "cm"
    assert_allclose(cm.driver.loops[0].area, (40 * 20 + math.pi * 50) / 100, rtol=1e-12)
    doc = ezdxf.readfile(f)
    doc.header["$INSUNITS"] = 0
    doc.saveas(tmp_path / "u.dxf")
    with pytest.raises(FileFormatError, match="does not state its length unit"):
        import_dxf(tmp_path / "u.dxf", parts=PARTS)
    inch = import_dxf(tmp_path / "u.dxf", parts=PARTS, units="in")
    assert inch.units == "in" and inch.driver.loops[0].bounds()[2] == 50.0


def test_mirrored_extrusion_arc_and_polyline(tmp_path):
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    neg = {"layer": "A", "extrusion": (0, 0, -1)}
    # in OCS with extrusion -z, x is mirrored: this is the WCS half-disk x >= 0
    msp.add_arc((0, 0), 1, 90, 270, dxfattribs=neg)
    msp.add_line((0, -1), (0, 1), dxfattribs={"layer": "A"})
    msp.add_lwpolyline([(-5, 0, 0), (-7, 0, 1)], format="xyb", close=True,
                       dxfattribs={"layer": "B", "extrusion": (0, 0, -1)})
    doc.saveas(tmp_path / "m.dxf")
    p = import_dxf(tmp_path / "m.dxf", parts=[{"layer": "A", "name": "a", "axis": Rotation()},
                                             {"layer": "B", "name": "b", "axis": Rotation()}])
    x0, y0, x1, y1 = p.driver.loops[0].bounds()
    assert_allclose([x0, y0, x1, y1], [0, -1, 1, 1], atol=1e-12)
    assert_allclose(p.driver.loops[0].area, math.pi / 2, rtol=1e-12)
    assert_allclose(p.follower.loops[0].bounds(), [5, -1, 7, 0], atol=1e-12)


def test_bad_files(tmp_path):
    with pytest.raises(FileFormatError, match="no such file"):
        import_dxf(tmp_path / "none.dxf", parts=PARTS)
    (tmp_path / "bad.dxf").write_text("this is not a drawing\n")
    with pytest.raises(FileFormatError, match="not a valid DXF|cannot read"):
        import_dxf(tmp_path / "bad.dxf", parts=PARTS)


def test_missing_extra(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "ezdxf", None)
    with pytest.raises(MissingExtraError, match=r"cspace-tolerance\[dxf\]") as ei:
        export_dxf(reciprocating_cam(), tmp_path / "x.dxf")
    assert ei.value.module == "ezdxf" and ei.value.extra == "dxf"
    with pytest.raises(MissingExtraError):
        import_dxf(tmp_path / "x.dxf", parts=PARTS)


# ------------------------------------------------------------------ every dimension a parameter

def test_dxf_to_model_every_dimension(tmp_path):
    f = plate_drawing(tmp_path / "p.dxf")
    pair = import_dxf(f, parts=PARTS)
    m = dxf_to_model(f, parts=PARTS, tol=0.05)
    # 4 + 4 vertices on the plate, 2 (half circles) on the pin, 2 centre coordinates
    assert m.n == 2 * (4 + 4 + 2) + 2
    assert "plate_L0_P3_x" in m.names and "plate_axis_y" in m.names
    assert_allclose(m.tol, 0.05, atol=0)
    assert_same_geometry_nominal(pair, m.build())
    save_model(m, tmp_path / "m.json")
    m2 = load_model(tmp_path / "m.json")
    assert model_to_dict(m2) == model_to_dict(m)
    u = m.values()
    u["plate_axis_y"] += 0.05
    assert m.build(u).driver.axis == Rotation((0.0, 10.05))
    prof = import_dxf(f, parts=PARTS, tol=0.05, param_mode="profile")
    assert prof.n == m.n - 2
    with pytest.raises(InputError, match="tolerance"):
        dxf_to_model(f, parts=PARTS, tol=None)


def assert_same_geometry_nominal(pair, built):
    for pa, pb in zip(pair.parts, built.parts):
        for la, lb in zip(pa.loops, pb.loops):
            assert_allclose(la.area, lb.area, rtol=1e-12)
            assert_allclose(la.bounds(), lb.bounds(), atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(n=st.integers(3, 9), seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1e-3, 1.0, 1e4]))
def test_shuffled_reversed_polygon_chains_back(tmp_path_factory, n, seed, scale):
    """A random star-shaped polygon drawn as shuffled, randomly reversed LINEs and
    one bulged edge comes back as one counter-clockwise loop of the same area."""
    rng = np.random.default_rng(seed)
    # a jittered regular polygon: simple, with no corner sharp enough for the cap to cross
    ang = (np.arange(n) + rng.uniform(-0.2, 0.2, n)) * 2 * np.pi / n
    rad = rng.uniform(0.8, 1.0, n) * scale
    pts = np.c_[rad * np.cos(ang), rad * np.sin(ang)]
    edges = [(tuple(pts[i]), tuple(pts[(i + 1) % n])) for i in range(n)]
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    # the first edge bulges outwards by a small circular cap
    b = 0.1
    p, q = edges[0]
    for k in rng.permutation(n):
        a, c = edges[k]
        rev = bool(rng.integers(2))
        if k == 0:
            msp.add_lwpolyline([(*(c if rev else a), -b if rev else b), c if not rev else a],
                               format="xyb", dxfattribs={"layer": "P"})
        else:
            msp.add_line(*((c, a) if rev else (a, c)), dxfattribs={"layer": "P"})
    msp.add_circle((5 * scale, 0), 0.1 * scale, dxfattribs={"layer": "Q"})
    path = tmp_path_factory.mktemp("h") / "poly.dxf"
    doc.saveas(path)
    pair = import_dxf(path, parts=[{"layer": "P", "name": "p", "axis": Rotation()},
                                   {"layer": "Q", "name": "q", "axis": Rotation()}])
    (lp,) = pair.driver.loops
    assert lp.is_ccw and len(lp.segments) == n
    x, y = pts[:, 0], pts[:, 1]
    shoelace = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    chord = np.hypot(*np.subtract(q, p))
    theta = 4 * math.atan(b)
    r = chord / (2 * math.sin(theta / 2))
    cap = 0.5 * r * r * (theta - math.sin(theta))
    assert_allclose(lp.area, shoelace + cap, rtol=1e-9)


# ------------------------------------------------------------------ drawing noise and size

def _two_layer_doc():
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    msp.add_circle((50, 0), 1, dxfattribs={"layer": "Q"})
    return doc, msp


TWO = [{"layer": "P", "name": "p", "axis": Rotation()},
       {"layer": "Q", "name": "q", "axis": Rotation()}]


def test_rounding_level_bulge_is_a_straight_edge(tmp_path):
    """A bulge whose arc rises less than the join tolerance above its chord (CAD
    round-off on a straight edge) gives a line; a real bulge still gives an arc."""
    doc, msp = _two_layer_doc()
    msp.add_lwpolyline([(0, 0, 1e-12), (10, 0, 0), (10, 10, 0), (0, 10, 0.2)], format="xyb",
                       close=True, dxfattribs={"layer": "P"})
    doc.saveas(tmp_path / "n.dxf")
    (lp,) = import_dxf(tmp_path / "n.dxf", parts=TWO).driver.loops
    kinds = [s.kind for s in lp.segments]
    assert kinds.count("line") == 3 and kinds.count("arc") == 1


def test_near_full_circle_bulge_is_refused(tmp_path):
    """A bulge so large that its arc is a full circle to within the join tolerance
    is an error naming the vertex, not a loop with a huge arc."""
    doc, msp = _two_layer_doc()
    msp.add_lwpolyline([(0, 0, 0), (10, 0, 1e12), (10, 10, 0), (0, 10, 0)], format="xyb",
                       close=True, dxfattribs={"layer": "P"})
    doc.saveas(tmp_path / "b.dxf")
    with pytest.raises(FileFormatError, match=r"bulge 1e\+12.*full circle.*expected \|bulge\|") \
            as ei:
        import_dxf(tmp_path / "b.dxf", parts=TWO)
    assert "vertex 1" in ei.value.path


def test_non_finite_numbers_are_refused(tmp_path):
    doc, msp = _two_layer_doc()
    msp.add_lwpolyline([(0, 0, 0), (10, 0, float("nan")), (10, 10, 0)], format="xyb",
                       close=True, dxfattribs={"layer": "P"})
    doc.saveas(tmp_path / "nan.dxf")
    with pytest.raises(FileFormatError, match="bulge nan.*not finite"):
        import_dxf(tmp_path / "nan.dxf", parts=TWO)


def test_near_duplicate_vertex_is_dropped(tmp_path):
    """A polyline vertex repeated within rounding (a zero-length edge) is one vertex."""
    doc, msp = _two_layer_doc()
    msp.add_lwpolyline([(0, 0), (10, 0), (10, 1e-13), (10, 10), (0, 10)], close=True,
                       dxfattribs={"layer": "P"})
    doc.saveas(tmp_path / "d.dxf")
    (lp,) = import_dxf(tmp_path / "d.dxf", parts=TWO).driver.loops
    assert len(lp.segments) == 4
    assert_allclose(lp.area, 100.0, rtol=1e-12)


def _gear_outline(n):
    """A closed polyline of 2 n vertices, a saw-toothed ring, and a square hole."""
    t = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    r = np.where(np.arange(2 * n) % 2 == 0, 10.0, 9.5)
    return np.c_[r * np.cos(t), r * np.sin(t)]


@pytest.mark.parametrize("cross", [False, True])
def test_large_polyline_is_validated_by_boxes(tmp_path, cross):
    """A part of 1,200 segments is chained and validated (the pair checks go through
    the bounding-box pre-selection); a crossing deep inside it is still found."""
    pts = _gear_outline(600)
    if cross:
        pts[[300, 302]] = pts[[302, 300]]      # two tooth tips swapped: the loop crosses
    doc, msp = _two_layer_doc()
    msp.add_lwpolyline(pts.tolist(), close=True, dxfattribs={"layer": "P"})
    msp.add_lwpolyline([(-1, -1), (1, -1), (1, 1), (-1, 1)], close=True,
                       dxfattribs={"layer": "P"})
    doc.saveas(tmp_path / "g.dxf")
    if cross:
        with pytest.raises(SelfIntersectionError, match="crosses itself"):
            import_dxf(tmp_path / "g.dxf", parts=TWO)
        return
    outer, hole = import_dxf(tmp_path / "g.dxf", parts=TWO).driver.loops
    assert len(outer.segments) == 1200 and outer.is_ccw and not hole.is_ccw
    x, y = pts[:, 0], pts[:, 1]
    assert_allclose(outer.area, 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y),
                    rtol=1e-12)


def test_imported_segments_are_named_after_their_entities(tmp_path):
    """Curve labels of an imported drawing say where each segment came from
    (layer, entity type and handle, polyline vertex), not ``L0S0``."""
    import re
    m = reciprocating_cam()
    pair = m.build()
    back = import_dxf(export_dxf(m, tmp_path / "m.dxf"), parts=parts_of(pair))
    names = [s.name for p in back.parts for lp in p.loops for s in lp.segments]
    assert all(re.fullmatch(r"[\w.-]+\.(LINE|ARC|CIRCLE|LWPOLYLINE)#\w+(\.\d+)?", n)
               for n in names), names
    labels = {c.label for c in model_cspaces(back, accuracy="fast", window=m.window)[0].curves}
    assert labels and not any(re.search(r"L\d+S\d+", lab) for lab in labels), labels
