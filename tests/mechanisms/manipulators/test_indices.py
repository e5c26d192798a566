"""LDI maps and the global design index (``mechanisms.manipulators.indices``)
over squares other than the prescribed one, checked against closed forms.

2-PaP: ``LDI = la min(cos theta_1, cos theta_2) = min(sqrt(la^2 - p_x^2),
sqrt(la^2 - p_y^2))``, largest (la) at the centre, smallest on the square's edge:
over ``|p_i| <= w`` the GDI is ``sqrt(1 - (w / la)^2)``.

Perpendicular 2-PPa: ``LDI = 1 / sigma_max([[1, t_1], [t_2, 1]])``, ``t_1 = tan
asin(p_y / la)``, ``t_2 = tan asin(p_x / la)``; 1 at the centre, ``1 / (1 + t)``
at the corners (w, w) and (-w, -w) with ``t = tan asin(w / la)``.
"""

import json
import math
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError
from mechanisms.manipulators import (closed_form_design_indices, global_design_index,
                                     ldi_map, local_design_index, table1_closed_form, two_pap,
                                     two_ppa, two_ppa_parallel)

PAP = two_pap(2.0, 60, unit="deg")
PPA = two_ppa(1.0, 1.5, 1.0, 30, unit="deg")
PAR = two_ppa_parallel(1.0, 1.2, 1.0, 30, unit="deg")


def test_ldi_map_grid_and_orientation():
    m = ldi_map(PAP, n=7)
    w = PAP.half_width
    assert m.half_width == w and m.ldi.shape == (7, 7)
    assert_allclose(m.x, np.linspace(-w, w, 7), atol=0)
    assert_allclose(m.y, m.x, atol=0)
    X, Y = np.meshgrid(m.x, m.y)
    la = PAP.la
    assert_allclose(m.ldi, np.minimum(np.sqrt(la * la - X * X), np.sqrt(la * la - Y * Y)),
                    rtol=1e-12)
    # ldi[i, j] lies at (x[j], y[i]): checked on a map without x/y symmetry
    par = ldi_map(PAR, 0.15, n=5)
    assert not np.allclose(par.ldi, par.ldi.T)
    for i in range(5):
        for j in range(5):
            assert par.ldi[i, j] == pytest.approx(
                float(local_design_index(PAR, [par.x[j], par.y[i]])), abs=1e-15)
    d = par.to_dict()
    assert json.loads(json.dumps(d))["half_width"] == 0.15


def test_ldi_map_input_checks():
    with pytest.raises(InputError, match=r"n must be an int"):
        ldi_map(PAP, n=1)
    with pytest.raises(InputError, match="half_width must be > 0"):
        ldi_map(PAP, -0.5)
    with pytest.raises(InputError, match="TwoPaP or TwoPPa"):
        ldi_map("2-PaP")


@pytest.mark.parametrize("frac", [0.3, 0.7, 0.95])
def test_gdi_of_a_2pap_over_a_smaller_square(frac):
    la, w = PAP.la, frac * PAP.la
    res = global_design_index(PAP, w)
    assert res.half_width == w
    assert res.ldi_max == pytest.approx(la, abs=1e-12)
    assert res.ldi_min == pytest.approx(math.sqrt(la * la - w * w), abs=1e-12)
    assert res.gdi == pytest.approx(math.sqrt(1 - frac * frac), abs=1e-12)
    assert res.ldi_max_over_min == pytest.approx(1 / res.gdi, rel=1e-12)
    assert_allclose(res.p_max, [0.0, 0.0], atol=1e-9)
    assert np.max(np.abs(res.p_min)) == pytest.approx(w, abs=1e-12)


@pytest.mark.parametrize("w", [0.2, 0.4, 0.6])
def test_gdi_of_a_2ppa_over_a_smaller_square(w):
    t = math.tan(math.asin(w / PPA.la))
    res = global_design_index(PPA, w)
    assert res.ldi_max == pytest.approx(1.0, abs=1e-12)
    assert res.ldi_min == pytest.approx(1 / (1 + t), abs=1e-12)
    assert res.gdi == pytest.approx(1 / (1 + t), abs=1e-12)
    assert_allclose(np.abs(res.p_min), [w, w], atol=1e-9)
    assert np.sign(res.p_min[0]) == np.sign(res.p_min[1])


def test_a_square_reaching_a_singularity_has_zero_gdi():
    """2-PaP over |p_i| <= la: the links reach 90 deg on the edge, LDI 0 there."""
    res = global_design_index(PAP, PAP.la, n=5)
    assert res.ldi_min == pytest.approx(0.0, abs=1e-7)
    assert res.gdi == pytest.approx(0.0, abs=1e-7)
    # on the grid the edge is a node: LDI = la cos(asin(1)), zero to rounding
    exact = global_design_index(PAP, PAP.la, n=5, refine=0)
    assert exact.ldi_min <= 1e-15 * PAP.la and exact.gdi <= 1e-15
    assert np.max(np.abs(exact.p_min)) == PAP.la
    assert exact.ldi_max_over_min >= 1e15


def test_refinement_only_improves_the_grid_and_counts_evaluations():
    grid = global_design_index(PPA, 0.45, n=4, refine=0)       # even n: no centre node
    assert grid.evaluations == 16
    assert grid.ldi_max < 1.0                                    # the centre was missed
    fine = global_design_index(PPA, 0.45, n=4, refine=3)
    assert fine.evaluations > 16
    assert fine.ldi_max >= grid.ldi_max and fine.ldi_min <= grid.ldi_min
    assert fine.ldi_max == pytest.approx(1.0, abs=1e-10)
    json.dumps(fine.to_dict())


def test_gdi_input_checks():
    with pytest.raises(InputError, match="n must be an int"):
        global_design_index(PAP, n=2)
    with pytest.raises(InputError, match="TwoPaP or TwoPPa"):
        global_design_index(3.0)


def test_closed_form_indices_and_their_deprecated_name():
    th = PAP.theta_limit
    assert closed_form_design_indices(PAP) == {"ldi_max": PAP.la,
                                               "ldi_min": PAP.la * math.cos(th),
                                               "gdi": math.cos(th)}
    v = 1 / (1 + math.tan(PPA.theta_limit))
    assert closed_form_design_indices(PPA) == {"ldi_max": 1.0, "ldi_min": v, "gdi": v}
    with pytest.raises(InputError, match="perpendicular 2-PPa only"):
        closed_form_design_indices(PAR)
    with pytest.warns(DeprecationWarning, match="closed_form_design_indices"):
        assert table1_closed_form(PPA) == closed_form_design_indices(PPA)


def test_deprecated_ratio_alias():
    res = global_design_index(PAP, n=5)
    with pytest.warns(DeprecationWarning, match="ldi_max_over_min"):
        assert res.ratio_eq28 == res.ldi_max_over_min
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert res.ldi_max_over_min == pytest.approx(1 / math.cos(PAP.theta_limit), rel=1e-12)


def test_a_square_beyond_the_workspace_is_flagged():
    """A 2-PPa whose stroke limits leave part of the prescribed square out of
    reach: the indices are the formula's over the square, and the result says
    the square leaves the workspace; over the effective square it does not."""
    from mechanisms.manipulators.models import two_ppa
    from mechanisms.manipulators.workspace import effective_square
    m = two_ppa(150, 300, 200, 35, b=60, unit="deg")
    res = global_design_index(m)
    assert not res.within_workspace and "leaves the workspace" in repr(res)
    assert res.to_dict()["within_workspace"] is False
    inside = global_design_index(m, effective_square(m).half_width)
    assert inside.within_workspace and "leaves" not in repr(inside)
