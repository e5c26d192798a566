"""The features of a part (cspace.features): what a loop of lines and arcs
gives, their keys, and the free side of each."""

import math

import numpy as np
import pytest

from cspace.features import Feature, free_normal, feature_by_key, features
from cspace.geometry import Arc, Loop, Part, Rotation

from .shapes import driver


def _square(s=2.0):
    # counter-clockwise: the material lies inside, the free side outside
    loop = Loop.from_bulges([(0.0, 0.0), (s, 0.0), (s, s), (0.0, s)], [0.0] * 4,
                            names=["bot", "right", "top", "left"])
    return Part("sq", (loop,), Rotation((0.0, 0.0)))


def test_a_square_has_four_vertices_and_four_lines():
    fs = features(_square(), 0)
    kinds = [f.kind for f in fs]
    assert kinds.count("vertex") == 4 and kinds.count("line") == 4 and "arc" not in kinds
    assert all(isinstance(f, Feature) and f.part == 0 for f in fs)
    lines = {f.name: f for f in fs if f.kind == "line"}
    assert set(lines) == {"bot", "right", "top", "left"}
    assert lines["bot"].p == (0.0, 0.0) and lines["bot"].q == (2.0, 0.0)


def test_free_normals_point_out_of_the_material():
    fs = {f.name: f for f in features(_square(), 1) if f.kind == "line"}
    np.testing.assert_allclose(free_normal(fs["bot"]), [0.0, -1.0], atol=1e-15)
    np.testing.assert_allclose(free_normal(fs["right"]), [1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(free_normal(fs["top"]), [0.0, 1.0], atol=1e-15)


def test_vertex_edges_are_unit_and_leave_the_vertex():
    for f in features(_square(), 0):
        if f.kind != "vertex":
            continue
        e1, e2 = np.array(f.e1), np.array(f.e2)
        assert np.linalg.norm(e1) == pytest.approx(1) and np.linalg.norm(e2) == pytest.approx(1)
        # a square's corner: the two edges at a right angle
        assert float(e1 @ e2) == pytest.approx(0.0, abs=1e-15)


def test_a_full_circle_is_one_convex_arc_without_vertices():
    pin = Part("pin", (Loop((Arc((1.0, 2.0), 0.5, 0.0, 2 * math.pi, name="pin"),)),),
               Rotation((0.0, 0.0)))
    (f,) = features(pin, 0)
    assert f.kind == "arc" and f.convex and f.radius == 0.5 and f.p == (1.0, 2.0)
    assert f.half == pytest.approx(math.pi)


def test_arcs_keep_their_convexity_and_sweep():
    fs = features(driver(), 0)
    arcs = {f.name: f for f in fs if f.kind == "arc"}
    # d.arc bulges out of the body (convex), d.notch into it (concave)
    assert arcs["d.arc"].convex and not arcs["d.notch"].convex
    assert 0 < arcs["d.arc"].half < math.pi


def test_feature_by_key_finds_every_feature_and_nothing_else():
    part = driver()
    fs = features(part, 0)
    for f in fs:
        g = feature_by_key(part, f.key + (f.kind,))
        assert g is not None and g.key == f.key and g.kind == f.kind
    assert feature_by_key(part, (0, 99, 0, "line")) is None


@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam",
                                  "eccentric_cam"])
def test_feature_rows_are_the_numbers_of_features(models, name):
    """:func:`cspace.features.feature_rows` (what a batch reads of every
    variant) gives the keys and the numbers of :func:`features`, bit for bit,
    on variants beyond the box too (where vertices come and go)."""
    from cspace.batch.kernels import _row
    from cspace.features import feature_rows
    from cspace.geometry import trusted
    from synthesis.verify import box_samples
    m = models[name]
    for u in box_samples(m.nominal, 1.5 * m.tol, 8, seed=1):
        with trusted():
            b = m.build(u)
        for pair in (b.pairs if hasattr(b, "pairs") else [b]):
            for part, idx in ((pair.driver, 0), (pair.follower, 1)):
                want = [(f.key + (f.kind,), _row(f)) for f in features(part, idx)]
                got = feature_rows(part, idx)
                assert [k for k, _ in got] == [k for k, _ in want]
                for (_, a), (_, b_) in zip(got, want):
                    assert np.array_equal(np.array(a, float), np.array(b_, float))
