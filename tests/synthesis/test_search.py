"""Transition points from margins (issue 22, "Minimal shifts from margins"): the
margin search brackets the same transition point as bisection, to the same
eps, with fewer defect tests; an unknown or contradicting margin falls back to
bisection; the command line and the checkpoint carry the choice."""

import json

import numpy as np
import pytest

from cspace.errors import FileFormatError, InputError
from mechanisms.models import reciprocating_cam
from synthesis import synthesize
from synthesis.checkpoint import checkpoint_text
from synthesis.cli import main
from synthesis.executors import SerialExecutor
from synthesis.removal import plan_with_refinement, transition_points
from synthesis.result import SynthesisState


def _oracle(root, scale=1.0, curve=0.0, margins=True):
    """Defective beyond ``root`` on every segment (fraction of u0 -> u_w along the
    first axis); margin ``scale * (root - t) * (1 + curve * t)``."""
    calls = []

    def f(us):
        calls.append(len(us))
        out = []
        for u in us:
            t = float(u[0])
            m = scale * (root - t) * (1.0 + curve * t)
            out.append((t >= root, m) if margins else t >= root)
        return out
    return f, calls


@pytest.mark.parametrize("root", [0.13, 0.5, 0.77, 0.999])
@pytest.mark.parametrize("curve", [0.0, 2.0, -0.6])
def test_margin_search_brackets_the_same_point_with_fewer_tests(root, curve):
    u0, uw = np.zeros(2), np.array([1.0, 0.5])
    eps = 1e-3
    f, calls_b = _oracle(root, curve=curve)
    (b,) = transition_points(u0, [uw], f, eps, method="bisect")
    g, calls_m = _oracle(root, curve=curve)
    m_end = (root * (1.0), (root - 1.0) * (1.0 + curve))
    (m,) = transition_points(u0, [uw], g, eps, method="margin", end_margins=[m_end])
    for tr in (b, m):
        assert tr.lam[0] < root <= tr.lam[1]
        assert (tr.lam[1] - tr.lam[0]) * 1.0 < eps
    assert sum(calls_m) < sum(calls_b)
    assert sum(calls_m) <= 0.6 * sum(calls_b)


def test_without_margins_the_margin_search_bisects():
    u0, uw = np.zeros(1), np.ones(1)
    f, _ = _oracle(0.3, margins=False)
    g, _ = _oracle(0.3, margins=False)
    (a,) = transition_points(u0, [uw], f, 1e-3, method="bisect")
    (b,) = transition_points(u0, [uw], g, 1e-3, method="margin")
    assert a.lam == b.lam and a.steps == b.steps


def test_a_margin_that_contradicts_its_verdict_is_not_used():
    # the full test decided against the batch's margin: sign disagrees
    u0, uw = np.zeros(1), np.ones(1)

    def f(us):
        return [(float(u[0]) >= 0.4, 1.0) for u in us]     # always "healthy" margins
    (tr,) = transition_points(u0, [uw], f, 1e-3, method="margin", end_margins=[(1.0, 1.0)])
    assert tr.lam[0] < 0.4 <= tr.lam[1] and tr.lam[1] - tr.lam[0] < 1e-3


def test_refinement_in_steps_equals_one_search():
    u0, uw = np.zeros(1), np.ones(1)
    f, _ = _oracle(0.6180339, curve=1.5)
    ends = [(0.6180339, (0.6180339 - 1) * 2.5)]
    (whole,) = transition_points(u0, [uw], f, 1e-4, method="margin", end_margins=ends)
    g, _ = _oracle(0.6180339, curve=1.5)
    (tr,) = transition_points(u0, [uw], g, 1e-4, method="margin", end_margins=ends,
                              max_steps=1)
    while (tr.lam[1] - tr.lam[0]) >= 1e-4:
        (tr,) = transition_points(u0, [uw], g, 1e-4, method="margin", start=[tr],
                                  max_steps=1)
    assert tr.lam == whole.lam and tr.steps == whole.steps


def test_plan_with_refinement_accepts_margins():
    u0, tol = np.zeros(2), np.ones(2)
    f, calls = _oracle(0.5)
    plan, trs = plan_with_refinement(u0, tol, [np.array([1.0, 1.0])], f, 1e-3,
                                     method="margin", end_margins=[(0.5, -0.5)])
    assert trs[0].lam[0] < 0.5 <= trs[0].lam[1] and plan.progress
    with pytest.raises(InputError, match="search method"):
        transition_points(u0, [np.ones(2)], f, 1e-3, method="newton")


def test_synthesis_with_margins_needs_fewer_tests_and_converges():
    m = reciprocating_cam()
    # the paper's removal searches every defective vector (the LP removal
    # searches only those without a continuous margin: none on this cam)
    b = synthesize(m, "fast", executor=SerialExecutor(), max_iter=10, search="bisect",
                   removal="greedy")
    g = synthesize(m, "fast", executor=SerialExecutor(), max_iter=10, search="margin",
                   removal="greedy")
    assert b.success and g.success
    assert sum(h.tests for h in g.history) < sum(h.tests for h in b.history)
    assert g.defects_per_iteration()[0] == b.defects_per_iteration()[0]
    assert g.to_dict()["search"] == "margin" and b.to_dict()["search"] == "bisect"


def test_the_search_is_kept_by_the_checkpoint(tmp_path, capsys):
    m = reciprocating_cam()
    st = SynthesisState(m.name, tuple(m.names), m.nominal, m.tol, m.nominal, m.tol,
                        {"name": "fast"}, 0.1, search="margin")
    doc = json.loads(checkpoint_text(st))
    assert SynthesisState.from_dict(doc).search == "margin"
    doc.pop("search")
    doc.pop("sha256")
    assert SynthesisState.from_dict(doc).search == "bisect"     # older checkpoints bisected
    doc["search"] = "golden"
    with pytest.raises(FileFormatError, match="search must be"):
        SynthesisState.from_dict(doc)
    out = tmp_path / "o"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--executor", "serial", "--no-plots", "--max-iter", "1",
                 "--search", "bisect"]) == 1
    assert json.loads((out / "checkpoint.json").read_text())["search"] == "bisect"
    assert main(["synthesize", "reciprocating_cam", "--out", str(out), "--resume",
                 "--search", "margin", "--no-plots"]) == 2
    assert "search" in capsys.readouterr().err
