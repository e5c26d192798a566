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

from cspace.errors import InputError

from .kinematics import as_pairs, check_model, ik_arrays
from .models import TwoPaP

__all__ = ["Singularity", "Jacobians", "jacobians", "local_design_index", "ldi_of_jacobian",
           "StaticsResult", "actuator_forces", "platform_force", "SINGULAR_REL"]

#: Relative determinant below which a Jacobian counts as singular.  Both determinants
#: are dimensionless (J_x rows and J_q entries are unit-vector products; 2-PaP J_q is
#: divided by la first), so 1e-12 is a few hundred ulps of the O(1) entries.
SINGULAR_REL = 1e-12


class Singularity(enum.IntEnum):
    """Which Jacobian is singular at a pose."""

    NONE = 0      #: regular pose
    INVERSE = 1   #: det J_q = 0 (serial / inverse singularity)
    DIRECT = 2    #: det J_x = 0 (parallel / direct singularity)
    BOTH = 3      #: both


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
    pose_status : (...) int, :class:`PoseStatus` of the IK used to place the legs
    """

    jx: np.ndarray
    jq: np.ndarray
    j: np.ndarray
    g: np.ndarray
    det_x: np.ndarray
    det_q: np.ndarray
    singularity: np.ndarray
    pose_status: np.ndarray

    def __repr__(self) -> str:
        return (f"Jacobians(det_x={_short(self.det_x)}, det_q={_short(self.det_q)}, "
                f"singular={bool(np.any(self.singularity != 0))})")

    def to_dict(self) -> dict:
        return {k: np.asarray(getattr(self, k)).tolist() for k in
                ("jx", "jq", "j", "g", "det_x", "det_q", "singularity", "pose_status")}


def jacobian_arrays(model, p):
    """Jacobians at trusted positions ``p`` (..., 2): ``(q, theta, status, jx, jq, j, g,
    det_x, det_q, singularity)`` arrays (see :class:`Jacobians`)."""
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
    sing = (np.abs(det_q) <= SINGULAR_REL).astype(int) * Singularity.INVERSE \
        + (np.abs(det_x) <= SINGULAR_REL).astype(int) * Singularity.DIRECT
    return q, theta, status, jx, jq, j, g, det_x, det_q, sing


def jacobians(model, p) -> Jacobians:
    """Jacobians of ``model`` at platform position(s) ``p`` ((2,) or (..., 2), length).

    The legs are placed by the IK working mode; ``pose_status`` reports whether p is
    in the workspace (the matrices are finite either way).
    """
    check_model(model)
    p = as_pairs(p, "p")
    _, _, status, jx, jq, j, g, det_x, det_q, sing = jacobian_arrays(model, p)
    return Jacobians(jx=jx, jq=jq, j=j, g=g, det_x=det_x, det_q=det_q,
                     singularity=np.asarray(sing, dtype=int), pose_status=status)


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
    """
    j = np.asarray(j, dtype=float)
    smax, smin = singular_values_2x2(j)
    if kind == "rotary":
        return smin
    if kind == "linear":
        return np.where(smax > 0, 1.0 / np.where(smax > 0, smax, 1.0), 0.0)
    raise InputError(f"kind must be 'rotary' or 'linear'; got {kind!r}", name="kind", value=kind)


def local_design_index(model, p) -> np.ndarray:
    """LDI (Eq. 27) at platform position(s) ``p``.

    Returns (...) float: length units for 2-PaP (scales with ``la``), dimensionless for
    2-PPa.  Zero where ``det J_q = 0``.
    """
    check_model(model)
    p = as_pairs(p, "p")
    return ldi_values(model, p)


def ldi_values(model, p):
    """LDI at trusted positions ``p`` (..., 2); see :func:`local_design_index`."""
    _, _, _, _, jq, j, _, _, det_q, _ = jacobian_arrays(model, p)
    out = ldi_of_jacobian(j, "rotary" if isinstance(model, TwoPaP) else "linear")
    # zero where the inverse singularity is flagged (a rotary design's value
    # there is rounding of cos(asin(1)), not 0)
    return np.where(np.abs(det_q) <= SINGULAR_REL, 0.0, out)


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
        Non-NONE when the requested map does not exist; the unknown side is then
        the least-squares (pseudo-inverse) answer.
    """

    force: np.ndarray
    tau: np.ndarray
    singularity: Singularity

    @property
    def success(self) -> bool:
        return self.singularity == Singularity.NONE

    def __repr__(self) -> str:
        return f"StaticsResult(force={_short(self.force)}, tau={_short(self.tau)}, {self.singularity.name})"

    def to_dict(self) -> dict:
        return {"force": self.force.tolist(), "tau": self.tau.tolist(),
                "singularity": self.singularity.name}


def _single(model, p):
    check_model(model)
    p = as_pairs(p, "p")
    if p.shape != (2,):
        raise InputError(f"p must have shape (2,) here; got {p.shape}", name="p", value=p)
    return p


def actuator_forces(model, p, force) -> StaticsResult:
    """Actuator efforts that balance an external ``force`` (2,) applied at P.

    2-PaP: ``tau = J^T f`` (Eq. 5).  2-PPa: ``tau = J^-T f`` from ``f = J^T tau`` (Eq. 23).
    """
    p = _single(model, p)
    f = as_pairs(force, "force")
    _, _, _, jx, jq, j, g, det_x, det_q, sing = jacobian_arrays(model, p)
    sing = Singularity(int(sing))
    if isinstance(model, TwoPaP):
        tau = j.T @ f
        ok = sing == Singularity.NONE
    else:
        tau = np.linalg.lstsq(j.T, f, rcond=None)[0]
        ok = sing == Singularity.NONE
    return StaticsResult(force=f.copy(), tau=tau, singularity=Singularity.NONE if ok else sing)


def platform_force(model, p, tau) -> StaticsResult:
    """Platform force produced by actuator efforts ``tau`` (2,).

    2-PaP: ``f = J^-T tau``.  2-PPa: ``f = J^T tau`` (Eq. 23).
    """
    p = _single(model, p)
    t = as_pairs(tau, "tau")
    _, _, _, jx, jq, j, g, det_x, det_q, sing = jacobian_arrays(model, p)
    sing = Singularity(int(sing))
    if isinstance(model, TwoPaP):
        f = np.linalg.lstsq(j.T, t, rcond=None)[0]
    else:
        f = j.T @ t
    return StaticsResult(force=f, tau=t.copy(), singularity=sing)

