"""A follower that starts in the play of its channel: the note says where the
motion repeats from (mechanisms.analysis.operating_point_notes)."""

import math

import pytest

from cspace.defects import reference
from cspace.match import closed_motion
from cspace.simulate import simulate
from mechanisms.analysis import operating_point_notes
from mechanisms.models import eccentric_cam, geneva, reciprocating_cam


def _play(m):
    ref = reference(m, "fast")
    notes = [(w, t) for w, t in operating_point_notes(ref.spaces, ref.sims, ref.start_choices)
             if "in the play of its channel" in t]
    return ref, notes


@pytest.mark.parametrize("mk", [geneva, reciprocating_cam])
def test_a_start_in_the_play_is_named_with_where_the_cycle_repeats(mk):
    ref, notes = _play(mk())
    assert len(notes) == 1 and notes[0][0] is False
    q2 = float(notes[0][1].rsplit("q2_start = ", 1)[1])
    cs, sim = ref.spaces[0], ref.sims[0]
    assert cs.window[2] <= q2 <= cs.window[3]
    # from the suggested start the motion ends where it starts (to the
    # printed digits)
    again = simulate(cs, ref.drive[0], ref.drive[1], q2)
    assert not closed_motion(cs, sim)
    gap = again.q2[-1] - again.q2[0]
    if cs.periodic[1]:
        gap = (gap + math.pi) % (2 * math.pi) - math.pi
    assert abs(gap) <= 1e-8 * (cs.window[3] - cs.window[2])
    first = sim.q2[-1] - sim.q2[0]
    if cs.periodic[1]:
        first = (first + math.pi) % (2 * math.pi) - math.pi
    assert abs(first) > 1e3 * abs(gap)


def test_a_closed_motion_has_no_such_note():
    ref, notes = _play(eccentric_cam())
    assert notes == [] and closed_motion(ref.spaces[0], ref.sims[0])
    assert math.isclose(ref.sims[0].q2[0], ref.sims[0].q2[-1], abs_tol=1e-9)


def test_the_take_up_is_bracketed_by_the_samples_around_it():
    """The yoke (crank R = 20, channel c = w - r = 0.03) starts at s = R and
    ends the turn at R - c, from where its motion repeats: the face pushes it
    from cos q1 = 1 - 2 c / R on, and from there the first turn follows the
    repeating motion.  The note brackets that driver angle by the samples
    around it (it named one sample, 5 % beyond the angle on a user's yoke)."""
    from tests.cspace.batch.yoke import yoke
    ref, notes = _play(yoke())
    assert len(notes) == 1
    text = notes[0][1]
    a, b = (float(x) for x in text.split("taken up between ", 1)[1].split(" rad")[0]
            .split(" and "))
    exact = math.acos(1 - 2 * 0.03 / 20)
    assert a <= exact <= b and b - a < 0.02
