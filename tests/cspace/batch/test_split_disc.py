"""An eccentric disc cam under a pivoted flat-faced lever held down by a
spring, the disc drawn as two half arcs joined at its top, where the lever
rests at the drive's start.  The motion is the one-arc disc's; a variant's
contact at q1 = 0 lies on the arc that ends the drive, which the batch's
plan does not have as a candidate at its first sample."""

import math

import numpy as np

from cspace.batch.margins import defect_margins
from cspace.defects import is_defective, reference
from cspace.geometry import Arc, Loop, Pair, Part, Rotation
from mechanisms.analysis import operating_point_notes
from mechanisms.models import Model, Parameter


def build(v, split=True):
    cx, cy, e, r = v["cam_x"], v["cam_y"], v["ecc"], v["disc_r"]
    c = (cx, cy - e)
    if split:
        disc = Loop((Arc(c, r, -math.pi / 2, math.pi / 2, True, name="right"),
                     Arc(c, r, math.pi / 2, 3 * math.pi / 2, True, name="left")))
    else:
        disc = Loop((Arc(c, r, -math.pi / 2, 3 * math.pi / 2, True, name="disc"),))
    yf = v["piv_y"] - v["face_off"]
    bar = Loop.from_bulges([(-65.0, yf), (35.0, yf), (35.0, yf + 5), (-65.0, yf + 5)],
                           [0.0] * 4, ["face", "end.right", "back", "end.left"])
    return Pair(Part("cam", (disc,), Rotation((cx, cy))),
                Part("lever", (bar,), Rotation((v["piv_x"], v["piv_y"]))), units="mm",
                name="lever", bias=-1)


def lever(split=True) -> Model:
    P = [("cam_x", 0.0), ("cam_y", 0.0), ("ecc", 5.0), ("disc_r", 20.0), ("piv_x", -60.0),
         ("piv_y", 17.5), ("face_off", 2.5)]
    return Model("lever", tuple(Parameter(n, x, 0.02) for n, x in P),
                 lambda v: build(v, split), units="mm",
                 window=(0.0, 2 * math.pi, -math.pi, math.pi), drive=(0.0, 2 * math.pi),
                 q2_start=(0.1,), deviation=0.0015)


def test_the_deviation_margin_follows_the_nominal_where_no_bound_is_known():
    """Each parameter at +- its tolerance: the batched deviation margin is the
    full test's d - max deviation, to the batch's band (it read the stated
    start, 0.1 rad, as the lever's place at the first sample: a deviation of
    0.1 rad where the full test reads 4e-4)."""
    m = lever()
    ref = reference(m, "fast")
    U = []
    for i in range(m.n):
        for s in (1.0, -1.0):
            u = m.nominal.copy()
            u[i] += s * m.tol[i]
            U.append(u)
    U = np.array(U)
    mb = defect_margins(m, U, ref, fallback=False)
    band = ref.accuracy.batch_dev_band * ref.d
    for u, dm in zip(U, mb.deviation):
        full = is_defective(m, u, ref=ref)
        assert abs((ref.d - dm) - full.max_deviation) <= 2 * band, (u, dm, full)


def test_a_drive_that_starts_at_a_hand_over_reads_as_the_one_arc_disc():
    """The turn ends where it starts, so the contact sequences are cycles: a
    variant whose hand-over between the halves moved across the start has the
    one-arc disc's verdict, by the full test and by the batch (read as lines,
    every such variant was defective)."""
    split, whole = lever(), lever(split=False)
    ref, ref1 = reference(split, "fast"), reference(whole, "fast")
    assert not [t for w, t in operating_point_notes(ref.spaces, ref.sims, ref.start_choices)
                if w and "hands over" in t]
    rng = np.random.default_rng(7)
    U = split.nominal + rng.uniform(-1.0, 1.0, (24, split.n)) * split.tol
    full = [is_defective(split, u, ref=ref) for u in U]
    assert [r.defective for r in full] == [is_defective(whole, u, ref=ref1).defective
                                           for u in U]
    assert sum(r.defective for r in full) < len(U)
    mb = defect_margins(split, U, ref, fallback=False)
    cert = mb.certified
    assert cert.sum() >= len(U) // 2, mb.stats
    assert list(mb.defective[cert]) == [r.defective for r, c in zip(full, cert) if c]
