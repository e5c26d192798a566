"""Total and effective workspaces (``mechanisms.manipulators.workspace``).

Closed form of a leg's region: leg i reaches ``g_i + (d + la cos phi) e_i +
la sin phi l_i`` for d in [0, stroke] and |phi| <= phi_max.  At the lateral
coordinate ``v = la sin phi`` it covers an interval of length ``stroke`` along
e_i, so its area is ``2 la sin(phi_max) stroke``; the polygon whose arcs are
sampled at the same angles has exactly that area too (a union of
parallelograms).  The inverse kinematics is the independent check of the
total workspace: it flags every pose a leg cannot reach.
"""

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import Point, box

from cspace.errors import InputError
from mechanisms.manipulators import (PoseStatus, design, effective_square, inverse_kinematics,
                                     leg_region, square_fits, total_workspace, two_pap, two_ppa,
                                     two_ppa_parallel)

PAP = two_pap(2.0, 50, unit="deg")
PPA = two_ppa(1.0, 1.6, 1.1, 30, b=0.2, unit="deg")
PAR = two_ppa_parallel(1.0, 1.2, 1.0, 30, unit="deg")


def test_2pap_total_workspace_is_the_prescribed_square():
    poly = total_workspace(PAP)
    w = PAP.half_width
    assert poly.equals(box(-w, -w, w, w))
    assert poly.exterior.is_ccw
    sq = effective_square(PAP)
    assert sq.half_width == w and sq.side == 2 * w and sq.iterations == 0
    assert square_fits(PAP, w) and not square_fits(PAP, w * (1 + 1e-12))


@pytest.mark.parametrize("model", [PPA, PAR], ids=["perpendicular", "parallel"])
@pytest.mark.parametrize("phi_deg", [90.0, 60.0, 30.0])
def test_leg_region_area_is_the_closed_form(model, phi_deg):
    for leg in (0, 1):
        poly = leg_region(model, leg, phi_max=phi_deg, unit="deg", arc_points=101)
        assert poly.is_valid and poly.exterior.is_ccw
        want = 2 * model.la * math.sin(math.radians(phi_deg)) * model.stroke
        assert poly.area == pytest.approx(want, rel=1e-12)


def test_leg_region_holds_exactly_its_reachable_points():
    rng = np.random.default_rng(0)
    for leg in (0, 1):
        poly = leg_region(PPA, leg, arc_points=2049)
        phi = rng.uniform(-0.45 * math.pi, 0.45 * math.pi, 400)
        g, e, lat = PPA.g[leg], PPA.e[leg], PPA.lat[leg]

        def reach(d):
            return g + (d + PPA.la * np.cos(phi))[:, None] * e \
                + (PPA.la * np.sin(phi))[:, None] * lat

        # the sampled arcs leave out slivers thinner than their sagitta (3e-7)
        p = reach(rng.uniform(0, PPA.stroke, 400))
        assert shapely.contains_xy(poly.buffer(1e-6), p[:, 0], p[:, 1]).all()
        for d in (-0.02, PPA.stroke + 0.02):             # beyond either end of the stroke
            p = reach(np.full(400, d))
            assert not shapely.intersects_xy(poly, p[:, 0], p[:, 1]).any()


def test_total_workspace_agrees_with_the_inverse_kinematics():
    """Inside the total workspace the legs reach P; outside both leg regions they
    do not.  For this design the regions also meet in a small lower-left piece
    that the total workspace leaves out: the legs reach it only in the other
    assembly mode."""
    poly = total_workspace(PPA, arc_points=4097)
    assert poly.exterior.is_ccw and poly.contains(Point(0.0, 0.0))
    both = leg_region(PPA, 0, arc_points=4097).intersection(leg_region(PPA, 1, arc_points=4097))
    pieces = sorted(getattr(both, "geoms", [both]), key=lambda g: g.area)
    assert len(pieces) == 2 and pieces[1].symmetric_difference(poly).area < 1e-12
    rng = np.random.default_rng(1)
    x0, y0, x1, y1 = poly.bounds
    p = rng.uniform([x0 - 0.4, y0 - 0.4], [x1 + 0.3, y1 + 0.3], (8000, 2))
    inside = shapely.contains_xy(poly.buffer(-1e-4), p[:, 0], p[:, 1])
    outside = ~shapely.contains_xy(both.buffer(1e-4), p[:, 0], p[:, 1])
    other = shapely.contains_xy(pieces[0].buffer(-1e-4), p[:, 0], p[:, 1])
    assert inside.sum() > 500 and outside.sum() > 500 and other.sum() > 5
    st = inverse_kinematics(PPA, p).status
    assert np.all(st[inside] != PoseStatus.OUTSIDE_WORKSPACE)
    assert np.all(st[outside] == PoseStatus.OUTSIDE_WORKSPACE)
    assert np.all(st[other] == PoseStatus.OTHER_ASSEMBLY)


@pytest.mark.parametrize("model", [PPA, PAR], ids=["perpendicular", "parallel"])
def test_effective_square_is_the_largest_square_in_the_polygon(model):
    sq = effective_square(model)
    w = sq.half_width
    assert 0 < w < model.la + model.stroke and sq.iterations > 10
    assert sq.polygon.equals(box(-w, -w, w, w)) and sq.side == 2 * w
    poly = total_workspace(model, arc_points=8193)
    assert poly.covers(box(-0.999 * w, -0.999 * w, 0.999 * w, 0.999 * w))
    assert not poly.covers(box(-1.001 * w, -1.001 * w, 1.001 * w, 1.001 * w))
    # the exact predicate agrees on both sides of it
    assert square_fits(model, w) and not square_fits(model, w * (1 + 1e-9))
    for f in (0.2, 0.6, 0.95):
        assert square_fits(model, f * w)
    assert sq.to_dict() == {"half_width": w, "side": 2 * w, "iterations": sq.iterations}


@pytest.mark.parametrize("th", [20, 35, 44])
def test_the_design_stroke_gives_exactly_the_prescribed_square(th):
    """Eq. 26's stroke is the least one: the effective square is the prescribed one."""
    d = design("2-PPa", 0.8, th, b=0.1, unit="deg")
    assert effective_square(d.model).half_width == pytest.approx(0.8, rel=1e-12)
    shorter = two_ppa(d.la, d.a, 0.99 * d.stroke, th, b=0.1, unit="deg")
    assert effective_square(shorter).half_width < 0.8 * (1 - 1e-4)


def test_effective_square_closed_forms():
    """PPA: leg 1 reaches back to ``p_x = (b - a) + la`` at d = 0 (link along +x, at
    p_y = 0), so the square ends at ``w = a - b - la`` = 0.4; the far end of the
    stroke is not reached there.  With the links limited to +/-phi_max the
    lateral reach ``la sin(phi_max)`` bounds it instead."""
    full = effective_square(PPA).half_width
    assert full == pytest.approx(PPA.a - PPA.b - PPA.la, rel=1e-13)
    limited = effective_square(PPA, phi_max=20, unit="deg").half_width
    assert limited == pytest.approx(PPA.la * math.sin(math.radians(20)), rel=1e-13)
    assert effective_square(PPA, phi_max=math.radians(20)).half_width == limited
    assert total_workspace(PPA, phi_max=20, unit="deg").area < total_workspace(PPA).area
    for bad in (0.0, -10.0, 91.0):
        with pytest.raises(InputError, match=r"phi_max must lie in \(0, 90\] deg"):
            leg_region(PPA, 0, phi_max=bad, unit="deg")


def test_unreachable_origin_gives_an_empty_square():
    far = two_ppa(1.0, 10.0, 1.0, 30, unit="deg")      # origin 10 along e_i from g_i
    sq = effective_square(far)
    assert sq.half_width == 0.0 and sq.polygon.is_empty and sq.iterations == 0
    assert not square_fits(far, 0.0)
    assert total_workspace(far).is_empty


def test_bad_input():
    with pytest.raises(InputError, match="leg_region needs a TwoPPa; got TwoPaP"):
        leg_region(PAP, 0)
    with pytest.raises(InputError, match="leg must be 0 or 1; got 2"):
        leg_region(PPA, 2)
    with pytest.raises(InputError, match="TwoPaP or TwoPPa"):
        total_workspace(None)
    with pytest.raises(InputError, match="TwoPaP or TwoPPa"):
        effective_square("x")
    with pytest.raises(InputError, match="unit must be one of"):
        total_workspace(PPA, phi_max=30, unit="grad")


@pytest.mark.parametrize("th", [50.0, 70.0])
def test_effective_square_stops_at_the_direct_singularity(th):
    """A perpendicular 2-PPa's links are parallel (the direct singularity) where
    th1 + th2 = 90 deg; beyond it the legs reach P only in the other assembly
    mode.  With theta_L > 45 deg the design's corners (w, w) lie beyond it, so
    the effective square is bounded by the singularity: at the corner, th1 =
    th2 = 45 deg, i.e. w = la sin 45 deg (strokes and reach allow more)."""
    d = design("2-PPa", 130.0, th, b=92.0, unit="deg")
    w = effective_square(d.model).half_width
    assert w == pytest.approx(d.la * math.sin(math.pi / 4), rel=1e-6)
    assert w < 130.0
    inside = inverse_kinematics(d.model, [[w, w], [-w, w], [0.999 * w, -w]]).status
    assert np.all(inside == PoseStatus.OK)
    assert inverse_kinematics(d.model, [1.001 * w, 1.001 * w]).status == \
        PoseStatus.OTHER_ASSEMBLY
    assert not square_fits(d.model, 1.001 * w)
    # the total workspace still holds that corner (its other-mode tail)
    assert total_workspace(d.model).buffer(1e-9).contains(Point(1.001 * w, 1.001 * w))
