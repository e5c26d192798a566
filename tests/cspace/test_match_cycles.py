"""Contact sequences of a motion that ends where it starts are compared as
cycles (cspace.match.closed_motion, cycle_form, same_cycle), by the full
defect test and by the batch alike."""

import math

import numpy as np
import pytest

from cspace.batch.margins import contact_sequences, defect_margins
from cspace.defects import RESOLUTION, Reason, is_defective, reference
from cspace.freespace import configuration_space
from cspace.match import closed_motion, cycle_form, motion_sequence, same_cycle
from cspace.simulate import simulate
from mechanisms.models import eccentric_cam, geneva

from .seam_cam import seam_cam

A, B, C = ("a", 0), ("b", 0), ("c", 0)


def test_cycle_form_and_same_cycle():
    assert same_cycle((A, B, C), (B, C, A))
    assert same_cycle((A, B, C), (C, A, B))
    assert not same_cycle((A, B, C), (A, C, B))
    # the contact that ends the motion is the one that starts it
    assert same_cycle((A, B, A), (B, A))
    assert cycle_form((A, B, A)) == cycle_form((A, B)) == (A, B)
    assert cycle_form(()) == () and cycle_form((A,)) == (A,) and cycle_form((A, A)) == (A,)
    assert not same_cycle((A, B), (A, B, C))
    assert not same_cycle((A,), ())


@pytest.fixture(scope="module")
def seam():
    m = seam_cam()
    return m, reference(m, "fast")


def test_closed_motion():
    for mk, closed in ((eccentric_cam, True), (geneva, False)):
        ref = reference(mk(), "fast")
        assert closed_motion(ref.spaces[0], ref.sims[0]) is closed
    # half a turn of the cam does not end where it starts
    m = eccentric_cam()
    ref = reference(m, "fast")
    half = simulate(ref.spaces[0], 0.0, math.pi, ref.starts[0][1])
    assert half.success and not closed_motion(ref.spaces[0], half)


def _own(m, ref, u):
    cs = configuration_space(m.build(u), ref.accuracy, window=m.window)
    return cs, simulate(cs, ref.drive[0], ref.drive[1], ref.starts[0][1])


def test_a_handover_at_the_start_is_no_change(seam):
    m, ref = seam
    cs0, sim0 = ref.spaces[0], ref.sims[0]
    assert closed_motion(cs0, sim0)
    res = RESOLUTION * ref.d
    lin0 = motion_sequence(cs0, sim0, res)
    # the nominal starts on one arc and ends on the other
    assert lin0[0][0] != lin0[0][-1]
    for k in (-1, 1):
        u = m.nominal.copy()
        u[m.names.index("slope")] = k * m.tol[m.names.index("slope")]
        cs, sim = _own(m, ref, u)
        lin = motion_sequence(cs, sim, res)
        # as a line the variant's sequence differs, as a cycle it does not
        assert lin != lin0
        assert all(same_cycle(a, b) for a, b in zip(lin, lin0))
        assert motion_sequence(cs, sim, res, cyclic=True)[0] in (
            motion_sequence(cs0, sim0, res, cyclic=True)[0],
            motion_sequence(cs0, sim0, res, cyclic=True)[0][::-1])
        r = is_defective(m, u, ref=ref)
        assert not r.defective, r.message
        assert r.matches[0].stats["cyclic"]


def test_the_batch_reads_the_same_cycle(seam):
    m, ref = seam
    rng = np.random.default_rng(3)
    U = m.nominal + rng.uniform(-1.5, 1.5, (40, len(m.nominal))) * m.tol
    mb = defect_margins(m, U, ref, fallback=False)
    full = [is_defective(m, u, ref=ref).defective for u in U]
    cert = mb.certified
    assert cert.sum() >= 30, mb.stats
    assert list(mb.defective[cert]) == [f for f, c in zip(full, cert) if c]
    # the slope alone moves the hand-over across the start: healthy, certified
    u = m.nominal.copy()
    u[m.names.index("slope")] = m.tol[m.names.index("slope")]
    one = defect_margins(m, u[None, :], ref, fallback=False)
    assert one.certified[0] and not one.defective[0] and one.sequence[0, 0] > 0
    seq = contact_sequences(m, u, ref)[0]
    assert seq is not None and seq[0] == cycle_form(seq[0])


def test_a_real_change_of_a_cycle_is_still_a_defect(seam):
    m, ref = seam
    # a face too narrow for the contact's travel: the disc runs off it onto
    # the face's corners, contacts the nominal cycle does not have
    u = m.nominal.copy()
    u[m.names.index("half_w")] = 0.4
    r = is_defective(m, u, ref=ref)
    assert r.defective and Reason.TOPOLOGY in r.reasons, r.message
    mb = defect_margins(m, u[None, :], ref)
    assert mb.defective[0]
