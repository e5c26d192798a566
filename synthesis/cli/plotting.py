"""Figures of a synthesis run and of the statistical analyses.

A run (:mod:`synthesis.cli.report` writes them): the contact zones before and
after ([Tolerance synthesis] Figs. 3, 7, 9), the defect count per iteration,
the changes per parameter and the parts before and after.  The statistics
(:mod:`synthesis.statistics`): the contributors at a design point.

Every function has the form ``plot_x(obj, *, ax=None, **kw) -> Axes``;
matplotlib is imported when a function is called (extra ``plot``), through
:func:`cspace.plotting.new_axes`.
"""

from __future__ import annotations

import numpy as np

from cspace.errors import CSpaceError

__all__ = ["plot_zones_before_after", "plot_defect_history", "plot_changes",
           "plot_parts_before_after", "plot_contributors", "separate_labels"]


def separate_labels(ax, pad: float = 1.0) -> int:
    """Move the text annotations of ``ax`` (the labels beside marks, as
    :func:`cspace.plotting.plot_failures` writes them) apart where they
    overlap on the drawn figure: each label that overlaps one placed before it
    (taken bottom-up by its mark) goes up just above it, ``pad`` pixels
    between them.  Returns the number of labels moved."""
    from matplotlib.text import Annotation
    fig = ax.figure
    labels = [t for t in ax.texts if isinstance(t, Annotation) and t.get_text()]
    if len(labels) < 2:
        return 0
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    # bottom-up by the mark each label belongs to, then by its own place
    labels.sort(key=lambda t: (ax.transData.transform(t.xy)[1],
                               t.get_window_extent(renderer).y0))
    placed, moved = [], 0
    for t in labels:
        box = t.get_window_extent(renderer)
        lift = 0.0
        for _ in range(len(placed) + 1):
            hit = [b for b in placed if box.x0 < b.x1 and b.x0 < box.x1
                   and box.y0 + lift < b.y1 and b.y0 < box.y1 + lift]
            if not hit:
                break
            lift = max(b.y1 for b in hit) + pad - box.y0
        if lift > 0:
            if t.get_anncoords() != "offset points":
                t.set_anncoords("offset points")
                t.xyann = (0.0, 0.0)
            dx, dy = t.xyann
            t.xyann = (dx, dy + lift * 72.0 / fig.dpi)
            box = t.get_window_extent(renderer)
            moved += 1
        placed.append(box)
    return moved


def plot_zones_before_after(zones_before, zones_after, cs_before, cs_after, *, unit="rad",
                            title=None, defects=None):
    """Two panels: zones of the initial and of the final design.  Returns the
    right-hand Axes (``ax.figure`` is the figure).  ``defects`` = (before,
    after) defective check-list vectors, shown beside the zone-overlap counts
    (an overlap is a bound, a defect a tested variant)."""
    d0, d1 = (f", {defects[0]} defective", f", {defects[1]} defective") if defects else ("", "")
    from cspace.plotting import new_figure, plot_zones
    fig = new_figure(figsize=(16, 6.5))
    a0, a1 = fig.subplots(1, 2, sharex=True, sharey=True)
    plot_zones(zones_before, cs_before, ax=a0, unit=unit, legend=False, inset=None,
               title=f"before: {len(zones_before.overlaps)} zone overlap(s){d0}")
    plot_zones(zones_after, cs_after, ax=a1, unit=unit, inset=None,
               title=f"after: {len(zones_after.overlaps)} zone overlap(s){d1}")
    fig.suptitle(title or f"Contact zones of {cs_before.pair.name}")
    return a1


def plot_defect_history(result, *, ax=None):
    """Defective check-list vectors and check-list size per iteration."""
    from cspace.plotting import new_axes
    ax = new_axes(ax, (7, 4))
    it = [h.iteration for h in result.history]
    ax.plot(it, result.defects_per_iteration(), "o-", color="tab:red", label="defective vectors")
    ax.plot(it, [h.counts.get("checklist", 0) for h in result.history], "s--",
            color="tab:gray", lw=0.8, label="check-list size")
    ax.set_xlabel("iteration")
    ax.set_ylabel("vectors")
    ax.set_xticks(it)
    ax.set_ylim(bottom=0)
    # counts: whole ticks only
    from matplotlib.ticker import MaxNLocator
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.legend(fontsize=8)
    ax.set_title(f"{result.model}: {result.status.name.lower()} after {result.nit} iteration(s), "
                 f"e = {result.e:.4g} {result.units}")
    return ax


def plot_changes(result, *, ax=None):
    """Horizontal bars per changed parameter: the nominal shift and the tolerance
    cut, both in units of the parameter's initial tolerance."""
    from cspace.plotting import new_axes, plain_text
    ch = result.changes()
    rows = [(nm, c) for nm, c in ch.items()
            if c["delta"] != 0 or c["tol_final"] != c["tol_initial"]]
    ax = new_axes(ax, (8, max(2.5, 0.28 * len(rows) + 1.2)))
    if not rows:
        ax.text(0.5, 0.5, "no dimension or tolerance changed", ha="center", va="center",
                transform=ax.transAxes)
        ax.set_axis_off()
        return ax
    y = np.arange(len(rows))
    t0 = np.array([c["tol_initial"] for _, c in rows])
    safe = np.where(t0 > 0, t0, 1.0)
    shift = np.array([c["delta"] for _, c in rows]) / safe
    cut = (np.array([c["tol_final"] for _, c in rows]) - t0) / safe
    ax.barh(y - 0.2, shift, height=0.38, color="tab:blue", label="nominal shift / initial tol")
    ax.barh(y + 0.2, cut, height=0.38, color="tab:orange",
            label="tolerance change / initial tol (a cut is negative)")
    ax.axvline(0, color="k", lw=0.8)
    ax.set_yticks(y)
    ax.set_yticklabels([plain_text(nm) for nm, _ in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("fraction of the initial tolerance")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2,
              frameon=False)
    ax.set_title(f"{plain_text(result.model)}: {int((shift != 0).sum())} shifted, "
                 f"{int((cut != 0).sum())} tolerance(s) cut; e = {result.e:.4g} {result.units}")
    return ax


def plot_parts_before_after(result, model, *, ax=None, visible: float = 0.03):
    """The parts of the initial (dashed) and final (solid) nominal design over
    each other.  A synthesis moves dimensions by fractions of their tolerance,
    too little to see, so the change is magnified until the largest one is
    ``visible`` times the part size (the factor is in the title)."""
    from cspace.plotting import plot_parts_overlay
    du = result.nominal - result.initial_nominal
    before = model.with_nominal(result.initial_nominal).pairs()[0]
    size = before.size
    big = float(np.max(np.abs(du))) if len(du) else 0.0
    k = 1.0
    if big > 0:
        k = float(min(max(1.0, visible * size / big), 1000.0))
    after = None
    while after is None:
        k = float(f"{k:.2g}")
        try:
            after = model.with_nominal(result.initial_nominal + k * du).pairs()[0]
        except CSpaceError:
            # a magnified design that does not build (arcs that no longer meet):
            # magnify less, down to the design itself
            if k <= 1.0:
                raise
            k = max(1.0, k / 2)
    ax = plot_parts_overlay(before, after, ax=ax, exaggerate=k)
    if big == 0:
        ax.set_title(f"{before.name}: no nominal dimension changed (tolerances only)")
    return ax


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
    k = len(result.design_points)
    what = ", ".join(p.reasons).lower() or "defect"
    where = f" in {plain_text(p.pair)}" if p.pair else ""
    ax.set_title(f"design point {point + 1} of {k} ({what}{where}): beta {p.beta:.2f}, "
                 f"FORM {1e6 * p.p_form:.3g} ppm\nsampled {result.ppm:.3g} ppm in all "
                 f"({result.method})" + ("; the other design points are in yield.json"
                                         if k > 1 else ""), fontsize=9)
    return ax
