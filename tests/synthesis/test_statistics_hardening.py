"""Statistical yield on the eccentric cam, whose failure region is known exactly.

A part of :func:`mechanisms.models.eccentric_cam` is defective exactly when
``|d_cam_y + d_disc_r - d_face| + |d_ecc| > 0.03`` (cm): four faces, one per
sign of ``S = d_cam_y + d_disc_r - d_face`` and of ``d_ecc``, equally likely
by symmetry, and ``cam_x``, ``half_w`` and ``thick`` play no part.  With every
parameter normal of sigma s, a face is the plane ``|S| + |e| = 0.03`` at
standard distance ``beta = 0.03 / (2 s)`` (4.5 at Cp 1), and
``P = int phi_e(e) 2 Phi(-(L - |e|) / (sqrt 3 s)) de + 2 Phi(-L / s)``.  With
the default truncated normal at Cp 1 the exact rate is 3.30 ppm.
"""

import dataclasses
import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import integrate
from scipy.special import ndtr
from scipy.stats import norm

from cspace.errors import InputError
from mechanisms.models import Distribution, eccentric_cam
from synthesis.executors import SerialExecutor
from synthesis.statistics import (DEFENSIVE, IS_MIN_FAILURES, clopper_pearson,
                                  standard_space, weighted_interval, yield_estimate)

LIFT = 0.03
TOL = 0.01
TRUTH_TN_CP1 = 3.3034e-06           # default truncated normal, Cp 1 (exact)
NAMES = ("cam_x", "cam_y", "ecc", "disc_r", "face", "half_w", "thick")


@pytest.fixture(scope="module")
def serial():
    return SerialExecutor()


def cam(dist=None, tol=None):
    """The eccentric cam with every parameter spread by ``dist`` (default: the
    default distribution) and, optionally, every tolerance ``tol``."""
    m = eccentric_cam()
    if tol is not None:
        m = m.with_tolerances(tol)
    ps = tuple(dataclasses.replace(p, distribution=dist) for p in m.parameters)
    return dataclasses.replace(m, parameters=ps)


def p_normal(cp):
    s = TOL / (3 * cp)
    f = lambda e: norm.pdf(e, scale=s) * 2 * norm.sf((LIFT - abs(e)) / (math.sqrt(3) * s))
    v, _ = integrate.quad(f, -LIFT, LIFT, points=[0], epsabs=1e-16, limit=200)
    return v + 2 * norm.sf(LIFT / s)


def _finite_json(r):
    return json.loads(json.dumps(r.to_dict(), allow_nan=False))


# ------------------------------------------------------------------ design points

@pytest.fixture(scope="module")
def normal_cp1(serial):
    r = yield_estimate(cam(Distribution("normal", cp=1)), 300, method="is", seed=0,
                       accuracy="fast", executor=serial)
    return r, p_normal(1.0)


def test_all_four_failure_faces_are_found(normal_cp1):
    r, _ = normal_cp1
    assert len(r.design_points) == 4
    assert "importance sampling around 4 of 4 design point(s)" in r.message
    assert "HL-RF steps without settling" not in r.message
    i = {n: k for k, n in enumerate(NAMES)}
    faces = set()
    for p in r.design_points:
        assert p.converged
        assert_allclose(p.beta, LIFT / (2 * TOL / 3), atol=0.02)     # 4.5
        z = p.z
        # on a face: z_y = z_r = -z_face = sign(S) beta / 2, z_ecc = sign(e) beta / 2
        assert_allclose(np.abs(z[[i["cam_y"], i["ecc"], i["disc_r"], i["face"]]]), 2.25,
                        atol=0.03)
        assert_allclose(z[i["disc_r"]], z[i["cam_y"]], atol=0.03)
        assert_allclose(z[i["face"]], -z[i["cam_y"]], atol=0.03)
        # the parameters without influence do not move the point
        assert_allclose(z[[i["cam_x"], i["half_w"], i["thick"]]], 0.0, atol=1e-6)
        for n in ("cam_y", "ecc", "disc_r", "face"):
            assert_allclose(p.shares[n], 0.25, atol=0.01)
        faces.add((int(np.sign(z[i["cam_y"]])), int(np.sign(z[i["ecc"]]))))
    assert faces == {(-1, -1), (-1, 1), (1, -1), (1, 1)}


def test_normal_estimate_covers_the_closed_form(normal_cp1):
    r, truth = normal_cp1
    assert r.ci_method == "weighted-normal"
    assert r.ci[0] <= truth <= r.ci[1]
    assert 0.8 < r.probability / truth < 1.25
    # FORM of one face is a quarter of the union bound of four
    assert_allclose(r.p_form, float(ndtr(-4.5)), rtol=0.05)
    _finite_json(r)


def test_importance_sampling_coverage_default_distribution(serial):
    """Five seeds on the default truncated normal at Cp 1 (exact 3.30 ppm).
    Before the design points were told apart by the coordinates that matter,
    1 to 3 of the 4 faces were sampled around, the estimate was 0.6 of the
    truth and the interval covered it in 6 of 20 seeds."""
    m = cam()
    est, cover = [], 0
    for s in range(5):
        r = yield_estimate(m, 200, method="is", seed=s, accuracy="fast", executor=serial)
        assert len(r.design_points) == 4
        est.append(r.probability)
        cover += r.ci[0] <= TRUTH_TN_CP1 <= r.ci[1]
    assert cover >= 4
    assert 0.8 < np.mean(est) / TRUTH_TN_CP1 < 1.25


# ------------------------------------------------------------------ small samples

def test_few_failing_samples_give_the_conservative_interval():
    v = np.zeros(500)
    v[:3] = [0.1, 0.2, 0.05]
    p, (lo, hi) = weighted_interval(v)
    assert p == pytest.approx(0.35 / 500)
    assert lo == 0.0 and hi >= clopper_pearson(3, 500)[1] / DEFENSIVE - 1e-12
    # enough failing samples of even weight: the normal interval
    v = np.r_[np.full(2 * IS_MIN_FAILURES, 1e-3), np.zeros(100)]
    p, (lo, hi) = weighted_interval(v)
    assert 0.0 < lo < p < hi < 1e-3
    # many failing samples, one weight dominating: conservative again
    v = np.r_[np.full(2 * IS_MIN_FAILURES, 1e-9), 5.0, np.zeros(100)]
    assert weighted_interval(v)[1][0] == 0.0


def test_the_probability_of_a_reason_is_at_most_one():
    """Importance weights reach 1 / DEFENSIVE: with every sample failing (a
    spread far wider than the part) the reasons' sums gave 1.3 while P was
    clipped to 1."""
    from types import SimpleNamespace
    from synthesis.statistics import breakdown
    r = SimpleNamespace(defective=True, reasons=(SimpleNamespace(name="INVALID"),), where=(0,))
    tests = SimpleNamespace(pair_name=lambda r: "pair")
    by_reason, by_pair = breakdown(tests, [r] * 4, np.full(4, 1.3))
    assert by_reason == {"INVALID": 1.0} and by_pair == {"pair": 1.0}
    by_reason, _ = breakdown(tests, [r] * 4, np.full(4, 0.5))
    assert by_reason == {"INVALID": 0.5}


def test_small_importance_sample_does_not_exclude_the_truth(serial):
    m = cam(Distribution("normal", cp=0.3))
    r = yield_estimate(m, 5, method="is", seed=0, accuracy="fast", executor=serial)
    assert r.ci_method == "weighted-conservative" and "too few" in r.message
    assert r.ci == (0.0, 1.0)
    _finite_json(r)


# ------------------------------------------------------------------ starts

def test_starts_outside_the_support_are_refused(serial):
    m = cam(Distribution("uniform"))
    with pytest.raises(InputError, match="inside the support of 'cam_x'.*uniform"):
        yield_estimate(m, 20, method="is", starts=[m.nominal + 5 * m.tol], executor=serial)
    fixed = cam(tol=0.0)
    with pytest.raises(InputError, match="at its nominal"):
        yield_estimate(fixed, 20, method="is", starts=[fixed.nominal + 0.01],
                       executor=serial)


@pytest.mark.parametrize("starts", ["abc", [[1.0, 2.0], [3.0]], {"a": 1}])
def test_starts_that_are_no_table_of_numbers_are_refused(serial, starts):
    """A string or ragged rows raised numpy's ValueError."""
    with pytest.raises(InputError, match=r"starts must be finite parameter vectors of shape "
                                         r"\(k, 7\), got "):
        yield_estimate(cam(), 20, method="is", starts=starts, executor=serial)


@pytest.mark.parametrize("dist", [None, Distribution("uniform")])
def test_a_box_corner_start_is_moved_inside(serial, dist):
    m = cam(dist)
    # a defective corner: S = +3 tol, e = +tol
    corner = m.nominal + m.tol * np.array([1, 1, 1, 1, -1, 1, 1])
    r = yield_estimate(m, 100, method="is", seed=0, accuracy="fast", executor=serial,
                       starts=[corner])
    assert r.design_points and all(math.isfinite(p.beta) for p in r.design_points)
    assert len(r.design_points) == 4            # the second round finds the other faces
    assert 0.0 < r.probability and r.ci[0] <= r.probability <= r.ci[1] <= 1.0
    _finite_json(r)


def test_a_healthy_start_is_not_a_design_point(serial):
    m = cam()
    r = yield_estimate(m, 30, method="is", seed=0, accuracy="fast", executor=serial,
                       starts=[m.nominal])
    assert not r.design_points and r.p_form is None
    assert "given starts are not defective" in r.message
    assert r.ci_method == "clopper-pearson"


# ------------------------------------------------------------------ degenerate spreads

def test_defective_nominal_has_no_design_point_with_mc(serial):
    m = cam()
    shifted = m.with_nominal(m.nominal + np.array([0, 0.05, 0, 0, 0, 0, 0]))
    r = yield_estimate(shifted, 30, method="mc", intent=m, accuracy="fast", executor=serial)
    assert r.probability == 1.0 and not r.design_points and r.p_form is None
    assert r.contributors == {} and "nominal itself is defective" in r.message
    assert "FORM" not in repr(r)


@pytest.mark.parametrize("method", ["mc", "is"])
def test_no_spread_is_exact(serial, method):
    m = cam(tol=0.0)
    r = yield_estimate(m, 50, method=method, accuracy="fast", executor=serial)
    assert r.probability == 0.0 and r.ci == (0.0, 0.0) and r.ci_method == "exact"
    assert r.tests == 1 and "no parameter has a spread" in r.message
    bad = m.with_nominal(m.nominal + np.array([0, 0.05, 0, 0, 0, 0, 0]))
    r = yield_estimate(bad, 50, method=method, accuracy="fast", executor=serial, intent=m)
    assert r.probability == 1.0 and r.ci == (1.0, 1.0) and not r.design_points
    _finite_json(r)


def test_zero_tolerance_keeps_the_nominal_unless_sigma_is_stated():
    # tol 0 without sigma: no spread; a stated sigma is a spread of its own
    assert not standard_space(cam(Distribution("normal", cp=1), tol=0.0)).active.any()
    assert not standard_space(cam(tol=0.0)).active.any()
    sp = standard_space(cam(Distribution("normal", sigma=0.002), tol=0.0))
    assert sp.active.all()
    assert_allclose(sp.sigma, 0.002)


def test_a_failure_region_beyond_the_box_is_found_for_untruncated_normals(serial):
    """Every parameter normal with sigma 0.005 but a tolerance of 0.005: no
    box corner is defective (|S| + |e| <= 0.02 < 0.03 there), yet the faces
    lie at beta = 0.03 / (2 * 0.005) = 3 standard units.  The corners are
    probed again at PROBE_FAR standard units: importance sampling finds the
    faces and the estimate covers the exact rate (it fell back to plain
    Monte Carlo and reported that no failure region was found)."""
    s = 0.005
    m = cam(Distribution("normal", sigma=s), tol=s)
    r = yield_estimate(m, 300, method="is", seed=0, accuracy="fast", executor=serial)
    assert r.design_points and r.ci_method.startswith("weighted")
    assert "no failure region" not in r.message
    assert_allclose(min(p.beta for p in r.design_points), LIFT / (2 * s), atol=0.02)
    f = lambda e: norm.pdf(e, scale=s) * 2 * norm.sf((LIFT - abs(e)) / (math.sqrt(3) * s))
    v, _ = integrate.quad(f, -LIFT, LIFT, points=[0], epsabs=1e-16, limit=200)
    truth = v + 2 * norm.sf(LIFT / s)
    assert r.ci[0] <= truth <= r.ci[1]


def test_a_failure_region_between_the_box_and_a_wider_support_is_found(serial):
    """Truncated normals with limit 2 reach twice the tolerance: every box
    corner is healthy (|S| + |e| <= 4 t = 0.02 < 0.03), the support's
    corners are not (8 t = 0.04).  The probe tests the support's corners,
    so importance sampling finds the faces and covers the rate (it probed
    the box's, found no defective corner and fell back to plain Monte Carlo
    with P = 0)."""
    from scipy.stats import truncnorm
    t = 0.005
    m = cam(Distribution("truncated_normal", sigma=t, limit=2.0), tol=t)
    r = yield_estimate(m, 300, method="is", seed=0, accuracy="fast", executor=serial)
    assert r.design_points and "no failure region" not in r.message
    rng = np.random.default_rng(1)
    x = truncnorm(-2.0, 2.0, scale=t).rvs(size=(4, 2_000_000), random_state=rng)
    truth = float(np.mean(np.abs(x[0] + x[1] - x[2]) + np.abs(x[3]) > LIFT))
    assert 2e-4 < truth < 2e-2
    assert r.ci[0] <= truth <= r.ci[1]


def test_a_truncated_normal_of_tiny_sigma_keeps_finite_coordinates(serial):
    """Tolerances of 42 sigma (a capability of 14): the tails beyond some 37
    standard units underflow.  The box corners had infinite standard
    coordinates; the design points and weights became inf and NaN, and the
    command line lost the run writing them (NaN is no JSON).  The
    coordinates are now read from logarithms of the tails: finite, and
    the transforms' round trip holds to rounding there and far beyond."""
    from synthesis.statistics import _truncated_coordinate, _truncated_quantile
    for b in (3.0, 10.0, 40.0, 100.0):
        x = np.array([0.5, -0.5 * b, 0.9 * b, 0.999 * b, -0.999 * b])
        z = _truncated_coordinate(x, b)
        assert np.all(np.isfinite(z)) and np.all(np.diff(np.sign(z)) == np.diff(np.sign(x)))
        assert_allclose(_truncated_quantile(z, b), x, rtol=1e-12, atol=1e-12)
    # scipy's quantile beyond 8.2 standard units gave 8.198 for every z
    assert_allclose(_truncated_quantile(np.array([9.0]), 10.0), [9.0], rtol=1e-5)
    r = yield_estimate(cam(Distribution("truncated_normal", cp=14)), 40, method="is",
                       seed=0, accuracy="fast", executor=serial)
    d = _finite_json(r)
    assert all(np.all(np.isfinite(p.z)) for p in r.design_points)
    assert 0.0 <= r.probability <= r.ci[1] and d["failing_parts"]
