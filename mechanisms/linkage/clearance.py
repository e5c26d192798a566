"""Four-bar with a clearance at the coupler-rocker joint ([Choi & Bae 1999]).

Two models of the same linkage, both with the crank turning at constant speed:

* :func:`continuous_contact` -- the paper's continuous-contact model (Eqs. 1-7):
  the contact direction ``alpha`` is that of the zero-clearance joint force,
  the kinematics are re-solved with the pin offset ``delta e^{j alpha}``, and the
  joint force ``R`` follows from the sum of the coupler and rocker moment
  equations (Eq. 3).  Contact loss is ``R < 0``.
* :func:`free_flight` -- the pin moves freely inside the clearance circle and
  meets the bush through a Lankarani-Nikravesh contact force; integrated by
  :func:`scipy.integrate.solve_ivp` with events at contact onset and separation.

Notation follows the paper, **not** :mod:`.fourbar`: ``theta1`` crank, ``theta2``
coupler (direction ``B -> C``), ``theta3`` rocker (direction ``C -> D``, so that the
loop reads ``l1 e^{j theta1} + l2 e^{j theta2} + delta e^{j alpha} + l3 e^{j theta3}
+ l4 e^{j theta4} = 0`` with the ground ``theta4 = pi``: ``D`` lies on +x from the
crank pivot ``A``).  Gravity acts along -y.  SI units (m, kg, s, N) throughout;
crank angles in rad (degrees only through ``unit="deg"`` arguments and the
``*_deg`` convenience properties).

Data of the linkage that [Choi & Bae 1999] does not print in Table 1 are assumptions,
stated in :meth:`ClearanceLinkage.reference`: centres of mass at mid-length of coupler and
rocker, and the ground length inferred by :func:`infer_ground`.
"""

from __future__ import annotations

import enum
import math
import warnings
from dataclasses import dataclass, fields, replace

import numpy as np

from cspace import geom2d
from cspace.argcheck import getangle, getint, getscalar, getunit
from cspace.errors import CSpaceError, InputError, NumericalError

from .fourbar import DEFAULT_TOL, Assembly, FourBar, PoseStatus, as_assembly, input_range, solve

__all__ = [
    "ClearanceLinkage", "GroundInference", "LossKind", "ContactLoss", "ContactForce",
    "FlightEvent", "FreeFlightResult", "FlightStatus",
    "infer_ground", "rocker_zero_acceleration", "continuous_contact", "free_flight",
    "hertz_stiffness", "rpm_to_rad_s",
]

G_STANDARD = 9.80665


def rpm_to_rad_s(rpm, name: str = "rpm") -> float:
    """Crank speed in rev/min converted to rad/s (``name``: the argument's
    name in an error message)."""
    return getscalar(rpm, name) * 2.0 * math.pi / 60.0


@dataclass(frozen=True)
class ClearanceLinkage:
    """Four-bar data for the clearance-joint analyses (SI units).

    Attributes
    ----------
    crank, coupler, rocker, ground : float, m
        ``l1``, ``l2``, ``l3``, ``l4`` of [Choi & Bae 1999].
    m_coupler, m_rocker : float, kg
    J_coupler : float, kg m^2
        Coupler moment of inertia about B.
    J_rocker : float, kg m^2
        Rocker moment of inertia about its ground pivot D.
    cg_coupler : float, m
        Distance B -> coupler centre of mass (``r2``).
    cg_rocker : float, m
        Distance C -> rocker centre of mass (``r3``; the paper measures it from C).
    gravity : float, m/s^2
        Acts along -y; 0 switches it off.
    bush_radius : float, m
        Radius of the bush at C (only the free-flight contact stiffness uses it).
    assembly : Assembly
        Branch of the zero-clearance four-bar (OPEN: C above the line B -> D).
    """

    crank: float
    coupler: float
    rocker: float
    ground: float
    m_coupler: float
    m_rocker: float
    J_coupler: float
    J_rocker: float
    cg_coupler: float
    cg_rocker: float
    gravity: float = G_STANDARD
    bush_radius: float = 6.5e-3
    assembly: Assembly = Assembly.OPEN

    def __post_init__(self):
        for name in ("crank", "coupler", "rocker", "ground", "m_coupler", "m_rocker",
                     "J_coupler", "J_rocker", "bush_radius"):
            object.__setattr__(self, name, getscalar(getattr(self, name), name, positive=True))
        for name in ("cg_coupler", "cg_rocker", "gravity"):
            object.__setattr__(self, name, getscalar(getattr(self, name), name, nonneg=True))
        object.__setattr__(self, "assembly", as_assembly(self.assembly))
        # parallel axes: the inertia about a pivot is at least m r^2, r the
        # centre of mass's distance from it
        for J, m, r, what in (("J_coupler", self.m_coupler, self.cg_coupler, "B"),
                              ("J_rocker", self.m_rocker, abs(self.rocker - self.cg_rocker),
                               "D")):
            least = m * r * r
            if getattr(self, J) < least * (1 - 1e-9):
                raise InputError(f"{J} is the moment of inertia about {what}, at least m r^2 "
                                 f"= {least:.6g} kg m^2 (r = {r:.6g} m, the centre of mass's "
                                 f"distance from {what}); got {getattr(self, J):.6g} kg m^2 "
                                 f"(the inertia about the centre of mass, or kg mm^2?)",
                                 name=J, value=getattr(self, J))

    @classmethod
    def reference(cls, ground: float | None = None, **changes) -> "ClearanceLinkage":
        """The reference linkage of the clearance analyses, from Table 1 of
        [Choi & Bae 1999]: l1 = 70 mm, l2 = l3 = 200 mm, m2 = m3 = 0.6 kg,
        J2B = J3D = 7190 kg mm^2.

        Assumptions (the paper does not print them): centres of mass at mid-length
        (``r2 = r3 = 100 mm``), gravity along -y with the ground horizontal, open
        branch, and the ground length from :func:`infer_ground` (rocker angular
        acceleration zero at a crank angle of 119 deg, paper Fig. 5) unless given.
        """
        base = cls(0.070, 0.200, 0.200, 0.120, 0.6, 0.6, 7190e-6, 7190e-6, 0.100, 0.100)
        if changes:
            allowed = [f.name for f in fields(cls) if f.name != "ground"]
            unknown = sorted(k for k in changes if k not in allowed)
            if unknown:
                raise InputError(f"ClearanceLinkage.reference got unknown field(s) "
                                 f"{', '.join(unknown)}; the fields that can be changed are "
                                 f"{', '.join(allowed)} (and ground)", name=unknown[0],
                                 value=changes[unknown[0]])
            base = replace(base, **changes)
        if ground is None:
            ground = infer_ground(base, 119.0, unit="deg").ground
        return replace(base, ground=getscalar(ground, "ground", positive=True))

    @classmethod
    def table1(cls, ground: float | None = None, **changes) -> "ClearanceLinkage":
        """Deprecated name of :meth:`reference`."""
        warnings.warn("ClearanceLinkage.table1 is deprecated; use ClearanceLinkage.reference",
                      DeprecationWarning, stacklevel=2)
        return cls.reference(ground, **changes)

    def fourbar(self) -> FourBar:
        """The zero-clearance linkage as a :class:`FourBar` (crank = l1 of [Choi & Bae 1999])."""
        return FourBar.from_lengths(self.ground, self.crank, self.coupler, self.rocker,
                                    assembly=self.assembly)

    def to_dict(self):
        d = dict(self.__dict__)
        d["assembly"] = self.assembly.name.lower()
        return d

    def __repr__(self):
        return (f"ClearanceLinkage(l1={self.crank:.4g}, l2={self.coupler:.4g}, "
                f"l3={self.rocker:.4g}, l4={self.ground:.4g} m)")


def _check_link(link):
    if not isinstance(link, ClearanceLinkage):
        raise InputError(f"expected a ClearanceLinkage, got {type(link).__name__}",
                         name="link", value=link)


def _speed(speed, speed_unit):
    if speed_unit == "rpm":
        w = rpm_to_rad_s(speed, "speed")
    elif speed_unit == "rad/s":
        w = getscalar(speed, "speed")
    else:
        raise InputError(f"speed_unit must be 'rpm' or 'rad/s', got {speed_unit!r}",
                         name="speed_unit", value=speed_unit)
    if not w > 0:
        raise InputError(f"speed must be > 0, got {speed!r} {speed_unit}", name="speed",
                         value=speed)
    return w


# ---------------------------------------------------------------------------
# kinematics of the loop with a pin offset (paper notation)
# ---------------------------------------------------------------------------

def _u(a):
    return np.stack([np.cos(a), np.sin(a)], -1)


def _kinematics(link: ClearanceLinkage, t1, w, delta, alpha, alpha_d, alpha_dd):
    """Coupler/rocker angles, rates and accelerations for the loop of Eq. 1.

    ``alpha_d``/``alpha_dd`` are time derivatives.  Returns th2, th3, th2d, th3d,
    th2dd, th3dd and an assembled mask.
    """
    l1, l2, l3, l4 = link.crank, link.coupler, link.rocker, link.ground
    D = np.array([l4, 0.0])
    B = l1 * _u(t1)
    ua = _u(alpha)
    Cc, kind = geom2d.circle_circle(B, l2, D - delta * ua, l3, int(link.assembly))
    ok = (kind == geom2d.IntersectionKind.TWO) | (kind == geom2d.IntersectionKind.TANGENT)
    th2 = np.arctan2(Cc[:, 1] - B[:, 1], Cc[:, 0] - B[:, 0])
    pin = Cc + delta * ua
    th3 = np.arctan2(D[1] - pin[:, 1], D[0] - pin[:, 0])
    p2, p3 = geom2d.perp(_u(th2)), geom2d.perp(_u(th3))
    det = l2 * l3 * geom2d.cross2(p2, p3)
    safe = np.where(det != 0, det, 1.0)

    def solve2(rhs):
        # l2 x p2 + l3 y p3 = rhs
        x = geom2d.cross2(rhs, l3 * p3) / safe
        y = geom2d.cross2(l2 * p2, rhs) / safe
        return x, y

    rhs = -(l1 * w * geom2d.perp(_u(t1)) + delta * alpha_d[:, None] * geom2d.perp(ua))
    th2d, th3d = solve2(rhs)
    rhs = (l1 * w * w * _u(t1) + l2 * (th2d ** 2)[:, None] * _u(th2)
           + l3 * (th3d ** 2)[:, None] * _u(th3)
           - delta * (alpha_dd[:, None] * geom2d.perp(ua) - (alpha_d ** 2)[:, None] * ua))
    th2dd, th3dd = solve2(rhs)
    return th2, th3, th2d, th3d, th2dd, th3dd, ok


def _periodic_derivatives(f, n_turns, n):
    """First and second derivative (per rad of crank) of samples over one turn.

    ``f`` is unwrapped; ``n_turns`` is its net winding (f(2 pi) - f(0) = 2 pi n_turns).
    """
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    g = f - n_turns * t
    k = np.fft.rfftfreq(n, d=1.0 / n)
    G = np.fft.rfft(g)
    d1 = np.fft.irfft(1j * k * G, n) + n_turns
    d2 = np.fft.irfft(-(k ** 2) * G, n)
    return d1, d2


# ---------------------------------------------------------------------------
# ground inference
# ---------------------------------------------------------------------------

def rocker_zero_acceleration(link: ClearanceLinkage, *, n: int = 7200) -> np.ndarray:
    """Crank angles (rad, in [0, 2 pi)) at which the rocker angular acceleration is
    zero at constant crank speed (kinematic: independent of the speed).

    Parameters
    ----------
    link : ClearanceLinkage
        Its crank must make whole turns.
    n : int, >= 360
        Samples of the crank turn; the zeros are interpolated linearly between them.
    """
    _check_link(link)
    n = getint(n, "n", minimum=360)
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    m = solve(link.fourbar(), t, omega2=1.0)
    _full_turn(t, np.asarray(m.status) != PoseStatus.UNASSEMBLABLE, link.fourbar())
    a = m.alpha4
    idx = np.nonzero(np.sign(a) != np.sign(np.roll(a, -1)))[0]
    out = []
    for i in idx:
        j = (i + 1) % n
        frac = a[i] / (a[i] - a[j])
        out.append((t[i] + frac * (2 * math.pi / n)) % (2 * math.pi))
    return np.sort(np.array(out))


@dataclass(frozen=True)
class GroundInference:
    """The ground length inferred from a zero of the rocker angular acceleration.

    Attributes
    ----------
    ground : float, m
    target : float, rad
        The crank angle at which the first zero was required.
    zeros : (k,) float, rad
        All zeros of the rocker angular acceleration with that ground.
    success : bool
        True: :func:`infer_ground` raises :class:`~cspace.errors.NumericalError`
        instead of returning a failed search.
    """

    ground: float
    target: float
    zeros: np.ndarray
    success: bool

    @property
    def zeros_deg(self):
        return np.degrees(self.zeros)

    def __repr__(self):
        return (f"GroundInference(ground={self.ground * 1e3:.2f} mm, zeros="
                f"{np.round(self.zeros_deg, 1).tolist()} deg"
                f"{'' if self.success else ', success=False'})")

    def to_dict(self):
        return {"ground": self.ground, "target": self.target, "zeros": self.zeros.tolist(),
                "success": self.success}


def infer_ground(link: ClearanceLinkage, target=math.radians(119.0), *, unit: str = "rad",
                 bracket=(0.100, 0.140)) -> GroundInference:
    """Ground length at which the rocker angular acceleration vanishes at crank
    angle ``target`` (first zero in (0, pi)); [Choi & Bae 1999] Fig. 5 reports 119 deg.

    Parameters
    ----------
    link : ClearanceLinkage
        Only crank, coupler, rocker and assembly are used.
    target : float
        Crank angle in ``unit``, in (0, pi) rad; default 119 deg (in rad).
    unit : {"rad", "deg"}
        Unit of ``target``.
    bracket : (float, float), m
        Two ground lengths between which to search; the crank must make whole
        turns with either.

    Returns
    -------
    GroundInference

    Raises
    ------
    InputError
        For a target outside (0, pi) rad or a bracket that is not two positive
        lengths at which the crank turns fully.
    NumericalError
        When the first zero does not pass through ``target`` within the bracket
        (no ground length in it puts the zero there): the message gives the
        zeros found at both ends.
    """
    from scipy.optimize import brentq

    _check_link(link)
    tgt = getangle(target, unit, "target")
    if not 0.0 < tgt < math.pi:
        raise InputError(f"target must be a crank angle in (0, pi) rad (0..180 deg), got "
                         f"{target!r} {unit} ({tgt:.4g} rad); pass unit='deg' for an angle "
                         f"in degrees", name="target", value=target)
    if isinstance(bracket, (str, bytes)) or not hasattr(bracket, "__len__") \
            or len(bracket) != 2:
        raise InputError(f"bracket must be two ground lengths (lo, hi) in m, got {bracket!r}",
                         name="bracket", value=bracket)
    lo, hi = sorted(getscalar(b, "bracket", positive=True) for b in bracket)
    if not lo < hi:
        raise InputError(f"bracket must be two different ground lengths, got {bracket!r}",
                         name="bracket", value=bracket)

    def zero_in_first_half(l4):
        z = rocker_zero_acceleration(replace(link, ground=l4), n=3600)
        z = z[(z > 0.0) & (z < math.pi)]
        return z[0] if z.size else math.pi

    def first_zero(l4):
        return zero_in_first_half(l4) - tgt

    ends = []
    for b in (lo, hi):
        try:
            ends.append(zero_in_first_half(b))
        except CSpaceError as e:
            raise InputError(f"bracket end {b:g} m is no ground length of this linkage: {e}",
                             name="bracket", value=bracket) from None
    flo, fhi = ends[0] - tgt, ends[1] - tgt
    found = (f"with the bracket ({lo:g}, {hi:g}) m the first zero in (0, 180) deg lies at "
             f"{math.degrees(ends[0]):.2f} and {math.degrees(ends[1]):.2f} deg "
             f"(180 meaning none)")
    if flo * fhi > 0:
        raise NumericalError(f"no ground length in the bracket puts the first zero of the "
                             f"rocker angular acceleration at {math.degrees(tgt):.2f} deg: "
                             f"{found}; widen the bracket or check the target and its unit")
    g = brentq(first_zero, lo, hi, xtol=1e-7)
    if abs(first_zero(g)) > 1e-3:
        # the first zero jumps across the target (it leaves (0, pi)) instead of passing it
        raise NumericalError(f"the first zero of the rocker angular acceleration jumps over "
                             f"{math.degrees(tgt):.2f} deg near a ground of {g:g} m instead "
                             f"of passing through it: {found}")
    return GroundInference(g, tgt, rocker_zero_acceleration(replace(link, ground=g)), True)


# ---------------------------------------------------------------------------
# continuous-contact model
# ---------------------------------------------------------------------------

class LossKind(enum.Enum):
    """Why contact is lost."""

    NEGATIVE_FORCE = "negative-force"   #: R < 0 in Eq. 3 (the paper's criterion)
    FORCE_REVERSAL = "force-reversal"   #: zero-clearance force passes a near-zero
    #: minimum while its direction turns by more than ``reversal_turn``: the pin must
    #: cross the clearance


@dataclass(frozen=True)
class ContactLoss:
    """One contact-loss position.

    Attributes
    ----------
    angle : float, rad in [0, 2 pi)
        Crank angle at the start of the loss.
    kind : LossKind
    extent : float, rad
        Crank-angle length of the R < 0 interval (0 for FORCE_REVERSAL).
    """

    angle: float
    kind: LossKind
    extent: float

    @property
    def angle_deg(self) -> float:
        return math.degrees(self.angle)

    @property
    def signed_deg(self) -> float:
        """The angle in degrees, in (-180, 180]."""
        a = self.angle_deg
        return a - 360.0 if a > 180.0 else a

    def to_dict(self):
        return {"angle": self.angle, "kind": self.kind.value, "extent": self.extent}


@dataclass(frozen=True)
class ContactForce:
    """Joint force over one crank revolution (continuous-contact model).

    Attributes
    ----------
    link : ClearanceLinkage
    omega : float, rad/s
        Crank speed.
    clearance : float, m
    crank_angle : (n,) float, rad
    R : (n,) float, N
        Joint force of Eq. 3 (compressive > 0).
    R0 : (n,) float, N
        Zero-clearance force magnitude.
    alpha : (n,) float, rad
        Contact direction (unwrapped).
    losses : tuple of ContactLoss
    status : PoseStatus
        UNASSEMBLABLE if some crank angle does not assemble (R is 0 there);
        else NEAR_TOGGLE if the coupler and rocker come (nearly) in line at some
        crank angle (``|sin(theta3 - theta2)| <``
        :attr:`~mechanisms.linkage.fourbar.LinkageTolerances.toggle_sin`, as a
        change-point linkage does): the loop's rates and R are unbounded there,
        and R's values near it are meaningless; else OK.  No contact loss is
        read within ``reversal_window`` of a crank angle that does not assemble
        or is such a toggle (a change-point linkage with a clearance: the
        pin's offset opens the loop near its toggle).
    """

    link: ClearanceLinkage
    omega: float
    clearance: float
    crank_angle: np.ndarray
    R: np.ndarray
    R0: np.ndarray
    alpha: np.ndarray
    losses: tuple
    status: PoseStatus

    @property
    def rpm(self) -> float:
        return self.omega * 60.0 / (2 * math.pi)

    def percentile(self, q: float) -> float:
        """The ``q``-th percentile (0..100) of R over the revolution, N.  The median
        and upper percentiles measure the force level without the narrow spikes
        the model produces where the contact direction turns fast."""
        q = getscalar(q, "q")
        if not 0.0 <= q <= 100.0:
            raise InputError(f"q must be a percentile in [0, 100], got {q:g}", name="q",
                             value=q)
        return float(np.percentile(self.R, q))

    def peak_near(self, angle, window=math.radians(10.0)) -> float:
        """Largest R within ``window`` (rad) of crank angle ``angle`` (rad), N."""
        d = np.abs(geom2d.wrap_pi(self.crank_angle - angle))
        return float(self.R[d <= window].max())

    def loss_angles(self, kind: LossKind | None = None) -> np.ndarray:
        """Loss angles (rad), optionally of one kind."""
        return np.array([c.angle for c in self.losses if kind is None or c.kind is kind])

    def __repr__(self):
        ls = ", ".join(f"{c.signed_deg:.1f} deg ({c.kind.value})" for c in self.losses)
        st = "" if self.status is PoseStatus.OK else f", {self.status.name}"
        return (f"ContactForce({self.rpm:.0f} rpm, {self.clearance * 1e6:.4g} um, "
                f"max R={self.R.max():.4g} N, losses=[{ls}]{st})")

    def to_dict(self):
        return {"link": self.link.to_dict(), "omega": self.omega,
                "clearance": self.clearance, "crank_angle": self.crank_angle.tolist(),
                "R": self.R.tolist(), "R0": self.R0.tolist(), "alpha": self.alpha.tolist(),
                "losses": [c.to_dict() for c in self.losses], "status": self.status.name}


def _zero_clearance_force(link, t1, w):
    z = np.zeros_like(t1)
    th2, th3, _, _, th2dd, th3dd, ok = _kinematics(link, t1, w, 0.0, z, z, z)
    l1, l2, l3 = link.crank, link.coupler, link.rocker
    m2, m3, r2, r3, g = link.m_coupler, link.m_rocker, link.cg_coupler, link.cg_rocker, \
        link.gravity
    # Eq. 6 (the paper prints theta1-dot where its square is meant)
    a11, a12 = -l2 * np.sin(th2), l2 * np.cos(th2)
    a21, a22 = -l3 * np.sin(th3), l3 * np.cos(th3)
    b1 = link.J_coupler * th2dd - m2 * r2 * l1 * w * w * np.sin(t1 - th2) \
        + m2 * g * r2 * np.cos(th2)
    b2 = link.J_rocker * th3dd - m3 * g * (l3 - r3) * np.cos(th3)
    det = a11 * a22 - a12 * a21
    safe = np.where(det != 0, det, 1.0)
    Rx = (b1 * a22 - a12 * b2) / safe
    Ry = (a11 * b2 - a21 * b1) / safe
    return Rx, Ry, ok


def _clearance(link: ClearanceLinkage, clearance, positive: bool = False) -> float:
    """A radial clearance (m), >= 0 (> 0 with ``positive``) and smaller than the
    crank and the bush: a larger one is no joint clearance (often one given in
    micrometres where metres are read)."""
    delta = getscalar(clearance, "clearance", positive=positive, nonneg=True)
    bound, what = min((link.crank, "the crank"), (link.bush_radius, "the bush radius"))
    if delta >= bound:
        raise InputError(f"clearance must be a small radial gap, smaller than {what} "
                         f"({bound:g} m), got {delta:g} m; the clearance is in metres "
                         f"(50 um is 5e-05)", name="clearance", value=delta)
    return delta


def _full_turn(t1, ok, fb=None) -> None:
    """Refuse a linkage whose crank cannot make the whole turn the analysis
    drives it through, and say where it assembles.  ``fb`` (the zero-clearance
    FourBar): where it does assemble at every crank angle, the samples that
    failed are change points (B on D with coupler = rocker, whose loop
    position is indeterminate), and the message says so."""
    if ok.all():
        return
    if fb is not None and input_range(fb).full_turn:
        at = ", ".join(f"{math.degrees(float(x)):.4g}" for x in t1[~ok][:4])
        raise InputError(f"the linkage passes a change point at crank angle(s) {at} deg "
                         f"(of the samples): B lies on D there and the coupler equals the "
                         f"rocker, so the loop's position is indeterminate (it can fold "
                         f"either way); the analysis needs a linkage whose position is "
                         f"defined all along the turn (change-point linkages, s + l = p + q, "
                         f"are not analysed)", name="link")
    share = 100.0 * float(np.mean(ok))
    where = ""
    if ok.any():
        where = f"; it assembles for crank angles in {', '.join(geom2d.angle_spans(t1, ok))}"
    raise InputError(f"the analysis drives the crank through a whole turn, but the "
                     f"zero-clearance linkage assembles over {share:.0f} % of it{where} "
                     f"(a crank must be the shortest link of a Grashof linkage)",
                     name="link")


def continuous_contact(link: ClearanceLinkage, speed, clearance, *, speed_unit: str = "rpm",
                       n: int = 36000, reversal_turn: float = math.pi / 2,
                       reversal_window: float = math.radians(5.0)) -> ContactForce:
    """Joint force R over one revolution by the continuous-contact model.

    Parameters
    ----------
    link : ClearanceLinkage
    speed : float
        Crank speed in ``speed_unit`` ("rpm" or "rad/s"), constant.
    clearance : float, m
        Radial clearance ``delta`` (>= 0).
    n : int
        Samples per revolution.  ``alpha``'s derivatives are spectral, so ``n``
        must resolve the fastest turn of the force direction: 36000 (0.01 deg) is
        converged for Table 1; coarse grids with finite differences produce
        spurious R < 0 spikes.
    reversal_turn : float, rad
        Direction change of the zero-clearance force, within ``reversal_window`` of
        crank angle on each side of a local minimum of its magnitude, that counts
        as a FORCE_REVERSAL contact loss.
    reversal_window : float, rad

    Returns
    -------
    ContactForce
    """
    _check_link(link)
    w = _speed(speed, speed_unit)
    delta = _clearance(link, clearance)
    n = getint(n, "n", minimum=360)
    turn = getscalar(reversal_turn, "reversal_turn", positive=True)
    win = getscalar(reversal_window, "reversal_window", positive=True)
    t1 = np.linspace(0.0, 2 * math.pi, int(n), endpoint=False)
    Rx, Ry, ok0 = _zero_clearance_force(link, t1, w)
    _full_turn(t1, ok0, link.fourbar())
    R0 = np.hypot(Rx, Ry)
    alpha = np.unwrap(np.arctan2(Ry, Rx))
    wind = int(round((np.unwrap(np.append(alpha, alpha[0]))[-1] - alpha[0]) / (2 * math.pi)))
    a1, a2 = _periodic_derivatives(alpha, wind, int(n))
    ad, add = a1 * w, a2 * w * w
    th2, th3, _, _, th2dd, th3dd, ok = _kinematics(link, t1, w, delta, alpha, ad, add)
    l1, l2, l3 = link.crank, link.coupler, link.rocker
    m2, m3, r2, r3, g = link.m_coupler, link.m_rocker, link.cg_coupler, link.cg_rocker, \
        link.gravity
    num = (link.J_coupler * th2dd + link.J_rocker * th3dd + m2 * g * r2 * np.cos(th2)
           - m2 * l1 * r2 * w * w * np.sin(t1 - th2) - m3 * g * (l3 - r3) * np.cos(th3))
    den = l2 * np.sin(alpha - th2) + l3 * np.sin(alpha - th3)
    R = num / np.where(den != 0, den, 1.0)
    allok = ok & ok0
    R = np.where(allok, R, 0.0)
    # coupler and rocker (nearly) in line: the loop's rates and the force are
    # unbounded there (a change-point linkage passes through such a pose), and
    # R is no force but the rounding of a division by almost zero
    toggle = allok & (np.abs(np.sin(th3 - th2)) < DEFAULT_TOL.toggle_sin)
    status = (PoseStatus.UNASSEMBLABLE if not np.all(allok)
              else PoseStatus.NEAR_TOGGLE if np.any(toggle) else PoseStatus.OK)
    losses = []
    # within the reversal window of a crank angle where the loop does not
    # close or the force is unbounded, R is no force: no contact loss is read
    # there (the edges of such a gap would read as losses)
    h = max(1, int(round(win / (2 * math.pi / n))))
    void = ~allok | toggle
    if void.any():
        void = np.convolve(np.concatenate([void[-h:], void, void[:h]]).astype(float),
                           np.ones(2 * h + 1), mode="valid") > 0
    neg = (R < 0) & ~void
    if np.any(neg) and not np.all(neg):
        starts = np.nonzero(neg & ~np.roll(neg, 1))[0]
        for s in starts:
            k = s
            length = 0
            while neg[k % n] and length < n:
                k += 1
                length += 1
            losses.append(ContactLoss(float(t1[s]), LossKind.NEGATIVE_FORCE,
                                      length * 2 * math.pi / n))
    # force reversals: local minima of |R0| with a fast turn of alpha around them
    is_min = (R0 < np.roll(R0, 1)) & (R0 <= np.roll(R0, -1)) & ~void
    for i in np.nonzero(is_min)[0]:
        lo, hi = i - h, i + h
        aw = np.unwrap(np.take(alpha, np.arange(lo, hi + 1), mode="wrap"))
        if abs(aw[-1] - aw[0]) > turn and R0[i] <= np.min(np.take(R0, np.arange(lo, hi + 1),
                                                                   mode="wrap")):
            near_neg = any(abs(geom2d.wrap_pi(c.angle - t1[i])) < win for c in losses)
            if not near_neg:
                losses.append(ContactLoss(float(t1[i]), LossKind.FORCE_REVERSAL, 0.0))
    losses.sort(key=lambda c: c.angle)
    return ContactForce(link, w, delta, t1, R, R0, alpha, tuple(losses), status)


# ---------------------------------------------------------------------------
# free flight and impact
# ---------------------------------------------------------------------------

class FlightStatus(enum.IntEnum):
    """Outcome of the free-flight integration."""

    OK = 0
    NOT_CONVERGED = 1   #: solve_ivp failed
    MAX_EVENTS = 2      #: more contact switches than ``max_events``


@dataclass(frozen=True)
class FlightEvent:
    """One contact-loss episode of the pin: a separation followed by a train of
    impacts (flights separated by less than ``cluster_gap`` of crank angle).

    Attributes
    ----------
    separation : float, rad in [0, 2 pi)
        Crank angle at which contact is first lost.
    first_impact : float, rad in [0, 2 pi)
        Crank angle of the first re-contact.
    strongest_impact : float, rad in [0, 2 pi)
        Crank angle of the impact with the largest normal approach speed.
    last_impact : float, rad in [0, 2 pi)
        Crank angle after which contact persists.
    impacts : int
        Number of impacts in the episode.
    flight : float, rad
        Total crank angle travelled in free flight.
    impact_velocity : float, m/s
        Largest normal approach speed.
    revolution : int
        Index (0 = the first) of the integrated crank revolution in which contact
        was lost; revolutions count from the start angle of the integration.
    """

    separation: float
    first_impact: float
    strongest_impact: float
    last_impact: float
    impacts: int
    flight: float
    impact_velocity: float
    revolution: int = 0

    @property
    def separation_deg(self):
        return math.degrees(self.separation)

    @property
    def first_impact_deg(self):
        return math.degrees(self.first_impact)

    @property
    def strongest_impact_deg(self):
        return math.degrees(self.strongest_impact)

    def to_dict(self):
        return dict(self.__dict__)


@dataclass(frozen=True)
class FreeFlightResult:
    """Free-flight-and-impact simulation.

    Attributes
    ----------
    link : ClearanceLinkage
    omega, clearance : float
        rad/s, m.
    stiffness, exponent, restitution : float
        Contact law ``F = K p^n (1 + 3 (1 - c^2)/4 * pdot / pdot_minus)``.
    crank_angle : (m,) float, rad
        Sample crank angles over the last revolution, unwrapped from its start.
    force : (m,) float, N
        Contact force at the samples.
    gap : (m,) float, m
        ``|e| - delta`` (> 0: penetration).
    events : tuple of FlightEvent
        Contact-loss episodes that start in the analysed revolutions (all but the
        first ``transient``), in time order, each followed to its end.
    n_switches : int
        Contact-onset/separation events integrated in total.
    status : FlightStatus
    message : str
    revolutions : int
        Crank revolutions integrated (not counting the run-out that completes the
        last episode).
    transient : int
        Leading revolutions discarded as start-up transient.
    """

    link: ClearanceLinkage
    omega: float
    clearance: float
    stiffness: float
    exponent: float
    restitution: float
    crank_angle: np.ndarray
    force: np.ndarray
    gap: np.ndarray
    events: tuple
    n_switches: int
    status: FlightStatus
    message: str
    revolutions: int = 1
    transient: int = 0

    @property
    def success(self):
        return self.status == FlightStatus.OK

    @property
    def analysed(self) -> int:
        """Number of analysed revolutions, ``revolutions - transient``."""
        return self.revolutions - self.transient

    def spread(self, near, *, window=None, unit: str = "rad") -> dict:
        """Spread over the analysed revolutions of the episodes that lose contact
        within ``window`` of crank angle ``near``.

        The impact train after a contact loss is sensitive to the state at the
        loss, so its details differ from one revolution to the next; this gives
        their range.

        Parameters
        ----------
        near, window : float, ``unit``
            The crank angle of the contact loss and the half-width of the window
            that selects the episodes (default 20 deg).
        unit : {"rad", "deg"}
            Unit of ``near``, ``window`` and of the angles returned.

        Returns
        -------
        dict
            ``"episodes"`` (the number found), ``"revolutions"`` (how many were
            analysed), and ``(min, median, max)`` of ``"separation"``,
            ``"first_impact"``, ``"strongest_impact"``, ``"last_impact"`` and
            ``"flight"`` (angles in ``unit``, continuous across ``near``: in
            ``near`` +- 180 deg), ``"impacts"`` and ``"impact_velocity"`` (m/s); each
            is None when no episode is found.
        """
        f = getunit(unit)
        c = getangle(near, unit, "near")
        win = math.radians(20.0) if window is None else getangle(window, unit, "window")
        if not 0.0 < win <= math.pi:
            raise InputError(f"window must lie in (0, pi] rad (0..180 deg), got {window!r} "
                             f"{unit}", name="window", value=window)
        around = lambda a: c + math.remainder(a - c, 2 * math.pi)  # noqa: E731
        sel = [e for e in self.events if abs(math.remainder(e.separation - c, 2 * math.pi))
               <= win]

        def mmm(values):
            if not sel:
                return None
            v = np.asarray(values, dtype=float)
            return (float(v.min()), float(np.median(v)), float(v.max()))

        out = {"episodes": len(sel), "revolutions": self.analysed}
        for name in ("separation", "first_impact", "strongest_impact", "last_impact"):
            out[name] = mmm([around(getattr(e, name)) / f for e in sel])
        out["flight"] = mmm([e.flight / f for e in sel])
        out["impacts"] = mmm([e.impacts for e in sel])
        out["impact_velocity"] = mmm([e.impact_velocity for e in sel])
        return out

    def __repr__(self):
        ev = ", ".join(f"{e.separation_deg:.1f}->{e.strongest_impact_deg:.1f} deg"
                       for e in self.events)
        return (f"FreeFlightResult({self.omega * 60 / (2 * math.pi):.0f} rpm, "
                f"{self.clearance * 1e6:.4g} um, flights=[{ev}], {self.status.name})")

    def to_dict(self):
        return {"omega": self.omega, "clearance": self.clearance, "stiffness": self.stiffness,
                "exponent": self.exponent, "restitution": self.restitution,
                "crank_angle": self.crank_angle.tolist(), "force": self.force.tolist(),
                "gap": self.gap.tolist(), "events": [e.to_dict() for e in self.events],
                "n_switches": self.n_switches, "status": self.status.name,
                "message": self.message, "revolutions": self.revolutions,
                "transient": self.transient}


def hertz_stiffness(link: ClearanceLinkage, clearance: float, *, E: float = 207e9,
                    nu: float = 0.3) -> float:
    """Pin-in-bush contact stiffness ``(4/3) E* sqrt(R*)`` (N/m^1.5), steel on steel.

    ``R* = R_bush R_pin / (R_bush - R_pin)`` (conformal contact),
    ``1/E* = 2 (1 - nu^2) / E``.

    Parameters
    ----------
    link : ClearanceLinkage
        Its ``bush_radius`` is ``R_bush``.
    clearance : float, m
        Radial clearance ``R_bush - R_pin``: > 0 and smaller than the bush radius
        (and the crank), so that the pin has a radius.
    E : float, Pa
        Young's modulus of pin and bush, > 0.
    nu : float
        Poisson's ratio of pin and bush, in (-1, 0.5]: the range of an isotropic
        elastic material (positive bulk and shear moduli; 0.5 is incompressible).

    Raises
    ------
    InputError
        For an argument outside its range, naming the range.
    """
    _check_link(link)
    delta = _clearance(link, clearance, positive=True)
    E = getscalar(E, "E", positive=True)
    nu = getscalar(nu, "nu")
    if not -1.0 < nu <= 0.5:
        raise InputError(f"nu must be a Poisson's ratio in (-1, 0.5] (isotropic elastic "
                         f"material; steel is 0.3), got {nu:g}", name="nu", value=nu)
    rb = link.bush_radius
    rp = rb - delta
    Rs = rb * rp / delta
    Es = E / (2.0 * (1.0 - nu * nu))
    return 4.0 / 3.0 * Es * math.sqrt(Rs)


def _flight_args(link, speed, clearance, speed_unit, stiffness, exponent, restitution,
                 revolutions):
    """Checked physical inputs of :func:`free_flight`:
    ``(w, delta, K, ne, ce, revolutions)``."""
    _check_link(link)
    w = _speed(speed, speed_unit)
    delta = _clearance(link, clearance, positive=True)
    K = hertz_stiffness(link, delta) if stiffness is None else \
        getscalar(stiffness, "stiffness", positive=True)
    ne = getscalar(exponent, "exponent", positive=True)
    ce = getscalar(restitution, "restitution", positive=True)
    if ce > 1:
        raise InputError(f"restitution must lie in (0, 1], got {ce}", name="restitution",
                         value=ce)
    revolutions = getint(revolutions, "revolutions", minimum=1)
    return w, delta, K, ne, ce, revolutions


def _flight_controls(revolutions, transient, min_flight, cluster_gap, max_events, rtol,
                     samples):
    """Checked numerical controls of :func:`free_flight`:
    ``(transient, min_flight, cluster_gap, max_events, rtol, samples)``."""
    transient = getint(transient, "transient", minimum=0)
    if transient >= revolutions:
        raise InputError(f"transient must be smaller than revolutions ({revolutions}), so "
                         f"that a revolution is left to analyse, got {transient} (transient=0 "
                         f"analyses from the start)",
                         name="transient", value=transient)
    min_flight = getscalar(min_flight, "min_flight", nonneg=True)
    cluster_gap = getscalar(cluster_gap, "cluster_gap", nonneg=True)
    for name, v in (("min_flight", min_flight), ("cluster_gap", cluster_gap)):
        if v > 2 * math.pi:
            raise InputError(f"{name} must be a crank angle in [0, 2 pi] rad, got {v:g} rad "
                             f"(the value is in rad, not deg)", name=name, value=v)
    max_events = getint(max_events, "max_events", minimum=1)
    rtol = getscalar(rtol, "rtol")
    if not 1e-13 <= rtol < 1.0:
        raise InputError(f"rtol must be a relative tolerance in [1e-13, 1) (solve_ivp does "
                         f"not go below 100 machine epsilons), got {rtol:g}", name="rtol",
                         value=rtol)
    samples = getint(samples, "samples", minimum=2)
    return transient, min_flight, cluster_gap, max_events, rtol, samples


def _flight_start(link, w, delta):
    """Start of the integration, ``(t10, y0)``: the crank angle of the largest
    zero-clearance force and the coupler/rocker state ``[th2, th2d, th3, th3d]``
    there with the pin in contact."""
    cc = continuous_contact(link, w, delta, speed_unit="rad/s", n=3600)
    i0 = int(np.argmax(cc.R0))
    t10 = float(cc.crank_angle[i0])
    z1 = np.zeros(1)
    a_0 = np.array([cc.alpha[i0]])
    th2, th3, th2d, th3d, _, _, _ = _kinematics(link, np.array([t10]), w, delta, a_0, z1, z1)
    # pin on the clearance circle in the force direction, zero penetration: the
    # compressive load builds up within a few contact periods
    y0 = np.array([th2[0], th2d[0], th3[0], th3d[0]])
    return t10, y0


def _flight_equations(link, w, delta, t10, K, ne, ce):
    """Equations of motion of the free pin, ``(geometry, rhs)``.

    ``geometry(t, y)`` returns ``(t1, u2, u3, n, p, pdot)``: crank angle, coupler and
    rocker unit vectors, contact normal (as ``(x, y)`` tuples), penetration
    ``|e| - delta`` and its rate.  ``rhs(t, y, vimp)`` is the state derivative;
    ``vimp`` is the approach speed of the current contact, or None in flight (no
    contact force).  Scalar arithmetic: these run some 10^5 times per revolution.
    """
    l1, l2, l3, l4 = link.crank, link.coupler, link.rocker, link.ground
    m2, m3, r2, r3, g = link.m_coupler, link.m_rocker, link.cg_coupler, link.cg_rocker, \
        link.gravity
    J2, J3 = link.J_coupler, link.J_rocker
    cos, sin, hypot = math.cos, math.sin, math.hypot

    def geometry(t, y):
        th2, th2d, th3, th3d = y
        t1 = t10 + w * t
        c1, s1, c2, s2, c3, s3 = cos(t1), sin(t1), cos(th2), sin(th2), cos(th3), sin(th3)
        # e = C(rocker) - C(coupler) = (D - l3 u3) - (l1 u1 + l2 u2)
        ex = l4 - l3 * c3 - l1 * c1 - l2 * c2
        ey = -l3 * s3 - l1 * s1 - l2 * s2
        de = hypot(ex, ey)
        nx, ny = (ex / de, ey / de) if de > 0 else (1.0, 0.0)
        # velocity of C(rocker) minus that of C(coupler), along n
        vx = l3 * th3d * s3 + l1 * w * s1 + l2 * th2d * s2
        vy = -l3 * th3d * c3 - l1 * w * c1 - l2 * th2d * c2
        return t1, (c2, s2), (c3, s3), (nx, ny), de - delta, vx * nx + vy * ny

    def rhs(t, y, vimp):
        t1, u2, u3, n, p, pdot = geometry(t, y)
        F = 0.0
        if vimp is not None and p > 0:
            F = K * p ** ne * (1.0 + 0.75 * (1.0 - ce * ce) * pdot / max(vimp, 1e-9))
            F = max(F, 0.0)
        Fx, Fy = F * n[0], F * n[1]
        mz2 = l2 * (u2[0] * Fy - u2[1] * Fx)                        # (l2 u2) x F
        mz3 = l3 * (u3[0] * Fy - u3[1] * Fx)                        # (-l3 u3) x (-F)
        dd2 = (mz2 + m2 * r2 * l1 * w * w * sin(t1 - y[0])
               - m2 * g * r2 * cos(y[0])) / J2
        dd3 = (mz3 + m3 * g * (l3 - r3) * cos(y[2])) / J3
        return [y[1], dd2, y[3], dd3]

    return geometry, rhs


def _integrate_flight(geometry, rhs, y0, T_total, w, delta, rtol, max_events, settle=0.0):
    """Integrate from contact at t = 0 to ``T_total``, switching between contact
    (LSODA) and flight (RK45) at the gap events, then on until the pin has stayed in
    contact for ``settle`` after its last impact (at most one more revolution), so
    that an episode that starts before ``T_total`` is complete.

    The solver's horizon is always ``T_total`` plus one revolution, the stop is an
    event and the first step is fixed, so a run is the exact beginning of any longer
    one.

    Returns ``(segs, switches, status, message)``: segments ``(t0, t1, dense, in_contact,
    vimp)`` and switches ``(t, onset, |pdot|)``.
    """
    from scipy.integrate import solve_ivp

    period = 2 * math.pi / w
    T_cap = T_total + period

    # the gap a segment starts from: its switch event fires when the gap
    # crosses a level just beyond it, so that a start on the wall (the gap
    # zero to rounding, on either side) cannot hide the next crossing
    level = {"p": 0.0}
    eps = 1e-9 * delta

    def ev_gap(t, y, vimp):
        return geometry(t, y)[4] - level["p"]

    t = 0.0
    y = y0
    in_contact = True
    t_onset = -math.inf
    pd_init = geometry(0.0, y0)[5]
    vimp = max(abs(pd_init), 1e-6)
    segs = []
    switches = []
    status, message = FlightStatus.OK, "completed"
    atol = np.array([1e-9, 1e-6, 1e-9, 1e-6]) * max(delta / 1e-4, 1e-3)
    while t < T_cap:
        p0 = geometry(t, y)[4]
        level["p"] = min(p0, 0.0) - eps if in_contact else max(p0, 0.0) + eps
        ev = (lambda tt, yy, v: ev_gap(tt, yy, v))
        ev.terminal = True
        ev.direction = -1.0 if in_contact else 1.0
        events = [ev]
        if in_contact:
            t_stop = max(T_total, t_onset + settle)
            if t >= t_stop:
                break
            stop = (lambda tt, yy, v, ts=t_stop: tt - ts)
            stop.terminal = True
            events.append(stop)
        sol = solve_ivp(rhs, (t, T_cap), y, method="LSODA" if in_contact else "RK45",
                        events=events, args=(vimp if in_contact else None,), rtol=rtol,
                        atol=atol, dense_output=True, max_step=period / 720,
                        first_step=period * 1e-6)
        if sol.status == -1:
            status, message = FlightStatus.NOT_CONVERGED, sol.message
            break
        segs.append((float(sol.t[0]), float(sol.t[-1]), sol.sol, in_contact, vimp))
        if not in_contact:
            deep = max(geometry(tt, yy)[4] for tt, yy in zip(sol.t, sol.y.T))
            if deep > max(1e-3 * delta, 10 * eps):
                status = FlightStatus.NOT_CONVERGED
                message = (f"an impact was missed: the pin went {deep:.3g} m into the bush "
                           f"wall in free flight at t = {sol.t[-1]:.4g} s; lower rtol "
                           f"(now {rtol:g})")
                break
        if sol.status == 1 and sol.t_events[0].size:
            te = float(sol.t_events[0][0])
            ye = sol.y_events[0][0]
            _, _, _, _, _, pdot = geometry(te, ye)
            switches.append((te, not in_contact, abs(pdot)))
            # step just past the event so that it does not re-trigger
            t = te
            y = ye
            if in_contact:
                in_contact = False
            else:
                in_contact = True
                t_onset = te
                vimp = max(abs(pdot), 1e-6)
            if len(switches) > max_events:
                status, message = FlightStatus.MAX_EVENTS, f"more than {max_events} switches"
                break
            nudge = 1e-12 * period
            y = y + nudge * np.array(rhs(t, y, vimp if in_contact else None))
            t = t + nudge
        else:
            if sol.status == 0 and not in_contact:
                message = ("completed; the pin was still in flight one revolution after the "
                           "end, so the last episode is not reported")
            break
    return segs, switches, status, message


def _resample_flight(segs, geometry, T_last, T_total, samples, K, ne, ce):
    """Gap and contact force at ``samples`` times over the last revolution, from the
    dense outputs of the segments: ``(tq, gap, force)``."""
    t_end = segs[-1][1] if segs else 0.0
    tq = np.linspace(T_last, min(T_total, t_end), int(samples))
    starts = np.array([sg[0] for sg in segs])
    gap = np.empty(tq.size)
    force = np.empty(tq.size)
    for k, tt in enumerate(tq):
        j = int(np.clip(np.searchsorted(starts, tt, side="right") - 1, 0, len(segs) - 1))
        _, _, dense, inc, vi = segs[j]
        yy = dense(tt)
        _, _, _, _, p, pdot = geometry(tt, yy)
        gap[k] = p
        force[k] = max(K * p ** ne * (1 + 0.75 * (1 - ce * ce) * pdot / max(vi, 1e-9)),
                       0.0) if (p > 0 and inc) else 0.0
    return tq, gap, force


def _flight_episodes(switches, T_first, T_end, w, cluster_gap):
    """Flights ``(separation t, impact t, impact speed)`` grouped into episodes (lists
    of flights less than ``cluster_gap`` of crank angle apart), over the whole run;
    the episodes whose first separation lies in ``[T_first, T_end)``."""
    flights = []
    for k, (te, onset, v) in enumerate(switches):
        if onset:
            continue
        nxt = next(((t2, v2) for t2, on2, v2 in switches[k + 1:] if on2), None)
        if nxt is not None:
            flights.append((te, nxt[0], nxt[1]))
    episodes = []
    for f in flights:
        if episodes and (f[0] - episodes[-1][-1][1]) * w < cluster_gap:
            episodes[-1].append(f)
        else:
            episodes.append([f])
    return [ep for ep in episodes if T_first <= ep[0][0] < T_end]


def _flight_events(episodes, t10, w, min_flight):
    """The episodes with at least ``min_flight`` of free flight, as FlightEvents with
    crank angles in [0, 2 pi)."""
    wrap = lambda tt: float((t10 + w * tt) % (2 * math.pi))  # noqa: E731
    events = []
    for ep in episodes:
        flight = sum((b - a) * w for a, b, _ in ep)
        if flight < min_flight:
            continue
        strongest = max(ep, key=lambda f: f[2])
        events.append(FlightEvent(wrap(ep[0][0]), wrap(ep[0][1]), wrap(strongest[1]),
                                  wrap(ep[-1][1]), len(ep), float(flight),
                                  float(strongest[2]), int(w * ep[0][0] // (2 * math.pi))))
    return tuple(events)


def free_flight(link: ClearanceLinkage, speed, clearance, *, speed_unit: str = "rpm",
                revolutions: int = 3, transient: int = 1, stiffness: float | None = None,
                exponent: float = 1.5, restitution: float = 0.9,
                min_flight: float = math.radians(0.5), cluster_gap: float = math.radians(5.0),
                max_events: int = 20000, rtol: float = 1e-8,
                samples: int = 3600) -> FreeFlightResult:
    """Pin free flight inside the clearance with Lankarani-Nikravesh impacts.

    The coupler turns about B (driven crank at constant speed), the rocker about D;
    their only coupling is the contact force at C.  The integration starts in
    contact at the crank angle of the largest zero-clearance force and runs
    ``revolutions`` turns.  The first ``transient`` of them are the start-up
    transient and are discarded; the contact-loss episodes that start in the others
    are reported, each followed to its end (past the last revolution if need be).

    The impact train after a contact loss is sensitive to the state at the loss
    (a change of 1e-9 in the initial state, or of ``rtol``, changes it after a few
    impacts): the separation and first impact angles are reproducible, the
    strongest impact and the number of impacts vary from revolution to revolution.
    Use several analysed revolutions and :meth:`FreeFlightResult.spread` for them.

    Parameters
    ----------
    link : ClearanceLinkage
    speed : float
        Crank speed in ``speed_unit`` ("rpm" or "rad/s"), constant.
    clearance : float, m
        Radial clearance, > 0.
    revolutions : int, >= 1
        Crank revolutions integrated (including the transient).
    transient : int, in [0, revolutions)
        Leading revolutions discarded.
    stiffness : float, N/m^exponent, optional
        Default :func:`hertz_stiffness` of a steel pin in a 13 mm steel bush.
    restitution : float in (0, 1]
        Coefficient of restitution of the hysteresis damping.
    min_flight : float, rad, in [0, 2 pi]
        Episodes with less total free flight are not reported.
    cluster_gap : float, rad, in [0, 2 pi]
        Flights closer than this (crank angle between an impact and the next
        separation) belong to one episode.
    max_events : int, >= 1
        Safety cap on contact switches.
    rtol : float, in [1e-13, 1)
        solve_ivp relative tolerance (absolute tolerances are scaled to the
        clearance).
    samples : int, >= 2
        Output samples over the last revolution.

    Returns
    -------
    FreeFlightResult
    """
    w, delta, K, ne, ce, revolutions = _flight_args(link, speed, clearance, speed_unit,
                                                    stiffness, exponent, restitution,
                                                    revolutions)
    transient, min_flight, cluster_gap, max_events, rtol, samples = _flight_controls(
        revolutions, transient, min_flight, cluster_gap, max_events, rtol, samples)
    t10, y0 = _flight_start(link, w, delta)
    geometry, rhs = _flight_equations(link, w, delta, t10, K, ne, ce)
    period = 2 * math.pi / w
    T_total = revolutions * period
    T_last = (revolutions - 1) * period
    segs, switches, status, message = _integrate_flight(geometry, rhs, y0, T_total, w, delta,
                                                        rtol, max_events, cluster_gap / w)
    tq, gap, force = _resample_flight(segs, geometry, T_last, T_total, samples, K, ne, ce)
    episodes = _flight_episodes(switches, transient * period, T_total, w, cluster_gap)
    events = _flight_events(episodes, t10, w, min_flight)
    return FreeFlightResult(link, w, delta, K, ne, ce, t10 + w * tq, force, gap,
                            events, len(switches), status, message, revolutions, transient)
