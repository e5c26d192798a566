"""Plots of C-spaces and parts (matplotlib, imported only when a plot is made).

Every function has the form ``plot_x(obj, *, ax=None, **kw) -> Axes`` and never
calls ``plt.show()``.  Install the extra with ``pip install 'cspace-tolerance[plot]'``.
"""

from __future__ import annotations


import numpy as np

from .errors import MissingExtraError
from .geometry import Pair, Rotation

__all__ = ["plain_text", "plot_cspace", "plot_parts", "plot_zones", "plot_output", "band_edges", "label_colors",
           "new_axes", "save_figure"]


def _plt():
    try:
        import matplotlib
        if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "cairo") and \
                not _has_display():
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise MissingExtraError("matplotlib", "plot") from None
    return plt


def _has_display() -> bool:
    import os
    return bool(os.environ.get("DISPLAY") or os.environ.get("MPLBACKEND"))


def new_axes(ax=None, figsize=(8, 6)):
    if ax is not None:
        return ax
    plt = _plt()
    _, ax = plt.subplots(figsize=figsize)
    return ax


def plain_text(text) -> str:
    """A name shown as it is: matplotlib would read text between two ``$`` as
    math (and fail on one ``$``)."""
    return str(text).replace("$", r"\$")


def save_figure(ax, path, dpi: int = 110):
    """Save the figure of ``ax`` atomically as PNG and close it."""
    import io as _io
    from .io import atomic_write
    plt = _plt()
    fig = ax.figure
    buf = _io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    atomic_write(path, buf.getvalue())


def label_colors(labels) -> dict:
    """A stable colour for each feature-pair label."""
    plt = _plt()
    cmap = plt.get_cmap("tab20")
    uniq = sorted(set(labels))
    return {lab: cmap(i % 20) for i, lab in enumerate(uniq)}


def _fill_geom(ax, g, **kw):
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path as MPath
    for p in getattr(g, "geoms", [g]):
        if p.geom_type != "Polygon" or p.is_empty:
            continue
        verts, codes = [], []
        for ring in [p.exterior, *p.interiors]:
            xy = np.asarray(ring.coords)
            verts.append(xy)
            codes += [MPath.MOVETO] + [MPath.LINETO] * (len(xy) - 2) + [MPath.CLOSEPOLY]
        ax.add_patch(PathPatch(MPath(np.vstack(verts), codes), **kw))


def _axis_labels(ax, pair: Pair, unit: str):
    names = []
    for i, part in enumerate(pair.parts):
        if isinstance(part.axis, Rotation):
            names.append(f"q{i + 1}: {plain_text(part.name)} angle [{unit}]")
        else:
            names.append(f"q{i + 1}: {plain_text(part.name)} slide [{plain_text(pair.units)}]")
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1])


def plot_cspace(cs, *, ax=None, boundary_only: bool = True, legend: bool = True,
                unit: str = "rad", blocked_color="0.78", free_color="white", lw: float = 1.2,
                title: str | None = None):
    """Free (white) and blocked (grey) faces with the contact curves coloured by
    feature pair.

    Parameters
    ----------
    cs : ConfigurationSpace
    boundary_only : bool
        Draw only the curve pieces that bound free space (default) or all curves.
    unit : {"rad", "deg"}
        Angle unit of the axes (the data stay in rad inside).
    """
    from .argcheck import getunit
    f = 1.0 / getunit(unit)
    ax = new_axes(ax, (9, 6.5))
    import shapely.affinity as aff
    pair = cs.pair
    sx = f if cs.periodic[0] or isinstance(pair.driver.axis, Rotation) else 1.0
    sy = f if isinstance(pair.follower.axis, Rotation) else 1.0
    lo1, hi1, lo2, hi2 = cs.window
    # blocked background, free faces on top: no hairline seams between cells
    ax.add_patch(__import__("matplotlib.patches", fromlist=["Rectangle"]).Rectangle(
        (lo1 * sx, lo2 * sy), (hi1 - lo1) * sx, (hi2 - lo2) * sy, facecolor=blocked_color,
        edgecolor="none"))
    for fid, g in cs.face_polygons().items():
        if not cs.faces[fid]:
            continue
        g2 = aff.scale(g, sx, sy, origin=(0, 0))
        _fill_geom(ax, g2, facecolor=free_color, edgecolor=free_color, lw=0.3)
    polys = cs.curve_polylines(boundary_only=boundary_only)
    colors = label_colors([lab for lab, _, _ in polys])
    seen = set()
    for lab, br, pl in polys:
        key = lab
        ax.plot(pl[:, 0] * sx, pl[:, 1] * sy, color=colors[lab], lw=lw,
                label=None if key in seen else plain_text(lab))
        seen.add(key)
    for vc in cs.vertical:
        ax.plot([vc.q1_value * sx] * 2, [vc.q2_lo * sy, vc.q2_hi * sy], color="k", lw=lw, ls=":")
    ax.set_xlim(lo1 * sx, hi1 * sx)
    ax.set_ylim(lo2 * sy, hi2 * sy)
    _axis_labels(ax, pair, unit)
    ax.set_title(title or f"C-space of {plain_text(pair.name)}")
    if legend and seen:
        ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False,
                  ncol=1 if len(seen) <= 30 else 2)
    return ax


def plot_parts(pair: Pair, q=(0.0, 0.0), *, ax=None, colors=("tab:blue", "tab:red"),
               show_axes: bool = True, title: str | None = None, label_segments: bool = False):
    """The two parts drawn at configuration ``q`` (true arcs, finely sampled)."""
    from .overlap import _move
    ax = new_axes(ax, (7, 7))
    for part, qq, col in zip(pair.parts, q, colors):
        for lp in part.loops:
            pts = lp.sample(720)
            pts = np.vstack([pts, pts[:1]])
            w = _move(part.axis, np.full(len(pts), float(qq)), pts)
            ax.fill(w[:, 0], w[:, 1], color=col, alpha=0.12, lw=0)
            ax.plot(w[:, 0], w[:, 1], color=col, lw=1.2)
            if label_segments:
                for s in lp.segments:
                    if not s.name:
                        continue
                    mid = s.sample(3)[1]
                    mw = _move(part.axis, np.array([float(qq)]), mid[None, :])[0]
                    ax.annotate(plain_text(s.name), mw, fontsize=6, color=col)
        if show_axes:
            if isinstance(part.axis, Rotation):
                ax.plot(*part.axis.center, marker="+", color=col, ms=10)
            else:
                o = np.asarray(part.axis.origin)
                e = np.asarray(part.axis.direction)
                L = 0.15 * pair.size
                ax.annotate("", o + L * e, o, arrowprops=dict(arrowstyle="->", color=col))
    ax.set_aspect("equal")
    ax.set_xlabel(f"x [{plain_text(pair.units)}]")
    ax.set_ylabel(f"y [{plain_text(pair.units)}]")
    ax.set_title(title or f"{plain_text(pair.name)} at q = ({q[0]:.4g}, {q[1]:.4g})")
    return ax


def band_edges(band, cs):
    """Edges of a zone band as (q1, q2) polylines: (lower edge, upper edge)."""
    s2 = 1.0 if cs.periodic[1] else 1.0 / cs.pair.char_length
    out = []
    for tau in (band.lower, band.upper):
        ok = np.isfinite(tau)
        x = band.q1[ok] + tau[ok] * band.normal[ok, 0]
        y = band.q2[ok] + tau[ok] * band.normal[ok, 1] / s2
        out.append(np.stack([x, y], 1))
    return tuple(out)


def plot_zones(zones, cs, *, ax=None, unit: str = "rad", window=None, title: str | None = None,
               band_color="tab:green", overlap_color="tab:red"):
    """Contact zones as bands over the nominal boundary curves, with overlaps
    highlighted (as in seed 003, Fig. 3(a)).

    Parameters
    ----------
    zones : ZoneAnalysis
    cs : ConfigurationSpace
        The nominal C-space the zones were computed on.
    window : (q1_lo, q1_hi, q2_lo, q2_hi), optional
        Zoom (data units, rad / model units).
    """
    from .argcheck import getunit
    from .geom2d import TWO_PI
    f = 1.0 / getunit(unit)
    ax = new_axes(ax, (9, 6.5))
    sx = f if isinstance(cs.pair.driver.axis, Rotation) else 1.0
    sy = f if cs.periodic[1] else 1.0
    lo2 = cs.window[2]
    shifts = (-TWO_PI, 0.0, TWO_PI) if cs.periodic[1] else (0.0,)
    for lab, br, pl in cs.curve_polylines(boundary_only=True):
        ax.plot(pl[:, 0] * sx, pl[:, 1] * sy, color="k", lw=0.7)
    for b in zones.bands:
        lo_e, up_e = band_edges(b, cs)
        if len(lo_e) < 2 or len(up_e) < 2:
            continue
        ring = np.vstack([lo_e, up_e[::-1]])
        base = (ring[:, 1] - lo2) // TWO_PI * TWO_PI if cs.periodic[1] else 0.0
        for sh in shifts:
            yy = ring[:, 1] - base + sh
            ax.fill(ring[:, 0] * sx, yy * sy, color=band_color, alpha=0.35, lw=0)
    for k, o in enumerate(zones.overlaps):
        a, bq = o.q1_range
        ax.plot([a * sx, bq * sx], [o.q[1] * sy] * 2, color=overlap_color, lw=3, alpha=0.8,
                solid_capstyle="butt", label="zone overlap" if k == 0 else None)
        ax.plot([o.q[0] * sx], [o.q[1] * sy], marker="o", mfc="none", color=overlap_color, ms=10)
    if zones.overlaps:
        ax.legend(fontsize=7, loc="upper right")
    w = window or cs.window
    ax.set_xlim(w[0] * sx, w[1] * sx)
    ax.set_ylim(w[2] * sy, w[3] * sy)
    _axis_labels(ax, cs.pair, unit)
    ax.set_title(title or f"Contact zones of {plain_text(cs.pair.name)}: {len(zones.overlaps)} overlap(s)")
    return ax


def plot_output(sims, *, ax=None, labels=None, unit: str = "rad", title: str | None = None):
    """Output functions f(q1) of one or more simulations (nominal first)."""
    from .argcheck import getunit
    f = 1.0 / getunit(unit)
    ax = new_axes(ax, (9, 4.5))
    sims = list(sims)
    labels = labels or [s.pair for s in sims]
    for k, (s, lab) in enumerate(zip(sims, labels)):
        ax.plot(s.q1 * f, s.q2 * f if _rot_output(s) else s.q2,
                lw=1.6 if k == 0 else 0.9, color="k" if k == 0 else None,
                alpha=1.0 if k == 0 else 0.7, label=plain_text(lab))
        if s.jam_q is not None:
            ax.plot([s.jam_q[0] * f], [s.jam_q[1] * (f if _rot_output(s) else 1.0)], "rx", ms=9)
    ax.set_xlabel(f"driver q1 [{unit}]")
    ax.set_ylabel("follower output f(q1)")
    ax.set_title(title or "Output function")
    if len(sims) <= 12:
        ax.legend(fontsize=7)
    return ax


def _rot_output(sim) -> bool:
    return getattr(sim, "rotating", True)
