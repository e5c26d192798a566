"""A box reaching values the builder refuses.

The zones evaluate only variants that build, so no zone extreme (and no
check-list vector) lies where the geometry cannot be made.  The Scotch yoke
below refuses a pin radius above 5.01 mm while its box reaches 5.02: without
the ends of every parameter's range in the check list, the run converged at
once with a third of the parts invalid."""

import dataclasses

import numpy as np

from mechanisms.analysis import unbuildable_tolerances
from synthesis import SerialExecutor, monte_carlo, synthesize
from synthesis.checklist import CheckList
from synthesis.loop import with_unbuildable_ends
from synthesis.result import SynthesisStatus

from ..cspace.batch.yoke import build_yoke, yoke

LIMIT = 5.01


def refusing(v):
    if v["pin_r"] > LIMIT:
        raise ValueError(f"pin radius {v['pin_r']} above {LIMIT}")
    return build_yoke(v)


def refusing_yoke():
    return dataclasses.replace(yoke(deviation=1.0), builder=refusing)


def _empty_list():
    return CheckList(vectors=(), n_seeds=0, n_seeds_kept=0, n_combined=0, n_added=0,
                     radius=0.0)


def test_the_ends_that_do_not_build_join_the_check_list():
    cl = _empty_list()
    assert with_unbuildable_ends(yoke(), cl) is cl        # every end builds: unchanged
    out = with_unbuildable_ends(refusing_yoke(), cl)
    (v,) = out.vectors
    np.testing.assert_array_equal(v.u, [20.0, 5.02, 5.03])
    assert v.depends == frozenset({1}) and v.origin == ("pin_r+ (does not build)",)


def test_synthesis_removes_the_box_ends_that_do_not_build():
    m = refusing_yoke()
    ex = SerialExecutor()
    r = synthesize(m, "fast", executor=ex, max_iter=8)
    assert r.status is SynthesisStatus.CONVERGED
    assert r.history[0].reasons.get("INVALID") == 1
    final = m.with_nominal(r.nominal).with_tolerances(r.tol)
    assert unbuildable_tolerances(final) == []
    assert r.nominal[1] + r.tol[1] <= LIMIT + 1e-12
    mc = monte_carlo(final, 100, seed=1, d=r.d, intent=m, accuracy="fast", executor=ex)
    assert "INVALID" not in mc.reasons, mc


def refusing_small(v):
    if v["pin_r"] < 4.99:
        raise ValueError(f"pin radius {v['pin_r']} below 4.99")
    return build_yoke(v)


def test_the_lower_end_is_named_by_its_side():
    m = dataclasses.replace(yoke(), builder=refusing_small)
    (v,) = with_unbuildable_ends(m, _empty_list()).vectors
    np.testing.assert_array_equal(v.u, [20.0, 4.98, 5.03])
    assert v.origin == ("pin_r- (does not build)",)


def test_a_process_pool_finds_the_ends_while_the_caller_goes_on():
    """On a process pool the ends are looked for in a worker
    (``_unbuildable_soon``) while the caller builds the reference; the check
    list gets the same vectors from what the worker found."""
    from synthesis import make_executor
    from synthesis.loop import _unbuildable_soon
    m = refusing_yoke()
    assert _unbuildable_soon(SerialExecutor(), m) is None
    with make_executor("process", 1) as ex:
        found = _unbuildable_soon(ex, m).result()
    assert found == unbuildable_tolerances(m)
    a = with_unbuildable_ends(m, _empty_list())
    b = with_unbuildable_ends(m, _empty_list(), found)
    assert [(v.u.tolist(), v.depends, v.origin) for v in a.vectors] == \
        [(v.u.tolist(), v.depends, v.origin) for v in b.vectors]
    assert with_unbuildable_ends(m, _empty_list(), []).vectors == ()
