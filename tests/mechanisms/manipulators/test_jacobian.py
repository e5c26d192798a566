"""Velocity Jacobians, the local design index and statics of 2-PaP and 2-PPa
(``mechanisms.manipulators.jacobian``).

Independent references: central finite differences of the inverse
kinematics (the paper's J for 2-PPa is ``dd/dp``, for 2-PaP ``J^-1 = dtheta/dp``),
numpy's SVD for the singular values, and the closed forms of Eq. 22 and Eq. 27.
"""

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError, NonFiniteError
from mechanisms.manipulators import (Singularity, actuator_forces, inverse_kinematics,
                                     jacobians, ldi_map, ldi_of_jacobian, local_design_index,
                                     platform_force, two_pap, two_ppa, two_ppa_parallel)
from mechanisms.manipulators.jacobian import SINGULAR_REL

PAP = two_pap(2.0, 60, unit="deg")
PPA = two_ppa(1.5, 2.0, 1.2, 30, b=0.3, unit="deg")
PAR = two_ppa_parallel(1.0, 1.2, 1.0, 30, unit="deg")
MODELS = {"2-PaP": PAP, "2-PPa": PPA, "parallel": PAR}


def _points(model, n, frac=0.8, seed=0):
    w = model.half_width if model is not PAR else 0.15
    return np.random.default_rng(seed).uniform(-frac * w, frac * w, (n, 2))


def _ik_fd(model, p, h=1e-6):
    """d q / d p by central differences of the inverse kinematics."""
    out = np.zeros((2, 2))
    for k in range(2):
        dp = np.zeros(2)
        dp[k] = h
        out[:, k] = (inverse_kinematics(model, p + dp).q
                     - inverse_kinematics(model, p - dp).q) / (2 * h)
    return out


@pytest.mark.parametrize("name", list(MODELS))
def test_jacobian_against_finite_differences_of_the_ik(name):
    model = MODELS[name]
    for p in _points(model, 15):
        jac = jacobians(model, p)
        dq_dp = _ik_fd(model, p)
        if name == "2-PaP":
            assert_allclose(jac.j @ dq_dp, np.eye(2), atol=1e-8)   # p_dot = J theta_dot
        else:
            assert_allclose(jac.j, dq_dp, atol=1e-8)               # J p_dot = d_dot
        # J_x p_dot = J_q q_dot for every p_dot
        assert_allclose(jac.jx, jac.jq @ dq_dp, atol=1e-8)


def test_batch_shapes_and_determinants():
    p = _points(PPA, 12).reshape(3, 4, 2)
    jac = jacobians(PPA, p)
    for a in (jac.jx, jac.jq, jac.j, jac.g):
        assert a.shape == (3, 4, 2, 2)
    for a in (jac.det_x, jac.det_q, jac.singularity, jac.pose_status):
        assert a.shape == (3, 4)
    assert_allclose(jac.det_x, np.linalg.det(jac.jx), atol=1e-14)
    assert_allclose(jac.det_q, np.linalg.det(jac.jq), atol=1e-14)
    # a batch gives what the single poses give
    one = jacobians(PPA, p[2, 1])
    assert_allclose(one.j, jac.j[2, 1], atol=0)
    # 2-PaP: det_q is made dimensionless by la^2
    jp = jacobians(PAP, _points(PAP, 5))
    assert_allclose(jp.det_q, np.linalg.det(jp.jq) / PAP.la ** 2, atol=1e-14)
    assert_allclose(jp.det_x, 1.0, atol=0)
    json.dumps(jp.to_dict())


def test_ldi_of_jacobian_against_svd():
    rng = np.random.default_rng(3)
    j = rng.normal(size=(50, 2, 2))
    s = np.linalg.svd(j, compute_uv=False)
    assert_allclose(ldi_of_jacobian(j, "rotary"), s[:, 1], rtol=1e-12)
    assert_allclose(ldi_of_jacobian(j, "linear"), 1.0 / s[:, 0], rtol=1e-12)
    # a zero Jacobian has no velocity ellipse: 0, not inf or NaN
    assert ldi_of_jacobian(np.zeros((2, 2)), "linear") == 0.0
    assert ldi_of_jacobian(np.zeros((2, 2)), "rotary") == 0.0
    with pytest.raises(InputError, match="kind must be 'rotary' or 'linear'; got 'angular'"):
        ldi_of_jacobian(np.eye(2), "angular")


@pytest.mark.parametrize("name", list(MODELS))
def test_ldi_is_the_smallest_semi_axis_of_the_velocity_ellipse(name):
    """Eq. 27: the smallest singular value of G = J_x^-1 J_q (p_dot = G q_dot)."""
    model = MODELS[name]
    p = _points(model, 30, seed=5)
    p = p[inverse_kinematics(model, p).ok]          # the LDI is defined at reachable poses
    assert len(p) >= 10
    jac = jacobians(model, p)
    g = np.linalg.solve(jac.jx, jac.jq)
    assert_allclose(jac.g, g, atol=1e-12)
    s_min = np.linalg.svd(g, compute_uv=False)[:, 1]
    assert_allclose(local_design_index(model, p), s_min, rtol=1e-10)


def test_ldi_closed_forms():
    p = _points(PAP, 40, frac=1.0, seed=8)
    th = np.arcsin(p / PAP.la)
    # 2-PaP: J = la diag(cos th1, cos th2), LDI = la min(cos th_i)
    assert_allclose(local_design_index(PAP, p), PAP.la * np.min(np.cos(th), axis=-1),
                    rtol=1e-12)
    # perpendicular 2-PPa, Eq. 22: J = [[1, tan th1], [tan th2, 1]], sin th1 = p_y / la
    p = _points(PPA, 40, frac=1.0, seed=9)
    p = p[inverse_kinematics(PPA, p).ok]            # the LDI is defined at reachable poses
    assert len(p) >= 10
    t1 = np.tan(np.arcsin(p[:, 1] / PPA.la))
    t2 = np.tan(np.arcsin(p[:, 0] / PPA.la))
    f = 2 + t1 ** 2 + t2 ** 2
    det = 1 - t1 * t2
    smax = np.sqrt(0.5 * (f + np.sqrt(f * f - 4 * det * det)))
    assert_allclose(local_design_index(PPA, p), 1.0 / smax, rtol=1e-12)
    # at the centre the links are at 0: J = I for 2-PPa, la I for 2-PaP
    assert local_design_index(PPA, [0.0, 0.0]) == pytest.approx(1.0, abs=1e-15)
    assert local_design_index(PAP, [0.0, 0.0]) == pytest.approx(PAP.la, abs=1e-15)


def test_singularity_kinds():
    assert Singularity.BOTH == Singularity.INVERSE | Singularity.DIRECT
    la = PPA.la
    # theta_1 = 90 deg (inverse) and theta_1 + theta_2 = 90 deg (direct): both
    jac = jacobians(PPA, [0.0, la])
    assert jac.singularity == Singularity.BOTH
    assert abs(jac.det_q) <= SINGULAR_REL and abs(jac.det_x) <= SINGULAR_REL
    # theta_1 = 90, theta_2 = 30 deg: inverse only
    jac = jacobians(PPA, [la * 0.5, la])
    assert jac.singularity == Singularity.INVERSE
    # the paper's J has a zero row where s_i . e_i = 0
    assert_allclose(jac.j[0], 0.0, atol=0)
    # 2-PaP has no direct singularity (J_x = I)
    assert jacobians(PAP, [PAP.la, PAP.la]).singularity == Singularity.INVERSE
    assert jacobians(PAP, [0.3, -0.2]).singularity == Singularity.NONE


def test_statics_closed_forms():
    rng = np.random.default_rng(2)
    for p in _points(PAP, 6, seed=12):
        f = rng.normal(size=2)
        tau = actuator_forces(PAP, p, f).tau
        # tau_i = la cos(theta_i) f_i: each actuator balances its own axis
        assert_allclose(tau, PAP.la * np.cos(np.arcsin(p / PAP.la)) * f, rtol=1e-12)
    # perpendicular 2-PPa at the centre: J = I, actuator force = platform force
    res = actuator_forces(PPA, [0.0, 0.0], [2.0, -3.0])
    assert res.success and res.singularity == Singularity.NONE
    assert_allclose(res.tau, [2.0, -3.0], atol=1e-15)
    back = platform_force(PPA, [0.0, 0.0], res.tau)
    assert_allclose(back.force, [2.0, -3.0], atol=1e-15)
    assert back.success
    json.dumps(res.to_dict())


def test_statics_at_a_singular_pose_is_flagged_and_finite():
    la = PAP.la
    res = platform_force(PAP, [la, 0.0], [1.0, 1.0])         # theta_1 = 90 deg
    assert res.singularity == Singularity.INVERSE and not res.success
    assert np.all(np.isfinite(res.force))
    res = actuator_forces(PAP, [la, 0.0], [1.0, 1.0])
    assert not res.success and np.all(np.isfinite(res.tau))
    # the link along the x-axis carries none of a force along x
    assert res.tau[0] == pytest.approx(0.0, abs=1e-12)


def test_statics_take_one_pose_only():
    with pytest.raises(InputError, match=r"p must have shape \(2,\) here; got \(3, 2\)"):
        actuator_forces(PPA, np.zeros((3, 2)), [1.0, 0.0])
    with pytest.raises(InputError, match=r"force must have shape \(2,\)"):
        actuator_forces(PPA, [0.0, 0.0], [1.0, 0.0, 0.0])
    with pytest.raises(NonFiniteError, match="tau must be finite"):
        platform_force(PPA, [0.0, 0.0], [math.nan, 0.0])
    with pytest.raises(InputError, match="TwoPaP or TwoPPa"):
        jacobians(object(), [0.0, 0.0])
    with pytest.raises(InputError, match="TwoPaP or TwoPPa"):
        local_design_index(None, [0.0, 0.0])


def test_2pap_ldi_is_zero_at_an_inverse_singularity():
    p = [PAP.la, 0.0]                                   # theta_1 = 90 deg
    assert jacobians(PAP, p).singularity == Singularity.INVERSE
    # beyond theta_limit, so out of reach: no index there, but the map over a square
    # that reaches it shows the formula's zero
    with pytest.raises(InputError, match="OUTSIDE_WORKSPACE"):
        local_design_index(PAP, p)
    assert ldi_map(PAP, PAP.la, n=3).ldi[1, 2] == 0.0     # at (la, 0)
