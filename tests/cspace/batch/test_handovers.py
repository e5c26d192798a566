"""The helpers that sample a variant's hand-overs again (``margins._handovers``):
ties, subdivision of sample intervals, undecided runs."""

import numpy as np

from cspace.batch.margins import _subdivide, _undecided, _untie


def _untie_by_rule(ids, tie):
    """The rule, sample by sample: a tied sample continues the run before it,
    or else the one after it, when that sample is not tied itself."""
    ids = ids.copy()
    V, N = ids.shape
    for v in range(V):
        src = ids[v].copy()
        for i in range(N):
            if tie[v, i]:
                if i > 0 and not tie[v, i - 1]:
                    ids[v, i] = src[i - 1]
                elif i + 1 < N and not tie[v, i + 1]:
                    ids[v, i] = src[i + 1]
    return ids


def test_untie_follows_the_rule():
    rng = np.random.default_rng(3)
    for _ in range(500):
        V, N = int(rng.integers(1, 4)), int(rng.integers(1, 12))
        ids = rng.integers(0, 5, (V, N))
        tie = rng.random((V, N)) < rng.random()
        got = ids.copy()
        _untie(got, tie)
        np.testing.assert_array_equal(got, _untie_by_rule(ids, tie))
        # int32 ids, as the bounds keep them: the compiled loop where numba is
        got32 = ids.astype(np.int32)
        _untie(got32, tie)
        np.testing.assert_array_equal(got32, _untie_by_rule(ids, tie))


def test_subdivide_splits_each_interval_into_pieces_no_longer_than_fine():
    rows = np.array([0, 2, 2])
    a = np.array([3.0, 7.0, 10.5])          # start positions (plan samples)
    wpos = np.array([1.0, 1.0, 0.5])        # widths in plan positions
    wx = np.array([0.005, 0.0004, 0.001])   # widths in driver motion
    pr, pp, capped = _subdivide(rows, a, wpos, wx, 0.00048)
    assert capped == set()
    for r, s, w, x in zip(rows, a, wpos, wx):
        inner = pp[(pr == r) & (pp > s) & (pp < s + w)]
        k = len(inner) + 1                  # pieces
        assert k == max(int(np.ceil(x / 0.00048)), 1)
        edges = np.concatenate([[s], inner, [s + w]])
        np.testing.assert_allclose(np.diff(edges), w / k)
    assert len(pp) == 10 + 0 + 2


def test_subdivide_caps_the_pieces_and_names_the_rows():
    """A resolution far finer than the samples (a tiny d) asks for 1e9 pieces
    of an interval: it gets ``cap``, and its row is named."""
    rows = np.array([0, 1, 1])
    a = np.array([3.0, 7.0, 10.0])
    wpos = np.ones(3)
    wx = np.array([0.005, 0.0004, 0.005])
    pr, pp, capped = _subdivide(rows, a, wpos, wx, 5e-12, cap=16)
    assert capped == {0, 1}
    assert len(pp) == 3 * 15
    pr, pp, capped = _subdivide(rows, a, wpos, wx, 0.00048, cap=16)
    assert capped == set() and len(pp) == 10 + 0 + 10


def test_a_tiny_deviation_threshold_leaves_the_verdicts_to_the_full_test():
    """d = 1e-9 rad asked the plan for 2.5e9 extra samples a side of every
    release point of the Geneva pair, and the hand-over sampling for 1e9 per
    sample interval (allocations of tens of GiB); now both are capped, the
    plan says it is not resolved, and the batch certifies nothing: the full
    test decides."""
    import time

    from cspace.batch.margins import defect_margins, plans_of
    from cspace.defects import is_defective, reference
    from mechanisms.models import geneva
    m = geneva()
    ref = reference(m, "fast", d=1e-9)
    assert not plans_of(ref)[0].resolved
    U = np.array([m.nominal + 0.25 * m.tol])
    t = time.perf_counter()
    mb = defect_margins(m, U, ref, fallback=False)
    assert time.perf_counter() - t < 120
    assert not mb.certified.any()
    full = defect_margins(m, U, ref)
    assert full.n_fallback == 1
    assert bool(full.defective[0]) == is_defective(m, U[0], ref=ref).defective
    assert plans_of(reference(m, "fast"))[0].resolved


def test_undecided_runs_are_those_the_samples_cannot_place():
    x = np.array([0.0, 1.0, 2.0, 2.5, 3.0, 4.0, 5.0])
    ids = np.array([1, 1, 1, 2, 3, 3, 3])
    # run "2" lasts between 0 (one sample) and 1.0 (2.0 .. 3.0): undecided
    # against 0.8, surely shorter than 1.5, and run "3" surely longer
    assert _undecided(ids, x, 0.8) == [2, 3]
    assert _undecided(ids, x, 1.5) == []


def test_point_jobs_look_only_where_a_candidate_has_samples():
    """:func:`_point_jobs` looks at the points within each candidate's stretch
    of samples only: the same jobs, in the same order, as a scan of every
    point for every candidate."""
    from types import SimpleNamespace

    from cspace.batch.margins import _point_jobs
    rng = np.random.default_rng(8)
    N, V, P = 400, 5, 300
    plan = SimpleNamespace(n=N)
    needed = {}
    for c in range(40):
        a = int(rng.integers(0, N - 2))
        idx = np.unique(rng.integers(a, min(N, a + int(rng.integers(1, 120))), 30))
        needed[c, 1 - 2 * (c % 2)] = (idx, rng.random((V, len(idx))) < 0.7)
    needed[99, 1] = (np.zeros(0, dtype=np.int64), np.zeros((V, 0), dtype=bool))
    pr = rng.integers(0, V, P)
    pi = rng.integers(0, N - 1, P)

    def scan():
        out = []
        for (c, side), (idx, nd) in needed.items():
            col = np.full(N + 1, -1)
            col[idx] = np.arange(len(idx))
            a, b = col[pi], col[pi + 1]
            if not ((a >= 0) | (b >= 0)).any():
                continue
            ok = (((a >= 0) & nd[pr, np.maximum(a, 0)]) | ((b >= 0) & nd[pr, np.maximum(b, 0)]))
            if ok.any():
                out.append((c, side, np.nonzero(ok)[0]))
        return out

    got, want = _point_jobs(plan, needed, pr, pi), scan()
    assert len(got) == len(want) > 10
    for (c, s, sel), (c2, s2, sel2) in zip(got, want):
        assert (c, s) == (c2, s2)
        np.testing.assert_array_equal(sel, sel2)

    # a curve key left out at some points: those points leave its jobs, and
    # a job left with none is dropped
    plan.key = np.arange(100) % 7
    skip = rng.integers(0, 7, P)
    got = _point_jobs(plan, needed, pr, pi, skip)
    want = [(c, s, sel[skip[sel] != plan.key[c]]) for c, s, sel in scan()]
    want = [w for w in want if len(w[2])]
    assert len(got) == len(want) > 10
    for (c, s, sel), (c2, s2, sel2) in zip(got, want):
        assert (c, s) == (c2, s2)
        np.testing.assert_array_equal(sel, sel2)


def _born_across_flip_by_flip(plan, cs, env, f, gap):
    """``margins._born_across`` as it was first written: each flip's points
    in a pass of their own over the candidates of the other curves."""
    from cspace.batch.margins import _born_far, _bounds_at, _held_by_other
    out = np.zeros(f.shape[0], dtype=bool)
    g = gap * plan.scale2
    for side, key, r, i, qa, qb, born in env.flips:
        fi, far = _born_far(env, f, g, side, r, i, qa, qb)
        sel = np.nonzero(born & far & ~out[r])[0]
        if not len(sel):
            continue
        others = {k: v for k, v in env.needed.items() if plan.key[k[0]] != key}
        rr, pp = r[sel], (i[sel] + 1).astype(float)
        lo_o, hi_o = _bounds_at(plan, cs, env.stacks, others, rr, pp)[6:8]
        out[rr[_held_by_other(side, lo_o, hi_o, fi[sel], qb[sel], g)]] = True
    return out


def test_contacts_born_across_are_found_in_one_pass(models, monkeypatch):
    """Every flip's points go through one pass over the candidates, each
    without its own curve: the variants found are those of a pass per flip
    (Geneva, box samples three tolerances wide, some of which have such a
    contact)."""
    import cspace.batch.margins as bm
    from cspace.defects import reference
    from synthesis.verify import box_samples
    m = models["geneva"]
    ref = reference(m, "fast")
    real = bm._born_across
    found = []

    def both(plan, cs, env, f, gap):
        got = real(plan, cs, env, f, gap)
        np.testing.assert_array_equal(got, _born_across_flip_by_flip(plan, cs, env, f, gap))
        found.append(int(got.sum()))
        return got

    monkeypatch.setattr(bm, "_born_across", both)
    bm.defect_margins(m, box_samples(m.nominal, 3 * m.tol, 150, seed=3), ref, fallback=False)
    assert found and sum(found) > 0
