"""FK/IK, Jacobians, statics and singularities of 2-PaP and 2-PPa."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from mechanisms.manipulators import (
    PoseStatus, Singularity, actuator_forces, design, closed_form_forward, forward_kinematics,
    inverse_kinematics, jacobians, ldi_map, ldi_of_jacobian, local_design_index, platform_force,
    total_workspace, two_ppa, two_ppa_parallel,
)
from cspace.errors import InputError, NonFiniteError

PAP = design("2-PaP", 1.0, 60, unit="deg").model
PPA = design("2-PPa", 1.0, 30, unit="deg").model
PAR = two_ppa_parallel(1.0, 1.2, 1.0, 30, unit="deg")
PROTO = two_ppa(260.0, 482.0, 300.0, 30, b=92.0, unit="deg")


def _square(model, n=41, frac=1.0):
    w = model.half_width * frac
    x = np.linspace(-w, w, n)
    X, Y = np.meshgrid(x, x)
    return np.stack([X.ravel(), Y.ravel()], -1)


@pytest.mark.parametrize("model", [PAP, PPA], ids=["2-PaP", "2-PPa"])
def test_fk_ik_identity_over_prescribed_square(model):
    p = _square(model)
    ik = inverse_kinematics(model, p)
    assert ik.success
    fk = forward_kinematics(model, ik.q)
    assert fk.success
    assert_allclose(fk.p, p, atol=1e-12)
    assert_allclose(fk.theta, ik.theta, atol=1e-12)


def test_fk_ik_identity_over_total_workspace_2ppa():
    # Random points of the whole (polygonal) total workspace, away from its boundary.
    rng = np.random.default_rng(1)
    poly = total_workspace(PPA).buffer(-1e-3 * PPA.la)
    x0, y0, x1, y1 = poly.bounds
    p = rng.uniform([x0, y0], [x1, y1], (4000, 2))
    import shapely
    p = p[shapely.contains_xy(poly, p[:, 0], p[:, 1])]
    assert len(p) > 1000
    ik = inverse_kinematics(PPA, p)
    # The total workspace holds a lower-left part reachable only in the other
    # assembly mode (Fig. 4, "unusable"); IK flags it, and FK o IK is the identity on
    # the rest.
    assert set(np.unique(ik.status)) == {PoseStatus.OK, PoseStatus.OTHER_ASSEMBLY}
    other = ik.status == PoseStatus.OTHER_ASSEMBLY
    assert np.all(p[other].sum(-1) < 0)          # it is the lower-left part
    p, ik = p[~other], inverse_kinematics(PPA, p[~other])
    fk = forward_kinematics(PPA, ik.q)
    # Where the circles nearly touch (theta_1 + theta_2 -> 90 deg) the FK loses digits
    # like sqrt(eps / |cos(theta_1 + theta_2)|); the prescribed square stays clear of it.
    c = np.abs(np.cos(ik.theta.sum(-1)))
    good = c > 1e-2
    assert np.all(fk.status[good] == PoseStatus.OK)
    assert_allclose(fk.p[good], p[good], atol=1e-12)


def test_fk_ik_identity_prototype_scale():
    p = _square(PROTO, n=31)
    fk = forward_kinematics(PROTO, inverse_kinematics(PROTO, p).q)
    assert_allclose(fk.p, p, atol=1e-12 * PROTO.la)


def test_fk_matches_paper_eq15():
    p = _square(PPA, n=21)
    d = inverse_kinematics(PPA, p).q
    assert_allclose(forward_kinematics(PPA, d).p, closed_form_forward(PPA, d), atol=1e-12)


def test_ik_matches_paper_eq12():
    p = _square(PPA, n=21)
    d = inverse_kinematics(PPA, p).q
    px, py = p[:, 0], p[:, 1]
    ab = PPA.a - PPA.b
    assert_allclose(d[:, 0], px + ab - np.sqrt(PPA.la ** 2 - py ** 2), atol=1e-12)
    assert_allclose(d[:, 1], py + ab - np.sqrt(PPA.la ** 2 - px ** 2), atol=1e-12)


def test_parallel_fk_ik_identity():
    p = np.array([[0.0, 0.0], [0.1, 0.05], [-0.1, -0.2]])
    ik = inverse_kinematics(PAR, p)
    assert ik.success
    assert_allclose(forward_kinematics(PAR, ik.q).p, p, atol=1e-12)


def test_workspace_checks():
    assert inverse_kinematics(PAP, [1.0, 0.0]).status == PoseStatus.OK
    assert inverse_kinematics(PAP, [1.01, 0.0]).status == PoseStatus.OUTSIDE_WORKSPACE
    assert forward_kinematics(PAP, [math.radians(61), 0.0]).status == PoseStatus.OUTSIDE_WORKSPACE
    assert inverse_kinematics(PPA, [0.0, 2.5]).status == PoseStatus.OUTSIDE_WORKSPACE
    # Far apart circle centres: no assembly, finite output.
    fk = forward_kinematics(PPA, [PPA.stroke, PPA.stroke + 10.0])
    assert fk.status == PoseStatus.NOT_ASSEMBLABLE
    assert np.all(np.isfinite(fk.p))
    # Actuator outside its stroke.
    assert forward_kinematics(PPA, [-0.2, 0.8]).status == PoseStatus.OUTSIDE_WORKSPACE


def test_degrees_only_through_unit_keyword():
    fk = forward_kinematics(PAP, [30.0, -45.0], unit="deg")
    assert_allclose(fk.p, PAP.la * np.sin(np.radians([30.0, -45.0])), atol=1e-15)
    with pytest.raises(InputError, match="joint variables are lengths"):
        forward_kinematics(PPA, [0.1, 0.1], unit="deg")
    with pytest.raises(InputError, match="unit must be one of"):
        forward_kinematics(PAP, [0.1, 0.1], unit="grad")


def test_bad_input_raises_typed_errors():
    with pytest.raises(InputError, match=r"shape \(2,\) or \(..., 2\)"):
        inverse_kinematics(PPA, [1.0, 2.0, 3.0])
    with pytest.raises(NonFiniteError, match="finite"):
        forward_kinematics(PPA, [np.nan, 0.0])
    with pytest.raises(InputError, match="TwoPaP or TwoPPa"):
        inverse_kinematics("robot", [0.0, 0.0])


def _fd_velocity_map(model, q, h=1e-6):
    g = np.zeros((2, 2))
    for k in range(2):
        dq = np.zeros(2)
        dq[k] = h
        g[:, k] = (forward_kinematics(model, q + dq).p - forward_kinematics(model, q - dq).p) / (2 * h)
    return g


@pytest.mark.parametrize("model", [PAP, PPA, PAR], ids=["2-PaP", "2-PPa", "parallel"])
def test_jacobian_matches_finite_differences(model):
    rng = np.random.default_rng(7)
    w = model.half_width if model is not PAR else 0.15
    for p in rng.uniform(-0.9 * w, 0.9 * w, (25, 2)):
        jac = jacobians(model, p)
        q = inverse_kinematics(model, p).q
        g_fd = _fd_velocity_map(model, q)
        assert_allclose(jac.g, g_fd, atol=1e-8)
        assert_allclose(jac.jx @ jac.g, jac.jq, atol=1e-12)
        if model is PAP:
            assert_allclose(jac.j, g_fd, atol=1e-8)                  # p_dot = J theta_dot
        else:
            assert_allclose(jac.j @ g_fd, np.eye(2), atol=1e-7)       # J p_dot = d_dot


def test_paper_jacobian_forms():
    th1, th2 = 0.3, -0.2
    p = np.array([PPA.la * math.sin(th2), PPA.la * math.sin(th1)])   # sin th1 = p_y/la
    jac = jacobians(PPA, p)
    assert_allclose(jac.j, [[1, math.tan(th1)], [math.tan(th2), 1]], atol=1e-12)
    assert_allclose(jac.jx, [[math.cos(th1), math.sin(th1)], [math.sin(th2), math.cos(th2)]], atol=1e-12)
    assert_allclose(jac.det_x, math.cos(th1 + th2), atol=1e-12)
    jp = jacobians(PAP, [PAP.la * math.sin(th1), PAP.la * math.sin(th2)])
    assert_allclose(jp.j, PAP.la * np.diag([math.cos(th1), math.cos(th2)]), atol=1e-12)
    # Parallel arrangement, Eq. 29: place P where leg angles are th1, th2.
    h = 0.6
    t1 = math.asin((0.05 + h) / PAR.la)
    t2 = math.asin((h - 0.05) / PAR.la)
    jr = jacobians(PAR, [0.05, 0.0])
    assert_allclose(jr.j, [[math.tan(t1), 1], [-math.tan(t2), 1]], atol=1e-12)


@pytest.mark.parametrize("model", [PAP, PPA], ids=["2-PaP", "2-PPa"])
def test_statics_virtual_work(model):
    rng = np.random.default_rng(3)
    for p in rng.uniform(-0.8, 0.8, (10, 2)) * model.half_width:
        f = rng.normal(size=2)
        st_ = actuator_forces(model, p, f)
        assert st_.success
        g = jacobians(model, p).g
        qd = rng.normal(size=2)
        assert_allclose(st_.tau @ qd, f @ (g @ qd), atol=1e-12)     # tau.q_dot = f.p_dot
        back = platform_force(model, p, st_.tau)
        assert_allclose(back.force, f, atol=1e-12)
        j = jacobians(model, p).j
        if model is PAP:
            assert_allclose(st_.tau, j.T @ f, atol=1e-12)             # Eq. 5
        else:
            assert_allclose(j.T @ st_.tau, f, atol=1e-12)             # Eq. 23


def test_singularity_detection():
    # 2-PPa direct singularity: theta_1 + theta_2 = 90 deg.
    th = math.radians(45)
    p = np.array([PPA.la * math.sin(th), PPA.la * math.sin(th)])
    jac = jacobians(PPA, p)
    assert jac.singularity == Singularity.DIRECT
    assert_allclose(jac.det_x, 0.0, atol=1e-12)
    # the formula is finite there; the pose is out of reach, so no index is reported
    ldi = ldi_of_jacobian(jac.j, "linear")
    assert np.isfinite(ldi) and ldi > 0
    assert jac.pose_status != PoseStatus.OK
    with pytest.raises(InputError, match="can reach"):
        local_design_index(PPA, p)
    # Inverse singularity at theta = 90 deg (P on the reach limit).
    jq = jacobians(PPA, [0.0, PPA.la])
    assert jq.singularity & Singularity.INVERSE
    assert ldi_map(PPA, PPA.la, n=3).ldi[2, 1] == 0.0          # at (0, la)
    assert jacobians(PAP, [PAP.la, 0.0]).singularity == Singularity.INVERSE
    assert jacobians(PPA, [0.0, 0.0]).singularity == Singularity.NONE
    res = actuator_forces(PPA, p, [1.0, 0.0])
    assert not res.success and np.all(np.isfinite(res.tau))


@settings(max_examples=200, deadline=None)
@given(st.floats(-80, 80), st.floats(-1e-6, 1e-6))
def test_near_theta_sum_90_is_finite_or_flagged(t1_deg, eps_deg):
    """Hypothesis: near theta_1 + theta_2 = 90 deg everything stays finite."""
    t1 = math.radians(t1_deg)
    t2 = math.radians(90 - t1_deg + eps_deg)
    if abs(t2) >= math.pi / 2:
        return
    la = PPA.la
    p = np.array([la * math.sin(t2), la * math.sin(t1)])
    jac = jacobians(PPA, p)
    for arr in (jac.jx, jac.jq, jac.j, jac.g, jac.det_x):
        assert np.all(np.isfinite(arr))
    ldi = ldi_of_jacobian(jac.j, "linear")
    assert np.isfinite(ldi) and ldi >= 0
    assert abs(jac.det_x) <= 1e-7
    ik = inverse_kinematics(PPA, p)
    if ik.status == PoseStatus.OK:
        assert (local_design_index(PPA, p) == pytest.approx(float(ldi), rel=1e-12)
                or jac.singularity & Singularity.INVERSE)
    else:
        with pytest.raises(InputError, match="can reach"):
            local_design_index(PPA, p)
    fk = forward_kinematics(PPA, ik.q)
    assert np.all(np.isfinite(fk.p)) and np.all(np.isfinite(ik.q))
    if fk.status == PoseStatus.OK and ik.status == PoseStatus.OK:
        # Conditioning near the tangency: error ~ sqrt(eps / |det J_x|) * la.
        tol = max(1e-9, 10 * math.sqrt(2.2e-16 / max(abs(float(jac.det_x)), 1e-300))) * la
        assert np.all(np.abs(fk.p - p) <= tol)
    else:
        assert fk.status in (PoseStatus.SINGULAR, PoseStatus.BRANCH_MISMATCH,
                             PoseStatus.NOT_ASSEMBLABLE, PoseStatus.OUTSIDE_WORKSPACE)
    st_ = actuator_forces(PPA, p, [1.0, 1.0])
    assert np.all(np.isfinite(st_.tau))
