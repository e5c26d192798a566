"""[Kim 2007] Tables 1-4 reproduced by computation."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mechanisms.manipulators import (
    Decoupling, arrangement_comparison, comparison_table, design, effective_square,
    global_design_index, closed_form_design_indices, total_workspace, two_pap, two_ppa,
)
from shapely.geometry import box


@pytest.fixture(scope="module")
def designs():
    return design("2-PaP", 1.0, 60, unit="deg"), design("2-PPa", 1.0, 30, unit="deg")


@pytest.mark.parametrize("kind,th", [("2-PaP", 60), ("2-PaP", 35), ("2-PPa", 30), ("2-PPa", 15)])
def test_table1_gdi_matches_closed_form(kind, th):
    m = design(kind, 1.0, th, unit="deg").model
    res = global_design_index(m)
    cf = closed_form_design_indices(m)
    assert_allclose(res.ldi_max, cf["ldi_max"], atol=1e-12)
    assert_allclose(res.ldi_min, cf["ldi_min"], atol=1e-12)
    assert_allclose(res.gdi, cf["gdi"], atol=1e-12)
    # Eq. 28 as printed is the reciprocal of the tables' entries.
    assert_allclose(res.ldi_max_over_min, 1.0 / cf["gdi"], atol=1e-10)
    # Where Table 1 says the extremes are: centre for the maximum ...
    assert_allclose(res.p_max, [0.0, 0.0], atol=1e-9)
    w = m.half_width
    if kind == "2-PPa":
        # ... and theta_1 = theta_2 = +-theta_L (corners (w, w) or (-w, -w)) for 2-PPa.
        assert_allclose(np.abs(res.p_min), [w, w], atol=1e-9)
        assert np.sign(res.p_min[0]) == np.sign(res.p_min[1])
    else:
        # 2-PaP: la cos(theta_L) is reached on the boundary (at the corners among others).
        assert_allclose(np.max(np.abs(res.p_min)), w, atol=1e-12)


@pytest.mark.parametrize("kind,th", [("2-PaP", 60), ("2-PPa", 30)])
def test_gdi_against_dense_grid(kind, th):
    m = design(kind, 1.0, th, unit="deg").model
    res = global_design_index(m, n=11)
    from mechanisms.manipulators import ldi_map
    grid = ldi_map(m, n=401).ldi
    # Optimised extremes bound the dense grid and agree with it to grid resolution.
    assert grid.min() >= res.ldi_min - 1e-12
    assert grid.max() <= res.ldi_max + 1e-12
    assert_allclose(grid.min(), res.ldi_min, atol=1e-12)  # extremes lie on grid nodes here
    assert_allclose(grid.max(), res.ldi_max, atol=1e-12)
    assert_allclose(grid.min() / grid.max(), res.gdi, atol=1e-12)


def test_table2_computed(designs):
    t = comparison_table(*designs)
    printed = {"GDI": (0.5, 0.634), "Workspace/stroke (2w/Delta d)": (1.0, 0.882),
               "Workspace/size (2w/a)": (0.928, 0.667)}
    for row, (v0, v1) in printed.items():
        assert_allclose(t.value(row, 0), v0, atol=5e-4)
        assert_allclose(t.value(row, 1), v1, atol=5e-4)
    assert t.value("Decoupled", 0) == Decoupling.ALWAYS.value
    assert t.value("Decoupled", 1) == Decoupling.AT_ONE_POINT.value
    md = t.to_markdown()
    assert "0.634" in md and "0.928" in md and "0.882" in md


def test_table3_arrangements():
    perp, par = arrangement_comparison()
    assert_allclose(perp.ldi, 1.0, atol=1e-9)
    assert_allclose(par.ldi, 1 / math.sqrt(2), atol=1e-9)
    assert_allclose(np.degrees(perp.theta), [0.0, 0.0], atol=1e-4)
    assert_allclose(np.degrees(par.theta), [45.0, 45.0], atol=1e-4)
    assert perp.decoupled and not par.decoupled
    assert_allclose(perp.transverse_ratio, 0.0, atol=1e-6)   # axial load only
    assert_allclose(par.transverse_ratio, 1.0, atol=1e-5)    # axial and transverse
    assert_allclose(par.condition, 1.0, atol=1e-5)


def test_table4_prototype_2pap():
    # la = 100, theta_L = 60 deg, b = 20, t = 55.
    d = design("2-PaP", 100 * math.sin(math.radians(60)), 60, t=55, b=20, unit="deg")
    assert_allclose(d.la, 100.0, atol=1e-12)
    assert_allclose(2 * d.w, 173.2, atol=0.05)
    assert_allclose(d.stroke, 173.2, atol=0.05)
    assert_allclose(effective_square(d.model).side, 173.2, atol=0.05)
    # Eq. 7 gives a_min = 261.6 mm; the prototype's a = 265.0 mm respects it.
    assert_allclose(d.a, 100 * (1 + math.sin(math.radians(60))) + 75, atol=1e-12)
    assert_allclose(d.a, 261.6, atol=0.05)
    assert d.a <= 265.0


def test_table4_prototype_2ppa():
    # The built prototype: la = 260, b = 92, a = 482, Delta d = 300, theta_L = 30 deg.
    m = two_ppa(260.0, 482.0, 300.0, 30, b=92.0, unit="deg")
    sq = effective_square(m)
    assert_allclose(sq.side, 260.0, atol=1e-9)
    poly = total_workspace(m, arc_points=4097)
    assert poly.covers(box(-129.99, -129.99, 129.99, 129.99))
    assert not poly.covers(box(-130.5, -130.5, 130.5, 130.5))
    # Design equations from w = 130, theta_L = 30 deg, b = 92 (Eq. 26).
    d = design("2-PPa", 130.0, 30, b=92.0, unit="deg")
    assert_allclose(d.la, 260.0, atol=1e-9)
    assert_allclose(d.a, 482.0, atol=1e-9)
    # Eq. 26 needs 294.8 mm of stroke; the 300 mm actuator covers it.
    assert_allclose(d.stroke, 130 * (4 - math.sqrt(3)), atol=1e-9)
    assert d.stroke <= 300.0
    # With the exact Eq. 26 stroke the effective square is exactly the prescribed one.
    assert_allclose(effective_square(d.model).half_width, 130.0, atol=1e-9)


def test_design_rejects_bad_angle():
    with pytest.raises(ValueError, match="theta_limit must lie in"):
        design("2-PaP", 1.0, 95, unit="deg")
    with pytest.raises(ValueError, match="kind must be"):
        design("3-RRR", 1.0, 30, unit="deg")
    with pytest.raises(ValueError, match="unit must be one of"):
        two_pap(1.0, 30, unit="grad")
