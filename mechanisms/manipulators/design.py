"""Design equations, the design helper and the comparison tables of [Kim 2007].

Design equations
----------------
2-PaP (Eqs. 6-8): ``la = w / sin th_L``, ``a_min = la (1 + sin th_L) + t + b``,
``L_min = la (1 + 2 sin th_L - cos th_L) + 2 (t + b)``; the passive-slide stroke
needed for the square is ``2 la sin th_L = 2 w`` (Table 2).
2-PPa (Eqs. 24-26): ``la = w / sin th_L``, ``a = w (1 + 1/sin th_L) + b``,
``Delta d = w (2 + 1/sin th_L - sqrt(1/sin^2 th_L - 1))``.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from cspace.argcheck import getangle, getint, getscalar, getvector
from cspace.errors import InputError

from .indices import global_design_index
from .jacobian import _ldi, jacobian_arrays, singular_values_2x2
from .kinematics import check_model
from .models import two_pap, two_ppa

__all__ = ["Design", "design", "Decoupling", "decoupling", "ComparisonTable", "comparison_table",
           "ArrangementPoint", "arrangement_comparison"]


@dataclass(frozen=True)
class Design:
    """Full dimension set for a prescribed square ``2w x 2w`` and design angle.

    Attributes
    ----------
    kind : str
        ``"2-PaP"`` or ``"2-PPa"``.
    w : float, length
        Half-width of the prescribed square.
    theta_limit : float, rad
    la : float, length
    stroke : float, length
        2-PaP: passive-slide travel ``2 la sin th_L``; 2-PPa: actuator stroke (Eq. 26).
    a : float, length
        Total size: 2-PaP ``a_min`` (Eq. 7), 2-PPa ``a`` (Eq. 26).
    L_min : float, length
        2-PaP minimum slide length (Eq. 8); 0 for 2-PPa.
    t, b : float, length
        The offsets used.
    model : TwoPaP or TwoPPa
        The manipulator built from these dimensions.
    """

    kind: str
    w: float
    theta_limit: float
    la: float
    stroke: float
    a: float
    L_min: float
    t: float
    b: float
    model: object = field(repr=False)

    @property
    def workspace_per_stroke(self) -> float:
        return 2 * self.w / self.stroke

    @property
    def workspace_per_size(self) -> float:
        return 2 * self.w / self.a

    def __repr__(self) -> str:
        return (f"Design({self.kind}, 2w={2 * self.w:.6g}, theta_L={math.degrees(self.theta_limit):.4g} deg, "
                f"la={self.la:.6g}, stroke={self.stroke:.6g}, a={self.a:.6g})")

    def to_dict(self) -> dict:
        return {"kind": self.kind, "w": self.w, "theta_limit": self.theta_limit, "la": self.la,
                "stroke": self.stroke, "a": self.a, "L_min": self.L_min, "t": self.t, "b": self.b,
                "workspace_per_stroke": self.workspace_per_stroke,
                "workspace_per_size": self.workspace_per_size}


def design(kind: str, w, theta_limit, *, t=0.0, b=0.0, unit: str = "rad") -> Design:
    """Dimensions from the prescribed half-width ``w`` and design angle ``theta_L``.

    Parameters
    ----------
    kind : ``"2-PaP"`` or ``"2-PPa"``
    w : float > 0, length
    theta_limit : float, rad (or deg with ``unit="deg"``), in (0, 90 deg)
    t, b : float >= 0, length
        Offsets (``t`` is used by 2-PaP only).

    Notes
    -----
    A perpendicular 2-PPa meets its direct singularity where ``th1 + th2 = 90
    deg``; its design corners ``(w, w)`` have ``th1 = th2 = theta_L``, so with
    ``theta_L >= 45 deg`` they lie on or beyond it (reached only in the other
    assembly mode) and the design does not reach its prescribed square:
    :func:`~mechanisms.manipulators.workspace.effective_square` of its model
    is then ``la sin 45 deg``.

    Examples
    --------
    >>> round(design("2-PPa", 130.0, 30, b=92.0, unit="deg").a, 6)
    482.0
    """
    if kind not in ("2-PaP", "2-PPa"):
        raise InputError(f"kind must be '2-PaP' or '2-PPa'; got {kind!r}", name="kind", value=kind)
    w = getscalar(w, "w", positive=True)
    th = getangle(theta_limit, unit, "theta_limit")
    if not 0 < th < math.pi / 2:
        raise InputError(f"theta_limit must lie in (0, 90) deg; got {theta_limit!r} {unit}",
                         name="theta_limit", value=theta_limit)
    t = getscalar(t, "t", nonneg=True)
    b = getscalar(b, "b", nonneg=True)
    s, c = math.sin(th), math.cos(th)
    la = w / s
    if kind == "2-PaP":
        a_min = la * (1 + s) + t + b
        L_min = la * (1 + 2 * s - c) + 2 * (t + b)
        return Design(kind=kind, w=w, theta_limit=th, la=la, stroke=2 * la * s, a=a_min,
                      L_min=L_min, t=t, b=b, model=two_pap(la, th, t=t, b=b))
    a = w * (1 + 1 / s) + b
    stroke = w * (2 + 1 / s - math.sqrt(1 / (s * s) - 1))
    return Design(kind=kind, w=w, theta_limit=th, la=la, stroke=stroke, a=a, L_min=0.0,
                  t=t, b=b, model=two_ppa(la, a, stroke, th, b=b))


class Decoupling(enum.Enum):
    """Where the paper's Jacobian J is diagonal (input-output decoupled)."""

    ALWAYS = "always"
    AT_ONE_POINT = "at one point"
    ON_A_SET = "on a set of points"
    NEVER = "never"


def decoupling(model, half_width=None, *, n: int = 41, tol: float = 1e-12) -> Decoupling:
    """Classify decoupling over the ``n x n`` grid of the prescribed square.

    Parameters
    ----------
    model : TwoPaP or TwoPPa
    half_width : float > 0, length, optional
        Defaults to the prescribed square of the model.
    n : odd int >= 3
        Odd so that the centre, where a 2-PPa decouples, is a grid node.
    tol : float >= 0
        Largest off-diagonal entry of the paper's J that counts as zero.
    """
    check_model(model)
    w = model.half_width if half_width is None else getscalar(half_width, "half_width", positive=True)
    n = getint(n, "n", minimum=3)
    if n % 2 == 0:
        raise InputError(f"n must be an odd int >= 3 (so that the centre is a grid node); "
                         f"got {n}", name="n", value=n)
    tol = getscalar(tol, "tol", nonneg=True)
    x = np.linspace(-w, w, n)
    X, Y = np.meshgrid(x, x)
    j = jacobian_arrays(model, np.stack([X, Y], -1))[5]
    diag = (np.abs(j[..., 0, 1]) <= tol) & (np.abs(j[..., 1, 0]) <= tol)
    k = int(np.count_nonzero(diag))
    if k == diag.size:
        return Decoupling.ALWAYS
    if k == 0:
        return Decoupling.NEVER
    return Decoupling.AT_ONE_POINT if k == 1 else Decoupling.ON_A_SET


@dataclass(frozen=True)
class ComparisonTable:
    """Table 2 of [Kim 2007], computed.

    Attributes
    ----------
    columns : tuple of str
        One per design, e.g. ``"2-PaP (theta_L = 60 deg)"``.
    rows : tuple of (str, tuple)
        Row name and one value per column.
    """

    columns: tuple
    rows: tuple

    def value(self, row: str, column: int):
        for name, vals in self.rows:
            if name == row:
                return vals[column]
        raise InputError(f"no row {row!r}; rows are {[r for r, _ in self.rows]}", name="row", value=row)

    def to_markdown(self, digits: int = 3) -> str:
        def fmt(v):
            return f"{v:.{digits}f}" if isinstance(v, float) else str(v)
        lines = ["| Performance | " + " | ".join(self.columns) + " |",
                 "|---" * (len(self.columns) + 1) + "|"]
        for name, vals in self.rows:
            lines.append(f"| {name} | " + " | ".join(fmt(v) for v in vals) + " |")
        return "\n".join(lines)

    def __repr__(self) -> str:
        """The table itself: one line per row with its values (3 digits)."""
        def fmt(v):
            if isinstance(v, enum.Enum):
                return str(v.value)
            return f"{v:.3g}" if isinstance(v, float) else str(v)
        w = max([len(str(n)) for n, _ in self.rows] + [1])
        lines = [f"ComparisonTable({len(self.rows)} rows x {len(self.columns)} designs)",
                 f"  {'':{w}}  " + " | ".join(str(c) for c in self.columns)]
        lines += [f"  {str(n):{w}}  " + " | ".join(fmt(v) for v in vals) for n, vals in self.rows]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"columns": list(self.columns),
                "rows": [{"name": n, "values": [v if not isinstance(v, enum.Enum) else v.value
                                                 for v in vals]} for n, vals in self.rows]}


def comparison_table(*designs: Design, gdi_grid: int = 21) -> ComparisonTable:
    """Computed Table 2 for the given designs (decoupling, GDI, 2w/stroke, 2w/size)."""
    if not designs or not all(isinstance(d, Design) for d in designs):
        raise InputError("comparison_table needs one or more Design values", name="designs",
                         value=designs)
    cols = tuple(f"{d.kind} (theta_L = {math.degrees(d.theta_limit):.4g} deg)" for d in designs)
    rows = (
        ("Decoupled", tuple(decoupling(d.model).value for d in designs)),
        ("GDI", tuple(global_design_index(d.model, n=gdi_grid).gdi for d in designs)),
        ("Workspace/stroke (2w/Delta d)", tuple(d.workspace_per_stroke for d in designs)),
        ("Workspace/size (2w/a)", tuple(d.workspace_per_size for d in designs)),
    )
    return ComparisonTable(columns=cols, rows=rows)


@dataclass(frozen=True)
class ArrangementPoint:
    """Best point (largest LDI, then isotropy) of a 2-PPa actuator arrangement (Table 3).

    Attributes
    ----------
    arrangement : str
    theta : (2,) float, rad
        Link angles of the best point.
    ldi : float
        LDI there.
    condition : float
        Condition number of J there (1 = isotropic).
    decoupled : bool
        J diagonal there.
    transverse_ratio : float
        Largest transverse/axial load ratio on an actuator, ``max |tan theta_i|``: the
        links carry axial force only, so a link at theta_i to its actuator loads it
        sideways by ``tan theta_i`` per unit axial force.
    """

    arrangement: str
    theta: np.ndarray
    ldi: float
    condition: float
    decoupled: bool
    transverse_ratio: float

    def __repr__(self) -> str:
        return (f"ArrangementPoint({self.arrangement}, theta={np.degrees(self.theta).round(4)} deg, "
                f"LDI={self.ldi:.6g})")

    def to_dict(self) -> dict:
        return {"arrangement": self.arrangement, "theta": self.theta.tolist(), "ldi": self.ldi,
                "condition": self.condition, "decoupled": self.decoupled,
                "transverse_ratio": self.transverse_ratio}


def _j_of_theta(arr: str, th):
    t1, t2 = np.tan(th[0]), np.tan(th[1])
    if arr == "perpendicular":
        return np.array([[1.0, t1], [t2, 1.0]])
    return np.array([[t1, 1.0], [-t2, 1.0]])


def arrangement_comparison(start_deg=(20.0, 20.0), bound_deg: float = 80.0) -> tuple:
    """Table 3: the best point of the perpendicular (Eq. 22) and parallel (Eq. 29) J.

    Maximises the LDI ``1 / sigma_max(J(theta_1, theta_2))`` and, among equal LDI,
    prefers isotropy (objective ``anisotropy - LDI``, the anisotropy being zero where
    cond J = 1; for both arrangements one point is best on both counts) over ``|theta_i| <= bound_deg`` from
    ``start_deg`` and reports the LDI (``1 / sigma_max(J)``) there.

    Parameters
    ----------
    start_deg : (2,) float, deg
        Starting link angles ``(theta_1, theta_2)``, within ``+-bound_deg``.
    bound_deg : float in (0, 90), deg
        Bound on ``|theta_i|``.

    Returns
    -------
    (ArrangementPoint, ArrangementPoint)
        Perpendicular, parallel.
    """
    bd = getscalar(bound_deg, "bound_deg", positive=True)
    if not bd < 90.0:
        raise InputError(f"bound_deg must lie in (0, 90) deg (tan theta is unbounded at 90); "
                         f"got {bound_deg!r}", name="bound_deg", value=bound_deg)
    b = math.radians(bd)
    if isinstance(start_deg, (str, bytes)):
        raise InputError(f"start_deg must be two angles in deg, (theta_1, theta_2); got "
                         f"{start_deg!r}", name="start_deg", value=start_deg)
    s0 = getvector(start_deg, 2, "start_deg")
    if np.any(np.abs(s0) > bd):
        raise InputError(f"start_deg must lie within +-bound_deg = +-{bd:g} deg; got "
                         f"{s0.tolist()}", name="start_deg", value=start_deg)
    x0 = np.radians(s0)
    out = []
    for arr in ("perpendicular", "parallel"):
        def anisotropy(th):
            # ((s_max^2 - s_min^2) / (s_max^2 + s_min^2))^2: smooth, zero exactly at
            # isotropy, unlike the condition number which has a kink there.
            j = _j_of_theta(arr, th)
            f = float(np.sum(j * j))
            det = float(np.linalg.det(j))
            return (f * f - 4 * det * det) / (f * f) - float(_ldi(j, "linear"))
        res = minimize(anisotropy, x0, method="Nelder-Mead",
                       options={"xatol": 1e-13, "fatol": 1e-18, "maxiter": 8000})
        th = np.clip(res.x, -b, b)
        j = _j_of_theta(arr, th)
        smax, smin = singular_values_2x2(j)
        out.append(ArrangementPoint(
            arrangement=arr, theta=th, ldi=float(_ldi(j, "linear")),
            condition=float(smax / smin), decoupled=bool(abs(j[0, 1]) < 1e-6 and abs(j[1, 0]) < 1e-6),
            transverse_ratio=float(np.max(np.abs(np.tan(th))))))
    return tuple(out)

