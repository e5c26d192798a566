"""Removal: bisection to ε, Eq. 3, shift order (Eqs. 4-5), conflicts, shrinks,
cycles and the spread shift of returning vectors."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InputError
from synthesis.removal import (COARSE_STEPS, Action, Transition, axis_evidence,
                               defect_support, distance_vector, excluded, max_abs,
                               plan_removal, plan_with_refinement, shift_vector,
                               transition_points)


def test_paper_shift_order_example():
    delta, pl = shift_vector([[3.0, 2.0], [3.0, 3.0]])
    assert_allclose(delta, [3.0, 0.0])
    # d2 goes first (|d2[k2]| = 3 > 2); d1 is then already outside the box
    assert pl[1].order == 0 and pl[1].action is Action.SHIFT and pl[1].axis == 0
    assert pl[0].action is Action.SKIPPED
    # the other order would need two axes
    assert_allclose(shift_vector([[3.0, 2.0]])[0], [0.0, 2.0])


def test_max_abs():
    assert max_abs(-3.0, 2.0) == -3.0 and max_abs(1.0, -2.0) == -2.0 and max_abs(2.0, -2.0) == 2.0


def test_sign_conflict_takes_the_next_cheapest_axis():
    # first vector shifts axis 0 by +3; the second wants axis 0 by -1 (conflict)
    delta, pl = shift_vector([[3.0, np.nan], [-1.0, 2.0]])
    assert_allclose(delta, [3.0, 2.0])
    assert pl[1].action is Action.SHIFT and pl[1].axis == 1


def test_every_axis_conflicting_asks_for_a_shrink():
    u0, tol = np.zeros(2), np.ones(2)
    # a: box must move +x; b: box must move -x; both only along x
    ta = Transition(0, np.array([1.0, 0.0]), np.array([0.6, 0.0]), np.array([0.61, 0.0]),
                    (0.6, 0.61), 7)
    tb = Transition(1, np.array([-1.0, 0.0]), np.array([-0.7, 0.0]), np.array([-0.71, 0.0]),
                    (0.7, 0.71), 7)
    plan = plan_removal(u0, tol, [ta, tb], names=["x", "y"])
    assert plan.progress
    acts = sorted(p.action.name for p in plan.placements)
    assert acts == ["CONFLICT", "SHIFT"]
    assert len(plan.shrinks) == 1 and plan.shrinks[0].name == "x"
    # after shift and shrink both defective points are outside the box
    c = u0 + plan.delta
    for tr in (ta, tb):
        assert excluded(tr, c, plan.tol)
    # minimal: the shrunk edge lies on the healthy end of the conflicting vector
    s = plan.shrinks[0]
    assert s.new < s.old and s.reason == "conflict"


def test_distance_vector_eq3():
    u0, tol = np.zeros(3), np.array([1.0, 2.0, 0.0])
    d = distance_vector(u0, tol, [0.25, -0.5, 0.0], [1.0, -2.0, 0.0])
    assert_allclose(d[:2], [0.25 - 1.0, -0.5 + 2.0])
    assert np.isnan(d[2])  # the segment does not move that axis


def test_bisection_reaches_eps():
    u0 = np.zeros(2)
    targets = [np.array([1.0, 1.0]), np.array([-1.0, 0.5])]
    # defective beyond a line x + y > 0.8 (first target) / x < -0.3 (second)
    calls = []

    def batch(us):
        calls.append(len(us))
        return [bool(u[0] + u[1] > 0.8) if u[1] > 0.6 * u[0] - 1e-9 and u[0] >= 0
                else bool(u[0] < -0.3) for u in us]

    eps = 1e-3
    trs = transition_points(u0, targets, batch, eps)
    for tr, lam_true in zip(trs, (0.4, 0.3)):
        assert np.max(np.abs(tr.defective - tr.healthy)) < eps
        assert tr.lam[0] <= lam_true <= tr.lam[1]
    # lock-step batches: one call per step with every open bracket
    assert calls[0] == 2 and len(calls) == max(tr.steps for tr in trs)
    with pytest.raises(InputError):
        transition_points(u0, targets, batch, 0.0)


def test_bisection_passes_each_vector_its_targets_hint():
    u0 = np.zeros(1)
    targets = [np.array([1.0]), np.array([-1.0]), np.array([2.0])]
    seen = []

    def batch(us, hints):
        seen.append(list(hints))
        # each target's hint is its own sign: the vector must lie on that side
        assert all(np.sign(u[0]) == h for u, h in zip(us, hints))
        return [abs(u[0]) > 0.5 for u in us]

    trs = transition_points(u0, targets, batch, 1e-2, hints=[1.0, -1.0, 1.0])
    assert seen[0] == [1.0, -1.0, 1.0]
    assert all(tr.lam[0] * abs(tr.u_w[0]) <= 0.5 <= tr.lam[1] * abs(tr.u_w[0]) for tr in trs)
    # the third target closes its bracket one step later (twice the span)
    assert seen[-1] == [1.0]


def test_cycle_refuses_a_shift_that_readmits_a_removed_point():
    u0, tol = np.zeros(2), np.ones(2)
    tr = Transition(0, np.array([1.0, 1.0]), np.array([0.5, 0.5]), np.array([0.51, 0.51]),
                    (0.5, 0.51), 7)
    # the cheap move along -x would bring back an earlier defect at (-1.4, 0)
    plan = plan_removal(u0, tol, [tr], removed=[np.array([-1.4, 0.0])])
    assert plan.cycle
    assert plan.delta[0] == 0 and plan.delta[1] == pytest.approx(-0.5)
    # every move refused -> shrink with reason "cycle"
    plan2 = plan_removal(u0, tol, [tr], removed=[np.array([-1.4, 0.0]), np.array([0.0, -1.4])])
    assert not np.any(plan2.delta) and plan2.shrinks and plan2.shrinks[0].reason == "cycle"
    assert excluded(tr, u0, plan2.tol)


def test_returning_vector_is_shrunk_and_spread_moves_every_axis():
    u0, tol = np.zeros(3), np.ones(3)
    tr = Transition(0, np.array([1.0, 1.0, 1.0]), np.full(3, 0.7), np.full(3, 0.701),
                    (0.7, 0.701), 9)
    single = plan_removal(u0, tol, [tr])
    assert np.count_nonzero(single.delta) == 1
    spread = plan_removal(u0, tol, [tr], spread=[0])
    assert_allclose(spread.delta, -0.3)
    assert spread.placements[0].axes == (0, 1, 2)
    # the whole corner now sits on the healthy end
    assert_allclose(u0 + spread.delta + tol, tr.healthy)
    ret = plan_removal(u0, tol, [tr], returning=[0])
    assert not np.any(ret.delta) and ret.cycle
    # a returning vector gets the spread shrink: every axis cut to the healthy end
    assert sorted(s.axis for s in ret.shrinks) == [0, 1, 2]
    assert {s.reason for s in ret.shrinks} == {"spread"}
    assert_allclose(ret.tol, 0.7)
    assert_allclose(u0 + ret.tol, tr.healthy)
    assert excluded(tr, u0, ret.tol)


def test_conflicting_vector_that_is_not_returning_gets_one_minimal_cut():
    u0, tol = np.zeros(3), np.ones(3)
    tr = Transition(0, np.array([1.0, 1.0, 1.0]), np.array([0.7, 0.8, 0.9]),
                    np.array([0.701, 0.801, 0.901]), (0.7, 0.701), 9)
    # every axis refused: removed points block each single-axis move
    removed = [np.array([-1.05, 0, 0]), np.array([0, -1.05, 0]), np.array([0, 0, -1.05])]
    plan = plan_removal(u0, tol, [tr], removed=removed)
    assert len(plan.shrinks) == 1 and plan.shrinks[0].reason == "cycle"
    # the smallest relative cut: axis 2 (edge moved to 0.9)
    assert plan.shrinks[0].axis == 2 and plan.shrinks[0].new == pytest.approx(0.9)


@pytest.mark.parametrize("spread_shrink", [True, False])
def test_symmetric_defect_needs_the_spread_shrink(spread_shrink):
    """A defect that no shift can cure and that needs all axes together:
    |sum(u - u_ref)| > 1.5 with the reference fixed (an output deviation that
    grows the same way on both sides of the nominal), t = 1 on three axes.
    Run as the loop runs it (removal counts, spread shift, patience): with
    the spread shrink the returning corners are removed in finitely many
    iterations; with one minimal cut per return the cut edge approaches the
    defect boundary only geometrically and the defects never go away."""
    from synthesis.loop import removal_counts
    n, patience = 3, 2
    t = np.ones(n)
    u0 = np.zeros(n)
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * n)).reshape(n, -1).T

    def bad(u):
        return bool(abs(u.sum()) > 1.5 + 1e-12)

    counts: dict = {}
    removed: list = []
    for it in range(25):
        U = u0 + corners * t
        flags = [bad(u) for u in U]
        if not any(flags):
            break
        idx = [i for i, f in enumerate(flags) if f]
        trs = transition_points(u0, [U[i] for i in idx],
                                lambda us: [bad(u) for u in us], 1e-6)
        keys = [str(corners[i]) for i in idx]
        ret = [p for p, k in enumerate(keys) if counts.get(k, 0) >= patience]
        spr = [p for p, k in enumerate(keys) if 0 < counts.get(k, 0) < patience]
        plan = plan_removal(u0, t, trs, removed=removed, spread=spr,
                            returning=ret if spread_shrink else ())
        if not spread_shrink and ret:
            # the old rule: one minimal cut per returning vector
            plan = plan_removal(u0, t, trs, removed=removed, spread=spr,
                                returning=ret)
            tt = t.copy()
            for p in ret:
                tr = trs[p]
                s = np.sign(tr.u_w - tr.healthy)
                a = s * (tr.healthy - (u0 + plan.delta))
                i = int(np.argmax(np.where(a > 0, a / t, -np.inf)))
                tt[i] = min(tt[i], a[i])
            plan = type(plan)(plan.delta, tt, plan.placements, plan.shrinks, plan.distances)
        counts = removal_counts(counts, keys, plan.placements)
        removed += [tr.defective for tr in trs]
        u0, t = u0 + plan.delta, plan.tol
    done = not any(bad(u) for u in u0 + corners * t)
    assert done is spread_shrink
    if spread_shrink:
        assert it <= 8 and np.all(t > 0.25)


def test_linear_interference_converges_in_finitely_many_iterations():
    """A defect that needs all axes together: the corner of the box is defective
    while sum(u) > 1.5 (n = 3, t = 1).  Single-axis shifts approach the
    boundary only geometrically; the spread shift of the returning vector ends it."""
    n, t = 3, np.ones(3)
    u0 = np.zeros(n)
    counts = 0
    for it in range(6):
        corner = u0 + t
        if corner.sum() <= 1.5 + 1e-3:
            break
        trs = transition_points(u0, [corner], lambda us: [bool(u.sum() > 1.5) for u in us],
                                1e-4)
        plan = plan_removal(u0, t, trs, spread=[0] if counts else [])
        counts += 1
        u0 = u0 + plan.delta
    assert it <= 2 and (u0 + t).sum() <= 1.5 + 1e-3


def test_axis_evidence_counts_sides_of_defective_and_healthy_vectors():
    u0 = np.zeros(2)
    U = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1], [1, 0]], float)
    bad = np.array([True, True, False, False, True])
    ev = axis_evidence(u0, U, bad)
    # axis 0: every defective vector is above the nominal, no healthy one is
    assert_allclose(ev[:, 0], [-1.0, 1.0])
    # axis 1: 1/3 of the defective above and 1/3 below; 1/2 of the healthy each
    assert_allclose(ev[:, 1], [1 / 3 - 1 / 2, 1 / 3 - 1 / 2])
    assert not axis_evidence(u0, U, np.zeros(5, bool)).any()
    assert not axis_evidence(u0, U, np.ones(5, bool)).any()
    with pytest.raises(InputError, match="shape"):
        axis_evidence(u0, U[:, :1], bad)
    with pytest.raises(InputError, match="flags"):
        axis_evidence(u0, U, bad[:3])


def test_equal_cost_axes_follow_the_evidence():
    # both axes cost 2; the second is the one the evidence ties to the defect
    d = [[-2.0, -2.0]]
    delta, pl = shift_vector(d)
    assert pl[0].axis == 0  # no evidence: axis order
    delta, pl = shift_vector(d, preference=np.array([[0.1, 0.9]]))
    assert pl[0].axis == 1
    assert_allclose(delta, [0.0, -2.0])
    # the evidence never overrides a cheaper axis
    delta, pl = shift_vector([[-1.0, -2.0]], preference=np.array([[0.0, 1.0]]))
    assert pl[0].axis == 0


def test_evidence_finds_the_driving_axis_where_the_axis_order_wanders():
    """Box corners are defective when u[3] + 0.2 * (u[0] + u[1] + u[2]) > 0.8
    (t = 1 on all four axes): axis 3 drives the defect, the first three barely
    matter.  Every corner has four equal-cost axes.  With the evidence the first
    shift moves axis 3; broken by axis number it moves the first axes, which
    hardly matter.  Returning vectors get the spread shift, as in the loop."""
    n = 4
    t = np.ones(n)
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * n)).reshape(n, -1).T

    def bad(u):
        return bool(u[3] + 0.2 * u[:3].sum() > 0.8 + 1e-12)

    def run(use_evidence):
        u0 = np.zeros(n)
        shifts = []
        for it in range(30):
            U = u0 + corners * t
            flags = np.array([bad(u) for u in U])
            if not flags.any():
                return it, u0, shifts
            trs = transition_points(u0, list(U[flags]), lambda us: [bad(u) for u in us], 1e-6)
            ev = axis_evidence(u0, U, flags) if use_evidence else None
            plan = plan_removal(u0, t, trs, evidence=ev,
                                spread=range(len(trs)) if shifts else ())
            shifts.append(plan.delta)
            u0 = u0 + plan.delta
        return None, u0, shifts

    it, u0, shifts = run(True)
    assert np.flatnonzero(shifts[0]).tolist() == [3]
    assert it is not None and it <= 3
    assert not any(bad(u0 + c * t) for c in corners)
    it_plain, u0_plain, shifts_plain = run(False)
    assert 3 not in np.flatnonzero(shifts_plain[0])  # axes 0, 1: they hardly matter
    # the evidence-guided design moved the driving parameter, not the others
    assert np.abs(u0[:3]).max() < np.abs(u0[3])


def test_vectors_removed_by_a_larger_shift_count_as_removed():
    """The paper's example: d2 = (3, 3) sets Δu = (3, 0), which already moves the
    box past d1 = (3, 2)'s point (skipped).  Both vectors were removed, so both
    count: in the next design either one coming back is a return."""
    from synthesis.loop import removal_counts
    delta, placements = shift_vector([[3.0, 2.0], [3.0, 3.0]])
    assert [p.action for p in placements] == [Action.SKIPPED, Action.SHIFT]
    counts = removal_counts({"b": 2}, ["a", "b"], placements)
    assert counts == {"a": 1, "b": 3}
    conflict = shift_vector([[1.0, np.nan], [-2.0, np.nan]])[1]
    assert Action.CONFLICT in [p.action for p in conflict]
    # a conflicting vector is removed by a cut: it counts too, so that its
    # return is recognised (and cured by the spread shrink after `patience`)
    assert removal_counts({}, ["x", "y"], conflict) == {"x": 1, "y": 1}
    # two vectors of one origin removed in the same iteration: one removal
    assert removal_counts({"a": 1}, ["a", "a"], placements) == {"a": 2}


def test_resumed_bisection_gives_the_bracket_of_a_search_at_once():
    """Bisection continued from a coarse bracket ends on the same bracket, bit for
    bit, as a search to ε in one go; ``max_steps`` stops it early."""
    u0 = np.zeros(3)
    targets = [np.array([1.0, 1.0, -1.0]), np.array([-1.0, 0.3, 1.0])]

    def batch(us):
        return [bool(u @ np.array([0.7, 0.2, -0.4]) > 0.61 or u[2] > 0.37) for u in us]

    full = transition_points(u0, targets, batch, 1e-6)
    coarse = transition_points(u0, targets, batch, 1e-6, max_steps=3)
    assert [tr.steps for tr in coarse] == [3, 3]
    assert all(tr.lam[1] - tr.lam[0] == 0.125 for tr in coarse)
    more = transition_points(u0, targets, batch, 1e-6, start=coarse)
    for a, b in zip(full, more):
        assert a.lam == b.lam and a.steps == b.steps
        assert np.array_equal(a.healthy, b.healthy) and np.array_equal(a.defective, b.defective)
    with pytest.raises(InputError, match="one entry per target"):
        transition_points(u0, targets, batch, 1e-6, start=coarse[:1])
    with pytest.raises(InputError, match="max_steps"):
        transition_points(u0, targets, batch, 1e-6, max_steps=-1)


def _corner_case(n=4, seed=3):
    """Box corners and edge midpoints of a box +/-1 around 0 in n dimensions, a
    defect region that is a union of half-spaces (several directions, so that
    some shifts exclude other vectors and some do not)."""
    rng = np.random.default_rng(seed)
    corners = np.array(np.meshgrid(*[[-1.0, 0.0, 1.0]] * n)).reshape(n, -1).T
    corners = corners[np.any(corners != 0, axis=1)]
    normals = rng.normal(size=(5, n))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    limits = rng.uniform(0.55, 0.9, size=5) * np.abs(normals).sum(axis=1)
    calls = []

    def batch(us):
        calls.append(len(us))
        return [bool(np.any(normals @ u > limits)) for u in us]

    flags = batch(list(corners))
    calls.clear()
    return np.zeros(n), np.ones(n), [c for c, f in zip(corners, flags) if f], batch, calls


def test_refinement_on_demand_uses_eps_where_the_plan_needs_it():
    u0, tol, targets, batch, calls = _corner_case()
    assert len(targets) >= 10
    eps = 1e-4
    seen = []
    plan, trs = plan_with_refinement(u0, tol, targets, batch, eps,
                                     progress=lambda k, m: seen.append((k, m)))
    n_lazy = sum(calls)
    # one progress call per batch, numbered over the whole search; it counts
    # the open brackets, and a batch of few also asks ahead (SEARCH_AHEAD)
    assert [k for k, _ in seen] == list(range(len(calls)))
    assert all(m <= c <= 3 * m for (_, m), c in zip(seen, calls))
    assert any(c > m for (_, m), c in zip(seen, calls))
    calls.clear()
    full = transition_points(u0, targets, batch, eps)
    n_full = sum(calls)
    assert n_lazy < 0.8 * n_full
    used = [p.vector for p in plan.placements if p.action is not Action.SKIPPED]
    assert used and len(used) < len(targets)
    for j, tr in enumerate(trs):
        width = np.max(np.abs(tr.defective - tr.healthy))
        if j in used:
            # the bracket of a search to eps at once, bit for bit
            assert width < eps and tr.lam == full[j].lam
        else:
            # skipped: coarse, or partly refined while an earlier plan used it;
            # either way a bracket of the same bisection
            assert (tr.steps >= COARSE_STEPS
                    and tr.lam[0] <= full[j].lam[0] <= full[j].lam[1] <= tr.lam[1])
        # skipped on the coarse healthy end: the fine transition is excluded too
        assert excluded(full[j], u0 + plan.delta, plan.tol)
    assert sum(tr.steps == COARSE_STEPS for tr in trs) >= len(targets) // 3
    # the plan is the plan of its own transitions
    again = plan_removal(u0, tol, trs)
    assert np.array_equal(again.delta, plan.delta) and np.array_equal(again.tol, plan.tol)
    # against the plan from transitions all bisected to eps: the same shifts up to eps
    ref = plan_removal(u0, tol, full)
    assert np.max(np.abs(ref.delta - plan.delta)) <= eps


def test_refinement_on_demand_with_no_coarse_steps_is_the_full_search():
    u0, tol, targets, batch, calls = _corner_case(n=3, seed=5)
    plan, trs = plan_with_refinement(u0, tol, targets, batch, 1e-5, coarse_steps=40)
    full = transition_points(u0, targets, batch, 1e-5)
    assert [t.lam for t in trs] == [t.lam for t in full]
    ref = plan_removal(u0, tol, full)
    assert np.array_equal(ref.delta, plan.delta)
    with pytest.raises(InputError, match="coarse_steps"):
        plan_with_refinement(u0, tol, targets, batch, 1e-5, coarse_steps=-2)


def _sum_defect(axes, level):
    """A defect that depends on ``axes`` only: defective when their sum exceeds
    ``level``; counts its tests."""
    calls = []

    def batch(us, hints=None):
        calls.append(len(us))
        return [bool(np.sum(np.asarray(u)[list(axes)]) > level) for u in us]
    return batch, calls


def test_defect_support_keeps_only_the_parameters_the_defect_needs():
    batch, calls = _sum_defect((0, 2), 1.5)
    u0 = np.zeros(5)
    out = defect_support(u0, [np.ones(5), np.array([1.0, 0.0, 1.0, 0.0, -1.0])], batch,
                         ahead=1)
    assert_allclose(out[0], [1.0, 0.0, 1.0, 0.0, 0.0])
    assert_allclose(out[1], [1.0, 0.0, 1.0, 0.0, 0.0])
    # one batch per parameter the vectors move (5 and 3): every vector in each
    assert len(calls) == 5 and calls[:3] == [2, 2, 2]
    # the reduced vectors are defective
    assert all(batch(out))
    # the order decides among redundant causes: either axis alone suffices
    batch2, _ = _sum_defect((0, 1), 0.5)
    assert_allclose(defect_support(np.zeros(2), [np.ones(2)], batch2)[0], [0.0, 1.0])
    assert_allclose(defect_support(np.zeros(2), [np.ones(2)], batch2, order=[[1, 0]])[0],
                    [1.0, 0.0])


def test_defect_support_tries_ahead_in_fewer_batches_with_the_same_result():
    """With few targets, a batch also tries each target's next parameters (on
    the guess that those before stay put back): fewer batches, the result of
    one parameter at a time, and the hints follow each trial's target."""
    batch, calls = _sum_defect((0, 2), 1.5)
    targets = [np.ones(5), np.array([1.0, 0.0, 1.0, 0.0, -1.0])]
    out = defect_support(np.zeros(5), targets, batch)
    assert_allclose(out[0], [1.0, 0.0, 1.0, 0.0, 0.0])
    assert_allclose(out[1], [1.0, 0.0, 1.0, 0.0, 0.0])
    # batch 1: every axis of each, on the guess that the one before stays put
    # back; axis 0 does not (for both), so only their first trials count;
    # batch 2: axis 1 stays, 2 does not; axis 2 of the second does not;
    # batch 3: the rest stay.  Three batches instead of five.
    assert len(calls) == 3 and calls[0] == 5 + 3
    seen = []

    def hinted(us, hints):
        seen.append(list(hints))
        return batch(us)
    defect_support(np.zeros(5), targets, hinted, hints=["a", "b"])
    assert seen[0] == ["a"] * 5 + ["b"] * 3
    # many random problems: any look-ahead gives the result of none
    rng = np.random.default_rng(3)
    for _ in range(200):
        n = int(rng.integers(1, 9))
        w, level = rng.normal(size=n), 0.5 * rng.normal()

        def sign_batch(us, hints=None):
            return [bool(np.dot(w, np.abs(u)) > level) for u in us]
        ts = [t for t in (rng.choice([-1.0, 0.0, 1.0], size=n) for _ in range(4))
              if sign_batch([t])[0]]
        order = [rng.permutation(n) for _ in ts]
        one = defect_support(np.zeros(n), ts, sign_batch, order=order, ahead=1)
        for a in (2, 5, 64):
            got = defect_support(np.zeros(n), ts, sign_batch, order=order, ahead=a)
            assert all(np.array_equal(x, y) for x, y in zip(one, got))


def test_spread_shrink_with_support_cuts_only_the_parameters_the_defect_needs():
    """A returning corner whose defect depends on two of four parameters: the
    paper's spread shrink cuts all four; with ``support`` only those two, and
    the cut box's corner on the defect's side is healthy."""
    batch, _ = _sum_defect((1, 3), 1.2)
    u0, tol = np.zeros(4), np.ones(4)
    target = np.ones(4)
    plain, _ = plan_with_refinement(u0, tol, [target], batch, 1e-6, returning=[0])
    assert sorted(s.axis for s in plain.shrinks) == [0, 1, 2, 3]
    plan, trs = plan_with_refinement(u0, tol, [target], batch, 1e-6, returning=[0],
                                     support=True)
    assert sorted(s.axis for s in plan.shrinks) == [1, 3]
    assert {s.reason for s in plan.shrinks} == {"spread"}
    assert_allclose(plan.tol[[0, 2]], 1.0)
    assert_allclose(plan.tol[[1, 3]], 0.6, atol=1e-6)
    assert not batch([u0 + plan.tol])[0]
    assert excluded(trs[0], u0, plan.tol)


def test_defect_support_checks_its_input():
    batch, _ = _sum_defect((0,), 0.5)
    with pytest.raises(InputError, match=r"target 1 has shape \(2,\)"):
        defect_support(np.zeros(3), [np.ones(3), np.ones(2)], batch)
    with pytest.raises(InputError, match=r"one axis order per target \(1\), got 2"):
        defect_support(np.zeros(3), [np.ones(3)], batch, order=[[0, 1, 2], [2, 1, 0]])
    with pytest.raises(InputError, match="ahead"):
        defect_support(np.zeros(3), [np.ones(3)], batch, ahead=0)


def test_costs_equal_but_for_rounding_are_ordered_by_axis():
    # the same shift on two axes of equal tolerance, computed from coordinates
    # of different magnitudes: equal but for rounding, which differs when the
    # model's length unit changes (mm against um chose whl_x against lockR)
    from synthesis.removal import _axis_order, shift_vector
    d = 0.0008362719301686639
    for noisy in ([d * (1 + 8e-12), d], [d, d * (1 + 8e-12)]):
        assert _axis_order(np.array(noisy), None) == [0, 1]
        delta, (p,) = shift_vector([noisy])
        assert p.axis == 0 and delta[0] != 0 and delta[1] == 0
    # a real difference still decides, and the evidence orders real ties
    assert _axis_order(np.array([2.0, 1.0]), None) == [1, 0]
    assert _axis_order(np.array([1.0, 1.0 + 1e-12]), np.array([0.0, 0.5])) == [1, 0]


@pytest.mark.parametrize("method", ["bisect", "margin"])
def test_asking_ahead_gives_the_same_brackets_in_fewer_batches(method):
    """With ``known``, a round of few brackets also asks the next point of both
    halves (where it is a bisection): the brackets, step counts and margins
    are those of the search without it, bit for bit, in fewer batches."""
    from synthesis.removal import SEARCH_AHEAD
    u0, tol, targets, _, _ = _corner_case()
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(3, len(u0)))
    calls = []

    def batch(us):
        calls.append(len(us))
        out = []
        for u in us:
            m = float(np.min(0.8 - normals @ u)) if method == "margin" else float("nan")
            # a sequence-like defect half the time: defective with a positive margin
            seq = float(np.sum(u)) > 1.2
            out.append((bool(m <= 0 or seq) if method == "margin" else seq
                        or bool(np.any(normals @ u > 0.8)), m))
        return out

    few = targets[:SEARCH_AHEAD - 2]
    plain = transition_points(u0, few, batch, 1e-6, method=method)
    n_plain, calls[:] = len(calls), []
    ahead = transition_points(u0, few, batch, 1e-6, method=method, known={})
    # (the margin rule's own steps converge in few rounds; its bisections
    # are the ones asked ahead)
    assert len(calls) < (0.75 if method == "bisect" else 1.0) * n_plain
    for a, b in zip(plain, ahead):
        assert a.lam == b.lam and a.steps == b.steps and a.kept == b.kept
        assert np.array_equal(a.margins, b.margins, equal_nan=True)
