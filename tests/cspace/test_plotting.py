"""Plots and animations (issue 24): legends, holes drawn empty, zoom insets,
failure marks, before/after overlay, and the motion GIF with its frame count."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from cspace import plotting as P


@pytest.fixture(scope="module")
def cam():
    from mechanisms.analysis import motion_at
    from mechanisms.models import reciprocating_cam
    m = reciprocating_cam()
    (cs,), (sim,) = motion_at(m, accuracy="fast")
    return m, cs, sim


@pytest.fixture(scope="module")
def geneva_fast():
    from mechanisms.analysis import motion_at
    from mechanisms.models import geneva
    (cs,), (sim,) = motion_at(geneva(), accuracy="fast")
    return cs, sim


def _legend_texts(ax):
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_cspace_legend_names_free_blocked_curves_and_path(cam):
    _, cs, sim = cam
    ax = P.plot_cspace(cs, motion=sim)
    texts = _legend_texts(ax)
    assert texts[:2] == ["free", "blocked"]
    assert "motion path" in texts
    # user segment names of the model, not L0S0
    assert any("finger0.tip" in t for t in texts)
    assert not any("L0S" in t for t in texts)
    matplotlib.pyplot.close(ax.figure)


def test_zone_legend_names_every_layer(cam):
    from cspace.zones import contact_zones
    m, cs, sim = cam
    zones = contact_zones(cs, m, 0, "fast", cells=sim.cells)
    assert zones.overlaps
    ax = P.plot_zones(zones, cs, motion=sim)
    texts = _legend_texts(ax)
    for want in ("free", "blocked", "zone band (tolerance box)", "nominal contact curve",
                 "zone overlap (bound, not a defect)", "motion path"):
        assert want in texts, want
    matplotlib.pyplot.close(ax.figure)


def test_holes_are_drawn_empty():
    """A square plate with a square hole: the hole's centre stays white."""
    from cspace.geometry import Line, Loop, Pair, Part, Rotation

    def square(h, ccw=True, x=0.0):
        pts = [(x - h, -h), (x + h, -h), (x + h, h), (x - h, h)]
        if not ccw:
            pts = pts[::-1]
        return Loop(tuple(Line(pts[i], pts[(i + 1) % 4]) for i in range(4)))
    plate = Part("plate", (square(2.0), square(1.0, ccw=False)), Rotation((0.0, 0.0)))
    pin = Part("pin", (square(0.2, x=5.0),), Rotation((5.0, 0.0)))
    ax = P.plot_parts(Pair(plate, pin, "mm", "plate"), (0.0, 0.0), show_axes=False)
    ax.set_xlim(-2.5, 5.5)
    ax.set_ylim(-2.5, 2.5)
    fig = ax.figure
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)

    def pixel(x, y):
        px, py = ax.transData.transform((x, y))
        h = img.shape[0]
        return img[int(h - py), int(px)]
    assert (pixel(0.0, 0.0) == 255).all()            # the hole: empty
    assert (pixel(1.5, 0.0) < 250).any()             # the plate: filled
    matplotlib.pyplot.close(fig)


def test_narrow_channel_inset_on_the_geneva_lock(geneva_fast):
    cs, sim = geneva_fast
    box = P.narrow_channel(cs, sim)
    assert box is not None
    q1lo, q1hi, q2lo, q2hi = box
    assert cs.window[0] <= q1lo < q1hi <= cs.window[1]
    assert q2hi - q2lo < 0.15 * (cs.window[3] - cs.window[2])      # a real zoom
    ax = P.plot_cspace(cs, motion=sim, inset="auto")
    assert len(ax.child_axes) == 1
    ia = ax.child_axes[0]
    np.testing.assert_allclose(ia.get_ylim(), (q2lo, q2hi), atol=1e-12)
    matplotlib.pyplot.close(ax.figure)
    # a wide channel gets no zoom
    from mechanisms.analysis import motion_at
    from mechanisms.models import reciprocating_cam
    (cs2,), (sim2,) = motion_at(reciprocating_cam(), accuracy="fast")
    assert P.narrow_channel(cs2, sim2) is None


def test_failures_are_marked_where_they_fail(cam):
    from cspace.defects import is_defective
    m, cs, _ = cam
    u = m.nominal + 6 * m.tol * np.where(np.arange(m.n) % 2, 1.0, -1.0)
    r = is_defective(m, u, accuracy="fast")
    assert r.defective and r.where is not None
    ax = P.plot_failures(cs, [r], labels=["v0"])
    marks = [ln for ln in ax.lines if ln.get_color() == P.FAIL_COLOR]
    assert len(marks) == 1
    x, y = marks[0].get_data()
    np.testing.assert_allclose([x[0], y[0]], [r.where[1] % (2 * np.pi), r.where[2]], atol=1e-9)
    # a jam is marked as a jam, where the drive meets it
    shown = "jam" if any(x.name == "JAM" for x in r.reasons) else r.reasons[0].name.lower()
    assert shown in _legend_texts(ax)
    matplotlib.pyplot.close(ax.figure)


def test_a_jam_is_marked_where_the_drive_meets_it(cam):
    """A variant whose channel splits (a topology change a probe finds near
    the drive's start) and whose drive jams later: the full test places it,
    and the plot marks it, where the drive jams."""
    import re

    from cspace.defects import Reason, is_defective, reference
    from synthesis.verify import box_samples
    m, cs, _ = cam
    ref = reference(m, "fast")
    U = box_samples(m.nominal, 1.5 * m.tol, 60, seed=1)
    rs = [is_defective(m, u, ref=ref) for u in U]
    jams = [r for r in rs if Reason.JAM in r.reasons and Reason.TOPOLOGY in r.reasons]
    assert jams
    for r in jams:
        q1 = float(re.search(r"driver blocked at q1 = ([-0-9.e+]+)", r.message).group(1))
        assert abs(r.where[1] - q1) <= 1e-5 * max(1.0, abs(q1)), (r.where, r.message)
    ax = P.plot_failures(cs, jams)
    assert "jam" in _legend_texts(ax) and "topology" not in _legend_texts(ax)
    matplotlib.pyplot.close(ax.figure)


def test_parts_overlay_before_after(cam):
    m, _, _ = cam
    before = m.build()
    after = m.with_nominal(m.nominal + 10 * m.tol).build()
    ax = P.plot_parts_overlay(before, after)
    texts = _legend_texts(ax)
    assert texts == ["cam before", "yoke before", "cam after", "yoke after"]
    styles = {ln.get_label(): ln.get_linestyle() for ln in ax.lines}
    assert styles["cam before"] == "--" and styles["cam after"] == "-"
    matplotlib.pyplot.close(ax.figure)


def test_animation_frame_count_and_event(cam, tmp_path):
    from PIL import Image

    from mechanisms.analysis import motion_at
    m, cs0, sim0 = cam
    a = P.animate_motion(cs0, sim0, tmp_path / "nominal.gif", frames=9)
    assert a.frames == 9 and a.event == "" and a.event_frame is None
    assert Image.open(a.path).n_frames == 9
    # a variant that deviates first and then jams: the event frame is marked and held
    u = m.nominal + 6 * m.tol * np.where(np.arange(m.n) % 2, 1.0, -1.0)
    (cs,), (sim,) = motion_at(m, u, accuracy="fast")
    assert sim.status.name == "JAMMED"
    b = P.animate_motion(cs, sim, tmp_path / "variant.gif", nominal=sim0, d=0.01, frames=10,
                         hold=3)
    assert b.event == "deviation" and b.frames == 10 + 3
    assert Image.open(b.path).n_frames == b.frames
    assert 0 < b.event_frame < b.frames
    # without the nominal the jam is the event, in the last frame
    c = P.animate_motion(cs, sim, tmp_path / "jam.gif", frames=6, hold=0)
    assert c.event == "jam" and c.event_frame == c.frames - 1
    np.testing.assert_allclose(c.event_q, sim.jam_q, atol=1e-9)
    assert "frames" in repr(c) and "jam at frame" in repr(c)


def _check_schedule(n, frames, ev, hold):
    idx, seq, event_frame = P._frame_schedule(n, frames, ev, hold)
    assert idx[0] == 0 and idx[-1] == n - 1                 # start and end (or jam)
    assert len(idx) == min(frames, n)                        # the count asked
    assert all(a < b for a, b in zip(idx, idx[1:]))          # drive order, no repeats
    assert seq[0] == 0 and seq[-1] == n - 1
    assert sorted(set(seq)) == idx
    if ev is None:
        assert seq == idx and event_frame is None
        return idx, seq, event_frame
    assert len(seq) == len(idx) + hold
    if ev in idx or len(idx) > 2:
        assert ev in idx and seq[event_frame] == ev
    else:                                   # two end frames: seen from the last
        assert seq[event_frame] == n - 1
    assert seq[event_frame:event_frame + hold + 1] == [seq[event_frame]] * (hold + 1)
    return idx, seq, event_frame


def test_frame_schedule_keeps_the_start_and_the_count():
    """An event just after the start (the reported case: 12 frames of 1268
    samples, the first deviation at sample 54) takes the place of the second
    frame, not the first: the animation starts at the start of the drive."""
    idx, seq, k = _check_schedule(1268, 12, 54, 4)
    assert idx[:2] == [0, 54] and k == 1
    assert seq[:7] == [0, 54, 54, 54, 54, 54, idx[2]]
    # just before the end: the end stays the last frame
    idx, seq, k = _check_schedule(1268, 12, 1260, 4)
    assert idx[-2:] == [1260, 1267] and seq[-1] == 1267
    # a blocked start and a jam are the first and the last frame
    assert _check_schedule(1268, 12, 0, 4)[2] == 0
    idx, seq, k = _check_schedule(1268, 12, 1267, 4)
    assert k == len(seq) - 5
    # two frames: the ends, the event seen (and held) at the last
    idx, seq, k = _check_schedule(100, 2, 40, 3)
    assert idx == [0, 99] and seq == [0, 99, 99, 99, 99] and k == 1
    # fewer samples than frames: every sample once
    assert _check_schedule(5, 12, 2, 1)[0] == [0, 1, 2, 3, 4]


@pytest.mark.parametrize("n", [2, 3, 7, 50, 1268])
@pytest.mark.parametrize("frames", [2, 3, 4, 12, 48])
def test_frame_schedule_invariants(n, frames):
    _check_schedule(n, frames, None, 4)
    for ev in sorted({0, 1, n // 3, n // 2, n - 2, n - 1}):
        _check_schedule(n, frames, ev, 4)


def test_animation_input_is_checked(cam, tmp_path):
    from cspace.errors import InputError
    _, cs, sim = cam
    with pytest.raises(InputError, match="must end in .gif"):
        P.animate_motion(cs, sim, tmp_path / "x.png")
    with pytest.raises(InputError, match="frames must be an int >= 2"):
        P.animate_motion(cs, sim, tmp_path / "x.gif", frames=1)
    with pytest.raises(InputError, match=r"hold must be an int >= 0, got -1"):
        P.animate_motion(cs, sim, tmp_path / "x.gif", hold=-1)


def test_new_axes_makes_a_figure_of_the_size_asked_or_passes_ax_through():
    import matplotlib.pyplot as plt
    ax = P.new_axes(None, (5, 3))
    assert tuple(ax.figure.get_size_inches()) == (5, 3)
    assert P.new_axes(ax) is ax
    ax3 = P.new_axes(None, None, projection="3d")
    assert ax3.name == "3d"
    assert tuple(ax3.figure.get_size_inches()) == tuple(plt.rcParams["figure.figsize"])
    plt.close("all")


def test_a_figure_is_made_without_pyplot_where_its_backend_cannot_draw(monkeypatch, tmp_path):
    """A backend configured for a display that is not there: the figure is a
    plain Figure, which still saves."""
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    def no_display(*a, **kw):
        raise ImportError("Cannot load backend 'TkAgg' which requires the 'tk' interactive "
                          "framework, as 'headless' is currently running")
    monkeypatch.setattr(plt, "figure", no_display)
    fig = P.new_figure(figsize=(3, 2))
    assert type(fig) is Figure and tuple(fig.get_size_inches()) == (3, 2)
    ax = P.new_axes(None, (3, 2))
    ax.plot([0, 1], [0, 1])
    P.save_figure(ax, tmp_path / "f.png")
    assert (tmp_path / "f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plotting_never_changes_the_backend(tmp_path):
    """Without a display, plotting neither switches the backend nor fails: a
    figure made under a backend the old code would have replaced (``template``,
    set before) saves as PNG and the backend is still ``template``."""
    import os
    import subprocess
    import sys
    code = ("import matplotlib; matplotlib.use('template')\n"
            "from cspace.plotting import new_axes, save_figure\n"
            "ax = new_axes(); ax.plot([0, 1], [1, 0])\n"
            f"save_figure(ax, {str(tmp_path / 'p.png')!r})\n"
            "print(matplotlib.get_backend())\n")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MPLBACKEND",
                                                          "WAYLAND_DISPLAY")}
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "template"
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"


def test_plotting_modules_share_one_matplotlib_import():
    """Only cspace.plotting imports matplotlib.pyplot; the other plotting modules
    make their figures through it."""
    import inspect

    import mechanisms.linkage.plotting as lp
    import mechanisms.manipulators.plotting as mp
    import mechanisms.spatial.plotting as sp
    import synthesis.cli.plotting as syp
    import synthesis.cli.report as rep
    for mod in (lp, mp, sp, syp, rep):
        src = inspect.getsource(mod)
        assert "import matplotlib" not in src and "_plt" not in src, mod.__name__


def test_a_zone_overlap_is_drawn_along_its_channel():
    """The overlap of a channel that moves (the Scotch yoke's follower slides
    with the crank) is drawn on the channel's mid-line, between the two
    nominal curves, over its whole driver range; not as a level line."""
    from cspace.defects import reference
    from synthesis.loop import operating_zones

    from .batch.yoke import yoke
    m = yoke()
    ref = reference(m, "fast")
    cs = ref.spaces[0]
    (z,) = operating_zones(m, ref, "fast")
    (o,) = z.overlaps
    xs, ys = P._overlap_line(o, cs)
    assert xs[0] == pytest.approx(o.q1_range[0]) and xs[-1] == pytest.approx(o.q1_range[1])
    mid = 0.5 * (cs.curves[o.lower_curve].evaluate(xs) + cs.curves[o.upper_curve].evaluate(xs))
    np.testing.assert_allclose(ys, mid, atol=1e-9)
    assert np.ptp(ys) > 30            # the slide follows the crank (radius 20)
    # its deepest point lies on the line
    k = np.argmin(np.abs(xs - o.q[0]))
    assert ys[k] == pytest.approx(o.q[1], abs=0.5)


def test_a_zone_overlap_of_a_turning_follower_wraps_in_the_window():
    from cspace.defects import reference
    from mechanisms.models import geneva
    from synthesis.loop import operating_zones
    m = geneva()
    ref = reference(m, "fast")
    cs = ref.spaces[0]
    (z,) = operating_zones(m, ref, "fast")
    lo, hi = cs.window[2], cs.window[3]
    for o in z.overlaps:
        xs, ys = P._overlap_line(o, cs)
        ok = np.isfinite(ys)
        assert ok.sum() >= 100 and np.all((ys[ok] >= lo) & (ys[ok] <= hi))
        # no stroke across the window: consecutive drawn points stay close
        both = ok[1:] & ok[:-1]
        assert np.all(np.abs(np.diff(ys))[both] < np.pi)
