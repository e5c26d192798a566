"""Check list: Table 1 combination, Eq. 1 and the ε-filter on synthetic sets."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError
from synthesis.checklist import (CheckVector, build_checklist, channel_partners, combinable,
                                 combine)

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
