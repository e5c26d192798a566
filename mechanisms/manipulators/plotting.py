"""Plots for the manipulators: LDI maps (Fig. 5) and workspaces (Figs. 3-4).

matplotlib is imported when a function is called; a missing installation raises
:class:`cspace.errors.MissingExtraError` naming the ``plot`` extra.
"""

from __future__ import annotations

import numpy as np

from cspace.plotting import new_axes

from .indices import LDIMap, ldi_map
from .models import TwoPaP
from .workspace import effective_square, leg_region, total_workspace

__all__ = ["plot_ldi_map", "plot_workspace"]


def plot_ldi_map(obj, *, ax=None, n: int = 41, surface: bool = True, **kw):
    """LDI over the prescribed square, as a mesh (Fig. 5) or a filled contour map.

    Parameters
    ----------
    obj : LDIMap, TwoPaP or TwoPPa
        A model is sampled with :func:`ldi_map` on an ``n x n`` grid.
    ax : matplotlib Axes, optional
        Must be a 3-D axes when ``surface`` is true; created if absent.
    surface : bool
        Mesh plot like the paper (True) or contour map (False).
    **kw
        Passed to ``plot_wireframe`` / ``contourf``.

    Returns
    -------
    matplotlib Axes
    """
    m = obj if isinstance(obj, LDIMap) else ldi_map(obj, n=n)
    X, Y = np.meshgrid(m.x, m.y)
    if surface:
        ax = new_axes(ax, figsize=None, projection="3d")
        kw.setdefault("linewidth", 0.6)
        ax.plot_wireframe(X, Y, m.ldi, **kw)
        ax.set_zlabel("LDI")
    else:
        ax = new_axes(ax, figsize=None)
        cs = ax.contourf(X, Y, m.ldi, **kw)
        ax.figure.colorbar(cs, ax=ax, label="LDI")
        ax.set_aspect("equal")
    ax.set_xlabel("p_x")
    ax.set_ylabel("p_y")
    return ax


def _fill(ax, poly, **kw):
    if poly.is_empty:
        return
    x, y = poly.exterior.xy
    ax.fill(x, y, **kw)


def plot_workspace(obj, *, ax=None, legs: bool = True, **kw):
    """Total workspace, leg regions and effective square (Figs. 3-4).

    Parameters
    ----------
    obj : TwoPaP or TwoPPa
    ax : matplotlib Axes, optional
    legs : bool
        Outline each 2-PPa leg's region.
    **kw
        Passed to the fill of the total workspace.
    """
    ax = new_axes(ax, figsize=None)
    total = total_workspace(obj)
    if legs and not isinstance(obj, TwoPaP):
        for i, style in ((0, "--"), (1, ":")):
            x, y = leg_region(obj, i).exterior.xy
            ax.plot(x, y, style, color="0.3", lw=1.0, label=f"leg {i + 1} region")
    kw.setdefault("alpha", 0.35)
    kw.setdefault("label", "total workspace")
    _fill(ax, total, **kw)
    sq = effective_square(obj).polygon
    x, y = sq.exterior.xy
    ax.plot(x, y, "-", color="C3", lw=1.6, label="effective square 2w x 2w")
    ax.plot([0], [0], "k+")
    ax.set_aspect("equal")
    ax.set_xlabel("p_x")
    ax.set_ylabel("p_y")
    ax.legend(loc="best", fontsize="small")
    return ax
