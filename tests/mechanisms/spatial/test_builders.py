"""Ready-made loops (``mechanisms.spatial.builders``): the HD tables read off
the frames, the start pose against the world layout written out by hand, and
:func:`hd_from_frames` as the inverse of chaining HD matrices."""

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError, InvalidModelError, NonFiniteError
from mechanisms.spatial import (Linkage, frame_transforms, hd_from_frames, loop_residual,
                                planar_fourbar, rccc, rssr, solve_pose, spherical_4r)

SPH = (0.5, 1.5, 1.0, 1.2)
RCCC = dict(alphas=(30, 80, 60, 70), lengths=(1.0, 3.0, 2.5, 3.5), s0=0.5, theta=20)
RSSR = dict(crank=1.0, crank_height=0.5, coupler=3.0, rocker=2.0, offset=2.5,
            twist=math.radians(60), rocker_height=0.5, theta=0.3)


def _world(lk, q=None):
    return lk.ground @ frame_transforms(lk.loop, lk.q0 if q is None else q)


def _circle_meet(b, rb, d, rd):
    """The two intersections of circles about b and d, (left of b->d, right)."""
    v = d - b
    dist = math.hypot(*v)
    x = (dist ** 2 + rb ** 2 - rd ** 2) / (2 * dist)
    h = math.sqrt(rb ** 2 - x ** 2)
    u = v / dist
    n = np.array([-u[1], u[0]])
    return b + x * u + h * n, b + x * u - h * n


def _all():
    return [planar_fourbar(2.0, 7.0, 9.0, 6.0, 0.3), spherical_4r(SPH, 0.3),
            rccc(**RCCC, unit="deg"), rssr(**RSSR)]


@pytest.mark.parametrize("branch", [1, -1])
def test_planar_fourbar_start_pose_is_the_hand_layout(branch):
    a, b, c, d, th = 2.0, 7.0, 9.0, 6.0, 0.3
    lk = planar_fourbar(a, b, c, d, th, branch=branch)
    assert isinstance(lk, Linkage) and lk.loop.signature() == "RRRR" and lk.output == 3
    assert_allclose(lk.ground, np.eye(4), atol=0)
    B = a * np.array([math.cos(th), math.sin(th)])
    D = np.array([d, 0.0])
    left, right = _circle_meet(B, b, D, c)
    C = left if branch == 1 else right
    W = _world(lk)
    for k, P in enumerate((np.zeros(2), B, C, D)):
        assert_allclose(W[k][:3, 3], [P[0], P[1], 0.0], atol=1e-12)
        assert_allclose(W[k][:3, 2], [0.0, 0.0, 1.0], atol=1e-15)
    # planar: no twists, no offsets; the link lengths with the ground as -d
    rows = [(f.a, f.alpha, f.s) for f in lk.loop.frames]
    assert_allclose(rows, [(a, 0, 0), (b, 0, 0), (c, 0, 0), (-d, 0, 0)], atol=1e-12)
    assert lk.q0[0] == pytest.approx(th, abs=1e-15)      # the HD input is the crank angle
    assert loop_residual(lk.loop, lk.q0) <= 1e-13
    assert lk.params == dict(crank=a, coupler=b, rocker=c, ground=d, theta=th, branch=branch)


def test_spherical_4r_keeps_every_axis_through_the_centre():
    lk = spherical_4r(SPH, 0.3)
    assert_allclose([(f.a, f.alpha, f.s) for f in lk.loop.frames],
                    [(0.0, al, 0.0) for al in SPH], atol=1e-14)
    W = _world(lk)
    assert_allclose(W[:, :3, 3], 0.0, atol=1e-14)
    z = W[:, :3, 2]
    # consecutive axes make the twist angles, ground axes as laid out
    for i in range(4):
        assert z[i] @ z[(i + 1) % 4] == pytest.approx(math.cos(SPH[i]), abs=1e-13)
    assert_allclose(z[0], [0, 0, 1], atol=1e-15)
    assert_allclose(z[3], [0, math.sin(SPH[3]), math.cos(SPH[3])], atol=1e-14)
    assert loop_residual(lk.loop, lk.q0) <= 1e-13
    deg = spherical_4r(np.degrees(SPH), math.degrees(0.3), unit="deg")
    assert_allclose(deg.q0, lk.q0, atol=1e-12)


def test_rccc_table_holds_the_given_dimensions():
    lk = rccc(**RCCC, unit="deg")
    assert lk.loop.signature() == "RCCC" and lk.loop.n_vars == 7
    assert lk.output == 5                                  # the last joint's theta
    assert lk.loop.variables[lk.output] == (3, "theta")
    assert_allclose([f.a for f in lk.loop.frames], RCCC["lengths"], atol=1e-13)
    assert_allclose([f.alpha for f in lk.loop.frames], np.radians(RCCC["alphas"]), atol=1e-13)
    assert lk.loop.frames[0].s == pytest.approx(RCCC["s0"], abs=1e-13)
    assert not lk.loop.frames[0].s_var and lk.loop.frames[1].s_var
    assert loop_residual(lk.loop, lk.q0) <= 1e-13
    json.dumps(lk.to_dict())


def test_rssr_start_pose_is_the_hand_layout():
    lk = rssr(**RSSR)
    assert lk.loop.signature() == "RSSR" and lk.loop.idle_dof == 1
    assert lk.loop.n_frames == 8 and lk.output == 7
    W = _world(lk)
    r1, h1, l, r2 = RSSR["crank"], RSSR["crank_height"], RSSR["coupler"], RSSR["rocker"]
    th, tw, e, h2 = RSSR["theta"], RSSR["twist"], RSSR["offset"], RSSR["rocker_height"]
    B = np.array([r1 * math.cos(th), r1 * math.sin(th), h1])
    u = np.array([0.0, math.sin(tw), math.cos(tw)])
    O2 = np.array([-e, 0.0, 0.0]) - h2 * u
    for k in (1, 2, 3):                                    # the first S joint's centre
        assert_allclose(W[k][:3, 3], B, atol=1e-12)
    C = W[4][:3, 3]
    assert_allclose(W[5][:3, 3], C, atol=1e-12)           # the second S joint's centre
    assert_allclose(W[6][:3, 3], C, atol=1e-12)
    assert np.linalg.norm(C - B) == pytest.approx(l, abs=1e-12)        # the coupler
    assert np.linalg.norm(C - O2) == pytest.approx(r2, abs=1e-12)      # the rocker
    assert (C - O2) @ u == pytest.approx(0.0, abs=1e-12)              # in its plane
    assert_allclose(W[7][:3, 3], O2, atol=1e-12)
    assert_allclose(W[7][:3, 2], u, atol=1e-14)                        # the output axis
    assert loop_residual(lk.loop, lk.q0) <= 1e-13


@pytest.mark.parametrize("lk", _all(), ids=lambda lk: lk.name)
def test_hd_from_frames_inverts_the_chain(lk):
    """At another closed pose the frames give back the constant a, alpha and
    the variables' values."""
    p = solve_pose(lk.loop, lk.q0[lk.loop.input] + 0.5, lk.q0)
    assert p.success
    T = frame_transforms(lk.loop, p.q)
    rows = hd_from_frames(T[:, :3, 3], T[:, :3, 2], T[:, :3, 0],
                          length_scale=lk.loop.length_scale)
    assert_allclose(rows[:, 0], [f.a for f in lk.loop.frames], atol=1e-10)
    assert_allclose(rows[:, 1], [f.alpha for f in lk.loop.frames], atol=1e-10)
    for v, (fi, kind) in enumerate(lk.loop.variables):
        got = rows[fi, 2] if kind == "theta" else rows[fi, 3]
        if kind == "theta":
            assert math.remainder(got - p.q[v], 2 * math.pi) == pytest.approx(0.0, abs=1e-10)
        else:
            assert got == pytest.approx(p.q[v], abs=1e-10)


def test_hd_from_frames_refuses_frames_that_break_the_rules():
    lk = planar_fourbar(2.0, 7.0, 9.0, 6.0, 0.3)
    T = frame_transforms(lk.loop, lk.q0)
    o, z, x = T[:, :3, 3].copy(), T[:, :3, 2].copy(), T[:, :3, 0].copy()
    hd_from_frames(o, z, x, length_scale=9.0)
    o_bad = o.copy()
    o_bad[2] += 0.01 * np.cross(z[1], x[2])          # moves C off span(z_1, x_2)
    with pytest.raises(InvalidModelError, match=r"frames 1->2 break the HD rules"):
        hd_from_frames(o_bad, z, x, length_scale=9.0)
    x_bad = x.copy()
    x_bad[1] = [0.0, 0.0, 1.0]                       # x_1 along z: not a common normal
    with pytest.raises(InvalidModelError, match=r"x_1 must be normal to z_0 and z_1"):
        hd_from_frames(o, z, x_bad)


@pytest.mark.parametrize("call, exc, match", [
    (lambda: planar_fourbar(5.0, 1.0, 1.0, 20.0, 0.3), InvalidModelError,
     "cannot be assembled at theta"),
    (lambda: planar_fourbar(2.0, 7.0, 9.0, 6.0, 0.3, branch=0), InputError,
     "branch must be \\+1 or -1; got 0"),
    (lambda: planar_fourbar(-2.0, 7.0, 9.0, 6.0, 0.3), InputError, "crank must be > 0"),
    (lambda: planar_fourbar(2.0, 7.0, 9.0, math.nan, 0.3), NonFiniteError, "ground must be finite"),
    (lambda: spherical_4r((0.5, 1.5, 1.0), 0.3), InputError, "alphas must be 4 twist angles"),
    (lambda: spherical_4r((0.5, 1.5, 1.0, 0.0), 0.3), InputError,
     r"alphas\[3\] must lie strictly between 0 and pi rad \(0 and 180 deg\); got 0.0 rad$"),
    # twists written in degrees, read in radians: the message says so
    (lambda: rccc((45, 75, 50, 80), (20, 50, 40, 60), 10, 0.1), InputError,
     r"alphas\[0\] must lie strictly between 0 and pi rad \(0 and 180 deg\); got 45 rad; "
     r"written in degrees\? pass unit='deg' \(radians\(45\) = 0.785398\)"),
    (lambda: spherical_4r((0.2, 2.5, 0.2, 0.3), 0.3), InvalidModelError,
     "cannot be assembled"),
    (lambda: rccc((30, 80, 60, 70), (1.0, 3.0, 2.5), 0.5, 20, unit="deg"), InputError,
     "lengths must be 4 numbers"),
    (lambda: rccc((30, 80, 60, 70), (1.0, -3.0, 2.5, 3.5), 0.5, 20, unit="deg"), InputError,
     r"lengths\[1\] must be >= 0"),
    (lambda: rssr(1.0, 0.5, 3.0, 2.0, 2.5, 0.0, 0.5, 0.3), InputError,
     "twist must lie strictly between 0 and pi rad \\(0 and 180 deg\\); got 0.0 rad$"),
    (lambda: rssr(1.0, 0.5, 3.0, 2.0, 2.5, 70, 0.5, 0.3), InputError,
     "got 70 rad; written in degrees\\? pass unit='deg'"),
    (lambda: rssr(1.0, 0.5, 0.5, 2.0, 2.5, 1.0, 0.5, 0.3), InvalidModelError,
     "RSSR cannot be assembled"),
    (lambda: rssr(1.0, 0.5, 3.0, 2.0, -2.5, 1.0, 0.5, 0.3), InputError, "offset must be >= 0"),
])
def test_builders_reject_bad_input(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


def test_every_builder_closes_on_both_branches():
    for br in (1, -1):
        for lk in (planar_fourbar(2.0, 7.0, 9.0, 6.0, 0.3, branch=br),
                   spherical_4r(SPH, 0.3, branch=br), rccc(**RCCC, branch=br, unit="deg"),
                   rssr(**RSSR, branch=br)):
            assert loop_residual(lk.loop, lk.q0) <= 1e-12, (lk.name, br)
            assert lk.params["branch"] == br
    # the two branches are different assemblies
    a = _world(planar_fourbar(2.0, 7.0, 9.0, 6.0, 0.3, branch=1))[2][:3, 3]
    b = _world(planar_fourbar(2.0, 7.0, 9.0, 6.0, 0.3, branch=-1))[2][:3, 3]
    assert np.linalg.norm(a - b) > 1.0


def test_a_loop_that_cannot_close_says_where_it_can():
    """A start angle where the loop does not close names the input angles
    where it does; dimensions that close it nowhere say so, instead of
    asking for another start angle."""
    from mechanisms.spatial.builders import planar_fourbar, rssr
    # exact limits acos(-0.35) = 1.92837 rad, rounded inwards, in the unit given
    with pytest.raises(InvalidModelError, match=r"choose a start angle where it assembles: "
                                                r"\[-1\.9283, 1\.9283\] rad"):
        planar_fourbar(40, 70, 50, 100, 3.1)
    for f in (lambda: planar_fourbar(40, 120, 100, 1000, 0.3),
              lambda: rssr(20, 10, 5000, 50, 60, 60, 5, 0, unit="deg")):
        with pytest.raises(InvalidModelError, match="assembles at no input angle"):
            f()
