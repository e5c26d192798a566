"""[Kim 1985]: velocity and acceleration (same M) against central finite differences."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from mechanisms.spatial import (
    LoopStatus, acceleration, frame_transforms, planar_fourbar, point_motion, solve_path,
    solve_pose, velocity,
)

from .conftest import TIGHT

H_V = 1e-5   # velocity step: truncation ~1e-10, rounding ~1e-14 / 1e-5 = 1e-9
H_A = 1e-4   # acceleration step: truncation ~1e-8, rounding ~1e-14 / 1e-8 = 1e-6


def _pose(lk, q, x):
    p = solve_pose(lk.loop, x, q, options=TIGHT)
    assert p.success
    return p.q


def _determinate(name, lk):
    """Variables that are functions of the input (RSSR: all but the idle S angles)."""
    if name == "rssr":
        return [0, lk.output]
    return list(range(lk.loop.n_vars))


@pytest.mark.parametrize("name", ["planar", "spherical", "rccc", "rssr"])
def test_velocity_and_acceleration_match_finite_differences(paths, name):
    lk, path = paths[name, 1]
    idx = _determinate(name, lk)
    for k in range(0, 361, 45):
        x, q = path.inputs[k], _pose(lk, path.q[k], path.inputs[k])
        qd = velocity(lk.loop, q)
        qdd = acceleration(lk.loop, q)
        qp, qm = _pose(lk, q, x + H_V), _pose(lk, q, x - H_V)
        assert_allclose(qd[idx], ((qp - qm) / (2 * H_V))[idx], atol=1e-7)
        qp, qm = _pose(lk, q, x + H_A), _pose(lk, q, x - H_A)
        assert_allclose(qdd[idx], ((qp - 2 * q + qm) / H_A ** 2)[idx], atol=2e-5)
        # The path stores the same numbers.
        assert_allclose(path.qd[k][idx], qd[idx], atol=1e-9)


@pytest.mark.parametrize("name", ["rccc", "rssr"])
def test_joint_frame_and_point_motion_match_finite_differences(paths, name):
    lk, path = paths[name, 1]
    # A coupler point in frame 2 (RCCC); for RSSR frame 2 turns with the idle spin, so
    # its origin (the S centre B) is used instead.  Plus the origin of the last frame.
    pt = np.array([0.3, -0.2, 0.4]) if name == "rccc" else np.zeros(3)
    for k in range(0, 361, 60):
        x, q = path.inputs[k], _pose(lk, path.q[k], path.inputs[k])
        for frame, local in ((2, pt), (lk.loop.n_frames - 1, np.zeros(3))):
            pm = point_motion(lk.loop, q, frame, local)
            T = frame_transforms(lk.loop, q)
            assert_allclose(pm.position, (T[frame] @ np.append(local, 1))[:3], atol=1e-14)

            def pos(qq, frame=frame, local=local):
                return point_motion(lk.loop, qq, frame, local).position
            qp, qm = _pose(lk, q, x + H_V), _pose(lk, q, x - H_V)
            assert_allclose(pm.velocity, (pos(qp) - pos(qm)) / (2 * H_V), atol=1e-7)
            qp, qm = _pose(lk, q, x + H_A), _pose(lk, q, x - H_A)
            assert_allclose(pm.acceleration, (pos(qp) - 2 * pos(q) + pos(qm)) / H_A ** 2, atol=2e-5)


def test_input_rate_scaling(paths):
    lk, path = paths["rccc", 1]
    q = path.q[40]
    qd1 = velocity(lk.loop, q)
    assert_allclose(velocity(lk.loop, q, 2.5), 2.5 * qd1, atol=1e-12)
    a = acceleration(lk.loop, q, 2.0, 0.7)
    assert_allclose(a, 4.0 * acceleration(lk.loop, q) + 0.7 * qd1, atol=1e-10)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 0.05), st.floats(-0.2, 0.2), st.floats(0.0, 6.283))
def test_near_change_point_fourbars_are_finite_or_flagged(eps, skew, theta):
    """Hypothesis: four-bars near s + l = p + q (folding poses) stay finite or flagged."""
    a, d, c = 2.0, 6.0, 5.0 + skew
    b = d + c - a + eps * (1 if skew >= 0 else -1)   # s + l ~ p + q
    try:
        lk = planar_fourbar(a, b, c, d, theta)
    except ValueError:
        return   # not assemblable at the start angle: a typed error, nothing to solve
    x = theta + np.linspace(0, 2 * math.pi, 73)
    path = solve_path(lk.loop, x, lk.q0)
    for arr in (path.q, path.qd, path.qdd, path.residual):
        assert np.all(np.isfinite(arr))
    assert set(np.unique(path.status)) <= {int(s) for s in LoopStatus}
    closed = path.status == LoopStatus.CONVERGED
    assert np.all(path.residual[closed] <= 1e-10)


@settings(max_examples=25, deadline=None)
@given(st.floats(3.55, 3.72))
def test_spatial_near_singular_poses_finite_or_flagged(coupler):
    """Hypothesis: RSSRs whose coupler length is near the limit of full crank rotation
    (about 3.62 for this layout) pass through or near folded, singular poses."""
    from cspace.errors import InvalidModelError
    from mechanisms.spatial import closedform as cf, rssr
    args = (1.0, 0.5, coupler, 2.0, 2.5, math.radians(60), 0.5)
    geo = cf.RSSRGeometry(*args)
    for start in (3.4, 0.3, 1.8, 5.0):
        try:
            lk = rssr(*args, start)
            break
        except InvalidModelError:
            continue
    else:
        return
    x = start + np.linspace(0, 2 * math.pi, 73)
    path = solve_path(lk.loop, x, lk.q0)
    for arr in (path.q, path.qd, path.qdd, path.residual):
        assert np.all(np.isfinite(arr))
    closed = path.status <= LoopStatus.SINGULAR
    assert np.all(path.residual[closed] <= 1e-10)
    for xi, c in zip(x, closed):
        if not cf.rssr_phi(geo, xi, 1)[1]:
            assert not c          # no real assembly: never reported as closed
