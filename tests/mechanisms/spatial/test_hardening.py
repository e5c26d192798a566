"""Hardening of :mod:`mechanisms.spatial`: results that do not depend on the length
unit, poses that close reported as closed, typed errors for bad input, exact
assembly limits in messages, and the documentation's four-bar classification."""

import math
import re
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError, NonFiniteError, InvalidModelError
from mechanisms.linkage import FourBar
from mechanisms.linkage.fourbar import GrashofType, grashof
from mechanisms.spatial import (LoopStatus, SolverOptions, acceleration, closedform as cf,
                                hd_matrix, loop_residual, planar_fourbar, point_motion, rccc,
                                rssr, solve_path, solve_pose, spherical_4r, velocity)

from .conftest import build

RCCC_AL = (30, 80, 60, 70)
RCCC_LEN = (1.0, 3.0, 2.5, 3.5)
DOC = Path(__file__).resolve().parents[3] / "docs" / "spatial.md"


def _rccc(scale):
    return rccc(RCCC_AL, tuple(v * scale for v in RCCC_LEN), 0.5 * scale, 20, unit="deg")


def _split(lk):
    ang = [k for k, (_, kind) in enumerate(lk.loop.variables) if kind == "theta"]
    sl = [k for k, (_, kind) in enumerate(lk.loop.variables) if kind == "s"]
    return ang, sl


# ------------------------------------------------------------ 1, 2: length unit

def test_a_linkage_in_millimetres_solves_like_the_same_in_metres():
    m, mm = _rccc(1.0), _rccc(1000.0)
    ang, sl = _split(m)
    a = solve_pose(m.loop, 25, unit="deg")
    b = solve_pose(mm.loop, 25, unit="deg")
    assert a.status == b.status == LoopStatus.CONVERGED
    assert a.iterations == b.iterations
    assert_allclose(b.q[ang], a.q[ang], rtol=1e-9, atol=1e-12)
    assert_allclose(b.q[sl] / 1000.0, a.q[sl], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("step", [5, 30, 60])
def test_paths_take_the_same_iterations_in_any_length_unit(step):
    ins = np.arange(20, 381, step)
    paths = [solve_path(_rccc(s).loop, ins, _rccc(s).q0, unit="deg") for s in (1.0, 1e3)]
    ang, sl = _split(_rccc(1.0))
    assert np.array_equal(paths[0].status, paths[1].status)
    assert np.array_equal(paths[0].iterations, paths[1].iterations)
    assert_allclose(paths[1].q[:, ang], paths[0].q[:, ang], rtol=1e-9, atol=1e-9)
    assert_allclose(paths[1].q[:, sl] / 1e3, paths[0].q[:, sl], rtol=1e-9, atol=1e-9)


def test_singular_flags_do_not_depend_on_the_length_unit():
    ins = np.radians(np.arange(20, 381, 5))
    status, ratio = [], []
    for s in (1.0, 1e3, 1e6):
        lk = _rccc(s)
        path = solve_path(lk.loop, ins, lk.q0)
        status.append(path.status)
        ratio.append([solve_pose(lk.loop, x, path.q[k]).sigma_ratio
                      for k, x in enumerate(ins[:5])])
    assert np.array_equal(status[0], status[1]) and np.array_equal(status[0], status[2])
    assert not np.any(status[2] == LoopStatus.SINGULAR)
    assert_allclose(ratio[1], ratio[0], rtol=1e-6)
    assert_allclose(ratio[2], ratio[0], rtol=1e-6)


# ------------------------------------------------------ 3: closed means closed

@pytest.mark.parametrize("name", ["planar", "spherical", "rccc", "rssr"])
@pytest.mark.parametrize("offset_deg", [-0.005, 0.0, 0.005])
def test_half_a_turn_from_the_start_closes(name, offset_deg):
    lk = build(name)
    x = lk.q0[lk.loop.input] + math.pi + math.radians(offset_deg)
    pose = solve_pose(lk.loop, x)
    assert pose.success, pose
    assert pose.q[lk.loop.input] == x
    assert loop_residual(lk.loop, pose.q) <= 1e-10


def test_half_a_turn_of_the_crank_rocker_from_the_report():
    lk = planar_fourbar(3, 8, 7, 10, 0.9)
    pose = solve_pose(lk.loop, 0.9 + math.pi)
    assert pose.status == LoopStatus.CONVERGED
    # the pose that continuation along the input reaches (the start's branch)
    path = solve_path(lk.loop, np.linspace(0.9, 0.9 + math.pi, 181), lk.q0)
    assert path.success
    d = (pose.q - path.q[-1] + math.pi) % (2 * math.pi) - math.pi
    assert np.max(np.abs(d)) < 1e-9
    # an explicit closed estimate half a turn away also closes
    r = _rccc(1.0)
    assert solve_pose(r.loop, 200, r.q0, unit="deg").status == LoopStatus.CONVERGED


@pytest.mark.parametrize("name", ["planar", "rccc"])
def test_a_path_may_start_half_a_turn_from_its_estimate(name):
    lk = build(name)
    x = lk.q0[lk.loop.input] + math.pi + np.array([0.0, 0.01, 0.02])
    path = solve_path(lk.loop, x, lk.q0)
    assert path.success and not np.any(path.gap_before)


def test_another_circuit_is_found_and_impossible_inputs_stay_impossible():
    lk = planar_fourbar(5, 4, 3, 4.5, 50, unit="deg")       # crank range [10.48, 94.78] deg
    other = solve_pose(lk.loop, -50, unit="deg")             # the mirror circuit
    assert other.success and loop_residual(lk.loop, other.q) <= 1e-10
    for t in (0.0, 120.0, 180.0):
        pose = solve_pose(lk.loop, t, unit="deg")
        assert pose.status == LoopStatus.NOT_ASSEMBLABLE and pose.residual > 1e-3


def test_a_long_input_step_continues_along_the_path():
    lk = _rccc(1.0)
    path = solve_path(lk.loop, [math.radians(20), 100.0], lk.q0)
    assert path.success and path.status[1] == LoopStatus.CONVERGED
    ref = cf.rccc(np.radians(RCCC_AL), RCCC_LEN, 0.5, 100.0, 1)
    ang, sl = _split(lk)
    assert_allclose(path.q[1, sl], ref.slides, atol=1e-9)


def test_a_closed_pose_is_never_called_not_assemblable():
    lk = _rccc(1.0)
    opts = SolverOptions(jump_factor=1e-6, max_subdivisions=1)
    path = solve_path(lk.loop, np.radians([20, 40, 60]), lk.q0, options=opts)
    assert not np.any(path.status == LoopStatus.NOT_ASSEMBLABLE)
    jumped = path.status == LoopStatus.BRANCH_JUMP
    assert np.any(jumped) and not path.success
    assert np.all(path.residual[jumped] <= 1e-10)
    for k in np.flatnonzero(jumped):
        assert loop_residual(lk.loop, path.q[k]) <= 1e-10
        assert path.q[k, lk.loop.input] == path.inputs[k]
    assert "reached by a branch jump" in path.message
    assert "BRANCH_JUMP" in path.to_dict()["status"]


# ---------------------------------------------------------- 4: no silent NaN

def test_hd_matrix_refuses_nan():
    with pytest.raises(NonFiniteError, match="a must be finite"):
        hd_matrix(math.nan, 0, 0, 0)
    with pytest.raises(NonFiniteError, match="s must be finite"):
        hd_matrix(1.0, 0, 0, math.inf)


def test_rates_need_a_closed_pose():
    lk = _rccc(1.0)
    q = np.zeros(lk.loop.n_vars)
    for f in (lambda: velocity(lk.loop, q), lambda: acceleration(lk.loop, q),
              lambda: point_motion(lk.loop, q, 1)):
        with pytest.raises(InputError, match=r"needs a closed pose.*residual <= closure_tol"):
            f()
    # a closed pose passes; a looser closure_tol is the caller's choice
    assert np.all(np.isfinite(velocity(lk.loop, lk.q0)))
    assert np.all(np.isfinite(velocity(lk.loop, q, closure_tol=10.0)))


# ------------------------------------------------------- 5: typed exceptions

@pytest.mark.parametrize("call, exc, match", [
    (lambda: spherical_4r(0.3, 0.3), InputError, "alphas must be 4 twist angles"),
    (lambda: spherical_4r(None, 0.3), InputError, "alphas must be 4 twist angles"),
    (lambda: rccc(RCCC_AL, 1.0, 0.5, 20, unit="deg"), InputError, "lengths must be 4 numbers"),
    (lambda: hd_matrix("a", 0, 0, 0), InputError, "a must be a real number"),
    (lambda: planar_fourbar(3, 8, 7, 10, 0.9, branch=True), InputError,
     r"branch must be \+1 or -1; got True \(bool"),
    (lambda: planar_fourbar(3, 8, 7, 10, 0.9, branch=np.bool_(True)), InputError,
     r"branch must be \+1 or -1"),
    (lambda: spherical_4r((0.5, 1.5, 1.0, 1.2), 0.3, branch=False), InputError,
     r"branch must be \+1 or -1"),
])
def test_bad_builder_input_is_a_typed_error(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


@pytest.mark.parametrize("args, exc, match", [
    ((np.zeros((4, 3)), np.zeros((3, 3)), np.zeros((4, 3))), InputError,
     r"origins, z and x must be \(n, 3\) arrays of one n >= 2 .*got shapes \(4, 3\), \(3, 3\)"),
    ((np.full((4, 3), np.nan),) * 3, NonFiniteError, "origins must be finite"),
    (("a", "b", "c"), InputError, r"origins must be an \(n, 3\) array of numbers, got 'a'"),
    ((np.zeros((4, 2)),) * 3, InputError, r"origins must be an \(n, 3\) array .*shape \(4, 2\)"),
])
def test_hd_from_frames_refuses_bad_frames(args, exc, match):
    """Frames of other shapes raised an IndexError, NaN ones gave a NaN table."""
    from mechanisms.spatial.builders import hd_from_frames
    with pytest.raises(exc, match=match):
        hd_from_frames(*args)


@pytest.mark.parametrize("theta", ["abc", {"a": 1}, object(), [1.0, 2.0], [1.0, 2.0, math.nan]])
def test_a_spherical_joint_needs_three_angles(theta):
    """theta='abc' raised numpy's ValueError, a dict a TypeError."""
    from mechanisms.spatial.loops import Joint, make_loop
    with pytest.raises(InputError, match=r"joints\[0\]\.theta must be 3 finite angles for S"):
        make_loop([Joint("S", a=1, theta=theta), Joint("R", a=1), Joint("R", a=1),
                   Joint("R", a=1)])


def test_bad_point_is_a_typed_error():
    lk = _rccc(1.0)
    with pytest.raises(InputError, match="point must be 3 finite numbers"):
        point_motion(lk.loop, lk.q0, 1, point="abc")
    with pytest.raises(InputError, match="point must be 3 finite numbers"):
        point_motion(lk.loop, lk.q0, 1, point=[[1.0, 2.0, 3.0]])
    with pytest.raises(NonFiniteError, match="point must be 3 finite numbers"):
        point_motion(lk.loop, lk.q0, 1, point=(1.0, math.nan, 0.0))


# ------------------------------------------------------------ 6: the doc text

def test_doc_names_the_grashof_type_of_its_four_bar():
    text = DOC.read_text(encoding="utf-8")
    assert "triple-rocker" not in text.lower()
    # crank 5, coupler 4, rocker 3, ground 4.5
    assert grashof(FourBar.from_lengths(4.5, 5.0, 4.0, 3.0)) is GrashofType.ROCKER_CRANK
    assert "ROCKER_CRANK" in text
    lo = math.degrees(math.acos((25 + 4.5 ** 2 - 1) / (2 * 5 * 4.5)))
    hi = math.degrees(math.acos((25 + 4.5 ** 2 - 49) / (2 * 5 * 4.5)))
    assert f"{lo:.2f} to {hi:.2f} deg" in text


# -------------------------------------------------------------- 7: messages

def _spans(message):
    return [(float(a), float(b)) for a, b in
            re.findall(r"\[(-?[\d.]+), (-?[\d.]+)\] (?:deg|rad)", message)]


def test_four_bar_limits_are_exact():
    with pytest.raises(InvalidModelError) as e:
        planar_fourbar(5, 4, 3, 4.5, 180, unit="deg")
    msg = str(e.value)
    assert "theta = 180 deg" in msg and "rad" not in msg
    assert _spans(msg) == [(-94.78, -10.48), (10.48, 94.78)]
    with pytest.raises(InvalidModelError, match=r"theta = 3\.14159 rad.*\[0\.1829, 1\.6542\] rad"):
        planar_fourbar(5, 4, 3, 4.5, math.pi)


def test_spatial_messages_echo_the_unit_and_exact_ranges():
    with pytest.raises(InvalidModelError) as e:
        rssr(1, 0.5, 0.1, 2, 2.5, 60, 0.5, 20, unit="deg")
    msg = str(e.value)
    assert "theta = 20 deg" in msg and "rad" not in msg
    geo = cf.RSSRGeometry(1, 0.5, 0.1, 2, 2.5, math.radians(60), 0.5)
    (lo, hi), = _spans(msg)
    # inside the printed range it assembles; 0.02 deg beyond either end it does not
    for t in np.linspace(lo, hi, 50):
        assert cf.rssr_phi(geo, math.radians(t), 1)[1]
    assert not cf.rssr_phi(geo, math.radians(lo - 0.02), 1)[1]
    assert not cf.rssr_phi(geo, math.radians(hi + 0.02), 1)[1]

    al = (20, 80, 20, 100)
    with pytest.raises(InvalidModelError) as e:
        rccc(al, RCCC_LEN, 0.5, 0, unit="deg")
    msg = str(e.value)
    assert "theta = 0 deg" in msg and "rad" not in msg
    spans = _spans(msg)
    assert spans
    for lo, hi in spans:
        for t in np.linspace(lo, hi, 20):
            assert cf.spherical_4r_psi(np.radians(al), math.radians(t), 1)[1]
        # (a range across +-180 deg is shown as two pieces ending there)
        if lo > -180.0:
            assert not cf.spherical_4r_psi(np.radians(al), math.radians(lo - 0.02), 1)[1]
        if hi < 180.0:
            assert not cf.spherical_4r_psi(np.radians(al), math.radians(hi + 0.02), 1)[1]
    with pytest.raises(InvalidModelError, match=r"twists \[20\.0, 80\.0, 20\.0, 100\.0\] deg "
                                                r"cannot be assembled at theta = 0 deg"):
        spherical_4r(al, 0, unit="deg")
