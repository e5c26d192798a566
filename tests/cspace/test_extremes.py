"""Numerical stability at the extremes: scale changes, tiny and large tolerances,
tangent and degenerate contacts, the window seam and nearly closed channels.
Every output is finite and correct, or a typed error / status."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import CSpaceError
from cspace.freespace import Status, configuration_space
from cspace.geometry import Arc, Line, Loop, Pair, Part, Rotation, Translation
from cspace.overlap import parts_overlap


def _scale_seg(g, s):
    if isinstance(g, Line):
        return Line((g.start[0] * s, g.start[1] * s), (g.end[0] * s, g.end[1] * s), g.name)
    return Arc((g.center[0] * s, g.center[1] * s), g.radius * s, g.start_angle, g.end_angle,
               g.ccw, g.name)


def _scale_axis(a, s):
    if isinstance(a, Rotation):
        return Rotation((a.center[0] * s, a.center[1] * s))
    return Translation(a.direction, (a.origin[0] * s, a.origin[1] * s))


def scale_pair(p: Pair, s: float) -> Pair:
    parts = [Part(pt.name, tuple(Loop(tuple(_scale_seg(g, s) for g in lp.segments), lp.name)
                                 for lp in pt.loops), _scale_axis(pt.axis, s))
             for pt in p.parts]
    return Pair(parts[0], parts[1], units=p.units, name=p.name)


# ------------------------------------------------------------------------- scale

@pytest.mark.parametrize("s", [1e-3, 1e3])
def test_scaled_reciprocating_cam_gives_scaled_cspace(models, s):
    m = models["reciprocating_cam"]
    p = m.build()
    w = m.window
    cs1 = configuration_space(p, "fast", window=w)
    cs2 = configuration_space(scale_pair(p, s), "fast", window=(w[0], w[1], w[2] * s, w[3] * s))
    assert cs1.stats["curves"] == cs2.stats["curves"]
    assert cs1.stats["boundary_pieces"] == cs2.stats["boundary_pieces"]
    assert sorted(cs1.faces.values()) == sorted(cs2.faces.values())
    # every curve: same label, same driver range, slide values scaled by s
    c2 = {(c.label, c.branch, round(c.q1_start, 6)): c for c in cs2.curves}
    for c in cs1.curves:
        d = c2[(c.label, c.branch, round(c.q1_start, 6))]
        assert d.q1_end == pytest.approx(c.q1_end, abs=1e-7)
        x = np.linspace(c.q1_start, c.q1_end, 7)
        assert_allclose(d.evaluate(x), s * c.evaluate(x), rtol=1e-8, atol=1e-9 * s)
    # classification agrees at scaled points
    rng = np.random.default_rng(0)
    q = np.column_stack([rng.uniform(w[0], w[1], 400), rng.uniform(w[2], w[3], 400)])
    assert np.array_equal(cs1.classify(q), cs2.classify(q * [1.0, s]))


def test_crossing_events_do_not_depend_on_the_last_bits_of_the_geometry(models):
    """Where a wheel vertex passes the junction of two driver arcs, the two
    contact curves join at a shared end.  The root finder used to report that
    join as a crossing or not depending on rounding (72 to 77 crossings under
    relative perturbations of 1e-12, and 73 against 74 for a DXF round trip of
    the same drawing).  The four identical slots make the nominal Geneva
    C-space repeat every quarter turn of the wheel, so its crossings come in
    fours; a join at a shared end is not a crossing."""
    m = models["geneva"]
    p = m.build()
    counts = set()
    for s in (1.0, 1 + 1e-12, 1 - 1e-12, 1 + 3e-13, 1e-3, 1e3):
        st = configuration_space(scale_pair(p, s), "fast", window=m.window).stats
        counts.add((st["crossings"], st["events"], st["boundary_pieces"], st["faces"]))
    assert len(counts) == 1
    (n, *_), = counts
    assert n % 4 == 0


@pytest.mark.parametrize("s", [1e-3, 1e3])
def test_scaled_rotating_pair_keeps_its_angles(models, s):
    m = models["optical_filter"]
    p = m.pairs()[0]
    cs1 = configuration_space(p, "fast")
    cs2 = configuration_space(scale_pair(p, s), "fast")
    assert cs1.stats["curves"] == cs2.stats["curves"]
    assert len(cs1.boundary) == len(cs2.boundary)
    rng = np.random.default_rng(1)
    q = np.column_stack([rng.uniform(-math.pi, math.pi, 300), rng.uniform(-math.pi, math.pi, 300)])
    assert np.array_equal(cs1.classify(q), cs2.classify(q))


# ------------------------------------------------------------------ tolerances

@pytest.mark.parametrize("tol", [1e-9, 0.25])
def test_zones_and_defects_at_tiny_and_large_tolerances(models, tol):
    """1e-9 cm and about 10 % of the cam size: finite zones, a defect result (or
    an INVALID reason) for every corner, never NaN or an exception."""
    from cspace.defects import Reason, is_defective, reference
    from cspace.zones import contact_zones
    m = models["reciprocating_cam"].with_tolerances(tol)
    ref = reference(m, "fast")
    z = contact_zones(ref.spaces[0], m, 0, "fast", faces=[ref.faces[0]])
    for b in z.bands:
        fin = np.isfinite(b.upper) & np.isfinite(b.lower)
        assert fin.any()
        assert np.all(b.upper[fin] >= b.lower[fin] - 1e-12)
        if tol < 1e-6:
            assert np.max(np.abs(b.upper[fin])) < 1e-6 and np.max(np.abs(b.lower[fin])) < 1e-6
    rng = np.random.default_rng(2)
    for _ in range(4):
        u = m.nominal + m.tol * rng.choice([-1.0, 1.0], m.n)
        r = is_defective(m, u, ref=ref)
        assert math.isfinite(r.max_deviation) or Reason.INVALID in r.reasons
        if tol < 1e-6:
            assert not r.defective, r.message


# ------------------------------------------------------------- degenerate contacts

def _block(x0, y0, x1, y1, name=""):
    pts = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    return Loop(tuple(Line(pts[i], pts[(i + 1) % 4], f"{name}{i}") for i in range(4)), name)


def _disk(c, r, name="disk"):
    return Loop((Arc(c, r, 0.0, 2 * math.pi, True, name),), name)


def test_zero_clearance_pin_in_a_parallel_slot_is_a_degenerate_channel():
    """A pin of radius r between two parallel walls 2r apart: the free space is a
    curve (zero width), so no free face of positive area may appear, and the
    computation stays finite."""
    r = 0.5
    pin = Part("pin", (_disk((0.0, 0.0), r),), Translation((1.0, 0.0), (0.0, 0.0)))
    walls = Part("walls", (_block(-5, r, 5, 2, "top"), _block(-5, -2, 5, -r, "bot")),
                 Translation((0.0, 1.0), (0.0, 0.0)))
    p = Pair(pin, walls, units="mm", name="zero_clearance")
    cs = configuration_space(p, "fast", window=(-1.0, 1.0, -0.5, 0.5))
    q = np.column_stack([np.linspace(-0.9, 0.9, 50), np.zeros(50)])
    st = cs.classify(q)
    assert set(np.unique(st)) <= {Status.CONTACT, Status.BLOCKED}
    for c in cs.curves:
        assert np.all(np.isfinite(c.evaluate(np.linspace(c.q1_start, c.q1_end, 5))))


def test_parallel_edges_and_equal_radii_are_finite():
    """A square block sliding past a square (parallel edges meet edge-on) and two
    equal disks (internal contact of equal radii degenerates)."""
    a = Part("a", (_block(-1, -1, 1, 1, "a"),), Rotation((0.0, 0.0)))
    b = Part("b", (_block(1.5, -1, 3.5, 1, "b"),), Translation((1.0, 0.0), (0.0, 0.0)))
    cs = configuration_space(Pair(a, b, name="squares"), "fast")
    assert cs.faces and any(cs.faces.values())
    for c in cs.curves:
        x = np.linspace(c.q1_start, c.q1_end, 9)
        assert np.all(np.isfinite(c.evaluate(x)))
    d1 = Part("d1", (_disk((0.0, 0.0), 1.0),), Rotation((0.5, 0.0)))
    d2 = Part("d2", (_disk((3.0, 0.0), 1.0),), Rotation((3.5, 0.0)))
    cs2 = configuration_space(Pair(d1, d2, name="equal_disks"), "fast")
    assert any(cs2.faces.values())
    rng = np.random.default_rng(3)
    q = rng.uniform(-math.pi, math.pi, (300, 2))
    st = cs2.classify(q)
    far = st != Status.CONTACT
    ov = parts_overlap(Pair(d1, d2), q[far])
    assert np.array_equal(ov, st[far] == Status.BLOCKED)


def test_coincident_vertices_do_not_break_the_sweep():
    """Two blocks whose vertices coincide at q = 0."""
    a = Part("a", (_block(-1, -1, 1, 1, "a"),), Translation((1.0, 0.0), (0.0, 0.0)))
    b = Part("b", (_block(1, 1, 3, 3, "b"),), Translation((0.0, 1.0), (0.0, 0.0)))
    cs = configuration_space(Pair(a, b, name="corner"), "fast", window=(-3, 3, -3, 3))
    rng = np.random.default_rng(4)
    q = rng.uniform(-3, 3, (400, 2))
    st = cs.classify(q)
    far = st != Status.CONTACT
    assert np.array_equal(parts_overlap(Pair(a, b), q[far]), st[far] == Status.BLOCKED)


# ------------------------------------------------------------------ window seam

def test_window_seam_does_not_change_the_free_space(models):
    """The same pair in a window shifted by an odd amount (curves cross the seam)
    classifies every configuration the same."""
    p = models["geneva"].build()
    cs0 = configuration_space(p, "fast", window=(0.0, 2 * math.pi, -math.pi, math.pi))
    cs1 = configuration_space(p, "fast", window=(1.2345, 1.2345 + 2 * math.pi, -math.pi,
                                                 math.pi))
    rng = np.random.default_rng(5)
    q = np.column_stack([rng.uniform(0, 2 * math.pi, 1500), rng.uniform(-math.pi, math.pi, 1500)])
    a, b = cs0.classify(q), cs1.classify(q)
    sure = (a != Status.CONTACT) & (b != Status.CONTACT)
    assert np.array_equal(a[sure], b[sure])
    assert sum(cs0.faces.values()) == sum(cs1.faces.values())


# ------------------------------------------------------------ nearly closed channel

@pytest.mark.parametrize("gap, preset", [(1e-3, "fast"), (1e-6, "fast"), (1e-6, "default"),
                                         (1e-9, "precise"), (1e-9, "fast")])
def test_nearly_closed_channel_stays_open(gap, preset):
    """A pin between walls with clearance ``gap`` (relative to the pin radius): the
    channel is one free face along the whole window, however narrow, as long as
    the preset resolves it; below the resolution the sweep says so."""
    r = 0.5
    pin = Part("pin", (_disk((0.0, 0.0), r),), Translation((1.0, 0.0), (0.0, 0.0)))
    h = r * (1 + gap)
    walls = Part("walls", (_block(-5, h, 5, 2, "top"), _block(-5, -2, 5, -h, "bot")),
                 Translation((0.0, 1.0), (0.0, 0.0)))
    cs = configuration_space(Pair(pin, walls, name="narrow"), preset,
                             window=(-1.0, 1.0, -0.5, 0.5))
    free = [f for f, v in cs.faces.items() if v]
    if 2 * gap * r / cs.pair.char_length <= 100 * cs.accuracy.root_tol:
        # below the resolution: flagged, and the centre line is not called free
        assert cs.stats["thin_cells"] > 0 and not free
        assert cs.classify([[0.0, 0.0]])[0] != Status.FREE
        return
    assert cs.stats["thin_cells"] == 0
    assert len(free) == 1
    faces = cs.face_at(np.column_stack([np.linspace(-0.99, 0.99, 40), np.zeros(40)]))
    assert set(faces.tolist()) == set(free)


def test_blocked_start_is_a_typed_error(models):
    import dataclasses

    from cspace.defects import reference
    m = dataclasses.replace(models["reciprocating_cam"], q2_start=(5.0,))
    with pytest.raises(CSpaceError):
        reference(m, "fast")


# ------------------------------------------------------- closed face boundaries

def _open_vertices(model, signs, preset):
    """Vertices of odd degree in the free-space graphs of a box corner, away from
    the vertical pieces (which are events, not graph edges)."""
    u = model.nominal + np.asarray(signs, dtype=float) * model.tol
    built = model.build(u)
    out = []
    for p in (built.pairs if hasattr(built, "pairs") else (built,)):
        cs = configuration_space(p, preset, window=model.window)
        vq = [v.q1_value for v in cs.vertical]
        for n, d in cs.graph.degree():
            q1 = cs.graph.nodes[n]["q"][0]
            if d % 2 and not any(abs(q1 - x) <= 1e-7 for x in vq):
                out.append((p.name, cs.graph.nodes[n]["q"]))
    return out


def _corner_property(models, name, preset, examples):
    from hypothesis import HealthCheck, given, settings, strategies as st
    m = models[name]

    @settings(max_examples=examples, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow])
    @given(st.lists(st.sampled_from([-1, 0, 1]), min_size=m.n, max_size=m.n))
    def check(signs):
        assert _open_vertices(m, signs, preset) == []

    check()


@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam"])
def test_face_boundaries_are_closed_at_box_corners(models, name):
    """Every face boundary is a set of closed cycles: each vertex joins an even
    number of boundary pieces.  At the `fast` root tolerance a turning point
    (the two branches of one equation meeting at a vertical tangent) used to
    split into two vertices here."""
    _corner_property(models, name, "fast", 4)


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["fast", "default"])
@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam"])
def test_face_boundaries_are_closed_at_many_box_corners(models, name, preset):
    _corner_property(models, name, preset, 40)


# ------------------------------------------------------ found by an extremes audit

def _poly(pts, name):
    n = len(pts)
    return Loop(tuple(Line(pts[i], pts[(i + 1) % n], f"{name}{i}") for i in range(n)), name)


@pytest.mark.parametrize("preset, chamfer", [("fast", 0.01), ("default", 0.004)])
def test_contact_shorter_than_the_scan_step_is_found(preset, chamfer):
    # a square cam with one corner chamfered by an edge much shorter than the
    # scan step, under a knife-edge follower: the chamfer's contact lasts less
    # than one step of the driver, and a slab without it would read as blocked
    e = chamfer / math.sqrt(2)
    cam = Part("cam", (_poly([(-1, -1), (1, -1), (1, 1 - e), (1 - e, 1), (-1, 1)], "cam"),),
               Rotation((0.0, 0.0)))
    fol = Part("fol", (_poly([(0.9, 1.2), (0.95, 3.0), (0.85, 3.0)], "fol"),),
               Translation((0.0, 1.0), (0.0, 0.0)))
    p = Pair(cam, fol)
    cs = configuration_space(p, preset, window=(0.0, 2 * math.pi, -3.0, 1.0))
    assert any("cam3" in c.label.split("|")[0] for c in cs.curves)
    rng = np.random.default_rng(0)
    q = np.column_stack([rng.uniform(0.0, 2 * math.pi, 20000), rng.uniform(-3.0, 1.0, 20000)])
    st = cs.classify(q)
    far = st != Status.CONTACT
    assert np.array_equal((st == Status.BLOCKED)[far], parts_overlap(p, q)[far])
    from cspace.simulate import SimStatus, simulate
    assert simulate(cs, 0.0, 2 * math.pi, 0.9).status == SimStatus.OK


def test_finely_polygonised_cam_keeps_every_edge():
    n = 400
    pts = [(math.cos(2 * math.pi * i / n) + 0.3, math.sin(2 * math.pi * i / n))
           for i in range(n)]
    cam = Part("cam", (_poly(pts, "c"),), Rotation((0.0, 0.0)))
    fol = Part("fol", (_poly([(-2, 1.4), (2, 1.4), (2, 2.5), (-2, 2.5)], "f"),),
               Translation((0.0, 1.0), (0.0, 0.0)))
    cs = configuration_space(Pair(cam, fol), "fast", window=(0.0, 2 * math.pi, -1.5, 1.0))
    rng = np.random.default_rng(1)
    q = np.column_stack([rng.uniform(0.0, 2 * math.pi, 5000), rng.uniform(-1.5, 1.0, 5000)])
    st = cs.classify(q)
    far = st != Status.CONTACT
    assert np.array_equal((st == Status.BLOCKED)[far], parts_overlap(cs.pair, q)[far])


def test_point_between_coincident_curves_lands_in_the_right_cell(models):
    # a zero-clearance lock: the locking arcs coincide with the wheel's, and
    # zero-height free cells lie between curves equal to rounding
    p = models["geneva"].build({"lock_r": 3.25})
    cs = configuration_space(p, "default")
    rng = np.random.default_rng(2)
    q = np.column_stack([np.full(400, 2.44), rng.uniform(0.0, 2 * math.pi, 400)])
    q = np.vstack([q, [[2.44, 1.7]]])
    st = cs.classify(q)
    far = st != Status.CONTACT
    assert np.array_equal((st == Status.BLOCKED)[far], parts_overlap(p, q)[far])


def test_start_on_a_pushing_contact_is_pushed():
    from cspace.simulate import SimStatus, simulate
    cam = Part("cam", (Loop((Arc((0.2, 0.0), 1.0, 0.0, 2 * math.pi, True, "disk"),)),),
               Rotation((0.0, 0.0)))
    face = _poly([(-2, 1), (2, 1), (2, 2), (-2, 2)], "face")
    fol = Part("fol", (face,), Translation((0.0, 1.0), (0.0, 0.0)))
    cs = configuration_space(Pair(cam, fol), "fast", window=(0.0, 2 * math.pi, -0.5, 0.5))
    lo = cs.free_intervals(0.0)[0][0]
    for q2 in (lo, lo + 1e-12):
        s = simulate(cs, 0.0, 1.0, q2)
        assert s.status == SimStatus.OK, s.message
        assert s.q2[-1] > lo + 0.05   # the disk lifted the face


def test_model_without_toleranced_dependencies_has_zero_width_zones(models):
    from cspace.defects import reference
    from cspace.zones import contact_zones
    m = models["reciprocating_cam"]
    t = np.zeros(m.n)
    t[m.index("xr_b")] = 0.02
    m = m.with_tolerances(t)
    ref = reference(m, "fast")
    z = contact_zones(ref.spaces[0], m, 0, "fast")
    for b in z.bands:
        if "xr_b" not in b.depends:
            w = b.upper - b.lower
            assert np.all(w[np.isfinite(w)] == 0)
    # every tolerance below what moves a segment measurably: dependencies are
    # still found (by the model-size step), so zones and tests still work
    m2 = models["reciprocating_cam"].with_tolerances(1e-13)
    assert any(m2.dependencies()[0].values())
    assert contact_zones(reference(m2, "fast").spaces[0], m2, 0, "fast").bands


def test_large_tolerances_do_not_break_the_nominal_reference(models):
    from cspace.defects import Reason, is_defective, reference
    m = models["geneva"].with_tolerances(1.0)
    ref = reference(m, "fast")
    r = is_defective(m, m.nominal + m.tol, ref=ref)
    assert r.defective and Reason.INVALID in r.reasons


@pytest.mark.parametrize("name, values", [("geneva", {"relief_d": 0.0}),
                                          ("reciprocating_cam", {"tip_r": -2.5})])
def test_builder_arithmetic_failure_is_an_invalid_model_error(models, name, values):
    from cspace.errors import InvalidModelError
    with pytest.raises(InvalidModelError, match="cannot be built"):
        models[name].build(values)


def _scaled_pair(p, s):
    return scale_pair(p, s)


def _wedge(s=1.0):
    """A sliding wedge cam with a bump under a sliding knife edge, scaled by s."""
    cam = _poly([(-5 * s, -s), (5 * s, -s), (5 * s, 0), (s, 0), (0, 0.8 * s), (-s, 0),
                 (-5 * s, 0)], "cam")
    fol = _poly([(0.0, 0.2 * s), (0.1 * s, 2.0 * s), (-0.1 * s, 2.0 * s)], "fol")
    return Pair(Part("cam", (cam,), Translation((1.0, 0.0), (0.0, 0.0))),
                Part("fol", (fol,), Translation((0.0, 1.0), (0.0, 0.0))))


@pytest.mark.parametrize("s", [1e-7, 1e3])
def test_sliding_driver_is_scale_invariant(s):
    from cspace.simulate import SimStatus, simulate
    ref = configuration_space(_wedge(), "fast", window=(-3, 3, -0.5, 1.5))
    cs = configuration_space(_wedge(s), "fast", window=(-3 * s, 3 * s, -0.5 * s, 1.5 * s))
    assert len(cs.curves) == len(ref.curves) and len(cs.events) == len(ref.events)
    assert_allclose(np.asarray(cs.events) / s, ref.events, rtol=0, atol=1e-8)
    a = simulate(ref, -2.9, 2.9, 0.1)
    b = simulate(cs, -2.9 * s, 2.9 * s, 0.1 * s)
    assert a.status == b.status == SimStatus.OK
    assert len(b.q1) == len(a.q1)
    assert_allclose(b.q2 / s, a.q2, rtol=0, atol=1e-8)
    rng = np.random.default_rng(3)
    q = np.column_stack([rng.uniform(-3, 3, 4000), rng.uniform(-0.5, 1.5, 4000)]) * s
    st = cs.classify(q)
    far = st != Status.CONTACT
    assert np.array_equal((st == Status.BLOCKED)[far], parts_overlap(cs.pair, q)[far])


def test_too_narrow_window_and_too_many_samples_are_typed_errors(models):
    from cspace.errors import InputError
    from cspace.simulate import simulate
    p = models["reciprocating_cam"].build()
    with pytest.raises(InputError, match="at least 1e-06"):
        configuration_space(p, "fast", window=(1.0, 1.0 + 1e-9, -1.0, 1.0))
    with pytest.raises(InputError, match="at least 1e-06"):
        configuration_space(p, "fast", window=(0.0, 2 * math.pi, 0.3, 0.3 + 1e-8))
    cs = configuration_space(p, "fast", window=models["reciprocating_cam"].window)
    with pytest.raises(InputError, match="output samples"):
        simulate(cs, 0.0, 0.001, 0.45, step=1e-300)
    with pytest.raises(InputError, match="output samples"):
        simulate(cs, 0.0, 1e12, 0.45)


def test_window_far_from_zero_is_still_one_turn(models):
    from cspace.simulate import SimStatus, simulate
    p = models["geneva"].build()
    lo = 2 * math.pi * 1e5
    cs = configuration_space(p, "fast", window=(lo, lo + 2 * math.pi, -math.pi, math.pi))
    assert cs.periodic[0]
    assert simulate(cs, lo, lo + 8 * math.pi, 0.0).status == SimStatus.OK


def test_part_far_from_the_origin_is_valid():
    x = 1e9
    sq = Loop((Line((x, 0), (x + 1, 0)), Line((x + 1, 0), (x + 1, 1)), Line((x + 1, 1), (x, 1)),
               Line((x, 1), (x, 0))))
    assert sq.area == pytest.approx(1.0)
    from cspace.errors import ZeroLengthSegmentError
    with pytest.raises(ZeroLengthSegmentError, match="of the loop size"):
        Loop((Line((0, 0), (1, 0)), Line((1, 0), (1, 1e-12)), Line((1, 1e-12), (1, 1)),
              Line((1, 1), (0, 1)), Line((0, 1), (0, 0))))


def test_huge_coordinates_and_windows_are_typed_errors(models):
    from cspace.errors import InputError
    with pytest.raises(InputError, match="at most 1e\\+100"):
        Arc((0.0, 0.0), 1e200, 0.0, 2 * math.pi, True)
    with pytest.raises(InputError, match="at most 1e\\+100"):
        Line((0.0, 0.0), (1e150, 0.0))
    with pytest.raises(InputError, match="at most 1e\\+100"):
        Rotation((1e300, 0.0))
    p = models["reciprocating_cam"].build()
    with pytest.raises(InputError, match="characteristic lengths"):
        configuration_space(p, "fast", window=(0.0, 2 * math.pi, -1e12, 1e12))


def test_zone_bands_do_not_depend_on_rounding_noise(models):
    # parameters without first-order effect on a curve (gradient ~1e-16) used
    # to take their corner sign from the last bits of the geometry: the Geneva
    # model scaled by 1e-3 moved a band by 0.03 rad (16 % of its width)
    import dataclasses

    from cspace.defects import reference
    from mechanisms.models import Model
    from synthesis.loop import operating_zones
    m = models["geneva"]
    s = 1e-3
    # every Geneva parameter is a length: scaling them all scales the pair
    ms = dataclasses.replace(
        m, parameters=tuple(dataclasses.replace(p, nominal=p.nominal * s, tol=p.tol * s)
                            for p in m.parameters),
        builder=lambda v: _scaled_pair(m.builder({k: x / s for k, x in v.items()}), s),
        window=m.window)
    assert isinstance(ms, Model)
    bands = [operating_zones(mm, reference(mm, "fast"), "fast")[0].bands for mm in (m, ms)]
    d = max(np.nanmax(np.abs(np.r_[a.upper - b.upper, a.lower - b.lower]))
            for a, b in zip(*bands))
    assert d < 1e-6
