"""Figures of the statistical analyses (:mod:`synthesis.statistics`).

Matplotlib is imported when a function is called (extra ``plot``).
"""

from __future__ import annotations

__all__ = ["plot_contributors"]


def plot_contributors(result, *, ax=None, point: int = 0, top: int = 15):
    """Bar chart of each parameter's share of the margin variance at a design
    point of a :class:`~synthesis.statistics.YieldResult`, largest first.

    Parameters
    ----------
    result : YieldResult
    ax : matplotlib Axes, optional
    point : int
        Which design point (0: the most probable).
    top : int
        Parameters shown; the rest are summed in one bar.

    Returns
    -------
    matplotlib Axes
    """
    from cspace.plotting import new_axes, plain_text
    ax = new_axes(ax, (7, 4))
    if not result.design_points:
        ax.text(0.5, 0.5, "no design point: no failure region found", ha="center",
                va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return ax
    p = result.design_points[point]
    items = sorted(p.shares.items(), key=lambda kv: -kv[1])
    shown, rest = items[:top], sum(v for _, v in items[top:])
    if rest > 0:
        shown.append((f"{len(items) - top} others", rest))
    names = [plain_text(k) for k, _ in shown][::-1]
    vals = [100 * v for _, v in shown][::-1]
    ax.barh(names, vals, color="tab:red")
    for y, v in enumerate(vals):
        ax.text(v, y, f" {v:.1f} %", va="center", fontsize=8)
    ax.set_xlabel("share of the margin variance at the design point (%)")
    ax.set_xlim(0, max(vals) * 1.2 if max(vals) > 0 else 1)
    ax.set_title(f"design point {point + 1}: beta {p.beta:.2f}, FORM {1e6 * p.p_form:.3g} ppm; "
                 f"sampled {result.ppm:.3g} ppm ({result.method})", fontsize=10)
    return ax
