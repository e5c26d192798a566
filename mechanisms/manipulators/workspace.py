"""Total and effective (square) workspaces.

Total workspace
    2-PaP: the square ``|p_i| <= la sin(theta_limit)`` set by the actuator range.
    2-PPa: the intersection of the two legs' regions (Fig. 4).  Leg i reaches
    ``g_i + d e_i + la (cos phi e_i + sin phi l_i)`` for ``d`` in ``[0, stroke]`` and
    ``|phi| <= phi_max`` (default 90 deg, the IK working mode): a band bounded by two
    translated half-circles.  Returned as a shapely polygon whose arcs are sampled
    with ``arc_points`` vertices.

Effective square workspace
    The largest square centred at the origin that the manipulator reaches in its
    working assembly mode.  For 2-PPa it is found by bisection on a predicate
    rather than on the polygon: over an axis-aligned square, ``d_i(p) = r.e_i -
    sqrt(la^2 - (r.l_i)^2)`` is convex, so its maximum is at a corner and its
    minimum where ``r.e_i`` is least and ``|r.l_i|`` is least (both directions
    are axis-aligned in the builders), which is exact; and no pose of the
    square may lie beyond the direct singularity, where the legs reach P only
    in the other assembly mode (the total workspace includes those poses: its
    lower-left tail), checked on the square's boundary, densely sampled, and an
    interior grid.  The polygon is used by the tests as an independent check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon, box
from shapely.geometry.polygon import orient

from cspace.argcheck import getangle, getint, getscalar
from cspace.errors import InputError

from .kinematics import check_model
from .models import TwoPaP, TwoPPa

__all__ = ["leg_region", "total_workspace", "EffectiveSquare", "effective_square", "square_fits"]


def _phi_max(phi_max, unit):
    if phi_max is None:
        return math.pi / 2
    v = getangle(phi_max, unit, "phi_max")
    if not 0 < v <= math.pi / 2:
        raise InputError(f"phi_max must lie in (0, 90] deg; got {phi_max!r} {unit}",
                         name="phi_max", value=phi_max)
    return v


def leg_region(model: TwoPPa, leg: int, *, phi_max=None, unit: str = "rad",
               arc_points: int = 513) -> Polygon:
    """Region reachable by P through leg ``leg`` (0 or 1) of a 2-PPa, as a polygon."""
    if not isinstance(model, TwoPPa):
        raise InputError(f"leg_region needs a TwoPPa; got {type(model).__name__}",
                         name="model", value=model)
    if leg not in (0, 1):
        raise InputError(f"leg must be 0 or 1; got {leg!r}", name="leg", value=leg)
    pm = _phi_max(phi_max, unit)
    phi = np.linspace(-pm, pm, getint(arc_points, "arc_points", minimum=3))
    g, e, lat, la = model.g[leg], model.e[leg], model.lat[leg], model.la
    arc = la * (np.cos(phi)[:, None] * e + np.sin(phi)[:, None] * lat)
    far = g + model.stroke * e + arc             # d = stroke, phi from -pm to +pm
    near = (g + arc)[::-1]                       # d = 0, phi from +pm to -pm
    poly = Polygon(np.vstack([far, near]))
    return orient(shapely.make_valid(poly) if not poly.is_valid else poly, 1.0)


def total_workspace(model, *, phi_max=None, unit: str = "rad", arc_points: int = 513) -> Polygon:
    """Total workspace as a shapely polygon (counter-clockwise exterior).

    ``arc_points`` (int >= 3) vertices sample each half-circle of a 2-PPa leg region.
    """
    check_model(model)
    arc_points = getint(arc_points, "arc_points", minimum=3)
    if isinstance(model, TwoPaP):
        w = model.half_width
        return orient(box(-w, -w, w, w), 1.0)
    inter = leg_region(model, 0, phi_max=phi_max, unit=unit, arc_points=arc_points).intersection(
        leg_region(model, 1, phi_max=phi_max, unit=unit, arc_points=arc_points))
    if inter.geom_type == "Polygon":
        return orient(inter, 1.0)
    # Several pieces (possible for odd designs): keep the largest, which holds the origin
    # for every sensible design.
    parts = [g for g in getattr(inter, "geoms", []) if g.geom_type == "Polygon"]
    if not parts:
        return Polygon()
    return orient(max(parts, key=lambda g: g.area), 1.0)


def square_fits(model, w: float, *, phi_max=None, unit: str = "rad", tol: float = 0.0) -> bool:
    """Does the manipulator reach every pose of the square ``|p_x|, |p_y| <= w``
    in its working mode: inside the total workspace (exact) and, for a 2-PPa,
    in the working assembly mode (sampled, see the module docstring)?

    ``w`` (float >= 0, length) is the half-width; ``tol`` (float >= 0, relative to
    ``la``) widens the limits; the effective square uses 0.
    """
    check_model(model)
    w = getscalar(w, "w", nonneg=True)
    tol = getscalar(tol, "tol", nonneg=True)
    if isinstance(model, TwoPaP):
        return w <= model.half_width * (1 + 1e-15)
    pm = _phi_max(phi_max, unit)
    la = model.la
    tol = tol * la
    corners = np.array([[-w, -w], [w, -w], [w, w], [-w, w]])
    for i in range(2):
        g, e, lat = model.g[i], model.e[i], model.lat[i]
        u = (corners - g) @ e
        v = (corners - g) @ lat
        if np.max(np.abs(v)) > la * math.sin(pm) + tol:
            return False
        dmax = np.max(u - np.sqrt(np.maximum(la * la - v * v, 0.0)))
        vmin = 0.0 if v.min() <= 0.0 <= v.max() else np.min(np.abs(v))
        dmin = u.min() - math.sqrt(max(la * la - vmin * vmin, 0.0))
        if dmin < -tol or dmax > model.stroke + tol:
            return False
    return _working_assembly(model, w, tol)


#: Samples per edge of the square, and per side of its interior grid, at which
#: :func:`square_fits` checks a 2-PPa's assembly mode.
ASSEMBLY_SAMPLES = (4097, 129)


def _working_assembly(model: TwoPPa, w: float, tol: float) -> bool:
    """Whether every pose of the square ``|p_x|, |p_y| <= w`` is reached in the
    working assembly mode: P on the ``fk_branch`` side of the line through the
    two sliders (the sign of ``cross(L_0, L_1)``, the legs' link vectors; it is
    zero on the direct singularity, where the links are parallel), as
    :func:`~mechanisms.manipulators.kinematics.inverse_kinematics` reads it.
    Beyond that curve the legs still reach P, but only in the other assembly
    mode, which the manipulator cannot pass into.  The square first meets the
    curve on its boundary as it grows from the origin; the boundary is sampled
    at :data:`ASSEMBLY_SAMPLES` points per edge, corners included, and the
    interior on a grid (a region of the other mode inside the square).
    ``tol``: length, widens the limit as in :func:`square_fits`."""
    from .kinematics import BOUNDARY_REL, PoseStatus, assembly_side, ik_arrays
    n_edge, n_in = ASSEMBLY_SAMPLES
    t = np.linspace(-w, w, n_edge)
    edges = np.concatenate([np.stack([t, np.full_like(t, s)], axis=1) for s in (-w, w)]
                           + [np.stack([np.full_like(t, s), t], axis=1) for s in (-w, w)])
    g = np.linspace(-w, w, n_in)
    p = np.concatenate([edges, np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)])
    d, _, status = ik_arrays(model, p)
    if tol <= BOUNDARY_REL * model.la:
        return not np.any(status == PoseStatus.OTHER_ASSEMBLY)
    # a wider limit than the IK's own
    return not np.any(model.fk_branch * assembly_side(model, p, d) < -tol * model.la)


@dataclass(frozen=True)
class EffectiveSquare:
    """Largest origin-centred square the manipulator reaches in its working mode.

    Attributes
    ----------
    half_width : float, length
        w; the square side is ``2 w``.
    polygon : shapely Polygon
        The square.
    iterations : int
        Bisection steps.
    """

    half_width: float
    polygon: Polygon
    iterations: int

    @property
    def side(self) -> float:
        return 2.0 * self.half_width

    def __repr__(self) -> str:
        return f"EffectiveSquare(2w={self.side:.6g})"

    def to_dict(self) -> dict:
        return {"half_width": self.half_width, "side": self.side, "iterations": self.iterations}


def effective_square(model, *, phi_max=None, unit: str = "rad", rtol: float = 1e-14) -> EffectiveSquare:
    """Effective square workspace by bisection on :func:`square_fits`.

    For 2-PaP it is the prescribed square itself.  ``rtol`` (float in [0, 1)) is the
    bisection's tolerance relative to ``la``: the half-width returned is a lower bound
    within ``rtol la`` of the exact one (at most 200 steps).
    """
    check_model(model)
    rtol = getscalar(rtol, "rtol", nonneg=True)
    if not rtol < 1.0:
        raise InputError(f"rtol must lie in [0, 1) (relative to la); got {rtol!r}",
                         name="rtol", value=rtol)
    if isinstance(model, TwoPaP):
        w = model.half_width
        return EffectiveSquare(half_width=w, polygon=box(-w, -w, w, w), iterations=0)
    lo, hi = 0.0, model.la + model.stroke
    if not square_fits(model, 0.0, phi_max=phi_max, unit=unit):
        return EffectiveSquare(half_width=0.0, polygon=Polygon(), iterations=0)
    it = 0
    while hi - lo > rtol * model.la and it < 200:
        mid = 0.5 * (lo + hi)
        if square_fits(model, mid, phi_max=phi_max, unit=unit):
            lo = mid
        else:
            hi = mid
        it += 1
    return EffectiveSquare(half_width=lo, polygon=box(-lo, -lo, lo, lo), iterations=it)
