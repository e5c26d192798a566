import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, reject, settings, strategies as st

from cspace.errors import DegenerateGeometryError

from cspace.accuracy import Accuracy
from cspace.contact import contact_curves, features
from cspace.geometry import Loop, Pair, Part, Rotation, Translation

from .shapes import ALL_KINDS, rr_pair, rt_pair


def _feature(pair, key):
    part = pair.parts[key[0]]
    for f in features(part, key[0]):
        if f.key == tuple(key[:3]) and f.kind == key[3]:
            return f
    raise KeyError(key)


def _sample_feature(f, n=4000):
    """Dense points on a feature at q = 0 (a vertex: short pieces of its edges)."""
    if f.kind == "line":
        t = np.linspace(0, 1, n)[:, None]
        return (1 - t) * np.array(f.p) + t * np.array(f.q)
    if f.kind == "arc":
        a = f.mid + np.linspace(-f.half, f.half, n)
        return np.array(f.p) + f.radius * np.stack([np.cos(a), np.sin(a)], 1)
    t = np.linspace(0, 1e-3, n // 2)[:, None]
    return np.vstack([np.array(f.p) + t * np.array(f.e1), np.array(f.p) + t * np.array(f.e2)])


def _side(f, p):
    """Signed distance of body points p from feature f's material (> 0: free side)."""
    if f.kind == "line":
        d = np.subtract(f.q, f.p)
        n = np.array([d[1], -d[0]]) / np.hypot(*d)
        return (p - np.array(f.p)) @ n
    if f.kind == "arc":
        r = np.hypot(*(p - np.array(f.p)).T)
        return r - f.radius if f.convex else f.radius - r
    v = p - np.array(f.p)
    c2 = f.e2[0] * v[:, 1] - f.e2[1] * v[:, 0]
    c1 = v[:, 0] * f.e1[1] - v[:, 1] * f.e1[0]
    return -np.minimum(c2, c1)


def _world(part, q, pts):
    from cspace.geometry import place_points
    return place_points(part.axis, np.full(len(pts), q), pts)


def check_curves_touch(pair, curves, npts=9):
    """Every sampled point of every curve puts its two features in contact, and they
    touch rather than overlap: near the contact point each feature lies on the
    other's free side (to 1e-9 x size)."""
    from cspace.overlap import local_point
    size = pair.size
    tol = 1e-9 * size
    rho = 2e-3 * size
    for c in curves:
        fa, fb = _feature(pair, c.features[0]), _feature(pair, c.features[1])
        pa0, pb0 = _sample_feature(fa), _sample_feature(fb)
        span = c.q1_end - c.q1_start
        for t in c.q1_start + span * np.linspace(0.05, 0.95, npts):
            q2 = float(c.evaluate(np.array([t]))[0])
            pa = _world(pair.driver, t, pa0)
            pb = _world(pair.follower, q2, pb0)
            # contact point: closest sampled pair, refined by the exact side functions
            sa_b = _side(fb, local_point(pair.follower, np.full(len(pa), q2), pa))
            sb_a = _side(fa, local_point(pair.driver, np.full(len(pb), t), pb))
            i = np.argmin(np.abs(sa_b)) if fb.kind != "vertex" else None
            j = np.argmin(np.abs(sb_a)) if fa.kind != "vertex" else None
            x = pa[i] if i is not None else pb[j]
            # touching: some feature point lies on the other's boundary
            gap = min(np.min(np.abs(sa_b)) if i is not None else np.inf,
                      np.min(np.abs(sb_a)) if j is not None else np.inf)
            assert gap <= max(tol, 1e-6 * size), (c.label, c.kind, gap)
            near_a = np.hypot(*(pa - x).T) < rho
            near_b = np.hypot(*(pb - x).T) < rho
            assert np.all(sa_b[near_a] >= -max(tol, 1e-6 * size) * 10), (c.label, c.kind, sa_b[near_a].min())
            assert np.all(sb_a[near_b] >= -max(tol, 1e-6 * size) * 10), (c.label, c.kind, sb_a[near_b].min())


def check_exact_distance(pair, curves, npts=7):
    """The exact boundary distance is ~0 at curve points of free-space boundaries."""
    from cspace.overlap import min_distance
    for c in curves:
        t = c.q1_start + (c.q1_end - c.q1_start) * np.linspace(0.05, 0.95, npts)
        d = min_distance(pair, np.stack([t, c.evaluate(t)], 1))
        assert np.all(d <= 1e-9 * pair.size), (c.label, d.max())


@pytest.mark.parametrize("make", [rr_pair, rt_pair], ids=["RR", "RT"])
def test_every_contact_type_is_found_and_touches(make):
    pair = make()
    cs = contact_curves(pair, "default")
    kinds = {c.kind for c in cs.curves}
    assert ALL_KINDS <= kinds, ALL_KINDS - kinds
    check_curves_touch(pair, cs.curves)
    check_exact_distance(pair, cs.curves)


def _one_at_a_time_matches_arrays(curves, seed=0):
    """The one-value fast path of the kernels and of ``values`` gives the array
    path's numbers bit for bit (results must not depend on batching)."""
    rng = np.random.default_rng(seed)
    n = 0
    for c in curves:
        if not hasattr(c, "values"):
            continue
        x = np.concatenate([rng.uniform(c.q1_start - 1, c.q1_end + 1, 7),
                            [c.q1_start, c.q1_end]])
        q2, ex = c.kernel.solve(x)
        wr, raw = c.values(x)
        for i in range(len(x)):
            q2i, exi = c.kernel.solve(x[i:i + 1])
            wi, ri = c.values(x[i:i + 1])
            np.testing.assert_array_equal(q2i[:, 0], q2[:, i], err_msg=c.label)
            np.testing.assert_array_equal(exi[0], ex[i], err_msg=c.label)
            np.testing.assert_array_equal((wi[0], ri[0]), (wr[i], raw[i]), err_msg=c.label)
            n += 1
    return n


@pytest.mark.parametrize("make", [rr_pair, rt_pair], ids=["RR", "RT"])
def test_one_value_path_is_the_array_path_bit_for_bit(make):
    assert _one_at_a_time_matches_arrays(contact_curves(make(), "default").curves) > 100


def test_one_value_path_on_the_builtin_models(cspaces):
    for name, spaces in cspaces.items():
        for cs in spaces:
            assert _one_at_a_time_matches_arrays(cs.curves, seed=len(name)) > 0, name


def test_rr_has_two_branches_rt_line_contacts_one():
    rr = contact_curves(rr_pair())
    rt = contact_curves(rt_pair())
    assert {c.branch for c in rr.curves} == {1, -1}
    # point-line contacts are linear in the slide, point-circle ones quadratic
    assert {c.branch for c in rt.curves
            if c.kind in ("vertex-line", "arc-line", "line-vertex", "line-arc")} == {0}
    assert {c.branch for c in rt.curves
            if c.kind in ("vertex-arc", "arc-vertex") or c.kind.startswith("arc-arc")} == {1, -1}


def test_curve_ends_are_feature_ends():
    """At a trimmed end the contact point leaves a feature: the validity margin is 0."""
    pair = rr_pair()
    acc = Accuracy()
    for c in contact_curves(pair, acc).curves:
        for x, closed in ((c.q1_start, c.start_closed), (c.q1_end, c.end_closed)):
            if closed:
                assert abs(c.margin(np.array([x]))[0]) < 1e-6, c.label


def test_polyline_chord_error_bounded():
    pair = rr_pair()
    for preset in ("fast", "default", "precise"):
        acc = Accuracy.preset(preset)
        for c in contact_curves(pair, acc).curves[:12]:
            pl = c.polyline(acc)
            mid = 0.5 * (pl[:-1, 0] + pl[1:, 0])
            chord = 0.5 * (pl[:-1, 1] + pl[1:, 1])
            err = np.abs(c.raw(mid) - chord)
            dt = np.diff(pl[:, 0])
            dv = np.diff(pl[:, 1])
            perp = err * dt / np.hypot(dt, dv)
            assert perp.max() <= acc.chord * 1.0001


def test_pruning_removes_only_pairs_that_cannot_touch():
    pair = rr_pair()
    pruned = contact_curves(pair)
    full = contact_curves(pair, prune=False)
    assert pruned.n_pruned > 0
    assert len(pruned.curves) == len(full.curves)


def test_dependency_sets_on_curves(models):
    m = models["geneva"]
    pair = m.build()
    cs = contact_curves(pair, deps=m.dependencies()[0], window=m.window)
    pin_slot = [c for c in cs.curves if c.label == "driver:pin|wheel:slot2.left"]
    assert pin_slot
    d = pin_slot[0].depends
    assert {"crank", "pin_r", "s2_wl", "whl_x", "drv_x"} <= d
    assert "s0_wl" not in d and "lock_r" not in d


def test_window_restricts_computation():
    pair = rr_pair()
    w = (0.5, 1.5, 0.0, 2 * math.pi)
    cs = contact_curves(pair, window=w)
    assert all(0.5 - 1e-12 <= c.q1_start <= c.q1_end <= 1.5 + 1e-12 for c in cs.curves)


def test_vertical_curve_for_concentric_follower_arc():
    from cspace.geometry import Arc
    drv = Part("d", (Loop.from_bulges([(1.0, -0.1), (1.4, -0.1), (1.4, 0.1), (1.0, 0.1)]),),
               Rotation((0, 0)))
    # follower: a ring sector concentric with its own axis at (2, 0)
    from cspace.geometry import Line
    ring = Loop((Arc((2.0, 0.0), 0.8, math.pi / 2, 3 * math.pi / 2, True, "outer"),
                 Line((2.0, -0.8), (2.0, -0.5)),
                 Arc((2.0, 0.0), 0.5, 3 * math.pi / 2, math.pi / 2, False, "inner"),
                 Line((2.0, 0.5), (2.0, 0.8))))
    pair = Pair(drv, Part("f", (ring,), Rotation((2.0, 0.0))))
    cs = contact_curves(pair)
    assert cs.vertical, "a vertex against a concentric arc is a vertical curve"
    from cspace.overlap import min_distance
    for v in cs.vertical:
        q2 = np.linspace(v.q2_lo, v.q2_hi, 7)[1:-1]
        d = min_distance(pair, np.stack([np.full_like(q2, v.q1_value), q2], 1))
        assert np.all(d < 1e-9 * pair.size)


def test_scale_invariance():
    """A model scaled by 1000 has the same curves (angles) and scaled slides."""
    a = contact_curves(rr_pair(1.0))
    b = contact_curves(rr_pair(1000.0))
    assert len(a.curves) == len(b.curves)
    for ca, cb in zip(a.curves, b.curves):
        assert ca.label == cb.label
        assert ca.q1_start == pytest.approx(cb.q1_start, abs=1e-8)
        t = np.linspace(ca.q1_start, ca.q1_end, 5)
        np.testing.assert_allclose(ca.raw(t), cb.raw(t), atol=1e-9)
    a = contact_curves(rt_pair(1.0))
    b = contact_curves(rt_pair(1000.0))
    assert len(a.curves) == len(b.curves)
    for ca, cb in zip(a.curves, b.curves):
        t = np.linspace(ca.q1_start, ca.q1_end, 5)
        np.testing.assert_allclose(ca.raw(t) * 1000.0, cb.raw(t), rtol=1e-9, atol=1e-9)


# ---------------------------------------------------------------- hypothesis

coord = st.floats(-0.3, 0.3)


@st.composite
def random_pair(draw):
    """A random convex-ish polygon with bulged edges against another, RR or RT."""
    def poly(cx, cy, r):
        n = draw(st.integers(3, 5))
        ang = sorted(draw(st.lists(st.floats(0, 2 * math.pi), min_size=n, max_size=n,
                                   unique=True)))
        gaps = np.diff(ang + [ang[0] + 2 * math.pi])
        if gaps.min() < 0.4:
            ang = list(np.linspace(0, 2 * math.pi, n, endpoint=False) + ang[0])
        pts = [(cx + r * math.cos(a), cy + r * math.sin(a)) for a in ang]
        bulges = [draw(st.sampled_from([0.0, 0.0, 0.25, -0.15])) for _ in range(n)]
        try:
            return Loop.from_bulges(pts, bulges)
        except DegenerateGeometryError:
            reject()  # a random bulge made the loop cross itself
    d = Part("d", (poly(1.0 + draw(coord), draw(coord), 0.5),), Rotation((0.0, 0.0)))
    if draw(st.booleans()):
        f = Part("f", (poly(2.3 + draw(coord), draw(coord), 0.5),), Rotation((2.6, 0.0)))
    else:
        a = draw(st.floats(0, math.pi))
        f = Part("f", (poly(2.2 + draw(coord), draw(coord), 0.5),),
                 Translation((math.cos(a), math.sin(a))))
    return Pair(d, f)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_pair())
def test_random_line_arc_pairs_touch(pair):
    cs = contact_curves(pair, "fast")
    check_curves_touch(pair, cs.curves, npts=5)
