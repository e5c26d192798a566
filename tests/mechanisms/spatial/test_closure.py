"""[Kim 1985]: loop closure over full revolutions, closed-form cross-checks, branches."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mechanisms.spatial import (
    LoopStatus, Q_S, Q_THETA, closedform as cf, frame_transforms, hd_matrix, loop_residual,
    make_loop, Joint, solve_path, solve_pose, SELECTED_ENTRIES,
)
from mechanisms.spatial.loops import JointType

from .conftest import PLANAR_ARGS, RCCC_ARGS, RSSR_ARGS, SPH_ALPHAS

NAMES = ["planar", "spherical", "rccc", "rssr"]


def _world(lk, q):
    return lk.ground @ frame_transforms(lk.loop, q)


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("branch", [1, -1])
def test_residual_over_full_revolution(paths, name, branch):
    lk, path = paths[name, branch]
    assert path.success
    assert np.all(path.status == LoopStatus.CONVERGED)
    assert np.max(path.residual) <= 1e-10
    # Recompute the residual independently of the solver's bookkeeping.
    assert max(loop_residual(lk.loop, q) for q in path.q) <= 1e-10
    assert not np.any(path.gap_before)


def _output(name, lk, q):
    """Closed-form-comparable output read from the HD frames (world coordinates)."""
    W = _world(lk, q)
    if name == "planar":
        C, D = W[2][:3, 3], W[3][:3, 3]
        return math.atan2(C[1] - D[1], C[0] - D[0])
    if name in ("spherical", "rccc"):
        z2 = W[2][:3, 2]
        z3 = np.array([0.0, math.sin(SPH_ALPHAS[3] if name == "spherical" else
                                     math.radians(RCCC_ARGS["alphas"][3])),
                       math.cos(SPH_ALPHAS[3] if name == "spherical" else
                                math.radians(RCCC_ARGS["alphas"][3]))])
        u = np.array([1.0, 0.0, 0.0])
        return math.atan2(z2 @ np.cross(z3, u), z2 @ u)
    geo = cf.RSSRGeometry(*(RSSR_ARGS[k] for k in ("crank", "crank_height", "coupler", "rocker",
                                                   "offset", "twist", "rocker_height")))
    return geo.phi_of(W[4][:3, 3])


def _closed(name, x, branch):
    if name == "planar":
        p = PLANAR_ARGS
        return cf.freudenstein(p["crank"], p["coupler"], p["rocker"], p["ground"], x, branch)
    if name == "spherical":
        return cf.spherical_4r_psi(SPH_ALPHAS, x, branch)
    if name == "rccc":
        al = tuple(math.radians(v) for v in RCCC_ARGS["alphas"])
        return cf.spherical_4r_psi(al, x, branch)
    geo = cf.RSSRGeometry(*(RSSR_ARGS[k] for k in ("crank", "crank_height", "coupler", "rocker",
                                                   "offset", "twist", "rocker_height")))
    return cf.rssr_phi(geo, x, branch)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("branch", [1, -1])
def test_output_matches_closed_form_without_branch_jump(paths, name, branch):
    lk, path = paths[name, branch]
    hd = np.array([_output(name, lk, q) for q in path.q])
    # The closed-form root that matches at the start must match at every input.
    x = path.inputs
    roots = {}
    for r in (1, -1):
        vals = []
        for xi in x:
            v, ok = _closed(name, xi, r)
            assert ok
            vals.append(v)
        roots[r] = np.array(vals)
    start = min(roots, key=lambda r: abs(_wrap(roots[r][0] - hd[0])))
    assert_allclose(_wrap(hd - roots[start]), 0.0, atol=1e-9)
    # ... and the other root is clearly away (so the match is not a coincidence).
    assert np.min(np.abs(_wrap(roots[-start] - hd))) > 1e-3
    # Continuity: no step of the unwrapped output exceeds a few input steps.
    assert np.max(np.abs(np.diff(np.unwrap(hd)))) < 10 * (x[1] - x[0])


def test_rccc_slides_and_frames_match_closed_form(paths):
    lk, path = paths["rccc", 1]
    al = tuple(math.radians(v) for v in RCCC_ARGS["alphas"])
    svars = [k for k, (f, kind) in enumerate(lk.loop.variables) if kind == "s"]
    for x, q in zip(path.inputs[::10], path.q[::10]):
        ref = cf.rccc(al, RCCC_ARGS["lengths"], RCCC_ARGS["s0"], x, 1)
        assert ref.ok
        W = _world(lk, q)
        assert_allclose(q[svars], ref.slides, atol=1e-9)
        for k in range(4):
            assert_allclose(W[k][:3, 3], ref.origins[k], atol=1e-9)
            assert_allclose(W[k][:3, 2], ref.z[k], atol=1e-9)


def test_planar_matches_linkage_fourbar(paths):
    """Cross-check with the planar four-bar of the linkage-error work."""
    from mechanisms.linkage.fourbar import FourBar, solve as fb_solve
    lk, path = paths["planar", 1]
    p = PLANAR_ARGS
    fb = FourBar.from_lengths(p["ground"], p["crank"], p["coupler"], p["rocker"], assembly="open")
    m = fb_solve(fb, path.inputs, omega2=1.0, alpha2=0.0)
    hd = np.array([_output("planar", lk, q) for q in path.q])
    assert_allclose(_wrap(hd - m.theta4), 0.0, atol=1e-10)
    out = lk.output
    # The HD output theta_3 turns x_3 (along C -> D) onto x_0 (+x), so
    # theta_3 = -(theta4 + pi) and its rates are minus the rocker's.
    assert_allclose(_wrap(path.q[:, out] + m.theta4 + math.pi), 0.0, atol=1e-10)
    assert_allclose(-path.qd[:, out], m.omega4, atol=1e-8)
    assert_allclose(-path.qdd[:, out], m.alpha4, atol=1e-7)


def test_hd_matrix_matches_paper_layout():
    a, al, th, s = 1.3, 0.4, 0.7, -0.2
    P = hd_matrix(a, al, th, s, layout="paper")
    ct, st, ca, sa = math.cos(th), math.sin(th), math.cos(al), math.sin(al)
    printed = np.array([[1, 0, 0, 0],
                        [a * ct, ct, -st * ca, st * sa],
                        [a * st, st, ct * ca, -ct * sa],
                        [s, 0, sa, ca]])
    assert_allclose(P, printed, atol=1e-15)
    # Derivative operators (Eq. 3, 7): dA/dtheta = Q_theta A, dA/ds = Q_s A.
    h = 1e-6
    dth = (hd_matrix(a, al, th + h, s) - hd_matrix(a, al, th - h, s)) / (2 * h)
    ds = (hd_matrix(a, al, th, s + h) - hd_matrix(a, al, th, s - h)) / (2 * h)
    A = hd_matrix(a, al, th, s)
    assert_allclose(dth, Q_THETA @ A, atol=1e-9)
    assert_allclose(ds, Q_S @ A, atol=1e-9)
    assert len(SELECTED_ENTRIES) == 9
    with pytest.raises(ValueError, match="layout must be"):
        hd_matrix(a, al, th, s, layout="transposed")


def test_non_assemblable_inputs_get_status():
    # Rocker-crank (Grashof, 3 + 5 < 4 + 4.5, the rocker shortest): the crank cannot turn fully.
    from mechanisms.spatial import planar_fourbar
    tr = planar_fourbar(5.0, 4.0, 3.0, 4.5, 0.3)
    x = 0.3 + np.linspace(0, 2 * math.pi, 181)
    path = solve_path(tr.loop, x, tr.q0)
    st = path.status
    assert np.any(st == LoopStatus.NOT_ASSEMBLABLE)
    assert np.any(st == LoopStatus.CONVERGED)
    assert np.all(np.isfinite(path.q)) and np.all(np.isfinite(path.qd)) and np.all(np.isfinite(path.qdd))
    # Closed poses agree with Freudenstein, on the branch they started on.
    good = st == LoopStatus.CONVERGED
    assert np.max(path.residual[good]) <= 1e-10
    # Closed-form check: the loop closes exactly where Freudenstein has a real root
    # (crank ranges 10.5..94.8 deg and their mirror); the solver re-enters after gaps.
    ok = np.array([cf.freudenstein(5.0, 4.0, 3.0, 4.5, xi, 1)[1] for xi in x])
    assert np.array_equal(ok, st <= LoopStatus.SINGULAR)
    assert np.count_nonzero(path.gap_before) == 2
    # A single impossible pose.
    pose = solve_pose(tr.loop, math.pi, tr.q0)
    assert pose.status in (LoopStatus.NOT_ASSEMBLABLE, LoopStatus.MAX_ITER)
    assert not pose.success and np.all(np.isfinite(pose.q))
    assert "cannot be closed" in pose.message or "iteration" in pose.message


def test_limit_position_is_flagged_singular():
    # At the crank's limit the coupler and rocker are collinear: M loses rank.
    a, b, c, d = 5.0, 4.0, 3.0, 4.5
    # Limit: |B - D| = b + c  ->  a^2 + d^2 - 2 a d cos(th) = (b + c)^2.
    th = math.acos((a * a + d * d - (b + c) ** 2) / (2 * a * d))
    from mechanisms.spatial import planar_fourbar
    tr = planar_fourbar(a, b, c, d, th - 0.05)
    x = np.linspace(th - 0.05, th, 60)
    path = solve_path(tr.loop, x, tr.q0)
    # the branches meet there: closed but singular, closed but reached only by what
    # looks like a jump of branch (a true closure), or not closed by rounding
    assert path.status[-1] in (LoopStatus.SINGULAR, LoopStatus.NOT_ASSEMBLABLE,
                               LoopStatus.BRANCH_JUMP)
    if path.status[-1] == LoopStatus.BRANCH_JUMP:
        assert path.residual[-1] <= 1e-10
    assert np.all(np.isfinite(path.qd))
    assert path.status[0] == LoopStatus.CONVERGED


def test_make_loop_validation():
    with pytest.raises(ValueError, match="kind must be one of R, P, C, S"):
        make_loop([Joint("X", a=1.0), Joint("R", a=1.0)])
    with pytest.raises(ValueError, match="3 finite angles for S"):
        make_loop([Joint("S", theta=1.0), Joint("R", a=1.0)])
    with pytest.raises(ValueError, match=r"input_variable must be an int in \[0, "):
        make_loop([Joint("R", a=1.0), Joint("R", a=1.0)], input_variable=5)
    lp = make_loop([Joint("R", a=1), {"kind": "C", "a": 2}, Joint("S", theta=(0, 90, 0)),
                    Joint("P")], unit="deg")
    assert lp.signature() == "RCSP"
    assert lp.n_frames == 1 + 1 + 3 + 1
    assert lp.n_vars == 1 + 2 + 3 + 1
    assert [k for _, k in lp.variables] == ["theta", "theta", "s", "theta", "theta", "theta", "s"]
    assert lp.frames[2].alpha == pytest.approx(math.pi / 2) and lp.joints[2].kind is JointType.S
    assert lp.frames[3].theta == pytest.approx(math.pi / 2)     # S middle angle, deg -> rad
    with pytest.raises(ValueError, match="loop must be a Loop"):
        solve_pose("RRRR", 0.0)
    with pytest.raises(ValueError, match=r"q must have shape \(7,\)"):
        loop_residual(lp, [0.0, 1.0])
