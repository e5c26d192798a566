"""Plots of the linkage analyses (matplotlib is imported on first use).

Every function has the signature ``plot_x(obj, *, ax=None, **kw) -> Axes``; none
calls ``plt.show()``.  Angles are shown in degrees (axis labels say so).
"""

from __future__ import annotations

import math

import numpy as np

from cspace.errors import InputError
from cspace.plotting import new_axes

from .clearance import ContactForce, FreeFlightResult, LossKind
from .error import ErrorCurve, ErrorEllipse

__all__ = ["plot_error_curve", "plot_error_ellipse", "plot_joint_force", "plot_loss_positions"]


def _seq(obj, cls, name):
    items = [obj] if isinstance(obj, cls) else list(obj) if isinstance(obj, (list, tuple)) \
        else None
    if not items or not all(isinstance(o, cls) for o in items):
        raise InputError(f"{name} expects a {cls.__name__} or a non-empty sequence of them, "
                         f"got {type(obj).__name__}", name="obj", value=obj)
    return items


def plot_error_curve(obj, *, ax=None, quantity: str = "theta4", scale: float = 1.0, **kw):
    """Output-angle (or coupler-point component) error against the pin angle.

    Parameters
    ----------
    obj : ErrorCurve or sequence of ErrorCurve
        E.g. the exact and the linear curve of one clearance.
    quantity : {"theta4", "theta3", "px", "py"}
    scale : float
        Multiplies the error (e.g. 100 to show units of 1e-2 rad as in [Shin & Choi 1995]).
    **kw
        Passed to ``Axes.plot``.
    """
    curves = _seq(obj, ErrorCurve, "plot_error_curve")
    own = ax is None
    ax = new_axes(ax, figsize=None)
    get = {"theta4": lambda c: c.d_theta4, "theta3": lambda c: c.d_theta3,
           "px": lambda c: c.dP[:, 0], "py": lambda c: c.dP[:, 1]}
    if quantity not in get:
        raise InputError(f"quantity must be one of {sorted(get)}, got {quantity!r}",
                         name="quantity", value=quantity)
    for c in curves:
        style = {"ls": "-" if c.method == "exact" else "--", "label": f"{c.method}"}
        style.update(kw)
        ax.plot(np.degrees(c.delta), scale * get[quantity](c), **style)
    ax.set_xlabel("pin angle delta (deg)")
    unit = "rad" if quantity.startswith("theta") else "length"
    ax.set_ylabel(f"error of {quantity} ({unit}" + (f" x {scale:g})" if scale != 1 else ")"))
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.legend()
    if own:
        ax.figure.tight_layout()      # the axis label whole, whatever the tick labels
    return ax


def plot_error_ellipse(obj, *, ax=None, exact: ErrorCurve | None = None, n: int = 361, **kw):
    """The first-order coupler-point error ellipse, with optional exact points.

    Parameters
    ----------
    obj : ErrorEllipse
    exact : ErrorCurve, optional
        Exact coupler-point errors to overlay as dots.
    """
    if not isinstance(obj, ErrorEllipse):
        raise InputError(f"plot_error_ellipse expects an ErrorEllipse, got "
                         f"{type(obj).__name__}", name="obj", value=obj)
    ax = new_axes(ax, figsize=None)
    pts = obj.points(np.linspace(0, 2 * math.pi, n))
    style = {"label": f"first order ({obj.kind.value}, joint {obj.joint})"}
    style.update(kw)
    ax.plot(pts[:, 0], pts[:, 1], **style)
    a = obj.semi_major
    u = np.array([math.cos(obj.orientation), math.sin(obj.orientation)])
    ax.plot([-a * u[0], a * u[0]], [-a * u[1], a * u[1]], color="0.6", lw=0.6)
    if exact is not None:
        ax.plot(exact.dP[:, 0], exact.dP[:, 1], ".", ms=3, label="exact")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("error of Px (length units)")
    ax.set_ylabel("error of Py (length units)")
    ax.legend()
    return ax


def _robust_range(v):
    """A y-range for values with rare spikes: the 1st to 99th percentile range
    (with 0) widened by a half of it on either side, or None when the data
    lie within that anyway."""
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    if v.size < 10:
        return None
    lo, hi = np.percentile(v, [1.0, 99.0])
    lo, hi = min(lo, 0.0), max(hi, 0.0)
    pad = 0.5 * (hi - lo) if hi > lo else 1.0
    lo, hi = lo - pad, hi + pad
    if v.min() >= lo and v.max() <= hi:
        return None
    return float(lo), float(hi)


def plot_joint_force(obj, *, ax=None, ylim=None, zero_clearance: bool = False, **kw):
    """Joint force R against crank angle ([Choi & Bae 1999] Figs. 2-4).

    Parameters
    ----------
    obj : ContactForce or sequence of ContactForce
    ylim : (float, float), optional
        The model's narrow spikes at fast turns of the contact direction dwarf the
        force level; a y-range (N) keeps the curve readable.  By default the
        range covers the force between its 1st and 99th percentiles, widened by
        a half on either side (and 0), when the extremes lie beyond that: the
        spikes are then cut at the frame.
    zero_clearance : bool
        Also draw the zero-clearance magnitude R0 of the first result.
    """
    res = _seq(obj, ContactForce, "plot_joint_force")
    ax = new_axes(ax, figsize=None)
    if zero_clearance:
        ax.plot(np.degrees(res[0].crank_angle), res[0].R0, color="k", lw=1.6, alpha=0.5,
                label="zero clearance")
    for r in res:
        style = {"lw": 0.9, "label": f"{r.rpm:.0f} rpm, {r.clearance * 1e6:.0f} um"}
        style.update(kw)
        line, = ax.plot(np.degrees(r.crank_angle), r.R, **style)
        for loss in r.losses:
            ax.axvline(loss.angle_deg, color=line.get_color(), lw=0.5,
                       ls=":" if loss.kind is LossKind.FORCE_REVERSAL else "--")
    ax.axhline(0.0, color="0.6", lw=0.5)
    if ylim is None:
        ylim = _robust_range(np.concatenate([r.R for r in res]
                                            + ([res[0].R0] if zero_clearance else [])))
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.set_xlim(0, 360)
    ax.set_xlabel("crank angle (deg)")
    ax.set_ylabel("joint force R (N)")
    ax.legend(fontsize="small")
    return ax


def plot_loss_positions(obj, *, ax=None, flights=None, **kw):
    """Contact-loss crank angle against crank speed ([Choi & Bae 1999] Fig. 10).

    Parameters
    ----------
    obj : sequence of ContactForce
        Results at several speeds (same clearance).
    flights : sequence of FreeFlightResult, optional
        Free-flight results whose strongest impacts are overlaid.
    """
    res = _seq(obj, ContactForce, "plot_loss_positions")
    ax = new_axes(ax, figsize=None)
    rpm = np.array([r.rpm for r in res])
    order = np.argsort(rpm, kind="stable")
    for kind, mark in ((LossKind.NEGATIVE_FORCE, "o"), (LossKind.FORCE_REVERSAL, "s")):
        # every loss of every speed; the k-th (by angle) of neighbouring speeds
        # with as many losses joined into a branch
        per = [(rpm[i], sorted(math.degrees(math.remainder(a, 2 * math.pi))
                               for a in res[i].loss_angles(kind))) for i in order]
        per = [(sp, ys) for sp, ys in per if ys]
        if not per:
            continue
        style = {"label": f"continuous contact: {kind.value}"}
        style.update(kw)
        line = ax.plot([sp for sp, ys in per for _ in ys], [y for _, ys in per for y in ys],
                       mark, **style)[0]
        start = 0
        for j in range(1, len(per) + 1):
            if j == len(per) or len(per[j][1]) != len(per[start][1]):
                run = per[start:j]
                for k in range(len(run[0][1]) if len(run) > 1 else 0):
                    ax.plot([sp for sp, _ in run], [ys[k] for _, ys in run], "-",
                            color=line.get_color(), linewidth=line.get_linewidth())
                start = j
    if flights is not None:
        fl = _seq(flights, FreeFlightResult, "plot_loss_positions(flights=)")
        for f in fl:
            s = f.omega * 60 / (2 * math.pi)
            for e in f.events:
                ax.plot(s, math.degrees(math.remainder(e.strongest_impact, 2 * math.pi)), "kx")
        ax.plot([], [], "kx", label="free flight: strongest impact")
    ax.set_xlabel("crank speed (rpm)")
    ax.set_ylabel("crank angle (deg)")
    ax.legend(fontsize="small")
    return ax
