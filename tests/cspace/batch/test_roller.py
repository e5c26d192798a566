"""Batched margins on a roller between two lines: the channel margin against its
closed form, and its zero against the bisection of the full test.

The pair
--------
A crank of radius R (driver, rotating about the origin, angle q1) carries a
roller of radius r centred at P(q1) = R (cos q1, sin q1).  The follower slides
along x (q2 = s) and carries two straight guides, the faces of two bars,
inclined at an angle a: with the unit normal n = (cos a, sin a), at the
follower's position s the faces are the lines

    n . p = s cos a - w/2    and    n . p = s cos a + w/2,

a distance w apart (a = 0 is the Scotch yoke of ``yoke.py`` with w the full
width).  The bars are long enough that the roller never reaches their ends.

Derivation of the gap
---------------------
The roller lies between the faces, touching neither, iff its centre is at
least r from both lines:

    s cos a - w/2 + r  <=  n . P(q1)  <=  s cos a + w/2 - r,

that is, at every q1, s lies in the interval

    [(n . P(q1) - (w/2 - r)) / cos a,  (n . P(q1) + (w/2 - r)) / cos a].

The channel's lower bound is the roller against the upper face, its upper
bound the roller against the lower face; at fixed q1 they are
``(w - 2 r) / cos a`` apart (model units), whatever q1.  The C-space metric
divides a slide by the characteristic length L of the nominal pair (the
batch measures every variant against the nominal's plan), so the channel
margin, the narrowest gap of the channel along the motion, is

    g(u) = (w - 2 r) / (L cos a),

for every variant u = (R, r, w) (R drops out).  It closes (g <= 0) where the
roller is wider than the gap between the lines.

Along a segment u(t) = u0 + t (u_w - u0), w - 2 r is linear in t, so g is
linear and its zero is t0 = g(u0) / (g(u0) - g(u_w)).  A variant with g < 0
jams: the full test (:func:`cspace.defects.is_defective`) finds it defective,
one with g > 0 moves like the nominal up to the changed clearance, which the
deviation threshold d of the model (set well above it) lets pass.  So the
first defective point of the segment, which the bisection of the loop
(:func:`synthesis.removal.transition_points`) brackets to eps, is u(t0).
"""

import itertools
import math

import numpy as np
import pytest

from cspace.batch.margins import defect_margins, plans_of
from cspace.defects import is_defective, reference
from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from mechanisms.models import Model, Parameter

H = 80.0     # half length of the faces: the roller never reaches their ends
B = 5.0      # bar thickness


def _bar(a, near, far, names):
    """A bar between the lines n . p = near and n . p = far (near < far), its
    points (x along n, y along the face) turned by a, counter-clockwise."""
    c, s = math.cos(a), math.sin(a)
    pts = [(near, -H), (far, -H), (far, H), (near, H)]
    return Loop.from_bulges([(c * x - s * y, s * x + c * y) for x, y in pts], names=names)


def roller(r=5.0, w=10.06, a=0.0, R=20.0, t_r=0.02, t_w=0.04) -> Model:
    def build(v):
        R_, r_, w_ = v["arm"], v["roller_r"], v["gap"]
        wheel = Loop((Arc((R_, 0.0), r_, 0.0, 2 * math.pi, name="roller"),))
        lower = _bar(a, -w_ / 2 - B, -w_ / 2, ["lo.bot", "lo.face", "lo.top", "lo.back"])
        upper = _bar(a, w_ / 2, w_ / 2 + B, ["up.bot", "up.back", "up.top", "up.face"])
        return Pair(Part("arm", (wheel,), Rotation((0.0, 0.0))),
                    Part("guide", (lower, upper), Translation((1.0, 0.0))), units="mm",
                    name="roller")

    span = R / math.cos(a) + w + 10.0
    return Model("roller", (Parameter("arm", R, 0.02), Parameter("roller_r", r, t_r),
                            Parameter("gap", w, t_w)), build, units="mm",
                 window=(0.0, 2 * math.pi, -span, span), drive=(0.0, 2 * math.pi),
                 q2_start=(R,), deviation=0.05)


def clearance(U, a, L):
    """The closed-form channel margin (C-space metric) of the rows of U."""
    U = np.atleast_2d(U)
    return (U[:, 2] - 2 * U[:, 1]) / (L * math.cos(a))


CASES = [(5.0, 10.06, 0.0), (3.0, 6.05, math.radians(30.0)), (8.0, 16.07, math.radians(-20.0))]


@pytest.fixture(scope="module", params=CASES, ids=["r5-w10.06", "r3-w6.05-30deg",
                                                   "r8-w16.07-m20deg"])
def case(request):
    r, w, a = request.param
    m = roller(r, w, a)
    return m, reference(m, "fast"), a


def _size(m):
    R, r, w = m.nominal
    return R + r + w


def test_channel_margin_is_the_closed_form(case):
    """For the nominal, the box corners and a batch of variants inside the box,
    the channel margin is (w - 2 r) / (L cos a) to 1e-9 of the pair's size."""
    m, ref, a = case
    L = plans_of(ref)[0].scale2
    rng = np.random.default_rng(7)
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=m.n)))
    U = np.vstack([m.nominal, m.nominal + m.tol * corners,
                   m.nominal + m.tol * rng.uniform(-1, 1, (30, m.n))])
    mb = defect_margins(m, U, ref, fallback=False)
    np.testing.assert_allclose(mb.channel[:, 0], clearance(U, a, L), rtol=0,
                               atol=1e-9 * _size(m) / L)
    # the box holds both open and closed channels; a closed one jams
    exact = clearance(U, a, L)
    closed = exact < -ref.accuracy.batch_gap_band
    assert closed.any() and (exact > ref.accuracy.batch_gap_band).any()
    assert mb.defective[closed].all()


def test_margin_zero_is_the_bisected_transition_point(case):
    """Along u0 -> u_w (roller up, gap down, the clearance closing) the channel
    margin is linear; its zero matches the bisection of the full test within
    eps = search_eps * max(tol)."""
    from synthesis.removal import transition_points
    m, ref, a = case
    L = plans_of(ref)[0].scale2
    uw = m.nominal + np.array([0.0, 1.0, -1.0]) * m.tol
    assert clearance(uw, a, L)[0] < 0 < clearance(m.nominal, a, L)[0]
    ts = np.array([0.0, 0.5, 1.0])
    mb = defect_margins(m, [m.nominal + t * (uw - m.nominal) for t in ts], ref, fallback=False)
    g = mb.channel[:, 0]
    np.testing.assert_allclose(np.diff(g), np.diff(g)[0], rtol=1e-9)      # linear in t
    t0 = -g[0] / (g[2] - g[0])
    g0, gw = clearance([m.nominal, uw], a, L)
    assert t0 == pytest.approx(g0 / (g0 - gw), abs=1e-9)
    eps = 5e-3 * float(np.max(m.tol))      # the fast preset's bisection stop length
    tr = transition_points(m.nominal, [uw], lambda us: [is_defective(m, u, ref=ref).defective
                                                        for u in us], eps)[0]
    u_zero = m.nominal + t0 * (uw - m.nominal)
    assert np.max(np.abs(tr.u_c - u_zero)) <= eps
