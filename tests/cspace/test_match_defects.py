
import numpy as np
import pytest

from cspace.defects import Reason, default_deviation, is_defective, reference
from cspace.freespace import configuration_space
from cspace.match import ChangeKind, channel_graph, match

from ..conftest import brute_overlap


@pytest.fixture(scope="module")
def geneva_ref(models):
    return reference(models["geneva"])


@pytest.fixture(scope="module")
def recip_ref(models):
    return reference(models["reciprocating_cam"])


def test_matcher_detects_a_constructed_channel_closure(models, geneva_ref):
    m = models["geneva"]
    # the pin no longer fits the slots: the index channels close
    cs = configuration_space(m.build({"pin_r": 0.45}), window=m.window,
                             deps=m.dependencies()[0])
    r = match(geneva_ref.spaces[0], cs, geneva_ref.starts[0])
    assert not r.same
    assert r.changes[0].kind == ChangeKind.CHANNEL_CLOSED
    # the change names the boundary pieces at the pinch, as feature-pair labels
    assert r.changes[0].labels and all("|" in lab for lab in r.changes[0].labels)
    d = is_defective(m, {"pin_r": 0.45}, ref=geneva_ref)
    assert d.defective and Reason.TOPOLOGY in d.reasons and Reason.JAM in d.reasons


def test_no_false_change_inside_the_box(models, geneva_ref):
    m = models["geneva"]
    rng = np.random.default_rng(7)
    u = m.nominal + 0.1 * m.tol * rng.uniform(-1, 1, m.n)
    cs = configuration_space(m.build(u), window=m.window, deps=m.dependencies()[0])
    r = match(geneva_ref.spaces[0], cs, geneva_ref.starts[0])
    assert r.same and r.isomorphic, r
    d = is_defective(m, u, ref=geneva_ref)
    assert not d.defective and d.max_deviation < d.d
    assert all(s.name == "OK" for s in d.sims)


def test_nominal_is_healthy(models, recip_ref):
    d = is_defective(models["reciprocating_cam"], None, ref=recip_ref)
    assert not d.defective and d.max_deviation == 0.0


def _closing_vector(m):
    """Fingers long, tip big, faces inward: the passage between cups closes."""
    u = m.nominal.copy()
    for n, s in [("f0", 1), ("f1", 1), ("f2", 1), ("tip_r", 1), ("xr_b", -1), ("xr_t", -1),
                 ("xl_b", 1), ("xl_t", 1)]:
        u[m.index(n)] += s * m.tol[m.index(n)]
    return u


def _brute_simulate(pair, q1s, s0, step=0.001, reach=0.05):
    """Independent quasi-static simulation: exact part overlap sampled with shapely
    on a slide grid (spacing ``step``) around the yoke; the yoke moves to the nearest
    free slide within ``reach`` of its position.  Returns (positions, jammed)."""
    pos = s0
    out = []
    k = int(round(reach / step))
    for t in q1s:
        s = pos + step * np.arange(-k, k + 1)
        free = ~brute_overlap(pair, np.stack([np.full_like(s, t), s], 1))
        if free[k]:
            out.append(pos)
            continue
        cand = np.nonzero(free)[0]
        if not cand.size:
            return np.array(out), True
        pos = s[cand[np.argmin(np.abs(cand - k))]]
        out.append(pos)
    return np.array(out), False


def test_box_vector_defective_and_confirmed_by_brute_force(models, recip_ref):
    m = models["reciprocating_cam"]
    u = _closing_vector(m)
    assert m.in_box(u)
    d = is_defective(m, u, ref=recip_ref)
    assert d.defective and Reason.JAM in d.reasons
    pair_id, q1_jam, _ = d.where
    q1s = np.linspace(0.0, 0.6, 121)
    _, jammed = _brute_simulate(m.build(u), q1s, 0.45)
    assert jammed
    _, jammed0 = _brute_simulate(m.build(), q1s, 0.45)
    assert not jammed0


def test_geneva_box_has_defective_vectors(models, geneva_ref):
    m = models["geneva"]
    rng = np.random.default_rng(1)
    found = None
    for _ in range(12):
        u = m.nominal + m.tol * rng.choice([-1.0, 1.0], m.n)
        d = is_defective(m, u, ref=geneva_ref)
        if d.defective:
            found = d
            break
    assert found is not None
    assert found.reasons and found.where is not None and found.message


def test_default_deviation_is_documented_rule(models):
    m = models["reciprocating_cam"]
    ref = reference(m, "fast")
    assert default_deviation(m, ref.spaces) == pytest.approx(5 * 0.02 / 2.5)
    assert ref.d == pytest.approx(5 * 0.02 / 2.5)  # the model states no d of its own
    assert reference(models["geneva"], "fast").d == 0.06  # the designer's d
    assert reference(m, "fast", d=0.3).d == 0.3


@pytest.mark.parametrize("signs", ["-+----+---+-+--+-----+++-+", "-++-+--+-+---+-+-+++--+++-"])
def test_turning_point_vertices_close_the_channel_boundary(models, signs):
    """At the `fast` root tolerance the two branches of a pin-corner curve end
    ~1e-5 rad apart in q2 at their turning point (a vertical tangent); they must
    still be one vertex, or the channel boundary falls apart and an unchanged
    channel reads as a changed contact sequence.  These two box corners of the
    initial Geneva design did exactly that."""
    m = models["geneva"]
    ref = reference(m, "fast")
    u = m.nominal + np.array([1.0 if s == "+" else -1.0 for s in signs]) * m.tol
    cs = configuration_space(m.build(u), "fast", window=m.window, deps=m.dependencies()[0])
    r = match(ref.spaces[0], cs, ref.starts[0])
    H = channel_graph(cs, r.variant_face)
    assert all(d % 2 == 0 for _, d in H.degree()), "the channel boundary is not closed"
    assert r.isomorphic and r.same, r


# a Geneva design part-way through a synthesis (changes from the built-in
# nominal, cm): there the pin leaves a locking arc just where the relief takes over
_HANDOVER = {"drv_x": -0.0095, "drv_y": 0.0032, "whl_x": 0.0095, "whl_y": -0.0032,
             "crank": 0.0055, "pin_r": -0.0063, "lock_r": -0.0117, "relief_d": -0.0036,
             "relief_r": 0.0117, "lock_cd": -0.0081, "lock0_r": 0.0032, "lock1_r": 0.0063,
             "lock2_r": 0.0063, "lock3_r": 0.0032, "s1_wl": 0.0063, "s2_wl": -0.0055,
             "s2_wr": 0.0063, "s2_depth": 0.0032, "s3_wl": 0.0032, "s3_wr": -0.0032}


@pytest.mark.parametrize("signs, instant", [("--++-++-+---+-+-++-+--++--", True),
                                            ("-+++----+-+--++++-+++--+-+", False)])
def test_instants_below_the_resolution_are_not_sequence_changes(models, signs, instant):
    """At this design a box corner adds a pin-on-locking-arc contact that lasts
    1e-5 to 6e-4 rad of driver motion, on one side of a near-tangency or the
    other.  Below the resolution (d/100 of driver motion) it is an instant, not
    a step of the contact sequence; a corner that changes the sequence over a
    finite driver range is still a change."""
    from cspace.defects import RESOLUTION
    m0 = models["geneva"]
    m = m0.with_nominal(m0.nominal + np.array([_HANDOVER.get(n, 0.0) for n in m0.names]))
    ref = reference(m, "fast")
    u = m.nominal + np.array([1.0 if s == "+" else -1.0 for s in signs]) * m.tol
    cs = configuration_space(m.build(u), "fast", window=m.window, deps=m.dependencies()[0])
    raw = match(ref.spaces[0], cs, ref.starts[0])
    assert not raw.same and raw.changes[0].kind == ChangeKind.SEQUENCE_CHANGED
    res = RESOLUTION * ref.d
    r = match(ref.spaces[0], cs, ref.starts[0], resolution=res)
    assert r.same is instant, r
    short = [p.q1_end - p.q1_start for p in cs.boundary
             if p.free_face == raw.variant_face and p.q1_end - p.q1_start < res]
    if instant:
        assert short  # the change was made of pieces below the resolution
    # the contracted boundary has no piece below the resolution and stays closed
    H = channel_graph(cs, raw.variant_face, res)
    assert all(abs(d["q1_range"][1] - d["q1_range"][0]) >= res
               for *_, d in H.edges(data=True))
    assert all(deg % 2 == 0 for _, deg in H.degree())
    # the defect test compares the contact sequence along the motions: the
    # instant is not a change there either; the other corner is defective
    # (its sequence change lies off the motion, its output deviates)
    from cspace.match import motion_sequence
    from cspace.simulate import simulate
    d = is_defective(m, u, ref=ref)
    sim = simulate(cs, ref.drive[0], ref.drive[1], ref.starts[0][1])
    same = motion_sequence(ref.spaces[0], ref.sims[0], res) == motion_sequence(cs, sim, res)
    assert (Reason.TOPOLOGY in d.reasons) is not same
    if instant:
        assert same and Reason.TOPOLOGY not in d.reasons
    else:
        assert d.defective


#: a later Geneva design of the synthesis (change from the built-in nominal, cm)
_LATER = {"drv_x": -0.0063, "whl_x": 0.0063, "pin_r": -0.0063, "lock_r": -0.0088,
          "relief_d": -0.0063, "relief_r": 0.0063, "lock_cd": -0.0142, "lock1_r": 0.0063,
          "lock2_r": 0.0063, "s0_wl": -0.0013, "s1_wl": 0.0037, "s1_depth": 0.0013,
          "s2_wr": 0.004}


def test_a_pocket_the_motion_never_enters_is_not_a_change(models):
    """At this design and tolerance-box vertex, a free pocket of the operating
    face splits off: configurations where the pin sits in a slot with the wheel
    about a radian away from any indexing position, reachable only by turning the
    wheel by hand through the relief.  Over the wheel's full cycle (four driver
    turns, every slot) the motion neither enters it nor changes, so the variant
    is not defective; the whole-face comparison still sees the split."""
    from cspace.simulate import simulate
    m0 = models["geneva"]
    m = m0.with_nominal(m0.nominal + np.array([_LATER.get(n, 0.0) for n in m0.names]))
    ref = reference(m, "fast")
    signs = "+--+-+++-+--00--+0-0000+00"
    u = m.nominal + np.array([{"+": 1.0, "-": -1.0, "0": 0.0}[c] for c in signs]) * m.tol
    cs = configuration_space(m.build(u), "fast", window=m.window, deps=m.dependencies()[0])
    whole = match(ref.spaces[0], cs, ref.starts[0])
    assert [c.kind for c in whole.changes] == [ChangeKind.CHANNEL_CLOSED]
    # the nominal-channel cells that split off lie far from the motion (in wheel
    # angle, over all four turns)
    from collections import Counter
    from cspace.match import _probes
    sim = simulate(cs, *ref.drive, ref.starts[0][1])
    P, _ = _probes(ref.spaces[0], ref.faces[0])
    vf = cs.face_at(P)
    free = np.array([cs.faces.get(int(g), False) for g in vf])
    main = Counter(vf[free].tolist()).most_common(1)[0][0]
    off = P[free & (vf != main)]
    assert len(off)
    f = np.stack([sim.output_at(off[:, 0] + 2 * np.pi * t) for t in range(4)])
    gap = np.abs((off[:, 1][None, :] - f + np.pi) % (2 * np.pi) - np.pi)
    assert gap.min() > 0.2, gap.min()
    region = match(ref.spaces[0], cs, ref.starts[0], paths=(ref.sims[0], sim))
    assert region.same, region
    assert region.stats["probes"] < whole.stats["probes"]
    # compared: the contacts along the motion, fewer than the face's boundary
    assert sum(region.stats["nominal_sequence"]) < whole.stats["nominal_edges"]
    d = is_defective(m, u, ref=ref)
    assert not d.defective, d
    # the defect test simulates the full cycle: every slot indexes
    assert {f"driver:pin|wheel:slot{k}.right" for k in range(4)} <= set(ref.sims[0].contact)


def test_match_paths_are_checked(models, geneva_ref):
    from cspace.errors import InputError
    cs = geneva_ref.spaces[0]
    with pytest.raises(InputError, match="paths"):
        match(cs, cs, geneva_ref.starts[0], paths=geneva_ref.sims[0])
    other = reference(models["reciprocating_cam"]).sims[0]
    bad = type(other)(other.q1, other.q2, other.contact, other.status,
                      cells=((10 ** 6, 0),))
    with pytest.raises(InputError, match="does not have"):
        match(cs, cs, geneva_ref.starts[0], paths=(geneva_ref.sims[0], bad))


@pytest.mark.parametrize("bad", [-1e-3, float("nan"), "fine"])
def test_match_resolution_is_checked(models, geneva_ref, bad):
    from cspace.errors import CSpaceError
    with pytest.raises(CSpaceError, match="resolution"):
        match(geneva_ref.spaces[0], geneva_ref.spaces[0], geneva_ref.starts[0], resolution=bad)


def test_stop_early_gives_the_same_verdict(models):
    """The search's early exit tests fewer things but never changes the verdict,
    whichever pair it starts with (optical filter: three pairs)."""
    from cspace.errors import InputError
    m = models["optical_filter"]
    ref = reference(m, "fast")
    rng = np.random.default_rng(7)
    us = [m.nominal + m.tol * rng.choice([-1.0, 1.0], m.n) * rng.uniform(0.5, 3.0)
          for _ in range(6)] + [m.nominal]
    verdicts = []
    for u in us:
        full = is_defective(m, u, ref=ref)
        verdicts.append(full.defective)
        for first in (None, 0, 1, 2):
            early = is_defective(m, u, ref=ref, stop_early=True, first_pair=first)
            assert early.defective == full.defective, (u, first, full.message, early.message)
            if early.defective:
                assert set(early.reasons) <= set(full.reasons)
    assert any(verdicts) and not all(verdicts)
    with pytest.raises(InputError, match="first_pair"):
        is_defective(m, us[0], ref=ref, stop_early=True, first_pair=3)
