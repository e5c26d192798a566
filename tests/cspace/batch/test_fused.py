"""The fused batched kernel (:mod:`cspace.batch.fused`) against the numpy code
it follows operation for operation: the same numbers, bit for bit (NaN
where the other is NaN)."""

import math
import zlib

import numpy as np
import pytest

from cspace.batch import fused
from cspace.batch.kernels import KernelStack
from cspace.equations import Equation

from .stacks import model_stacks
from .subproc import batch_in_subprocess

pytestmark = pytest.mark.skipif(not fused.AVAILABLE, reason="numba not available")


def _same(a, b) -> bool:
    return np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("name", ["geneva", "optical_filter"])
def test_every_covered_curve_of_the_models_gives_the_same_bits(models, name):
    """A driver value per sample (past the window's ends too), per variant and
    sample (a grouped call), and one per variant (a hand-over point)."""
    rng = np.random.default_rng(1)
    covered = 0
    for plan, c, st in model_stacks(models[name]):
        if not fused.supports(st):
            continue
        covered += 1
        V = len(st.ok)
        x = np.linspace(plan.window[0] - 1.0, plan.window[1] + 1.0, 97)
        X = x[None, :] + rng.uniform(-0.1, 0.1, (V, len(x)))
        for q1 in (x, X, X[:, :1]):
            a, b = fused.branch(st, q1, c.bi), st.branch_numpy(q1, c.bi, plan.window)
            assert _same(a[0], b[0]) and _same(a[1], b[1]), (c.features, q1.shape)
    assert covered >= 100


def _random_stack(rng, eq, owner, fp_kind, concave, V=16):
    ft_kind = "arc" if eq == Equation.POINT_CIRCLE else "line"

    def rows(kind, convex):
        f = np.zeros((V, 13))
        f[:, 0:4] = rng.uniform(-30, 30, (V, 4))
        f[:, 4] = rng.uniform(0.5, 8, V)
        f[:, 5] = 1.0 if convex else 0.0
        f[:, 6] = rng.uniform(-4, 4, V)
        f[:, 7] = rng.choice([0.3, 1.2, math.pi, 2.5], V)
        e = rng.uniform(0, 2 * math.pi, (V, 2))
        f[:, 8:10] = np.c_[np.cos(e[:, 0]), np.sin(e[:, 0])]
        f[:, 10:12] = np.c_[np.cos(e[:, 1]), np.sin(e[:, 1])]
        f[:, 12] = {"vertex": 0.0, "line": 1.0, "arc": 2.0}[kind]
        return f

    fp = rows(fp_kind, not concave)
    ft = rows(ft_kind, bool(rng.integers(2)))
    r = rng.uniform(0.1, 10, (V, 1))
    r[0] = 0.0
    return KernelStack(eq, owner, (True, True), np.ones(V, dtype=bool), r, fp, ft, fp_kind,
                       ft_kind, rng.uniform(-20, 20, (V, 2)), rng.uniform(-20, 20, (V, 2)),
                       rng.uniform(5, 40, (V, 1)))


@pytest.mark.parametrize("eq", [Equation.POINT_CIRCLE, Equation.POINT_LINE])
@pytest.mark.parametrize("owner", [0, 1])
@pytest.mark.parametrize("fp_kind,concave", [("vertex", False), ("arc", False), ("arc", True)])
def test_random_stacks_give_the_same_bits(eq, owner, fp_kind, concave):
    """Random constants of every covered equation, both branches, with a
    degenerate row (a zero radius), values outside every range, and a NaN
    driver value."""
    rng = np.random.default_rng(zlib.crc32(f"{eq.value} {owner} {fp_kind} {concave}".encode()))
    st = _random_stack(rng, eq, owner, fp_kind, concave)
    assert fused.supports(st)
    x = np.r_[np.linspace(-20.0, 20.0, 201), math.nan, 1e6]
    X = rng.uniform(-10, 10, (len(st.ok), 50))
    for bi in (0, 1):
        for q1 in (x, X, X[:, :1]):
            with np.errstate(all="ignore"):
                a, b = fused.branch(st, q1, bi), st.branch_numpy(q1, bi)
            assert _same(a[0], b[0]) and _same(a[1], b[1])


def test_a_sliding_part_runs_the_numpy_code(models):
    """The reciprocating cam's follower slides: not covered; branch runs
    branch_numpy (the same arrays)."""
    for plan, c, st in model_stacks(models["reciprocating_cam"], n=3):
        assert not fused.supports(st)
        x = np.linspace(0.0, 1.0, 7)
        a, b = st.branch(x, c.bi, plan.window), st.branch_numpy(x, c.bi, plan.window)
        assert _same(a[0], b[0]) and _same(a[1], b[1])


def test_branch_dispatches_to_the_fused_loops(models, monkeypatch):
    plan, c, st = next(s for s in model_stacks(models["geneva"], n=2) if fused.supports(s[2]))
    calls = []
    real = fused.branch
    monkeypatch.setattr(fused, "branch", lambda *a: calls.append(1) or real(*a))
    st.branch(np.linspace(0.0, 1.0, 5), c.bi, plan.window)
    assert calls == [1]
    monkeypatch.setattr(fused, "ENABLED", False)
    st.branch(np.linspace(0.0, 1.0, 5), c.bi, plan.window)
    assert calls == [1]


def test_margins_are_the_same_with_the_numpy_code():
    """24 box samples of the Geneva pair: verdicts, certifications and every
    margin the same bits with the fused loops and with ``CSPACE_FUSED=0``."""
    out = {flag: batch_in_subprocess("fused", "geneva", 24, {"CSPACE_FUSED": flag})
           for flag in ("1", "0")}
    assert out["1"]["enabled"] and not out["0"]["enabled"]
    for k in ("defective", "certified"):
        assert out["1"][k] == out["0"][k]
    a, b = np.array(out["1"]["margins"], float), np.array(out["0"]["margins"], float)
    assert _same(a, b)
