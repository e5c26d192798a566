"""Contacts the nominal parts do not make but a variant may (cspace.near): a
crank pin that reaches 25 mm in a slot whose end is at 25.2 +- 0.3 mm.  The
nominal C-space has no curve for the pin and the slot's end (the broad phase
drops the pair); a variant with a short slot jams against it.  The batch
certified such variants healthy (the full test finds the jam); now it leaves
them to the full test, and the check list holds the corner that closes the
gap most."""

import math

import numpy as np
import pytest

from cspace.batch.margins import defect_margins
from cspace.defects import is_defective, reference
from cspace.features import features
from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from cspace.near import SAFETY
from cspace.pruning import _can_touch, pair_gap
from mechanisms.models import Model, Parameter

NAMES = ("R", "rp", "w", "Ls")


def build(v):
    R, rp, w, Ls = v["R"], v["rp"], v["w"], v["Ls"]
    pin = Loop((Arc((R, 0.0), rp, 0.0, 2 * math.pi, name="pin"),))
    outer = Loop.from_bulges([(-20.0, -40.0), (20.0, -40.0), (20.0, 40.0), (-20.0, 40.0)],
                             names=["o.bottom", "o.right", "o.top", "o.left"])
    slot = Loop.from_bulges([(-w, -Ls), (-w, Ls), (w, Ls), (w, -Ls)],
                            names=["slot.left", "slot.top", "slot.right", "slot.bottom"])
    return Pair(Part("crank", (pin,), Rotation((0.0, 0.0))),
                Part("yoke", (outer, slot), Translation((1.0, 0.0))), units="mm", name="yoke")


def closed_slot(Ls=25.2, tol_Ls=0.3):
    return Model("closed_slot", (Parameter("R", 20.0, 0.02), Parameter("rp", 5.0, 0.02),
                                 Parameter("w", 5.05, 0.02), Parameter("Ls", Ls, tol_Ls)),
                 build, units="mm", window=(0.0, 2 * math.pi, -60.0, 60.0),
                 drive=(0.0, 2 * math.pi), q2_start=(20.0,), deviation=0.004)


@pytest.fixture(scope="module")
def model():
    return closed_slot()


@pytest.fixture(scope="module")
def ref(model):
    return reference(model, "fast")


def test_the_slot_ends_are_near_pairs(model, ref):
    near = ref.near[0]
    names = {k: f.name for f in features(model.pairs()[0].follower, 1) for k in [f.key + (f.kind,)]}
    assert sorted(names[kb] for _, kb in near.keys) == ["slot.bottom", "slot.top"]
    # the pin's top reaches 25, the slot's end is at 25.2
    assert near.gaps == pytest.approx([0.2, 0.2])
    # R, rp and Ls move the pin and the slot's end by their own moves, and w
    # the end's corners (along it: a bound, first order)
    assert near.reach[:, 0] == pytest.approx([1.0, 1.0, 1.0, 1.0])
    top = [k for k, (_, kb) in enumerate(near.keys) if names[kb] == "slot.top"][0]
    # longer crank and pin, shorter slot close the gap; w leaves it
    assert list(near.closing[top]) == [1.0, 1.0, 0.0, -1.0]
    assert list(near.corners(model.nominal, model.tol)[top]) == pytest.approx(
        [20.02, 5.02, 5.05, 24.9])


@pytest.mark.parametrize("Ls, jams", [(24.95, True), (25.1, False), (25.45, False)])
def test_a_variant_that_may_reach_the_slot_end_is_left_to_the_full_test(model, ref, Ls, jams):
    u = np.array([20.0, 5.0, 5.05, Ls])
    full = is_defective(model, u, ref=ref)
    assert full.defective == jams
    mb = defect_margins(model, u[None, :], ref, fallback=False)
    # moved by 0.25 towards the end, half the gap or more: tested with its own
    # features; 0.1 short of it (pin at 25, end at 25.1): still apart
    assert mb.certified[0] == (not jams)
    assert defect_margins(model, u[None, :], ref).defective[0] == jams


def test_far_pairs_are_not_near(model):
    """With the slot's end 5 mm beyond the pin's reach and a tolerance of 0.3
    there is nothing to watch; nor without tolerances."""
    assert not len(reference(closed_slot(Ls=30.0), "fast").near[0])
    assert reference(closed_slot().with_tolerances(0.0), "fast").near == ()


def test_the_gap_is_the_broad_phase_test_as_a_distance(model):
    pair = model.pairs()[0]
    fa_all, fb_all = features(pair.driver, 0), features(pair.follower, 1)
    for fa in fa_all:
        for fb in fb_all:
            g = pair_gap(fa, fb, pair)
            assert g >= 0.0
            for m in (0.0, 0.19, 0.21, 1.0):
                if abs(g - m) > 1e-9:
                    assert _can_touch(fa, fb, pair, m) == (g <= m)


def test_the_check_list_holds_the_closing_corner(model, ref):
    from synthesis.checklist import CheckList
    from synthesis.loop import with_near_contacts
    cl = with_near_contacts(model, ref, CheckList((), 0, 0, 0, 0, 0.0))
    got = {v.origin[0]: v.u for v in cl.vectors}
    # the two ends' corners are one vector (the pin reaches both alike)
    assert list(got) == ["near contact crank:pin | yoke:slot.top"]
    u = got["near contact crank:pin | yoke:slot.top"]
    assert cl.vectors[0].depends == frozenset({0, 1, 3})
    assert is_defective(model, u, ref=ref).defective
    assert SAFETY > 1


def test_a_shallow_jam_against_an_end_parallel_to_the_slide_is_seen_at_fast(model, ref):
    """The slot's end is parallel to the slide: its contact with the pin does
    not depend on the follower's position, and exists between two roots of a
    residual of q1.  With the pin 0.0002 mm above the end they lie 0.009 rad
    apart, between two samples of the `fast` scan (0.005 rad), and the full
    test found the drive healthy; the residual's dip between samples is now
    searched."""
    from cspace.contact import contact_curves
    u = np.array([20.0, 5.0, 5.05, 24.9998])
    for preset in ("fast", "default"):
        cs = contact_curves(model.build(u), preset, window=model.window)
        q1 = sorted(c.q1_value for c in cs.vertical if "slot.top" in c.label)
        assert len(q1) == 2 and 0.008 < q1[1] - q1[0] < 0.01
    r = is_defective(model, u, ref=ref)
    assert r.defective and "JAM" in [x.name for x in r.reasons]
