"""Defect margins for a whole batch of variants at once.

The full defect test (:func:`cspace.defects.is_defective`) builds each
variant's C-space, simulates it and matches it with the nominal: some 0.1 to
0.4 s of one core per variant.  This package
tests many variants of one design in one pass of array operations:

``cspace.batch.kernels``
    Contact equations of one feature pair for many variants at once
    (:class:`~cspace.batch.kernels.KernelStack`, built from a
    :class:`~cspace.batch.kernels.FeatureTable` of the variants' features).
``cspace.batch.fused``
    The contact kernel of a turning driver and follower with its arithmetic
    fused into compiled loops (numba, on by default) and numpy's
    trigonometric functions between them: the numpy kernel's numbers bit for
    bit, five times faster.
``cspace.batch.fused_bounds``
    The channel bounds' bookkeeping (which samples each variant needs, the
    running bounds and their curve ids) in compiled loops, on and off with
    the fused kernel: the numpy code's numbers bit for bit.
``cspace.batch.heap``
    glibc's allocator told to reuse freed arrays (the batch's temporaries of
    many MB otherwise cost fresh pages each): set when a batch starts and in
    the process pool's workers, ``CSPACE_HEAP=0`` to leave it alone.
``cspace.batch.compiled``
    The whole contact kernel compiled (numba, off by default: it measured
    no faster): one loop over variants and driver values, the values of the
    numpy kernel to rounding.
``cspace.batch.plan``
    The nominal motion laid out for batched evaluation
    (:class:`~cspace.batch.plan.PathPlan`): driver samples, the cells of the
    motion, and the curves that can bound its channel.
``cspace.batch.margins``
    :func:`~cspace.batch.margins.defect_margins`: signed channel, sequence and
    deviation margins and verdicts of a batch (:class:`~cspace.batch.margins.MarginBatch`);
    a variant whose margins lie within a band of zero falls back to the full
    test, which decides it.  :func:`~cspace.batch.margins.margin_tables`: the
    same margins without verdicts (what finite differences read).

>>> from cspace.batch import defect_margins                 # doctest: +SKIP
>>> mb = defect_margins(model, U, reference(model, "fast"))
>>> mb.defective, mb.margins(), mb.n_fallback
"""

from .margins import MarginBatch, defect_margins, margin_tables

__all__ = ["MarginBatch", "defect_margins", "margin_tables"]
