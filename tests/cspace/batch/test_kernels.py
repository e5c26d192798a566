"""Stacked contact equations against the per-design kernels they batch."""

import numpy as np
import pytest

from cspace.batch.kernels import curve_stack, feature_table, stack_kernel
from cspace.contact import contact_curves
from cspace.defects import reference
from cspace.geometry import Assembly, trusted


def _pairs(m, U):
    with trusted():
        built = [m.build(u) for u in U]
    n = len(built[0].pairs) if isinstance(built[0], Assembly) else 1
    return [[b.pairs[i] if isinstance(b, Assembly) else b for b in built] for i in range(n)]


@pytest.mark.parametrize("name", ["geneva", "optical_filter", "reciprocating_cam"])
def test_every_curve_of_every_variant_matches_its_own_kernel(models, name):
    """Row v of a stack gives the values and validity margins of variant v's own
    contact curve (built from its own pair), for every curve of the model."""
    m = models[name]
    ref = reference(m, "fast")
    rng = np.random.default_rng(5)
    U = np.vstack([m.nominal, m.nominal + m.tol * rng.uniform(-1, 1, (6, m.n))])
    for i, (cs, pairs) in enumerate(zip(ref.spaces, _pairs(m, U))):
        table = feature_table(pairs)
        assert table.present.all()
        for v in (0, 3, 6):
            own = {(c.features, c.branch): c
                   for c in contact_curves(pairs[v], "fast", window=cs.window).curves}
            checked = 0
            for c in cs.curves:
                mine = own.get((c.features, c.branch))
                if mine is None:
                    continue
                st = stack_kernel(table, c.features, c.kernel.eq, c.kernel.owner)
                assert st.ok.all()
                x = np.linspace(mine.q1_start, mine.q1_end, 9)
                q, mg = st.branch(x, c.bi)
                m_own, q_own = mine.kernel.margin(x, mine.bi)
                np.testing.assert_allclose(q[v], q_own, rtol=0, atol=1e-10)
                np.testing.assert_allclose(mg[v], m_own, rtol=0, atol=1e-10)
                checked += 1
            assert checked > len(cs.curves) // 2


def test_a_variant_that_loses_a_feature_is_marked(models):
    """A stack marks the variants whose features are not the nominal's kinds."""
    m = models["reciprocating_cam"]
    ref = reference(m, "fast")
    (pairs,) = _pairs(m, [m.nominal, m.nominal])
    table = feature_table(pairs)
    table.present[1] = False
    c = ref.spaces[0].curves[0]
    st = stack_kernel(table, c.features, c.kernel.eq, c.kernel.owner)
    assert st.ok.tolist() == [True, False]


@pytest.mark.parametrize("name", ["geneva", "optical_filter"])
def test_curve_stack_matches_the_full_table(models, name):
    """curve_stack reads only a curve's two features and gives the rows of
    stack_kernel on the full feature table; an unbuildable variant's row is not
    ok; with ``scale``, every row measures margins in that length."""
    m = models[name]
    ref = reference(m, "fast")
    rng = np.random.default_rng(2)
    U = np.vstack([m.nominal, m.nominal + m.tol * rng.uniform(-1, 1, (4, m.n))])
    cs, pairs = ref.spaces[0], _pairs(m, U)[0]
    table = feature_table(pairs)
    for c in cs.curves[::5]:
        full = stack_kernel(table, c.features, c.kernel.eq, c.kernel.owner)
        mine = curve_stack(pairs + [None], c.features, c.kernel.eq, c.kernel.owner)
        assert mine.ok.tolist() == full.ok.tolist() + [False]
        x = np.linspace(c.q1_start, c.q1_end, 7)
        for bi in range(full.nbranch):
            a, b = full.branch_numpy(x, bi), mine.take(np.arange(len(pairs))).branch_numpy(x, bi)
            np.testing.assert_array_equal(a[0], b[0])
            np.testing.assert_array_equal(a[1], b[1])
        fixed = curve_stack(pairs, c.features, c.kernel.eq, c.kernel.owner, scale=2.5)
        assert np.all(fixed.scale == 2.5)
    assert curve_stack([None, None], cs.curves[0].features, "x", 0) is None


def test_a_packed_stack_gives_the_same_numbers(models):
    """:meth:`KernelStack.from_packed` of rows of :attr:`KernelStack.packed`
    (one gather for several stacks of an equation, as a grouped kernel call
    makes) gives the values of the fields it was packed from, bit for bit."""
    m = models["geneva"]
    ref = reference(m, "fast")
    rng = np.random.default_rng(2)
    U = np.vstack([m.nominal, m.nominal + m.tol * rng.uniform(-1, 1, (9, m.n))])
    cs, pairs = ref.spaces[0], _pairs(m, U)[0]
    table = feature_table(pairs)
    x = np.linspace(0.0, 2 * np.pi, 37)
    for c in cs.curves[::7]:
        st = stack_kernel(table, c.features, c.kernel.eq, c.kernel.owner)
        assert st.packed.shape == (len(U), 33) and st.packed.flags.c_contiguous
        rows = np.array([0, 4, 4, 9, 2])
        back = st.from_packed(st.packed[rows])
        plain = st.take(rows)
        for f in ("ok", "r", "fp", "ft", "axis_a", "axis_b", "scale"):
            np.testing.assert_array_equal(getattr(back, f), getattr(plain, f))
        assert back.ok.dtype == bool and back.packed is not None
        for a, b in zip(back.branch(x, c.bi), plain.branch(x, c.bi)):
            np.testing.assert_array_equal(a, b)
