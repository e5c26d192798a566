"""Every contact curve of a model as a :class:`~cspace.batch.kernels.KernelStack`
of random variants, for the tests that compare the kernel's code paths."""

import numpy as np

from cspace.batch.kernels import feature_table, stack_kernel
from cspace.batch.margins import _build, plans_of
from cspace.defects import reference


def model_stacks(m, n=10, seed=4, spread=1.0):
    """``(plan, curve, stack)`` of every curve of every pair of ``m``: the
    nominal and ``n`` variants, each parameter uniform within ``spread``
    tolerances of its nominal (seeded)."""
    ref = reference(m, "fast")
    rng = np.random.default_rng(seed)
    U = np.vstack([m.nominal, m.nominal + m.tol * rng.uniform(-spread, spread, (n, m.n))])
    pairs, bad, _ = _build(m, U)
    for plan, cs, row in zip(plans_of(ref), ref.spaces, pairs):
        table = feature_table(row)
        for c in cs.curves:
            k = c.kernel
            yield plan, c, stack_kernel(table, c.features, k.eq, k.owner)
