"""Batched defect margins: closed forms, agreement with the full test, and
independence of how a batch is split."""

import math

import numpy as np
import pytest

from cspace.batch.margins import DEV_FLOOR, MarginBatch, defect_margins, margin_tables, plans_of
from cspace.defects import is_defective, reference
from cspace.errors import InputError

from .yoke import output, yoke


@pytest.fixture(scope="module")
def yoke_ref():
    m = yoke()
    return m, reference(m, "fast")


def _L(m, u):
    return m.build(u).char_length


def test_channel_margin_is_the_analytic_clearance(yoke_ref):
    """A pin of radius r between faces 2w apart: the channel margin is
    2 (w - r) / L (C-space metric) for every variant, to 1e-9 of the size."""
    m, ref = yoke_ref
    rng = np.random.default_rng(1)
    U = m.nominal + m.tol * rng.uniform(-1, 1, (40, m.n))
    mb = defect_margins(m, U, ref, fallback=False)
    L = plans_of(ref)[0].scale2
    exact = 2 * (U[:, 2] - U[:, 1]) / L
    np.testing.assert_allclose(mb.channel[:, 0], exact, rtol=0, atol=1e-9 * 30 / L)
    # closed where the pin is wider than the gap, and then defective
    closed = exact < -ref.accuracy.batch_gap_band
    assert closed.any() and (~closed).any()
    assert mb.defective[closed].all()


def test_deviation_margin_is_the_analytic_motion(yoke_ref):
    """The follower rests until a face is pushed: the batch's deviation margin
    is d minus the largest distance, at the nominal motion's samples, between
    the closed-form motions of variant and nominal (C-space metric)."""
    m, ref = yoke_ref
    plan = plans_of(ref)[0]
    x = plan.x[plan.is_ref]
    np.testing.assert_allclose(plan.f0[plan.is_ref], output(m.nominal, x), rtol=0, atol=1e-9)
    rng = np.random.default_rng(2)
    U = m.nominal + m.tol * rng.uniform(-1, 1, (25, m.n))
    U = U[U[:, 2] - U[:, 1] > 1e-3]
    mb = defect_margins(m, U, ref, fallback=False)
    L = plan.scale2
    f0 = output(m.nominal, x)
    for u, dev in zip(U, mb.deviation):
        exact = ref.d - np.max(np.abs(output(u, x) - f0)) / L
        # the variant's turn-around (q1 = pi) lies between the extra samples
        # around the nominal's: 20 mm * (1e-3 rad)^2 / 2 at most
        assert abs(dev - exact) < 1e-5 / L, (u, dev, exact)
        full = is_defective(m, u, ref=ref)
        assert abs(dev - (ref.d - full.max_deviation)) < ref.accuracy.batch_dev_band * ref.d


def test_the_margin_zero_is_the_bisected_transition_point(yoke_ref):
    """Along u0 -> u_w (the clearance closing), the channel margin is linear and
    its zero lies where the bisection of the full test puts the transition."""
    from synthesis.removal import transition_points
    m, ref = yoke_ref
    uw = m.nominal + np.array([0.0, 1.0, -1.0]) * m.tol     # interference 0.01
    ts = np.array([0.0, 0.5, 1.0])
    mb = defect_margins(m, [m.nominal + t * (uw - m.nominal) for t in ts], ref,
                        fallback=False)
    g = mb.channel[:, 0]
    np.testing.assert_allclose(np.diff(g), np.diff(g)[0], rtol=1e-9)   # linear in t
    t0 = -g[0] / (g[2] - g[0])
    assert t0 == pytest.approx(0.75, abs=1e-9)                          # w - r = 0 there
    eps = 5e-3 * float(np.max(m.tol))      # the fast preset's bisection stop length
    tr = transition_points(m.nominal, [uw], lambda us: [is_defective(m, u, ref=ref).defective
                                                        for u in us], eps)[0]
    u_zero = m.nominal + t0 * (uw - m.nominal)
    assert np.max(np.abs(tr.u_c - u_zero)) <= eps


@pytest.mark.parametrize("name", ["reciprocating_cam", "geneva", "optical_filter"])
def test_verdicts_equal_the_full_test(models, name):
    """Seeded box samples (half corners): the batch's verdict is the full
    test's for every one, whether the margins or the fall-back decided it."""
    from synthesis.verify import box_samples
    m = models[name]
    ref = reference(m, "fast")
    n = {"reciprocating_cam": 60, "geneva": 16}.get(name, 8)
    U = box_samples(m.nominal, m.tol, n, seed=11)
    mb = defect_margins(m, U, ref, fallback=False)
    full = [is_defective(m, u, ref=ref) for u in U]
    cert = mb.certified
    assert cert.sum() >= 0.7 * n
    for v in np.nonzero(cert)[0]:
        assert mb.defective[v] == full[v].defective, (v, mb.results[v], full[v])
    done = defect_margins(m, U, ref)
    assert done.defective.tolist() == [r.defective for r in full]
    assert done.n_fallback == int((~cert).sum())


def test_a_kink_between_the_full_tests_samples_is_left_to_it(models):
    """Where a bound starts pushing a form-closed follower between two of the
    variant's own samples, the full test reads its output there by linear
    interpolation, 2 % of d from the output's value on this Geneva variant.
    With d between the two readings, the batch must not certify a verdict
    (it did: defective, where the full test says healthy)."""
    m = models["geneva"]
    z = np.array([0.2065, 0.2802, -0.1352, 0.7739, 0.6714, 0.8667, -0.1082, 0.4602, -0.1386,
                  -0.4424, 0.3038, 0.892, 0.6086, -0.4296, -0.5438, 0.5433, 0.4103, 0.7272,
                  -0.7073, 0.7234, -0.1347, -0.4533, -0.3135, 0.987, 0.9121, -0.8325])
    u = m.nominal + z * m.tol
    ref = reference(m, "fast")
    full = is_defective(m, u, ref=ref).max_deviation
    batch = ref.d - defect_margins(m, [u], ref, fallback=False).deviation[0]
    assert abs(batch - full) > 0.01 * ref.d          # the two readings differ
    d = 0.5 * (batch + full)
    assert abs(batch - full) / 2 > ref.accuracy.batch_dev_band * d   # beyond the band
    ref_d = reference(m, "fast", d=d)
    mb = defect_margins(m, [u], ref_d, fallback=False)
    truth = is_defective(m, u, ref=ref_d).defective
    assert not mb.certified[0] or bool(mb.defective[0]) == truth
    assert bool(defect_margins(m, [u], ref_d).defective[0]) == truth


def test_a_deviation_read_where_the_output_is_straight_is_certified_within_the_band(models):
    """A Geneva check-list corner whose largest deviation lies 1.5 % of d
    inside d, where the output runs straight between the drive's regular
    samples: the full test reads the same value, so the batch certifies it
    healthy (it left it to the full test while the whole band was asked for).
    With d moved to within the floor of the band from that deviation, it is
    left to the full test; with d below it by more, certified defective;
    each as the full test says."""
    m = models["geneva"]
    z = np.zeros(26)
    z[[0, 3, 4, 9, 10, 15, 16]] = 1.0
    z[[1, 2, 5]] = -1.0
    u = m.nominal + z * m.tol
    ref = reference(m, "fast")
    band = ref.accuracy.batch_dev_band * ref.d
    mb = defect_margins(m, [u], ref, fallback=False)
    full = is_defective(m, u, ref=ref)
    assert 0.5 * band < mb.deviation[0] < band
    assert abs(ref.d - mb.deviation[0] - full.max_deviation) < 1e-3 * band
    assert mb.certified[0] and not mb.defective[0] and not full.defective
    share = DEV_FLOOR * ref.accuracy.batch_dev_band
    for k, certified in ((0.5, False), (-0.5, False), (-2.0, True)):
        d = full.max_deviation * (1 + k * share)
        ref_d = reference(m, "fast", d=d)
        got = defect_margins(m, [u], ref_d, fallback=False)
        truth = is_defective(m, u, ref=ref_d).defective
        assert bool(got.certified[0]) == certified, k
        assert truth == (k < 0)
        if certified:
            assert bool(got.defective[0]) == truth
        assert bool(defect_margins(m, [u], ref_d).defective[0]) == truth


def test_the_deviation_alone_skips_the_hand_overs_with_the_same_numbers(models):
    """``kinds=("deviation", "start")``: the same deviation and start margins
    (the hand-over samples do not touch them), NaN channel and sequence
    margins, fewer curve evaluations, and only a deviation beyond the band
    certified."""
    from synthesis.verify import box_samples
    m = models["geneva"]
    ref = reference(m, "fast")
    U = box_samples(m.nominal, 1.5 * m.tol, 24, seed=3)
    a = defect_margins(m, U, ref, fallback=False)
    b = defect_margins(m, U, ref, fallback=False, kinds=("deviation", "start"))
    np.testing.assert_array_equal(a.deviation, b.deviation)
    np.testing.assert_array_equal(a.start, b.start)
    assert np.isnan(b.channel).all() and np.isnan(b.sequence).all()
    assert b.stats["handover_samples"] == 0 < a.stats["handover_samples"]
    assert b.stats["curve_evaluations"] < a.stats["curve_evaluations"]
    band = ref.accuracy.batch_dev_band * ref.d
    assert (b.certified == (b.deviation <= -band)).all()
    assert (a.defective[b.certified]).all()
    with pytest.raises(InputError, match="kinds must name some of"):
        defect_margins(m, U[:1], ref, kinds=("gap",))
    with pytest.raises(InputError, match="kinds must name some of"):
        defect_margins(m, U[:1], ref, kinds=())


def test_hand_overs_for_some_rows_give_each_row_its_own_numbers(models):
    """``handover_rows``: the rows asked for get the margins of a call with
    every kind, the others those of ``kinds=("deviation", "start")``, bit for
    bit, whatever the chunks."""
    from synthesis.verify import box_samples
    m = models["geneva"]
    ref = reference(m, "fast")
    U = box_samples(m.nominal, 1.5 * m.tol, 16, seed=5)
    want = np.arange(16) % 3 == 0
    a = defect_margins(m, U, ref, fallback=False)
    b = defect_margins(m, U, ref, fallback=False, kinds=("deviation", "start"))
    for chunk in (16, 5):
        c = defect_margins(m, U, ref, fallback=False, handover_rows=want, chunk=chunk)
        np.testing.assert_array_equal(c.channel[want], a.channel[want])
        np.testing.assert_array_equal(c.sequence[want], a.sequence[want])
        assert np.isnan(c.channel[~want]).all() and np.isnan(c.sequence[~want]).all()
        np.testing.assert_array_equal(c.deviation, a.deviation)
        np.testing.assert_array_equal(c.start, b.start)
        np.testing.assert_array_equal(c.certified[~want], b.certified[~want])
        np.testing.assert_array_equal(c.certified[want], a.certified[want])
    with pytest.raises(InputError, match="handover_rows must be 16 bools"):
        defect_margins(m, U, ref, handover_rows=want[:3])


@pytest.mark.parametrize("name", ["geneva", "eccentric_cam"])
def test_margin_tables_are_the_margins_of_defect_margins(models, name):
    """:func:`margin_tables` (no verdicts; the rows without hand-overs
    evaluated lean, in chunks of their own) gives every margin of
    :func:`defect_margins` bit for bit: with every row's hand-overs, with
    none, and with some, whatever the chunks of either.  The eccentric cam's follower is force-closed (it rests on its
    bound's curve, read with ties)."""
    from synthesis.verify import box_samples
    m = models[name]
    ref = reference(m, "fast")
    n = 14
    U = box_samples(m.nominal, 1.5 * m.tol, n, seed=6)
    want = np.arange(n) % 4 == 1
    for rows in (np.ones(n, dtype=bool), np.zeros(n, dtype=bool), want):
        a = defect_margins(m, U, ref, fallback=False, handover_rows=rows)
        for chunk, lean in ((128, 256), (4, 3), (3, 128)):
            t = margin_tables(m, U, ref, rows, chunk=chunk, lean_chunk=lean)
            assert set(t) == {"channel", "sequence", "deviation", "start"}
            for kind in t:
                np.testing.assert_array_equal(t[kind], getattr(a, kind))
    t = margin_tables(m, U[:3], ref)
    assert np.isfinite(t["channel"]).all() and np.isfinite(t["sequence"]).all()
    with pytest.raises(InputError, match="handover_rows must be 3 bools"):
        margin_tables(m, U[:3], ref, [1, 0, 1])
    with pytest.raises(InputError, match="chunk"):
        margin_tables(m, U[:3], ref, chunk=0)
    with pytest.raises(InputError, match="lean_chunk must be an int >= 1"):
        margin_tables(m, U[:3], ref, lean_chunk=True)
    with pytest.raises(InputError, match="finite"):
        margin_tables(m, np.full((1, m.n), math.nan), ref)


def test_results_do_not_depend_on_the_chunks(models):
    m = models["reciprocating_cam"]
    ref = reference(m, "fast")
    rng = np.random.default_rng(4)
    U = m.nominal + m.tol * rng.choice([-1.0, 1.0], (23, m.n))
    # repeated rows and rows equal in some parameters share curve evaluations
    U = np.vstack([U, U[:5], np.where(np.arange(m.n) % 2, U[5:10], m.nominal)])
    a = defect_margins(m, U, ref, fallback=False)          # one chunk (CHUNK = 128)
    for chunk in (32, 5, 1):
        b = defect_margins(m, U, ref, fallback=False, chunk=chunk)
        for f in ("channel", "sequence", "deviation", "defective", "certified", "start"):
            np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
        assert b.stats["handover_samples"] == a.stats["handover_samples"]


def test_a_variant_is_sampled_again_where_it_alone_needs_it(models):
    """Where a candidate begins or ends between two samples, the interval is
    sampled again per variant; which intervals does not depend on the other
    variants in its chunk (on the Geneva pair it did, for 2 of 12 variants,
    when 'next sample' was read in the chunk's union of samples)."""
    from cspace.batch import margins as M
    from synthesis.verify import box_samples
    m = models["geneva"]
    ref = reference(m, "fast")
    U = box_samples(m.nominal, m.tol, 12, seed=5)
    seen = []
    real = M._handovers

    def spy(plan, cs, env, res, rows=None):
        out = real(plan, cs, env, res, rows=rows)
        if rows is None or rows[1:].any():       # not the nominal row's own (kept once)
            seen.append((env.ends[1:].copy(),
                         {v - 1: len(h[0]) for v, h in out[0].items() if v}))
        return out

    runs = []
    for chunk in (1, 12):
        seen.clear()
        M._handovers = spy
        try:
            mb = defect_margins(m, U, ref, fallback=False, chunk=chunk)
        finally:
            M._handovers = real
        ends = np.vstack([e for e, _ in seen])
        counts = {}
        for k, (_, c) in enumerate(seen):          # one pair: one call per chunk
            counts.update({k * chunk + v: n for v, n in c.items()})
        runs.append((ends, counts, mb))
    (e1, c1, a), (e12, c12, b) = runs
    np.testing.assert_array_equal(e1, e12)
    assert c1 == c12
    np.testing.assert_array_equal(a.margins(), b.margins())


def test_an_unbuildable_variant_has_no_margins(yoke_ref):
    """A vector that does not build (a pin of negative radius) is defective,
    and its margins are NaN in every form of the batch: it has no channel
    (its rows once carried the nominal's numbers, which stood in for its
    pairs)."""
    m, ref = yoke_ref
    u = m.nominal.copy()
    u[1] = -1.0
    U = np.vstack([m.nominal, u])
    mb = defect_margins(m, U, ref, fallback=False)
    assert mb.defective.tolist() == [False, True] and mb.certified.all()
    for a in (mb.channel, mb.sequence, mb.start, mb.deviation[:, None]):
        assert np.isfinite(a[0]).all() and np.isnan(a[1]).all()
    for rows in (None, [False, False]):
        tabs = margin_tables(m, U, ref, rows)
        assert np.isnan(tabs["deviation"][1]) and np.isnan(tabs["start"][1]).all()
        assert np.isfinite(tabs["deviation"][0])
        if rows is None:
            assert np.isnan(tabs["channel"][1]).all() and np.isnan(tabs["sequence"][1]).all()


def test_bad_input_is_refused(yoke_ref):
    m, ref = yoke_ref
    with pytest.raises(InputError, match=r"\(n, 3\) array"):
        defect_margins(m, np.zeros((2, 4)), ref)
    with pytest.raises(InputError, match="finite"):
        defect_margins(m, [[20.0, math.nan, 5.0]], ref)
    with pytest.raises(InputError, match="chunk"):
        defect_margins(m, [m.nominal], ref, chunk=0)
    mb = defect_margins(m, m.nominal, ref)
    assert isinstance(mb, MarginBatch) and mb.n == 1 and not mb.defective[0]
    assert "1 variants" in repr(mb)


def test_a_variant_is_assembled_where_its_channel_lies_as_in_the_full_test():
    """The stated start picks the channel.  A crank radius that moves the pin's
    channel off the stated start (by more than the clearance) does not block
    the variant: its follower starts at the nearest point of its channel, in
    the full test (``assembled_start``) and in the batch alike, so the crank
    radius causes no defect here.  The start margin still reports how far
    the stated start lies inside the channel."""
    from cspace.defects import assembled_start
    m = yoke(deviation=0.5)
    ref = reference(m, "fast")
    U = np.array([[20.02, 5.0, 5.01], [20.0, 5.0, 5.01], [20.005, 5.0, 5.01],
                  [20.012, 5.0, 5.01], [20.0, 5.02, 5.01]])
    mb = defect_margins(m, U, ref)
    full = [is_defective(m, u, ref=ref) for u in U]
    # only the last one, whose pin is wider than its slot, jams
    assert list(mb.defective) == [r.defective for r in full] == [False] * 4 + [True]
    assert mb.certified[:4].all()
    # start margin: (w - r) - |crank - R| over the pair's C-space length scale
    L = plans_of(ref)[0].scale2
    want = ((U[:4, 2] - U[:4, 1]) - np.abs(U[:4, 0] - 20.0)) / L
    np.testing.assert_allclose(mb.start[:4, 0], want, atol=1e-9)
    # the full test starts the first variant on the near face: s = R' - (w - r)
    cs0 = ref.spaces[0]
    from cspace.freespace import configuration_space
    cs = configuration_space(m.build(U[0]), "fast", window=m.window)
    # (a hair, 1e-9 of the length scale, inside)
    assert assembled_start(cs0, cs, ref.starts[0]) == pytest.approx(20.02 - 0.01, abs=1e-7)
    # a start that is free in the variant stays where it was stated
    cs = configuration_space(m.build(U[1]), "fast", window=m.window)
    assert assembled_start(cs0, cs, ref.starts[0]) == ref.starts[0][1]

def _box_batch(name, scales, seed):
    """A built-in model, its ``fast`` reference, and 6 box samples at each
    scale of its tolerances."""
    from mechanisms.models import BUILTIN
    from synthesis.verify import box_samples
    m = BUILTIN[name]()
    U = np.vstack([box_samples(m.nominal, m.tol * k, 6, seed=seed) for k in scales])
    return m, reference(m, "fast"), U


def _assert_same_margins(a, b):
    for kind in ("channel", "sequence", "deviation", "start"):
        assert np.array_equal(getattr(a, kind), getattr(b, kind), equal_nan=True), kind


def _needed_everywhere(plan, item, dmax, reach_factor):
    """The reach test of ``cspace.batch.margins._needed`` at every candidate
    sample (no pre-selection of the samples within the largest reach): the
    reference its pre-selection must reproduce."""
    import cspace.batch.margins as M
    c, side, idx, curve, st, rows, disp, dm = item
    disp, dm = st.spread(disp), st.spread(dm)      # per distinct row: per row
    V, n = len(dmax), len(idx)
    cols = np.arange(n)
    dist0, m0 = plan.distance[c, side], plan.margin0[c, side]
    mn = m0 if plan.margin_near is None else plan.margin_near[c, side]
    need = ((dist0[None, :] <= reach_factor * (M._spread_at(disp, cols) + dmax[rows, None])
             + M.ROUNDING)
            & (mn[None, :] >= -reach_factor * M._spread_at(dm, cols) - M.VALID_TOL))
    others = np.ones(V, dtype=bool)
    others[rows] = False
    other = np.nonzero(others)[0]
    need_o = ((dist0[None, :] <= reach_factor * dmax[other, None] + M.ROUNDING)
              & (m0[None, :] >= -M.VALID_TOL))
    cols = np.nonzero(need.any(axis=0) | need_o.any(axis=0))[0]
    if not len(cols):
        return None
    return idx[cols], need[:, cols], need_o[:, cols], other, cols


@pytest.mark.parametrize("name", ["geneva", "optical_filter"])
def test_reach_preselection_gives_the_same_numbers(name, monkeypatch):
    """Only the candidate samples within the largest reach of the batch are
    tested one by one: the margins are those of testing every sample, bit for
    bit (small and large moves, rows inside and outside the box)."""
    import cspace.batch.margins as M
    m, ref, U = _box_batch(name, (0.05, 1.0, 3.0), seed=4)
    got = defect_margins(m, U, ref, fallback=False)
    seen = []
    orig = M._needed

    def both(plan, item, dmax, reach_factor):
        a, b = orig(plan, item, dmax, reach_factor), _needed_everywhere(plan, item, dmax,
                                                                         reach_factor)
        seen.append(a is not None)
        assert (a is None) == (b is None)
        if a is not None:
            for x, y in zip(a, b):
                assert np.array_equal(x, y)
        return b

    monkeypatch.setattr(M, "_needed", both)
    ref2 = defect_margins(m, U, ref, fallback=False)
    assert any(seen) and not all(seen)
    _assert_same_margins(got, ref2)


def _point_values_one_by_one(plan, cs, stacks, jobs, pr, pp, pxw):
    """``cspace.batch.margins._point_values`` with a kernel call per job: the
    reference of its calls grouped by contact equation."""
    import cspace.batch.margins as M
    out = []
    for c, side, sel in jobs:
        curve, stack = cs.curves[c], stacks[c]
        if plan.periodic2:
            u, first, inv = np.unique(pp[sel], return_index=True, return_inverse=True)
            rows_ = np.concatenate([pr[sel], np.zeros(len(u), dtype=np.int64)])
            x_ = np.concatenate([pxw[sel], pxw[sel][first]])
            qq, mm = stack.take(rows_).branch(x_[:, None], curve.bi, plan.window)
            q, m, q0 = qq[:len(sel), 0], mm[:len(sel), 0], qq[len(sel):, 0]
            p0 = M.placed_on_turn(q0, M._at(plan.lo0, u), M._at(plan.hi0, u),
                                  M._at(plan.f0, u), side)
            out.append((p0[inv] + M.wrap_pi(q - q0[inv]), m, len(sel) + len(u)))
        else:
            q, m = stack.take(pr[sel]).branch(pxw[sel][:, None], curve.bi, plan.window)
            out.append((q[:, 0], m[:, 0], len(sel)))
    return out


@pytest.mark.parametrize("name", ["geneva", "reciprocating_cam"])
def test_grouped_point_evaluations_give_the_same_numbers(name, monkeypatch):
    """The hand-over points of candidates that share a contact equation are
    evaluated in one kernel call: the margins are those of a call per
    candidate, bit for bit (a rotating and a sliding follower)."""
    import cspace.batch.margins as M
    m, ref, U = _box_batch(name, (0.3, 1.0, 2.0), seed=5)
    got = defect_margins(m, U, ref, fallback=False)
    calls = []
    orig = M._point_values

    def both(plan, cs, stacks, jobs, pr, pp, pxw):
        a = orig(plan, cs, stacks, jobs, pr, pp, pxw)
        b = _point_values_one_by_one(plan, cs, stacks, jobs, pr, pp, pxw)
        calls.append(len(jobs))
        for (qa, ma, ka), (qb, mb_, kb) in zip(a, b):
            assert np.array_equal(qa, qb, equal_nan=True) and ka == kb
            assert np.array_equal(ma, mb_, equal_nan=True)
        return b

    monkeypatch.setattr(M, "_point_values", both)
    again = defect_margins(m, U, ref, fallback=False)
    assert calls and max(calls) > 1
    _assert_same_margins(got, again)


@pytest.mark.parametrize("name", ["geneva", "reciprocating_cam", "optical_filter"])
def test_grouped_curve_evaluations_give_the_same_numbers(name, monkeypatch):
    """Curves with few values to compute that share a contact equation go in
    one kernel call (rows padded to the longest): every curve's values, and
    the margins, are those of a call per curve, bit for bit, for small
    batches (where most curves are grouped) and large ones."""
    import cspace.batch.margins as M
    m, ref, U = _box_batch(name, (0.3, 1.0, 2.0), seed=7)
    grouped = []
    orig = M._unions_at

    def both(plan, asked, grouped_only=False):
        a = orig(plan, asked, grouped_only)
        for c, (st, bi, parts) in asked.items():
            if c not in a:                     # left to the caller (grouped_only)
                assert grouped_only and st.n_distinct * len(M._union(parts)) > M.GROUP_SIZE
                continue
            at, q, mg = a[c]
            want = M._alone(plan, st, bi, M._union(parts))
            assert np.array_equal(at, want[0])
            assert np.array_equal(q, want[1], equal_nan=True)
            assert np.array_equal(mg, want[2], equal_nan=True)
        grouped.append(sum(st.n_distinct * len(M._union(p)) <= M.GROUP_SIZE
                           for st, _, p in asked.values()))
        return a

    monkeypatch.setattr(M, "_unions_at", both)
    for rows in (U[:2], U):
        got = defect_margins(m, rows, ref, fallback=False)
        monkeypatch.setattr(M, "GROUP_SIZE", 0)          # every curve alone
        alone = defect_margins(m, rows, ref, fallback=False)
        monkeypatch.setattr(M, "GROUP_SIZE", 4096)
        _assert_same_margins(got, alone)
    assert max(grouped) > 5


def test_a_jam_is_placed_where_the_drive_meets_it(yoke_ref):
    """A pin wider than the slot closes the channel all along the motion: the
    batch places the jam where the drive meets it, the drive's start, as the
    full test does (not at the narrowest of equal gaps)."""
    m, ref = yoke_ref
    u = m.nominal.copy()
    u[1] = u[2] + 0.01                        # pin radius above the half width
    mb = defect_margins(m, u[None], ref, fallback=False)
    r = mb.results[0]
    assert mb.certified[0] and r.defective and r.where[:2] == (0, ref.drive[0])
    assert r.message == (f"pair 0: the channel closes at about q1 = {ref.drive[0]:.5g} "
                         f"(narrowest gap {mb.channel[0, 0]:.3g})")
    full = is_defective(m, u, ref=ref)
    assert full.where[:2] == r.where[:2]


def test_the_blocked_clamp_scan_is_the_follower_loop_bit_for_bit():
    """:func:`cspace.batch.margins._clamp_scan` (clamps composed block by
    block) gives the numbers of the loop ``f = min(max(f, lo), hi)``, with
    infinite bounds, bounds that cross (lo > hi) and infinite starts, for
    lengths that do and do not fill the last block."""
    from cspace.batch.margins import _clamp_scan
    rng = np.random.default_rng(0)
    for trial in range(120):
        V, N = int(rng.integers(1, 5)), int(rng.integers(1, 260))
        c = np.cumsum(rng.normal(size=(V, N)), axis=1)
        lo, hi = c - rng.uniform(-0.5, 2, (V, N)), c + rng.uniform(-0.5, 2, (V, N))
        u = rng.random((V, N))
        lo[u < 0.05], hi[u > 0.95] = -math.inf, math.inf
        lo[(u > 0.4) & (u < 0.42)], hi[(u > 0.5) & (u < 0.52)] = math.inf, -math.inf
        start = (float(rng.normal()), math.inf, -math.inf)[trial % 3]
        f = np.full(V, start)
        want = np.empty((V, N))
        for i in range(N):
            f = np.minimum(np.maximum(f, lo[:, i]), hi[:, i])
            want[:, i] = f
        np.testing.assert_array_equal(_clamp_scan(lo, hi, start), want)


def test_the_grid_readings_are_the_reduction_over_every_sample(models):
    """:func:`cspace.batch.margins._grid_readings` reduces the nominal's
    samples between regular ones apart and takes the deviation itself
    elsewhere: the same ``(least, most)`` as the reduction over every sample
    of full arrays (the readings there, no jump and no error elsewhere), bit
    for bit, with NaN outputs, jumps and flat stretches."""
    from cspace.batch.margins import DEV_FLOOR, _between_regular, _grid_readings, plans_of
    rng = np.random.default_rng(1)
    for name in ("geneva", "reciprocating_cam"):
        ref = reference(models[name], "fast")
        plan = plans_of(ref)[0]
        band = ref.accuracy.batch_dev_band * ref.d
        floor = DEV_FLOOR * band
        for trial in range(6):
            V = 5
            f = plan.f0[None, :] + np.cumsum(rng.normal(0, 1e-3, (V, plan.n)), axis=1)
            f[:, rng.integers(0, plan.n, 20)] += rng.normal(0, 0.5, 20)      # jumps
            if trial % 2:
                f[rng.integers(0, V), rng.integers(0, plan.n)] = np.nan
            f0 = plan.f0[None, :]
            with np.errstate(invalid="ignore"):
                dev = np.where(plan.is_ref[None, :], np.abs(f - f0), 0.0) / plan.scale2
                jump = np.zeros(f.shape, dtype=bool)
                h_lo, h_hi, err = f.copy(), f.copy(), np.zeros(f.shape)
                grid = np.nonzero(plan.on_grid)[0]
                K = np.nonzero(plan.is_ref & ~plan.on_grid)[0]
                jump[:, K], h_lo[:, K], h_hi[:, K], err[:, K] = _between_regular(
                    plan, f, band, floor, grid, K)
                d_lo = np.maximum(np.maximum(h_lo - f0, f0 - h_hi), 0.0) / plan.scale2
                d_hi = np.maximum(np.abs(h_lo - f0), np.abs(h_hi - f0)) / plan.scale2
                low = np.where(jump, d_lo - (band - floor), dev - err)
                high = np.where(jump, d_hi + (band - floor), dev + err)
                ref_ = plan.is_ref[None, :]
                least = np.max(np.where(ref_, low, -math.inf), axis=1, initial=-math.inf)
                most = np.max(np.where(ref_, high, 0.0), axis=1, initial=0.0)
                got = _grid_readings(plan, f, dev, band, floor)
            assert got is not None
            np.testing.assert_array_equal(got[0], least)
            np.testing.assert_array_equal(got[1], most)


def test_a_reference_of_another_model_is_refused(models):
    m, other = models["eccentric_cam"], models["geneva"]
    ref = reference(other, "fast")
    for call in (lambda: defect_margins(m, m.nominal, ref),
                 lambda: margin_tables(m, m.nominal, ref)):
        with pytest.raises(InputError, match="ref is the reference of another model"):
            call()


def test_the_fall_back_tests_run_on_a_process_pool(models):
    """``defect_margins(..., executor=)`` sends the Reference to the workers
    (its curve cache pickles with its entries, without its lock): the full
    test's verdicts there are this process's."""
    import pickle
    from concurrent.futures import ProcessPoolExecutor

    from cspace.batch.margins import _fallback
    from cspace.cache import CurveCache
    from synthesis.verify import box_samples
    m = models["reciprocating_cam"]
    ref = reference(m, "fast")
    back = pickle.loads(pickle.dumps(ref))
    assert isinstance(back.cache, CurveCache) and len(back.cache) == len(ref.cache) > 0
    back.cache.get_or_compute(("k",), lambda: 1)          # its own lock works
    U = box_samples(m.nominal, 1.5 * m.tol, 4, seed=3)
    here = _fallback(m, U, ref)
    with ProcessPoolExecutor(2) as ex:
        there = _fallback(m, U, ref, ex)
        mb = defect_margins(m, U, ref, executor=ex)
    assert [r.defective for r in there] == [r.defective for r in here]
    assert [r.reasons for r in there] == [r.reasons for r in here]
    assert len(mb.defective) == 4


def test_rows_may_be_mappings_as_for_the_full_test():
    """``defect_margins`` takes ``{name: value}`` rows (one, or a list mixed
    with vectors), as ``is_defective`` does; a non-numeric row is an
    InputError that says what U must be."""
    from mechanisms.models import reciprocating_cam
    m = reciprocating_cam()
    ref = reference(m, "fast")
    u = m.vector({"tip_r": m.nominal[m.names.index("tip_r")] + 0.01})
    a = defect_margins(m, [{"tip_r": float(u[m.names.index("tip_r")])}, m.nominal], ref)
    b = defect_margins(m, np.vstack([u, m.nominal]), ref)
    assert np.array_equal(a.margins(), b.margins(), equal_nan=True)
    assert defect_margins(m, {"tip_r": float(u[m.names.index("tip_r")])}, ref).n == 1
    with pytest.raises(InputError, match="mappings"):
        defect_margins(m, [["a"] * m.n], ref)


def test_a_sequence_defect_says_where_and_which_contacts():
    """Geneva variants (box samples at 1.5 times the tolerances) whose contact
    sequence the batch finds surely changed: the result names where (about
    the full test's driver value, the same side of the follower) and the
    contact that stands out against the nominal's; it named neither."""
    from mechanisms.models import geneva
    from synthesis.verify import box_samples
    m = geneva()
    ref = reference(m, "fast")
    U = box_samples(m.nominal, 1.5 * m.tol, 150, seed=2)[[14, 63, 98, 140]]
    mb = defect_margins(m, U, ref)
    near = 0
    for u, r, cert in zip(U, mb.results, mb.certified):
        assert cert and r.defective and "contact sequence" in r.message, r.message
        assert "changed at about q1 = " in r.message and "where the nominal's is" in r.message
        assert math.isfinite(r.where[1])
        full = is_defective(m, u, ref=ref)
        side = "below" if "(below the follower" in r.message else "above"
        if full.where is not None and abs(full.where[1] - r.where[1]) < 0.3:
            near += 1
            assert f"({side} the follower" in full.message
    assert near >= 3
