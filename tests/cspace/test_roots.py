"""The vectorised root finder and the adaptive polyline (cspace.roots)."""

import math

import numpy as np

from cspace.roots import adaptive_polyline, vroots


def test_vroots_finds_many_roots_at_once_to_the_tolerance():
    c = np.array([0.5, 2.0, 3.0, 10.0])
    calls = []

    def fn(x):
        calls.append(len(x))
        # x^2 - c for each bracket (the three-block call repeats the pattern)
        return x ** 2 - np.resize(c, len(x))
    tol = 1e-12
    got = vroots(fn, np.zeros(4), np.full(4, 4.0), tol)
    np.testing.assert_allclose(got, np.sqrt(c), atol=tol)
    # Illinois steps: far fewer calls than bisection's 42 halvings
    assert len(calls) < 42


def test_vroots_without_a_sign_change_returns_the_midpoint_and_exact_zeros_at_once():
    got = vroots(lambda x: x ** 2 + 1.0, np.array([-1.0]), np.array([3.0]), 1e-9)
    assert got[0] == 1.0
    got = vroots(lambda x: x - 2.0, np.array([2.0, 0.0]), np.array([5.0, 2.0]), 1e-9)
    np.testing.assert_array_equal(got, [2.0, 2.0])
    assert vroots(np.sin, np.zeros(0), np.zeros(0), 1e-9).size == 0


def test_adaptive_polyline_meets_its_midpoint_chord_tolerance():
    chord = 1e-4
    pts = adaptive_polyline(np.sin, 0.0, 2 * math.pi, chord, 0.05)
    t, v = pts[:, 0], pts[:, 1]
    assert t[0] == 0.0 and t[-1] == 2 * math.pi and np.all(np.diff(t) > 0)
    np.testing.assert_array_equal(v, np.sin(t))
    # the criterion: the curve's midpoint of every segment within chord of the chord
    tm = 0.5 * (t[:-1] + t[1:])
    dt, dv = np.diff(t), np.diff(v)
    err = np.abs(np.sin(tm) - 0.5 * (v[:-1] + v[1:])) * dt / np.hypot(dt, dv)
    assert np.all(err <= chord)
    # with steps this short (the accuracy's max_step), the whole segment too
    s = np.linspace(0.0, 1.0, 11)[None, :]
    x = t[:-1, None] + s * dt[:, None]
    lin = v[:-1, None] + s * dv[:, None]
    assert np.max(np.abs(np.sin(x) - lin)) <= 1.5 * chord
    # it refines: the tolerance decides the number of points
    assert len(adaptive_polyline(np.sin, 0.0, 2 * math.pi, chord / 100, 0.05)) > 2 * len(t)
    # a straight line needs no refinement beyond the step
    assert len(adaptive_polyline(lambda x: 2 * x, 0.0, 1.0, 1e-9, 0.25)) == 5


def test_adaptive_polyline_checks_midpoints_only():
    """The criterion sees the midpoint: a segment centred on an inflection
    (sin about pi) passes it whatever its length, which is why callers bound
    the step (``Accuracy.max_step``)."""
    pts = adaptive_polyline(np.sin, math.pi - 0.45, math.pi + 0.45, 1e-6, 1.0)
    assert len(pts) == 2
