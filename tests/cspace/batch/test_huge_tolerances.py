"""Huge tolerances (a user's Geneva wheel of +-1 on a 50 mm centre distance,
a yoke whose slot length is +-10): the batch certifies only what the full
test says, and the full test reads a motion that stays in one cell."""

import json
from pathlib import Path

import numpy as np
import pytest

from cspace.batch.margins import defect_margins
from cspace.defects import RESOLUTION, is_defective, reference
from cspace.freespace import configuration_space
from cspace.match import motion_sequence
from cspace.simulate import simulate
from mechanisms.models import eccentric_cam
from mechanisms.userfile import model_from_dict
from synthesis.verify import box_samples

DATA = Path(__file__).parent / "data"

#: vectors the batch certified against the full test's verdict before
GENEVA = [[51.5, 33.85533905932737, 3.75, 29.8, 31.1, 34.0, 4.35, 15.75],
          [48.65771935266813, 34.84519658714556, 3.3684247895402315, 29.87444072559661,
           31.245914636380586, 32.971024050095124, 4.172800713728099, 11.540612843416346]]
YOKE = [[29.97, 4.985, 5.085, 55.0, 90.0, 60.75],
        [30.03, 4.985, 5.114999999999999, 55.0, 90.0, 59.25]]


def _model(name):
    return model_from_dict(json.loads((DATA / name).read_text()))


@pytest.mark.parametrize("name, vectors", [("geneva_huge.json", GENEVA),
                                           ("yoke_huge.json", YOKE)])
def test_certified_verdicts_are_the_full_tests(name, vectors):
    m = _model(name)
    ref = reference(m, "fast")
    U = np.vstack([np.array(vectors), box_samples(m.nominal, 1.5 * m.tol, 24, seed=2)])
    mb = defect_margins(m, U, ref, fallback=False)
    for u, c, dfc in zip(U, mb.certified, mb.defective):
        if c:
            assert bool(dfc) == is_defective(m, u, ref=ref).defective, u.tolist()


def test_the_geneva_contact_beyond_the_plans_reach_is_not_certified():
    """Its lock arc's contact lasts 0.33 rad longer than the nominal's, past
    the plan's reach: the batch read the arc's other branch there and a
    changed sequence; it leaves the verdict to the full test now."""
    m = _model("geneva_huge.json")
    ref = reference(m, "fast")
    mb = defect_margins(m, np.array(GENEVA), ref, fallback=False)
    assert not mb.certified.any()
    assert not any(is_defective(m, u, ref=ref).defective for u in GENEVA)


def test_a_turn_in_one_cell_keeps_its_contact():
    """A motion that stays in one cell for a whole turn lasts the turn: its
    wrapped ends coincide, and it had read as lasting 0 and been contracted
    away (a yoke variant's contacts 'vanished'; the eccentric cam's nominal
    had an empty sequence)."""
    m = _model("yoke_huge.json")
    ref = reference(m, "fast")
    res = RESOLUTION * ref.d
    u = np.array(YOKE[0])
    cs = configuration_space(m.build(u), ref.accuracy, window=m.window)
    sim = simulate(cs, ref.drive[0], ref.drive[1], ref.starts[0][1])
    assert len(sim.cells) == 1
    assert motion_sequence(cs, sim, res) == motion_sequence(ref.spaces[0], ref.sims[0], res)
    assert all(len(side) == 1 for side in motion_sequence(cs, sim, res))
    assert not is_defective(m, u, ref=ref).defective
    e = reference(eccentric_cam(), "fast")
    assert len(e.sims[0].cells) == 1
    assert motion_sequence(e.spaces[0], e.sims[0], RESOLUTION * e.d)[0] != ()
