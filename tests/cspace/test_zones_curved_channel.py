"""Zone overlaps on curved channels: no chord sag counted as band offset.

A Scotch yoke's slot sides are, in C-space, ``q2 = a cos q1 +/- (hw - r)``.  The
crank radius ``a`` moves both together, so the channel ``2 (hw - r)`` can only
narrow by the pin and slot tolerances and the zone bands of the two sides
(computed one curve at a time) pass each other by at most
``2 (tol_r + tol_hw + tol_a |cos q1|)``.  The bands are sampled sparsely (24
samples at ``fast``); measuring a chord between band-edge samples against the
exact curve counted the sag ``a (1 - cos(pi / 23))`` (0.28 mm for a = 30 mm) as
band offset and reported an overlap that no variant reaches.
"""

import math

import numpy as np
import pytest

from cspace.defects import reference
from cspace.geometry import trusted
from cspace.zones import _edge_offset, contact_zones, varied_curve_values
from mechanisms.userfile import model_from_dict
from synthesis.loop import operating_zones

from .slotted_yoke import yoke_document


def _yoke_dict(a=30.0, s=40.0, B=60.0, window=40.0):
    """The user's Scotch yoke (a crank pin in a stadium slot of a yoke sliding
    along x), as a cspace-model file: channel 2 (hw - r) = 0.2 mm."""
    def P(n, v, t):
        return {"name": n, "nominal": v, "tol": t}
    return yoke_document([P("a", a, 0.02), P("r", 5.0, 0.01), P("hw", 5.1, 0.01),
                          P("s", s, 0.05), P("B", B, 0.5), P("H", B, 0.5)],
                         name="scotch_yoke", window=window,
                         drive=("radians(0)", "radians(360)"), q2_start=a,
                         outline_names=("bottom", "right", "top", "left"))


#: the user's yoke_mm.json (a = 30 mm) and yoke_big.json (a = 100 mm)
_SIZES = {30.0: {}, 100.0: dict(a=100.0, s=110.0, B=200.0, window=120.0)}


@pytest.mark.parametrize("a,preset", [(30.0, "fast"), (30.0, "default"), (100.0, "fast"),
                                      (100.0, "default")])
def test_curved_slot_channel_has_no_false_overlap(a, preset):
    """The slot channel (0.2 mm) narrows by at most 0.04 mm, and the two bands
    together by at most 0.12 mm: no zone overlap, in the operating region
    (``analyze``) or over the whole operating face (before the fix: 0.1187 mm
    for a = 30 mm at ``fast``, 0.0631 mm for a = 100 mm at ``default``)."""
    m = model_from_dict(_yoke_dict(**_SIZES[a]))
    ref = reference(m, preset)
    (z,) = operating_zones(m, ref, preset)
    assert z.overlaps == (), [(o.lower_label, o.upper_label, o.depth) for o in z.overlaps]
    zf = contact_zones(ref.spaces[0], m, 0, preset, faces=[ref.faces[0]])
    assert zf.overlaps == ()


@pytest.mark.parametrize("preset", ["fast", "default"])
def test_curved_band_edges_match_the_closed_form(preset):
    """The band edges of the slot sides, as q2 offsets from the nominal curves
    (what the overlaps compare), are the closed form ``tol_r + tol_hw + tol_a
    |cos q1|`` away from the curve, between the samples too (up to the band's
    own linear interpolation: 2e-4 along cos q1, 3e-3 across the kink of |cos q1|
    at q1 = pi/2, 3 pi/2); the chord sag was 0.28 mm."""
    m = model_from_dict(_yoke_dict())
    ref = reference(m, preset)
    cs = ref.spaces[0]
    (z,) = operating_zones(m, ref, preset)
    lo = next(b for b in z.bands if b.label.endswith("yoke:slot.right"))
    up = next(b for b in z.bands if b.label.endswith("yoke:slot.left"))
    xs = np.linspace(0.3, 2 * math.pi - 0.3, 1201)
    exact = 0.02 + 0.02 * np.abs(np.cos(xs))
    far = np.abs(np.cos(xs)) > 0.2  # away from the kinks
    for band, side in ((lo, +1), (up, -1), (lo, -1), (up, +1)):
        off = _edge_offset(band, xs, side, cs, False)
        assert np.all(np.isfinite(off))
        np.testing.assert_allclose(side * off[far], exact[far], rtol=0, atol=1e-3)
        assert np.max(np.abs(side * off - exact)) < 6e-3


def test_overlap_vectors_push_the_curves_into_the_channel_where_it_is_deepest():
    """A real overlap on a curved channel (the yoke of ``batch/yoke.py``: a
    0.06 mm channel that the pin and slot tolerances can close): its depth is
    the closed form 2 (0.02 + 0.02 + 0.02) - 0.06 = 0.06 at q1 = 0 and pi (not
    inflated by chord sag), and the vectors it names move the lower curve up and
    the upper curve down *there* by the bands' 0.06 each (the curve's extreme
    over its whole range may move it the other way at q1 = pi)."""
    from .batch.yoke import yoke
    m = yoke()
    ref = reference(m, "fast")
    cs = ref.spaces[0]
    (z,) = operating_zones(m, ref, "fast")
    (o,) = z.overlaps
    assert o.depth == pytest.approx(0.06, abs=2e-3)
    assert min(abs(o.q[0]), abs(o.q[0] - math.pi), abs(o.q[0] - 2 * math.pi)) < 0.15
    x = np.array([o.q[0]])

    def moved(curve, u):
        with trusted():
            pair = m.build(u)
        return float((varied_curve_values(cs.curves[curve], pair, x)
                      - cs.curves[curve].raw(x))[0])

    assert moved(o.lower_curve, o.u_lower_curve_up) == pytest.approx(0.06, abs=2e-3)
    assert moved(o.upper_curve, o.u_upper_curve_down) == pytest.approx(-0.06, abs=2e-3)
    # the per-sample vectors are box vectors that change only the curve's dependencies
    for b in z.bands:
        for U in (b.u_upper_at, b.u_lower_at):
            assert U.shape == (len(b.q1), m.n)
            for u in U:
                assert m.in_box(u)
                changed = {n for n, d in zip(m.names, u - m.nominal) if d != 0}
                assert changed <= set(b.depends)


def _capped_yoke(hw):
    """A crank pin (a = 20, r = 5 +- 0.02) in a stadium slot whose round ends
    stop it 0.03 mm short of its travel (s = 19.97, fixed): at q1 = pi/2 the
    pin's centre lies 0.03 mm beyond the end's centre, so the pin fits there
    only while hw - r >= 0.03."""
    def P(n, v, t):
        return {"name": n, "nominal": v, "tol": t}
    return model_from_dict(yoke_document(
        [P("a", 20.0, 0.0), P("r", 5.0, 0.02), P("hw", hw, 0.02), P("s", 19.97, 0.0),
         P("B", 12.0, 0.0), P("H", 35.0, 0.0)], q2_start=20.0))


def test_a_slot_end_that_closes_on_the_pin_is_a_closure():
    """hw = 5.05: the channel between the two branches of the pin's contact
    with a slot end (0.080 mm wide at q1 = pi/2) closes for hw - r < 0.03,
    which the box reaches (0.01).  The bands of the two branches stop short of
    each other (the variants that still have the contact stay open); the zones
    report a closure at both ends, whose vector jams."""
    from cspace.defects import is_defective
    m = _capped_yoke(5.05)
    ref = reference(m, "fast")
    (z,) = operating_zones(m, ref, "fast")
    closures = [o for o in z.overlaps if o.kind == "closure"]
    assert sorted(o.lower_label for o in closures) == ["crank:pin|yoke:cap.bottom",
                                                      "crank:pin|yoke:cap.top"]
    for o in closures:
        assert o.lower_label == o.upper_label and o.lower_curve != o.upper_curve
        x = o.q[0]
        assert min(abs(x - math.pi / 2), abs(x - 3 * math.pi / 2)) < 0.05
        assert o.q1_range[0] <= x <= o.q1_range[1]
        # the range holds where the worst corner (hw - r = 0.01) closes it:
        # 20 |sin q1| > 19.97 + 0.01
        t = math.asin(0.999)
        lo, hi = (t, math.pi - t) if x < math.pi else (math.pi + t, 2 * math.pi - t)
        assert o.q1_range[0] <= lo + 1e-9 and o.q1_range[1] >= hi - 1e-9, (o.q1_range, lo, hi)
        assert o.depth == pytest.approx(o.gap) and o.gap == pytest.approx(0.08, abs=0.005)
        assert is_defective(m, o.u_lower_curve_up, ref=ref).defective
        assert o.to_dict(m.names)["kind"] == "closure"


def test_a_slot_end_with_room_to_spare_is_no_closure():
    """hw = 5.1: hw - r >= 0.06 over the box, more than the 0.03 the pin needs
    at the slot's end: no closure (and no overlap)."""
    m = _capped_yoke(5.1)
    ref = reference(m, "fast")
    (z,) = operating_zones(m, ref, "fast")
    assert z.overlaps == ()
