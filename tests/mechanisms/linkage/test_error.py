import math

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from numpy.testing import assert_allclose

from cspace.errors import InputError
from mechanisms.linkage import (EllipseKind, ErrorStatus, FourBar, PoseStatus, ToleranceSpec,
                                coupler_ellipse, dubowsky_deltas, exact_error, harmonic_fit,
                                harmonic_max, input_range, linear_error, monte_carlo,
                                clearance_b_closed_form, rss, sensitivity, solve, worst_case)

from .conftest import (HALF_UNIT, TABLE2_CRANK_DEG, TABLE2_DELTA_DEG, TABLE2_EXACT,
                       TABLE2_LINEAR)

# ---------------------------------------------------------------- Table 2


def test_table2_both_columns_to_printed_digits(paper_fourbar):
    d = TABLE2_DELTA_DEG
    ex = exact_error(paper_fourbar, TABLE2_CRANK_DEG, joint="B", radius=0.1, delta=d,
                     unit="deg")
    li = linear_error(paper_fourbar, TABLE2_CRANK_DEG, joint="B", radius=0.1, delta=d,
                      unit="deg")
    assert ex.success and li.success
    # 1e-12 rad of slack: the linear entries at 60 and 240 deg sit on a rounding tie
    # (0.29615e-2), printed once up and once down
    assert_allclose(ex.d_theta4, np.array(TABLE2_EXACT) * 1e-2, rtol=0, atol=HALF_UNIT + 1e-12)
    assert_allclose(li.d_theta4, np.array(TABLE2_LINEAR) * 1e-2, rtol=0,
                    atol=HALF_UNIT + 1e-12)
    # relative error column (%): the paper formed it from its 4-digit entries, which
    # moves it by up to 0.03 points against the unrounded ratio
    rel = (li.d_theta4 - ex.d_theta4) / ex.d_theta4 * 100
    paper_rel = [-0.10, -0.03, 1.58, -6.48, -1.55, -0.42, 0.11, 0.05, -1.50, 7.36, 1.58, 0.45,
                 -0.10]
    assert_allclose(rel, paper_rel, atol=0.04)


def test_table2_at_design_angle_within_last_digit(paper_fourbar):
    # DESIGN's rounded 62.94 deg: every entry within 1.1 units of the last digit
    d = TABLE2_DELTA_DEG
    ex = exact_error(paper_fourbar, 62.94, joint="B", radius=0.1, delta=d, unit="deg")
    li = linear_error(paper_fourbar, 62.94, joint="B", radius=0.1, delta=d, unit="deg")
    assert_allclose(ex.d_theta4, np.array(TABLE2_EXACT) * 1e-2, rtol=0, atol=2.2 * HALF_UNIT)
    assert_allclose(li.d_theta4, np.array(TABLE2_LINEAR) * 1e-2, rtol=0, atol=2.2 * HALF_UNIT)


def test_open_branch_does_not_reproduce_table2(paper_fourbar):
    fb = paper_fourbar.replace(assembly="open")
    ex = exact_error(fb, TABLE2_CRANK_DEG, joint="B", radius=0.1, delta=TABLE2_DELTA_DEG,
                     unit="deg")
    assert np.max(np.abs(ex.d_theta4 - np.array(TABLE2_EXACT) * 1e-2)) > 10 * HALF_UNIT


# ---------------------------------------------------------------- sensitivity linkage


def test_general_velocity_solution_matches_eqs_19_20_25(paper_fourbar):
    t2 = math.radians(72.0)
    delta = np.linspace(0, 2 * np.pi, 37)
    s = sensitivity(paper_fourbar, t2, "B", delta)
    beta = delta + t2 + math.pi
    cf = clearance_b_closed_form(paper_fourbar, t2, beta)
    assert_allclose(s.dtheta3, cf.omega3, atol=1e-13)
    assert_allclose(s.dtheta4, cf.omega4, atol=1e-13)
    assert_allclose(s.dP, cf.vP, atol=1e-13)


@pytest.mark.parametrize("source", ["l1", "l2", "l3", "l4", "lp", "alpha", "theta1"])
def test_length_sensitivity_matches_central_difference(paper_fourbar, source):
    t2 = 1.1
    h = 1e-6
    s = sensitivity(paper_fourbar, t2, source)
    ep = exact_error(paper_fourbar, t2, dl={source: h})
    em = exact_error(paper_fourbar, t2, dl={source: -h})
    assert_allclose(s.dtheta3, (ep.d_theta3 - em.d_theta3) / (2 * h), atol=1e-7)
    assert_allclose(s.dtheta4, (ep.d_theta4 - em.d_theta4) / (2 * h), atol=1e-7)
    assert_allclose(s.dP, (ep.dP - em.dP) / (2 * h), atol=1e-7)


@pytest.mark.parametrize("joint", ["A", "B", "C", "D"])
def test_clearance_sensitivity_matches_exact_small_radius(paper_fourbar, joint):
    t2 = 1.1
    r = 1e-7
    d = np.linspace(0, 2 * np.pi, 13)
    s = sensitivity(paper_fourbar, t2, joint, d)
    ex = exact_error(paper_fourbar, t2, joint=joint, radius=r, delta=d)
    assert_allclose(s.dtheta4, ex.d_theta4 / r, atol=1e-5)
    assert_allclose(s.dP, ex.dP / r, atol=1e-5)


def test_theta4_error_depends_only_on_total_clearance_vector(paper_fourbar):
    # a consequence of the loop closure: all joints give the same first-order
    # theta4 error for the same world pin direction
    t2 = 0.9
    beta = np.linspace(0, 2 * np.pi, 9)
    m = solve(paper_fourbar, t2)
    ref = {"A": paper_fourbar.theta1, "B": t2, "C": m.theta3[0], "D": m.theta4[0]}
    vals = [sensitivity(paper_fourbar, t2, j, beta - ref[j] - math.pi).dtheta4 for j in "ABCD"]
    for v in vals[1:]:
        assert_allclose(v, vals[0], atol=1e-13)


# ---------------------------------------------------------------- harmonic / Dubowsky


def test_harmonic_fit_recovers_parameters():
    d = np.array([0.3, 1.9, 4.0])
    c, A, ph = harmonic_fit(0.2 + 1.5 * np.cos(d - 2.5), d)
    assert_allclose([c, A, ph], [0.2, 1.5, 2.5], atol=1e-12)
    with pytest.raises(InputError, match="distinct"):
        harmonic_fit([1, 2, 3], [0.0, 0.0, 1.0])


def test_harmonic_three_points_vs_dense_sweep(paper_fourbar):
    t2 = math.radians(TABLE2_CRANK_DEG)
    dense = np.linspace(0, 2 * np.pi, 20001)
    lin = linear_error(paper_fourbar, t2, joint="B", radius=0.1, delta=dense)
    hl = harmonic_max(paper_fourbar, t2, "B", 0.1, method="linear")
    assert hl.evaluations == 3
    assert_allclose(hl(dense), lin.d_theta4, atol=1e-15)        # exactly harmonic
    ex = exact_error(paper_fourbar, t2, joint="B", radius=0.1, delta=dense)
    he = harmonic_max(paper_fourbar, t2, "B", 0.1, method="exact")
    i = np.argmax(ex.d_theta4)
    # the exact error is harmonic up to second order in r / l (here r = 1.25 % of l2)
    assert abs(he.max_value - ex.d_theta4[i]) < 3e-3 * he.amplitude
    assert abs(math.remainder(he.delta_max - dense[i], 2 * math.pi)) < 0.02
    assert np.max(np.abs(he(dense) - ex.d_theta4)) < 0.02 * he.amplitude


def test_dubowsky_collinearity(paper_fourbar):
    t2 = math.radians(TABLE2_CRANK_DEG)
    for joint in "ABCD":
        h = harmonic_max(paper_fourbar, t2, joint, 0.1, method="linear")
        da, db = dubowsky_deltas(paper_fourbar, t2, joint)
        # {da, db} equals {delta_max, delta_min} modulo 2 pi
        for x in (h.delta_max, h.delta_min):
            gap = min(abs(math.remainder(x - da, 2 * math.pi)),
                      abs(math.remainder(x - db, 2 * math.pi)))
            assert gap < 1e-12
        assert abs(abs(math.remainder(da - db, 2 * math.pi)) - math.pi) < 1e-12
    # at the maximising angle of joint B the pin offset is collinear with BC
    m = solve(paper_fourbar, t2)
    h = harmonic_max(paper_fourbar, t2, "B", 0.1, method="linear")
    beta = h.delta_max + t2 + math.pi
    assert abs(math.sin(beta - m.theta3[0])) < 1e-12


# ---------------------------------------------------------------- ellipse


def test_coupler_ellipse_b_and_segment_at_c(paper_fourbar):
    t2 = math.radians(72.0)
    beta = np.linspace(0, 2 * np.pi, 3601)
    ell = coupler_ellipse(paper_fourbar, t2, "B", 0.1)
    assert ell.kind is EllipseKind.ELLIPSE
    m = solve(paper_fourbar, t2)
    li = linear_error(paper_fourbar, t2, joint="B", radius=0.1, delta=beta - t2 - math.pi)
    assert_allclose(ell.implicit(li.dP), 0.0, atol=1e-9)
    rad = np.hypot(*li.dP.T)
    assert_allclose([rad.max(), rad.min()], [ell.semi_major, ell.semi_minor], atol=1e-6)
    # exact errors lie near the ellipse (second-order deviation)
    ex = exact_error(paper_fourbar, t2, joint="B", radius=0.01, delta=beta)
    e2 = coupler_ellipse(paper_fourbar, t2, "B", 0.01)
    assert np.max(np.abs(e2.implicit(ex.dP))) < 0.05
    for joint in "CD":
        ec = coupler_ellipse(paper_fourbar, t2, joint, 0.1)
        assert ec.kind is EllipseKind.SEGMENT
        # the segment is perpendicular to B -> P (P turns about B)
        bp = m.P[0] - m.B[0]
        u = np.array([math.cos(ec.orientation), math.sin(ec.orientation)])
        assert abs(np.dot(u, bp)) < 1e-9 * np.linalg.norm(bp)
    assert coupler_ellipse(paper_fourbar, t2, "A", 0.1).kind is EllipseKind.ELLIPSE
    assert "ellipse" in repr(ell) and ell.to_dict()["kind"] == "ellipse"


# ---------------------------------------------------------------- linear vs exact


def _rel_err(fb, t2, r, joint="B"):
    d = np.linspace(0, 2 * np.pi, 721)
    ex = exact_error(fb, t2, joint=joint, radius=r, delta=d)
    li = linear_error(fb, t2, joint=joint, radius=r, delta=d)
    return np.max(np.abs(ex.d_theta4 - li.d_theta4)) / np.max(np.abs(ex.d_theta4))


def test_linear_vs_exact_below_one_percent_and_grows_linearly(paper_fourbar):
    t2 = math.radians(TABLE2_CRANK_DEG)
    l2 = paper_fourbar.crank
    for frac in (1e-4, 5e-4, 1e-3):
        for joint in "ABCD":
            assert _rel_err(paper_fourbar, t2, frac * l2, joint) < 0.01
    e1 = _rel_err(paper_fourbar, t2, 1e-3 * l2)
    e2 = _rel_err(paper_fourbar, t2, 2e-3 * l2)
    assert 1.8 < e2 / e1 < 2.2        # the gap is second order: relative error ~ r


# ---------------------------------------------------------------- hypothesis


fourbars = st.tuples(st.floats(1.0, 5.0), st.floats(0.5, 5.0), st.floats(0.5, 5.0),
                     st.floats(0.5, 5.0), st.floats(0.0, 3.0), st.floats(-3.0, 3.0),
                     st.sampled_from(["open", "crossed"]), st.floats(0.0, 1.0))


def _drawn_pose(spec):
    """The four-bar of a drawn spec and its pose at the drawn input (a fraction
    ``u`` of the full turn, or of the input range of a rocker)."""
    l1, l2, l3, l4, lp, alpha, asm, u = spec
    # a loop whose longest link is as long as the other three never closes
    # (FourBar refuses it)
    assume(2 * max(l1, l2, l3, l4) < l1 + l2 + l3 + l4)
    fb = FourBar.from_lengths(l1, l2, l3, l4, lp, alpha, assembly=asm)
    rng = input_range(fb)
    if rng.full_turn:
        t2 = 2 * math.pi * u
    else:
        assume(rng.limits)
        lo, hi = rng.limits
        t2 = lo + (hi - lo) * u
    return fb, t2, solve(fb, t2)


@settings(max_examples=80, deadline=None)
@given(fourbars)
def test_harmonic_ellipse_claims_on_random_fourbars(spec):
    l1, l2, l3, l4 = spec[:4]
    fb, t2, m = _drawn_pose(spec)
    assume(m.status[0] != PoseStatus.UNASSEMBLABLE)
    r = 1e-3 * min(l1, l2, l3, l4)
    h = harmonic_max(fb, t2, "B", r, method="linear")
    s34 = abs(math.sin(m.theta3[0] - m.theta4[0]))
    if s34 < 1e-3:
        # near toggle: the result must say so rather than be silently wrong
        assert m.status[0] == PoseStatus.NEAR_TOGGLE and h.status == ErrorStatus.NEAR_TOGGLE
        return
    assert h.status == ErrorStatus.OK
    dense = np.linspace(0, 2 * np.pi, 181)
    li = linear_error(fb, t2, joint="B", radius=r, delta=dense)
    assert_allclose(h(dense), li.d_theta4, atol=1e-12 * max(h.amplitude, 1e-300) + 1e-15)
    da, db = dubowsky_deltas(fb, t2, "B")
    assert min(abs(math.remainder(h.delta_max - da, 2 * math.pi)),
               abs(math.remainder(h.delta_max - db, 2 * math.pi))) < 1e-9
    ell = coupler_ellipse(fb, t2, "B", r)
    if ell.kind is EllipseKind.ELLIPSE:
        # the linear errors lie on the ellipse.  The implicit form x^T Q x - 1
        # turns an error e across a slender ellipse into about 2 e / b: points
        # within 1e-9 a of the curve give at most 1e-6 + 4e-9 a / b
        a, b = ell.semi_major, ell.semi_minor
        assert np.max(np.abs(ell.implicit(li.dP))) < 1e-6 + 4e-9 * a / b
    assert coupler_ellipse(fb, t2, "C", r).kind in (EllipseKind.SEGMENT, EllipseKind.POINT)


def test_near_toggle_reported():
    fb = FourBar.from_lengths(5.0, 2.0, 3.0, 2.5)        # non-Grashof
    lo, hi = input_range(fb).limits
    h = harmonic_max(fb, hi - 1e-9, "B", 1e-4, method="linear")
    assert h.status is ErrorStatus.NEAR_TOGGLE
    ex = exact_error(fb, hi - 1e-9, joint="B", radius=1e-3, delta=np.linspace(0, 6, 7))
    assert set(ex.status.tolist()) <= {ErrorStatus.NEAR_TOGGLE, ErrorStatus.UNASSEMBLABLE}
    assert np.any(ex.status == ErrorStatus.UNASSEMBLABLE)
    assert np.all(np.isfinite(ex.d_theta4))


# ---------------------------------------------------------------- combined


SPEC = ToleranceSpec({"l1": 0.01, "l2": 0.01, "l3": 0.01, "l4": 0.01},
                     {"A": 0.005, "B": 0.01, "C": 0.005, "D": 0.005})


def test_worst_case_bounds_monte_carlo_and_rss(paper_fourbar):
    t2 = 1.1
    wc = worst_case(paper_fourbar, t2, SPEC)
    assert wc.success and wc.status is ErrorStatus.OK
    mc = monte_carlo(paper_fourbar, t2, SPEC, n=4000, seed=3)
    assert mc.maximum <= wc.exact_max + 1e-12 and mc.minimum >= wc.exact_min - 1e-12
    assert_allclose(wc.exact_max, wc.linear_max, rtol=0.03)
    assert_allclose(wc.exact_min, wc.linear_min, rtol=0.03)
    r = rss(paper_fourbar, t2, SPEC)
    assert max(r.contributions.values()) <= r.value <= wc.linear_max
    assert_allclose(sum(r.contributions.values()), wc.linear_max, atol=1e-15)
    # the exact optimum is attained: re-evaluate at its argument
    dl = {k: v for k, v in wc.argmax.items() if k.startswith("l")}
    assert all(abs(v) <= SPEC.lengths[k] + 1e-15 for k, v in dl.items())
    for j in "ABCD":
        assert math.hypot(*wc.argmax[j]) <= SPEC.clearances[j] + 1e-15
    assert "WorstCase(theta4" in repr(wc) and wc.to_dict()["status"] == "OK"


def test_worst_case_coupler_point(paper_fourbar):
    wc = worst_case(paper_fourbar, 1.1, SPEC, quantity="px")
    mc = monte_carlo(paper_fourbar, 1.1, SPEC, n=2000, seed=5, quantity="px", pins="disc")
    assert mc.maximum <= wc.exact_max + 1e-12
    assert wc.exact_max > 0.5 * wc.linear_max


def test_monte_carlo_seeded_and_ci(paper_fourbar):
    a = monte_carlo(paper_fourbar, 1.1, SPEC, n=500, seed=11)
    b = monte_carlo(paper_fourbar, 1.1, SPEC, n=500, seed=np.random.default_rng(11))
    c = monte_carlo(paper_fourbar, 1.1, SPEC, n=500, seed=12)
    assert_allclose(a.samples, b.samples, atol=0)
    assert not np.allclose(a.samples, c.samples)
    assert a.ci[0] < a.mean < a.ci[1]
    big = monte_carlo(paper_fourbar, 1.1, SPEC, n=8000, seed=11)
    w_small, w_big = a.ci[1] - a.ci[0], big.ci[1] - big.ci[0]
    assert_allclose(w_small / w_big, 4.0, rtol=0.15)       # ~ 1/sqrt(n)
    assert a.n_feasible + a.n_infeasible == 500 and a.n_infeasible == 0


def test_monte_carlo_counts_infeasible_samples():
    fb = FourBar.from_lengths(5.0, 2.0, 3.0, 2.5)        # non-Grashof, near its limit
    lo, hi = input_range(fb).limits
    spec = ToleranceSpec({"l3": 0.05, "l4": 0.05}, {"B": 0.02})
    mc = monte_carlo(fb, hi - 0.01, spec, n=1000, seed=1)
    assert 0 < mc.n_infeasible < 1000
    assert mc.n_feasible + mc.n_infeasible == 1000
    assert mc.samples.size == mc.n_feasible
    assert np.all(np.isfinite(mc.samples))


def test_bad_inputs(paper_fourbar):
    with pytest.raises(InputError, match="joint must be one of"):
        exact_error(paper_fourbar, 1.0, joint="E", radius=0.1)
    with pytest.raises(InputError, match="source must be"):
        sensitivity(paper_fourbar, 1.0, "l9")
    with pytest.raises(InputError, match="quantity must be one of"):
        rss(paper_fourbar, 1.0, SPEC, quantity="speed")
    with pytest.raises(InputError, match="seed must be"):
        monte_carlo(paper_fourbar, 1.0, SPEC, seed="abc")
    with pytest.raises(InputError, match="radius must be >= 0"):
        linear_error(paper_fourbar, 1.0, joint="B", radius=-0.1)
    with pytest.raises(InputError, match="tolerance keys"):
        ToleranceSpec({"l7": 0.1})
    with pytest.raises(InputError, match="n must be an int"):
        monte_carlo(paper_fourbar, 1.0, SPEC, n=1)
    # a clearance radius without its joint was silently ignored (error 0)
    for f in (exact_error, linear_error):
        with pytest.raises(InputError, match="radius 0.1 is a clearance at a joint, but no "
                                             "joint was given"):
            f(paper_fourbar, 1.0, radius=0.1)


@pytest.mark.slow
@settings(max_examples=1000, deadline=None)
@given(fourbars, st.sampled_from(["A", "B", "C", "D"]))
def test_slow_sensitivities_match_exact_on_many_fourbars(spec, joint):
    l1, l2, l3, l4 = spec[:4]
    fb, t2, m = _drawn_pose(spec)
    assume(m.status[0] == PoseStatus.OK)
    assume(abs(math.sin(m.theta3[0] - m.theta4[0])) > 0.05)
    r = 1e-7 * min(l1, l2, l3, l4)
    d = np.linspace(0, 2 * np.pi, 7)
    s = sensitivity(fb, t2, joint, d)
    ex = exact_error(fb, t2, joint=joint, radius=r, delta=d)
    scale = 1.0 + np.max(np.abs(s.dtheta4))
    assert_allclose(s.dtheta4, ex.d_theta4 / r, atol=1e-4 * scale)


def test_tolerances_and_clearances_a_part_cannot_have_are_refused():
    """A length tolerance or deviation that makes a link <= 0 long, or a
    clearance as large as the shortest link, is an InputError that names the
    link and its length (not an exact range marked OK for a crank of -5)."""
    fb = FourBar.from_lengths(110, 40, 120, 100)
    with pytest.raises(InputError, match=r"lengths\['l2'\] = 45 gives l2 = -5 <= 0"):
        worst_case(fb, 1.0, ToleranceSpec(lengths={"l2": 45}))
    for f in (rss, lambda *a: monte_carlo(*a, 10, seed=1)):
        with pytest.raises(InputError, match="must leave the length > 0"):
            f(fb, 1.0, ToleranceSpec(lengths={"l1": 110}))
        with pytest.raises(InputError, match="at least the shortest link"):
            f(fb, 1.0, ToleranceSpec(clearances={"B": 50}))
    with pytest.raises(InputError, match="shortest link"):
        linear_error(fb, 1.0, joint="B", radius=1e6, delta=[0.0])
    with pytest.raises(InputError, match=r"dl\['l2'\] = -41 gives l2 = -1"):
        exact_error(fb, 1.0, dl={"l2": -41})
    # a long deviation the other way is a longer link: allowed
    assert exact_error(fb, 1.0, dl={"l2": 41}).success


def test_results_without_a_value_say_so():
    """An exact error of an unassemblable pose and a Monte Carlo in which no
    sample assembles say so in their repr, not as a plain 0."""
    cp = FourBar.from_lengths(120, 40, 100, 60)
    curve = exact_error(cp, 179, dl={"l1": 0.05}, unit="deg")
    assert not curve.success and "UNASSEMBLABLE" in repr(curve)
    fb = FourBar.from_lengths(110, 40, 120, 100)
    assert "UNASSEMBLABLE" not in repr(exact_error(fb, 1.0, dl={"l2": 0.1}))
    far = FourBar.from_lengths(60, 40, 10, 15)      # |BD| = 100 > 25 at theta2 = pi
    mc = monte_carlo(far, math.pi, ToleranceSpec(lengths={"l2": 0.1}), 20, seed=1)
    assert mc.n_feasible == 0 and "no sample assembles" in repr(mc)
    ok = monte_carlo(fb, 1.0, ToleranceSpec(lengths={"l2": 0.1}), 20, seed=1)
    assert ok.n_feasible == 20 and ok.status.name in repr(ok)


def test_an_rss_bound_over_a_box_past_a_toggle_is_not_ok():
    """0.1 deg before the toggle of a change-point linkage a 0.05 tolerance on
    the ground reaches past it: the first-order RSS bound is no bound there,
    and its status says so (it said OK); well inside, it stays OK."""
    cp = FourBar.from_lengths(120, 40, 100, 60)
    spec = ToleranceSpec(lengths={"l1": 0.05})
    assert worst_case(cp, 179.9, spec, unit="deg").status == ErrorStatus.UNASSEMBLABLE
    assert rss(cp, 179.9, spec, unit="deg").status == ErrorStatus.UNASSEMBLABLE
    assert rss(cp, 90, spec, unit="deg").status == ErrorStatus.OK
