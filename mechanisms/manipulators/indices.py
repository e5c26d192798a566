"""Local and global design indices over the prescribed square workspace.

GDI definition
--------------
Eq. 28 of [Kim 2007] prints ``GDI = LDI_max / LDI_min``, but every number in Tables 1-2
is ``LDI_min / LDI_max`` (e.g. 2-PaP: ``cos(theta_L) = 0.5`` at 60 deg, which is <= 1).
:func:`global_design_index` therefore returns ``gdi = LDI_min / LDI_max`` (in (0, 1],
1 = isotropic everywhere) and also carries ``ldi_max_over_min = LDI_max / LDI_min`` so the
printed formula can be checked too.  The tests compare both with Tables 1-2.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from cspace.argcheck import getint, getscalar
from cspace.errors import InputError

from .jacobian import ldi_values
from .kinematics import check_model
from .models import TwoPaP

__all__ = ["LDIMap", "ldi_map", "GDIResult", "global_design_index", "closed_form_design_indices",
           "table1_closed_form"]


@dataclass(frozen=True)
class LDIMap:
    """LDI sampled on a square grid (for Fig. 5 style plots).

    Attributes
    ----------
    x, y : (n,) float, length
        Grid coordinates (``p_x`` varies along axis 1 of ``ldi``).
    ldi : (n, n) float
        ``ldi[i, j]`` at ``(x[j], y[i])``.
    half_width : float, length
    """

    x: np.ndarray
    y: np.ndarray
    ldi: np.ndarray
    half_width: float

    def __repr__(self) -> str:
        return (f"LDIMap(n={self.x.size}, w={self.half_width:.6g}, "
                f"min={self.ldi.min():.6g}, max={self.ldi.max():.6g})")

    def to_dict(self) -> dict:
        return {"x": self.x.tolist(), "y": self.y.tolist(), "ldi": self.ldi.tolist(),
                "half_width": self.half_width}


def _half_width(model, half_width):
    if half_width is None:
        return model.half_width
    return getscalar(half_width, "half_width", positive=True)


def ldi_map(model, half_width=None, *, n: int = 41) -> LDIMap:
    """LDI on an ``n x n`` grid over the square ``|p_x|, |p_y| <= half_width``.

    ``half_width`` defaults to the model's prescribed square, ``la sin(theta_limit)``.
    """
    check_model(model)
    w = _half_width(model, half_width)
    n = getint(n, "n", minimum=2)
    x = np.linspace(-w, w, n)
    X, Y = np.meshgrid(x, x)
    return LDIMap(x=x, y=x.copy(), ldi=ldi_values(model, np.stack([X, Y], -1)), half_width=w)


@dataclass(frozen=True)
class GDIResult:
    """Global design index over a square workspace.

    Attributes
    ----------
    gdi : float
        ``LDI_min / LDI_max`` (the tables' convention; see module notes).
    ldi_max_over_min : float
        ``LDI_max / LDI_min``, the GDI as printed in Eq. 28 of [Kim 2007] (inf if
        LDI_min = 0).  Formerly ``ratio_eq28`` (deprecated alias).
    ldi_min, ldi_max : float
    p_min, p_max : (2,) float, length
        Where they occur.
    half_width : float, length
    evaluations : int
        LDI evaluations spent.
    within_workspace : bool
        Whether the whole square lies in the workspace
        (:func:`~mechanisms.manipulators.workspace.square_fits`: the joint and
        stroke limits).  The indices are the formula's over the whole square
        either way; where this is False, some of its poses are out of reach
        (compare :func:`~mechanisms.manipulators.workspace.effective_square`).
    """

    gdi: float
    ldi_max_over_min: float
    ldi_min: float
    ldi_max: float
    p_min: np.ndarray
    p_max: np.ndarray
    half_width: float
    evaluations: int
    within_workspace: bool = True

    @property
    def ratio_eq28(self) -> float:
        """Deprecated name of :attr:`ldi_max_over_min`."""
        warnings.warn("GDIResult.ratio_eq28 is deprecated; use GDIResult.ldi_max_over_min",
                      DeprecationWarning, stacklevel=2)
        return self.ldi_max_over_min

    def __repr__(self) -> str:
        out = (f"GDIResult(gdi={self.gdi:.6g}, ldi_min={self.ldi_min:.6g} at {np.round(self.p_min, 6)}, "
               f"ldi_max={self.ldi_max:.6g} at {np.round(self.p_max, 6)}")
        if not self.within_workspace:
            out += f", the square of half-width {self.half_width:.6g} leaves the workspace"
        return out + ")"

    def to_dict(self) -> dict:
        return {"gdi": self.gdi, "ldi_max_over_min": self.ldi_max_over_min, "ldi_min": self.ldi_min,
                "ldi_max": self.ldi_max, "p_min": self.p_min.tolist(),
                "p_max": self.p_max.tolist(), "half_width": self.half_width,
                "evaluations": self.evaluations, "within_workspace": self.within_workspace}


def global_design_index(model, half_width=None, *, n: int = 21, refine: int = 4) -> GDIResult:
    """GDI of ``model`` over the square ``|p_x|, |p_y| <= half_width``.

    The LDI extremes are found on an ``n x n`` grid (corners, edge mid-points and the
    centre are on it for odd ``n``) and then polished by bounded local optimisation
    (L-BFGS-B) from the ``refine`` best grid points of each kind.  The LDI is only
    piecewise smooth (2-PaP: a minimum of two cosines), so the best of all evaluated
    points is kept.

    Parameters
    ----------
    model : TwoPaP or TwoPPa
    half_width : float, length, optional
        Defaults to the prescribed square of the model.
    n : int >= 3
    refine : int >= 0
    """
    check_model(model)
    w = _half_width(model, half_width)
    n = getint(n, "n", minimum=3)
    refine = getint(refine, "refine", minimum=0)
    grid = ldi_map(model, w, n=n)
    X, Y = np.meshgrid(grid.x, grid.y)
    pts = np.stack([X.ravel(), Y.ravel()], -1)
    vals = grid.ldi.ravel()
    evals = vals.size
    best = {}
    for sign, key in ((1.0, "min"), (-1.0, "max")):
        order = np.argsort(sign * vals)
        bp, bv = pts[order[0]].copy(), vals[order[0]]
        for k in order[:refine]:
            res = minimize(lambda z: sign * float(ldi_values(model, z)), pts[k],
                           method="L-BFGS-B", bounds=[(-w, w), (-w, w)],
                           options={"ftol": 1e-15, "gtol": 1e-13})
            evals += res.nfev
            v = float(ldi_values(model, res.x))
            if sign * v < sign * bv:
                bp, bv = res.x.copy(), v
        best[key] = (bp, bv)
    (pmin, lmin), (pmax, lmax) = best["min"], best["max"]
    gdi = lmin / lmax if lmax > 0 else 0.0
    r28 = lmax / lmin if lmin > 0 else math.inf
    from .workspace import square_fits
    return GDIResult(gdi=gdi, ldi_max_over_min=r28, ldi_min=lmin, ldi_max=lmax, p_min=pmin,
                     p_max=pmax, half_width=w, evaluations=int(evals),
                     within_workspace=bool(square_fits(model, w, tol=1e-12)))


def closed_form_design_indices(model) -> dict:
    """LDI extremes and GDI of ``model`` over its prescribed square, in closed form.

    The closed forms of Table 1 of [Kim 2007], evaluated at the model's
    ``theta_limit``; used to check :func:`global_design_index`.

    Returns ``{"ldi_max", "ldi_min", "gdi"}``: 2-PaP ``la, la cos th_L, cos th_L``;
    2-PPa ``1, 1/(1 + tan th_L), 1/(1 + tan th_L)``.  (The perpendicular 2-PPa only.)
    """
    check_model(model)
    th = model.theta_limit
    if isinstance(model, TwoPaP):
        return {"ldi_max": model.la, "ldi_min": model.la * math.cos(th), "gdi": math.cos(th)}
    if model.arrangement.name != "PERPENDICULAR":
        raise InputError("Table 1 covers the perpendicular 2-PPa only", name="model", value=model)
    v = 1.0 / (1.0 + math.tan(th))
    return {"ldi_max": 1.0, "ldi_min": v, "gdi": v}


def table1_closed_form(model) -> dict:
    """Deprecated name of :func:`closed_form_design_indices`."""
    warnings.warn("table1_closed_form is deprecated; use closed_form_design_indices",
                  DeprecationWarning, stacklevel=2)
    return closed_form_design_indices(model)
