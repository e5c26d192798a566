"""Planar four-bar kinematics over arrays of input angles.

Conventions
-----------
* Ground pivots ``A`` (crank) and ``D`` (rocker); ``l1 = |D - A|`` is the ground
  length and ``theta1`` the direction of ``A -> D``.
* ``l2`` crank ``A -> B``, ``l3`` coupler ``B -> C``, ``l4`` rocker ``D -> C``.
  ``theta2``, ``theta3``, ``theta4`` are the world directions (rad, counter-clockwise
  from +x) of ``A -> B``, ``B -> C`` and ``D -> C``.
* The coupler point is ``P = B + lp (cos(theta3 + alpha), sin(theta3 + alpha))``.
* Assembly branch: :attr:`Assembly.OPEN` puts ``C`` to the left of the directed line
  ``B -> D`` (branch ``+1`` of :func:`cspace.geom2d.circle_circle`), which for a
  ground drawn ``A -> D`` along +x and the crank above it is the convex (open)
  quadrilateral; :attr:`Assembly.CROSSED` puts it to the right.  ``C`` can change side
  of ``B -> D`` only when coupler and rocker are collinear (a toggle), so holding
  the side fixed *is* continuation along the input: the branch never jumps.  Poses
  that come near a toggle are flagged :attr:`PoseStatus.NEAR_TOGGLE`; poses past it
  are :attr:`PoseStatus.UNASSEMBLABLE`.

Everything is in radians and model length units; degrees only through
``unit="deg"``.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np

from cspace import geom2d
from cspace.argcheck import getangle, getangles, getpoint, getscalar
from cspace.errors import DegenerateGeometryError, InputError

__all__ = [
    "Assembly", "GrashofType", "PoseStatus", "LinkageTolerances", "FourBar",
    "FourBarMotion", "InputRange", "grashof", "solve", "input_range",
]


class Assembly(enum.IntEnum):
    """Assembly branch; the value is the :func:`cspace.geom2d.circle_circle` branch."""

    OPEN = 1      #: C left of B -> D
    CROSSED = -1  #: C right of B -> D


class GrashofType(enum.Enum):
    """Grashof classification (s + l vs p + q) and which link is the shortest."""

    CRANK_ROCKER = "crank-rocker"        #: Grashof, crank shortest
    DOUBLE_CRANK = "double-crank"        #: Grashof, ground shortest
    DOUBLE_ROCKER = "double-rocker"      #: Grashof, coupler shortest
    ROCKER_CRANK = "rocker-crank"        #: Grashof, rocker shortest (crank rocks)
    CHANGE_POINT = "change-point"        #: s + l == p + q (can fold flat)
    TRIPLE_ROCKER = "triple-rocker"      #: non-Grashof

    @property
    def crank_fully_rotates(self) -> bool:
        """True when the input link can make full turns relative to the ground."""
        return self in (GrashofType.CRANK_ROCKER, GrashofType.DOUBLE_CRANK)


class PoseStatus(enum.IntEnum):
    """Per-pose status of a kinematic solution."""

    OK = 0             #: assembled, well conditioned
    NEAR_TOGGLE = 1    #: assembled but |sin(transmission angle)| < tolerance
    UNASSEMBLABLE = 2  #: the coupler and rocker circles do not meet


@dataclass(frozen=True)
class LinkageTolerances:
    """Named numeric thresholds of the linkage analyses.

    Attributes
    ----------
    toggle_sin : float
        A pose whose transmission angle mu (between coupler and rocker) has
        ``|sin mu| < toggle_sin`` is NEAR_TOGGLE.  First-order sensitivities scale
        with ``1/sin mu``, so at 1e-3 they are amplified 1000-fold and a linear
        error model is no longer trustworthy for clearances above ~1e-6 of the
        link lengths.
    dead_centre_sin : float
        ``|sin(theta3 - theta2)|`` below which crank and coupler are collinear
        (rocker at an extreme; a dead centre when the rocker drives).
    tangent_rel : float
        Relative tolerance of the circle-circle tangency test (see
        :func:`cspace.geom2d.circle_circle`).
    grashof_rel : float
        Relative tolerance (of the total link length) for ``s + l == p + q``.
    """

    toggle_sin: float = 1e-3
    dead_centre_sin: float = 1e-3
    tangent_rel: float = 1e-12
    grashof_rel: float = 1e-9

    def __post_init__(self):
        for name in ("toggle_sin", "dead_centre_sin", "tangent_rel", "grashof_rel"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and 0.0 < float(v) < 1.0):
                raise InputError(f"LinkageTolerances.{name} must be a float in (0, 1), "
                                 f"got {v!r}", name=name, value=v)


DEFAULT_TOL = LinkageTolerances()


def check_tolerances(tol) -> LinkageTolerances:
    """``tol`` when it is a :class:`LinkageTolerances`; anything else (a bare
    number, None) raises :class:`~cspace.errors.InputError`."""
    if not isinstance(tol, LinkageTolerances):
        raise InputError(f"tol must be a LinkageTolerances (e.g. LinkageTolerances("
                         f"toggle_sin=1e-4)), got {type(tol).__name__} {tol!r}", name="tol",
                         value=tol)
    return tol


def as_assembly(value) -> Assembly:
    """``value`` as an :class:`Assembly`: an Assembly, ``"open"``/``"crossed"`` (any case)
    or +1/-1; anything else raises :class:`~cspace.errors.InputError`."""
    if isinstance(value, Assembly):
        return value
    if isinstance(value, str):
        try:
            return Assembly[value.upper()]
        except KeyError:
            pass
    elif isinstance(value, (int, np.integer)) and not isinstance(value, bool) and value in (1, -1):
        return Assembly(int(value))
    raise InputError(f"assembly must be Assembly.OPEN/CROSSED, 'open'/'crossed' or +1/-1; "
                     f"got {value!r}", name="assembly", value=value)


@dataclass(frozen=True)
class FourBar:
    """A planar four-bar linkage (a value; variants are new values).

    Attributes
    ----------
    A, D : tuple of 2 float, length units
        Crank and rocker ground pivots.
    crank, coupler, rocker : float, length units
        ``l2 = |AB|``, ``l3 = |BC|``, ``l4 = |DC|`` (> 0).
    lp : float, length units
        Distance of the coupler point P from B (>= 0).
    alpha : float, rad
        Angle of ``B -> P`` measured from ``B -> C``.
    assembly : Assembly
        The assembly branch, held fixed along any motion.

    Examples
    --------
    >>> fb = FourBar.from_lengths(13.55, 8, 5.25, 13.3, lp=3.816, alpha=38,
    ...                           assembly="crossed", unit="deg")
    >>> round(fb.ground, 2)
    13.55
    """

    A: tuple
    D: tuple
    crank: float
    coupler: float
    rocker: float
    lp: float = 0.0
    alpha: float = 0.0
    assembly: Assembly = Assembly.OPEN

    def __post_init__(self):
        A = getpoint(self.A, "A")
        D = getpoint(self.D, "D")
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "D", D)
        for name in ("crank", "coupler", "rocker"):
            object.__setattr__(self, name, getscalar(getattr(self, name), name, positive=True))
        object.__setattr__(self, "lp", getscalar(self.lp, "lp", nonneg=True))
        object.__setattr__(self, "alpha", _within_a_turn(getscalar(self.alpha, "alpha"),
                                                         "alpha"))
        object.__setattr__(self, "assembly", as_assembly(self.assembly))
        scale = self.crank + self.coupler + self.rocker
        if math.hypot(D[0] - A[0], D[1] - A[1]) <= 1e-12 * scale:
            raise DegenerateGeometryError(
                f"ground pivots A and D must be distinct points; got A={A}, D={D}",
                where="FourBar.ground")
        links = {"ground": self.ground, "crank": self.crank, "coupler": self.coupler,
                 "rocker": self.rocker}
        name, longest = max(links.items(), key=lambda kv: kv[1])
        rest = sum(links.values()) - longest
        if longest >= rest:
            raise DegenerateGeometryError(
                f"the {name} ({longest:g}) must be shorter than the other three links together "
                f"({rest:g}): the loop closes at no crank angle (links {links})",
                where="FourBar")

    @classmethod
    def from_lengths(cls, ground, crank, coupler, rocker, lp=0.0, alpha=0.0, *,
                     ground_angle=0.0, A=(0.0, 0.0), assembly=Assembly.OPEN,
                     unit: str = "rad") -> "FourBar":
        """Build from the four link lengths (``l1..l4``) and the ground direction.

        ``alpha`` and ``ground_angle`` are in ``unit`` ("rad" or "deg").
        """
        l1 = getscalar(ground, "ground", positive=True)
        t1 = _within_a_turn(getangle(ground_angle, unit, "ground_angle"), "ground_angle", unit)
        a = _within_a_turn(getangle(alpha, unit, "alpha"), "alpha", unit)
        A = getpoint(A, "A")
        D = (A[0] + l1 * math.cos(t1), A[1] + l1 * math.sin(t1))
        return cls(A, D, crank, coupler, rocker, lp, a, assembly)

    # -- derived values -------------------------------------------------
    @property
    def ground(self) -> float:
        """``l1 = |AD|``, length units."""
        return math.hypot(self.D[0] - self.A[0], self.D[1] - self.A[1])

    @property
    def theta1(self) -> float:
        """Direction of ``A -> D``, rad."""
        return math.atan2(self.D[1] - self.A[1], self.D[0] - self.A[0])

    @property
    def lengths(self) -> tuple:
        """``(l1, l2, l3, l4)``."""
        return (self.ground, self.crank, self.coupler, self.rocker)

    def replace(self, **changes) -> "FourBar":
        """A variant with some fields changed; ``ground=`` rescales ``A -> D``.

        The fields are those of :class:`FourBar` (``alpha`` in rad) and
        ``ground``; any other name raises :class:`~cspace.errors.InputError`.
        """
        import dataclasses
        allowed = tuple(f.name for f in dataclasses.fields(self)) + ("ground",)
        unknown = [k for k in changes if k not in allowed]
        if unknown:
            raise InputError(f"FourBar.replace takes the fields {allowed}; got "
                             f"{', '.join(map(repr, unknown))}", name=unknown[0],
                             value=changes[unknown[0]])
        if "ground" in changes:
            l1 = getscalar(changes.pop("ground"), "ground", positive=True)
            t1 = self.theta1
            A = getpoint(changes.get("A", self.A), "A")
            changes["D"] = (A[0] + l1 * math.cos(t1), A[1] + l1 * math.sin(t1))
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        return {"A": list(self.A), "D": list(self.D), "crank": self.crank,
                "coupler": self.coupler, "rocker": self.rocker, "lp": self.lp,
                "alpha": self.alpha, "assembly": self.assembly.name.lower()}

    def __repr__(self):
        return (f"FourBar(l1={self.ground:.6g}, l2={self.crank:.6g}, l3={self.coupler:.6g}, "
                f"l4={self.rocker:.6g}, lp={self.lp:.6g}, alpha={self.alpha:.6g} rad, "
                f"{self.assembly.name.lower()})")


def _within_a_turn(a: float, name: str, unit: str = "rad") -> float:
    """A fixed angle of a linkage (rad), refused beyond a turn either way: one
    written in degrees where radians are read."""
    if abs(a) > 2 * math.pi + 1e-9:
        hint = (f"; written in degrees? pass unit='deg' (radians({a:g}) = {math.radians(a):.6g})"
                if unit == "rad" else "")
        raise InputError(f"{name} must lie within a turn, |{name}| <= 2 pi rad, got {a:g} rad"
                         f"{hint}", name=name, value=a)
    return a


def grashof(fb: FourBar, *, tol: LinkageTolerances = DEFAULT_TOL) -> GrashofType:
    """Grashof type of ``fb`` with the crank (``l2``) as input link."""
    if not isinstance(fb, FourBar):
        raise InputError(f"grashof expects a FourBar, got {type(fb).__name__}", name="fb")
    ls = {"ground": fb.ground, "crank": fb.crank, "coupler": fb.coupler, "rocker": fb.rocker}
    vals = sorted(ls.values())
    s, l = vals[0], vals[-1]
    p, q = vals[1], vals[2]
    total = sum(vals)
    if abs((s + l) - (p + q)) <= tol.grashof_rel * total:
        return GrashofType.CHANGE_POINT
    if s + l > p + q:
        return GrashofType.TRIPLE_ROCKER
    shortest = min(ls, key=ls.get)
    return {"crank": GrashofType.CRANK_ROCKER, "ground": GrashofType.DOUBLE_CRANK,
            "coupler": GrashofType.DOUBLE_ROCKER, "rocker": GrashofType.ROCKER_CRANK}[shortest]


@dataclass(frozen=True)
class FourBarMotion:
    """Positions, velocities and accelerations of a four-bar over input angles.

    All arrays have the shape ``(n,)`` (points ``(n, 2)``) of the flattened input.

    Attributes
    ----------
    fourbar : FourBar
    theta2, omega2, alpha2 : (n,) float, rad, rad/s, rad/s^2
        Input angle, speed and acceleration.
    theta3, theta4 : (n,) float, rad
        Coupler and rocker angles (unwrapped along the input sequence).
    omega3, omega4 : (n,) float, rad/s
    alpha3, alpha4 : (n,) float, rad/s^2
    B, C, P : (n, 2) float, length units
        Joint positions and the coupler point.
    vP, aP : (n, 2) float, length/s and length/s^2
        Velocity and acceleration of P.
    transmission : (n,) float, rad
        Transmission angle ``theta4 - theta3`` wrapped to [0, pi].
    status : (n,) int
        :class:`PoseStatus` values.  Velocities and accelerations are 0 where the
        pose is UNASSEMBLABLE (positions are then the nearest near-miss), and finite
        but large near a toggle.
    dead_centre : (n,) bool
        Crank and coupler collinear within ``tol.dead_centre_sin``.
    toggle : (n,) bool
        Pose exactly at a toggle (coupler and rocker collinear: the circles are
        tangent within ``tol.tangent_rel``; status NEAR_TOGGLE).  The positions
        are valid; the rates are unbounded there, so ``omega3``, ``omega4``,
        ``alpha3``, ``alpha4`` and the components of ``vP``, ``aP`` that grow
        without bound read ``+inf`` or ``-inf``, the sign of their limit as the
        input approaches the toggle on the assembly branch (0 when the input is
        at rest, ``omega2 = alpha2 = 0``).  Never NaN.  A change point (a
        linkage that :func:`grashof` calls ``CHANGE_POINT``, at the crank angle
        where all four links lie in line) is a toggle too, but there the two
        branches cross: each has finite rates, different on the two sides of
        it, and the values read at that pose (0, or +-inf within the tangency
        tolerance) are neither branch's.
    """

    fourbar: FourBar
    theta2: np.ndarray
    omega2: np.ndarray
    alpha2: np.ndarray
    theta3: np.ndarray
    theta4: np.ndarray
    omega3: np.ndarray
    omega4: np.ndarray
    alpha3: np.ndarray
    alpha4: np.ndarray
    B: np.ndarray
    C: np.ndarray
    P: np.ndarray
    vP: np.ndarray
    aP: np.ndarray
    transmission: np.ndarray
    status: np.ndarray
    dead_centre: np.ndarray
    toggle: np.ndarray = None

    def __post_init__(self):
        if self.toggle is None:
            object.__setattr__(self, "toggle", np.zeros(np.shape(self.status), dtype=bool))

    @property
    def ok(self) -> np.ndarray:
        """Boolean mask of poses with status OK."""
        return self.status == PoseStatus.OK

    @property
    def success(self) -> bool:
        """True when every pose is assembled (OK or NEAR_TOGGLE)."""
        return bool(np.all(self.status != PoseStatus.UNASSEMBLABLE))

    def __len__(self):
        return int(self.theta2.shape[0])

    def __repr__(self):
        counts = {s.name: int(np.sum(self.status == s)) for s in PoseStatus}
        k = int(np.sum(self.toggle))
        note = f", {k} exactly at a toggle (rates infinite there)" if k else ""
        return f"FourBarMotion(n={len(self)}, {counts}{note})"

    def to_dict(self) -> dict:
        d = {"fourbar": self.fourbar.to_dict()}
        for k in ("theta2", "omega2", "alpha2", "theta3", "theta4", "omega3", "omega4",
                  "alpha3", "alpha4", "B", "C", "P", "vP", "aP", "transmission",
                  "dead_centre", "toggle"):
            d[k] = np.asarray(getattr(self, k)).tolist()
        d["status"] = [PoseStatus(int(s)).name for s in self.status]
        return d


def loop_positions(fb: FourBar, theta2, tol: LinkageTolerances):
    """Vectorised loop positions at input angles ``theta2`` (rad); trusts its input.

    Returns B, C, theta3, theta4, status, s34 (``sin(theta3 - theta4)``).  At a
    toggle (the coupler and rocker circles tangent, C clamped to the double
    point) ``s34`` is exactly 0: the value computed there is round-off.
    """
    A = np.asarray(fb.A)
    D = np.asarray(fb.D)
    u2 = np.stack([np.cos(theta2), np.sin(theta2)], -1)
    B = A + fb.crank * u2
    C, kind = geom2d.circle_circle(B, fb.coupler, D, fb.rocker, int(fb.assembly),
                                   tol=tol.tangent_rel)
    t3 = np.arctan2(C[..., 1] - B[..., 1], C[..., 0] - B[..., 0])
    t4 = np.arctan2(C[..., 1] - D[1], C[..., 0] - D[0])
    s34 = np.where(kind == geom2d.IntersectionKind.TANGENT, 0.0, np.sin(t3 - t4))
    status = np.full(np.shape(theta2), PoseStatus.OK, dtype=int)
    status = np.where(np.abs(s34) < tol.toggle_sin, PoseStatus.NEAR_TOGGLE, status)
    bad = (kind == geom2d.IntersectionKind.NONE) | (kind == geom2d.IntersectionKind.COINCIDENT)
    status = np.where(bad, PoseStatus.UNASSEMBLABLE, status)
    return B, C, t3, t4, status, s34


def solve(fb: FourBar, theta2, omega2=1.0, alpha2=0.0, *, unit: str = "rad",
          tol: LinkageTolerances = DEFAULT_TOL) -> FourBarMotion:
    """Positions, velocities and accelerations of ``fb`` for input angles ``theta2``.

    Parameters
    ----------
    fb : FourBar
    theta2 : float or array, rad (or ``unit``)
        World direction of the crank ``A -> B``.  A sequence is treated as a path:
        ``theta3``/``theta4`` are unwrapped along it.
    omega2 : float or array broadcastable to ``theta2``, rad/s
        Crank angular velocity (``unit`` does not apply: always rad/s).
    alpha2 : float or array, rad/s^2
        Crank angular acceleration.
    unit : {"rad", "deg"}
        Unit of ``theta2``.
    tol : LinkageTolerances

    Returns
    -------
    FourBarMotion
        At a pose exactly at a toggle (``FourBarMotion.toggle``) the rates are
        unbounded and read ``+-inf`` (the sign of their limit along the branch);
        the positions there are valid.
    """
    if not isinstance(fb, FourBar):
        raise InputError(f"solve expects a FourBar, got {type(fb).__name__}", name="fb")
    tol = check_tolerances(tol)
    th2 = getangles(theta2, unit, "theta2")
    if th2.ndim > 1:
        raise InputError(f"theta2 must be one angle or a 1-D array of them, got an array of "
                         f"shape {th2.shape}", name="theta2", value=theta2)
    th2 = np.ravel(th2)
    if th2.size == 0:
        raise InputError("theta2 must hold at least one angle, got an empty array",
                         name="theta2", value=theta2)
    try:
        w2 = np.broadcast_to(np.asarray(omega2, dtype=float), np.shape(theta2)).ravel()
        a2 = np.broadcast_to(np.asarray(alpha2, dtype=float), np.shape(theta2)).ravel()
    except (ValueError, TypeError):
        raise InputError(f"omega2 and alpha2 must be numbers or arrays broadcastable to "
                         f"theta2's shape {np.shape(theta2)}", name="omega2") from None
    if not (np.all(np.isfinite(w2)) and np.all(np.isfinite(a2))):
        raise InputError("omega2 and alpha2 must be finite", name="omega2")
    B, C, t3, t4, status, s34 = loop_positions(fb, th2, tol)
    assembled = status != PoseStatus.UNASSEMBLABLE
    l2, l3, l4 = fb.crank, fb.coupler, fb.rocker
    safe = np.where(assembled & (s34 != 0.0), s34, 1.0)
    # velocity loop: l2 w2 perp(u2) + l3 w3 perp(u3) = l4 w4 perp(u4)
    w3 = l2 * w2 * np.sin(t4 - th2) / (l3 * safe)
    w4 = l2 * w2 * np.sin(t3 - th2) / (l4 * safe)
    # acceleration loop: l3 a3 perp(u3) - l4 a4 perp(u4) = K
    u2 = np.stack([np.cos(th2), np.sin(th2)], -1)
    u3 = np.stack([np.cos(t3), np.sin(t3)], -1)
    u4 = np.stack([np.cos(t4), np.sin(t4)], -1)
    K = (-l2 * (a2[:, None] * geom2d.perp(u2) - (w2 ** 2)[:, None] * u2)
         + l3 * (w3 ** 2)[:, None] * u3 - l4 * (w4 ** 2)[:, None] * u4)
    a4 = -geom2d.dot2(K, u3) / (l4 * safe)
    a3 = -geom2d.dot2(K, u4) / (l3 * safe)
    zero = ~assembled
    w3, w4, a3, a4 = (np.where(zero, 0.0, x) for x in (w3, w4, a3, a4))
    up = np.stack([np.cos(t3 + fb.alpha), np.sin(t3 + fb.alpha)], -1)
    P = B + fb.lp * up
    vB = l2 * w2[:, None] * geom2d.perp(u2)
    aB = l2 * (a2[:, None] * geom2d.perp(u2) - (w2 ** 2)[:, None] * u2)
    vP = vB + fb.lp * w3[:, None] * geom2d.perp(up)
    aP = aB + fb.lp * (a3[:, None] * geom2d.perp(up) - (w3 ** 2)[:, None] * up)
    vP = np.where(zero[:, None], 0.0, vP)
    aP = np.where(zero[:, None], 0.0, aP)
    toggle = assembled & (s34 == 0.0)
    if toggle.any():
        # exactly at a toggle sin(theta3 - theta4) = 0 and the rates are
        # unbounded: each is a polynomial in q = 1/sin(theta3 - theta4), and
        # q -> +-inf with the sign sin(theta3 - theta4) keeps on the branch
        # (C left of B -> D makes it negative)
        sig = -float(int(fb.assembly))
        n3 = l2 * w2 * np.sin(t4 - th2) / l3           # omega3 = n3 q
        n4 = l2 * w2 * np.sin(t3 - th2) / l4           # omega4 = n4 q
        Kf = -l2 * (a2[:, None] * geom2d.perp(u2) - (w2 ** 2)[:, None] * u2)
        Kl = l3 * (n3 ** 2)[:, None] * u3 - l4 * (n4 ** 2)[:, None] * u4   # K = Kf + Kl q^2
        zero1 = np.zeros_like(n3)
        a3c = (zero1, -geom2d.dot2(Kf, u4) / l3, zero1, -geom2d.dot2(Kl, u4) / l3)
        a4c = (zero1, -geom2d.dot2(Kf, u3) / l4, zero1, -geom2d.dot2(Kl, u3) / l4)
        vB = l2 * w2[:, None] * geom2d.perp(u2)
        aB = l2 * (a2[:, None] * geom2d.perp(u2) - (w2 ** 2)[:, None] * u2)
        pu = geom2d.perp(up)
        vPc = (vB, fb.lp * n3[:, None] * pu)
        aPc = (aB, fb.lp * a3c[1][:, None] * pu, -fb.lp * (n3 ** 2)[:, None] * up,
               fb.lp * a3c[3][:, None] * pu)
        tg, tg2 = toggle, toggle[:, None]
        w3 = np.where(tg, _unbounded_limit((zero1, n3), sig), w3)
        w4 = np.where(tg, _unbounded_limit((zero1, n4), sig), w4)
        a3 = np.where(tg, _unbounded_limit(a3c, sig), a3)
        a4 = np.where(tg, _unbounded_limit(a4c, sig), a4)
        vP = np.where(tg2, _unbounded_limit(vPc, sig), vP)
        aP = np.where(tg2, _unbounded_limit(aPc, sig), aP)
    mu = np.abs(geom2d.wrap_pi(t4 - t3))
    dead = np.abs(np.sin(t3 - th2)) < tol.dead_centre_sin
    if th2.size > 1:
        t3 = np.unwrap(t3)
        t4 = np.unwrap(t4)
    return FourBarMotion(fb, th2, w2, a2, t3, t4, w3, w4, a3, a4, B, C, P, vP, aP, mu,
                         status.astype(int), dead & assembled, toggle)


def _unbounded_limit(coefs, sign: float) -> np.ndarray:
    """The limit of ``sum_k coefs[k] q**k`` as ``|q| -> inf`` with ``q`` of sign
    ``sign``: ``+-inf`` by the highest non-zero coefficient, ``coefs[0]`` when
    every other is 0."""
    out = np.array(coefs[0], dtype=float, copy=True)
    for k in range(1, len(coefs)):
        c = np.asarray(coefs[k], dtype=float) * sign ** k
        out = np.where(c != 0.0, np.copysign(np.inf, c), out)
    return out


@dataclass(frozen=True)
class InputRange:
    """The interval(s) of crank angle over which ``fb`` assembles.

    A rocking crank of a linkage whose ``|BD|`` must stay between two toggles
    (``|l3 - l4|`` and ``l3 + l4``) assembles on two mirror intervals, one on
    each side of the ground line; the crank cannot pass from one to the other
    (it would have to pass a toggle it cannot cross).  :attr:`intervals` holds
    both; :attr:`limits` is the first of them.

    Attributes
    ----------
    full_turn : bool
        True when every crank angle assembles.
    limits : tuple of float, rad
        For a rocking crank, the two toggle angles ``(lo, hi)`` with ``lo <= hi``
        (``hi`` may exceed pi so that the interval is contiguous) of the first
        interval (the one at ``theta2 - theta1`` in ``(0, pi)`` when there are
        two); empty otherwise.
    intervals : tuple of (float, float), rad
        Every interval ``(lo, hi)`` on which the crank assembles, ``limits``
        first and the mirror interval (about the ground line) second when
        there is one; empty when ``full_turn`` (or when nothing assembles).
    """

    full_turn: bool
    limits: tuple = field(default=())
    intervals: tuple = field(default=())

    def __post_init__(self):
        limits = tuple(float(x) for x in self.limits)
        ivs = tuple((float(lo), float(hi)) for lo, hi in self.intervals)
        if not ivs and limits:
            ivs = (limits,)
        object.__setattr__(self, "limits", limits)
        object.__setattr__(self, "intervals", ivs)

    def contains(self, theta2, *, unit: str = "rad") -> np.ndarray:
        """Whether crank angles ``theta2`` (rad, or ``unit``; any shape) lie in
        one of the intervals (modulo a turn), limits included."""
        t = getangles(theta2, unit, "theta2")
        if self.full_turn:
            return np.ones(np.shape(t), dtype=bool)
        inside = np.zeros(np.shape(t), dtype=bool)
        for lo, hi in self.intervals:
            inside |= np.mod(t - lo + 1e-12, 2 * math.pi) <= (hi - lo) + 2e-12
        return inside

    def __repr__(self):
        if self.full_turn:
            return "InputRange(full turn)"
        if not self.intervals:
            return "InputRange(no crank angle assembles)"
        iv = ["[%.6g, %.6g] rad" % lo_hi for lo_hi in self.intervals]
        if len(iv) == 1:
            return f"InputRange(limits={iv[0]})"
        return (f"InputRange(limits={iv[0]}, and the mirror interval {iv[1]}: two "
                f"intervals, the crank cannot pass from one to the other)")

    def to_dict(self):
        return {"full_turn": self.full_turn, "limits": list(self.limits),
                "intervals": [list(iv) for iv in self.intervals]}


def input_range(fb: FourBar) -> InputRange:
    """Crank angles at which ``fb`` assembles (closed form from the B-D distance).

    The coupler-rocker dyad closes when ``|l3 - l4| <= |BD| <= l3 + l4``; ``|BD|``
    depends on the crank angle relative to the ground only.  When both bounds
    are reached the crank assembles on two mirror intervals (see
    :class:`InputRange`): ``theta2 - theta1`` in ``[p_lo, p_hi]`` and in
    ``[-p_hi, -p_lo]``.
    """
    if not isinstance(fb, FourBar):
        raise InputError(f"input_range expects a FourBar, got {type(fb).__name__} {fb!r}; "
                         "build one with FourBar.from_lengths(ground, crank, coupler, rocker)",
                         name="fb", value=fb)
    l1, l2, l3, l4 = fb.lengths
    lo_d, hi_d = abs(l3 - l4), l3 + l4
    eps = 1e-12
    # |BD|^2 = l1^2 + l2^2 - 2 l1 l2 cos(phi), phi = theta2 - theta1
    def phi_of(dist):
        c = (l1 * l1 + l2 * l2 - dist * dist) / (2 * l1 * l2)
        return None if abs(c) > 1 + eps else math.acos(min(max(c, -1.0), 1.0))
    p_hi = phi_of(hi_d)   # |BD| reaches l3 + l4 at phi = +-p_hi
    p_lo = phi_of(lo_d)
    # a bound |BD| only touches at phi = pi (the longest) or 0 (the shortest)
    # is a toggle the crank passes through, not a limit of its motion (a
    # change-point or parallelogram linkage turns fully)
    if p_hi is not None and p_hi >= math.pi - 1e-6:
        p_hi = None
    if p_lo is not None and p_lo <= 1e-6:
        p_lo = None
    if p_hi is None and p_lo is None:
        dmin, dmax = abs(l1 - l2), l1 + l2
        tol = eps * (l1 + l2 + l3 + l4)
        if dmin >= lo_d - tol and dmax <= hi_d + tol:
            return InputRange(True)
        return InputRange(False, ())
    t1 = fb.theta1
    if p_hi is not None and p_lo is None:
        return InputRange(False, (t1 - p_hi, t1 + p_hi))
    if p_lo is not None and p_hi is None:
        return InputRange(False, (t1 + p_lo, t1 + 2 * math.pi - p_lo))
    # both toggles exist: two separate mirror intervals, phi in [p_lo, p_hi] and
    # in [-p_hi, -p_lo]; limits keeps the first
    first = (t1 + p_lo, t1 + p_hi)
    return InputRange(False, first, (first, (t1 - p_hi, t1 - p_lo)))
