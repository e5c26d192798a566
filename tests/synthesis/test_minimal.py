"""Minimal changes from defect margins: bands and noise levels, linearised
margins and their JSON form, and the smallest change on hand-made constraints
with known answers (``test_minimal_fix.py`` runs whole syntheses)."""

import math
from collections import OrderedDict

import numpy as np
import pytest

import synthesis.executors as executors
from cspace.accuracy import as_accuracy
from cspace.defects import RESOLUTION, DefectResult, Reason, reference
from cspace.errors import InputError
from synthesis.memo import TestMemo
from mechanisms.models import Parameter
from synthesis.guards import Guards
from synthesis.minimal import (CONTINUOUS, KINDS, REMOVALS, TARGET, Linearised,
                               MarginSensitivity, describe_defect, known_from_dicts,
                               linearise, margin_bands, margin_sensitivities, minimal_change,
                               sensitivity_task, shift_only)

from ..cspace.batch.yoke import yoke


def test_the_vocabulary():
    assert REMOVALS == ("lp", "greedy")
    assert set(CONTINUOUS) == set(KINDS) - {"sequence"}


def test_margin_bands_follow_the_accuracy_and_d():
    acc = as_accuracy("fast")
    b = margin_bands("fast", 0.5)
    assert b == {"channel": acc.batch_gap_band, "start": acc.batch_gap_band,
                 "deviation": acc.batch_dev_band * 0.5, "sequence": RESOLUTION * 0.5}


# ------------------------------------------------------------------ sensitivities
def _sens(kind="channel", margin=-0.01, grad=(2.0, -0.5, 0.0), noise=(1.0, 1.0, np.inf),
          band=0.1, pair=0):
    return MarginSensitivity(kind, pair, margin, np.array(grad, dtype=float),
                             np.array(noise, dtype=float), band)


def test_a_sensitivity_counts_above_its_noise():
    s = _sens()
    assert s.significant.tolist() == [True, False, False]
    assert s.usable
    assert repr(s) == ("<MarginSensitivity channel pair 0: margin -0.01, 1 of 3 sensitivities "
                       "above the noise>")
    # a sequence margin jumps: never usable; nor a margin without sensitivity or value
    assert not _sens(kind="sequence").usable
    assert not _sens(grad=(0.5, -0.5, 0.0)).usable
    assert not _sens(margin=math.nan).usable


def test_linearise_drops_the_noise_and_aims_at_a_tenth_of_the_band():
    point = np.array([1.0, 2.0, 3.0])
    about = {"vector": 7}
    (c,) = linearise(_sens(), point, "k", about)
    assert isinstance(c, Linearised)
    np.testing.assert_array_equal(c.gradient, [2.0, 0.0, 0.0])
    assert c.target == pytest.approx(TARGET * 0.1) and c.band == 0.1
    assert (c.key, c.kind, c.pair, c.margin) == ("k", "channel", 0, -0.01)
    # its own copies
    point[0] = 99.0
    about["vector"] = 8
    assert c.point[0] == 1.0 and c.about == {"vector": 7}
    # a deviation without d: one constraint
    assert len(linearise(_sens(kind="deviation", pair=-1), point, "k")) == 1


def test_a_deviation_gets_its_companion_on_the_other_side():
    s = _sens(kind="deviation", margin=-0.002, pair=-1)
    own, other = linearise(s, [0.0, 0.0, 0.0], "v3|deviation|-1", d=0.01)
    assert other.key == "v3|deviation|-1|other side"
    assert other.margin == pytest.approx(2 * 0.01 + 0.002)
    np.testing.assert_array_equal(other.gradient, -own.gradient)
    assert other.target == own.target and other.kind == "deviation"


def test_worst_is_the_worst_corner_of_the_linear_model():
    c = Linearised("k", np.array([1.0, 1.0]), -0.02, np.array([2.0, -1.0]), 0.0, 1.0,
                   "channel", 0)
    # m + g . (c - p) - |g| . t
    assert c.worst([1.0, 1.0], [0.0, 0.0]) == pytest.approx(-0.02)
    assert c.worst([1.1, 0.9], [0.01, 0.02]) == pytest.approx(-0.02 + 0.2 + 0.1 - 0.02 - 0.02)
    # brute force over the corners of the box
    rng = np.random.default_rng(0)
    for _ in range(20):
        ctr, tol = rng.normal(1, 0.1, 2), rng.uniform(0, 0.05, 2)
        corners = [ctr + np.array([sa, sb]) * tol for sa in (-1, 1) for sb in (-1, 1)]
        lin = [c.margin + c.gradient @ (x - c.point) for x in corners]
        assert c.worst(ctr, tol) == pytest.approx(min(lin), abs=1e-12)


# ------------------------------------------------------------------ JSON form
def _lin(**kw):
    d = dict(key="v1|channel|0", point=np.array([20.0, 5.0]), margin=-0.003,
             gradient=np.array([0.0, -0.08]), target=1e-5, band=1e-4, kind="channel", pair=0,
             about={"vector": 1, "kind": ["jam"]})
    d.update(kw)
    return Linearised(**d)


def test_linearised_dict_round_trip():
    c = _lin()
    back = Linearised.from_dict(c.to_dict(), 2)
    assert back.to_dict() == c.to_dict()
    assert back.point.tobytes() == c.point.tobytes()
    assert "1 parameter(s)" in repr(back)
    (again,) = known_from_dicts([c.to_dict()], 2)
    assert again.key == c.key
    assert known_from_dicts([], 2) == ()


@pytest.mark.parametrize("change, n, message", [
    ({}, 3, "must hold 3 values"),
    ({"gradient": [0.0, math.inf]}, 2, "must be finite"),
    ({"margin": math.nan}, 2, "must be finite"),
    ({"kind": "sequence!"}, 2, "kind must be one of"),
])
def test_linearised_from_dict_refuses_other_documents(change, n, message):
    d = dict(_lin().to_dict(), **change)
    with pytest.raises(ValueError, match=message):
        Linearised.from_dict(d, n)


def test_linearised_from_dict_needs_its_keys():
    d = _lin().to_dict()
    del d["band"]
    with pytest.raises(KeyError):
        Linearised.from_dict(d, 2)


# ------------------------------------------------------------------ the LP
def _one(margin=-0.03, grad=1.0, band=1.0, key="jam"):
    return Linearised(key, np.zeros(1), margin, np.array([grad]), 0.0, band, "channel", 0)


def test_no_constraint_is_no_change_or_the_forced_one():
    u0, tol = np.zeros(2), np.full(2, 0.02)
    r = minimal_change(u0, tol, [])
    assert r.success and r.status == "none" and not r.delta.any()
    np.testing.assert_array_equal(r.tol, tol)
    r = minimal_change(u0, tol, [], at_least=[0.0, -0.005], at_most=[0.01, 0.02])
    assert r.status == "shift"
    np.testing.assert_array_equal(r.delta, [0.0, -0.005])
    np.testing.assert_array_equal(r.tol, [0.01, 0.02])


def test_a_box_already_clear_needs_nothing():
    # m + g (c - p) - |g| t = 0.05 - 0.01 > 0
    r = minimal_change([0.0], [0.01], [_one(margin=0.05)])
    assert r.success and r.status == "none" and r.binding == {}
    assert r.delta.tolist() == [0.0] and r.tol.tolist() == [0.01]
    assert r.message == "the box is already clear of every linearised defect"


def test_the_shift_is_bounded_by_the_trust_region():
    """-0.03 + Δ - t' >= 0 with t' <= 0.01: a shift of 0.04 at least, four
    initial tolerances; a cut alone gains at most 0.01."""
    r = minimal_change([0.0], [0.01], [_one()], trust=5.0)
    assert r.success and r.status == "shift"
    np.testing.assert_allclose(r.delta, [0.04], rtol=1e-6)
    assert r.binding == {("shift", 0): 0}
    bad = minimal_change([0.0], [0.01], [_one()], trust=1.0)
    assert not bad.success and bad.status == "infeasible" and bad.infeasible == (0,)
    assert bad.delta.tolist() == [0.0] and bad.tol.tolist() == [0.01]
    assert bad.message.startswith("1 defect(s) cannot be cleared")


def test_a_change_is_attributed_to_this_iteration_s_defect_first():
    """Two identical constraints, both active: the change is named after the
    current one when only one is current, else after the first."""
    old, new = _one(key="old"), _one(key="new")
    r = minimal_change([0.0], [0.01], [old, new], trust=5.0, current=[False, True])
    assert r.binding == {("shift", 0): 1}
    r = minimal_change([0.0], [0.01], [old, new], trust=5.0)
    assert r.binding == {("shift", 0): 0}
    assert r.nit >= 2                      # the largest move, then the sum at that maximum


class _Params:
    """The parameter names and defaults :meth:`Guards.of` reads from a model."""

    def __init__(self, n):
        self.names = tuple(f"u{i}" for i in range(n))
        self.parameters = tuple(Parameter(nm, 0.0, 1.0) for nm in self.names)


def _two_sided_and_one_sided():
    """Axis 0: a deviation at both sides of the nominal, 0.01 beyond the box
    (worst corners -0.01 - Δ0 + 0.03 - t0' and -0.01 + Δ0 + 0.03 - t0'): only a
    cut to 0.02 clears it.  Axis 1: a jam at one side,
    -0.001 - Δ1 + 0.02 - t1': a shift of -0.001 or a cut of 0.001 clears it."""
    both = {"both_sides": True}
    return [Linearised("a", np.array([0.03, 0.0]), -0.01, np.array([-1.0, 0.0]), 0.0, 1.0,
                       "deviation", -1, both),
            Linearised("b", np.array([-0.03, 0.0]), -0.01, np.array([1.0, 0.0]), 0.0, 1.0,
                       "deviation", -1, both),
            Linearised("c", np.array([0.0, 0.02]), -0.001, np.array([0.0, -1.0]), 0.0, 1.0,
                       "channel", 0, {"vector": 2})]


def test_shift_only_marks_the_one_sided_defects():
    assert shift_only(_two_sided_and_one_sided()) == [False, False, True]
    assert shift_only([]) == []


def test_a_one_sided_defect_is_shifted_while_a_two_sided_one_is_cut():
    """With a cheap cut on axis 1 the cut phase would cut both axes; a cut
    does not count for the one-sided defect, so it is shifted instead."""
    u0, tol = np.zeros(2), np.array([0.03, 0.02])
    cons = _two_sided_and_one_sided()
    g = Guards.of(_Params(2), cut_cost={"u1": 0.1})
    free = minimal_change(u0, tol, cons, guards=g)
    assert free.status == "cut"
    np.testing.assert_allclose(free.tol, [0.02, 0.019], atol=1e-8)
    np.testing.assert_allclose(free.delta, 0.0, atol=1e-12)
    r = minimal_change(u0, tol, cons, guards=g, shift_only=shift_only(cons))
    assert r.status == "cut"
    np.testing.assert_allclose(r.tol, [0.02, 0.02], atol=1e-8)
    np.testing.assert_allclose(r.delta, [0.0, -0.001], atol=1e-8)
    # the cut is named after a two-sided defect, the shift after the one-sided one
    assert r.binding[("cut", 0)] in (0, 1) and r.binding[("shift", 1)] == 2
    # the one-sided defect on a fixed parameter: no allowed change clears it
    fixed = Guards.of(_Params(2), fixed=["u1"])
    bad = minimal_change(u0, tol, cons, guards=fixed, shift_only=shift_only(cons))
    assert not bad.success and bad.infeasible == (2,)
    ok = minimal_change(u0, tol, cons, guards=fixed)
    assert ok.success and ok.tol[1] < tol[1]


def test_the_rows_no_change_clears_alone_are_found_without_an_lp_each():
    """An infeasible joint change names the constraints no allowed change
    clears on their own; each row's answer is read from its best corner
    (``_clearable_alone``) where it is clear, and it is HiGHS's answer on
    random constraints with fixed, hard and floored parameters, two-sided
    ones and forced moves."""
    import synthesis.minimal as mn
    rng = np.random.default_rng(7)
    decided = 0
    for trial in range(40):
        n = int(rng.integers(2, 6))
        u0 = rng.normal(size=n)
        tol = rng.uniform(0.005, 0.05, n) * (rng.random(n) > 0.1)
        cons = []
        for k in range(int(rng.integers(2, 9))):
            g = rng.normal(size=n) * (rng.random(n) > 0.3)
            cons.append(Linearised(f"d{k}", u0 + rng.normal(scale=0.02, size=n),
                                   float(rng.uniform(-0.2, 0.01)), g, 0.0,
                                   float(rng.uniform(1e-4, 1e-2)), "channel", 0,
                                   {"both_sides": bool(rng.random() < 0.3)}))
        names = [f"u{i}" for i in range(n)]
        g = Guards.of(_Params(n), fixed=[x for x in names if rng.random() < 0.2],
                      hard=[x for x in names if rng.random() < 0.2],
                      min_keep=float(rng.uniform(0.1, 0.9)))
        need = np.where(rng.random(n) < 0.2, rng.normal(scale=0.01, size=n), 0.0)
        t = float(rng.uniform(0.5, 3.0))
        lim = mn._change_limits(tol, tol, g, need, None)
        lp = mn._change_lp(u0, tol, tol, cons, lim, t, shift_only(cons))
        for j, alone in enumerate(mn._clearable_alone(lp)):
            lp_says = mn._solve_lp(lp, lp.c_cut, lp.s_hi_cut, rows=slice(j, j + 1)).status == 0
            if alone is not None:
                decided += 1
                assert alone == lp_says, (trial, j)
    assert decided > 100


# ------------------------------------------------------------------ provenance
def test_describe_defect_reads_the_memo():
    memo = TestMemo(1, np.zeros(2), np.ones(2))
    r = DefectResult(True, (Reason.JAM, Reason.TOPOLOGY), 0.0, 0.1, (1, 0.25, float("nan")),
                     (), (), "pair b: jams")
    memo.put([0.5, 0.5], r, True, -0.1)
    assert describe_defect(memo, np.array([0.5, 0.5])) == {
        "u": [0.5, 0.5], "pair": 1, "kind": ["jam", "topology"], "q1": 0.25, "q2": None,
        "message": "pair b: jams"}
    empty = {"pair": None, "kind": [], "q1": None, "q2": None, "message": ""}
    assert describe_defect(memo, [0.5, 0.6]) == {"u": [0.5, 0.6], **empty}
    assert describe_defect(None, [0.5, 0.5]) == {"u": [0.5, 0.5], **empty}


# ------------------------------------------------------------------ worker task
def test_sensitivity_task_uses_the_worker_s_reference(monkeypatch):
    """The yoke's jamming corner (pin 5.02 in a slot of half width 5.01): the
    channel margin 2 (w - r) / L, sensitive to r and w only."""
    m = yoke()
    acc = as_accuracy("fast")
    ref = reference(m, acc)
    monkeypatch.setattr(executors, "_REFS", OrderedDict())
    executors.remember_reference(m, acc, ref.d, ref)
    corner = np.array([[20.0, 5.02, 5.01]])
    (found,) = sensitivity_task(m, corner, acc, ref.d, m.tol)
    direct = margin_sensitivities(m, corner, ref, m.tol)[0]
    assert [s.kind for s in found] == [s.kind for s in direct]
    ch = next(s for s in found if s.kind == "channel")
    L = 25.0
    assert ch.margin == pytest.approx(2 * (5.01 - 5.02) / L, abs=1e-9)
    np.testing.assert_allclose(ch.gradient, [0.0, -2 / L, 2 / L], atol=1e-6)
    assert ch.significant.tolist() == [False, True, True]
    with pytest.raises(InputError, match="U must be an"):
        sensitivity_task(m, np.zeros((1, 2)), acc, ref.d, m.tol)


def test_margins_a_test_computed_are_not_computed_again(monkeypatch):
    """``base``: the rows' margins as the check list's batched test gave them
    (synthesis.executors.margin_rows): the same sensitivities, bit for bit,
    and no batched call for those rows (a row without them gets its own)."""
    import cspace.batch.margins as bm
    from synthesis.executors import margin_rows
    m = yoke()
    ref = reference(m, as_accuracy("fast"))
    U = np.array([[20.0, 5.02, 5.01], [20.0, 5.0, 5.0], [20.0, 5.02, 4.99]])
    direct = margin_sensitivities(m, U, ref, m.tol)
    given = margin_rows(bm.defect_margins(m, U, ref))
    calls = []
    real = bm.defect_margins
    monkeypatch.setattr(bm, "defect_margins", lambda *a, **k: calls.append(len(a[1])) or
                        real(*a, **k))
    for base, asked in ((given, []), ([given[0], None, given[2]], [1])):
        calls.clear()
        got = margin_sensitivities(m, U, ref, m.tol, base=base)
        assert calls == asked
        for a, b in zip(got, direct):
            assert [(s.kind, s.pair, s.margin) for s in a] == [(s.kind, s.pair, s.margin)
                                                               for s in b]
            for s, t in zip(a, b):
                np.testing.assert_array_equal(s.gradient, t.gradient)
                np.testing.assert_array_equal(s.noise, t.noise)
    for bad in (given[:2], 5):
        with pytest.raises(InputError, match="one entry per row"):
            margin_sensitivities(m, U, ref, m.tol, base=bad)
    with pytest.raises(InputError, match=r"base\[1\] must hold"):
        margin_sensitivities(m, U, ref, m.tol, base=[given[0], {"channel": 1}, None])


def test_a_repeated_target_is_differenced_once(monkeypatch):
    """A target repeated (a defective vector whose mirror is another defective
    check-list vector) travels in one task, and every copy gets its result."""
    from synthesis.minimal import _target_sensitivities
    m = yoke()
    acc = as_accuracy("fast")
    ref = reference(m, acc)
    monkeypatch.setattr(executors, "_REFS", OrderedDict())
    executors.remember_reference(m, acc, ref.d, ref)
    sent = []
    real = executors.run_ordered

    def spy(executor, fn, argsets, *a, **k):
        argsets = list(argsets)
        sent.extend(np.asarray(s[1]) for s in argsets)
        return real(executor, fn, argsets, *a, **k)

    monkeypatch.setattr(executors, "run_ordered", spy)
    corner = np.array([20.0, 5.02, 5.01])
    other = np.array([20.0, 5.02, 5.0])
    targets = [corner, other, corner.copy(), np.array([20.0, 5.0, 5.0])]
    sens, distinct = _target_sensitivities(executors.SerialExecutor(), m, targets, [0, 1, 2],
                                           acc, ref.d, m.tol, None)
    assert distinct == [0, 1]
    rows = np.vstack(sent)
    assert len(rows) == 2 and sorted(map(tuple, rows)) == sorted([tuple(corner), tuple(other)])
    assert sorted(sens) == [0, 1, 2]
    assert sens[2] is sens[0]
    direct = margin_sensitivities(m, [corner, other], ref, m.tol)
    for j, d_ in ((0, direct[0]), (1, direct[1]), (2, direct[0])):
        assert [(s.kind, s.margin) for s in sens[j]] == [(s.kind, s.margin) for s in d_]
        for s, t in zip(sens[j], d_):
            np.testing.assert_array_equal(s.gradient, t.gradient)


def test_a_step_that_does_not_build_gives_a_one_sided_difference():
    """A yoke whose pin has almost no radius: the step down along the pin's
    radius does not build.  Its sensitivity is the one-sided difference of the
    step up (the deviation grows by one unit of w - r per unit of r: d/dr of
    d - max|s - s0| is +1/L), twice as noisy; the nominal's margin must not
    stand in for the missing side (it gave -9.97)."""
    m = yoke()
    ref = reference(m, "fast")
    u = m.nominal.copy()
    u[1] = 0.005
    tol = np.array([0.02, 0.02, 0.02])
    (dev,) = margin_sensitivities(m, [u], ref, tol)[0]
    assert dev.kind == "deviation" and dev.margin < 0
    L = m.build(m.nominal).char_length
    assert dev.gradient[1] == pytest.approx(1 / L, rel=1e-6)
    assert dev.gradient[2] == pytest.approx(-1 / L, rel=1e-6)
    assert dev.noise[1] == pytest.approx(2 * dev.noise[2])
