"""The compiled batched kernel against the numpy reference it follows."""

import numpy as np
import pytest

from cspace.batch import compiled

from .stacks import model_stacks
from .subproc import batch_in_subprocess
from .test_roller import roller
from .yoke import yoke

pytestmark = pytest.mark.skipif(not compiled.AVAILABLE, reason="numba not available")


def _cases(models):
    return [models["geneva"], models["optical_filter"], models["reciprocating_cam"], yoke(),
            roller(a=0.3)]


def _same(a, b):
    """Equal to rounding, NaN where the other is NaN."""
    assert np.array_equal(np.isnan(a), np.isnan(b))
    fin = np.isfinite(a)
    np.testing.assert_allclose(a[fin], b[fin], rtol=0, atol=1e-12)


def test_every_curve_matches_numpy_on_a_grid(models):
    """Every contact curve of five designs (rotating and sliding followers,
    point-line and point-circle equations, both owners), 13 variants each, at
    200 driver values with and without the follower window: the values and
    validity margins equal numpy's to 1e-12."""
    checked = 0
    for m in _cases(models):
        for plan, c, st in model_stacks(m, n=12, spread=3.0):
            x = np.linspace(plan.window[0] - 0.3, plan.window[1] + 0.3, 200)
            for win in (None, plan.window):
                qa, ma = st.branch_numpy(x, c.bi, win)
                qb, mb = compiled.branch(st, x, c.bi, win)
                _same(qa[st.ok], qb[st.ok])
                _same(ma[st.ok], mb[st.ok])
                checked += 1
    assert checked > 300


def test_one_value_per_variant_matches_numpy(models):
    """The (V, 1) form (one driver value per variant, as the hand-over search
    calls it) equals numpy's."""
    rng = np.random.default_rng(0)
    for m in (models["geneva"], yoke()):
        for plan, c, st in model_stacks(m, n=20, spread=3.0):
            q1 = rng.uniform(plan.window[0], plan.window[1], (len(st.ok), 1))
            qa, ma = st.branch_numpy(q1, c.bi, plan.window)
            qb, mb = compiled.branch(st, q1, c.bi, plan.window)
            assert qb.shape == (len(st.ok), 1)
            _same(qa[st.ok], qb[st.ok])
            _same(ma[st.ok], mb[st.ok])


def test_branch_dispatches_to_the_compiled_loop(models, monkeypatch):
    """KernelStack.branch runs the compiled loop when it is enabled (off by
    default: ``CSPACE_NUMBA=1`` turns it on)."""
    monkeypatch.setattr(compiled, "ENABLED", True)
    plan, c, st = next(iter(model_stacks(models["geneva"], n=2, spread=3.0)))
    x = np.linspace(0.0, 1.0, 5)
    qa, ma = st.branch(x, c.bi, plan.window)
    qb, mb = compiled.branch(st, x, c.bi, plan.window)
    assert np.array_equal(qa, qb, equal_nan=True) and np.array_equal(ma, mb, equal_nan=True)


def test_verdicts_do_not_depend_on_the_kernel():
    """The batched verdicts, certifications and margins of 60 Monte Carlo
    samples of the cam are the same with the compiled kernel and with numpy
    (``CSPACE_NUMBA=0``); the margins to 1e-10."""
    out = {flag: batch_in_subprocess("compiled", "reciprocating_cam", 60,
                                     {"CSPACE_NUMBA": flag})
           for flag in ("1", "0")}
    assert out["1"]["enabled"] and not out["0"]["enabled"]
    assert out["1"]["defective"] == out["0"]["defective"]
    assert out["1"]["certified"] == out["0"]["certified"]
    a, b = np.array(out["1"]["margins"], float), np.array(out["0"]["margins"], float)
    assert np.array_equal(np.isnan(a), np.isnan(b))
    np.testing.assert_allclose(a[np.isfinite(a)], b[np.isfinite(b)], rtol=0, atol=1e-10)
