"""Bad input and edge poses of ``mechanisms.manipulators``: typed errors, statuses
at unreachable and near-singular poses, and independence of the length unit."""

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import CSpaceError, InputError, InvalidModelError, NonFiniteError
from mechanisms.manipulators import (Arrangement, Singularity, TwoPaP, TwoPPa, actuator_forces,
                                     arrangement_comparison, decoupling, effective_square,
                                     global_design_index, inverse_kinematics, jacobians,
                                     ldi_of_jacobian, local_design_index, platform_force,
                                     square_fits, total_workspace, two_pap, two_ppa)
from mechanisms.manipulators import jacobian as jacobian_module

PAP = two_pap(150.0, 50, unit="deg")
PPA = two_ppa(200.0, 350.0, 250.0, 25, b=60.0, unit="deg")


def _near_direct(model, eps):
    """A pose ``eps la`` off the direct singularity theta_1 = theta_2 = 45 deg."""
    s = math.sin(math.pi / 4)
    return np.array([s, s]) * model.la + np.array([eps, eps]) * model.la


# -- 1. the LDI of a pose the manipulator cannot reach ---------------------------------

def test_ldi_refuses_an_unreachable_pose():
    assert inverse_kinematics(PPA, [0.0, -150.0]).status == 1          # OUTSIDE_WORKSPACE
    with pytest.raises(InputError, match=r"OUTSIDE_WORKSPACE") as e:
        local_design_index(PPA, [0.0, -150.0])
    assert e.value.name == "p"
    assert "reach" in str(e.value) and "PoseStatus.OK" in str(e.value)
    with pytest.raises(InputError, match=r"1 of 3 poses"):
        local_design_index(PAP, [[0.0, 0.0], [10.0, 5.0], [149.0, 0.0]])
    # reachable poses keep their value; the formula elsewhere stays available
    assert local_design_index(PPA, [0.0, 0.0]) == pytest.approx(1.0, abs=1e-15)
    jac = jacobians(PPA, [0.0, -150.0])
    assert jac.pose_status == 1 and np.isfinite(ldi_of_jacobian(jac.j, "linear"))


def test_statics_at_an_unreachable_pose_is_not_a_success():
    res = actuator_forces(PPA, [0.0, -150.0], [1.0, 0.0])
    assert res.pose_status == 1 and not res.success
    assert actuator_forces(PPA, [0.0, 0.0], [1.0, 0.0]).success


# -- 2. relative, unit-independent singularity test --------------------------------------

def _long_stroke(scale):
    """A perpendicular 2-PPa whose direct singularity lies inside its workspace."""
    return two_ppa(100.0 * scale, 60.0 * scale, 400.0 * scale, 30, b=0.0, unit="deg")


def test_near_singular_pose_is_flagged_with_its_condition_number():
    m = _long_stroke(1.0)
    p = _near_direct(m, -1e-9)
    assert inverse_kinematics(m, p).status == 0                         # reachable
    jac = jacobians(m, p)
    assert abs(jac.det_x) < 1e-8
    assert jac.singularity == Singularity.NEAR_SINGULAR
    assert jac.condition > 1e8
    res = actuator_forces(m, p, [1.0, 0.0])
    assert res.singularity == Singularity.NEAR_SINGULAR and not res.success
    assert res.condition == pytest.approx(float(jac.condition), rel=1e-12)
    assert "NEAR_SINGULAR" in repr(res)
    assert not platform_force(m, p, [1.0, 0.0]).success
    # a regular pose: condition near 1, no flag
    jac = jacobians(m, [0.0, 0.0])
    assert jac.singularity == Singularity.NONE and jac.condition == pytest.approx(1.0)
    # exact singularity keeps its kind
    assert jacobians(m, _near_direct(m, 0.0)).singularity == Singularity.DIRECT


def test_cond_limit_is_the_near_singular_threshold():
    m = _long_stroke(1.0)
    p = _near_direct(m, -1e-3)
    cond = float(jacobians(m, p).condition)
    assert 100 < cond < jacobian_module.NEAR_SINGULAR_COND
    assert jacobians(m, p).singularity == Singularity.NONE
    assert jacobians(m, p, cond_limit=100.0).singularity == Singularity.NEAR_SINGULAR
    assert not actuator_forces(m, p, [1.0, 0.0], cond_limit=100.0).success
    with pytest.raises(InputError, match="cond_limit"):
        jacobians(m, p, cond_limit=0.5)


@pytest.mark.parametrize("eps", [-1e-9, -1e-6, -1e-3, -0.05])
def test_singularity_flags_do_not_depend_on_the_length_unit(eps):
    mm, m = _long_stroke(1.0), _long_stroke(1e-3)
    p_mm, p_m = _near_direct(mm, eps), _near_direct(m, eps)
    a, b = jacobians(mm, p_mm), jacobians(m, p_m)
    assert a.singularity == b.singularity
    assert_allclose(a.condition, b.condition, rtol=1e-5)
    fa, fb = actuator_forces(mm, p_mm, [1.0, 2.0]), actuator_forces(m, p_m, [1.0, 2.0])
    assert fa.singularity == fb.singularity and fa.success == fb.success
    assert_allclose(fa.tau, fb.tau, rtol=1e-5)                 # 2-PPa: forces, no length
    # 2-PaP: condition and flags unit-free, torques scale with the length unit
    pa, pb = two_pap(150.0, 89.99, unit="deg"), two_pap(0.15, 89.99, unit="deg")
    qa = [pa.half_width, 0.0]
    qb = [pb.half_width, 0.0]
    assert jacobians(pa, qa).singularity == jacobians(pb, qb).singularity
    assert_allclose(jacobians(pa, qa).condition, jacobians(pb, qb).condition, rtol=1e-6)
    assert_allclose(actuator_forces(pa, qa, [1.0, 1.0]).tau,
                    1e3 * actuator_forces(pb, qb, [1.0, 1.0]).tau, rtol=1e-6)


# -- 3. the model constructors validate ----------------------------------------------

@pytest.mark.parametrize("kw, name, err", [
    (dict(la=-1.0, theta_limit=0.5), "la", InputError),
    (dict(la="a", theta_limit=0.5), "la", InputError),
    (dict(la=math.inf, theta_limit=0.5), "la", NonFiniteError),
    (dict(la=1.0, theta_limit=5), "theta_limit", InputError),
    (dict(la=1.0, theta_limit=0.0), "theta_limit", InputError),
    (dict(la=1.0, theta_limit=True), "theta_limit", InputError),
    (dict(la=1.0, theta_limit=0.5, t=-1.0), "t", InputError),
])
def test_twopap_constructor_validates(kw, name, err):
    with pytest.raises(err) as e:
        TwoPaP(**kw)
    assert e.value.name == name and name in str(e.value)


def test_theta_limit_message_states_the_unit_rule():
    with pytest.raises(InputError, match=r"radians.*\(0, pi/2\).*unit=\"deg\"") as e:
        TwoPaP(la=1.0, theta_limit=60)
    assert "60" in str(e.value)


def test_twoppa_constructor_validates():
    good = dataclasses.asdict(PPA)
    good["arrangement"] = PPA.arrangement
    assert TwoPPa(**good) == PPA
    for field, value, err in [("la", 0.0, InputError), ("stroke", "x", InputError),
                              ("theta_limit", 2.0, InputError), ("base", [[0, 0]], InputError),
                              ("axis", ((2.0, 0.0), (0.0, 1.0)), InputError),
                              ("lateral", ((1.0, 0.0), (1.0, 0.0)), InvalidModelError),
                              ("arrangement", "perpendicular", InputError),
                              ("fk_branch", 0, InputError), ("ik_sign", True, InputError),
                              ("b", -1.0, InputError)]:
        kw = dict(good, **{field: value})
        with pytest.raises(err, match=field):
            TwoPPa(**kw)
    with pytest.raises(InputError, match="arrangement"):
        TwoPPa(**dict(good, arrangement=Arrangement.DECOUPLED_ROTARY))


def test_replace_revalidates():
    with pytest.raises(InputError, match="la"):
        dataclasses.replace(PAP, la=-2.0)


# -- 4. typed errors instead of TypeError / ValueError / AttributeError ---------------

@pytest.mark.parametrize("call, name", [
    (lambda: decoupling("x"), "model"),
    (lambda: decoupling(PPA, n="a"), "n"),
    (lambda: decoupling(PPA, n=10), "n"),
    (lambda: global_design_index(PPA, refine="a"), "refine"),
    (lambda: global_design_index(PPA, refine=-1), "refine"),
    (lambda: effective_square(PPA, rtol="a"), "rtol"),
    (lambda: effective_square(PPA, rtol=5.0), "rtol"),
    (lambda: square_fits(PPA, "a"), "w"),
    (lambda: total_workspace(PPA, arc_points=1), "arc_points"),
    (lambda: total_workspace(PPA, arc_points="a"), "arc_points"),
    (lambda: arrangement_comparison(start_deg="a"), "start_deg"),
    (lambda: arrangement_comparison(bound_deg=95.0), "bound_deg"),
    (lambda: ldi_of_jacobian("x", "linear"), "j"),
    (lambda: ldi_of_jacobian([[1.0, math.nan], [0.0, 1.0]], "linear"), "j"),
])
def test_bad_arguments_are_typed_errors(call, name):
    with pytest.raises(InputError) as e:
        call()
    assert e.value.name == name and name in str(e.value)


# -- 5. wrong shapes and values are refused ------------------------------------------

@pytest.mark.parametrize("call, name, text", [
    (lambda: arrangement_comparison(start_deg=(1.0, 2.0, 3.0)), "start_deg", r"\(3,\)"),
    (lambda: ldi_of_jacobian(np.eye(3), "linear"), "j", r"\(3, 3\)"),
    (lambda: actuator_forces(PAP, [0.0, 0.0], [[1, 2], [3, 4]]), "force", r"\(2, 2\)"),
    (lambda: platform_force(PAP, [0.0, 0.0], [[1, 2], [3, 4]]), "tau", r"\(2, 2\)"),
    (lambda: square_fits(PPA, -5.0), "w", r">= 0"),
    (lambda: inverse_kinematics(PAP, [True, False]), "p", "bool"),
    (lambda: inverse_kinematics(PAP, np.array([True, False])), "p", "bool"),
    (lambda: inverse_kinematics(PAP, [[0.0, 1.0], [True, 2.0]]), "p", "bool"),
    (lambda: jacobians(PAP, [1 + 2j, 0.0]), "p", "real"),
])
def test_wrong_shapes_and_values_are_refused(call, name, text):
    with pytest.raises(InputError, match=text) as e:
        call()
    assert e.value.name == name


def test_refusals_derive_from_the_library_root():
    for call in (lambda: ldi_of_jacobian("x", "linear"), lambda: decoupling(None),
                 lambda: TwoPaP(la="a", theta_limit=0.5)):
        with pytest.raises(CSpaceError):
            call()
