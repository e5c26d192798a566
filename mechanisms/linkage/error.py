"""Mechanical error of a four-bar from link tolerances and joint clearances.

Two ways to compute the error at one crank angle ``theta2``:

* **exact** -- re-solve the perturbed linkage (:func:`exact_error`);
* **first order** -- the velocity solution of the *sensitivity linkage*
  (:func:`sensitivity`, :func:`linear_error`): the linkage with an added slider
  for a length tolerance, or an added pin and slider for a clearance, the
  original inputs held (rate 0) and the added slider driven at unit rate.  The
  velocity analysis is solved for the general vector loop, not only through the
  closed forms of [Shin & Choi 1995] (those are in :func:`clearance_b_closed_form`
  and agree with it).

Sources of error
----------------
Length sources ``"l1"`` (ground), ``"l2"`` (crank), ``"l3"`` (coupler),
``"l4"`` (rocker), ``"lp"`` (length units) and the angle-valued ``"alpha"``,
``"theta1"`` (:data:`ANGLE_SOURCES`; rad inside).  Angle-valued deviations
``dl`` are in the call's ``unit``, like ``theta2`` and ``delta``; angle-valued
tolerances of a :class:`ToleranceSpec` are in the spec's own ``unit``, fixed
when it is built.
Clearance joints ``"A"`` (ground-crank), ``"B"`` (crank-coupler),
``"C"`` (coupler-rocker) and ``"D"`` (rocker-ground).

Clearance convention
--------------------
Going round the loop ground -> crank -> coupler -> rocker -> ground, the
*clearance vector* ``e_J`` of joint J is the position of the outboard element
minus that of the inboard one (for A: the crank's pivot relative to the ground's
hole; for B: the coupler's pin relative to the crank's bore; for C: the rocker's
element relative to the coupler's; for D: the ground's element relative to the
rocker's).  The pin sits on the clearance circle, ``e_J = r (cos beta, sin beta)``,
with ``beta = delta + theta_ref + pi`` where the reference direction is that of
the ground (A), crank (B), coupler (C) or rocker (D) in the nominal pose.  For
joint B this is Eq. 21 of [Shin & Choi 1995] (``beta = delta1 + theta2 - pi`` is the
same direction).

Because every clearance vector enters the closure ``A -> B -> C -> D`` additively,
``theta3`` and ``theta4`` depend only on their sum, and the first-order output
error of any joint is ``r cos(beta - theta3) / (l4 sin(theta3 - theta4))``: a
simple harmonic of ``delta`` whose extremes lie where the pin offset is collinear
with the coupler (Dubowsky).
"""

from __future__ import annotations

import enum
import math
import warnings
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from cspace import geom2d
from cspace.argcheck import getangle, getangles, getint, getscalar, getseed, getunit
from cspace.errors import InputError, NonFiniteError, NumericalError

from .fourbar import (DEFAULT_TOL, FourBar, LinkageTolerances, PoseStatus, _unbounded_limit,
                      _within_a_turn, check_tolerances, loop_positions)

__all__ = [
    "LENGTH_SOURCES", "ANGLE_SOURCES", "JOINTS", "QUANTITIES", "ErrorStatus", "EllipseKind",
    "Sensitivity", "ErrorCurve", "ClosedForm", "Harmonic", "ErrorEllipse",
    "ToleranceSpec", "WorstCase", "RSSResult", "MonteCarloResult",
    "sensitivity", "clearance_gradient", "exact_error", "linear_error",
    "clearance_b_closed_form", "paper_closed_form", "harmonic_fit", "harmonic_max",
    "coupler_ellipse", "dubowsky_deltas", "worst_case", "rss", "monte_carlo",
]

LENGTH_SOURCES = ("l1", "l2", "l3", "l4", "lp", "alpha", "theta1")
ANGLE_SOURCES = ("alpha", "theta1")   #: the angle-valued ones among LENGTH_SOURCES
JOINTS = ("A", "B", "C", "D")
QUANTITIES = ("theta4", "theta3", "px", "py")


class ErrorStatus(enum.IntEnum):
    """Status of an error analysis (per evaluation or per result)."""

    OK = 0
    NEAR_TOGGLE = 1     #: nominal or perturbed pose within the toggle tolerance
    UNASSEMBLABLE = 2   #: nominal or perturbed linkage does not close
    NOT_CONVERGED = 3   #: the bounded optimisation did not report success


class EllipseKind(enum.Enum):
    """Shape of the first-order coupler-point error locus."""

    ELLIPSE = "ellipse"
    SEGMENT = "segment"   #: minor semi-axis ~ 0 (e.g. clearance at C or D)
    POINT = "point"       #: both semi-axes ~ 0


# ---------------------------------------------------------------------------
# argument checks (public boundary)
# ---------------------------------------------------------------------------

def _check_fb(fb):
    if not isinstance(fb, FourBar):
        raise InputError(f"expected a FourBar, got {type(fb).__name__}", name="fb", value=fb)


def _check_joint(joint) -> str:
    if not isinstance(joint, str) or joint.upper() not in JOINTS:
        raise InputError(f"joint must be one of {JOINTS}, got {joint!r}", name="joint",
                         value=joint)
    return joint.upper()


def _check_source(source) -> str:
    if isinstance(source, str):
        if source in LENGTH_SOURCES:
            return source
        if source.upper() in JOINTS:
            return source.upper()
    raise InputError(f"source must be a length source {LENGTH_SOURCES} or a joint "
                     f"{JOINTS}, got {source!r}", name="source", value=source)


def _check_quantity(q) -> str:
    if q not in QUANTITIES:
        raise InputError(f"quantity must be one of {QUANTITIES}, got {q!r}", name="quantity",
                         value=q)
    return q


def _link_lengths(fb) -> dict:
    """The lengths a deviation or tolerance may not exceed (``lp`` when the
    coupler point is off the pin)."""
    out = dict(zip(("l1", "l2", "l3", "l4"), fb.lengths))
    if fb.lp > 0:
        out["lp"] = fb.lp
    return out


def _check_physical(fb, lengths: Mapping, clearances: Mapping, what: str) -> None:
    """Refuse length deviations (``what="dl"``) or symmetric tolerances
    (``what="lengths"``) that reach a length <= 0, and clearances as large as
    the shortest link (no real part has them: a value typed in other units,
    or on the wrong link)."""
    ls = _link_lengths(fb)
    noun = "deviation" if what == "dl" else "tolerance"
    for k, t in lengths.items():
        if k not in ls:
            continue
        low = ls[k] + t if what == "dl" else ls[k] - abs(t)
        if low <= 0:
            raise InputError(
                f"{what}[{k!r}] = {t:g} gives {k} = {low:g} <= 0 (nominal {ls[k]:g}, length "
                f"units); a length {noun} must leave the length > 0", name=what, value=t)
    shortest = min(fb.lengths)
    for j, r in clearances.items():
        if r >= shortest:
            raise InputError(
                f"clearance at joint {j} = {r:g} is at least the shortest link ({shortest:g}, "
                "length units): a radial clearance is a small gap in a pin joint; given in "
                "other units?", name="clearance", value=r)


def _check_dl(dl, unit: str = "rad") -> dict:
    """Deviations by source; the angle-valued ones (``alpha``, ``theta1``) are
    read in ``unit``, returned in rad and refused beyond a turn."""
    if dl is None:
        return {}
    if not isinstance(dl, Mapping):
        raise InputError(f"dl must be a mapping source -> deviation, got {type(dl).__name__}",
                         name="dl", value=dl)
    k_unit = getunit(unit)
    out = {}
    for k, v in dl.items():
        if k not in LENGTH_SOURCES:
            raise InputError(f"dl keys must be among {LENGTH_SOURCES}, got {k!r}", name="dl",
                             value=k)
        out[k] = getscalar(v, f"dl[{k!r}]")
        if k in ANGLE_SOURCES:
            out[k] = _within_a_turn(out[k] * k_unit, f"dl[{k!r}]", unit)
    return out


def _angles_1d(x, unit: str, name: str) -> np.ndarray:
    """One angle or a non-empty 1-D array of them, in rad (a 2-D array is refused,
    not flattened)."""
    a = getangles(x, unit, name)
    if a.ndim > 1:
        raise InputError(f"{name} must be one angle or a 1-D array of them, got an array of "
                         f"shape {a.shape}", name=name, value=x)
    a = np.atleast_1d(a)
    if a.size == 0:
        raise InputError(f"{name} must hold at least one angle, got an empty array",
                         name=name, value=x)
    return a


# ---------------------------------------------------------------------------
# exact re-solution (private, vectorised, trusts input)
# ---------------------------------------------------------------------------

def _ref_angles(fb: FourBar, t2: float, t3: float, t4: float) -> dict:
    return {"A": fb.theta1, "B": t2, "C": t3, "D": t4}


def _nominal(fb: FourBar, t2: float, tol: LinkageTolerances):
    return _nominal_pose(fb, t2, tol)[:4]


def _nominal_pose(fb: FourBar, t2: float, tol: LinkageTolerances):
    """theta3, theta4, P, status and whether the pose is exactly at a toggle
    (there the first-order rates are unbounded)."""
    B, C, t3, t4, st, s34 = loop_positions(fb, np.array([t2]), tol)
    P = B + fb.lp * np.stack([np.cos(t3 + fb.alpha), np.sin(t3 + fb.alpha)], -1)
    toggle = bool(st[0] != PoseStatus.UNASSEMBLABLE and s34[0] == 0.0)
    return float(t3[0]), float(t4[0]), P[0], int(st[0]), toggle


def _solve_perturbed(fb: FourBar, t2: float, dl: Mapping[str, np.ndarray],
                     e: Mapping[str, np.ndarray], n: int, tol: LinkageTolerances, *,
                     gap: bool = False, on_line: bool = False):
    """theta3, theta4, P, status of n perturbed linkages.

    ``dl[src]`` are (n,) deviations, ``e[joint]`` (n, 2) clearance vectors.
    Where the dyad does not close, the angles and P are those of the near miss
    (C on the line of centres), which run on continuously from the toggle.
    With ``on_line`` C is put on the line of centres for every variant (the
    toggle pose where the dyad just closes: a smooth function of the
    deviations).  With ``gap`` a fifth value, (n, 2) ``(|BD| - (l3 + l4),
    |l3 - l4| - |BD|)`` (length units), says how far each dyad is from its
    outer and inner toggle: it closes where both are <= 0.
    """
    z = np.zeros(n)
    z2 = np.zeros((n, 2))
    g = lambda k: np.broadcast_to(np.asarray(dl.get(k, z), float), (n,))  # noqa: E731
    eA, eB, eC, eD = (np.broadcast_to(np.asarray(e.get(j, z2), float), (n, 2))
                      for j in JOINTS)
    l1 = fb.ground + g("l1")
    l2 = fb.crank + g("l2")
    l3 = fb.coupler + g("l3")
    l4 = fb.rocker + g("l4")
    lp = fb.lp + g("lp")
    al = fb.alpha + g("alpha")
    t1 = fb.theta1 + g("theta1")
    A = np.asarray(fb.A)
    D = A + l1[:, None] * np.stack([np.cos(t1), np.sin(t1)], -1)
    u2 = np.array([math.cos(t2), math.sin(t2)])
    Bc = A + eA + l2[:, None] * u2 + eB           # the coupler's B
    Dc = D - eD - eC                              # centre of the circle of coupler's C
    C, kind = geom2d.circle_circle(Bc, l3, Dc, l4, 0 if on_line else int(fb.assembly),
                                   tol=tol.tangent_rel)
    t3 = np.arctan2(C[:, 1] - Bc[:, 1], C[:, 0] - Bc[:, 0])
    t4 = np.arctan2(C[:, 1] - Dc[:, 1], C[:, 0] - Dc[:, 0])
    P = Bc + lp[:, None] * np.stack([np.cos(t3 + al), np.sin(t3 + al)], -1)
    s34 = np.sin(t3 - t4)
    st = np.where(np.abs(s34) < tol.toggle_sin, ErrorStatus.NEAR_TOGGLE, ErrorStatus.OK)
    bad = (kind == geom2d.IntersectionKind.NONE) | (kind == geom2d.IntersectionKind.COINCIDENT)
    st = np.where(bad, ErrorStatus.UNASSEMBLABLE, st).astype(int)
    # the perturbed pose must stay on the nominal branch *by continuation*: a
    # perturbation large enough to carry C across the toggle is unassemblable on it
    if gap:
        d = np.hypot(*(Dc - Bc).T)
        return t3, t4, P, st, np.stack([d - (l3 + l4), np.abs(l3 - l4) - d], -1)
    return t3, t4, P, st


def _pin_vectors(radius, beta):
    beta = np.asarray(beta, float)
    return np.stack([radius * np.cos(beta), radius * np.sin(beta)], -1)


# ---------------------------------------------------------------------------
# first order: the general velocity solution of the sensitivity linkage
# ---------------------------------------------------------------------------

def _loop_rates(members, unknown, det_sign=None):
    """Velocity analysis of one planar vector loop ``sum r_k u(phi_k) = 0``.

    ``members`` is a dict name -> (r, phi, rdot, phidot) with numbers or (n,)
    arrays; ``unknown`` names the two members whose ``phidot`` is solved for.
    Returns ``{name: phidot}`` for the unknowns and the determinant.

    ``det_sign`` (+-1) is for a singular loop (a toggle, determinant 0): the
    rates are then ``c / det`` with ``det -> 0`` of that sign, and the
    coefficients ``c * det_sign`` are returned instead (their sign is that of
    the unbounded rate).
    """
    rhs = 0.0
    cols = []
    for name, (r, phi, rdot, phidot) in members.items():
        u = np.stack([np.cos(phi), np.sin(phi)], -1)
        rhs = rhs - np.asarray(rdot)[..., None] * u
        if name in unknown:
            cols.append(np.asarray(r)[..., None] * geom2d.perp(u))
            continue
        rhs = rhs - (np.asarray(r) * np.asarray(phidot))[..., None] * geom2d.perp(u)
    M = np.stack(cols, -1)                      # (..., 2, 2)
    det = M[..., 0, 0] * M[..., 1, 1] - M[..., 0, 1] * M[..., 1, 0]
    if det_sign is not None:
        safe = np.full(np.shape(det), float(det_sign))
    else:
        safe = np.where(det != 0.0, det, 1.0)
    x0 = (rhs[..., 0] * M[..., 1, 1] - M[..., 0, 1] * rhs[..., 1]) / safe
    x1 = (M[..., 0, 0] * rhs[..., 1] - M[..., 1, 0] * rhs[..., 0]) / safe
    return {unknown[0]: x0, unknown[1]: x1}, det


def _sensitivity_core(fb: FourBar, t2: float, t3: float, t4: float, source, beta, *,
                      toggle: bool = False, coefficients: bool = False):
    """(dtheta3, dtheta4, dP) per unit of ``source`` (unit slider rate), and the
    determinant.

    ``source`` is a source name, or a mapping source -> rate driving several
    sliders at once (the superposed first-order error).  With ``toggle`` (the
    nominal pose exactly at a toggle, determinant 0) the rates are unbounded:
    they read ``+-inf`` (the sign of the limit on the assembly branch), or the
    finite value when their unbounded part vanishes; with ``coefficients`` too,
    ``(c3, c4, cP, fP)`` are returned instead: as ``s = sin(theta3 - theta4) ->
    0`` the rates grow like ``k c / |s|`` and ``fP + k cP / |s|`` (one positive
    ``k``).
    """
    beta = np.asarray(beta, float)
    n = beta.shape
    zero = np.zeros(n)
    one = np.ones(n)
    t1 = fb.theta1
    rate = {k: 0.0 for k in LENGTH_SOURCES}
    slider = {j: 0.0 for j in JOINTS}
    for k, v in ({source: 1.0} if isinstance(source, str) else source).items():
        if k in JOINTS:
            slider[k] = float(v)
        else:
            rate[k] = float(v)
    bc = lambda x: np.broadcast_to(np.asarray(x, float), n)  # noqa: E731
    # the sensitivity linkage: original loop + a slider of length s = 0 at each
    # clearance joint (direction beta), driven at unit rate for the chosen source
    members = {
        "sA": (zero, bc(beta), bc(slider["A"]), zero),
        "crank": (bc(fb.crank), bc(t2), bc(rate["l2"]), zero),
        "sB": (zero, bc(beta), bc(slider["B"]), zero),
        "coupler": (bc(fb.coupler), bc(t3), bc(rate["l3"]), None),
        "sC": (zero, bc(beta), bc(slider["C"]), zero),
        "rocker": (bc(fb.rocker), bc(t4 + math.pi), bc(rate["l4"]), None),
        "sD": (zero, bc(beta), bc(slider["D"]), zero),
        "ground": (bc(fb.ground), bc(t1 + math.pi), bc(rate["l1"]), bc(rate["theta1"])),
    }
    # the determinant is l3 l4 sin(theta3 - theta4), whose sign is fixed on the
    # branch (negative with C left of B -> D)
    sig = -float(int(fb.assembly))
    w, det = _loop_rates(members, ("coupler", "rocker"), sig if toggle else None)
    w3, w4 = w["coupler"], w["rocker"]
    u2 = np.array([math.cos(t2), math.sin(t2)])
    up = np.array([math.cos(t3 + fb.alpha), math.sin(t3 + fb.alpha)])
    ub = np.stack([np.cos(beta), np.sin(beta)], -1)
    if toggle:
        fP = ((slider["A"] + slider["B"]) * ub + rate["l2"] * u2
              + fb.lp * rate["alpha"] * one[..., None] * geom2d.perp(up)
              + rate["lp"] * up * one[..., None])
        cP = fb.lp * w3[..., None] * geom2d.perp(up)
        if coefficients:
            return w3, w4, cP, fP
        zc = np.zeros_like(w3)
        return (_unbounded_limit((zc, w3), 1.0), _unbounded_limit((zc, w4), 1.0),
                _unbounded_limit((fP, cP), 1.0), det)
    vP = ((slider["A"] + slider["B"]) * ub + rate["l2"] * u2
          + fb.lp * (w3 + rate["alpha"])[..., None] * geom2d.perp(up)
          + rate["lp"] * up * one[..., None])
    return w3, w4, vP, det


@dataclass(frozen=True)
class Sensitivity:
    """First-order sensitivity of the outputs to one error source.

    Attributes
    ----------
    source : str
        Length source or clearance joint.
    theta2 : float, rad
    delta : (n,) float, rad
        Pin angles (clearance sources; zeros for length sources).
    dtheta3, dtheta4 : (n,) float
        Output rates per unit source (rad per length unit, or rad/rad).
    dP : (n, 2) float
        Coupler-point rate per unit source.
    status : ErrorStatus
        Of the nominal pose.
    """

    source: str
    theta2: float
    delta: np.ndarray
    dtheta3: np.ndarray
    dtheta4: np.ndarray
    dP: np.ndarray
    status: ErrorStatus

    def __repr__(self):
        return (f"Sensitivity(source={self.source!r}, theta2={self.theta2:.6g}, "
                f"n={self.delta.size}, status={self.status.name})")

    def to_dict(self):
        return {"source": self.source, "theta2": self.theta2, "delta": self.delta.tolist(),
                "dtheta3": self.dtheta3.tolist(), "dtheta4": self.dtheta4.tolist(),
                "dP": self.dP.tolist(), "status": self.status.name}


def sensitivity(fb: FourBar, theta2, source: str, delta=0.0, *, unit: str = "rad",
                tol: LinkageTolerances = DEFAULT_TOL) -> Sensitivity:
    """Sensitivity of theta3, theta4 and P to ``source`` at crank angle ``theta2``.

    It is the velocity solution of the sensitivity linkage: every original input
    held (rate 0), the added slider of ``source`` driven at unit rate.

    Parameters
    ----------
    fb : FourBar
    theta2 : float, rad (or ``unit``)
    source : str
        One of :data:`LENGTH_SOURCES` or :data:`JOINTS`.
    delta : float or array, rad (or ``unit``)
        Pin angle on the clearance circle (clearance sources only).
    unit : {"rad", "deg"}
        Unit of ``theta2`` and ``delta``.

    Returns
    -------
    Sensitivity
        Exactly at a toggle (``sin(theta3 - theta4) = 0``, status NEAR_TOGGLE)
        the sensitivities are unbounded and read ``+-inf`` (the sign of the
        limit on the assembly branch; a component with no unbounded part keeps
        its finite value).
    """
    _check_fb(fb)
    tol = check_tolerances(tol)
    t2 = getangle(theta2, unit, "theta2")
    src = _check_source(source)
    d = _angles_1d(delta, unit, "delta")
    t3, t4, _, st, toggle = _nominal_pose(fb, t2, tol)
    if src in JOINTS:
        beta = d + _ref_angles(fb, t2, t3, t4)[src] + math.pi
    else:
        beta = np.zeros_like(d)
    if st == PoseStatus.UNASSEMBLABLE:
        z = np.zeros_like(d)
        return Sensitivity(src, t2, d, z, z, np.zeros((d.size, 2)), ErrorStatus.UNASSEMBLABLE)
    w3, w4, vP, _ = _sensitivity_core(fb, t2, t3, t4, src, beta, toggle=toggle)
    return Sensitivity(src, t2, d, w3, w4, vP, ErrorStatus(st))


def clearance_gradient(fb: FourBar, theta2, joint: str, *, unit: str = "rad",
                       tol: LinkageTolerances = DEFAULT_TOL):
    """Gradients of (theta3, theta4, Px, Py) with respect to the clearance vector.

    Returns
    -------
    G : (4, 2) float
        Row k is the gradient of quantity k (order ``theta3, theta4, px, py``)
        with respect to ``e_J = (ex, ey)``; ``+-inf`` entries exactly at a
        toggle (see :func:`sensitivity`).
    status : ErrorStatus
    """
    _check_fb(fb)
    tol = check_tolerances(tol)
    t2 = getangle(theta2, unit, "theta2")
    j = _check_joint(joint)
    t3, t4, _, st, toggle = _nominal_pose(fb, t2, tol)
    w3, w4, vP, _ = _sensitivity_core(fb, t2, t3, t4, j, np.array([0.0, math.pi / 2]),
                                      toggle=toggle)
    G = np.array([w3, w4, vP[:, 0], vP[:, 1]])
    return G, ErrorStatus(st)


@dataclass(frozen=True)
class ErrorCurve:
    """Mechanical error over pin angles (or a single length deviation).

    Attributes
    ----------
    method : {"exact", "linear"}
    theta2 : float, rad
    joint : str or None
        Clearance joint, None when only length deviations are applied.
    radius : float, length units
    delta : (n,) float, rad
    d_theta3, d_theta4 : (n,) float, rad
        Output errors (perturbed minus nominal, wrapped to [-pi, pi)).
    dP : (n, 2) float, length units
        Coupler-point error.
    status : (n,) int
        :class:`ErrorStatus` values; errors are 0 where UNASSEMBLABLE.
    """

    method: str
    theta2: float
    joint: str | None
    radius: float
    delta: np.ndarray
    d_theta3: np.ndarray
    d_theta4: np.ndarray
    dP: np.ndarray
    status: np.ndarray

    @property
    def success(self) -> bool:
        return bool(np.all(self.status == ErrorStatus.OK))

    def __repr__(self):
        bad = self.status == ErrorStatus.UNASSEMBLABLE
        note = ""
        if bad.any():
            note = (", UNASSEMBLABLE" if bad.all() else
                    f", {int(bad.sum())} of {bad.size} UNASSEMBLABLE (their errors read 0)")
        elif not self.success:
            note = f", {ErrorStatus(int(self.status.max())).name}"
        return (f"ErrorCurve({self.method}, joint={self.joint}, r={self.radius:.4g}, "
                f"n={self.delta.size}, max|dtheta4|={np.max(np.abs(self.d_theta4)):.4g}{note})")

    def to_dict(self):
        return {"method": self.method, "theta2": self.theta2, "joint": self.joint,
                "radius": self.radius, "delta": self.delta.tolist(),
                "d_theta3": self.d_theta3.tolist(), "d_theta4": self.d_theta4.tolist(),
                "dP": self.dP.tolist(),
                "status": [ErrorStatus(int(s)).name for s in self.status]}


def _prep_error_args(fb, theta2, joint, radius, delta, dl, unit, tol):
    _check_fb(fb)
    check_tolerances(tol)
    t2 = getangle(theta2, unit, "theta2")
    j = None if joint is None else _check_joint(joint)
    r = getscalar(radius, "radius", nonneg=True)
    if j is None and r != 0.0:
        raise InputError(f"radius {r:g} is a clearance at a joint, but no joint was given; "
                         f"pass joint='A', 'B', 'C' or 'D' with it (or radius=0 for the "
                         f"length deviations alone)", name="joint", value=None)
    d = _angles_1d(delta, unit, "delta")
    dl = _check_dl(dl, unit)
    _check_physical(fb, dl, {j: r} if j is not None else {}, "dl")
    return t2, j, r, d, dl


def exact_error(fb: FourBar, theta2, *, joint: str | None = None, radius=0.0, delta=0.0,
                dl: Mapping[str, float] | None = None, unit: str = "rad",
                tol: LinkageTolerances = DEFAULT_TOL) -> ErrorCurve:
    """Exact error: re-solve the linkage with deviations ``dl`` and/or the pin of
    ``joint`` displaced by ``radius`` on its clearance circle at angles ``delta``.

    Parameters
    ----------
    fb : FourBar
    theta2 : float, rad (or ``unit``)
    joint : {"A", "B", "C", "D"} or None
    radius : float, length units
    delta : float or (n,) array, rad (or ``unit``)
        One angle or a non-empty 1-D array of them.
    dl : mapping source -> deviation, optional
        Length deviations (length units); the angle-valued ``alpha`` and
        ``theta1`` in rad (or ``unit``, like ``theta2`` and ``delta``), each
        within a turn.
    unit : {"rad", "deg"}
        Unit of ``theta2``, ``delta`` and the angle-valued deviations of ``dl``.

    Returns
    -------
    ErrorCurve
    """
    t2, j, r, d, dlv = _prep_error_args(fb, theta2, joint, radius, delta, dl, unit, tol)
    n = d.size
    t3, t4, P0, st0 = _nominal(fb, t2, tol)
    T3, T4, P, st = _deviated(fb, t2, t3, t4, j, r, d, dlv, n, tol)
    st = np.maximum(st, st0)
    ok = st != ErrorStatus.UNASSEMBLABLE
    d3 = np.where(ok, geom2d.wrap_pi(T3 - t3), 0.0)
    d4 = np.where(ok, geom2d.wrap_pi(T4 - t4), 0.0)
    dP = np.where(ok[:, None], P - P0, 0.0)
    return ErrorCurve("exact", t2, j, r, d, d3, d4, dP, st)


def _deviated(fb: FourBar, t2, t3, t4, j, r, d, dlv, n, tol):
    """theta3, theta4, P and status of the linkage re-solved with the
    deviations ``dlv`` and the pin of joint ``j`` displaced by ``r`` at the
    angles ``d`` (:func:`exact_error`'s arguments, as
    :func:`_prep_error_args` reads them), about the nominal pose ``t3``,
    ``t4``."""
    e = {}
    if j is not None:
        beta = d + _ref_angles(fb, t2, t3, t4)[j] + math.pi
        e[j] = _pin_vectors(r, beta)
    return _solve_perturbed(fb, t2, {k: np.full(n, v) for k, v in dlv.items()}, e, n, tol)


def linear_error(fb: FourBar, theta2, *, joint: str | None = None, radius=0.0, delta=0.0,
                 dl: Mapping[str, float] | None = None, unit: str = "rad",
                 tol: LinkageTolerances = DEFAULT_TOL) -> ErrorCurve:
    """First-order error from the sensitivity linkage (same arguments as
    :func:`exact_error`).  Linear superposition of every source.

    Exactly at a toggle the first-order error is unbounded: it reads ``+-inf``
    (the sign of the limit on the assembly branch), 0 where no source acts.
    Away from a toggle (the nominal pose OK), where the deviated linkage
    itself does not close (as :func:`exact_error` finds it), the status is
    UNASSEMBLABLE and the errors read 0, as for every :class:`ErrorCurve`: a
    first-order error of parts that cannot be assembled means nothing.  Near
    a toggle the first-order rates are what is asked for, and kept.
    """
    t2, j, r, d, dlv = _prep_error_args(fb, theta2, joint, radius, delta, dl, unit, tol)
    n = d.size
    t3, t4, _, st0, toggle = _nominal_pose(fb, t2, tol)
    d3 = np.zeros(n)
    d4 = np.zeros(n)
    dP = np.zeros((n, 2))
    if st0 != PoseStatus.UNASSEMBLABLE and toggle:
        # every source at once: the sign of the unbounded sum is that of the
        # summed coefficients, which separate infinities would not give
        rates = {k: v for k, v in dlv.items() if v != 0.0}
        beta = np.zeros(n)
        if j is not None and r > 0:
            rates[j] = r
            beta = d + _ref_angles(fb, t2, t3, t4)[j] + math.pi
        if rates:
            d3, d4, dP, _ = _sensitivity_core(fb, t2, t3, t4, rates, beta, toggle=True)
    elif st0 != PoseStatus.UNASSEMBLABLE:
        if j is not None and r > 0:
            beta = d + _ref_angles(fb, t2, t3, t4)[j] + math.pi
            w3, w4, vP, _ = _sensitivity_core(fb, t2, t3, t4, j, beta)
            d3 += r * w3
            d4 += r * w4
            dP += r * vP
        for k, v in dlv.items():
            w3, w4, vP, _ = _sensitivity_core(fb, t2, t3, t4, k, np.zeros(1))
            d3 += v * w3[0]
            d4 += v * w4[0]
            dP += v * vP[0]
    status = np.full(n, st0, dtype=int)
    if st0 == PoseStatus.OK and not toggle and (any(v != 0.0 for v in dlv.values())
                                                or (j is not None and r > 0)):
        bad = _deviated(fb, t2, t3, t4, j, r, d, dlv, n, tol)[3] == ErrorStatus.UNASSEMBLABLE
        if bad.any():
            status = np.where(bad, int(ErrorStatus.UNASSEMBLABLE), status)
            d3, d4 = np.where(bad, 0.0, d3), np.where(bad, 0.0, d4)
            dP = np.where(bad[:, None], 0.0, dP)
    return ErrorCurve("linear", t2, j, r, d, d3, d4, dP, status)


# ---------------------------------------------------------------------------
# closed forms of [Shin & Choi 1995] (joint B)
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class ClosedForm:
    """Closed forms of [Shin & Choi 1995] for a clearance at B, per unit clearance.

    Attributes
    ----------
    beta : (n,) float, rad
    omega3, omega4 : (n,) float
        Eqs. 19-20 (with the rocker length ``l4`` in Eq. 20's denominator; the
        printed ``l3`` is a misprint: Eq. 18's second column carries ``l4``).
    vP : (n, 2) float
        Eq. 25 with ``g1 = (H - lp sin(alpha+theta3) cos theta4) / H``,
        ``g2 = -lp sin(alpha+theta3) sin theta4 / H``,
        ``h1 = lp cos(alpha+theta3) cos theta4 / H``,
        ``h2 = (H + lp cos(alpha+theta3) sin theta4) / H`` and
        ``H = l3 sin(theta3 - theta4)`` (re-derived from Eqs. 19, 22-24; the printed
        coefficients are garbled).
    """

    beta: np.ndarray
    omega3: np.ndarray
    omega4: np.ndarray
    vP: np.ndarray

    def __repr__(self):
        def rng(a):
            a = np.asarray(a)
            return f"[{a.min():.4g}, {a.max():.4g}]" if a.size else "[]"
        return (f"ClosedForm(n={self.beta.size}, omega3 in {rng(self.omega3)}, "
                f"omega4 in {rng(self.omega4)}, max|vP|="
                f"{np.max(np.hypot(*np.asarray(self.vP).reshape(-1, 2).T)) if self.vP.size else 0:.4g})")

    def to_dict(self):
        return {"beta": self.beta.tolist(), "omega3": self.omega3.tolist(),
                "omega4": self.omega4.tolist(), "vP": self.vP.tolist()}


def clearance_b_closed_form(fb: FourBar, theta2, beta, *, unit: str = "rad",
                            tol: LinkageTolerances = DEFAULT_TOL) -> ClosedForm:
    """First-order error velocities of a clearance at joint B in closed form.

    The coupler and rocker angular velocities and the coupler-point velocity of the
    sensitivity linkage, per unit clearance, at crank angle ``theta2`` for pin
    directions ``beta`` (world, rad or ``unit``): Eqs. 19, 20 and 25 of
    [Shin & Choi 1995] (see :class:`ClosedForm` for the corrections).  They agree
    with :func:`linear_error` for ``joint="B"``.

    The closed forms divide by ``sin(theta3 - theta4)``: exactly at a toggle
    they raise :class:`~cspace.errors.NumericalError` (:func:`sensitivity`
    reports the unbounded rates there).
    """
    _check_fb(fb)
    tol = check_tolerances(tol)
    t2 = getangle(theta2, unit, "theta2")
    b = _angles_1d(beta, unit, "beta")
    t3, t4, _, _, toggle = _nominal_pose(fb, t2, tol)
    l3, l4, lp, a = fb.coupler, fb.rocker, fb.lp, fb.alpha
    s34 = math.sin(t3 - t4)
    if toggle or s34 == 0.0:
        raise NumericalError(
            f"clearance_b_closed_form divides by sin(theta3 - theta4), which is 0 at "
            f"theta2 = {t2:.9g} rad: the pose is exactly at a toggle, where the rates are "
            "unbounded; use sensitivity() (it reports them as +-inf) or a crank angle "
            "off the toggle")
    w3 = np.cos(t4 - b) / (l3 * s34)
    w4 = np.cos(t3 - b) / (l4 * s34)
    H = l3 * s34
    sa, ca = math.sin(a + t3), math.cos(a + t3)
    g1 = (H - lp * sa * math.cos(t4)) / H
    g2 = -lp * sa * math.sin(t4) / H
    h1 = lp * ca * math.cos(t4) / H
    h2 = (H + lp * ca * math.sin(t4)) / H
    vP = np.stack([g1 * np.cos(b) + g2 * np.sin(b), h1 * np.cos(b) + h2 * np.sin(b)], -1)
    return ClosedForm(b, w3, w4, vP)


def paper_closed_form(fb: FourBar, theta2, beta, *, unit: str = "rad",
                      tol: LinkageTolerances = DEFAULT_TOL) -> ClosedForm:
    """Deprecated name of :func:`clearance_b_closed_form`."""
    warnings.warn("paper_closed_form is deprecated; use clearance_b_closed_form",
                  DeprecationWarning, stacklevel=2)
    return clearance_b_closed_form(fb, theta2, beta, unit=unit, tol=tol)


# ---------------------------------------------------------------------------
# harmonic structure, ellipse, Dubowsky
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Harmonic:
    """``f(delta) ~ offset + amplitude cos(delta - phase)`` from three evaluations.

    Attributes
    ----------
    offset : float
    amplitude : float (>= 0)
    phase : float, rad in [-pi, pi)
    delta_max, delta_min : float, rad
        Maximising / minimising pin angle (``phase`` and ``phase + pi``).
    max_value, min_value : float
        ``offset +- amplitude``.
    evaluations : int
        Number of function evaluations used (3).
    quantity, method : str
    status : ErrorStatus
    """

    offset: float
    amplitude: float
    phase: float
    delta_max: float
    delta_min: float
    max_value: float
    min_value: float
    evaluations: int
    quantity: str = "theta4"
    method: str = "exact"
    status: ErrorStatus = ErrorStatus.OK

    def __call__(self, delta):
        """The fitted harmonic at ``delta`` (rad)."""
        return self.offset + self.amplitude * np.cos(np.asarray(delta, float) - self.phase)

    def __repr__(self):
        return (f"Harmonic({self.quantity}, {self.method}: {self.offset:.4g} + "
                f"{self.amplitude:.4g} cos(delta {'+' if self.phase < 0 else '-'} "
                f"{abs(self.phase):.4g}), {self.status.name})")

    def to_dict(self):
        return {k: (v.name if isinstance(v, enum.Enum) else v)
                for k, v in self.__dict__.items()}


def harmonic_fit(values, deltas=None) -> tuple:
    """Offset, amplitude and phase of ``c + A cos(delta - phi)`` through three points.

    Parameters
    ----------
    values : (3,) float
    deltas : (3,) float, rad, optional
        Distinct angles (default ``0, 2 pi/3, 4 pi/3``).

    Returns
    -------
    (offset, amplitude, phase)

    Raises
    ------
    InputError
        Values or angles that are not three real numbers.
    NonFiniteError
        A NaN or infinite value or angle.
    """
    f = _three_numbers(values, "values")
    d = np.array([0.0, 2 * math.pi / 3, 4 * math.pi / 3]) if deltas is None \
        else _three_numbers(deltas, "deltas")
    if f.shape != (3,) or d.shape != (3,):
        raise InputError(f"harmonic_fit needs 3 values at 3 angles, got shapes {f.shape} "
                         f"and {d.shape}", name="values")
    M = np.stack([np.ones(3), np.cos(d), np.sin(d)], -1)
    if abs(np.linalg.det(M)) < 1e-12:
        raise InputError(f"harmonic_fit needs three distinct angles mod 2 pi, got {d.tolist()}",
                         name="deltas", value=d)
    c, a, b = np.linalg.solve(M, f)
    return float(c), float(math.hypot(a, b)), float(math.atan2(b, a))


def _three_numbers(x, name: str) -> np.ndarray:
    """A (3,) float array from real numbers, for :func:`harmonic_fit`."""
    if isinstance(x, (str, bytes)) or np.asarray(x).dtype.kind not in "iuf":
        raise InputError(f"harmonic_fit needs {name} as 3 real numbers, got "
                         f"{type(x).__name__} {x!r}", name=name, value=x)
    a = np.asarray(x, dtype=float)
    if a.shape != (3,):
        raise InputError(f"harmonic_fit needs 3 values at 3 angles, got {name} of shape "
                         f"{a.shape}", name=name, value=x)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"harmonic_fit needs finite {name}, got {a.tolist()}",
                             name=name, value=x)
    return a


_QIDX = {"theta3": 0, "theta4": 1, "px": 2, "py": 3}


def _curve_quantity(curve: ErrorCurve, q: str) -> np.ndarray:
    return {"theta3": curve.d_theta3, "theta4": curve.d_theta4,
            "px": curve.dP[:, 0], "py": curve.dP[:, 1]}[q]


def harmonic_max(fb: FourBar, theta2, joint: str, radius, *, quantity: str = "theta4",
                 method: str = "exact", unit: str = "rad",
                 tol: LinkageTolerances = DEFAULT_TOL) -> Harmonic:
    """Extremes over the pin angle from three evaluations at ``delta = 0, 2pi/3, 4pi/3``.

    The first-order error is exactly harmonic in ``delta``; with ``method="exact"``
    the three evaluations are exact re-solutions, and the fit also captures the
    second-order offset.  The deviation from a dense sweep is second order in the
    clearance.

    Exactly at a toggle the first-order error is unbounded: with
    ``method="linear"`` the result then has ``amplitude``, ``max_value`` and
    ``-min_value`` ``inf``, offset 0, the phase of the unbounded harmonic and
    the status NEAR_TOGGLE.
    """
    if method not in ("exact", "linear"):
        raise InputError(f"method must be 'exact' or 'linear', got {method!r}", name="method",
                         value=method)
    q = _check_quantity(quantity)
    t2 = getangle(theta2, unit, "theta2")
    d = np.array([0.0, 2 * math.pi / 3, 4 * math.pi / 3])
    fn = exact_error if method == "exact" else linear_error
    curve = fn(fb, t2, joint=joint, radius=radius, delta=d, tol=tol)
    st = ErrorStatus(int(np.max(curve.status)))
    values = _curve_quantity(curve, q)
    if not np.all(np.isfinite(values)):
        # a linear error at a toggle: fit the coefficients of the unbounded part
        j = _check_joint(joint)
        t3, t4, _, _ = _nominal(fb, t2, tol)
        beta = d + _ref_angles(fb, t2, t3, t4)[j] + math.pi
        c3, c4, cP, _ = _sensitivity_core(fb, t2, t3, t4, j, beta, toggle=True,
                                          coefficients=True)
        coef = {"theta3": c3, "theta4": c4, "px": cP[:, 0], "py": cP[:, 1]}[q]
        _, _, ph = harmonic_fit(coef, d)
        return Harmonic(0.0, math.inf, ph, ph, float(geom2d.wrap_pi(ph + math.pi)), math.inf,
                        -math.inf, 3, q, method, ErrorStatus.NEAR_TOGGLE)
    c, A, ph = harmonic_fit(values, d)
    return Harmonic(c, A, ph, ph, float(geom2d.wrap_pi(ph + math.pi)), c + A, c - A, 3, q,
                    method, st)


@dataclass(frozen=True)
class ErrorEllipse:
    """First-order coupler-point error locus ``dP(beta) = M (cos beta, sin beta)``.

    Attributes
    ----------
    matrix : (2, 2) float, length units
        ``M`` (already scaled by the clearance radius).
    semi_major, semi_minor : float, length units
    orientation : float, rad
        Direction of the major axis in [-pi/2, pi/2).
    kind : EllipseKind
    joint : str
    status : ErrorStatus
    """

    matrix: np.ndarray
    semi_major: float
    semi_minor: float
    orientation: float
    kind: EllipseKind
    joint: str
    status: ErrorStatus

    def points(self, beta) -> np.ndarray:
        """Locus points ``(n, 2)`` at pin directions ``beta`` (world, rad)."""
        b = np.asarray(beta, float)
        return np.stack([np.cos(b), np.sin(b)], -1) @ self.matrix.T

    def implicit(self, pts) -> np.ndarray:
        """``x^T (M M^T)^+ x - 1`` for points ``(n, 2)``: 0 on a proper ellipse."""
        Q = np.linalg.pinv(self.matrix @ self.matrix.T)
        pts = np.asarray(pts, float)
        return np.einsum("ni,ij,nj->n", pts, Q, pts) - 1.0

    def __repr__(self):
        return (f"ErrorEllipse({self.kind.value}, a={self.semi_major:.4g}, "
                f"b={self.semi_minor:.4g}, orientation={self.orientation:.4g} rad)")

    def to_dict(self):
        return {"matrix": self.matrix.tolist(), "semi_major": self.semi_major,
                "semi_minor": self.semi_minor, "orientation": self.orientation,
                "kind": self.kind.value, "joint": self.joint, "status": self.status.name}


def coupler_ellipse(fb: FourBar, theta2, joint: str, radius, *, unit: str = "rad",
                    segment_rel: float = 1e-9,
                    tol: LinkageTolerances = DEFAULT_TOL) -> ErrorEllipse:
    """The ellipse traced by the first-order coupler-point error as the pin goes
    round the clearance circle of ``joint``.

    ``segment_rel``: minor/major ratio below which the ellipse is reported as a
    SEGMENT (the minor axis is then round-off; 1e-9 is far above double-precision
    noise of the 2x2 SVD and far below any real ellipse's aspect ratio); a
    number in (0, 1).

    Exactly at a toggle the first-order coupler-point error is unbounded (when
    the coupler point is off the pin, ``lp > 0``): there is no ellipse, and
    :class:`~cspace.errors.NumericalError` says so.
    """
    seg = getscalar(segment_rel, "segment_rel")
    if not 0.0 < seg < 1.0:
        raise InputError(f"segment_rel must be a ratio in (0, 1), got {seg:g}",
                         name="segment_rel", value=segment_rel)
    G, st = clearance_gradient(fb, theta2, joint, unit=unit, tol=tol)
    r = getscalar(radius, "radius", nonneg=True)
    if r > 0 and not np.all(np.isfinite(G[2:4, :])):
        raise NumericalError(
            f"no coupler-point error ellipse at theta2 = {float(getangle(theta2, unit)):.9g} "
            "rad: the pose is exactly at a toggle, where the first-order error of P is "
            "unbounded; use exact_error, or a crank angle off the toggle")
    M = r * G[2:4, :] if r > 0 else np.zeros((2, 2))
    U, S, _ = np.linalg.svd(M)
    a, b = float(S[0]), float(S[1])
    scale = r * (1.0 + fb.lp / fb.coupler)
    if a <= seg * max(scale, 1e-300):
        kind = EllipseKind.POINT
    elif b <= seg * a:
        kind = EllipseKind.SEGMENT
    else:
        kind = EllipseKind.ELLIPSE
    ori = float(math.atan2(U[1, 0], U[0, 0]))
    ori = float((ori + math.pi / 2) % math.pi - math.pi / 2)
    return ErrorEllipse(M, a, b, ori, kind, _check_joint(joint), st)


def dubowsky_deltas(fb: FourBar, theta2, joint: str, *, unit: str = "rad",
                    tol: LinkageTolerances = DEFAULT_TOL) -> tuple:
    """Pin angles at which the pin offset is collinear with the coupler.

    Returns ``(delta_a, delta_b)`` (rad, wrapped to [-pi, pi)) for ``beta = theta3``
    and ``beta = theta3 + pi``: the extremes of the first-order output error.
    """
    _check_fb(fb)
    t2 = getangle(theta2, unit, "theta2")
    j = _check_joint(joint)
    t3, t4, _, _ = _nominal(fb, t2, tol)
    ref = _ref_angles(fb, t2, t3, t4)[j]
    da = float(geom2d.wrap_pi(t3 - ref - math.pi))
    return da, float(geom2d.wrap_pi(da + math.pi))


# ---------------------------------------------------------------------------
# combined error: worst case, RSS, Monte Carlo
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class ToleranceSpec:
    """Symmetric length tolerances and joint clearances.

    A spec is reused across calls, so the unit of its angle-valued tolerances
    (``alpha``, ``theta1``) is its own, stated when it is built, and not the
    ``unit`` of a call (which is that of the crank angle): ``ToleranceSpec(
    lengths={"alpha": 0.5}, unit="deg")`` is half a degree in every call.  A
    spec that holds angle tolerances without stating a unit reads them in rad,
    and a call with ``unit="deg"`` refuses it (it cannot tell which was meant).

    Attributes
    ----------
    lengths : mapping source -> half-width (>= 0)
        Keys among :data:`LENGTH_SOURCES`; length units, and ``unit`` for the
        angle-valued ``alpha`` and ``theta1`` (stored in rad, each within a
        turn).  The deviation lies in ``[-t, t]``.
    clearances : mapping joint -> radius (>= 0), length units
        Radial clearance (pin offset ``|e_J| <= r``).
    unit : {"rad", "deg"} or None
        Unit in which the angle tolerances are given.  They are stored in rad,
        so a spec built with a stated unit reads ``unit == "rad"`` afterwards;
        None (the default) means not stated (rad, refused by a call in
        degrees when the spec holds angle tolerances).
    """

    lengths: Mapping[str, float] = field(default_factory=dict)
    clearances: Mapping[str, float] = field(default_factory=dict)
    unit: str | None = None

    def __post_init__(self):
        if not isinstance(self.lengths, Mapping) or not isinstance(self.clearances, Mapping):
            raise InputError("ToleranceSpec.lengths and .clearances must be mappings, got "
                             f"{type(self.lengths).__name__} and "
                             f"{type(self.clearances).__name__}", name="spec")
        k_unit = 1.0 if self.unit is None else getunit(self.unit)
        L = {}
        for k, v in self.lengths.items():
            if k not in LENGTH_SOURCES:
                raise InputError(f"tolerance keys must be among {LENGTH_SOURCES}, got {k!r}",
                                 name="lengths", value=k)
            L[k] = getscalar(v, f"lengths[{k!r}]", nonneg=True)
            if k in ANGLE_SOURCES:
                L[k] = _within_a_turn(L[k] * k_unit, f"lengths[{k!r}]", self.unit or "rad")
        Cl = {}
        for k, v in self.clearances.items():
            Cl[_check_joint(k)] = getscalar(v, f"clearances[{k!r}]", nonneg=True)
        object.__setattr__(self, "lengths", dict(sorted(L.items())))
        object.__setattr__(self, "clearances", dict(sorted(Cl.items())))
        object.__setattr__(self, "unit", None if self.unit is None else "rad")

    def to_dict(self):
        return {"lengths": dict(self.lengths), "clearances": dict(self.clearances),
                "unit": self.unit}


def _check_spec(spec, fb=None, unit: str = "rad") -> ToleranceSpec:
    """``spec`` checked against ``fb``; a call in ``unit`` other than rad refuses a
    spec whose angle tolerances have no stated unit."""
    if not isinstance(spec, ToleranceSpec):
        raise InputError(f"spec must be a ToleranceSpec, got {type(spec).__name__}",
                         name="spec", value=spec)
    angles = [k for k in ANGLE_SOURCES if spec.lengths.get(k, 0.0) != 0.0]
    if angles and spec.unit is None and unit != "rad":
        raise InputError(
            f"the spec holds angle tolerances ({', '.join(angles)}) without a stated unit, and "
            f"this call reads theta2 in {unit!r}: the call's unit does not apply to a spec; "
            f"build it with ToleranceSpec(..., unit={unit!r}) (or unit='rad') to say which "
            "is meant", name="spec", value=spec)
    if fb is not None:
        _check_physical(fb, spec.lengths, spec.clearances, "lengths")
    return spec


def _linear_terms(fb, t2, spec, q, tol):
    """Per-source linear coefficients: lengths -> scalar, joints -> (2,) gradient
    (``+-inf`` where unbounded, exactly at a toggle)."""
    t3, t4, _, st, toggle = _nominal_pose(fb, t2, tol)
    k = _QIDX[q]
    lin = {}
    for s in spec.lengths:
        w3, w4, vP, _ = _sensitivity_core(fb, t2, t3, t4, s, np.zeros(1), toggle=toggle)
        lin[s] = float(np.array([w3[0], w4[0], vP[0, 0], vP[0, 1]])[k])
    grad = {}
    for j in spec.clearances:
        w3, w4, vP, _ = _sensitivity_core(fb, t2, t3, t4, j, np.array([0.0, math.pi / 2]),
                                          toggle=toggle)
        grad[j] = np.array([w3, w4, vP[:, 0], vP[:, 1]])[k]
    return lin, grad, st, (t3, t4)


def _contributions(spec, lin, grad) -> dict:
    """The first-order worst-case contribution of every source: ``|S| t`` and
    ``r |g|`` (inf where the sensitivity is unbounded, 0 for a zero tolerance)."""
    out = {s: (abs(lin[s]) * t if t > 0 else 0.0) for s, t in spec.lengths.items()}
    out.update({j: (r * float(np.hypot(*grad[j])) if r > 0 else 0.0)
                for j, r in spec.clearances.items()})
    return out


def _exact_raw(fb, t2, q, dl_arr, e_arr, n, nominal, tol, on_line=False):
    """The exact error of ``q``, status and toggle distances (see
    :func:`_solve_perturbed`) of n variants; where a variant does not assemble
    the error is that of its near miss."""
    t3n, t4n, P0, _ = nominal
    T3, T4, P, st, miss = _solve_perturbed(fb, t2, dl_arr, e_arr, n, tol, gap=True,
                                           on_line=on_line)
    val = {"theta3": geom2d.wrap_pi(T3 - t3n), "theta4": geom2d.wrap_pi(T4 - t4n),
           "px": P[:, 0] - P0[0], "py": P[:, 1] - P0[1]}[q]
    return val, st, miss


def _exact_quantity(fb, t2, spec, q, dl_arr, e_arr, n, nominal, tol):
    val, st, _ = _exact_raw(fb, t2, q, dl_arr, e_arr, n, nominal, tol)
    return np.where(st == ErrorStatus.UNASSEMBLABLE, 0.0, val), st


@dataclass(frozen=True)
class WorstCase:
    """Worst-case bounds of one output error over the tolerance box.

    Attributes
    ----------
    quantity : str
    linear_max, linear_min : float
        First-order bounds ``+- (sum |S_i| t_i + sum r_J |g_J|)``; ``+-inf``
        exactly at a toggle (unbounded sensitivities).  No bound when the
        status is UNASSEMBLABLE (the box reaches past a toggle).
    exact_max, exact_min : float
        The largest and smallest exact error found over the box (L-BFGS-B from
        the linear extremes and from the best of a fixed sample of the box,
        every evaluation counted).  The nominal linkage (error 0) is in the
        box, so ``exact_min <= 0 <= exact_max`` always holds.  When part of the
        box does not assemble (``partial``) they are the extremes over the part
        that does.
    argmax, argmin : dict
        Deviations at the exact extremes: length sources -> value, joints ->
        ``(ex, ey)``.
    success : bool
        Both searches converged and the whole box assembles.
    status : ErrorStatus
        UNASSEMBLABLE when part of the box does not assemble (``partial``), or
        when the nominal linkage does not (no bounds at all: every number then
        reads 0 and ``argmax``, ``argmin`` are empty).
    message : str
    nfev : int
        Exact evaluations used (sample, optimiser and boundary search).
    partial : bool
        Some variants in the box do not assemble (the box reaches past a
        toggle): the exact values bound only the variants that do, the
        linear ones bound nothing.
    """

    quantity: str
    linear_max: float
    linear_min: float
    exact_max: float
    exact_min: float
    argmax: dict
    argmin: dict
    success: bool
    status: ErrorStatus
    message: str
    nfev: int
    partial: bool = False

    def __repr__(self):
        if self.status == ErrorStatus.UNASSEMBLABLE and not self.partial:
            return (f"WorstCase({self.quantity}: no bounds, the nominal linkage does not "
                    f"assemble, {self.status.name})")
        lin = f"linear [{self.linear_min:.4g}, {self.linear_max:.4g}]"
        ex = f"exact [{self.exact_min:.4g}, {self.exact_max:.4g}]"
        if self.partial:
            lin += " (no bound: part of the box does not assemble)"
            ex = f"exact over the assembling part of the box [{self.exact_min:.4g}, " \
                 f"{self.exact_max:.4g}]"
        return f"WorstCase({self.quantity}: {lin}, {ex}, {self.status.name})"

    def to_dict(self):
        conv = lambda d: {k: (list(map(float, v)) if np.ndim(v) else float(v))  # noqa: E731
                          for k, v in d.items()}
        return {"quantity": self.quantity, "linear_max": self.linear_max,
                "linear_min": self.linear_min, "exact_max": self.exact_max,
                "exact_min": self.exact_min, "argmax": conv(self.argmax),
                "argmin": conv(self.argmin), "success": self.success,
                "status": self.status.name, "message": self.message, "nfev": self.nfev,
                "partial": self.partial}


def worst_case(fb: FourBar, theta2, spec: ToleranceSpec, *, quantity: str = "theta4",
               unit: str = "rad", maxiter: int = 200,
               tol: LinkageTolerances = DEFAULT_TOL) -> WorstCase:
    """Worst-case error over all length tolerances and joint clearances.

    The linear bound adds absolute first-order contributions.  The exact bound
    maximises (and minimises) the exactly re-solved error over the box of length
    deviations and the discs of the clearances, by L-BFGS-B in the variables
    ``(dl_i in [-t_i, t_i], rho_J in [0, r_J], phi_J)``, started at the linear
    extreme (and, when that is not enough, at the best points of a fixed
    sample of the box); the extremes reported are those of every exact
    evaluation, the nominal linkage (error 0) included, so ``exact_min <= 0 <=
    exact_max``.

    Variants that do not assemble are penalised by how far their loop fails to
    close, which leads the search to the edge of the assembling part of the
    box (near a toggle the extremes lie there), and a variant that does not
    assemble is never an extreme.  When any variant in the box fails to
    assemble the result says so: status UNASSEMBLABLE, ``partial`` True, and
    the exact values are the extremes over the part of the box that does.

    Parameters
    ----------
    fb : FourBar
    theta2 : float, rad (or ``unit``)
    spec : ToleranceSpec
        Its angle tolerances are in its own unit (see :class:`ToleranceSpec`).
    quantity : {"theta4", "theta3", "px", "py"}
    unit : {"rad", "deg"}
        Unit of ``theta2``.
    maxiter : int >= 1
        Iteration limit of each L-BFGS-B search.
    tol : LinkageTolerances

    Returns
    -------
    WorstCase
    """
    from scipy.optimize import minimize

    _check_fb(fb)
    tol = check_tolerances(tol)
    t2 = getangle(theta2, unit, "theta2")
    spec = _check_spec(spec, fb, unit)
    q = _check_quantity(quantity)
    maxiter = getint(maxiter, "maxiter", minimum=1)
    nominal = _nominal(fb, t2, tol)
    if nominal[3] == PoseStatus.UNASSEMBLABLE:
        return WorstCase(q, 0.0, 0.0, 0.0, 0.0, {}, {}, False, ErrorStatus.UNASSEMBLABLE,
                         "the nominal linkage does not assemble at theta2: no bounds", 0)
    lin, grad, st0, _ = _linear_terms(fb, t2, spec, q, tol)
    contrib = _contributions(spec, lin, grad)
    lin_max = sum(contrib[s] for s in spec.lengths) + sum(contrib[j] for j in spec.clearances)
    names_l = list(spec.lengths)
    names_j = list(spec.clearances)
    nl = len(names_l)
    nx = nl + 2 * len(names_j)
    if nx == 0:
        return WorstCase(q, 0.0, 0.0, 0.0, 0.0, {}, {}, True, ErrorStatus(st0),
                         "max: no error sources; min: no error sources", 0)
    lower = np.array([-spec.lengths[s] for s in names_l]
                     + [v for j in names_j for v in (0.0, -np.inf)])
    upper = np.array([spec.lengths[s] for s in names_l]
                     + [v for j in names_j for v in (spec.clearances[j], np.inf)])
    bounds = [(-spec.lengths[s], spec.lengths[s]) for s in names_l]
    for j in names_j:
        bounds += [(0.0, spec.clearances[j]), (None, None)]

    def arg_of(x):
        arg = {s: float(x[i]) for i, s in enumerate(names_l)}
        for k, j in enumerate(names_j):
            rho, phi = x[nl + 2 * k], x[nl + 2 * k + 1]
            arg[j] = (float(rho * math.cos(phi)), float(rho * math.sin(phi)))
        return arg

    # the best assembling variant of each sign seen by any evaluation; the
    # nominal linkage (no deviation, error 0) assembles
    best = {1.0: [0.0, np.zeros(nx), int(st0)], -1.0: [0.0, np.zeros(nx), int(st0)]}
    seen = {"nfev": 0, "partial": False, "outer": False, "inner": False}

    def evaluate(X, on_line=False):
        """Errors, assembly and toggle distances of the variants X (m, nx); the
        assembling ones update the extremes (not the on-line toggle poses)."""
        X = np.clip(np.atleast_2d(np.asarray(X, float)), lower, upper)
        m = X.shape[0]
        dl = {s: X[:, i] for i, s in enumerate(names_l)}
        e = {}
        for k, j in enumerate(names_j):
            rho, phi = X[:, nl + 2 * k], X[:, nl + 2 * k + 1]
            e[j] = np.stack([rho * np.cos(phi), rho * np.sin(phi)], -1)
        val, st, miss = _exact_raw(fb, t2, q, dl, e, m, nominal, tol, on_line)
        seen["nfev"] += m
        if on_line:
            return val, None, miss
        feas = st != ErrorStatus.UNASSEMBLABLE
        if not feas.all():
            seen["partial"] = True
            seen["outer"] |= bool(np.any(~feas & (miss[:, 0] > 0)))
            seen["inner"] |= bool(np.any(~feas & (miss[:, 1] > 0)))
        for sgn in (1.0, -1.0):
            if feas.any():
                i = int(np.argmax(np.where(feas, sgn * val, -np.inf)))
                if sgn * val[i] > sgn * best[sgn][0]:
                    best[sgn] = [float(val[i]), X[i].copy(), int(st[i])]
        return val, feas, miss

    # linear extremes, and a fixed sample of the box (pins on their clearance
    # circles and inside them): cheap, vectorised, and it finds out whether
    # the whole box assembles
    x0s = {}
    for sign in (1.0, -1.0):
        x0 = [sign * math.copysign(spec.lengths[s], lin[s]) if lin[s] else 0.0
              for s in names_l]
        for j in names_j:
            g = grad[j]
            x0 += [spec.clearances[j], math.atan2(sign * g[1], sign * g[0])]
        x0s[sign] = np.array(x0, float)
    rng = np.random.default_rng(0)
    ms = 1024
    S = np.empty((ms, nx))
    S[:, :nl] = rng.uniform(-1.0, 1.0, (ms, nl)) * upper[:nl]
    for k, j in enumerate(names_j):
        u = rng.uniform(0.0, 1.0, ms)
        S[:, nl + 2 * k] = spec.clearances[j] * np.where(np.arange(ms) % 2 == 0, 1.0,
                                                         np.sqrt(u))
        S[:, nl + 2 * k + 1] = rng.uniform(0.0, 2 * math.pi, ms)
    S = np.vstack([x0s[1.0], x0s[-1.0], S])
    sval, sfeas, _ = evaluate(S)

    finite = [v for v in contrib.values() if math.isfinite(v)]
    regular = not seen["partial"] and st0 == PoseStatus.OK and math.isfinite(lin_max)
    if regular:
        scale = max(list(contrib.values()) + [1e-300])
    else:
        scale = max([float(np.max(np.abs(sval[sfeas]))) if sfeas.any() else 0.0]
                    + finite + [1e-300])
    # penalty per unit of toggle distance (normalised by the tolerances): above
    # the rate at which the near-miss error can change with it
    tscale = max(sum(spec.lengths.values()) + sum(spec.clearances.values()), 1e-300)
    lmin = min(fb.coupler, fb.rocker)
    slope = 1.0 / lmin if q in ("theta3", "theta4") else 1.0 + fb.lp / lmin
    mu = 10.0 * slope * tscale / scale

    def pull_in(x_out, x_in):
        """Bisection from x_in (assembles) towards x_out, to the edge of the
        assembling part of the box (every step is an evaluation)."""
        a, b = np.asarray(x_in, float), np.asarray(x_out, float)
        for _ in range(64):
            mid = 0.5 * (a + b)
            if evaluate(mid)[1][0]:
                a = mid
            else:
                b = mid
            if np.max(np.abs(b - a)) <= 1e-16 * (1.0 + np.max(np.abs(a))):
                break

    def lbfgsb(fun, x_start):
        return minimize(fun, x_start, method="L-BFGS-B", bounds=bounds,
                        options={"maxiter": maxiter})

    messages = {}
    oks = {}
    for sign in (1.0, -1.0):

        def obj(x, sign=sign):
            v, feas, miss = evaluate(x)
            gap = max(float(miss[0].max()), 0.0) if not feas[0] else 0.0
            return -sign * float(v[0]) / scale + mu * gap / tscale

        runs = [lbfgsb(obj, x0s[sign])]
        if not regular:
            # further starts: the best assembling points of the sample
            order = np.argsort(np.where(sfeas, -sign * sval, np.inf))
            runs += [lbfgsb(obj, S[i]) for i in order[:2] if sfeas[i]]
        elif sign * best[sign][0] > -runs[0].fun * scale + 1e-9 * scale:
            # the sample beat the search from the linear extreme: search from there
            runs.append(lbfgsb(obj, best[sign][1]))
        if seen["partial"]:
            for res in runs:
                if not evaluate(res.x)[1][0]:
                    pull_in(res.x, best[sign][1])
            # near a toggle the extremes lie on the edge of the assembling part,
            # where the variant is itself at a toggle: maximise there, along
            # the (smooth) toggle poses, subject to being at the toggle
            for which in (0, 1):
                if not seen[("outer", "inner")[which]]:
                    continue

                def on_line(x, sign=sign):
                    return -sign * float(evaluate(x, on_line=True)[0][0]) / scale

                def at_toggle(x, which=which):
                    return float(evaluate(x, on_line=True)[2][0, which]) / tscale

                anchor = best[sign][1].copy()
                res = minimize(on_line, anchor, method="SLSQP", bounds=bounds,
                               constraints=[{"type": "eq", "fun": at_toggle}],
                               options={"maxiter": maxiter, "ftol": 1e-14})
                if np.all(np.isfinite(res.x)) and not evaluate(res.x)[1][0]:
                    pull_in(res.x, anchor)
        oks[sign] = bool(runs[0].success) or runs[0].status == 0
        messages[sign] = str(runs[0].message)

    partial = bool(seen["partial"])
    status = ErrorStatus(max(int(st0), best[1.0][2], best[-1.0][2]))
    if not (oks[1.0] and oks[-1.0]) and status == ErrorStatus.OK:
        status = ErrorStatus.NOT_CONVERGED
    msg = f"max: {messages[1.0]}; min: {messages[-1.0]}"
    if partial:
        status = ErrorStatus.UNASSEMBLABLE
        msg += ("; part of the tolerance box does not assemble (it reaches past a toggle): "
                "the exact values are the extremes over the part that does, the linear "
                "ones are no bound")
    return WorstCase(q, lin_max, -lin_max, best[1.0][0], best[-1.0][0], arg_of(best[1.0][1]),
                     arg_of(best[-1.0][1]), oks[1.0] and oks[-1.0] and not partial, status, msg,
                     seen["nfev"], partial)


@dataclass(frozen=True)
class RSSResult:
    """Root-sum-square combination of the first-order worst-case contributions.

    Attributes
    ----------
    quantity : str
    value : float
        ``sqrt(sum (S_i t_i)^2 + sum (r_J |g_J|)^2)``; inf exactly at a toggle.
    contributions : dict
        Source -> its worst-case first-order contribution.
    status : ErrorStatus
        UNASSEMBLABLE also when the linkage does not assemble at a
        first-order extreme of the tolerance box (the box reaches past a
        toggle, where no linear bound holds).
    """

    quantity: str
    value: float
    contributions: dict
    status: ErrorStatus

    def __repr__(self):
        return f"RSSResult({self.quantity}={self.value:.4g}, {self.status.name})"

    def to_dict(self):
        return {"quantity": self.quantity, "value": self.value,
                "contributions": dict(self.contributions), "status": self.status.name}


def rss(fb: FourBar, theta2, spec: ToleranceSpec, *, quantity: str = "theta4",
        unit: str = "rad", tol: LinkageTolerances = DEFAULT_TOL) -> RSSResult:
    """Statistical (root-sum-square) error bound from the sensitivities.

    ``unit`` is that of ``theta2``; the angle tolerances of ``spec`` are in the
    spec's own unit (see :class:`ToleranceSpec`).  Exactly at a toggle the
    sensitivities are unbounded, and so (inf) are the contributions of the
    sources that act there.
    """
    _check_fb(fb)
    tol = check_tolerances(tol)
    t2 = getangle(theta2, unit, "theta2")
    spec = _check_spec(spec, fb, unit)
    q = _check_quantity(quantity)
    lin, grad, st0, _ = _linear_terms(fb, t2, spec, q, tol)
    contrib = _contributions(spec, lin, grad)
    status = ErrorStatus(st0)
    if st0 == PoseStatus.UNASSEMBLABLE:
        contrib = {k: 0.0 for k in contrib}
    elif _box_leaves_assembly(fb, t2, spec, q, lin, grad, tol):
        # a first-order bound over a box part of which does not assemble
        # (past a toggle) is no bound: say so
        status = ErrorStatus.UNASSEMBLABLE
    val = float(math.sqrt(sum(v * v for v in contrib.values())))
    return RSSResult(q, val, contrib, status)


def _box_leaves_assembly(fb, t2, spec, q, lin, grad, tol) -> bool:
    """Whether the linkage fails to assemble at either first-order extreme of
    the tolerance box (every length at the end its sensitivity points to,
    every pin along its gradient, and the opposite corner)."""
    nominal = _nominal(fb, t2, tol)
    for sign in (1.0, -1.0):
        dl = {s: np.array([sign * math.copysign(t, lin[s]) if lin[s] else 0.0])
              for s, t in spec.lengths.items()}
        e = {}
        for j, r in spec.clearances.items():
            g = np.asarray(grad[j], dtype=float)
            if not np.all(np.isfinite(g)):
                # unbounded (at a toggle): its direction is that of the infinities
                g = np.where(np.isinf(g), np.sign(g), 0.0)
            n = float(np.hypot(*g))
            e[j] = (sign * r * g / n)[None, :] if n > 0 else np.zeros((1, 2))
        if not dl and not e:
            return False
        _, st = _exact_quantity(fb, t2, spec, q, dl, e, 1, nominal, tol)
        if st[0] == ErrorStatus.UNASSEMBLABLE:
            return True
    return False


@dataclass(frozen=True)
class MonteCarloResult:
    """Seeded Monte Carlo of one output error.

    Attributes
    ----------
    quantity : str
    n : int
        Samples drawn.
    n_feasible, n_infeasible, n_near_toggle : int
        Assembled samples, unassemblable ones (counted, excluded from the
        statistics) and assembled ones within the toggle tolerance (included).
    mean, std : float
        Of the feasible samples.
    ci : (float, float)
        Confidence interval of the mean (Student t).
    confidence : float
    minimum, maximum : float
        Extremes of the feasible samples.
    samples : (n_feasible,) float
    status : ErrorStatus
        OK, NEAR_TOGGLE if any sample was, UNASSEMBLABLE if no sample assembled.
    """

    quantity: str
    n: int
    n_feasible: int
    n_infeasible: int
    n_near_toggle: int
    mean: float
    std: float
    ci: tuple
    confidence: float
    minimum: float
    maximum: float
    samples: np.ndarray
    status: ErrorStatus

    def __repr__(self):
        if self.n_feasible == 0:
            return (f"MonteCarloResult({self.quantity}: n={self.n}, no sample assembles, "
                    f"{self.status.name})")
        return (f"MonteCarloResult({self.quantity}: n={self.n}, infeasible={self.n_infeasible}"
                f", mean={self.mean:.4g} CI[{self.ci[0]:.4g}, {self.ci[1]:.4g}], "
                f"range [{self.minimum:.4g}, {self.maximum:.4g}], {self.status.name})")

    def to_dict(self):
        d = {k: v for k, v in self.__dict__.items() if k not in ("samples", "status", "ci")}
        d["ci"] = list(self.ci)
        d["status"] = self.status.name
        d["samples"] = self.samples.tolist()
        return d


def monte_carlo(fb: FourBar, theta2, spec: ToleranceSpec, n: int = 1000, *,
                seed=None, quantity: str = "theta4", lengths: str = "uniform",
                pins: str = "circle", confidence: float = 0.95, unit: str = "rad",
                tol: LinkageTolerances = DEFAULT_TOL) -> MonteCarloResult:
    """Monte Carlo of the exactly re-solved error.

    Parameters
    ----------
    n : int
        Number of samples (>= 2).
    seed : int, numpy Generator or None
    lengths : {"uniform", "normal"}
        Length deviations uniform on ``[-t, t]``, or normal with ``sigma = t / 3``
        (clipped to ``[-t, t]``).
    pins : {"circle", "disc"}
        Pin on the clearance circle at a uniform angle (the contact assumption of
        [Shin & Choi 1995]), or uniform over the clearance disc.
    confidence : float in (0, 1)
    unit : {"rad", "deg"}
        Unit of ``theta2``; the angle tolerances of ``spec`` are in the spec's
        own unit (see :class:`ToleranceSpec`).
    """
    from scipy import stats

    _check_fb(fb)
    tol = check_tolerances(tol)
    t2 = getangle(theta2, unit, "theta2")
    spec = _check_spec(spec, fb, unit)
    q = _check_quantity(quantity)
    n = getint(n, "n", minimum=2)
    if lengths not in ("uniform", "normal"):
        raise InputError(f"lengths must be 'uniform' or 'normal', got {lengths!r}",
                         name="lengths", value=lengths)
    if pins not in ("circle", "disc"):
        raise InputError(f"pins must be 'circle' or 'disc', got {pins!r}", name="pins",
                         value=pins)
    conf = getscalar(confidence, "confidence")
    if not 0.0 < conf < 1.0:
        raise InputError(f"confidence must lie in (0, 1), got {conf}", name="confidence",
                         value=conf)
    rng = getseed(seed)
    dl = {}
    for s, t in spec.lengths.items():
        if lengths == "uniform":
            dl[s] = rng.uniform(-t, t, n)
        else:
            dl[s] = np.clip(rng.normal(0.0, t / 3.0, n), -t, t)
    e = {}
    for j, r in spec.clearances.items():
        phi = rng.uniform(0.0, 2 * math.pi, n)
        rho = np.full(n, r) if pins == "circle" else r * np.sqrt(rng.uniform(0.0, 1.0, n))
        e[j] = np.stack([rho * np.cos(phi), rho * np.sin(phi)], -1)
    nominal = _nominal(fb, t2, tol)
    if nominal[3] == PoseStatus.UNASSEMBLABLE:
        return MonteCarloResult(q, n, 0, n, 0, 0.0, 0.0, (0.0, 0.0), conf, 0.0, 0.0,
                                np.zeros(0), ErrorStatus.UNASSEMBLABLE)
    v, st = _exact_quantity(fb, t2, spec, q, dl, e, n, nominal, tol)
    feas = st != ErrorStatus.UNASSEMBLABLE
    x = v[feas]
    nf = int(feas.sum())
    ntog = int(np.sum(st == ErrorStatus.NEAR_TOGGLE))
    if nf == 0:
        return MonteCarloResult(q, n, 0, n, 0, 0.0, 0.0, (0.0, 0.0), conf, 0.0, 0.0,
                                np.zeros(0), ErrorStatus.UNASSEMBLABLE)
    mean = float(x.mean())
    std = float(x.std(ddof=1)) if nf > 1 else 0.0
    half = float(stats.t.ppf(0.5 + conf / 2, max(nf - 1, 1)) * std / math.sqrt(nf))
    status = ErrorStatus.NEAR_TOGGLE if (ntog or nominal[3]) else ErrorStatus.OK
    return MonteCarloResult(q, n, nf, n - nf, ntog, mean, std, (mean - half, mean + half),
                            conf, float(x.min()), float(x.max()), x, status)
