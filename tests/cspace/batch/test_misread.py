"""Variants whose contact sequence the batched margins once read wrongly
(``misread.json``): the batch certifies each with the full test's verdict, and
reads the contact sequence the variant's own C-space has.

* Geneva, iteration 3 of the case study, vectors 350 and 489: the pin touches
  the corner of lock arc 3 and slot 3 for 0.003 and 0.001 rad (0.067 rad at
  nominal), between two plan samples 0.005 rad apart where the lock arc hands
  over to the slot flank.  Read at the plan's samples only, the sequence
  lacked that contact (a false "sequence changed"); the hand-overs of each
  variant are now sampled finely.
* Geneva, first check list, vectors 31 and 51: a contact sequence that surely
  differs along an open channel, with the output within d, is defective by
  the batch's margins alone.
* Optical filter, first check list, vector 92: a candidate of the third cam
  turns by half a turn between two samples where it begins; placed on the
  turn of a neighbouring sample, it cut into the channel.
* Geneva, 2,000 box samples of the initial design (seed 0), vectors 1178,
  1299, 1767 and 1883: the lock2/slot2 corner begins about 0.0008 rad
  earlier than at nominal, where its validity margin rises steeply; its
  change, measured every 8th sample, looked too small, and the corner was
  not evaluated where it already bounded the channel (a contact sequence
  read as changed).  A candidate is now evaluated wherever the nominal
  contact is real within the plan's reach (``PathPlan.margin_near``).
* Geneva, the third check list of the default-preset case study, vector 439
  (``squeezed``, against that iteration's design): the slot corner's contact
  begins below the wheel while the lock disk holds it; the batch read a push
  where the full test finds a jam.  Such a variant is now left to the full
  test (``margins._born_across``).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from cspace.batch.margins import contact_sequences, defect_margins
from cspace.defects import RESOLUTION, is_defective, reference
from cspace.freespace import configuration_space
from cspace.geometry import trusted
from cspace.match import motion_sequence
from cspace.simulate import simulate

DATA = json.loads((Path(__file__).parent / "misread.json").read_text())
CASES = DATA["cases"]


@pytest.fixture(scope="module")
def refs(models):
    out = {}

    def get(name):
        if name not in out:
            out[name] = reference(models[name], DATA["preset"])
        return out[name]
    return get


def _own_sequences(m, u, ref):
    """motion_sequence of every pair of the variant's own C-space and motion."""
    with trusted():
        built = m.build(u)
    pairs = getattr(built, "pairs", (built,))
    deps = m.dependencies()
    out = []
    for i, (pair, start) in enumerate(zip(pairs, ref.starts)):
        cs = configuration_space(pair, ref.accuracy, window=m.window, deps=deps[i],
                                 cache=ref.cache)
        sim = simulate(cs, ref.drive[0], ref.drive[1], start[1])
        out.append(motion_sequence(cs, sim, RESOLUTION * ref.d))
    return tuple(out)


@pytest.mark.parametrize("case", CASES, ids=[c["source"].replace(" ", "_") for c in CASES])
def test_certified_with_the_full_tests_verdict(models, refs, case):
    m = models[case["model"]]
    ref = refs(case["model"])
    u = np.array(case["vector"])
    mb = defect_margins(m, u[None, :], ref, fallback=False)
    full = is_defective(m, u, ref=ref)
    assert full.defective == case["defective"]
    assert mb.certified[0], mb.results[0]
    assert mb.defective[0] == full.defective, (mb.results[0], full)
    if case["defective"]:
        # defective by the contact sequence alone: the channel stays open and
        # the output within d
        assert mb.sequence[0].min() < 0 < mb.channel[0].min() and mb.deviation[0] > 0
        assert "contact sequence" in mb.results[0].message
    else:
        assert mb.sequence[0].min() > 0


@pytest.mark.parametrize("case", [c for c in CASES if c["model"] == "geneva"][:2],
                         ids=["iteration3_350", "iteration3_489"])
def test_the_batch_reads_the_variants_own_contact_sequence(models, refs, case):
    """The batch's reading equals motion_sequence of the variant's own C-space,
    the contact at the lock3/slot3 corner included."""
    m = models["geneva"]
    ref = refs("geneva")
    u = np.array(case["vector"])
    own = _own_sequences(m, u, ref)
    assert ("driver:pin|wheel:lock3^slot3.right", 1) in own[0][1]
    assert contact_sequences(m, u, ref) == own


@pytest.mark.parametrize("case", [c for c in CASES if "Monte Carlo" in c["source"]],
                         ids=lambda c: c["source"].split()[-1])
def test_a_contact_that_begins_earlier_is_evaluated_where_it_bounds(models, refs, case):
    """The lock2/slot2 corner of these variants begins before the nominal's,
    where its validity margin rises steeply: the batch reads the variant's
    own contact sequence (flank, corner), not the lock arc above it."""
    m = models["geneva"]
    ref = refs("geneva")
    u = np.array(case["vector"])
    own = _own_sequences(m, u, ref)
    assert ("driver:pin|wheel:lock2", 1) not in own[0][1]
    assert contact_sequences(m, u, ref) == own


def test_a_contact_born_under_a_held_follower_is_left_to_the_full_test(models):
    """A contact the nominal has above the channel begins below the follower
    while the lock disk holds it: the blocked region squeezes the wheel (the
    full test: a jam).  The batch must not certify the variant healthy."""
    it3 = DATA["geneva_default_iteration_3"]
    case = DATA["squeezed"]
    m = models["geneva"].with_nominal(np.array(it3["nominal"])).with_tolerances(
        np.array(it3["tol"]))
    ref = reference(m, it3["preset"], d=it3["d"])
    u = np.array(case["vector"])
    mb = defect_margins(m, u[None, :], ref, fallback=False)
    assert not mb.certified[0]
    full = is_defective(m, u, ref=ref)
    assert full.defective == case["defective"]
    assert defect_margins(m, u[None, :], ref).defective[0]


def test_a_contact_passing_between_segments_in_line_is_no_squeeze(models, refs):
    """In the Geneva pair's own motion the pin's contact passes from one
    segment of a slot flank to the next, in line with it, while the wheel
    turns fast: the new segment's value before its beginning lies 1.5e-4 rad
    below the wheel (more than the gap band), its value at the next sample on
    the old segment's, which still holds.  That is a hand-over, not a contact
    born under a held follower: the nominal design itself and a variant on
    its way to a defective one (a search point of the main job) are certified,
    with the full test's verdict."""
    m = models["geneva"]
    ref = refs("geneva")
    case = DATA["squeezed"]
    # a point a tenth of the way from the nominal to a box corner
    u = m.nominal + 0.1 * (np.array(DATA["cases"][0]["vector"]) - m.nominal)
    U = np.vstack([m.nominal, u])
    mb = defect_margins(m, U, ref, fallback=False)
    assert mb.certified.all()
    for row, verdict in zip(U, mb.defective):
        assert is_defective(m, row, ref=ref).defective == verdict
    assert case["defective"]        # the squeezed variant, above, stays with the full test


def test_the_fixture_is_of_the_built_in_design(models):
    """The vectors were tested against the built-in Geneva design; the case
    study's third design is recorded beside them."""
    m = models["geneva"]
    it3 = DATA["geneva_iteration_3"]
    assert len(it3["nominal"]) == len(it3["tol"]) == m.n
    assert it3["d"] == m.deviation
    for c in CASES:
        assert len(c["vector"]) == models[c["model"]].n
