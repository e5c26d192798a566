"""HD matrices and loop descriptions (``mechanisms.spatial.loops``)."""

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError, InvalidModelError
from mechanisms.spatial import HDFrame, Joint, JointType, Loop, Q_S, Q_THETA, hd_matrix, make_loop


def _rz(t):
    c, s = math.cos(t), math.sin(t)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    return m


def _rx(t):
    c, s = math.cos(t), math.sin(t)
    m = np.eye(4)
    m[1:3, 1:3] = [[c, -s], [s, c]]
    return m


def _tz(d):
    m = np.eye(4)
    m[2, 3] = d
    return m


def _tx(d):
    m = np.eye(4)
    m[0, 3] = d
    return m


@pytest.mark.parametrize("a, alpha, theta, s", [(1.3, 0.4, 0.7, -0.2), (0.0, -2.0, 3.0, 5.0),
                                                (-2.5, math.pi / 2, -1.1, 0.0)])
def test_hd_matrix_is_the_product_of_elementary_motions(a, alpha, theta, s):
    m = hd_matrix(a, alpha, theta, s)
    assert_allclose(m, _rz(theta) @ _tz(s) @ _tx(a) @ _rx(alpha), atol=1e-15)
    r = m[:3, :3]
    assert_allclose(r @ r.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-15)
    # the next frame's origin and axis, seen in this frame
    assert_allclose(m[:3, 3], [a * math.cos(theta), a * math.sin(theta), s], atol=1e-15)
    assert_allclose(m[:3, 2], [math.sin(theta) * math.sin(alpha),
                               -math.cos(theta) * math.sin(alpha), math.cos(alpha)], atol=1e-15)
    # the paper's layout is the same matrix with the homogeneous coordinate first
    p = hd_matrix(a, alpha, theta, s, layout="paper")
    assert p[0, 0] == 1.0 and np.all(p[0, 1:] == 0.0)
    assert_allclose(p[1:, 1:], m[:3, :3], atol=0)
    assert_allclose(p[1:, 0], m[:3, 3], atol=0)


def test_derivative_operators_are_read_only():
    for q in (Q_THETA, Q_S):
        with pytest.raises(ValueError):
            q[0, 0] = 1.0
    assert Q_S[2, 3] == 1.0 and np.count_nonzero(Q_S) == 1
    assert_allclose(Q_THETA + Q_THETA.T, 0.0, atol=0)


def test_loop_of_a_planar_four_bar():
    lp = make_loop([Joint("R", a=1), Joint("R", a=3), Joint("R", a=2), Joint("R", a=4)])
    assert isinstance(lp, Loop) and lp.signature() == "RRRR"
    assert lp.n_frames == 4 and lp.n_vars == 4 and lp.idle_dof == 0
    assert lp.variables == ((0, "theta"), (1, "theta"), (2, "theta"), (3, "theta"))
    assert lp.input == 0 and lp.unknowns == (1, 2, 3)
    assert lp.length_scale == 4.0                          # the largest |a| or |s|
    assert [f.name for f in lp.frames] == ["R0", "R1", "R2", "R3"]
    assert all(isinstance(f, HDFrame) and f.theta_var and not f.s_var for f in lp.frames)
    d = lp.to_dict()
    assert json.loads(json.dumps(d)) == d and d["signature"] == "RRRR"
    assert "RRRR" in repr(lp)


def test_joint_kinds_expand_to_frames_and_variables():
    lp = make_loop([Joint("P", a=0.5, alpha=90, theta=30, s=2.0, name="slide"),
                    {"kind": "c", "a": 1.5, "alpha": 45, "s": -3.0},
                    Joint(JointType.S, a=2.0, alpha=60, theta=(10, 80, -20), s=0.7),
                    Joint("R", a=1.0)],
                   unit="deg", input_variable=0, idle_dof=1)
    assert lp.signature() == "PCSR"
    assert lp.n_frames == 6 and lp.n_vars == 7
    assert [(lp.frames[f].name, k) for f, k in lp.variables] == [
        ("slide", "s"), ("C1", "theta"), ("C1", "s"),
        ("S2.a", "theta"), ("S2.b", "theta"), ("S2.c", "theta"), ("R3", "theta")]
    assert lp.variables[lp.input] == (0, "s") and lp.unknowns == (1, 2, 3, 4, 5, 6)
    # the prismatic joint's theta is a constant, its s the variable
    p = lp.frames[0]
    assert (p.theta_var, p.s_var) == (False, True)
    assert p.theta == pytest.approx(math.radians(30)) and p.alpha == pytest.approx(math.pi / 2)
    c = lp.frames[1]
    assert (c.theta_var, c.s_var) == (True, True) and c.name == "C1"
    # S: (a=0, 90 deg, theta_a, s), (a=0, 90 deg, theta_b, 0), (a, alpha, theta_c, 0)
    sa, sb, sc = lp.frames[2:5]
    assert (sa.a, sb.a, sc.a) == (0.0, 0.0, 2.0)
    assert sa.alpha == sb.alpha == pytest.approx(math.pi / 2)
    assert sc.alpha == pytest.approx(math.radians(60))
    assert (sa.s, sb.s, sc.s) == (0.7, 0.0, 0.0)
    assert_allclose([sa.theta, sb.theta, sc.theta], np.radians([10, 80, -20]), atol=1e-15)
    assert {f.joint for f in (sa, sb, sc)} == {2}
    assert lp.idle_dof == 1 and lp.length_scale == 3.0
    assert_allclose(lp.reference_q(), [2.0, math.radians(0), -3.0,
                                       *np.radians([10, 80, -20]), 0.0], atol=1e-15)


def test_input_variable_and_length_scale():
    joints = [Joint("R", a=1.0), Joint("P", alpha=math.pi / 2, s=-2.0), Joint("R")]
    lp = make_loop(joints, input_variable=1)
    assert lp.variables[lp.input] == (1, "s") and lp.unknowns == (0, 2)
    assert lp.length_scale == 2.0
    assert make_loop(joints, length_scale=10).length_scale == 10.0
    assert make_loop([Joint("R"), Joint("R")]).length_scale == 1.0   # all zero: 1
    with pytest.raises(InputError, match="length_scale must be > 0"):
        make_loop(joints, length_scale=0.0)
    with pytest.raises(InputError, match=r"input_variable must be an int in \[0, 2\]"):
        make_loop(joints, input_variable=3)
    with pytest.raises(InputError, match="idle_dof must be an int"):
        make_loop(joints, idle_dof=-1)


def test_make_loop_rejects_bad_joints():
    with pytest.raises(InvalidModelError, match="at least 2 joints; got 1"):
        make_loop([Joint("R", a=1.0)])
    with pytest.raises(InputError, match="joints must be a sequence of Joint"):
        make_loop(5)
    with pytest.raises(InputError, match=r"joints\[1\] must be a Joint or a dict; got str"):
        make_loop([Joint("R"), "R"])
    with pytest.raises(InputError, match=r"joints\[0\]: .*length"):
        make_loop([{"kind": "R", "length": 1.0}, Joint("R")])
    with pytest.raises(InputError, match=r"joints\[1\].a must be a real number"):
        make_loop([Joint("R"), Joint("R", a="far")])
    with pytest.raises(InputError, match=r"joints\[0\].alpha must be finite"):
        make_loop([Joint("R", alpha=math.nan), Joint("R")])
    with pytest.raises(InputError, match=r"joints\[0\].theta must be 3 finite angles for S"):
        make_loop([Joint("S", theta=(0.0, math.inf, 0.0)), Joint("R")])
    with pytest.raises(InputError, match="unit must be one of"):
        make_loop([Joint("R"), Joint("R")], unit="turns")
