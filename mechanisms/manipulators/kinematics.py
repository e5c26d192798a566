"""Inverse and forward position kinematics of 2-PaP and 2-PPa.

All functions are vectorised: ``p`` and ``q`` may have shape ``(2,)`` or ``(..., 2)``.
A pose that cannot be reached is reported in the result's ``status`` array
(:class:`PoseStatus` values), never by NaN: the numbers returned for such a pose are
finite (clamped) and must not be used.

Branches
--------
2-PaP
    IK: ``theta_i = asin(p_i / la)`` (principal value, ``|theta_i| <= pi/2``, Eq. 2).
    FK: Eq. 1, unique.
2-PPa
    IK (working mode): ``d_i = r.e_i + ik_sign * sqrt(la^2 - (r.l_i)^2)`` with
    ``r = p - g_i`` (Eq. 11/12); the paper's ``ik_sign = -1`` keeps the link ahead of the
    slider (``s_i . e_i >= 0``).
    FK (assembly mode): P is the intersection of the circles of radius ``la`` about
    ``n_i = g_i + d_i e_i`` on side ``fk_branch`` of ``n_1 -> n_2`` (+1 = left, the
    convention of :func:`cspace.geom2d.circle_circle`).  For the perpendicular design
    +1 is the paper's Eq. 15.  A forward solution whose links are not in the IK working
    mode is flagged :attr:`PoseStatus.BRANCH_MISMATCH`.
"""

from __future__ import annotations

import enum
import warnings
from dataclasses import dataclass

import numpy as np

from cspace.argcheck import getunit
from cspace.errors import InputError, NonFiniteError
from cspace.geom2d import IntersectionKind, circle_circle, cross2

from .models import TwoPaP, TwoPPa

__all__ = ["PoseStatus", "IKResult", "FKResult", "inverse_kinematics", "forward_kinematics",
           "leg_geometry", "closed_form_forward", "eq15_forward"]

#: Default relative tolerance (times ``la``) for workspace-boundary tests: a few ulps
#: of the largest coordinate, so that poses computed exactly on the boundary count as in.
BOUNDARY_REL = 1e-12


class PoseStatus(enum.IntEnum):
    """Why a pose is (not) usable."""

    OK = 0                 #: reachable, in range
    OUTSIDE_WORKSPACE = 1  #: IK: |r.l| > la or actuator outside its range
    NOT_ASSEMBLABLE = 2    #: FK: the two leg circles do not meet
    SINGULAR = 3           #: FK: the circles are tangent (direct singularity, det J_x = 0)
    BRANCH_MISMATCH = 4    #: FK: solution exists but not in the IK working mode
    OTHER_ASSEMBLY = 5     #: IK: legs reach P, but only in the other FK assembly mode


def _short(a) -> str:
    a = np.asarray(a)
    return np.array2string(a, precision=6, threshold=6) if a.ndim else f"{a:.6g}"


class _PoseMask:
    """``ok`` (per-pose mask) and ``success`` (all poses OK) from ``status``."""

    __slots__ = ()

    @property
    def ok(self) -> np.ndarray:
        return self.status == PoseStatus.OK

    @property
    def success(self) -> bool:
        return bool(np.all(self.ok))


@dataclass(frozen=True)
class IKResult(_PoseMask):
    """Inverse kinematics.

    Attributes
    ----------
    q : (..., 2) float
        Joint variables: angles (rad) for 2-PaP, actuator displacements (length) for 2-PPa.
    theta : (..., 2) float, rad
        Parallelogram link angles theta_i.
    status : (...) int, :class:`PoseStatus` values
    """

    q: np.ndarray
    theta: np.ndarray
    status: np.ndarray

    def __repr__(self) -> str:
        return f"IKResult(q={_short(self.q)}, success={self.success})"

    def to_dict(self) -> dict:
        return {"q": self.q.tolist(), "theta": self.theta.tolist(), "status": self.status.tolist()}


@dataclass(frozen=True)
class FKResult(_PoseMask):
    """Forward kinematics.

    Attributes
    ----------
    p : (..., 2) float, length
        Platform point.
    theta : (..., 2) float, rad
        Parallelogram link angles at the solution.
    status : (...) int, :class:`PoseStatus` values
    """

    p: np.ndarray
    theta: np.ndarray
    status: np.ndarray

    def __repr__(self) -> str:
        return f"FKResult(p={_short(self.p)}, success={self.success})"

    def to_dict(self) -> dict:
        return {"p": self.p.tolist(), "theta": self.theta.tolist(), "status": self.status.tolist()}


def _holds_bool(x) -> bool:
    """Whether nested lists/tuples (or an object array) ``x`` hold a bool anywhere."""
    stack = [x]
    while stack:
        v = stack.pop()
        if isinstance(v, (bool, np.bool_)):
            return True
        if isinstance(v, (list, tuple)):
            stack.extend(v)
        elif isinstance(v, np.ndarray):
            if v.dtype.kind == "b":
                return True
            if v.dtype.kind == "O":
                stack.extend(v.ravel().tolist())
    return False


def as_pairs(x, name: str, single: bool = False) -> np.ndarray:
    """``x`` as a finite float array of shape (2,) or (..., 2) (only (2,) if ``single``);
    raises :class:`~cspace.errors.InputError` (named ``name``) otherwise.

    Real numbers only: booleans, complex numbers and strings are refused rather than
    read as 0/1, truncated or parsed."""
    if isinstance(x, (str, bytes)):
        raise InputError(f"{name} must be real numbers of shape (2,) or (..., 2); got {x!r}",
                         name=name, value=x)
    if _holds_bool(x):
        raise InputError(f"{name} must be real numbers of shape (2,) or (..., 2), not bool; "
                         f"got {x!r}", name=name, value=x)
    try:
        raw = np.asarray(x)
        kind = raw.dtype.kind
        if kind not in "iufO":
            raise TypeError(kind)
        a = np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be real numbers of shape (2,) or (..., 2); got {x!r}",
                         name=name, value=x) from None
    if single and a.shape != (2,):
        raise InputError(f"{name} must have shape (2,) (one vector at one pose); got shape "
                         f"{a.shape}", name=name, value=x)
    if a.ndim == 0 or a.shape[-1] != 2:
        raise InputError(f"{name} must have shape (2,) or (..., 2); got shape {a.shape}",
                         name=name, value=x)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} must be finite", name=name, value=x)
    return a


def check_model(model):
    """Raise :class:`~cspace.errors.InputError` unless ``model`` is a TwoPaP or TwoPPa."""
    if not isinstance(model, (TwoPaP, TwoPPa)):
        raise InputError(f"model must be a TwoPaP or TwoPPa; got {type(model).__name__}",
                         name="model", value=model)


def leg_geometry(model: TwoPPa, p: np.ndarray):
    """Leg coordinates of trusted positions ``p`` (..., 2) of a 2-PPa: ``(u, v)``.

    ``u[..., i] = (p - g_i) . e_i`` and ``v[..., i] = (p - g_i) . l_i``.
    """
    r = p[..., None, :] - model.g            # (..., 2 legs, 2)
    u = np.sum(r * model.e, axis=-1)
    v = np.sum(r * model.lat, axis=-1)
    return u, v


def assembly_side(model: TwoPPa, p, d):
    """Assembly mode of a 2-PPa at positions ``p`` (..., 2) with slider
    displacements ``d`` (..., 2): the side of the line through the two sliders
    ``n_1 -> n_2`` that P lies on, as a signed length squared (> 0 is geom2d
    branch +1; 0 on the direct singularity, where the links are parallel)."""
    n = model.g + d[..., :, None] * model.e
    return cross2(n[..., 1, :] - n[..., 0, :], p - n[..., 0, :])


def ik_arrays(model, p):
    """Inverse kinematics of trusted positions ``p`` (..., 2): ``(q, theta, status)``
    arrays, as in :class:`IKResult`."""
    la = model.la
    tol = BOUNDARY_REL * la
    if isinstance(model, TwoPaP):
        lim = model.la * np.sin(model.theta_limit)
        ratio = np.clip(p / la, -1.0, 1.0)
        theta = np.arcsin(ratio)
        bad = np.any(np.abs(p) > lim + tol, axis=-1)
        status = np.where(bad, PoseStatus.OUTSIDE_WORKSPACE, PoseStatus.OK).astype(int)
        return theta.copy(), theta, status
    u, v = leg_geometry(model, p)
    root2 = la * la - v * v
    root = np.sqrt(np.where(root2 > 0, root2, 0.0))
    d = u + model.ik_sign * root
    theta = np.arctan2(v, u - d)
    bad = np.any((np.abs(v) > la + tol) | (d < -tol) | (d > model.stroke + tol), axis=-1)
    status = np.where(bad, PoseStatus.OUTSIDE_WORKSPACE, PoseStatus.OK).astype(int)
    other = (model.fk_branch * assembly_side(model, p, d) < -tol * la) & ~bad
    status = np.where(other, PoseStatus.OTHER_ASSEMBLY, status)
    return d, theta, status


def inverse_kinematics(model, p) -> IKResult:
    """Joint variables for platform position(s) ``p``.

    Parameters
    ----------
    model : TwoPaP or TwoPPa
    p : (2,) or (..., 2) float, length

    Returns
    -------
    IKResult
        Out-of-range poses get :attr:`PoseStatus.OUTSIDE_WORKSPACE` (2-PaP: beyond
        ``la sin(theta_limit)``; 2-PPa: beyond the link reach or the stroke ``[0, stroke]``).
        2-PPa poses that the legs reach only in the other assembly mode (the unusable
        lower-left part of the total workspace, Fig. 4) get
        :attr:`PoseStatus.OTHER_ASSEMBLY`; ``q`` is still the working-mode solution.

    Examples
    --------
    >>> from mechanisms.manipulators import two_pap
    >>> inverse_kinematics(two_pap(1.0, 60, unit="deg"), [0.5, 0.0]).q  # doctest: +ELLIPSIS
    array([0.5235..., 0.        ])
    """
    check_model(model)
    p = as_pairs(p, "p")
    q, theta, status = ik_arrays(model, p)
    return IKResult(q=q, theta=theta, status=status)


def _fk(model, q):
    la = model.la
    if isinstance(model, TwoPaP):
        p = la * np.sin(q)
        bad = np.any(np.abs(q) > model.theta_limit + BOUNDARY_REL, axis=-1)
        status = np.where(bad, PoseStatus.OUTSIDE_WORKSPACE, PoseStatus.OK).astype(int)
        return p, q.copy(), status
    n = model.g + q[..., :, None] * model.e    # (..., 2, 2) circle centres
    p, kind = circle_circle(n[..., 0, :], la, n[..., 1, :], la, model.fk_branch)
    u, v = leg_geometry(model, p)
    theta = np.arctan2(v, u - q)
    # Working-mode test: the IK of the found point must give back the same d.
    d_back, _, _ = ik_arrays(model, p)
    mismatch = np.any(np.abs(d_back - q) > 1e-8 * la, axis=-1)
    status = np.full(kind.shape, PoseStatus.OK, dtype=int)
    status = np.where(mismatch, PoseStatus.BRANCH_MISMATCH, status)
    oor = np.any((q < -BOUNDARY_REL * la) | (q > model.stroke + BOUNDARY_REL * la), axis=-1)
    status = np.where(oor, PoseStatus.OUTSIDE_WORKSPACE, status)
    status = np.where(kind == IntersectionKind.TANGENT, PoseStatus.SINGULAR, status)
    status = np.where((kind == IntersectionKind.NONE) | (kind == IntersectionKind.COINCIDENT),
                      PoseStatus.NOT_ASSEMBLABLE, status)
    return p, theta, status


def forward_kinematics(model, q, *, unit: str = "rad") -> FKResult:
    """Platform position(s) for joint variables ``q``.

    Parameters
    ----------
    model : TwoPaP or TwoPPa
    q : (2,) or (..., 2) float
        rad (or deg with ``unit="deg"``) for 2-PaP, length for 2-PPa.
    unit : ``"rad"`` or ``"deg"``
        Angle unit of ``q``; only meaningful for 2-PaP.

    Returns
    -------
    FKResult
        ``p`` is finite everywhere; check ``status`` (:class:`PoseStatus`).
    """
    check_model(model)
    q = as_pairs(q, "q")
    if unit != "rad":
        if isinstance(model, TwoPPa):
            raise InputError(f"a 2-PPa's joint variables are lengths; unit must be 'rad' "
                             f"(the default), got {unit!r}", name="unit", value=unit)
        q = q * getunit(unit)
    p, theta, status = _fk(model, q)
    return FKResult(p=p, theta=theta, status=status)


def closed_form_forward(model: TwoPPa, d) -> np.ndarray:
    """Closed-form forward kinematics of the perpendicular 2-PPa, Eq. 15 of [Kim 2007].

    Used to cross-check :func:`forward_kinematics`; assumes the circles meet.
    """
    if not isinstance(model, TwoPPa) or model.arrangement.name != "PERPENDICULAR":
        raise InputError("closed_form_forward needs a perpendicular TwoPPa model",
                         name="model", value=model)
    d = as_pairs(d, "d")
    c1 = d[..., 0] + model.b - model.a
    c2 = d[..., 1] + model.b - model.a
    k = np.sqrt(np.maximum(4 * model.la ** 2 / (c1 * c1 + c2 * c2) - 1.0, 0.0))
    return np.stack([0.5 * (c1 - c2 * k), 0.5 * (c2 - c1 * k)], -1)


def eq15_forward(model: TwoPPa, d) -> np.ndarray:
    """Deprecated name of :func:`closed_form_forward`."""
    warnings.warn("eq15_forward is deprecated; use closed_form_forward",
                  DeprecationWarning, stacklevel=2)
    return closed_form_forward(model, d)
