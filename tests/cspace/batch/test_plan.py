"""The nominal motion laid out for batched evaluation (:class:`PathPlan`), on
the Scotch yoke of ``yoke.py`` (closed-form channel) and on a pair with a
rotating follower."""

import dataclasses
import math

import numpy as np
import pytest

from cspace.batch.plan import PathPlan, path_plan
from cspace.defects import reference
from cspace.freespace import configuration_space
from cspace.simulate import simulate

from .. import shapes
from .yoke import B, build_yoke, output, yoke

R, r, w = 20.0, 5.0, 5.03
L = R + r                   # the crank's reach: the characteristic length
LOWER = "crank:pin|yoke:r.face"
UPPER = "crank:pin|yoke:l.face"
BACK = "crank:pin|yoke:r.back"


@pytest.fixture(scope="module")
def yoke_ref():
    m = yoke()
    return m, reference(m, "fast")


@pytest.fixture(scope="module")
def plan(yoke_ref):
    m, ref = yoke_ref
    return path_plan(ref.spaces[0], ref.sims[0], 0, ref.starts[0][1])


def _curve(cs, label):
    return [i for i, c in enumerate(cs.curves) if c.label == label]


def test_plain_plan_samples_the_nominal_simulation(yoke_ref, plan):
    m, ref = yoke_ref
    cs, sim = ref.spaces[0], ref.sims[0]
    assert isinstance(plan, PathPlan) and plan.pair == 0
    np.testing.assert_array_equal(plan.x, sim.q1)
    assert plan.is_ref.all() and plan.n == len(sim.q1)
    np.testing.assert_array_equal(plan.f0, sim.q2)
    # the driver turns once from the window start: the wrapped samples are the
    # unwrapped ones in [0, 2 pi), the last one (2 pi) back at 0
    assert np.all((plan.xw >= 0) & (plan.xw < 2 * math.pi))
    np.testing.assert_array_equal(plan.xw[:-1], plan.x[:-1])
    assert plan.x[-1] == pytest.approx(2 * math.pi) and plan.xw[-1] == pytest.approx(0.0)
    assert plan.start == 20.0 and plan.window == tuple(cs.window) and plan.bias == 0
    assert not plan.periodic2
    # crank angle in rad, slide in characteristic lengths
    assert plan.scale1 == 1.0 and plan.scale2 == pytest.approx(L)
    assert repr(plan) == (f"<PathPlan pair 0: {plan.n} samples, {len(plan.cells)} cells, "
                          f"{len(plan.candidates)} candidate curves>")


def test_channel_bounds_are_the_closed_form(yoke_ref, plan):
    """The pin fits where R cos q1 + r - w <= s <= R cos q1 - r + w."""
    m, ref = yoke_ref
    cs = ref.spaces[0]
    c = R * np.cos(plan.x)
    np.testing.assert_allclose(plan.lo0, c + r - w, atol=1e-9)
    np.testing.assert_allclose(plan.hi0, c - r + w, atol=1e-9)
    assert {cs.curves[i].label for i in np.unique(plan.lower)} == {LOWER}
    assert {cs.curves[i].label for i in np.unique(plan.upper)} == {UPPER}
    assert np.all(plan.lo0 <= plan.f0 + 1e-9) and np.all(plan.f0 <= plan.hi0 + 1e-9)


def test_each_sample_lies_in_its_path_cell(yoke_ref, plan):
    m, ref = yoke_ref
    cs = ref.spaces[0]
    assert plan.cells == tuple(tuple(int(v) for v in kj) for kj in ref.sims[0].cells)
    # the cells are met in path order
    assert np.all(np.diff(plan.cell) >= 0)
    assert plan.cell[0] == 0 and plan.cell[-1] == len(plan.cells) - 1
    slabs = np.array([plan.cells[i][0] for i in plan.cell])
    inner = ~np.isin(plan.xw, cs.events)         # an event sample belongs to the cell it leaves
    np.testing.assert_array_equal(slabs[inner], cs.slab_of(plan.xw[inner]))
    for i in range(0, plan.n, 97):
        k, j = plan.cells[plan.cell[i]]
        assert plan.lower[i] == cs.cells[k][j].lower and plan.upper[i] == cs.cells[k][j].upper


def test_candidates_sides_and_distances(yoke_ref, plan):
    """The faces bound the channel (distance 0); the right bar's back lies
    below it and the left bar's back above, each 2 r + B from it."""
    m, ref = yoke_ref
    cs = ref.spaces[0]
    sides = {}
    for (c, side), idx in plan.candidates.items():
        sides.setdefault(cs.curves[c].label, set()).add(side)
        assert np.all(np.diff(idx) > 0) and idx.min() >= 0 and idx.max() < plan.n
        assert plan.distance[c, side].shape == idx.shape == plan.margin0[c, side].shape
        assert np.all(plan.distance[c, side] >= 0)
        if not plan.periodic2:
            np.testing.assert_array_equal(plan.place[c, side], cs.curves[c].raw(plan.xw[idx]))
    assert sides == {LOWER: {1}, UPPER: {-1}, BACK: {1}, "crank:pin|yoke:l.back": {-1}}
    for c in _curve(cs, LOWER):
        assert np.all(plan.distance[c, 1] == 0)
    for c in _curve(cs, BACK):
        np.testing.assert_allclose(plan.distance[c, 1], (2 * r + B) / L, atol=1e-9)
    (lb,) = _curve(cs, "crank:pin|yoke:l.back")
    np.testing.assert_allclose(plan.distance[lb, -1], (2 * r + B) / L, atol=1e-9)


def test_validity_margins_include_the_window(yoke_ref, plan):
    """A face's contact point stays at least H - R = 20 from the face's ends
    (0.8 L), so within the follower window [-30, 30] the margin is the
    distance to the window's edge wherever that is nearer."""
    m, ref = yoke_ref
    cs = ref.spaces[0]
    lo2, hi2 = cs.window[2], cs.window[3]
    for (c, side), idx in plan.candidates.items():
        v = cs.curves[c].raw(plan.xw[idx])
        clip = np.minimum(v - lo2, hi2 - v) / L
        mg = plan.margin0[c, side]
        assert np.all(mg <= clip + 1e-12)
        assert np.all(mg >= np.minimum(0.8, clip) - 1e-6)
        near = clip < 0.8 - 1e-6
        np.testing.assert_allclose(mg[near], clip[near], atol=1e-12)
    # the pin on the right bar's back: s = R cos q1 - (r + w + B), down to -35.03,
    # out of the window (a negative margin) around q1 = pi
    for c in _curve(cs, BACK):
        idx = plan.candidates[c, 1]
        x = plan.xw[idx]
        np.testing.assert_allclose(cs.curves[c].raw(x), R * np.cos(x) - (r + w + B), atol=1e-9)
    back = np.concatenate([plan.margin0[c, 1] for c in _curve(cs, BACK)])
    assert back.min() < 0 < back.max()


def test_curves_of_one_contact_share_a_key(yoke_ref, plan):
    m, ref = yoke_ref
    cs = ref.spaces[0]
    labels = [(c.label, c.branch) for c in cs.curves]
    assert plan.key.shape == (len(cs.curves),)
    for i in range(len(labels)):
        for j in range(len(labels)):
            assert (plan.key[i] == plan.key[j]) == (labels[i] == labels[j])
    # the right bar's back is split at the window seam into two curves, one key
    assert len(_curve(cs, BACK)) == 2 and len(set(plan.key.tolist())) == len(set(labels))


def test_extra_samples_around_events_and_releases(yoke_ref):
    m, ref = yoke_ref
    cs, sim = ref.spaces[0], ref.sims[0]
    fine, width = 1e-3, 5e-3
    p = path_plan(cs, sim, 0, 20.0, fine=fine, width=width)
    assert p.n > len(sim.q1)
    np.testing.assert_array_equal(p.x[p.is_ref], sim.q1)
    np.testing.assert_array_equal(p.f0[p.is_ref], sim.q2)
    assert np.all(np.diff(p.x) > 0)
    extra = p.x[~p.is_ref]
    np.testing.assert_allclose(p.f0[~p.is_ref], sim.output_at(extra), atol=1e-12)
    # the nominal output between samples is interpolated: within h^2 R / 8 of the
    # closed-form motion (h the simulation's step)
    h = np.max(np.diff(sim.q1))
    np.testing.assert_allclose(p.f0[~p.is_ref], output(m.nominal, extra),
                               rtol=0, atol=h * h * R / 8)
    # the follower is let go at q1 = pi; the events are where the backs cross the window
    release = [sim.q1[i] for i in range(1, len(sim.q1))
               if sim.contact[i - 1] != "" and sim.contact[i] == ""]
    assert release == [pytest.approx(math.pi, abs=0.01)]
    anchors = np.concatenate([cs.events, release])
    near = np.min(np.abs(extra[:, None] - anchors[None, :]), axis=1)
    assert np.all(near <= width + 1e-12)
    # only the release without events
    q = path_plan(cs, sim, 0, 20.0, fine=fine, width=width, events=False)
    ex = q.x[~q.is_ref]
    assert 0 < len(ex) <= 2 * width / fine
    assert np.all(np.abs(ex - release[0]) <= width + 1e-12)
    # bounds are still the closed form at the extra samples
    np.testing.assert_allclose(p.hi0, R * np.cos(p.x) - r + w, atol=1e-9)


def _held_yoke(v):
    return dataclasses.replace(build_yoke(v), bias=-1)


def test_the_plan_keeps_the_closure_of_the_motion():
    m = dataclasses.replace(yoke(), builder=_held_yoke)
    ref = reference(m, "fast")
    p = path_plan(ref.spaces[0], ref.sims[0], 0, ref.starts[0][1])
    assert p.bias == -1
    # held down, the follower rides the channel's lower bound
    np.testing.assert_allclose(p.f0, p.lo0, atol=1e-9)


def test_rotating_follower_bounds_and_placement():
    """A rotating follower: unbounded cells give infinite bounds, and every
    candidate's value is placed on the turn where it can bound the channel
    from its side."""
    cs = configuration_space(shapes.rr_pair(), "fast")
    q1 = cs.window[0]
    q2 = cs.start_choice(q1).q2
    sim = simulate(cs, q1, q1 + 2 * math.pi, q2)
    p = path_plan(cs, sim, 0, q2)
    assert p.periodic2 and p.scale1 == p.scale2 == 1.0
    fin_lo, fin_hi = np.isfinite(p.lo0), np.isfinite(p.hi0)
    assert fin_lo.any() and (~fin_lo).any()
    assert np.all(p.lo0[fin_lo] <= p.f0[fin_lo] + 1e-9)
    assert np.all(p.f0[fin_hi] <= p.hi0[fin_hi] + 1e-9)
    # a bound lies within one turn of the follower
    assert np.all(p.f0[fin_lo] - p.lo0[fin_lo] < 2 * math.pi)
    assert np.all(p.hi0[fin_hi] - p.f0[fin_hi] < 2 * math.pi)
    for (c, side), idx in p.candidates.items():
        v = p.place[c, side]
        turns = (v - cs.curves[c].raw(p.xw[idx])) / (2 * math.pi)
        np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)
        if side > 0:
            top = np.where(np.isfinite(p.hi0[idx]), p.hi0[idx], p.f0[idx] + math.pi)
            assert np.all(v <= top + 1e-9)
        else:
            bot = np.where(np.isfinite(p.lo0[idx]), p.lo0[idx], p.f0[idx] - math.pi)
            assert np.all(v >= bot - 1e-9)
        assert np.all(p.distance[c, side] >= 0)


def test_the_drive_grid_is_every_variants_own(models):
    """The samples :attr:`PathPlan.on_grid` marks (the drive's regular samples,
    a rotating driver) are samples of every variant's simulation too, the same
    bits: the full test reads the variant's output there without
    interpolation.  The nominal's other samples (its events) are not."""
    from cspace.batch.margins import plans_of
    from cspace.simulate import drive_grid
    m = models["geneva"]
    ref = reference(m, "fast")
    plan = plans_of(ref)[0]
    grid = drive_grid(ref.drive[0], ref.drive[1], ref.accuracy.sim_step)
    assert plan.on_grid.sum() == len(grid)
    np.testing.assert_array_equal(plan.x[plan.on_grid], grid)
    assert (plan.is_ref & ~plan.on_grid).sum() > 0          # the nominal's events
    rng = np.random.default_rng(3)
    u = m.nominal + m.tol * rng.uniform(-1, 1, m.n)
    pair = m.build(u)
    cs = configuration_space(pair, ref.accuracy, window=m.window, deps=m.dependencies()[0])
    sim = simulate(cs, ref.drive[0], ref.drive[1], ref.starts[0][1])
    assert np.isin(grid, sim.q1).all()
    own = set(sim.q1.tolist())
    assert not all(x in own for x in plan.x[plan.is_ref & ~plan.on_grid])


def test_a_sliding_driver_has_no_common_grid(yoke_ref):
    """A sliding driver steps by a share of each variant's own characteristic
    length: no sample is known to be every variant's (the yoke's crank, a
    rotating driver, has its grid)."""
    from types import SimpleNamespace

    from cspace.batch.margins import _with_grid, plans_of
    from cspace.geometry import Translation
    _, ref = yoke_ref
    plan = plans_of(ref)[0]
    assert plan.on_grid.any()
    slide = SimpleNamespace(pair=SimpleNamespace(driver=SimpleNamespace(
        axis=Translation((1.0, 0.0)))), _s1=25.0)
    assert not _with_grid(plan, slide, ref).on_grid.any()


def test_values_are_placed_on_their_turn_with_a_side_per_value():
    """placed_on_turn with one side per value gives each value what a call
    with its side alone gives (the hand-over points of many candidates are
    placed together)."""
    from cspace.batch.plan import placed_on_turn
    rng = np.random.default_rng(5)
    n = 400
    v = rng.uniform(-10, 10, n)
    lo = np.where(rng.random(n) < 0.2, -np.inf, rng.uniform(-3, 0, n))
    hi = np.where(rng.random(n) < 0.2, np.inf, lo + rng.uniform(0, 3, n))
    f0 = rng.uniform(-3, 3, n)
    side = np.where(rng.random(n) < 0.5, 1, -1)
    got = placed_on_turn(v, lo, hi, f0, side)
    for s in (1, -1):
        k = side == s
        np.testing.assert_array_equal(got[k], placed_on_turn(v[k], lo[k], hi[k], f0[k], s))
    top = np.where(np.isfinite(hi), hi, f0 + math.pi)
    assert np.all(got[side > 0] <= top[side > 0] + 1e-6)
