"""Velocity Jacobians, singularities, statics and the local design index.

Conventions ([Kim 2007])
------------------------
Both manipulators are written as ``J_x p_dot = J_q q_dot``.

2-PaP
    ``J_x = I``, ``J_q = la diag(cos th1, cos th2)`` and the paper's Jacobian is
    ``J = J_q`` with ``p_dot = J theta_dot`` (Eq. 3-4).  Statics: ``tau = J^T f`` (Eq. 5).
2-PPa
    ``J_x = [s_1^T; s_2^T]``, ``J_q = diag(s_1.e_1, s_2.e_2)`` (Eq. 19) and the paper's
    Jacobian is ``J = J_q^-1 J_x`` with ``J p_dot = d_dot`` (Eq. 21-22).  Statics:
    ``f = J^T tau`` (Eq. 23).

Singularities: ``det J_q = 0`` is the inverse (serial) kind, ``det J_x = 0`` the direct
(parallel) kind; for the perpendicular 2-PPa the latter is ``theta_1 + theta_2 = +-90 deg``.
Both are judged on dimensionless, scale-free measures, so that the verdict does not depend
on the length unit: the condition number of ``J_x`` (whose rows are unit vectors) and the
leg transmissions ``|cos theta_i|`` (``J_q`` divided by its value at ``theta = 0``).  Their
combination, :attr:`Jacobians.condition`, is 1 at an ideal pose and infinite at a
singular one; a pose whose condition exceeds ``cond_limit`` (default
:data:`NEAR_SINGULAR_COND`) is reported as :attr:`Singularity.NEAR_SINGULAR`.

Local design index (Eq. 27): the smallest semi-axis of the velocity ellipse
``{p_dot = G q_dot : |q_dot| <= 1}`` with ``G = J_x^-1 J_q``, i.e. the smallest singular
value of G.  For 2-PaP this is ``sqrt(min eig(J J^T))`` and for 2-PPa
``sqrt(min eig((J J^T)^-1)) = 1 / sigma_max(J)``, as the paper states.  It is computed
from ``J`` so that it stays finite at direct singularities.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from cspace.argcheck import getscalar
from cspace.errors import InputError, NonFiniteError

from .kinematics import PoseStatus, as_pairs, check_model, ik_arrays
from .models import TwoPaP

__all__ = ["Singularity", "Jacobians", "jacobians", "local_design_index", "ldi_of_jacobian",
           "StaticsResult", "actuator_forces", "platform_force", "SINGULAR_REL",
           "NEAR_SINGULAR_COND"]

#: Relative measure below which a Jacobian counts as exactly singular: the reciprocal
#: condition number of J_x, or the smallest leg transmission |cos theta_i| for J_q.
#: Both are dimensionless and O(1) at a good pose, so 1e-12 is a few hundred ulps.
SINGULAR_REL = 1e-12

#: Default condition number (:attr:`Jacobians.condition`) above which a pose that is not
#: exactly singular is reported as :attr:`Singularity.NEAR_SINGULAR`: actuator efforts or
#: platform velocities are then amplified more than 10^4 times relative to the ideal pose
#: (for example, 1 N on the platform asks more than 10 kN of an actuator).
NEAR_SINGULAR_COND = 1e4


class Singularity(enum.IntEnum):
    """Which Jacobian is singular at a pose."""

    NONE = 0      #: regular pose
    INVERSE = 1   #: det J_q = 0 (serial / inverse singularity)
    DIRECT = 2    #: det J_x = 0 (parallel / direct singularity)
    BOTH = 3      #: both
    NEAR_SINGULAR = 4  #: not exactly singular, but the condition number exceeds ``cond_limit``


def _short(a) -> str:
    return np.array2string(np.asarray(a), precision=4, threshold=8)


@dataclass(frozen=True)
class Jacobians:
    """Jacobians at one pose or a batch of poses.

    Attributes
    ----------
    jx, jq : (..., 2, 2) float
        ``J_x p_dot = J_q q_dot``.
    j : (..., 2, 2) float
        The paper's Jacobian: ``J_q`` for 2-PaP, ``J_q^-1 J_x`` for 2-PPa (zero rows where
        ``det J_q = 0``).
    g : (..., 2, 2) float
        Velocity map ``p_dot = g q_dot`` (pseudo-inverse based where ``det J_x = 0``).
    det_x, det_q : (...) float
        Determinants, ``det_q`` made dimensionless for 2-PaP (divided by ``la^2``).
    singularity : (...) int, :class:`Singularity` values
        ``INVERSE``/``DIRECT``/``BOTH`` at exact singularities, ``NEAR_SINGULAR`` where
        ``condition`` exceeds the ``cond_limit`` asked for.
    pose_status : (...) int, :class:`PoseStatus` of the IK used to place the legs
    condition : (...) float
        ``max(cond(J_x), 1 / min_i |cos theta_i|)``, dimensionless and so independent of
        the length unit: 1 at an ideal pose (2-PPa perpendicular at the centre), inf at
        an exact singularity.
    """

    jx: np.ndarray
    jq: np.ndarray
    j: np.ndarray
    g: np.ndarray
    det_x: np.ndarray
    det_q: np.ndarray
    singularity: np.ndarray
    pose_status: np.ndarray
    condition: np.ndarray

    def __repr__(self) -> str:
        sing = np.asarray(self.singularity)
        near = bool(np.any(sing == Singularity.NEAR_SINGULAR))
        return (f"Jacobians(det_x={_short(self.det_x)}, det_q={_short(self.det_q)}, "
                f"condition={_short(self.condition)}, "
                f"singular={bool(np.any((sing != 0) & (sing != Singularity.NEAR_SINGULAR)))}"
                + (", near-singular" if near else "") + ")")

    def to_dict(self) -> dict:
        return {k: np.asarray(getattr(self, k)).tolist() for k in
                ("jx", "jq", "j", "g", "det_x", "det_q", "singularity", "pose_status",
                 "condition")}


def _cond_limit(cond_limit) -> float:
    v = getscalar(cond_limit, "cond_limit")
    if not 1.0 <= v <= 1.0 / SINGULAR_REL:
        raise InputError(f"cond_limit must lie in [1, {1.0 / SINGULAR_REL:g}] (a condition "
                         f"number); got {cond_limit!r}", name="cond_limit", value=cond_limit)
    return v


def jacobian_arrays(model, p, cond_limit=NEAR_SINGULAR_COND):
    """Jacobians at trusted positions ``p`` (..., 2): ``(q, theta, status, jx, jq, j, g,
    det_x, det_q, singularity, condition)`` arrays (see :class:`Jacobians`)."""
    q, theta, status = ik_arrays(model, p)
    c, s = np.cos(theta), np.sin(theta)
    shape = p.shape[:-1]
    eye = np.broadcast_to(np.eye(2), shape + (2, 2))
    if isinstance(model, TwoPaP):
        jx = eye.copy()
        jq = model.la * np.stack([np.stack([c[..., 0], 0 * c[..., 0]], -1),
                                  np.stack([0 * c[..., 1], c[..., 1]], -1)], -2)
        det_x = np.ones(shape)
        det_q = c[..., 0] * c[..., 1]
        j = jq.copy()
        g = jq.copy()
        trans = np.abs(c)                                               # |cos theta_i|
    else:
        svec = c[..., :, None] * model.e + s[..., :, None] * model.lat   # (..., 2, 2): rows s_i
        jx = svec
        se = np.sum(svec * model.e, axis=-1)                            # s_i . e_i
        jq = se[..., :, None] * eye
        det_x = jx[..., 0, 0] * jx[..., 1, 1] - jx[..., 0, 1] * jx[..., 1, 0]
        det_q = se[..., 0] * se[..., 1]
        safe = np.where(np.abs(se) > SINGULAR_REL, se, 1.0)
        j = np.where((np.abs(se) > SINGULAR_REL)[..., None], jx / safe[..., None], 0.0)
        g = np.linalg.pinv(jx) @ jq
        trans = np.abs(se)                                              # |cos theta_i|
    # Scale-free measures: J_x has unit rows (2-PaP: I), and J_q / J_q(theta = 0) is
    # diag(cos theta_i) for both manipulators.
    smax, smin = singular_values_2x2(jx)
    rcond_x = np.where(smax > 0, smin / np.where(smax > 0, smax, 1.0), 0.0)
    tmin = np.min(trans, axis=-1)
    inverse = tmin <= SINGULAR_REL
    direct = rcond_x <= SINGULAR_REL
    cond = np.maximum(np.where(direct, np.inf, 1.0 / np.where(direct, 1.0, rcond_x)),
                      np.where(inverse, np.inf, 1.0 / np.where(inverse, 1.0, tmin)))
    sing = inverse.astype(int) * Singularity.INVERSE + direct.astype(int) * Singularity.DIRECT
    sing = np.where((sing == 0) & (cond > cond_limit), int(Singularity.NEAR_SINGULAR), sing)
    return q, theta, status, jx, jq, j, g, det_x, det_q, sing, cond


def jacobians(model, p, *, cond_limit=NEAR_SINGULAR_COND) -> Jacobians:
    """Jacobians of ``model`` at platform position(s) ``p`` ((2,) or (..., 2), length).

    The legs are placed by the IK working mode; ``pose_status`` reports whether p is
    in the workspace (the matrices are finite either way).

    Parameters
    ----------
    model : TwoPaP or TwoPPa
    p : (2,) or (..., 2) float, length
    cond_limit : float in [1, 1e12], optional
        Condition number above which a pose is :attr:`Singularity.NEAR_SINGULAR`
        (default :data:`NEAR_SINGULAR_COND`).
    """
    check_model(model)
    p = as_pairs(p, "p")
    lim = _cond_limit(cond_limit)
    _, _, status, jx, jq, j, g, det_x, det_q, sing, cond = jacobian_arrays(model, p, lim)
    return Jacobians(jx=jx, jq=jq, j=j, g=g, det_x=det_x, det_q=det_q,
                     singularity=np.asarray(sing, dtype=int), pose_status=status,
                     condition=cond)


def singular_values_2x2(m):
    """Singular values (max, min) of 2x2 matrices (..., 2, 2), closed form."""
    f = np.sum(m * m, axis=(-2, -1))
    det = m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
    disc = np.sqrt(np.maximum(f * f - 4 * det * det, 0.0))
    smax = np.sqrt(0.5 * (f + disc))
    smin = np.where(smax > 0, np.abs(det) / np.where(smax > 0, smax, 1.0), 0.0)
    return smax, smin


def ldi_of_jacobian(j, kind: str) -> np.ndarray:
    """LDI from the paper's Jacobian(s) ``j`` (..., 2, 2).

    ``kind="rotary"``: ``sqrt(min eig(J J^T))`` (2-PaP, ``p_dot = J q_dot``);
    ``kind="linear"``: ``sqrt(min eig((J J^T)^-1)) = 1 / sigma_max(J)`` (2-PPa,
    ``J p_dot = q_dot``).

    Parameters
    ----------
    j : (2, 2) or (..., 2, 2) array of finite real numbers
    kind : ``"rotary"`` or ``"linear"``

    Raises
    ------
    InputError
        For another ``kind``, or a ``j`` that is not real numbers of shape (..., 2, 2)
        (:class:`~cspace.errors.NonFiniteError` for NaN or inf).
    """
    if kind not in ("rotary", "linear"):
        raise InputError(f"kind must be 'rotary' or 'linear'; got {kind!r}", name="kind",
                         value=kind)
    try:
        raw = np.asarray(j)
        if isinstance(j, (str, bytes)) or raw.dtype.kind not in "iufO":
            raise TypeError(raw.dtype.kind)
        a = np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"j must be real numbers of shape (2, 2) or (..., 2, 2); got {j!r}",
                         name="j", value=j) from None
    if a.ndim < 2 or a.shape[-2:] != (2, 2):
        raise InputError(f"j must have shape (2, 2) or (..., 2, 2) (a 2 x 2 Jacobian per "
                         f"pose); got shape {a.shape}", name="j", value=j)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError("j must be finite (no NaN or inf)", name="j", value=j)
    return _ldi(a, kind)


def _ldi(j, kind: str) -> np.ndarray:
    """:func:`ldi_of_jacobian` of trusted float arrays."""
    smax, smin = singular_values_2x2(j)
    if kind == "rotary":
        return smin
    return np.where(smax > 0, 1.0 / np.where(smax > 0, smax, 1.0), 0.0)


def local_design_index(model, p) -> np.ndarray:
    """LDI (Eq. 27) at platform position(s) ``p``.

    Parameters
    ----------
    model : TwoPaP or TwoPPa
    p : (2,) or (..., 2) float, length
        Poses the manipulator reaches: their :func:`inverse_kinematics` status must be
        :attr:`PoseStatus.OK`.

    Returns
    -------
    (...) float
        Length units for 2-PaP (scales with ``la``), dimensionless for 2-PPa.  Zero
        where ``det J_q = 0``.

    Raises
    ------
    InputError
        If any pose is out of reach (``OUTSIDE_WORKSPACE``, or ``OTHER_ASSEMBLY`` for a
        2-PPa): an index there would describe no real configuration.  To screen a
        batch use ``inverse_kinematics(model, p).ok``; the formula's value at any pose
        is ``ldi_of_jacobian(jacobians(model, p).j, kind)``, whose ``pose_status`` says
        whether it is reachable.
    """
    check_model(model)
    p = as_pairs(p, "p")
    _, _, status, _, _, j, _, _, _, sing, _ = jacobian_arrays(model, p)
    bad = status != PoseStatus.OK
    if np.any(bad):
        k = int(np.argmax(bad.ravel()))
        first = p.reshape(-1, 2)[k]
        name = PoseStatus(int(status.ravel()[k])).name
        raise InputError(
            f"local_design_index needs poses the manipulator can reach (inverse_kinematics "
            f"status PoseStatus.OK); {int(np.count_nonzero(bad))} of {bad.size} poses are "
            f"not, the first p={_short(first)} with status {name}.  Screen poses with "
            f"inverse_kinematics(model, p).ok", name="p", value=p)
    return _ldi_of(model, j, sing)


def ldi_values(model, p):
    """LDI at trusted positions ``p`` (..., 2), reachable or not; see
    :func:`local_design_index`."""
    _, _, _, _, _, j, _, _, _, sing, _ = jacobian_arrays(model, p)
    return _ldi_of(model, j, sing)


def _ldi_of(model, j, sing):
    out = _ldi(j, "rotary" if isinstance(model, TwoPaP) else "linear")
    # zero where the inverse singularity is flagged (a rotary design's value
    # there is rounding of cos(asin(1)), not 0)
    return np.where((np.asarray(sing) & Singularity.INVERSE) != 0, 0.0, out)


@dataclass(frozen=True)
class StaticsResult:
    """Force transmission at a pose.

    Attributes
    ----------
    force : (2,) float
        Force on the platform at P (force units).
    tau : (2,) float
        Actuator efforts: torques (force x length) for 2-PaP, forces for 2-PPa.
    singularity : Singularity
        Non-NONE when the requested map does not exist (the unknown side is then the
        least-squares, pseudo-inverse answer) or, ``NEAR_SINGULAR``, when it is so
        ill-conditioned that the unknown side is dominated by the singularity.
    condition : float
        :attr:`Jacobians.condition` at the pose (1 ideal, inf singular).
    pose_status : PoseStatus
        Whether the manipulator reaches the pose (the numbers are the formula's for
        the IK working mode either way).

    ``success`` is True only for a regular (``Singularity.NONE``) pose that the
    manipulator reaches.
    """

    force: np.ndarray
    tau: np.ndarray
    singularity: Singularity
    condition: float = 1.0
    pose_status: PoseStatus = PoseStatus.OK

    @property
    def success(self) -> bool:
        return self.singularity == Singularity.NONE and self.pose_status == PoseStatus.OK

    def __repr__(self) -> str:
        out = (f"StaticsResult(force={_short(self.force)}, tau={_short(self.tau)}, "
               f"{self.singularity.name}, condition={self.condition:.4g}")
        if self.pose_status != PoseStatus.OK:
            out += f", {self.pose_status.name}"
        return out + ")"

    def to_dict(self) -> dict:
        return {"force": self.force.tolist(), "tau": self.tau.tolist(),
                "singularity": self.singularity.name, "condition": self.condition,
                "pose_status": self.pose_status.name}


def _single(model, p, name, vec):
    check_model(model)
    p = as_pairs(p, "p")
    if p.shape != (2,):
        raise InputError(f"p must have shape (2,) here; got {p.shape}", name="p", value=p)
    return p, as_pairs(vec, name, single=True)


def _statics(model, p, cond_limit):
    lim = _cond_limit(cond_limit)
    _, _, status, _, _, j, _, _, _, sing, cond = jacobian_arrays(model, p, lim)
    return j, Singularity(int(sing)), float(cond), PoseStatus(int(status))


def actuator_forces(model, p, force, *, cond_limit=NEAR_SINGULAR_COND) -> StaticsResult:
    """Actuator efforts that balance an external ``force`` (2,) applied at P.

    2-PaP: ``tau = J^T f`` (Eq. 5).  2-PPa: ``tau = J^-T f`` from ``f = J^T tau`` (Eq. 23).
    A pose whose condition number exceeds ``cond_limit`` is reported as
    :attr:`Singularity.NEAR_SINGULAR` (``success`` False), as are exact singularities.
    """
    p, f = _single(model, p, "force", force)
    j, sing, cond, status = _statics(model, p, cond_limit)
    if isinstance(model, TwoPaP):
        tau = j.T @ f
    else:
        tau = np.linalg.lstsq(j.T, f, rcond=None)[0]
    return StaticsResult(force=f.copy(), tau=tau, singularity=sing, condition=cond,
                         pose_status=status)


def platform_force(model, p, tau, *, cond_limit=NEAR_SINGULAR_COND) -> StaticsResult:
    """Platform force produced by actuator efforts ``tau`` (2,).

    2-PaP: ``f = J^-T tau``.  2-PPa: ``f = J^T tau`` (Eq. 23).  Singular and
    near-singular poses are flagged as in :func:`actuator_forces`.
    """
    p, t = _single(model, p, "tau", tau)
    j, sing, cond, status = _statics(model, p, cond_limit)
    if isinstance(model, TwoPaP):
        f = np.linalg.lstsq(j.T, t, rcond=None)[0]
    else:
        f = j.T @ t
    return StaticsResult(force=f, tau=t.copy(), singularity=sing, condition=cond,
                         pose_status=status)

