"""Plots of spatial loops: displacement, velocity and acceleration against the input
([Kim 1985] Figs. 3-5) and a 3-D skeleton of a pose.

matplotlib is imported when a function is called; a missing installation raises
:class:`cspace.errors.MissingExtraError` naming the ``plot`` extra.
"""

from __future__ import annotations

import numpy as np

from cspace.errors import InputError
from cspace.plotting import new_axes

from .solve import LoopPath, LoopStatus, frame_transforms

__all__ = ["plot_displacement", "plot_velocity", "plot_acceleration", "plot_linkage"]


def _series(obj, which, *, ax, variables, labels, loop, **kw):
    if not isinstance(obj, LoopPath):
        raise InputError(f"expected a LoopPath; got {type(obj).__name__}", name="obj", value=obj)
    ax = new_axes(ax, figsize=None)
    data = {"q": obj.q, "qd": obj.qd, "qdd": obj.qdd}[which]
    n = data.shape[1]
    idx = [i for i in range(n) if loop is None or i != loop.input] if variables is None \
        else list(variables)
    good = obj.status <= LoopStatus.SINGULAR
    x = np.degrees(obj.inputs)
    for i in idx:
        kind = loop.variables[i][1] if loop is not None else "theta"
        y = data[:, i].copy()
        if which == "q" and kind == "theta":
            y = np.degrees(np.unwrap(y))
        elif kind == "theta":
            y = np.degrees(y) if which == "q" else y
        y = np.where(good, y, np.nan)   # plot gaps where the loop did not close
        name = labels[i] if labels is not None else (
            f"{loop.frames[loop.variables[i][0]].name}.{kind}" if loop is not None else f"q{i}")
        ax.plot(x, y, label=name, **kw)
    ax.set_xlabel("input angle (deg)")
    ax.legend(fontsize="small", ncol=2)
    ax.grid(True, lw=0.3)
    return ax


def plot_displacement(obj, *, ax=None, variables=None, labels=None, loop=None, **kw):
    """Joint displacements against the input (Fig. 3).

    Parameters
    ----------
    obj : LoopPath
    ax : matplotlib Axes, optional
    variables : sequence of int, optional
        Variable indices to draw (default: every variable but the input).
    labels : sequence of str, optional
        One per variable of the loop.
    loop : Loop, optional
        For names and units (angles drawn in degrees, slides in length units).
    **kw
        Passed to ``Axes.plot``.
    """
    ax = _series(obj, "q", ax=ax, variables=variables, labels=labels, loop=loop, **kw)
    ax.set_ylabel("displacement (deg, or length)")
    return ax


def plot_velocity(obj, *, ax=None, variables=None, labels=None, loop=None, **kw):
    """Joint rates per unit input rate against the input (Fig. 4)."""
    ax = _series(obj, "qd", ax=ax, variables=variables, labels=labels, loop=loop, **kw)
    ax.set_ylabel("velocity ratio dq / d(input)")
    return ax


def plot_acceleration(obj, *, ax=None, variables=None, labels=None, loop=None, **kw):
    """Joint accelerations per unit input rate squared against the input (Fig. 5)."""
    ax = _series(obj, "qdd", ax=ax, variables=variables, labels=labels, loop=loop, **kw)
    ax.set_ylabel("acceleration ratio d2q / d(input)2")
    return ax


def plot_linkage(obj, q=None, *, ax=None, ground=None, **kw):
    """3-D skeleton: polyline through the frame origins, with joint axes.

    Parameters
    ----------
    obj : Linkage or Loop
    q : (n_vars,) float, optional
        Pose (default: the linkage's start pose).
    ax : 3-D matplotlib Axes, optional
    """
    loop = getattr(obj, "loop", obj)
    if q is None:
        q = getattr(obj, "q0", None)
        if q is None:
            q = loop.reference_q()
    G = getattr(obj, "ground", np.eye(4)) if ground is None else np.asarray(ground)
    T = G @ frame_transforms(loop, q)
    ax = new_axes(ax, figsize=None, projection="3d")
    o = T[:, :3, 3]
    pts = np.vstack([o, o[:1]])
    kw.setdefault("marker", "o")
    ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], **kw)
    L = 0.25 * loop.length_scale
    for t in T:
        a = t[:3, 3]
        b = a + L * t[:3, 2]
        ax.plot([a[0], b[0]], [a[1], b[1]], [a[2], b[2]], color="C3", lw=1.0)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    return ax
