"""Check list: Table 1 combination, Eq. 1 and the ε-filter on synthetic sets."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError
from synthesis.checklist import (CheckVector, build_checklist, channel_partners, combinable,
                                 combine, handover_partners)

NOM = np.zeros(6)
TOL = np.full(6, 1.0)


def vec(values: dict, key=None, tag=None):
    u = NOM.copy()
    for i, v in values.items():
        u[i] = v
    keys = frozenset({key}) if key is not None else frozenset()
    return CheckVector(u, frozenset(values), (tag or str(sorted(values.items())),), keys)


def test_combine_takes_each_set_from_its_vector_and_nominal_elsewhere():
    a = vec({0: 1.0, 1: -1.0})
    b = vec({3: 1.0})
    c = combine(a, b, NOM)
    assert_allclose(c.u, [1, -1, 0, 1, 0, 0])
    assert c.depends == {0, 1, 3} and c.origin == a.origin + b.origin


def test_disjoint_sets_combine_overlapping_sets_only_when_they_agree():
    a, b = vec({0: 1.0}), vec({1: 1.0})
    assert combinable(a, b, 0.25)
    c = vec({0: 1.0, 2: 1.0})
    d = vec({0: -1.0, 2: 1.0, 4: 1.0})
    assert not combinable(c, vec({0: -1.0, 3: 1.0}), 0.25)   # disagree on parameter 0
    assert combinable(c, vec({0: 1.0, 3: 1.0}), 0.25)        # agree on it
    assert not combinable(c, vec({0: 1.0, 3: 1.0}), 0.25, extended=False)  # paper's rule
    assert not combinable(c, d, 0.25)
    # a set inside the other adds nothing
    assert not combinable(vec({0: 1.0, 1: 1.0}), vec({0: 1.0}), 0.25)


def test_table1_closure_on_three_disjoint_seeds():
    seeds = [vec({0: 1.0}), vec({1: 1.0}), vec({2: 1.0})]
    cl = build_checklist(seeds, NOM, TOL, 0.25, extended=False)
    # pairs 01, 02, 12 and the triple 012 (made once; duplicates filtered)
    sets = sorted(tuple(sorted(v.depends)) for v in cl.vectors)
    assert sets == [(0,), (0, 1), (0, 1, 2), (0, 2), (1,), (1, 2), (2,)]
    assert cl.n_seeds == 3 and cl.n_seeds_kept == 3
    assert cl.n_added == 4 and cl.n_combined > cl.n_added  # the filter dropped repeats
    assert len(cl) == 7 and not cl.truncated


def test_eps_filter_drops_near_duplicates_and_keeps_distinct_vectors():
    seeds = [vec({0: 1.0}), vec({0: 0.9}), vec({0: -1.0})]
    cl = build_checklist(seeds, NOM, TOL, 0.25)
    assert cl.n_seeds_kept == 2          # 0.9 lies within 0.25 of 1.0
    assert cl.radius == 0.25
    cl2 = build_checklist(seeds, NOM, TOL, 0.05)
    assert cl2.n_seeds_kept == 3
    # radius scales with the largest tolerance
    assert build_checklist(seeds, NOM, 2 * TOL, 0.25).radius == 0.5


def test_partners_restrict_the_extension_and_combine_disagreeing_seeds():
    lo = vec({0: 1.0, 1: 1.0}, key=(0, 5, 1), tag="lo+")
    up = vec({0: -1.0, 2: 1.0}, key=(0, 6, -1), tag="up-")
    other = vec({0: -1.0, 3: 1.0}, key=(0, 7, -1), tag="x-")
    partners = {frozenset({(0, 5, 1), (0, 6, -1)})}
    cl = build_checklist([lo, up, other], NOM, TOL, 0.25, partners=partners)
    made = {v.origin for v in cl.vectors if len(v.origin) > 1}
    # the closing pair disagrees on parameter 0: both orders of Eq. 1
    assert ("lo+", "up-") in made and ("up-", "lo+") in made
    # lo and other disagree and are not partners: no combination
    assert not any(set(o) == {"lo+", "x-"} for o in made)
    both = [v for v in cl.vectors if v.origin == ("lo+", "up-")][0]
    assert_allclose(both.u, [1, 1, 1, 0, 0, 0])


def test_cap_marks_a_truncated_list():
    seeds = [vec({i: 1.0}) for i in range(6)]
    cl = build_checklist(seeds, NOM, TOL, 0.25, max_vectors=10)
    assert cl.truncated and len(cl) <= 10
    full = build_checklist(seeds, NOM, TOL, 0.25)
    assert len(full) == 2 ** 6 - 1 and not full.truncated


def test_bad_arguments_raise_typed_errors():
    with pytest.raises(InputError, match="filter_eps"):
        build_checklist([], NOM, TOL, 0.0)
    with pytest.raises(InputError, match="shapes"):
        build_checklist([], NOM, np.ones(3), 0.25)


def test_channel_partners_pair_lower_up_with_upper_down(models):
    from cspace.defects import reference
    ref = reference(models["reciprocating_cam"], "fast")
    p = channel_partners(ref.spaces, ref.faces)
    assert p and all(len(k) == 2 for k in p)
    for k in p:
        (a, b) = sorted(k, key=lambda t: -t[2])
        assert a[2] == 1 and b[2] == -1 and a[0] == b[0] == 0


def test_channel_partners_of_the_operating_region_are_a_subset(models):
    from cspace.defects import reference
    ref = reference(models["geneva"], "fast")
    whole = channel_partners(ref.spaces, ref.faces)
    region = channel_partners(ref.spaces, ref.faces, [s.cells for s in ref.sims])
    assert region and region < whole
    # every closing pair of the region bounds a cell the nominal motion passes through
    cs = ref.spaces[0]
    passed = {frozenset({(0, cs.cells[k][j].lower, 1), (0, cs.cells[k][j].upper, -1)})
              for k, j in ref.sims[0].cells}
    assert region <= passed


def test_handover_partners_pair_the_curves_of_consecutive_cells(models):
    from cspace.defects import reference
    ref = reference(models["reciprocating_cam"], "fast")
    paths = [s.cells for s in ref.sims]
    assert not handover_partners(ref.spaces, paths, reach=0)
    one = handover_partners(ref.spaces, paths, reach=1)
    two = handover_partners(ref.spaces, paths, reach=2)
    assert one and one <= two
    for k in two:
        (pa, a, sa), (pb, b, sb) = sorted(k)
        assert pa == pb == 0 and a != b and sa in (1, -1) and sb in (1, -1)
    # every change of bounding curves along the motion gives all four directions
    cs = ref.spaces[0]
    seq = []
    for k, j in paths[0]:
        c = cs.cells[k][j]
        b = frozenset(x for x in (c.lower, c.upper) if x >= 0)
        if b and (not seq or seq[-1] != b):
            seq.append(b)
    assert len(seq) > 1
    for first, later in zip(seq, seq[1:]):
        for a in first:
            for b in later - {a}:
                assert all(frozenset({(0, a, sa), (0, b, sb)}) in one
                           for sa in (1, -1) for sb in (1, -1))


def test_handover_seeds_combine_in_both_orders_once():
    a = vec({0: 1.0, 1: 1.0}, key=(0, 1, 1), tag="a+")
    b = vec({1: -1.0, 2: 1.0}, key=(0, 2, -1), tag="b-")
    c = vec({3: 1.0}, key=(0, 3, 1), tag="c+")
    ho = {frozenset({(0, 1, 1), (0, 2, -1)})}
    plain = build_checklist([a, b, c], NOM, TOL, 0.25, partners=set())
    cl = build_checklist([a, b, c], NOM, TOL, 0.25, partners=set(), handover=ho)
    new = [v for v in cl.vectors if v not in plain.vectors
           and not any(np.array_equal(v.u, w.u) for w in plain.vectors)]
    # Eq. 1 read both ways: the first seed's values win on the shared parameter
    assert sorted(tuple(v.u[:3]) for v in new) == [(1.0, -1.0, 1.0), (1.0, 1.0, 1.0)]
    assert all(len(v.origin) == 2 for v in new)
    # they do not combine further (c is disjoint from both but is not paired again)
    assert len(cl) == len(plain) + 2


def test_handover_vector_catches_a_defect_the_paper_list_misses(models):
    """A Geneva design that the check list without hand-over partners passed
    (the end of a synthesis run), where a seeded Monte Carlo still found 31
    defective box corners out of 1000: deviations just above d where the pin
    leaves the locking arc and picks the wheel up.  The hand-over combination of
    the pin against slot 0's corner with the pin against slot 0's right side is
    in the new list, not in the old one, and defective."""
    from cspace.accuracy import as_accuracy
    from cspace.defects import is_defective, reference
    from synthesis.loop import checklist_of, operating_zones
    nominal = np.array(NOMINAL_GENEVA)
    design = models["geneva"].with_nominal(nominal).with_tolerances(np.array(TOL_GENEVA))
    acc = as_accuracy("fast")
    ref = reference(design, acc, 0.06)
    zones = operating_zones(design, ref, acc)
    old = checklist_of(design, ref, zones, acc.replace(handover_reach=0))
    new = checklist_of(design, ref, zones, acc)
    u = np.array(U_HANDOVER)
    assert any(np.allclose(v.u, u, rtol=0, atol=1e-12) for v in new.vectors)
    assert not any(np.allclose(v.u, u, rtol=0, atol=1e-12) for v in old.vectors)
    assert len(new) > len(old)
    r = is_defective(design, u, ref=ref)
    assert r.defective and r.max_deviation > 0.06


NOMINAL_GENEVA = [-0.0028828125, 0.01771875, 4.997609375000001, -0.0103359375, 3.5405260934327374, 0.29507812499999997, 3.1227578125, 5.0052734375000005, 3.2641484375, 4.98875, 3.2500703125, 3.2443750000000002, 3.2528828124999998, 3.25, 0.352546875, 0.3600703125, 1.2, 0.36, 0.351140625, 1.194234375, 0.3554296875, 0.36, 1.2, 0.3583125, 0.3554296875, 1.2]
TOL_GENEVA = [0.012516174316406252, 0.0142657470703125, 0.012516174316406392, 0.01251617431640625, 0.01307812499999983, 0.013078124999999996, 0.017226562499999876, 0.01722656249999943, 0.017226562499999876, 0.012516174316406392, 0.018, 0.017226562499999876, 0.018, 0.01307812499999983, 0.017226562500000042, 0.018, 0.017226562500000098, 0.018, 0.017226562499999987, 0.018, 0.013078124999999996, 0.018, 0.018, 0.018, 0.013078124999999996, 0.013078125000000052]
U_HANDOVER = [-0.015398986816406252, 0.003453002929687499, 5.010125549316407, 0.0021802368164062502, 3.5274479684327376, 0.282, 3.1227578125, 5.0052734375000005, 3.2641484375, 4.976233825683593, 3.2680703125, 3.2616015625, 3.2528828124999998, 3.25, 0.3697734375, 0.3780703125, 1.1827734374999999, 0.36, 0.3339140625, 1.194234375, 0.3554296875, 0.36, 1.2, 0.3583125, 0.3554296875, 1.2]
