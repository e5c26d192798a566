"""The design helper, decoupling and the comparison tables
(``mechanisms.manipulators.design``), against the design equations written
out by hand (Eqs. 6-8 and 24-26 of [Kim 2007])."""

import json
import math

import numpy as np
import pytest

from cspace.errors import InputError, NonFiniteError
from mechanisms.manipulators import (ArrangementPoint, ComparisonTable, Decoupling, Design,
                                     TwoPaP, TwoPPa, arrangement_comparison, comparison_table,
                                     decoupling, design, global_design_index, two_pap,
                                     two_ppa, two_ppa_parallel)


@pytest.mark.parametrize("th", [15.0, 40.0, 75.0])
def test_2pap_design_equations(th):
    w, t, b = 0.7, 0.05, 0.12
    d = design("2-PaP", w, th, t=t, b=b, unit="deg")
    s, c = math.sin(math.radians(th)), math.cos(math.radians(th))
    la = w / s
    assert d.kind == "2-PaP" and d.w == w and d.t == t and d.b == b
    assert d.theta_limit == pytest.approx(math.radians(th), rel=1e-15)
    assert d.la == pytest.approx(la, rel=1e-14)
    assert d.stroke == pytest.approx(2 * w, rel=1e-14)          # passive slide: the square
    assert d.a == pytest.approx(la * (1 + s) + t + b, rel=1e-14)
    assert d.L_min == pytest.approx(la * (1 + 2 * s - c) + 2 * (t + b), rel=1e-14)
    assert d.workspace_per_stroke == pytest.approx(1.0, rel=1e-14)
    assert d.workspace_per_size == pytest.approx(2 * w / d.a, rel=1e-14)
    assert isinstance(d.model, TwoPaP)
    assert d.model.la == d.la and d.model.half_width == pytest.approx(w, rel=1e-14)
    assert (d.model.t, d.model.b) == (t, b)


@pytest.mark.parametrize("th", [10.0, 30.0, 60.0, 85.0])
def test_2ppa_design_equations(th):
    w, b = 130.0, 92.0
    d = design("2-PPa", w, th, b=b, t=55.0, unit="deg")
    s = math.sin(math.radians(th))
    assert d.la == pytest.approx(w / s, rel=1e-14)
    assert d.a == pytest.approx(w * (1 + 1 / s) + b, rel=1e-14)
    assert d.stroke == pytest.approx(w * (2 + 1 / s - math.sqrt(1 / s ** 2 - 1)), rel=1e-13)
    assert d.L_min == 0.0
    m = d.model
    assert isinstance(m, TwoPPa) and m.arrangement.name == "PERPENDICULAR"
    assert (m.la, m.a, m.b, m.stroke) == (d.la, d.a, b, d.stroke)
    assert m.half_width == pytest.approx(w, rel=1e-14)
    # g_i = (b - a) e_i
    np.testing.assert_allclose(m.g, [[b - d.a, 0.0], [0.0, b - d.a]], atol=0)


def test_degrees_and_radians_agree_and_to_dict():
    a = design("2-PPa", 1.0, 30, unit="deg")
    r = design("2-PPa", 1.0, math.pi / 6)
    for k in ("la", "stroke", "a", "theta_limit"):
        assert getattr(a, k) == pytest.approx(getattr(r, k), rel=1e-15)
    d = a.to_dict()
    assert json.loads(json.dumps(d)) == d
    assert d["workspace_per_stroke"] == pytest.approx(2.0 / a.stroke, rel=1e-15)
    assert set(d) == {"kind", "w", "theta_limit", "la", "stroke", "a", "L_min", "t", "b",
                      "workspace_per_stroke", "workspace_per_size"}
    assert "2-PPa" in repr(a) and "theta_L=30 deg" in repr(a)


@pytest.mark.parametrize("args, kw, exc, match", [
    (("2-PaP", 0.0, 30), {"unit": "deg"}, InputError, "w must be > 0"),
    (("2-PaP", -1.0, 30), {"unit": "deg"}, InputError, "w must be > 0"),
    (("2-PaP", math.inf, 30), {"unit": "deg"}, NonFiniteError, "w must be finite"),
    (("2-PaP", 1.0, 0), {"unit": "deg"}, InputError, r"theta_limit must lie in \(0, 90\)"),
    (("2-PPa", 1.0, 90), {"unit": "deg"}, InputError, r"theta_limit must lie in \(0, 90\)"),
    (("2-PPa", 1.0, math.pi / 2), {}, InputError, r"theta_limit must lie in \(0, 90\)"),
    (("2-PaP", 1.0, 30), {"unit": "deg", "t": -0.1}, InputError, "t must be >= 0"),
    (("2-PPa", 1.0, 30), {"unit": "deg", "b": -0.1}, InputError, "b must be >= 0"),
    (("2-ppa", 1.0, 30), {"unit": "deg"}, InputError, "kind must be '2-PaP' or '2-PPa'"),
])
def test_design_rejects_bad_input(args, kw, exc, match):
    with pytest.raises(exc, match=match):
        design(*args, **kw)


def test_decoupling_classes():
    pap = design("2-PaP", 1.0, 45, unit="deg").model
    ppa = design("2-PPa", 1.0, 45, unit="deg").model
    par = two_ppa_parallel(1.0, 1.2, 1.0, 30, unit="deg")
    # 2-PaP: J = la diag(cos th1, cos th2) everywhere
    assert decoupling(pap) is Decoupling.ALWAYS
    # perpendicular 2-PPa: J = [[1, tan th1], [tan th2, 1]], diagonal at p = 0 only
    assert decoupling(ppa) is Decoupling.AT_ONE_POINT
    assert decoupling(ppa, 0.3, n=11) is Decoupling.AT_ONE_POINT
    # parallel arrangement: J = [[tan th1, 1], [-tan th2, 1]] is never diagonal
    assert decoupling(par, 0.15) is Decoupling.NEVER
    with pytest.raises(InputError, match="half_width must be > 0"):
        decoupling(ppa, 0.0)


def test_comparison_table_rows_are_computed_per_design():
    d1 = design("2-PaP", 1.0, 45, unit="deg")
    d2 = design("2-PPa", 1.0, 20, unit="deg")
    t = comparison_table(d1, d2, gdi_grid=11)
    assert isinstance(t, ComparisonTable)
    assert t.columns == ("2-PaP (theta_L = 45 deg)", "2-PPa (theta_L = 20 deg)")
    assert [r for r, _ in t.rows] == ["Decoupled", "GDI", "Workspace/stroke (2w/Delta d)",
                                      "Workspace/size (2w/a)"]
    assert t.value("Decoupled", 0) == "always" and t.value("Decoupled", 1) == "at one point"
    assert t.value("GDI", 0) == pytest.approx(math.cos(math.radians(45)), abs=1e-12)
    assert t.value("GDI", 1) == pytest.approx(1 / (1 + math.tan(math.radians(20))), abs=1e-12)
    assert t.value("GDI", 1) == pytest.approx(global_design_index(d2.model, n=11).gdi, abs=0)
    assert t.value("Workspace/stroke (2w/Delta d)", 1) == pytest.approx(2 / d2.stroke)
    assert t.value("Workspace/size (2w/a)", 0) == pytest.approx(2 / d1.a)
    md = t.to_markdown(digits=4).splitlines()
    assert md[0] == "| Performance | " + " | ".join(t.columns) + " |"
    assert md[1] == "|---|---|---|"
    assert md[3] == f"| GDI | {t.value('GDI', 0):.4f} | {t.value('GDI', 1):.4f} |"
    d = t.to_dict()
    assert json.loads(json.dumps(d)) == d
    assert d["rows"][0] == {"name": "Decoupled", "values": ["always", "at one point"]}
    assert repr(t).startswith("ComparisonTable(4 rows x 2 designs)")


def test_comparison_table_input_checks():
    with pytest.raises(InputError, match="one or more Design values"):
        comparison_table()
    with pytest.raises(InputError, match="one or more Design values"):
        comparison_table(two_pap(1.0, 0.5))
    t = comparison_table(design("2-PaP", 1.0, 45, unit="deg"), gdi_grid=5)
    with pytest.raises(InputError, match=r"no row 'Cost'; rows are \['Decoupled', 'GDI'"):
        t.value("Cost", 0)


def test_arrangement_points_are_optima():
    perp, par = arrangement_comparison()
    assert isinstance(perp, ArrangementPoint) and perp.arrangement == "perpendicular"
    assert par.arrangement == "parallel"
    # no sampled angle pair beats the reported LDI (1 / sigma_max of the J of Eq. 22 / 29)
    g = np.radians(np.linspace(-80, 80, 81))
    T1, T2 = np.meshgrid(np.tan(g), np.tan(g))
    one = np.ones_like(T1)
    for pt, J in ((perp, np.stack([np.stack([one, T1], -1), np.stack([T2, one], -1)], -2)),
                  (par, np.stack([np.stack([T1, one], -1), np.stack([-T2, one], -1)], -2))):
        ldi = 1 / np.linalg.svd(J, compute_uv=False)[..., 0]
        assert ldi.max() <= pt.ldi + 1e-9
        assert pt.condition >= 1.0
        json.dumps(pt.to_dict())
    with pytest.raises(InputError, match="bound_deg must be > 0"):
        arrangement_comparison(bound_deg=0.0)


def test_the_design_is_the_model_the_builder_makes():
    d = design("2-PPa", 0.5, 25, b=0.1, unit="deg")
    m = two_ppa(d.la, d.a, d.stroke, d.theta_limit, b=d.b)
    assert m == d.model
    assert isinstance(d, Design)
