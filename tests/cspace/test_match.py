"""The channel matcher on a Scotch yoke (``batch/yoke.py``): one channel
bounded below by the pin on the right bar's face and above by the pin on the
left bar's face, over the whole driver turn."""

import math

import numpy as np
import pytest

from cspace.defects import reference
from cspace.errors import InputError
from cspace.freespace import configuration_space
from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from cspace.match import (ChangeKind, MatchResult, TopologyChange, channel_graph, match,
                          motion_sequence, operating_face)
from cspace.simulate import simulate

from .batch.yoke import B, H, yoke

LOWER = "crank:pin|yoke:r.face"
UPPER = "crank:pin|yoke:l.face"
START = (0.0, 20.0)


@pytest.fixture(scope="module")
def nominal():
    m = yoke()
    ref = reference(m, "fast")
    return m, ref, ref.spaces[0]


def _cs(m, u):
    return configuration_space(m.build(u), "fast", window=m.window, deps=m.dependencies()[0])


def _renamed_yoke(face="r.flank"):
    """The nominal yoke with its right bar's face named ``face``: the same
    geometry, another contact curve label."""
    R, r, w = 20.0, 5.0, 5.03
    pin = Loop((Arc((R, 0.0), r, 0.0, 2 * math.pi, name="pin"),))
    left = Loop.from_bulges([(-w - B, -H), (-w, -H), (-w, H), (-w - B, H)],
                            names=["l.bot", "l.face", "l.top", "l.back"])
    right = Loop.from_bulges([(w, -H), (w + B, -H), (w + B, H), (w, H)],
                             names=["r.bot", "r.back", "r.top", face])
    return Pair(Part("crank", (pin,), Rotation((0.0, 0.0))),
                Part("yoke", (left, right), Translation((1.0, 0.0))), units="mm", name="yoke")


# ------------------------------------------------------------------ operating face
def test_operating_face_of_free_blocked_and_contact_starts(nominal):
    m, ref, cs = nominal
    f = operating_face(cs, START)
    assert f == ref.faces[0] and cs.faces[f]
    # the right bar on the pin
    assert operating_face(cs, (0.0, 12.5)) == -1
    # on the channel's upper bound (the left face touches the pin): the channel
    assert operating_face(cs, (0.0, 20.03)) == f
    # free, but beyond the right bar: another free face
    g = operating_face(cs, (0.0, 0.0))
    assert g >= 0 and g != f and cs.faces[g]


# ------------------------------------------------------------------ channel graph
def test_channel_graph_of_the_yoke(nominal):
    m, ref, cs = nominal
    G = channel_graph(cs, ref.faces[0])
    edges = sorted((d["label"], d["free_above"]) for *_, d in G.edges(data=True))
    # the lower bound has the free side above it, the upper bound below
    assert edges == [(UPPER, False), (LOWER, True)]
    for *_, d in G.edges(data=True):
        assert d["q1_range"] == pytest.approx((0.0, 2 * math.pi))
    # a closed boundary: every vertex has even degree
    assert all(deg % 2 == 0 for _, deg in G.degree())


def test_channel_graph_restricted_to_cells_and_contracted(nominal):
    m, ref, cs = nominal
    full = channel_graph(cs, ref.faces[0])
    on_path = channel_graph(cs, ref.faces[0], cells=ref.sims[0].cells)
    assert sorted(d["label"] for *_, d in on_path.edges(data=True)) == \
        sorted(d["label"] for *_, d in full.edges(data=True))
    assert channel_graph(cs, ref.faces[0], cells=()).number_of_edges() == 0
    # pieces shorter than the resolution (here: all, a full turn < 7 rad) are contracted
    assert channel_graph(cs, ref.faces[0], resolution=7.0).number_of_edges() == 0
    assert channel_graph(cs, ref.faces[0], resolution=6.0).number_of_edges() == 2


def test_motion_sequence_of_the_yoke(nominal):
    m, ref, cs = nominal
    assert motion_sequence(cs, ref.sims[0]) == (((LOWER, 0),), ((UPPER, 0),))
    # contacts lasting less than the resolution are dropped
    assert motion_sequence(cs, ref.sims[0], resolution=7.0) == ((), ())


# ------------------------------------------------------------------ match
def test_the_nominal_matches_itself(nominal):
    m, ref, cs = nominal
    r = match(cs, cs, START)
    assert r.same and r.isomorphic and r.changes == ()
    assert r.nominal_face == r.variant_face == ref.faces[0]
    assert r.stats["nominal_edges"] == r.stats["variant_edges"] == 2
    assert repr(r) == "<MatchResult: same topology>"
    rp = match(cs, cs, START, paths=(ref.sims[0], ref.sims[0]))
    assert rp.same and rp.stats["nominal_sequence"] == rp.stats["variant_sequence"] == [1, 1]


def test_a_variant_inside_the_box_matches(nominal):
    m, ref, cs = nominal
    u = m.nominal + np.array([0.01, 0.01, 0.0])       # still 0.02 clearance per side
    v = _cs(m, u)
    assert match(cs, v, START).same
    sim = simulate(v, 0.0, 2 * math.pi, 20.0)
    assert match(cs, v, START, paths=(ref.sims[0], sim)).same


def test_a_blocked_start_is_a_closed_channel(nominal):
    m, ref, cs = nominal
    v = _cs(m, [20.0, 5.04, 5.03])
    r = match(cs, v, START)
    assert not r.same and r.variant_face == -1
    (ch,) = r.changes
    assert ch.kind is ChangeKind.CHANNEL_CLOSED and ch.q == START
    assert ch.detail == "the start configuration is blocked in the variant"
    assert repr(r) == "<MatchResult: channel closed at q1 = 0>"
    d = r.to_dict()
    assert d["same"] is False and d["changes"][0] == {
        "kind": "channel closed", "q": [0.0, 20.0], "q1_range": [0.0, 0.0], "labels": [],
        "detail": "the start configuration is blocked in the variant"}


def test_the_variant_start_is_where_the_variant_is_assembled(nominal):
    """A crank 0.05 shorter moves the channel off the stated start: blocked
    there, the same channel from where the variant's follower starts."""
    m, ref, cs = nominal
    v = _cs(m, [19.95, 5.0, 5.03])
    assert match(cs, v, START).changes[0].kind is ChangeKind.CHANNEL_CLOSED
    r = match(cs, v, START, variant_start=(0.0, 19.97))
    assert r.same and r.variant_face >= 0


def test_a_start_outside_the_nominal_free_space_is_refused(nominal):
    m, ref, cs = nominal
    with pytest.raises(InputError, match=r"q_start \(0\.0, 12\.5\) is not in the nominal "
                                         r"free space"):
        match(cs, cs, (0.0, 12.5))


def test_a_changed_curve_is_a_sequence_change(nominal):
    """The same geometry with the lower face renamed: its contact curve is
    another feature pair, and the channel's contact sequence changed."""
    m, ref, cs = nominal
    v = configuration_space(_renamed_yoke(), "fast", window=m.window)
    new = "crank:pin|yoke:r.flank"
    r = match(cs, v, START)
    assert not r.same and not r.isomorphic
    (ch,) = r.changes
    assert ch.kind is ChangeKind.SEQUENCE_CHANGED
    assert ch.labels == tuple(sorted([LOWER, new]))
    assert f"curves vanished: ['{LOWER}']" in ch.detail
    assert f"curves appeared: ['{new}']" in ch.detail
    # along the motions: the curve below the follower changed
    sim = simulate(v, 0.0, 2 * math.pi, 20.0)
    rp = match(cs, v, START, paths=(ref.sims[0], sim))
    assert not rp.same and rp.changes[0].kind is ChangeKind.SEQUENCE_CHANGED
    assert rp.changes[0].detail.endswith("(below the follower)")
    assert motion_sequence(v, sim) == (((new, 0),), ((UPPER, 0),))


def test_results_as_dicts():
    ch = TopologyChange(ChangeKind.NEW_COMPONENT, (1.0, 2.0), (0.5, 1.5), ("a|b",), "pocket")
    assert ch.to_dict() == {"kind": "new free component", "q": [1.0, 2.0],
                            "q1_range": [0.5, 1.5], "labels": ["a|b"], "detail": "pocket"}
    r = MatchResult(False, (ch,), True, 3, 4, {"probes": 7})
    assert r.to_dict() == {"same": False, "isomorphic": True, "changes": [ch.to_dict()],
                           "stats": {"probes": 7}}
    assert repr(r) == "<MatchResult: new free component at q1 = 1>"


def test_a_sequence_change_is_placed_where_the_sequences_part():
    """The first contacts that differ: the earlier of their beginnings along
    the drive, with the variant's follower there; the drive's start when
    nothing differs or the motion is too short to place it."""
    from types import SimpleNamespace

    from cspace.match import _first_difference
    a, b, c, n = ("a", 0), ("b", 0), ("c", 0), ("n", 0)
    sim = SimpleNamespace(q1=np.array([0.0, 1.0, 2.0, 3.0]), q2=np.array([0.0, 10.0, 20.0, 30.0]))
    # a contact that appears at 1.5 in the variant
    assert _first_difference(((a, 0.0), (b, 2.0)), ((a, 0.0), (n, 1.5), (b, 2.0)), sim,
                             (0.0, 0.0)) == (1.5, 15.0)
    # one that vanishes: where the nominal's began
    assert _first_difference(((a, 0.0), (c, 1.2), (b, 2.0)), ((a, 0.0), (b, 2.1)), sim,
                             (0.0, 0.0)) == pytest.approx((1.2, 12.0))
    # a drive run backwards: the first along it is the larger q1
    back = SimpleNamespace(q1=sim.q1[::-1].copy(), q2=sim.q2[::-1].copy())
    assert _first_difference(((a, 3.0), (b, 1.0)), ((a, 3.0), (n, 2.5), (b, 1.0)), back,
                             (3.0, 30.0)) == (2.5, 25.0)
    # nothing to place
    assert _first_difference(((a, 0.0),), ((a, 0.0),), sim, (0.0, 7.0)) == (0.0, 7.0)


def test_a_geneva_sequence_change_is_placed_at_the_slot_not_at_the_start():
    """A Geneva variant whose contact sequence changes where the pin leaves a
    slot (q1 about 3.73 in the window, on one of the drive's four turns): the
    full test places it there, not at the drive's start."""
    from cspace.batch.margins import defect_margins
    from cspace.defects import Reason, is_defective
    from mechanisms.models import geneva
    from synthesis.verify import box_samples
    m = geneva()
    ref = reference(m, "fast")
    U = box_samples(m.nominal, m.tol, 60, seed=2)
    mb = defect_margins(m, U, ref, fallback=False)
    seq = np.nonzero((mb.sequence.min(axis=1) < 0) & (mb.channel.min(axis=1) > 0)
                     & (mb.deviation > 0))[0]
    assert len(seq)
    r = is_defective(m, U[seq[0]], ref=ref)
    assert r.reasons == (Reason.TOPOLOGY,) and "contact sequence changed" in r.message
    q1 = r.where[1] % (2 * math.pi)
    assert 2.3 < q1 < 4.0 and r.where[1] > 0.5


def test_a_split_is_located_where_the_channel_closes():
    """A crank pin in a stadium slot whose rounded ends stop it 0.05 mm
    short of its travel (slot half width 5.03, pin radius 5.02): the channel
    closes around q1 = pi/2 and 3 pi/2, where the pin meets the slot's end,
    and falls into two free components.  The split is placed there, at the
    probes the variant blocks, not at the first probe of the motion
    (q1 = 0.363, where the channel is 0.02 mm wide)."""
    from mechanisms.userfile import model_from_dict
    from cspace.defects import is_defective
    from .slotted_yoke import yoke_document
    params = [("a", 20.0, 0.02), ("r", 5.0, 0.02), ("hw", 5.05, 0.02), ("s", 19.97, 0.02),
              ("B", 12.0, 0.0), ("H", 35.0, 0.0)]
    m = model_from_dict(yoke_document([{"name": n, "nominal": v, "tol": t}
                                       for n, v, t in params], q2_start=20.0))
    res = is_defective(m, {"r": 5.02, "hw": 5.03, "s": 19.95}, accuracy="fast")
    assert res.defective
    split = [c for mr in res.matches for c in mr.changes if c.kind is ChangeKind.CHANNEL_CLOSED]
    assert split, res.message
    q1 = split[0].q[0]
    assert abs(q1 - math.pi / 2) < 0.1 or abs(q1 - 3 * math.pi / 2) < 0.1, res.message
    lo, hi = split[0].q1_range
    assert lo <= q1 <= hi and hi - lo < 0.2
