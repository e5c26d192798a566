import math

import networkx as nx
import numpy as np
import pytest

from cspace.errors import InputError, NonFiniteError
from cspace.freespace import Status, configuration_space
from cspace.geom2d import TWO_PI

from ..conftest import brute_overlap
from .shapes import rr_pair, rt_pair

MARGIN = 2e-3  # C-space metric units (rad) kept away from every curve


def far_from_curves(cs, q, margin=MARGIN):
    """Mask of configurations at least ``margin`` from every contact curve (vertical
    distance), from every curve end and vertical curve (horizontal distance)."""
    keep = np.ones(len(q), dtype=bool)
    L = cs.pair.char_length
    s2 = 1.0 if cs.periodic[1] else 1.0 / L
    for c in cs.curves:
        inside = (q[:, 0] >= c.q1_start - margin) & (q[:, 0] <= c.q1_end + margin)
        if not inside.any():
            continue
        x = np.clip(q[inside, 0], c.q1_start, c.q1_end)
        d = q[inside, 1] - c.evaluate(x)
        if cs.periodic[1]:
            d = (d + math.pi) % TWO_PI - math.pi
        near = np.abs(d) * s2 < margin
        near |= np.minimum(np.abs(q[inside, 0] - c.q1_start), np.abs(q[inside, 0] - c.q1_end)) < margin
        keep[np.nonzero(inside)[0][near]] = False
    for v in cs.vertical:
        keep &= np.abs(q[:, 0] - v.q1_value) >= margin
    return keep


def random_configs(cs, n, seed):
    rng = np.random.default_rng(seed)
    lo1, hi1, lo2, hi2 = cs.window
    return np.stack([rng.uniform(lo1, hi1, n), rng.uniform(lo2, hi2, n)], 1)


def assert_agrees_with_brute_force(cs, n_keep=2000, seed=0):
    q = random_configs(cs, int(n_keep * 1.6), seed)
    q = q[far_from_curves(cs, q)]
    assert len(q) >= n_keep, len(q)
    q = q[:n_keep]
    cl = cs.classify(q)
    ref = brute_overlap(cs.pair, q)
    assert np.all(cl != Status.CONTACT)
    wrong = np.nonzero((cl == Status.BLOCKED) != ref)[0]
    assert wrong.size == 0, (cs.pair.name, q[wrong[:5]], cl[wrong[:5]])


@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam"])
def test_classify_matches_brute_force_on_models(cspaces, name):
    for i, cs in enumerate(cspaces[name]):
        assert_agrees_with_brute_force(cs, 2000, seed=i)


@pytest.mark.parametrize("make", [rr_pair, rt_pair], ids=["RR", "RT"])
def test_classify_matches_brute_force_on_synthetic(make):
    cs = configuration_space(make())
    assert_agrees_with_brute_force(cs, 1000, seed=3)


def test_classify_statuses_and_contact(cspaces):
    cs = cspaces["geneva"][0]
    b = cs.boundary[0]
    c = cs.curves[b.curve]
    x = 0.5 * (b.q1_start + b.q1_end)
    y = float(c.evaluate(np.array([x]))[0])
    st = cs.classify([[x, y], [x, y + (1e-4 if b.free_above else -1e-4)],
                      [x, y - (1e-4 if b.free_above else -1e-4)]])
    assert list(st) == [Status.CONTACT, Status.FREE, Status.BLOCKED]


def test_classify_accepts_any_angle_and_rejects_bad_input(cspaces):
    cs = cspaces["geneva"][0]
    q = np.array([[0.1, 0.0], [0.1 + TWO_PI, 0.0], [0.1 - 3 * TWO_PI, TWO_PI]])
    st = cs.classify(q)
    assert st[0] == st[1] == st[2]
    with pytest.raises(NonFiniteError):
        cs.classify([[np.nan, 0.0]])
    with pytest.raises(InputError, match=r"shape \(2,\) or \(N, 2\)"):
        cs.classify(np.zeros((3, 3)))


def test_geneva_nominal_symmetry(cspaces):
    """The nominal Geneva C-space is invariant under phi -> phi + pi/2."""
    cs = cspaces["geneva"][0]
    q = random_configs(cs, 6000, 11)
    qs = q + [0.0, math.pi / 2]
    keep = far_from_curves(cs, q) & far_from_curves(cs, qs - [0.0, 0.0])
    q, qs = q[keep], qs[keep]
    assert len(q) > 2000
    np.testing.assert_array_equal(cs.classify(q), cs.classify(qs))
    # the boundary pieces come in four rotated copies
    assert len(cs.boundary) % 4 == 0


def test_free_space_graph(cspaces):
    cs = cspaces["geneva"][0]
    G = cs.graph
    assert isinstance(G, nx.MultiGraph)
    assert G.number_of_edges() == len(cs.boundary)
    for u, v, d in G.edges(data=True):
        assert "|" in d["label"] and d["branch"] in (-1, 0, 1)
        assert cs.faces[d["free_face"]] and not cs.faces[d["blocked_face"]]
    assert len(set(cs.face_at([[0.0, 0.0], [math.pi, -math.pi / 4], [0.0, math.pi / 2]]))) == 1
    # every node has even degree: boundaries are closed chains
    assert all(deg % 2 == 0 for _, deg in G.degree())


def test_window_seam_periodic_driver():
    """Faces are joined across the q1 = 2 pi seam: shifting the window start does not
    change the number of faces."""
    pair = rr_pair()
    a = configuration_space(pair)
    b = configuration_space(pair, window=(1.0, 1.0 + TWO_PI, 0.0, TWO_PI))
    assert a.stats["faces"] == b.stats["faces"]
    assert a.stats["free_faces"] == b.stats["free_faces"]
    q = random_configs(a, 3000, 5)
    keep = far_from_curves(a, q) & far_from_curves(b, q)
    np.testing.assert_array_equal(a.classify(q[keep]), b.classify(q[keep]))


def test_bad_window():
    with pytest.raises(InputError, match="lo < hi"):
        configuration_space(rr_pair(), window=(1, 0, 0, 1))
    with pytest.raises(InputError, match="one full period"):
        configuration_space(rr_pair(), window=(0, 1, 0, 1))
    with pytest.raises(InputError, match="Pair"):
        configuration_space("geneva")


def test_face_polygons_cover_window(cspaces):
    cs = cspaces["reciprocating_cam"][0]
    polys = cs.face_polygons()
    lo1, hi1, lo2, hi2 = cs.window
    area = sum(g.area for g in polys.values())
    assert area == pytest.approx((hi1 - lo1) * (hi2 - lo2), rel=1e-3)


def test_a_window_a_rounding_off_a_full_period_says_how_far_and_the_fix():
    """pi typed to six digits misses 2 pi by 5e-6 rad: the message shows the
    span to ten digits, how far off it is, the tolerance and what to write."""
    from mechanisms.models import geneva
    m = geneva()
    pair = m.build(m.nominal)
    with pytest.raises(InputError, match=r"6.283185307179586 rad to 1e-12 rad; got q2 from "
                                         r"-3.14159 to 3.14159, a span of 6.28318 \(-5.31e-06 "
                                         r"rad off\): give q2_hi = q2_lo \+ 6.283185307179586"):
        configuration_space(pair, "fast", window=(0, 2 * math.pi, -3.14159, 3.14159))
    with pytest.raises(InputError, match=r"at most one period is allowed \(2 pi = "
                                         r"6.283185307179586, .* 1.47e-05 rad more\): give "
                                         r"q1_hi = q1_lo \+ 6.283185307179586"):
        configuration_space(pair, "fast", window=(0, 6.2832, -math.pi, math.pi))
