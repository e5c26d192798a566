"""Exported face polygons agree with ``classify`` and tile the window (issue 23,
item 10): a contact curve's raw angle may jump by 2 pi inside a slab, and a cell
closing at its slab's end may cross itself by rounding; neither may give a face
polygon that overlaps its neighbours or leaves a gap."""

import math

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon, box

from cspace.freespace import Status, configuration_space
from cspace.geometry import Loop, Pair, Part, Rotation, Translation
from cspace.io import cspace_to_dict


def _exported_faces(cs):
    """Face id -> (free, shapely geometry) as cspace.json holds them."""
    out = {}
    for f in cspace_to_dict(cs)["faces"]:
        polys = [Polygon(p["exterior"], p["holes"]) for p in f["polygons"]]
        out[f["id"]] = (f["free"], shapely.union_all(polys) if polys else Polygon())
    return out


def check_faces(cs, n=4000, seed=0):
    """Faces tile the window without overlap; points inside a face (farther than
    a few chords from its outline) classify as the face says."""
    lo1, hi1, lo2, hi2 = cs.window
    win = box(lo1, lo2, hi1, hi2)
    faces = _exported_faces(cs)
    geoms = [g for _, g in faces.values()]
    total = sum(g.area for g in geoms)
    assert total == pytest.approx(win.area, rel=1e-7), "faces do not tile the window"
    union = shapely.union_all(geoms)
    assert union.area == pytest.approx(win.area, rel=1e-7), "faces overlap or leave a gap"
    rng = np.random.default_rng(seed)
    q = np.column_stack([rng.uniform(lo1, hi1, n), rng.uniform(lo2, hi2, n)])
    pts = shapely.points(q)
    # the outline is a polyline within the accuracy's chord of the curves
    L = cs.pair.char_length
    margin = 5 * cs.accuracy.chord * max(1.0, L, cs._s1)
    outline = shapely.union_all([g.boundary for g in geoms])
    far = shapely.distance(outline, pts) > margin
    status = cs.classify(q)
    far &= status != Status.CONTACT
    seen = np.zeros(n, dtype=int)
    for fid, (free, g) in faces.items():
        shapely.prepare(g)
        inside = shapely.contains(g, pts)
        seen += inside
        sel = inside & far
        got = status[sel] == Status.FREE
        bad = np.nonzero(got != free)[0]
        assert len(bad) == 0, (f"face {fid} ({'free' if free else 'blocked'}) holds points "
                               f"classify calls otherwise, e.g. {q[sel][bad[:3]].tolist()}")
    assert np.all(seen[far] == 1), "a point lies in no face or in two"
    return int(far.sum())


@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam",
                                  "eccentric_cam"])
def test_builtin_faces_agree_with_classify(cspaces, name):
    from mechanisms.models import BUILTIN
    assert set(BUILTIN) == {"geneva", "optical_filter", "reciprocating_cam", "eccentric_cam"}
    for cs in cspaces[name]:
        assert check_faces(cs) > 1000


def test_geneva_seam_slab_faces(cspaces):
    # the reported sliver: first slab, q1 in [0, 0.02], q2 in [1.54, 3.08]
    cs = cspaces["geneva"][0]
    q = np.array([[q1, q2] for q1 in np.linspace(0.0005, 0.02, 15)
                  for q2 in np.linspace(1.54, 3.08, 60)])
    status = cs.classify(q)
    pts = shapely.points(q)
    for free, g in _exported_faces(cs).values():
        inside = shapely.contains(g, pts) & (status != Status.CONTACT)
        inside &= shapely.distance(g.boundary, pts) > 5 * cs.accuracy.chord
        assert np.all((status[inside] == Status.FREE) == free)


def _convex(rng_pts, cx, cy, r):
    ang = np.sort(np.asarray(rng_pts))
    pts = [(cx + r * math.cos(a), cy + r * math.sin(a)) for a in ang]
    return pts


@st.composite
def pairs(draw):
    """A random pair: convex polygons (some edges bulged into arcs), a rotating
    driver, a rotating or sliding follower, placed so that they touch."""
    def loop(cx, cy, r):
        k = draw(st.integers(3, 6))
        angles = draw(st.lists(st.floats(0, 2 * math.pi - 1e-3), min_size=k, max_size=k,
                               unique=True).filter(
            lambda a: min(np.diff(np.sort(np.r_[a, a[0] + 2 * math.pi if a else 0]))) > 0.3))
        bulges = draw(st.lists(st.sampled_from([0.0, 0.0, 0.2, 0.5]), min_size=k, max_size=k))
        return Loop.from_bulges(_convex(angles, cx, cy, r), bulges)

    r1 = draw(st.floats(0.5, 1.5))
    drv = Part("driver", (loop(draw(st.floats(0.3, 1.0)), 0.0, r1),), Rotation((0.0, 0.0)))
    r2 = draw(st.floats(0.3, 1.2))
    gap = draw(st.floats(2.0, 3.5))
    if draw(st.booleans()):
        fol = Part("follower", (loop(gap, 0.0, r2),), Rotation((gap + draw(st.floats(0.2, 1.0)),
                                                                0.0)))
    else:
        fol = Part("slider", (loop(gap, 0.0, r2),), Translation((1.0, 0.0)))
    return Pair(drv, fol, units="mm", name="random")


@settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck))
@given(pairs())
def test_random_pair_faces_agree_with_classify(pair):
    cs = configuration_space(pair, "fast")
    check_faces(cs, n=1500)


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(pairs())
def test_random_pair_faces_agree_with_classify_many(pair):
    cs = configuration_space(pair, "fast")
    check_faces(cs, n=3000)


def test_face_polygons_are_computed_once_per_cspace(cspaces, monkeypatch):
    """A report draws the faces of one C-space several times: they are computed
    once and kept outside the object (not pickled with it); each call gives a
    new dict of the same geometries."""
    import pickle

    from cspace import freespace
    cs = cspaces["reciprocating_cam"][0]
    first = cs.face_polygons()
    calls = []
    real = freespace.ConfigurationSpace.cell_polygons
    monkeypatch.setattr(freespace.ConfigurationSpace, "cell_polygons",
                        lambda self: calls.append(1) or real(self))
    again = cs.face_polygons()
    assert calls == [] and again is not first and again.keys() == first.keys()
    assert all(again[f] is first[f] for f in first)
    again.clear()                                   # the caller's own dict
    assert cs.face_polygons().keys() == first.keys()
    copy = pickle.loads(pickle.dumps(cs))
    assert copy not in freespace._FACE_POLYGONS
    got = copy.face_polygons()
    assert calls == [1] and all(got[f].equals(first[f]) for f in first)
