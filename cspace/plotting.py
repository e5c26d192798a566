"""Plots of C-spaces and parts (matplotlib, imported only when a plot is made).

Every function has the form ``plot_x(obj, *, ax=None, **kw) -> Axes`` and never
calls ``plt.show()``; :func:`animate_motion` writes a GIF and returns an
:class:`AnimationFile`.  Install the extra with
``pip install 'cspace-tolerance[plot]'``.

Figures come from :func:`new_figure` (and :func:`new_axes`), which every
plotting module of the library uses: matplotlib is imported on the first
plot, a missing installation raises :class:`~cspace.errors.MissingExtraError`
naming the ``plot`` extra, and the matplotlib backend is never changed.
Without a display matplotlib draws with its file backend (Agg) by itself,
so :func:`save_figure` writes PNGs on a headless machine too.

Every C-space and zone plot has a legend naming what it draws: free and
blocked space, the nominal contact curves, the zone bands, zone overlaps and
the motion path.  Holes in parts are drawn empty.
"""

from __future__ import annotations


import numpy as np

from .errors import MissingExtraError
from .geometry import Pair, Rotation, place_points
from .metric import follower_scale
from .tolerances import SLACK

__all__ = ["pyplot", "new_figure", "new_axes", "save_figure", "plain_text", "plot_cspace",
           "plot_parts", "plot_zones", "plot_output", "band_edges", "label_colors", "plot_motion",
           "plot_failures", "narrow_channel", "add_zoom_inset", "plot_parts_overlay",
           "animate_motion", "AnimationFile"]

FREE_COLOR = "white"
BLOCKED_COLOR = "0.78"
PATH_COLOR = "tab:blue"
FAIL_COLOR = "tab:red"


def pyplot():
    """``matplotlib.pyplot``, imported on the first call.

    The backend stays whatever the user or matplotlib chose.

    Raises
    ------
    MissingExtraError
        matplotlib is not installed (the ``plot`` extra).
    """
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise MissingExtraError("matplotlib", "plot") from None
    return plt


def new_figure(figsize=None, **kw):
    """A new matplotlib Figure, without changing the backend.

    The figure is made through pyplot, so that it shows in a notebook or a
    window like any other.  When the configured backend needs a display that
    is not there, it is a figure outside pyplot instead: it cannot be shown,
    but it draws and saves (``savefig`` picks its canvas by file type).

    Parameters
    ----------
    figsize : (float, float), optional
        Width and height in inches; default matplotlib's.
    **kw
        Passed to the Figure.
    """
    plt = pyplot()
    try:
        return plt.figure(figsize=figsize, **kw)
    except ImportError:
        from matplotlib.figure import Figure
        return Figure(figsize=figsize, **kw)


def new_axes(ax=None, figsize=(8, 6), **subplot_kw):
    """``ax`` itself, or the single Axes of a :func:`new_figure`.

    Parameters
    ----------
    ax : matplotlib Axes, optional
    figsize : (float, float) or None
        Inches; None for matplotlib's default.
    **subplot_kw
        Passed to ``Figure.add_subplot``, e.g. ``projection="3d"``.
    """
    if ax is not None:
        return ax
    return new_figure(figsize).add_subplot(**subplot_kw)


def plain_text(text) -> str:
    """A name shown as it is: matplotlib would read text between two ``$`` as
    math (and fail on one ``$``)."""
    return str(text).replace("$", r"\$")


def save_figure(ax, path, dpi: int = 110):
    """Save the figure of ``ax`` atomically as PNG and close it."""
    import io as _io
    from .io import atomic_write
    fig = ax.figure
    buf = _io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    pyplot().close(fig)
    atomic_write(path, buf.getvalue())


def label_colors(labels) -> dict:
    """A stable colour for each feature-pair label."""
    cmap = pyplot().get_cmap("tab20")
    uniq = sorted(set(labels))
    return {lab: cmap(i % 20) for i, lab in enumerate(uniq)}


def _fill_geom(ax, g, **kw):
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path as MPath
    from shapely.geometry.polygon import orient
    for p in getattr(g, "geoms", [g]):
        if p.geom_type != "Polygon" or p.is_empty:
            continue
        # exterior counter-clockwise, holes clockwise: the nonzero fill rule
        # leaves the holes empty
        p = orient(p, 1.0)
        verts, codes = [], []
        for ring in [p.exterior, *p.interiors]:
            xy = np.asarray(ring.coords)
            verts.append(xy)
            codes += [MPath.MOVETO] + [MPath.LINETO] * (len(xy) - 2) + [MPath.CLOSEPOLY]
        ax.add_patch(PathPatch(MPath(np.vstack(verts), codes), **kw))
        kw.pop("label", None)


def _material(rings):
    """The region of closed rings by the even-odd rule (shapely geometry)."""
    from shapely.geometry import Polygon
    geom = None
    for w in rings:
        p = Polygon(w).buffer(0)
        geom = p if geom is None else geom.symmetric_difference(p)
    return geom


def _axis_labels(ax, pair: Pair, unit: str):
    names = []
    for i, part in enumerate(pair.parts):
        if isinstance(part.axis, Rotation):
            names.append(f"q{i + 1}: {plain_text(part.name)} angle [{unit}]")
        else:
            names.append(f"q{i + 1}: {plain_text(part.name)} slide [{plain_text(pair.units)}]")
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1])


def _scales(cs, unit):
    """Axis scale factors (q1, q2) for angle unit ``unit``."""
    from .argcheck import getunit
    f = 1.0 / getunit(unit)
    pair = cs.pair
    sx = f if cs.periodic[0] or isinstance(pair.driver.axis, Rotation) else 1.0
    sy = f if isinstance(pair.follower.axis, Rotation) else 1.0
    return sx, sy


def _draw_faces(ax, cs, sx, sy, blocked_color=BLOCKED_COLOR, free_color=FREE_COLOR):
    """Blocked background, free faces on top (no hairline seams between cells)."""
    import shapely.affinity as aff
    from matplotlib.patches import Rectangle
    lo1, hi1, lo2, hi2 = cs.window
    ax.add_patch(Rectangle((lo1 * sx, lo2 * sy), (hi1 - lo1) * sx, (hi2 - lo2) * sy,
                           facecolor=blocked_color, edgecolor="none"))
    for fid, g in cs.face_polygons().items():
        if not cs.faces[fid]:
            continue
        g2 = aff.scale(g, sx, sy, origin=(0, 0))
        _fill_geom(ax, g2, facecolor=free_color, edgecolor=free_color, lw=0.3)


def _space_handles(blocked_color=BLOCKED_COLOR, free_color=FREE_COLOR):
    from matplotlib.patches import Patch
    return [Patch(facecolor=free_color, edgecolor="0.4", lw=0.6, label="free"),
            Patch(facecolor=blocked_color, edgecolor="0.4", lw=0.6, label="blocked")]


def _wrapped_path(cs, q1, q2):
    """(q1, q2) of a motion in the window, with NaN breaks where it wraps."""
    q1 = np.asarray(q1, dtype=float).copy()
    q2 = np.asarray(q2, dtype=float).copy()
    lo1, hi1, lo2, hi2 = cs.window
    if cs.periodic[0]:
        q1 = (q1 - lo1) % (hi1 - lo1) + lo1
    if cs.periodic[1]:
        q2 = (q2 - lo2) % (hi2 - lo2) + lo2
    jump = np.zeros(len(q1), dtype=bool)
    if len(q1) > 1:
        jump[1:] = ((np.abs(np.diff(q1)) > 0.5 * (hi1 - lo1))
                    | (np.abs(np.diff(q2)) > 0.5 * (hi2 - lo2)))
    if not jump.any():
        return q1, q2
    idx = np.nonzero(jump)[0]
    return np.insert(q1, idx, np.nan), np.insert(q2, idx, np.nan)


def plot_motion(sim, cs, *, ax=None, unit: str = "rad", color=PATH_COLOR, lw: float = 1.6,
                ls="-", label: str = "motion path", mark_end: bool = True):
    """The path of a simulated motion in the C-space (on top of :func:`plot_cspace`
    or :func:`plot_zones`), its start as a dot and a jam as a red cross."""
    ax = new_axes(ax, (9, 6.5))
    sx, sy = _scales(cs, unit)
    x, y = _wrapped_path(cs, sim.q1, sim.q2)
    ax.plot(x * sx, y * sy, color=color, lw=lw, ls=ls, label=label, zorder=4)
    if len(x):
        ax.plot([x[0] * sx], [y[0] * sy], "o", color=color, ms=5, zorder=5,
                label="motion start")
    if mark_end and sim.jam_q is not None:
        jx, jy = _wrapped_path(cs, [sim.jam_q[0]], [sim.jam_q[1]])
        ax.plot(jx * sx, jy * sy, "X", color=FAIL_COLOR, ms=11, mec="k", zorder=6,
                label=f"jam ({plain_text(sim.jam_reason or sim.status.name.lower())})")
    return ax


def plot_cspace(cs, *, ax=None, boundary_only: bool = True, legend: bool = True,
                unit: str = "rad", blocked_color=BLOCKED_COLOR, free_color=FREE_COLOR,
                lw: float = 1.2, title: str | None = None, motion=None,
                max_curve_labels: int = 24, inset=None):
    """Free (white) and blocked (grey) faces with the contact curves coloured by
    feature pair.

    Parameters
    ----------
    cs : ConfigurationSpace
    boundary_only : bool
        Draw only the curve pieces that bound free space (default) or all curves.
    unit : {"rad", "deg"}
        Angle unit of the axes (the data stay in rad inside).
    motion : SimulationResult, optional
        A motion to draw as a path (:func:`plot_motion`, black dashes: the
        curves have colours).
    inset : "auto", None or (q1_lo, q1_hi, q2_lo, q2_hi)
        A zoom inset on a narrow channel (``"auto"``: the narrowest stretch of
        ``motion``, :func:`narrow_channel`).
    max_curve_labels : int
        The legend names at most this many feature pairs (labels are the
        segment names of the model or file, ``part:segment|part:segment``);
        free, blocked and the motion path are always named.
    """
    ax = new_axes(ax, (9, 6.5))
    pair = cs.pair
    sx, sy = _scales(cs, unit)
    lo1, hi1, lo2, hi2 = cs.window
    _draw_faces(ax, cs, sx, sy, blocked_color, free_color)
    polys = cs.curve_polylines(boundary_only=boundary_only)
    colors = label_colors([lab for lab, _, _ in polys])
    box = _inset_box(cs, motion, inset)
    if box is not None:     # the zoom panel takes the lower part of the legend's room
        max_curve_labels = min(max_curve_labels, 16)
    seen: list = []
    for lab, br, pl in polys:
        name = None
        if lab not in seen:
            seen.append(lab)
            name = plain_text(lab) if len(seen) <= max_curve_labels else None
        ax.plot(pl[:, 0] * sx, pl[:, 1] * sy, color=colors[lab], lw=lw, label=name)
    for vc in cs.vertical:
        ax.plot([vc.q1_value * sx] * 2, [vc.q2_lo * sy, vc.q2_hi * sy], color="k", lw=lw, ls=":")
    if motion is not None:
        plot_motion(motion, cs, ax=ax, unit=unit, color="k", ls=(0, (4, 2)), lw=1.4)
    ax.set_xlim(lo1 * sx, hi1 * sx)
    ax.set_ylim(lo2 * sy, hi2 * sy)
    _axis_labels(ax, pair, unit)
    ax.set_title(title or f"C-space of {plain_text(pair.name)}")
    if legend:
        handles, labels = ax.get_legend_handles_labels()
        extra = _space_handles(blocked_color, free_color)
        more = len(seen) - max_curve_labels
        if more > 0:
            from matplotlib.lines import Line2D
            handles.append(Line2D([], [], color="0.5", lw=lw,
                                  label=f"... {more} more contact curves"))
        ax.legend(handles=extra + handles, fontsize=6, loc="upper left",
                  bbox_to_anchor=(1.01, 1.0), frameon=False,
                  title="contact curves (feature pairs)", title_fontsize=6,
                  ncol=1 if len(handles) + len(extra) <= 30 else 2)
    if box is not None:
        def draw(ia):
            _draw_faces(ia, cs, sx, sy, blocked_color, free_color)
            for lab, br, pl in polys:
                ia.plot(pl[:, 0] * sx, pl[:, 1] * sy, color=colors[lab], lw=lw)
            if motion is not None:
                plot_motion(motion, cs, ax=ia, unit=unit, color="k", ls=(0, (4, 2)), lw=1.4)
        # below the legend when there is one, else right of the axes
        add_zoom_inset(ax, box, draw, sx=sx, sy=sy,
                       bounds=(1.04, -0.02, 0.4, 0.32) if legend else (1.04, 0.0, 0.42, 0.42))
    return ax


def _inset_box(cs, motion, inset):
    if isinstance(inset, str) and inset == "auto":
        return narrow_channel(cs, motion) if motion is not None else None
    return None if inset is None else tuple(float(v) for v in inset)


def plot_parts(pair: Pair, q=(0.0, 0.0), *, ax=None, colors=("tab:blue", "tab:red"),
               show_axes: bool = True, title: str | None = None, label_segments: bool = False):
    """The two parts drawn at configuration ``q`` (true arcs, finely sampled)."""
    ax = new_axes(ax, (7, 7))
    for part, qq, col in zip(pair.parts, q, colors):
        rings = []
        for lp in part.loops:
            pts = lp.sample(720)
            pts = np.vstack([pts, pts[:1]])
            w = place_points(part.axis, np.full(len(pts), float(qq)), pts)
            rings.append(w)
            ax.plot(w[:, 0], w[:, 1], color=col, lw=1.2)
        # material by nesting (even-odd): a loop inside another is a hole, a loop
        # inside a hole is material again; holes are left empty
        _fill_geom(ax, _material(rings), facecolor=col, alpha=0.15, lw=0,
                   label=plain_text(part.name))
        for lp in part.loops:
            if label_segments:
                for s in lp.segments:
                    if not s.name:
                        continue
                    mid = s.sample(3)[1]
                    mw = place_points(part.axis, np.array([float(qq)]), mid[None, :])[0]
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
    s2 = 1.0 / follower_scale(cs.pair)
    out = []
    for tau in (band.lower, band.upper):
        ok = np.isfinite(tau)
        x = band.q1[ok] + tau[ok] * band.normal[ok, 0]
        y = band.q2[ok] + tau[ok] * band.normal[ok, 1] / s2
        out.append(np.stack([x, y], 1))
    return tuple(out)


def plot_zones(zones, cs, *, ax=None, unit: str = "rad", window=None, title: str | None = None,
               band_color="tab:green", overlap_color="tab:red", motion=None, inset="auto",
               legend: bool = True):
    """Contact zones as bands over the nominal boundary curves, with overlaps
    highlighted (as in [Tolerance synthesis] Fig. 3(a)), over free (white) and blocked
    (grey) space.

    A *zone overlap* marks where the zone bands of the two curves bounding one
    free channel overlap: some variant in the tolerance box may close the
    channel there.  It is the conservative bound of the zones, not a defect: a
    defect is a tested variant whose motion jams, changes contact sequence or
    deviates by more than d (:mod:`cspace.defects`).  Its ``depth`` and ``gap``
    are in follower units (rad, or model units for a slide).

    Parameters
    ----------
    zones : ZoneAnalysis
    cs : ConfigurationSpace
        The nominal C-space the zones were computed on.
    window : (q1_lo, q1_hi, q2_lo, q2_hi), optional
        Zoom (data units, rad / model units).
    motion : SimulationResult, optional
        The nominal motion, drawn as a path.
    inset : "auto", None or (q1_lo, q1_hi, q2_lo, q2_hi)
        A zoom inset on a narrow channel: ``"auto"`` picks the narrowest
        stretch of ``motion`` when its channel is thin against the window
        (:func:`narrow_channel`), else the deepest overlap; None: no inset.
    """
    ax = new_axes(ax, (9, 6.5))
    sx, sy = _scales(cs, unit)
    _draw_faces(ax, cs, sx, sy)
    _draw_zone_layers(ax, zones, cs, sx, sy, band_color, overlap_color, labels=True)
    if motion is not None:
        plot_motion(motion, cs, ax=ax, unit=unit)
    w = window or cs.window
    ax.set_xlim(w[0] * sx, w[1] * sx)
    ax.set_ylim(w[2] * sy, w[3] * sy)
    _axis_labels(ax, cs.pair, unit)
    ax.set_title(title or f"Contact zones of {plain_text(cs.pair.name)}: "
                          f"{len(zones.overlaps)} zone overlap(s)")
    if legend:
        from matplotlib.patches import Patch
        handles, labels = ax.get_legend_handles_labels()
        extra = _space_handles() + [Patch(facecolor=band_color, alpha=0.35,
                                          label="zone band (tolerance box)")]
        ax.legend(handles=extra + handles, fontsize=7, loc="upper left",
                  bbox_to_anchor=(1.01, 1.0), frameon=False)
    box = None
    what = "zoom on the narrowest channel"
    if isinstance(inset, str) and inset == "auto":
        box = narrow_channel(cs, motion) if motion is not None else None
        if box is None and zones.overlaps:
            what = "zoom on the deepest zone overlap"
            o = max(zones.overlaps, key=lambda o: o.depth)
            h2 = max(3.0 * o.gap, 2.0 * o.depth, SLACK)
            # around the deepest point, at most three times as wide as high:
            # the whole overlap's driver range squeezed a channel upright
            h1 = max(min(o.q1_range[1] - o.q1_range[0], 3.0 * h2),
                     0.02 * (cs.window[1] - cs.window[0]))
            box = (o.q[0] - h1, o.q[0] + h1, o.q[1] - h2, o.q[1] + h2)
            _, wy = cs.window[2], cs.window[3] - cs.window[2]
            if 2 * h2 > 0.1 * wy:
                box = None          # wide enough to read without a zoom
    elif inset is not None:
        box = tuple(float(v) for v in inset)
    if box is not None:
        def draw(ia):
            _draw_faces(ia, cs, sx, sy)
            _draw_zone_layers(ia, zones, cs, sx, sy, band_color, overlap_color, labels=False)
            if motion is not None:
                plot_motion(motion, cs, ax=ia, unit=unit)
        add_zoom_inset(ax, box, draw, sx=sx, sy=sy, title=what)
    return ax


def _draw_zone_layers(ax, zones, cs, sx, sy, band_color, overlap_color, labels):
    from .geom2d import TWO_PI
    lo2 = cs.window[2]
    shifts = (-TWO_PI, 0.0, TWO_PI) if cs.periodic[1] else (0.0,)
    for k, (lab, br, pl) in enumerate(cs.curve_polylines(boundary_only=True)):
        ax.plot(pl[:, 0] * sx, pl[:, 1] * sy, color="k", lw=0.7,
                label="nominal contact curve" if labels and k == 0 else None)
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
        xs, ys = _overlap_line(o, cs)
        ax.plot(xs * sx, ys * sy, color=overlap_color, lw=3, alpha=0.8,
                solid_capstyle="butt",
                label="zone overlap (bound, not a defect)" if labels and k == 0 else None)
        ax.plot([o.q[0] * sx], [o.q[1] * sy], marker="o", mfc="none", color=overlap_color,
                ms=10, ls="none", label="deepest point of an overlap" if labels and k == 0
                else None)


def _overlap_line(o, cs, n: int = 200):
    """Where a zone overlap is drawn: along its channel's mid-line (between
    the nominal curves bounding it) over its driver range, broken where a
    periodic follower coordinate wraps; a level line through its deepest
    point where the curves cannot be evaluated there."""
    from .geom2d import TWO_PI
    a, b = o.q1_range
    xs = np.linspace(a, b, n)
    with np.errstate(invalid="ignore"):
        fl = np.asarray(cs.curves[o.lower_curve].evaluate(xs), dtype=float)
        fu = np.asarray(cs.curves[o.upper_curve].evaluate(xs), dtype=float)
        gap = fu - fl
        if cs.periodic[1]:
            gap = gap % TWO_PI
        ys = fl + 0.5 * gap
        if cs.periodic[1]:
            ys = (ys - cs.window[2]) % TWO_PI + cs.window[2]
    if not np.isfinite(ys).any():
        return np.array([a, b]), np.array([o.q[1], o.q[1]])
    if cs.periodic[1] and len(ys) > 1:
        jump = np.nonzero(np.abs(np.diff(ys)) > np.pi)[0] + 1
        xs, ys = np.insert(xs, jump, np.nan), np.insert(ys, jump, np.nan)
    return xs, ys


def narrow_channel(cs, sim, *, thin: float = 0.05, zoom: float = 8.0):
    """A window around the narrowest stretch of a motion's channel, when the
    channel is thin against the C-space window (its typical width below
    ``thin`` times the follower range), else None.

    The channel width at a sample is the free follower interval that holds the
    motion there; the window is centred on the middle of the longest run of
    samples no wider than twice the median width, ``zoom`` widths high and a
    tenth of the driver range wide.

    Returns
    -------
    (q1_lo, q1_hi, q2_lo, q2_hi) or None
    """
    q1 = np.asarray(sim.q1, dtype=float)
    q2 = np.asarray(sim.q2, dtype=float)
    if len(q1) < 3:
        return None
    lo1, hi1, lo2, hi2 = cs.window
    idx = np.unique(np.linspace(0, len(q1) - 1, min(len(q1), 200)).round().astype(int))
    widths, centres = [], []
    for i in idx:
        x, y = float(q1[i]), float(q2[i])
        if cs.periodic[1]:
            y = (y - lo2) % (hi2 - lo2) + lo2
        w = np.inf
        c = y
        for a, b, _ in cs.free_intervals(x):
            for sh in ((-(hi2 - lo2), 0.0, hi2 - lo2) if cs.periodic[1] else (0.0,)):
                if a + sh - SLACK <= y <= b + sh + SLACK and np.isfinite(b - a):
                    w, c = b - a, 0.5 * (a + b) + sh
        widths.append(w)
        centres.append(c)
    widths = np.asarray(widths)
    ok = np.isfinite(widths) & (widths > 0)
    if not ok.any():
        return None
    med = float(np.median(widths[ok]))
    if med >= thin * (hi2 - lo2):
        return None
    good = ok & (widths <= 2.0 * med)
    best, run, start_best, start = 0, 0, 0, 0
    for j, g in enumerate(good):
        if g:
            if run == 0:
                start = j
            run += 1
            if run > best:
                best, start_best = run, start
        else:
            run = 0
    j = start_best + best // 2
    i = idx[j]
    x = float(q1[i])
    if cs.periodic[0]:
        x = (x - lo1) % (hi1 - lo1) + lo1
    h1 = 0.05 * (hi1 - lo1)
    x = min(max(x, lo1 + h1), hi1 - h1)      # the zoom stays inside the window
    h2 = 0.5 * zoom * widths[j]
    return (x - h1, x + h1, centres[j] - h2, centres[j] + h2)


def add_zoom_inset(ax, box, draw, *, sx: float = 1.0, sy: float = 1.0,
                   bounds=(1.04, 0.0, 0.42, 0.42), title: str = "zoom on the narrowest channel"):
    """An inset of ``ax`` showing ``box`` (q1_lo, q1_hi, q2_lo, q2_hi; data units),
    drawn by ``draw(inset_axes)``, with the zoomed region outlined on ``ax``.
    ``bounds`` (x, y, width, height in axes fractions) default to a panel right
    of the axes, below the legend, so that the zoom hides no data.
    Returns the inset Axes."""
    ia = ax.inset_axes(list(bounds))
    draw(ia)
    ia.set_xlim(box[0] * sx, box[1] * sx)
    ia.set_ylim(box[2] * sy, box[3] * sy)
    ia.tick_params(labelsize=6)
    ia.set_title(title, fontsize=7)
    ax.indicate_inset_zoom(ia, edgecolor="0.2")
    return ia


def plot_failures(cs, results, *, ax=None, unit: str = "rad", labels=None, pair_index: int = 0,
                  title: str | None = None):
    """Defective variants marked where they fail, over the nominal C-space.

    Parameters
    ----------
    cs : ConfigurationSpace
        The nominal C-space of pair ``pair_index``.
    results : sequence of cspace.defects.DefectResult
        Defect tests; each defective one with a location (``where``: pair, q1,
        q2) on this pair is marked by its first reason (a jam by its jam, where
        the drive meets it).
    labels : sequence of str, optional
        A label per result (e.g. its check-list index), written beside its mark.
    """
    from .defects import main_reason
    ax = plot_cspace(cs, ax=ax, unit=unit, legend=False,
                     title=title or f"Where defective variants of {plain_text(cs.pair.name)} "
                                    f"fail")
    sx, sy = _scales(cs, unit)
    markers = {"JAM": "X", "TOPOLOGY": "s", "DEVIATION": "^", "INVALID": "D"}
    seen = set()
    marks = []
    # variants failing at one place (within 1 % of the window: one spot on the
    # plot) share one mark
    groups: dict = {}
    span = max(cs.window[1] - cs.window[0], cs.window[3] - cs.window[2])
    for k, r in enumerate(results):
        if not r.defective or not r.where or int(r.where[0]) != pair_index:
            continue
        # a jam is marked where the drive meets it (DefectResult.where)
        main = main_reason(getattr(r, "reasons", ()))
        reason = main.name if main is not None else "INVALID"
        x, y = _wrapped_path(cs, [r.where[1]], [r.where[2]])
        key = (reason, round(float(x[0]) / span, 2), round(float(y[0]) / span, 2))
        groups.setdefault(key, [x[0], y[0], []])[2].append(k)
    placed: list = []
    for (reason, _, _), (x, y, ks) in groups.items():
        ln, = ax.plot([x * sx], [y * sy], markers.get(reason, "o"), color=FAIL_COLOR, mec="k",
                      ms=8, ls="none", zorder=6, label=reason.lower())
        if reason not in seen:
            marks.append(ln)
        seen.add(reason)
        if labels is not None:
            names = [str(labels[k]) for k in ks]
            text = ", ".join(names) if len(names) <= 3 else f"{names[0]} .. {names[-1]}"
            text += f" ({len(ks)})" if len(ks) > 1 else ""
            # labels of nearby marks are stacked, not printed over each other
            near = sum(1 for px, py in placed
                       if abs(px - x) < 0.05 * span and abs(py - y) < 0.05 * span)
            placed.append((x, y))
            ax.annotate(plain_text(text), (x * sx, y * sy), fontsize=6,
                        xytext=(5, 5 + 8 * near), textcoords="offset points")
    ax.legend(handles=_space_handles() + marks, fontsize=7, loc="upper left",
              bbox_to_anchor=(1.01, 1.0), frameon=False,
              title="defect (a jam, else the first reason)", title_fontsize=7)
    return ax


def plot_parts_overlay(before: Pair, after: Pair, q=(0.0, 0.0), *, ax=None,
                       title: str | None = None, exaggerate: float = 1.0):
    """The parts of two designs drawn over each other at ``q``: the initial
    design dashed, the final one solid (a before/after overlay of a synthesis).

    ``exaggerate`` is only shown in the title: pass geometry already scaled
    when the changes are too small to see (a synthesis moves dimensions by
    fractions of their tolerance)."""
    ax = new_axes(ax, (7, 7))
    for pair, ls, lw, tag in ((before, "--", 1.0, "before"), (after, "-", 1.3, "after")):
        for part, qq, col in zip(pair.parts, q, ("tab:blue", "tab:red")):
            first = True
            for lp in part.loops:
                pts = lp.sample(720)
                pts = np.vstack([pts, pts[:1]])
                w = place_points(part.axis, np.full(len(pts), float(qq)), pts)
                ax.plot(w[:, 0], w[:, 1], color=col, lw=lw, ls=ls,
                        label=f"{plain_text(part.name)} {tag}" if first else None)
                first = False
    ax.set_aspect("equal")
    ax.set_xlabel(f"x [{plain_text(after.units)}]")
    ax.set_ylabel(f"y [{plain_text(after.units)}]")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title(title or f"{plain_text(after.name)}: before (dashed) and after (solid)"
                          + (f", changes x{exaggerate:g}" if exaggerate != 1.0 else ""))
    return ax


def plot_output(sims, *, ax=None, labels=None, unit: str = "rad", title: str | None = None):
    """Output functions f(q1) of one or more simulations (nominal first).

    ``unit`` is the angle unit of a rotating driver's and follower's axis; a
    sliding one's is in the pair's length unit (:attr:`SimulationResult.units
    <cspace.simulate.SimulationResult.units>`).  Each axis label names its unit."""
    from .argcheck import getunit
    f = 1.0 / getunit(unit)
    ax = new_axes(ax, (9, 4.5))
    sims = list(sims)
    labels = labels or [s.pair for s in sims]
    for k, (s, lab) in enumerate(zip(sims, labels)):
        f1 = f if _rot_driver(s) else 1.0
        f2 = f if _rot_output(s) else 1.0
        ax.plot(s.q1 * f1, s.q2 * f2,
                lw=1.6 if k == 0 else 0.9, color="k" if k == 0 else None,
                alpha=1.0 if k == 0 else 0.7, label=plain_text(lab))
        if s.jam_q is not None:
            ax.plot([s.jam_q[0] * f1], [s.jam_q[1] * f2], "rx", ms=9)
    first = sims[0] if sims else None
    ax.set_xlabel(f"driver q1 [{_axis_unit(first, 0, unit)}]")
    ax.set_ylabel(f"follower output f(q1) [{_axis_unit(first, 1, unit)}]")
    ax.set_title(title or "Output function")
    if len(sims) <= 12:
        ax.legend(fontsize=7)
    return ax


def _rotating(sim, i: int) -> bool:
    rot = getattr(sim, "rotating", True)
    return bool(rot[i]) if isinstance(rot, (tuple, list)) else bool(rot)


def _rot_output(sim) -> bool:
    return _rotating(sim, 1)


def _rot_driver(sim) -> bool:
    return _rotating(sim, 0)


def _axis_unit(sim, i: int, angle_unit: str) -> str:
    """The unit of coordinate q{i + 1} of ``sim`` for an axis label: the angle
    unit of a rotating part, the pair's length unit (as its file states it) of
    a sliding one ("length" when the result does not say)."""
    if sim is None or _rotating(sim, i):
        return plain_text(angle_unit)
    return plain_text(getattr(sim, "units", "") or "length")


class AnimationFile:
    """What :func:`animate_motion` wrote.

    Attributes
    ----------
    path : pathlib.Path
        The GIF.
    frames : int
        Frames in the file.
    event : str
        ``"jam"``, ``"deviation"``, ``"start blocked"`` or ``""`` (none).
    event_frame : int or None
        The frame where the event is first seen (0-based).
    event_q : (float, float) or None
        The configuration of the event.
    """

    __slots__ = ("path", "frames", "event", "event_frame", "event_q")

    def __init__(self, path, frames, event="", event_frame=None, event_q=None):
        self.path, self.frames, self.event = path, frames, event
        self.event_frame, self.event_q = event_frame, event_q

    def __repr__(self):
        ev = (f", {self.event} at frame {self.event_frame} (q = ({self.event_q[0]:.5g}, "
              f"{self.event_q[1]:.5g}))" if self.event else ", no jam or deviation")
        return f"<AnimationFile {self.path.name}: {self.frames} frames{ev}>"


def _deviation_index(cs, sim, nominal, d):
    """First sample of ``sim`` deviating from ``nominal`` by more than ``d``
    (C-space metric), or None."""
    if nominal is None or d is None or len(sim.q1) == 0:
        return None
    s2 = 1.0 / follower_scale(cs.pair)
    lo, hi = min(nominal.q1[0], nominal.q1[-1]), max(nominal.q1[0], nominal.q1[-1])
    inside = (sim.q1 >= lo) & (sim.q1 <= hi)
    dev = np.zeros(len(sim.q1))
    dev[inside] = np.abs(sim.q2[inside] - nominal.output_at(sim.q1[inside])) * s2
    over = np.nonzero(dev > d)[0]
    return int(over[0]) if len(over) else None


def _animation_args(path, frames, hold, fps, d):
    """Checked ``frames``, ``hold``, ``fps``, ``d`` and the ``.gif`` path of an animation."""
    from pathlib import Path as _Path

    from .argcheck import getint, getscalar
    from .errors import InputError
    frames = getint(frames, "frames", minimum=2)
    hold = getint(hold, "hold", minimum=0)
    fps = getscalar(fps, "fps", positive=True)
    if d is not None:
        d = getscalar(d, "d", positive=True)
    path = _Path(path)
    if path.suffix.lower() != ".gif":
        raise InputError(f"an animation is written as GIF: the path must end in .gif, got "
                         f"{path.name!r}", name="path", value=str(path))
    return path, frames, hold, fps, d


def _first_event(cs, sim, nominal, d):
    """The event to mark, ``(name, sample)``: a blocked start, the jam or the first
    deviation from ``nominal``, whichever comes first; ``("", None)`` if none."""
    from .simulate import SimStatus
    n = len(sim.q1)
    event, ev = "", None
    if sim.status == SimStatus.START_BLOCKED:
        event, ev = "start blocked", 0
    elif sim.status == SimStatus.JAMMED:
        event, ev = "jam", n - 1
    dv = _deviation_index(cs, sim, nominal, d)
    if dv is not None and (ev is None or dv < ev):
        event, ev = "deviation", dv
    return event, ev


def _frame_schedule(n, frames, ev, hold):
    """Samples shown, ``(idx, seq, event_frame)``: ``frames`` evenly spaced samples of
    ``n`` (all of them if fewer), in increasing order, the first and the last
    always among them, with the event sample ``ev`` among them; the frame
    sequence with the event held ``hold`` extra frames; and the first frame
    showing the event.

    An event between the evenly spaced samples replaces the nearest one
    inside the drive, never the first or the last, so the count stays.  With
    only the two end frames an event inside the drive has no frame of its
    own: it is shown (and held) from the last frame."""
    idx = [int(i) for i in np.unique(np.linspace(0, max(n - 1, 0), min(frames, max(n, 1)))
                                     .round().astype(int))]
    if ev is not None and ev not in idx and len(idx) > 2:
        inner = range(1, len(idx) - 1)
        near = min(inner, key=lambda k: abs(idx[k] - ev))
        idx[near] = int(ev)
    # the frame where the event is first seen: the event's own or the next one
    at = next((i for i in idx if i >= ev), None) if ev is not None else None
    seq = []
    for i in idx:
        seq.append(i)
        if i == at:
            seq += [i] * hold
    event_frame = seq.index(at) if at is not None else None
    return idx, seq, event_frame


def _parts_view(pair, sim, idx):
    """Fixed view of the parts, ``(lo, hi, pad)``: everything they sweep over the
    samples ``idx``."""
    pts = []
    for part, k in zip(pair.parts, (0, 1)):
        qs = np.asarray([sim.q1[i] if k == 0 else sim.q2[i] for i in idx], dtype=float)
        for lp in part.loops:
            smp = lp.sample(90)
            for qq in qs:
                pts.append(place_points(part.axis, np.full(len(smp), qq), smp))
    pts = np.vstack(pts)
    lo, hi = pts.min(0), pts.max(0)
    pad = 0.05 * float(np.max(hi - lo))
    return lo, hi, pad


def _cspace_panel(ax, cs, sim, nominal, unit, sx, sy, event, jammed):
    """The C-space with the whole path, drawn once, and its legend; returns the
    markers that the frames move: ``(trail, dot, event mark, jam mark)``."""
    plot_cspace(cs, ax=ax, unit=unit, legend=False, lw=0.8,
                title=f"C-space of {plain_text(cs.pair.name)}")
    nom_line = []
    if nominal is not None:
        x0, y0 = _wrapped_path(cs, nominal.q1, nominal.q2)
        nom_line = ax.plot(x0 * sx, y0 * sy, color="k", lw=1.0, ls="--", label="nominal motion")
    xw, yw = _wrapped_path(cs, sim.q1, sim.q2)
    ahead, = ax.plot(xw * sx, yw * sy, color=PATH_COLOR, lw=1.0, alpha=0.35,
                     label="motion path (whole)")
    trail, = ax.plot([], [], color=PATH_COLOR, lw=2.0, label="motion path (travelled)")
    dot, = ax.plot([], [], "o", color="k", ms=7, zorder=7, label="configuration")
    evm, = ax.plot([], [], "X", color=FAIL_COLOR, mec="k", ms=13, zorder=8,
                   label=f"{event} (first)" if event else "event")
    jam_m, = ax.plot([], [], "X", color="orange", mec="k", ms=11, zorder=8, label="jam")
    mine = nom_line + [ahead, trail, dot] + ([evm] if event else []) + ([jam_m] if jammed else [])
    ax.legend(handles=_space_handles() + mine, fontsize=7, loc="upper center",
              bbox_to_anchor=(0.5, -0.13), frameon=False, ncol=3)
    return trail, dot, evm, jam_m


def _parts_frame(ax, pair, q, view, title, hit):
    """Left panel of one frame: the parts at ``q`` in the fixed ``view``, titled in
    red once the event has been seen (``hit``)."""
    lo, hi, pad = view
    ax.clear()
    plot_parts(pair, q, ax=ax, title="")
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_title(title, color=FAIL_COLOR if hit else "k", fontsize=10)


def _cspace_frame(markers, cs, sim, i, q, sx, sy, jam_now, ev, pulse):
    """Right panel of one frame: the path travelled up to sample ``i``, the
    configuration ``q``, the jam mark when ``jam_now`` and the event mark of sample
    ``ev`` (None: hidden), enlarged on odd ``pulse``."""
    trail, dot, evm, jam_m = markers
    if jam_now:
        jx, jy = _wrapped_path(cs, [sim.q1[-1]], [sim.q2[-1]])
        jam_m.set_data(jx * sx, jy * sy)
    else:
        jam_m.set_data([], [])
    xs, ys = _wrapped_path(cs, sim.q1[:i + 1], sim.q2[:i + 1])
    trail.set_data(xs * sx, ys * sy)
    px, py = _wrapped_path(cs, [q[0]], [q[1]])
    dot.set_data(px * sx, py * sy)
    if ev is not None:
        ex, ey = _wrapped_path(cs, [sim.q1[ev]], [sim.q2[ev]])
        evm.set_data(ex * sx, ey * sy)
        # the held event frames pulse (the GIF writer merges equal frames)
        evm.set_markersize(13 + 5 * pulse)
    else:
        evm.set_data([], [])


def _write_gif(anim, fig, path, fps, dpi, plt):
    """Render ``anim`` to ``path`` atomically (through a hidden temporary file) and
    close ``fig``, also on failure."""
    from matplotlib.animation import PillowWriter
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    try:
        anim.save(str(tmp), writer=PillowWriter(fps=fps), dpi=dpi)
        from .io import atomic_write
        atomic_write(path, tmp.read_bytes())
    finally:
        plt.close(fig)
        if tmp.exists():
            tmp.unlink()


def animate_motion(cs, sim, path, *, nominal=None, d: float | None = None, frames: int = 48,
                   fps: int = 10, unit: str = "rad", dpi: int = 72, title: str | None = None,
                   hold: int = 4) -> AnimationFile:
    """A GIF of a pair moving over its drive (left) with its C-space (right): the
    configuration moves along the motion path, and the frame where the drive
    jams, or the output first deviates from ``nominal`` by more than ``d``, is
    marked in red.

    Parameters
    ----------
    cs : ConfigurationSpace
        The C-space of the pair as simulated (nominal, or a variant).
    sim : SimulationResult
        Its motion (:func:`cspace.simulate.simulate`,
        :func:`mechanisms.analysis.motion_at`).
    path : path-like
        The ``.gif`` file (written atomically, matplotlib's Pillow writer).
    nominal : SimulationResult, optional
        The nominal motion: drawn as a dashed path, and the reference of the
        deviation mark.
    d : float, optional
        Deviation threshold (C-space metric: rad, or slide / characteristic
        length); with ``nominal``, the first sample beyond it is marked.
    frames : int
        Frames along the motion (>= 2), evenly spaced in samples from the
        start of the drive to its end (or the jam), in drive order; the event
        frame is one of them (it replaces the nearest evenly spaced frame
        inside the drive; with ``frames=2`` an event inside the drive is shown
        from the last frame) and is held ``hold`` extra frames, so the file
        has ``frames + hold`` frames when there is an event.  A motion of
        fewer samples gives one frame per sample.
    hold : int
        Extra frames (>= 0) holding the event frame, its mark pulsing.
    fps : int
        Frames per second.

    Returns
    -------
    AnimationFile
        The path, the number of frames written and the event frame.

    Examples
    --------
    >>> from mechanisms.analysis import motion_at              # doctest: +SKIP
    >>> (cs,), (sim,) = motion_at(reciprocating_cam())           # doctest: +SKIP
    >>> animate_motion(cs, sim, "cam.gif")                       # doctest: +SKIP
    <AnimationFile cam.gif: 48 frames, no jam or deviation>
    """
    path, frames, hold, fps, d = _animation_args(path, frames, hold, fps, d)
    plt = pyplot()
    from matplotlib.animation import FuncAnimation

    from .simulate import SimStatus
    n = len(sim.q1)
    event, ev = _first_event(cs, sim, nominal, d)
    idx, seq, event_frame = _frame_schedule(n, frames, ev, hold)
    jammed = sim.status == SimStatus.JAMMED and event != "jam" and n > 0

    pair = cs.pair
    sx, sy = _scales(cs, unit)
    u1, u2 = (plain_text(unit) if isinstance(part.axis, Rotation) else plain_text(pair.units)
              for part in (pair.driver, pair.follower))
    fig = new_figure(figsize=(11, 5))
    a0, a1 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.25]})
    view = _parts_view(pair, sim, idx)
    markers = _cspace_panel(a1, cs, sim, nominal, unit, sx, sy, event, jammed)

    def draw(j):
        i = seq[j]
        q = (float(sim.q1[i]), float(sim.q2[i]))
        hit = ev is not None and i >= ev and j >= event_frame
        jam_now = jammed and i == n - 1
        now = (event.upper() if hit and i == ev else "JAMMED" if jam_now
               else f"after {event}" if hit else "")
        _parts_frame(a0, pair, q, view,
                     f"q1 = {q[0] * sx:.4g} {u1}, q2 = {q[1] * sy:.4g} {u2}"
                     + (f"   {now}" if now else ""),
                     hit)
        _cspace_frame(markers, cs, sim, i, q, sx, sy, jam_now, ev if hit else None,
                      (j - event_frame) % 2 if hit else 0)
        return markers

    fig.subplots_adjust(bottom=0.24, wspace=0.3)
    fig.suptitle(title or f"{plain_text(pair.name)}: motion over the drive"
                 + (f" ({event} marked)" if event else ""))
    anim = FuncAnimation(fig, draw, frames=len(seq), blit=False)
    _write_gif(anim, fig, path, fps, dpi, plt)
    evq = ((float(sim.q1[ev]), float(sim.q2[ev])) if ev is not None and n else None)
    return AnimationFile(path, len(seq), event, event_frame, evq)
