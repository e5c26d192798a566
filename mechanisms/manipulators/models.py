"""Model values of the two planar translational parallel manipulators.

Both manipulators carry a platform point P = (p_x, p_y) that only translates.  The
platform is held by two legs; each leg contains a parallelogram whose rotating links
have length ``la`` and make an angle ``theta_i`` with the leg's reference axis.

:class:`TwoPaP`
    Two rotary-actuated parallelograms with passive prismatic joints (2-PaP, [Kim 2007]
    Fig. 1).  The actuated angles are the joint variables ``q = (theta_1, theta_2)``
    and ``p = la (sin theta_1, sin theta_2)`` (Eq. 1).
:class:`TwoPPa`
    Two linear actuators, each carrying a passive parallelogram (2-PPa, Fig. 2).  The
    joint variables are the actuator displacements ``q = (d_1, d_2)`` in
    ``[0, stroke]``.  Each leg ``i`` is described by a base point ``g_i``, a unit
    actuator direction ``e_i`` and a unit lateral direction ``l_i`` (perpendicular to
    ``e_i``); its loop equation is ``p = g_i + d_i e_i + la s_i`` (Eq. 9 with the
    offsets ``a`` and ``b`` folded into ``g_i``), where the link direction is
    ``s_i = cos(theta_i) e_i + sin(theta_i) l_i``.

Builders validate input once (taking degrees through ``unit="deg"``); the model values
are frozen and check their own fields when constructed directly, in the internal units
(lengths, ``theta_limit`` in radians).  Evaluation is a pure function of (model, pose).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from cspace.argcheck import getangle, getscalar
from cspace.errors import InputError, InvalidModelError, NonFiniteError

__all__ = ["Arrangement", "TwoPaP", "TwoPPa", "two_pap", "two_ppa", "two_ppa_parallel"]


class Arrangement(enum.Enum):
    """How the two legs are placed."""

    DECOUPLED_ROTARY = "2-PaP"           #: 2-PaP, Oldham-like crossed passive slides
    PERPENDICULAR = "2-PPa perpendicular"  #: 2-PPa with perpendicular actuators (the paper's)
    PARALLEL = "2-PPa parallel"          #: 2-PPa with parallel actuators (Eq. 29, ref. 10)


@dataclass(frozen=True)
class TwoPaP:
    """2-PaP manipulator (rotary actuation).

    Attributes
    ----------
    la : float, length
        Length of the parallelogram's rotating links.
    theta_limit : float, rad
        Actuator range ``|theta_i| <= theta_limit`` (the paper's theta_L), in (0, pi/2).
    t, b : float, length
        Construction offsets used only by the design equations (Eqs. 7-8).
    """

    la: float
    theta_limit: float
    t: float = 0.0
    b: float = 0.0

    arrangement = Arrangement.DECOUPLED_ROTARY

    def __post_init__(self):
        _set(self, "la", getscalar(self.la, "la", positive=True))
        _set(self, "theta_limit", _theta_limit_rad(self.theta_limit, "TwoPaP", "two_pap"))
        _set(self, "t", getscalar(self.t, "t", nonneg=True))
        _set(self, "b", getscalar(self.b, "b", nonneg=True))

    @property
    def half_width(self) -> float:
        """Half-width w of the prescribed square workspace, ``la sin(theta_limit)`` (Eq. 6)."""
        return self.la * math.sin(self.theta_limit)

    def __repr__(self) -> str:
        return (f"TwoPaP(la={self.la:.6g}, theta_limit={math.degrees(self.theta_limit):.4g} deg, "
                f"w={self.half_width:.6g})")

    def to_dict(self) -> dict:
        return {"kind": self.arrangement.value, "la": self.la, "theta_limit": self.theta_limit,
                "t": self.t, "b": self.b}


@dataclass(frozen=True)
class TwoPPa:
    """2-PPa manipulator (linear actuation).

    Attributes
    ----------
    la : float, length
        Length of the parallelogram's rotating links.
    stroke : float, length
        Actuator stroke Delta d; ``0 <= d_i <= stroke``.
    theta_limit : float, rad
        Design angle theta_L: the prescribed square has half-width ``la sin(theta_limit)``
        (Eq. 24).  It does not restrict the reachable (total) workspace.
    base : (2, 2) float, length
        Base points ``g_i`` (row i), where P lies at ``d_i = 0, theta_i = 0`` minus ``la e_i``.
    axis : (2, 2) float
        Unit actuator directions ``e_i``.
    lateral : (2, 2) float
        Unit lateral directions ``l_i`` (``theta_i`` is measured from ``e_i`` towards ``l_i``).
    arrangement : Arrangement
    a, b : float, length
        The paper's offsets (perpendicular arrangement only; ``g_i = (b - a) e_i``).
    fk_branch : +1 or -1
        Assembly mode of the forward kinematics: the intersection of the two leg circles
        (centres ``n_i = g_i + d_i e_i``) on this side of ``n_1 -> n_2`` (geom2d convention,
        +1 = left).  +1 is the paper's Eq. 15 for the perpendicular arrangement.
    ik_sign : +1 or -1
        Working mode of the inverse kinematics: sign in front of the square root of Eq. 11.
        -1 (the paper's choice) puts the link ahead of the slider, ``s_i . e_i >= 0``.
    """

    la: float
    stroke: float
    theta_limit: float
    base: tuple
    axis: tuple
    lateral: tuple
    arrangement: Arrangement
    a: float = 0.0
    b: float = 0.0
    fk_branch: int = 1
    ik_sign: int = -1

    def __post_init__(self):
        _set(self, "la", getscalar(self.la, "la", positive=True))
        _set(self, "stroke", getscalar(self.stroke, "stroke", positive=True))
        _set(self, "theta_limit", _theta_limit_rad(self.theta_limit, "TwoPPa", "two_ppa"))
        if self.arrangement not in (Arrangement.PERPENDICULAR, Arrangement.PARALLEL):
            raise InputError(f"arrangement must be Arrangement.PERPENDICULAR or "
                             f"Arrangement.PARALLEL for a TwoPPa; got {self.arrangement!r}",
                             name="arrangement", value=self.arrangement)
        _set(self, "base", _rows(self.base, "base"))
        for name in ("axis", "lateral"):
            rows = _rows(getattr(self, name), name)
            norms = np.linalg.norm(rows, axis=1)
            if np.any(np.abs(norms - 1.0) > UNIT_TOL):
                raise InputError(f"{name} must hold two unit vectors (rows); got lengths "
                                 f"{norms.tolist()}", name=name, value=getattr(self, name))
            _set(self, name, rows)
        dots = np.sum(self.e * self.lat, axis=1)
        if np.any(np.abs(dots) > UNIT_TOL):
            raise InvalidModelError(f"lateral directions must be perpendicular to the axis "
                                    f"directions (l_i . e_i = 0); got l_i . e_i = {dots.tolist()}")
        _set(self, "a", getscalar(self.a, "a", nonneg=True))
        _set(self, "b", getscalar(self.b, "b", nonneg=True))
        for name in ("fk_branch", "ik_sign"):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or v not in (1, -1) \
                    or not isinstance(v, (int, np.integer)):
                raise InputError(f"{name} must be the int +1 or -1; got {v!r}", name=name,
                                 value=v)
            _set(self, name, int(v))

    @property
    def half_width(self) -> float:
        """Half-width w of the prescribed square workspace, ``la sin(theta_limit)`` (Eq. 24)."""
        return self.la * math.sin(self.theta_limit)

    @property
    def g(self) -> np.ndarray:
        return np.asarray(self.base, dtype=float)

    @property
    def e(self) -> np.ndarray:
        return np.asarray(self.axis, dtype=float)

    @property
    def lat(self) -> np.ndarray:
        return np.asarray(self.lateral, dtype=float)

    def __repr__(self) -> str:
        return (f"TwoPPa({self.arrangement.value}, la={self.la:.6g}, stroke={self.stroke:.6g}, "
                f"theta_limit={math.degrees(self.theta_limit):.4g} deg)")

    def to_dict(self) -> dict:
        return {"kind": self.arrangement.value, "la": self.la, "stroke": self.stroke,
                "theta_limit": self.theta_limit, "base": [list(r) for r in self.base],
                "axis": [list(r) for r in self.axis], "lateral": [list(r) for r in self.lateral],
                "a": self.a, "b": self.b, "fk_branch": self.fk_branch, "ik_sign": self.ik_sign}


#: Tolerance on |e_i| = |l_i| = 1 and e_i . l_i = 0 for directly constructed 2-PPa models.
UNIT_TOL = 1e-9


def _set(model, name, value):
    object.__setattr__(model, name, value)


def _theta_limit_rad(value, cls: str, builder: str) -> float:
    """``theta_limit`` of a directly constructed model: radians in (0, pi/2)."""
    th = getscalar(value, "theta_limit")
    if not 0.0 < th < math.pi / 2:
        raise InputError(
            f"{cls}.theta_limit is in radians and must lie in (0, pi/2) = (0, 1.5708); got "
            f"{value!r} (= {math.degrees(th):.6g} deg).  For degrees use "
            f"{builder}(..., unit=\"deg\")", name="theta_limit", value=value)
    return th


def _rows(x, name: str) -> tuple:
    """A finite (2, 2) float array as a tuple of two tuples (hashable)."""
    if isinstance(x, (str, bytes)):
        raise InputError(f"{name} must be a (2, 2) array of numbers; got {x!r}", name=name,
                         value=x)
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a (2, 2) array of numbers; got {x!r}", name=name,
                         value=x) from None
    if a.shape != (2, 2):
        raise InputError(f"{name} must have shape (2, 2) (one row per leg); got shape {a.shape}",
                         name=name, value=x)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} must be finite; got {a.tolist()}", name=name, value=x)
    return tuple(tuple(float(v) for v in row) for row in a)


def _theta_limit(theta_limit, unit) -> float:
    th = getangle(theta_limit, unit, "theta_limit")
    if not 0.0 < th < math.pi / 2:
        raise InputError(
            f"theta_limit must lie in (0, 90) deg / (0, pi/2) rad; got {theta_limit!r} {unit}",
            name="theta_limit", value=theta_limit)
    return th


def two_pap(la, theta_limit, *, unit: str = "rad", t=0.0, b=0.0) -> TwoPaP:
    """Build a 2-PaP manipulator.

    Parameters
    ----------
    la : float > 0, length
        Rotating-link length.
    theta_limit : float, rad (or deg with ``unit="deg"``)
        Actuator range theta_L, in (0, 90 deg).
    t, b : float >= 0, length
        Construction offsets of Eqs. 7-8.

    Examples
    --------
    >>> two_pap(100.0, 60, unit="deg").half_width  # doctest: +ELLIPSIS
    86.60...
    """
    return TwoPaP(la=getscalar(la, "la", positive=True), theta_limit=_theta_limit(theta_limit, unit),
                  t=getscalar(t, "t", nonneg=True), b=getscalar(b, "b", nonneg=True))


def two_ppa(la, a, stroke, theta_limit, *, b=0.0, unit: str = "rad") -> TwoPPa:
    """Build a 2-PPa manipulator with perpendicular actuators (the paper's design).

    Leg 1 slides along +x, leg 2 along +y; ``g_i = (b - a) e_i``; the lateral
    directions are ``l_1 = +y`` and ``l_2 = +x`` so that ``J = [[1, tan th1], [tan th2, 1]]``
    (Eq. 22), with ``sin th1 = p_y / la`` and ``sin th2 = p_x / la``.

    Parameters
    ----------
    la, a, stroke : float > 0, length
        Link length, offset a and actuator stroke Delta d.
    theta_limit : float, rad (or deg)
        Design angle theta_L (sets the prescribed square only).
    b : float >= 0, length
        Platform offset b.
    """
    la = getscalar(la, "la", positive=True)
    a = getscalar(a, "a", positive=True)
    stroke = getscalar(stroke, "stroke", positive=True)
    b = getscalar(b, "b", nonneg=True)
    th = _theta_limit(theta_limit, unit)
    c = b - a
    return TwoPPa(la=la, stroke=stroke, theta_limit=th, base=((c, 0.0), (0.0, c)),
                  axis=((1.0, 0.0), (0.0, 1.0)), lateral=((0.0, 1.0), (1.0, 0.0)),
                  arrangement=Arrangement.PERPENDICULAR, a=a, b=b, fk_branch=1, ik_sign=-1)


def two_ppa_parallel(la, spacing, stroke, theta_limit, *, offset=None, unit: str = "rad") -> TwoPPa:
    """Build a 2-PPa manipulator with parallel actuators (Eq. 29).

    Both actuators slide along +y on the lines ``x = -spacing/2`` (leg 1) and
    ``x = +spacing/2`` (leg 2); leg 1 leans towards +x and leg 2 towards -x, so that
    ``J = [[tan th1, 1], [-tan th2, 1]]``.

    Parameters
    ----------
    la, spacing, stroke : float > 0, length
    theta_limit : float, rad (or deg)
        Design angle (sets the prescribed square only).
    offset : float, length, optional
        ``g_i`` lies ``offset`` below the x axis; default ``stroke / 2 + la cos(45 deg)``
        so that mid-stroke at theta = 45 deg puts P on the x axis.
    """
    la = getscalar(la, "la", positive=True)
    spacing = getscalar(spacing, "spacing", positive=True)
    stroke = getscalar(stroke, "stroke", positive=True)
    th = _theta_limit(theta_limit, unit)
    if spacing >= 2 * la:
        raise InputError(f"spacing must be < 2 la = {2 * la} so that the legs can meet; got {spacing}",
                         name="spacing", value=spacing)
    off = stroke / 2 + la * math.sqrt(0.5) if offset is None else getscalar(offset, "offset")
    h = spacing / 2
    return TwoPPa(la=la, stroke=stroke, theta_limit=th, base=((-h, -off), (h, -off)),
                  axis=((0.0, 1.0), (0.0, 1.0)), lateral=((1.0, 0.0), (-1.0, 0.0)),
                  arrangement=Arrangement.PARALLEL, fk_branch=1, ik_sign=-1)
