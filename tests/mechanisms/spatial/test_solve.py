"""The HD loop solver (``mechanisms.spatial.solve``) on a slider-crank written
as an RRRP loop by hand, checked against its trigonometry.

Slider-crank
------------
Crank AB (r = 1) turns about A = origin at world angle theta; coupler BC (l = 3);
the slider pin C runs on the world x-axis:

    x_C = r cos theta + sqrt(l^2 - r^2 sin^2 theta),
    x_C' = -r s - r^2 s c / sqrt(D),
    x_C'' = -r c - r^2 (c^2 - s^2) / sqrt(D) - r^4 s^2 c^2 / D^(3/2),

with s, c = sin, cos theta and D = l^2 - r^2 s^2; inversely
``cos theta = (x_C^2 + r^2 - l^2) / (2 r x_C)``.

HD frames: frame 0 at A with z_0 = world z and x_0 = -world y (the common
normal of the slide axis and the crank axis), so the HD input is theta + 90 deg;
frame 1 at B (x_1 along AB), frame 2 at C (x_2 along BC), frame 3 at C with
z_3 = world x (the slide) and x_3 = world y.  The slide variable is
``s_3 = -x_C``.  Ground coordinates (frame 0) of a world point (X, Y, Z) are
(-Y, X, Z).
"""

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError, NonFiniteError
from mechanisms.spatial import (Joint, LoopStatus, SolverOptions, acceleration,
                                frame_transforms, hd_matrix, loop_product, loop_residual,
                                make_loop, point_motion, solve_path, solve_pose, velocity)

R, L = 1.0, 3.0


def x_c(th):
    return R * math.cos(th) + math.sqrt(L * L - (R * math.sin(th)) ** 2)


def dx_c(th):
    s, c = math.sin(th), math.cos(th)
    return -R * s - R * R * s * c / math.sqrt(L * L - R * R * s * s)


def ddx_c(th):
    s, c = math.sin(th), math.cos(th)
    d = L * L - R * R * s * s
    return -R * c - R * R * (c * c - s * s) / math.sqrt(d) - R ** 4 * s * s * c * c / d ** 1.5


def slider_crank(th, input_variable=0):
    """The loop, its reference values closed at crank angle ``th``."""
    x = x_c(th)
    phi = math.atan2(-R * math.sin(th), x - R * math.cos(th))      # direction of BC
    return make_loop([Joint("R", a=R, theta=th + math.pi / 2, name="A"),
                      Joint("R", a=L, theta=phi - th, name="B"),
                      Joint("R", alpha=math.pi / 2, theta=math.pi / 2 - phi, name="C"),
                      Joint("P", alpha=math.pi / 2, theta=math.pi, s=-x, name="slide")],
                     input_variable=input_variable)


def ground(p):
    """Frame-0 coordinates of a world point (x, y)."""
    return np.array([-p[1], p[0], 0.0])


LOOP = slider_crank(0.4)
ANGLES = [0.0, 0.7, 2.0, 3.5, 5.5]


def test_reference_pose_is_closed():
    q = LOOP.reference_q()
    assert loop_residual(LOOP, q) <= 1e-15
    assert_allclose(loop_product(LOOP, q), np.eye(4), atol=1e-15)
    assert LOOP.length_scale == pytest.approx(x_c(0.4))


def test_loop_product_and_residual_of_an_open_pose():
    q = LOOP.reference_q() + [0.0, 0.05, -0.02, 0.1]
    want = np.eye(4)
    for f, v in zip(LOOP.frames, (q[0], q[1], q[2], math.pi)):
        want = want @ hd_matrix(f.a, f.alpha, v, q[3] if f.s_var else f.s)
    F = loop_product(LOOP, q)
    assert_allclose(F, want, atol=1e-15)
    d = F - np.eye(4)
    res = max(np.max(np.abs(d[:3, :3])), np.max(np.abs(d[:3, 3])) / LOOP.length_scale)
    assert loop_residual(LOOP, q) == pytest.approx(res, rel=1e-15) and res > 1e-3


@pytest.mark.parametrize("th", ANGLES)
def test_solve_pose_gives_the_slider_position(th):
    p = solve_pose(LOOP, th + math.pi / 2)            # from the reference pose at 0.4
    assert p.status == LoopStatus.CONVERGED and p.success and p.message == "loop closed"
    assert p.residual <= 1e-12 and p.rank == 3
    assert p.q[0] == th + math.pi / 2                  # the input is held
    assert p.q[3] == pytest.approx(-x_c(th), abs=1e-10)
    # the frames lie on the joints: A, B, C, C
    T = frame_transforms(LOOP, p.q)
    B = R * np.array([math.cos(th), math.sin(th)])
    C = np.array([x_c(th), 0.0])
    for k, P in enumerate((np.zeros(2), B, C, C)):
        assert_allclose(T[k][:3, 3], ground(P), atol=1e-10)
    assert_allclose(T[3][:3, 2], ground((1.0, 0.0)), atol=1e-10)     # z_3 along the slide
    # degrees through unit=
    pd = solve_pose(LOOP, math.degrees(th) + 90.0, unit="deg")
    assert_allclose(pd.q, p.q, atol=1e-12)


@pytest.mark.parametrize("th", ANGLES)
def test_velocity_and_acceleration_are_the_derivatives(th):
    q = solve_pose(LOOP, th + math.pi / 2, options=SolverOptions(tol=1e-14)).q
    qd = velocity(LOOP, q)
    qdd = acceleration(LOOP, q)
    assert qd[0] == 1.0 and qdd[0] == 0.0
    assert qd[3] == pytest.approx(-dx_c(th), abs=1e-10)
    assert qdd[3] == pytest.approx(-ddx_c(th), abs=1e-9)
    # the three angles of a planar loop sum to a constant
    assert qd[0] + qd[1] + qd[2] == pytest.approx(0.0, abs=1e-12)
    assert qdd[0] + qdd[1] + qdd[2] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("th", ANGLES)
def test_coupler_midpoint_motion(th):
    """The coupler's midpoint is (-l/2, 0, 0) in frame 2 (origin C, x_2 along BC)."""
    q = solve_pose(LOOP, th + math.pi / 2, options=SolverOptions(tol=1e-14)).q
    s, c = math.sin(th), math.cos(th)
    pm = point_motion(LOOP, q, 2, (-L / 2, 0.0, 0.0))
    pos = 0.5 * (R * np.array([c, s]) + np.array([x_c(th), 0.0]))
    vel = 0.5 * (R * np.array([-s, c]) + np.array([dx_c(th), 0.0]))
    acc = 0.5 * (-R * np.array([c, s]) + np.array([ddx_c(th), 0.0]))
    assert_allclose(pm.position, ground(pos), atol=1e-10)
    assert_allclose(pm.velocity, ground(vel), atol=1e-10)
    assert_allclose(pm.acceleration, ground(acc), atol=1e-9)
    # with the rates of another input speed: velocity scales with it
    pm2 = point_motion(LOOP, q, 2, (-L / 2, 0.0, 0.0), qd=2.0 * velocity(LOOP, q),
                       qdd=4.0 * acceleration(LOOP, q))
    assert_allclose(pm2.velocity, 2.0 * pm.velocity, atol=1e-12)
    json.dumps(pm.to_dict())


def test_prismatic_input_drives_the_crank():
    lp = slider_crank(0.4, input_variable=3)
    assert lp.variables[lp.input] == (3, "s")
    xs = np.linspace(L + R - 0.05, L - R + 0.05, 60)
    path = solve_path(lp, -xs)
    assert path.success and np.all(path.status == LoopStatus.CONVERGED)
    assert not np.any(path.gap_before)
    th = np.arccos((xs ** 2 + R * R - L * L) / (2 * R * xs))      # the upper branch
    assert_allclose(path.q[:, 0] - math.pi / 2, th, atol=1e-10)
    # d theta / d s_3 = -1 / x_C'(theta)
    assert_allclose(path.qd[:, 0], [-1.0 / dx_c(t) for t in th], rtol=1e-8)
    assert path.message == "60 of 60 poses closed (0 singular)"


def test_a_slide_beyond_reach_is_a_status_not_an_error():
    lp = slider_crank(0.4, input_variable=3)
    p = solve_pose(lp, -(L + R + 0.5))
    assert p.status == LoopStatus.NOT_ASSEMBLABLE and not p.success
    assert p.residual > 1e-3 and np.all(np.isfinite(p.q))
    assert p.message == "loop cannot be closed near the estimate"
    json.dumps(p.to_dict())
    # a path through it: the failed pose repeats the last good one and is flagged
    path = solve_path(lp, [-3.5, -3.9, -(L + R + 0.5), -3.9, -3.5])
    assert list(path.status[:2]) == [LoopStatus.CONVERGED] * 2
    assert path.status[2] == LoopStatus.NOT_ASSEMBLABLE
    assert_allclose(path.q[2], path.q[1], atol=0)
    assert list(path.gap_before) == [False, False, False, True, False]
    assert path.status[3] == LoopStatus.CONVERGED and not path.success
    assert path.message == "4 of 5 poses closed (0 singular)"
    d = path.to_dict()
    assert d["status"][2] == "NOT_ASSEMBLABLE"
    json.dumps(d)


def test_iteration_limit():
    """Near the closure one step is not enough for 1e-12: the limit is reported;
    far from it (residual > 1e-3) running out of steps counts as no assembly."""
    near = solve_pose(LOOP, 0.45 + math.pi / 2, options=SolverOptions(max_iter=1))
    assert near.status == LoopStatus.MAX_ITER and near.iterations == 1
    assert near.message == "iteration limit reached"
    assert 1e-12 < near.residual < 1e-3
    far = solve_pose(LOOP, 3.5 + math.pi / 2, options=SolverOptions(max_iter=1))
    assert far.status == LoopStatus.NOT_ASSEMBLABLE and far.residual > 1e-3
    # with the default limit both close
    assert solve_pose(LOOP, 3.5 + math.pi / 2).status == LoopStatus.CONVERGED


def test_path_in_degrees_matches_radians():
    x = np.linspace(0.4, 0.4 + 2 * math.pi, 37)
    a = solve_path(LOOP, x + math.pi / 2)
    b = solve_path(LOOP, np.degrees(x) + 90.0, unit="deg")
    assert_allclose(b.inputs, a.inputs, atol=1e-14)
    assert_allclose(b.q, a.q, atol=1e-12)
    assert_allclose(a.q[:, 3], [-x_c(t) for t in x], atol=1e-10)


@pytest.mark.parametrize("kw, match", [
    ({"tol": 0.0}, "SolverOptions.tol must be a positive finite float"),
    ({"max_step": math.inf}, "SolverOptions.max_step must be a positive finite float"),
    ({"jump_factor": -1.0}, "SolverOptions.jump_factor must be a positive finite float"),
    ({"max_iter": 0}, "SolverOptions.max_iter must be an int"),
    ({"max_halvings": 2.5}, "SolverOptions.max_halvings must be an int"),
])
def test_solver_options_are_checked(kw, match):
    with pytest.raises(InputError, match=match):
        SolverOptions(**kw)


def test_bad_arguments():
    q = LOOP.reference_q()
    with pytest.raises(InputError, match="options must be SolverOptions or None; got dict"):
        solve_pose(LOOP, 0.0, options={"tol": 1e-9})
    with pytest.raises(InputError, match="inputs must be a non-empty 1-D sequence"):
        solve_path(LOOP, [])
    with pytest.raises(NonFiniteError, match="inputs must be finite"):
        solve_path(LOOP, [0.0, math.nan])
    with pytest.raises(NonFiniteError, match="q must be finite"):
        velocity(LOOP, [math.inf, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match=r"q must have shape \(4,\)"):
        solve_pose(LOOP, 0.0, guess=[0.0, 0.0])
    with pytest.raises(InputError, match=r"frame must be an int in \[0, 3\]"):
        point_motion(LOOP, q, 4)
    with pytest.raises(InputError, match="point must be 3 finite numbers"):
        point_motion(LOOP, q, 1, (0.0, 1.0))
    with pytest.raises(InputError, match="loop must be a Loop"):
        loop_product(None, q)
    assert SolverOptions().to_dict()["tol"] == 1e-12
