"""The compiled bookkeeping of the channel bounds (:mod:`cspace.batch.fused_bounds`)
against the numpy code of :mod:`cspace.batch.margins` it stands in for: the
same numbers, bit for bit."""

from types import SimpleNamespace

import numpy as np
import pytest

from cspace.batch import fused, fused_bounds
from cspace.batch import margins as M
from cspace.batch.margins import defect_margins, margin_tables
from cspace.defects import reference
from synthesis.verify import box_samples

pytestmark = pytest.mark.skipif(not fused.AVAILABLE, reason="numba not available")


def _same(a, b) -> bool:
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


def _both(monkeypatch, f):
    out = []
    for flag in (True, False):
        monkeypatch.setattr(fused_bounds, "enabled", lambda flag=flag: flag)
        out.append(f())
    return out


@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam"])
def test_margins_and_verdicts_are_the_same(models, monkeypatch, name):
    """Box samples (a fifth beyond the box, so that some are defective) of a
    turning follower with turning bounds (Geneva, optical filter) and a
    sliding one (reciprocating cam): every margin, verdict and count of
    :func:`defect_margins`, and the lean tables of :func:`margin_tables`."""
    m = models[name]
    ref = reference(m, "fast")
    U = box_samples(m.nominal, 1.2 * m.tol, 16, seed=3)

    def run():
        mb = defect_margins(m, U, ref, fallback=False)
        tabs = margin_tables(m, U[:8], ref, np.arange(8) % 2 == 0)
        return mb, tabs

    (a, ta), (b, tb) = _both(monkeypatch, run)
    for k in ("channel", "sequence", "deviation", "start", "defective", "certified"):
        assert _same(getattr(a, k), getattr(b, k)), k
    assert a.stats == b.stats
    assert ta.keys() == tb.keys()
    for k in ta:
        assert _same(ta[k], tb[k]), k


class _Shared:
    """A curve's distinct rows as :class:`cspace.batch.margins._Distinct`
    keeps them: row i of the curve's rows reads distinct row ``inv[i]``."""

    def __init__(self, inv):
        self.inv = np.asarray(inv)

    def spread(self, v):
        return v[self.inv]


def _fake(rng, V, N, periodic2):
    plan = SimpleNamespace(periodic2=periodic2, window=(0.0, 1.0, -2.0, 2.0),
                           key={7: 3}, place={(7, 1): rng.normal(size=N),
                                              (7, -1): rng.normal(size=N)})
    return plan


@pytest.mark.parametrize("periodic2", [True, False])
@pytest.mark.parametrize("side", [1, -1])
@pytest.mark.parametrize("lean", [True, False])
def test_accumulate_on_random_values_with_nans(periodic2, side, lean, monkeypatch):
    """Random values (some NaN, some beyond a turn), needs and validity, a
    candidate moved by some rows (two of which share their values: one
    distinct row) and seen by the others, added on top of earlier bounds:
    bounds, runners-up, ids, flips and needs the same."""
    rng = np.random.default_rng(5)
    V, N = 9, 40
    plan = _fake(rng, V, N, periodic2)
    rows = np.array([0, 2, 3, 7])
    other = np.setdiff1d(np.arange(V), rows)
    idx = np.sort(rng.choice(N, 25, replace=False))
    cols = idx.copy()
    K = len(idx)
    st = _Shared([0, 1, 2, 1])
    q = rng.normal(scale=4.0, size=(3, K))
    q[rng.random(q.shape) < 0.1] = np.nan
    m = rng.normal(size=(3, K))
    m[rng.random(m.shape) < 0.05] = np.nan
    need = rng.random((len(rows), K)) < 0.8
    need_o = rng.random((len(other), K)) < 0.8
    item = (7, side, idx, None, st, rows, None, None)
    sel = (idx, need, need_o, other, cols)
    # earlier bounds to compare with; where the follower does not turn, some
    # values tie with them (a tie keeps the earlier curve)
    lo0 = rng.normal(size=(V, N)) - 1.0
    hi0 = rng.normal(size=(V, N)) + 1.0
    if not periodic2:
        tie = rng.random(q.shape) < 0.2
        r_, k_ = np.nonzero(tie)
        q[r_, k_] = (lo0 if side > 0 else hi0)[rows[r_], idx[k_]]
        m[r_, k_] = 1.0
    # the values each row reads differ where its need does
    assert not np.array_equal(need[1], need[3])

    def run():
        acc = M._Bounds(plan, V, N, runners_up=not lean)
        acc.lo[:], acc.hi[:] = lo0, hi0
        acc.lo_id[:], acc.hi_id[:] = 1, 2
        M._accumulate(plan, acc, item, sel, q, m, lean)
        return acc

    out = []
    for flag in (True, False):
        monkeypatch.setattr(fused_bounds, "enabled", lambda flag=flag: flag)
        out.append(run())
    a, b = out
    for k in ("lo", "hi", "lo_id", "hi_id", "lo2", "hi2"):
        assert _same(getattr(a, k) if getattr(a, k) is not None else 0,
                     getattr(b, k) if getattr(b, k) is not None else 0), k
    assert len(a.flips) == len(b.flips)
    for fa, fb in zip(a.flips, b.flips):
        assert all(_same(x, y) for x, y in zip(fa, fb))
    assert a.needed.keys() == b.needed.keys()
    for k in a.needed:
        assert _same(a.needed[k][0], b.needed[k][0]) and _same(a.needed[k][1], b.needed[k][1])


def test_needs_on_random_reaches_with_nans(monkeypatch):
    """:func:`cspace.batch.margins._needed` with random distances, margins and
    reaches (NaN among them): the same samples and needs."""
    rng = np.random.default_rng(8)
    V, n = 12, 70
    nc = -(-n // M._STRIDE)
    rows = np.array([0, 1, 4, 5, 9])
    dist0 = np.abs(rng.normal(size=n))
    m0 = rng.normal(scale=0.1, size=n)
    plan = SimpleNamespace(distance={(3, 1): dist0}, margin0={(3, 1): m0},
                           margin_near={(3, 1): m0 - 0.05})
    st = _Shared([0, 1, 2, 3, 1])          # rows 1 and 4 of the curve share theirs
    disp = np.abs(rng.normal(scale=0.3, size=(4, nc)))
    dm = np.abs(rng.normal(scale=0.1, size=(4, nc)))
    dmax = np.abs(rng.normal(scale=0.3, size=V))
    dm[1, 2] = np.nan
    disp[2, 3] = np.nan
    idx = np.arange(100, 100 + n)
    item = (3, 1, idx, None, st, rows, disp, dm)
    a, b = _both(monkeypatch, lambda: M._needed(plan, item, dmax, 2.0))
    assert a is not None and b is not None
    for x, y in zip(a, b):
        assert _same(x, y)
    # none within reach
    far = SimpleNamespace(distance={(3, 1): dist0 + 100.0}, margin0={(3, 1): m0},
                          margin_near=None)
    a, b = _both(monkeypatch, lambda: M._needed(far, item, np.zeros(V), 2.0))
    assert a is None and b is None


def test_warm_up_runs():
    fused_bounds.warm_up()
    assert fused_bounds.enabled() == fused.ENABLED


def test_kernel_values_are_counted_per_path(models, monkeypatch):
    """:data:`cspace.batch.kernels.KERNEL_VALUES`: the Geneva pair (a turning
    driver and follower) runs the fused kernel for every curve value, the
    reciprocating cam (a sliding follower) the numpy code; with the fused
    loops off, the Geneva pair's values go to numpy too."""
    from cspace.batch.kernels import KERNEL_VALUES, reset_kernel_values
    got = {}
    for name in ("geneva", "reciprocating_cam"):
        m = models[name]
        ref = reference(m, "fast")
        U = box_samples(m.nominal, m.tol, 3, seed=1)
        reset_kernel_values()
        defect_margins(m, U, ref, fallback=False)
        got[name] = reset_kernel_values()
    assert got["geneva"]["fused"] > 0 and got["geneva"]["numpy"] == 0
    assert got["reciprocating_cam"]["numpy"] > 0 and got["reciprocating_cam"]["fused"] == 0
    monkeypatch.setattr(fused, "ENABLED", False)
    m = models["geneva"]
    defect_margins(m, box_samples(m.nominal, m.tol, 3, seed=1), reference(m, "fast"),
                   fallback=False)
    assert KERNEL_VALUES["fused"] == 0 and KERNEL_VALUES["numpy"] > 0


def test_clamp_scan_is_the_array_form_bit_for_bit():
    """The compiled follower of a form-closed pair against
    :func:`cspace.batch.margins._clamp_scan` (array operations): random
    bounds with infinities and crossed bounds (lo > hi), several lengths (the
    array form cuts the samples into blocks)."""
    rng = np.random.default_rng(11)
    for N in (1, 2, 7, 64, 1001):
        lo = rng.normal(size=(5, N))
        hi = lo + rng.normal(scale=0.5, size=(5, N))        # crossed where < lo
        lo[rng.random(lo.shape) < 0.1] = -np.inf
        hi[rng.random(hi.shape) < 0.1] = np.inf
        for start in (0.0, 3.0, -np.inf):
            a = fused_bounds.clamp_scan(lo, hi, start)
            b = M._clamp_scan(lo, hi, start)
            assert _same(a, b), N
