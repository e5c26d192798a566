"""Signed defect margins of many variants in one pass of array operations.

:func:`defect_margins` tests a batch of parameter vectors ``U`` (shape
``(n, p)``) against a nominal :class:`cspace.defects.Reference`.  The variants
share the nominal's structure, so instead of building each variant's C-space,
it follows the nominal motion (:class:`~cspace.batch.plan.PathPlan`) and, at
every driver sample of it, evaluates the contact curves that can bound the
motion's channel for all variants at once (:mod:`cspace.batch.kernels`).  The
stages read top to bottom:

1. :func:`_build` builds every variant (an unbuildable one is defective);
2. :func:`_envelopes` evaluates the candidate curves and takes, per variant and
   sample, the channel's lower bound (the largest valid curve below it) and
   upper bound (the smallest above), with the curve that attains each;
3. :func:`_follow` moves the follower through the variant's channel, the
   quasi-static rule of :func:`cspace.simulate.simulate`: it stays where it is
   until a bound pushes it;
4. :func:`_handovers` samples again, per variant, the intervals between
   samples where its bounds change curve or a candidate near its channel
   begins or ends (a variant's events are not the nominal's), and
   :func:`_sequence_margin` compares which curves bound the channel, in order,
   with the nominal's (contacts shorter than the resolution of
   :mod:`cspace.defects` contracted);
5. :func:`_certify` turns the margins into verdicts, or into *uncertain* where a
   margin lies within its band of zero or the structure differs;
6. :func:`_fallback` runs the full per-variant test
   (:func:`cspace.defects.is_defective`) on every uncertain variant; its
   verdict is final.

Margins (C-space metric: rad, or slide over the characteristic length)
-----------------------------------------------------------------------
channel
    The narrowest gap of the variant's channel along the motion (upper minus
    lower bound), per pair, at the plan's samples and those of
    :func:`_handovers`.  <= 0: the channel closes, the drive jams.
sequence
    Per pair, how far the contacts along the motion (below and above the
    follower) lie from the resolution of :mod:`cspace.defects` (d/100 of
    driver motion) when the variant's contact sequence is surely the
    nominal's (> 0); ``-resolution`` when it surely is not; 0 when a contact
    lasts so close to the resolution that the samples cannot tell.
deviation
    ``d - max |f - f0|`` over the drive (all pairs).  <= 0: the output deviates.

The verdict is *defective* iff some margin is <= 0.  A channel margin within
the accuracy's band of zero (``Accuracy.batch_gap_band``), a deviation whose
full-test reading may lie within a quarter of its band of d (the band,
``Accuracy.batch_dev_band`` times d, where the batch cannot bound that
reading sample by sample: :func:`_follow`, :data:`DEV_FLOOR`), a variant
whose features changed kind, or a channel whose bounds the candidate curves
do not determine, is decided by the full test instead:
:attr:`MarginBatch.fallback` marks and counts them.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field, replace

import numpy as np

from ..geom2d import wrap_pi
from ..match import cycle_form
from ..geometry import Assembly, Rotation, trusted
from ..tolerances import ROUNDING
from . import fused_bounds, heap
from .kernels import feature_table, stack_kernel
from .plan import VALID_TOL, PathPlan, path_plan, placed_on_turn

__all__ = ["KINDS", "MarginBatch", "contact_sequences", "defect_margins", "margin_tables",
           "plans_of"]

HEALTHY, DEFECTIVE, UNCERTAIN = 0, 1, -1


@dataclass(frozen=True, eq=False)
class MarginBatch:
    """Verdicts and signed margins of a batch of variants.

    Margins are in the C-space metric: radians for a turning follower or
    driver, a slide divided by the pair's characteristic length L for a
    sliding one (``cspace.metric``; a channel margin of 0.0365 on a pair of
    L = 2.5 cm is 0.091 cm of slide).  Positive is healthy.  The sequence
    margin is in driver motion: how far the contacts along the motion last
    beyond the resolution ``RESOLUTION * d`` (:mod:`cspace.defects`), at most
    that resolution.  :meth:`margins` stacks the channel, sequence and
    deviation margins (a method: it computes the stack).

    Attributes
    ----------
    defective : (n,) bool
        The final verdicts (batched where certified, else the full test's).
    channel : (n, P) float
        Channel margin per pair (C-space metric); NaN where not computed (an
        unbuildable variant).
    sequence : (n, P) float
        Sequence margin per pair (driver motion, C-space metric); NaN for
        an unbuildable variant.
    deviation : (n,) float
        ``d - max deviation`` (C-space metric); NaN for an unbuildable
        variant.
    certified : (n,) bool
        Decided by the batch.
    fallback : (n,) bool
        Decided by the full per-variant test.
    results : tuple of DefectResult
        One per variant (reasons, where, message).
    d : float
    start : (n, P) float
        Start margin per pair: how far the stated follower start lies inside
        the variant's channel at the drive's start (C-space metric).  Not a
        defect margin: a variant whose channel lies off the stated start
        starts at the nearest point of it (the full test assembles it there,
        :func:`cspace.defects.assembled_start`); only a channel closed at the
        start, which the channel margin reads, blocks it.  NaN for an
        unbuildable variant.
    """

    defective: np.ndarray
    channel: np.ndarray
    sequence: np.ndarray
    deviation: np.ndarray
    certified: np.ndarray
    fallback: np.ndarray
    results: tuple
    d: float
    stats: dict = field(default_factory=dict)
    start: np.ndarray | None = None

    @property
    def n(self) -> int:
        return len(self.defective)

    @property
    def n_fallback(self) -> int:
        return int(np.sum(self.fallback))

    def __repr__(self):
        return (f"<MarginBatch: {self.n} variants, {int(np.sum(self.defective))} defective, "
                f"{self.n_fallback} decided by the full test>")

    def margins(self) -> np.ndarray:
        """(n, 3) array: smallest channel margin, smallest sequence margin,
        deviation margin."""
        with np.errstate(invalid="ignore"):
            return np.stack([np.min(self.channel, axis=1), np.min(self.sequence, axis=1),
                             self.deviation], axis=1)


def plans_of(ref) -> tuple:
    """The :class:`PathPlan` of every pair of a Reference (cached on it)."""
    plans = getattr(ref, "_plans", None)
    if plans is None:
        res = _resolution(ref.d)
        step = ref.accuracy.sim_step
        # extra samples where the follower is let go; contacts that hand over
        # are sampled per variant, where its own events lie (_handovers)
        plans = tuple(_with_grid(path_plan(cs, sim, i, start[1], fine=res / 2.5, width=step,
                                           events=False), cs, ref)
                      for i, (cs, sim, start) in enumerate(zip(ref.spaces, ref.sims, ref.starts)))
        object.__setattr__(ref, "_plans", plans)
    return plans


def _with_grid(plan: PathPlan, cs, ref) -> PathPlan:
    """``plan`` with :attr:`PathPlan.on_grid`: its nominal samples that are
    the drive's regular samples, which the full test's simulation of every
    variant has too (a rotating driver's step does not depend on the
    variant)."""
    from ..metric import driver_scale
    from ..simulate import drive_grid
    on = np.zeros(plan.n, dtype=bool)
    if isinstance(cs.pair.driver.axis, Rotation):
        grid = drive_grid(ref.drive[0], ref.drive[1],
                          ref.accuracy.sim_step * driver_scale(cs.pair))
        on = np.isin(plan.x, grid) & plan.is_ref
    return replace(plan, on_grid=on)


# ------------------------------------------------------------------ stage 1
def _build(model, U):
    """Pairs of every variant (per pair index) and the unbuildable ones."""
    n = len(U)
    bad = np.zeros(n, dtype=bool)
    msgs = [""] * n
    built = []
    with trusted():
        for v in range(n):
            try:
                out = model.build(U[v])
            except (ValueError, ArithmeticError) as e:
                bad[v] = True
                msgs[v] = f"invalid geometry: {e}"
                out = None
            built.append(out)
    first = next((b for b in built if b is not None), None)
    npairs = len(first.pairs) if isinstance(first, Assembly) else 1
    pairs = []
    for i in range(npairs):
        row = []
        for b in built:
            if b is None:
                b = first
            row.append(b.pairs[i] if isinstance(b, Assembly) else b)
        pairs.append(row)
    return pairs, bad, msgs


# ------------------------------------------------------------------ stage 2
def _envelopes(plan: PathPlan, cs, table, changed, deps, reach_factor: float = 2.0,
               lean: bool = False):
    """Lower and upper channel bounds (V, N) per variant and sample, the curve
    key attaining each (-1: window edge / none), the variants whose features
    did not support the evaluation, the number of curve evaluations, the
    sample intervals where a candidate near a variant's channel begins or
    ends, and where each variant evaluated each candidate: an
    :class:`Envelopes`.

    A candidate curve counts for a variant only at the samples where it can
    come near that variant's channel: where it lies within ``reach_factor *
    (its own displacement + the largest displacement of the channel's
    bounds)`` of the nominal channel and its validity margin within
    ``reach_factor`` times its change of the nominal's.  Displacements are
    measured per variant at every ``_STRIDE``-th sample of the curve first,
    so a variant's result does not depend on the others in its batch.

    ``lean``: the bounds and their curve keys only, the same numbers (no
    runners-up, ties, candidate ends or record of where each candidate was
    evaluated: what the hand-over samples and the certification read;
    :func:`margin_tables`)."""
    V, N = table.n, plan.n
    work, dmax, ok, stacks = _reaches(plan, cs, table, changed, deps)
    acc = _Bounds(plan, V, N, runners_up=not lean)
    sels = [_needed(plan, item, dmax, reach_factor) for item in work]
    for item, sel, got in zip(work, sels, _evaluated_once(plan, work, sels)):
        if got is not None:
            q, m, n_eval = got
            acc.n_eval += n_eval
            _accumulate(plan, acc, item, sel, q, m, lean)
    if lean:
        return Envelopes(acc.lo, acc.hi, acc.lo_id, acc.hi_id, ok, acc.n_eval, None, {}, None,
                         stacks, [])
    with np.errstate(invalid="ignore"):
        ties = ((acc.lo - acc.lo2) / plan.scale2 <= TIE, (acc.hi2 - acc.hi) / plan.scale2 <= TIE)
    _untie(acc.lo_id, ties[0])
    _untie(acc.hi_id, ties[1])
    return Envelopes(acc.lo, acc.hi, acc.lo_id, acc.hi_id, ok, acc.n_eval,
                     _ends(acc.flips, acc.lo, acc.hi, acc.lo_id, acc.hi_id), acc.needed, ties,
                     stacks, acc.flips)


def _reaches(plan: PathPlan, cs, table, changed, deps):
    """Per candidate curve, its stack for the variants that move it (and the
    nominal row), and how far each moves it and its validity margin at every
    ``_STRIDE``-th candidate sample; the largest displacement (C-space metric)
    of the channel's own bounds per variant; and the variants whose features
    support the evaluation."""
    V = table.n
    # a variant with a feature the nominal has not (a new convex vertex) has
    # contacts the nominal's curves do not describe: the full test decides
    ok = np.ones(V, dtype=bool) if table.extra is None else ~table.extra
    work = []
    dmax = np.zeros(V)
    stacks: dict = {}     # per curve (a candidate on both sides shares it)
    coarse_of = _coarse(plan)
    for (c, side) in plan.candidates:
        if c not in stacks:
            k = cs.curves[c].kernel
            stack = stack_kernel(table, cs.curves[c].features, k.eq, k.owner)
            dep = deps.get(c)
            rows = (np.nonzero(changed[:, dep].any(axis=1))[0] if dep is not None
                    else np.arange(V))
            if not (len(rows) and rows[0] == 0):
                # with the nominal row (sorted, as rows are)
                rows = np.concatenate([np.zeros(1, dtype=rows.dtype), rows])
            st = _Distinct(stack, rows)
            ok[rows] &= st.ok
            stacks[c] = (stack, rows, st)
    # per candidate (curve and side), the curve's values at its coarse
    # samples (each side at its own: they do not overlap, _evaluated_once)
    at_coarse = _unions_at(plan, {key: (stacks[key[0]][2], cs.curves[key[0]].bi,
                                        [coarse_of[key]])
                                  for key in plan.candidates})
    for (c, side), idx in plan.candidates.items():
        curve = cs.curves[c]
        _, rows, st = stacks[c]
        coarse = coarse_of[c, side]
        # per distinct row of the curve's stack (row 0 the nominal's): the
        # rows that share it share every number below
        _, q, mg = at_coarse[c, side]
        dq = q - q[:1]
        if plan.periodic2:
            dq = wrap_pi(dq)
        # a value moves the channel only where the curve is a contact
        live = (mg >= -VALID_TOL) | (mg[:1] >= -VALID_TOL)
        disp = np.where(live, np.abs(dq), 0.0) / plan.scale2
        dm = np.abs(mg - mg[:1])
        own = (plan.lower[coarse] == c) if side > 0 else (plan.upper[coarse] == c)
        if own.any():
            dmax[rows] = np.maximum(dmax[rows], st.spread(np.max(disp[:, own], axis=1)))
        work.append((c, side, idx, curve, st, rows, disp, dm))
    return work, dmax, ok, {c: v[0] for c, v in stacks.items()}


def _coarse(plan: PathPlan) -> dict:
    """Per candidate, its every ``_STRIDE``-th sample (where its displacement
    is measured), kept on the plan: the same in every call."""
    got = _PLAN_CACHE.setdefault(plan, {}).get("coarse")
    if got is None:
        got = {key: idx[::_STRIDE] for key, idx in plan.candidates.items()}
        _PLAN_CACHE[plan]["coarse"] = got
    return got


#: Per plan (weakly: a plan's caches go with it, and never into a pickle of
#: it), what every call on it computes the same: :func:`_coarse`.
_PLAN_CACHE: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()

class _Bounds:
    """The running lower and upper bounds (V, N) of the channel, the curve keys
    attaining them and their runners-up, as candidates are added
    (:func:`_accumulate`)."""

    def __init__(self, plan: PathPlan, V: int, N: int, runners_up: bool = True):
        self.lo = np.full((V, N), -math.inf)
        self.hi = np.full((V, N), math.inf)
        if not plan.periodic2:
            self.lo[:] = plan.window[2]
            self.hi[:] = plan.window[3]
        self.lo_id = np.full((V, N), -1, dtype=np.int32)
        self.hi_id = np.full((V, N), -1, dtype=np.int32)
        # the runner-up of each bound
        self.lo2 = np.full((V, N), -math.inf) if runners_up else None
        self.hi2 = np.full((V, N), math.inf) if runners_up else None
        self.n_eval = 0
        self.flips: list = []
        self.needed: dict = {}

    def add(self, side: int, key, idx, full) -> None:
        if len(idx) and idx[-1] - idx[0] + 1 == len(idx):
            # a run of samples: updated in place through views (the same
            # numbers as the assignments below)
            sl = slice(int(idx[0]), int(idx[-1]) + 1)
            b, b2, ids = ((self.lo, self.lo2, self.lo_id) if side > 0
                          else (self.hi, self.hi2, self.hi_id))
            b, ids = b[:, sl], ids[:, sl]
            better = full > b if side > 0 else full < b
            if b2 is not None:
                b2 = b2[:, sl]
                if side > 0:
                    np.maximum(b2, np.minimum(b, full), out=b2)
                else:
                    np.minimum(b2, np.maximum(b, full), out=b2)
            np.copyto(b, full, where=better)
            np.copyto(ids, key, where=better)
            return
        if side > 0:
            cur = self.lo[:, idx]
            better = full > cur
            if self.lo2 is not None:
                self.lo2[:, idx] = np.maximum(self.lo2[:, idx], np.minimum(cur, full))
            self.lo[:, idx] = np.where(better, full, cur)
            self.lo_id[:, idx] = np.where(better, key, self.lo_id[:, idx])
        else:
            cur = self.hi[:, idx]
            better = full < cur
            if self.hi2 is not None:
                self.hi2[:, idx] = np.minimum(self.hi2[:, idx], np.maximum(cur, full))
            self.hi[:, idx] = np.where(better, full, cur)
            self.hi_id[:, idx] = np.where(better, key, self.hi_id[:, idx])


def _needed(plan: PathPlan, item, dmax, reach_factor: float):
    """Where one candidate curve must be evaluated: the samples where a
    variant can bring it near its channel, ``(samples, need, need_o,
    other, cols)`` (the variants that move the curve and those that see the
    nominal's, :func:`_accumulate`; ``cols``: the samples' places among the
    candidate's), or None where none can."""
    c, side, idx, curve, st, rows, disp, dm = item     # disp, dm per distinct row
    V = len(dmax)
    n = len(idx)
    dist0 = plan.distance[c, side]
    m0 = plan.margin0[c, side]
    # where a variant that moves the curve may make it real: where the
    # nominal is real within the plan's reach (the contact's start and end
    # move with the variant's events; its margin changes steeply there,
    # between the samples its change is measured at), or short of it by
    # less than that change
    mn = m0 if plan.margin_near is None else plan.margin_near[c, side]
    # only the samples within the largest reach of any variant can be
    # needed (the same test with the largest displacements: rounding is
    # monotone, so no sample it leaves out passes the test below)
    top = reach_factor * (disp.max(initial=0.0) + dmax.max(initial=0.0)) + ROUNDING
    sub = np.nonzero(dist0 <= top)[0] if not math.isnan(top) else np.arange(n)
    if not len(sub):
        return None
    others = np.ones(V, dtype=bool)
    others[rows] = False
    other = np.nonzero(others)[0]
    if fused_bounds.enabled():
        keep, need, need_o = fused_bounds.need(dist0, m0, mn, sub, disp, dm, st.inv, dmax, rows,
                                               other, reach_factor, ROUNDING, VALID_TOL, _STRIDE)
    else:
        disp, dm = st.spread(disp), st.spread(dm)
        d0 = dist0[sub][None, :]
        # the variants that move this curve, and those that see the nominal
        # curve (their channel may still move towards it)
        need = ((d0 <= reach_factor * (_spread_at(disp, sub) + dmax[rows, None]) + ROUNDING)
                & (mn[sub][None, :] >= -reach_factor * _spread_at(dm, sub) - VALID_TOL))
        need_o = ((d0 <= reach_factor * dmax[other, None] + ROUNDING)
                  & (m0[sub][None, :] >= -VALID_TOL))
        keep = np.nonzero(need.any(axis=0) | need_o.any(axis=0))[0]
        need, need_o = need[:, keep], need_o[:, keep]
    if not len(keep):
        return None
    cols = sub[keep]
    return idx[cols], need, need_o, other, cols


def _accumulate(plan: PathPlan, acc: _Bounds, item, sel, q, m, lean: bool = False) -> None:
    """Add one candidate curve, evaluated (``q``, ``m``, per distinct row of
    its stack) at the samples of ``sel`` (:func:`_needed`), to the bounds
    (``lean``: and nothing else, :func:`_envelopes`)."""
    if fused_bounds.enabled():
        _accumulate_fused(plan, acc, item, sel, q, m, lean)
        return
    c, side, _, curve, st, rows, disp, dm = item
    idx, need, need_o, other, cols = sel
    V = acc.lo.shape[0]
    q, m = st.spread(q), st.spread(m)
    valid = m >= -VALID_TOL
    if plan.periodic2:
        # on the turn of the nominal value's place (PathPlan.place)
        q = plan.place[c, side][cols] + wrap_pi(q - q[:1])
    # where a contact the variant can bring near its channel begins or
    # ends between two samples, it may bound the channel for less than a
    # sample step: :func:`_handovers` samples the interval again
    # (two samples are next to each other for a variant when both are samples
    # it or the nominal needs, as in a batch of the variant alone: the flips
    # of a variant do not depend on the others in its batch)
    if not lean:
        _flips(plan, acc, c, side, rows, idx, need, need_o, other, q, valid)
    far = -math.inf if side > 0 else math.inf
    vals = np.where(valid & need, q, far)
    if not lean:
        _needs(acc, c, side, V, rows, other, idx, need, need_o)
    if len(rows) == V:
        full = vals
    else:
        full = np.empty((V, len(idx)))
        full[other] = np.where(valid[:1] & need_o, q[:1], far)
        full[rows] = vals
    acc.add(side, plan.key[c], idx, full)


def _accumulate_fused(plan: PathPlan, acc: _Bounds, item, sel, q, m, lean: bool) -> None:
    """:func:`_accumulate` with the compiled loops of
    :mod:`cspace.batch.fused_bounds`, the same numbers."""
    c, side, st, rows = item[0], item[1], item[4], item[5]
    idx, need, need_o, other, cols = sel
    b, b2, ids = ((acc.lo, acc.lo2, acc.lo_id) if side > 0 else (acc.hi, acc.hi2, acc.hi_id))
    place = plan.place[c, side][cols] if plan.periodic2 else None
    qp = fused_bounds.accumulate(b, b2, ids, side, int(plan.key[c]), idx, rows, other, q, m,
                                 st.inv, need, need_o, place,
                                 -math.inf if side > 0 else math.inf, VALID_TOL,
                                 placed=not lean)
    if not lean:
        nxt = np.diff(idx) == 1
        if nxt.any():
            r_, k_, o_r, o_k = fused_bounds.flip_marks(m, st.inv, VALID_TOL, need, need_o, nxt)
            key = plan.key[c]
            rv = m[st.inv[r_], k_ + 1] >= -VALID_TOL
            acc.flips.append((side, key, rows[r_], idx[k_], qp[r_, k_], qp[r_, k_ + 1], rv))
            if len(other):
                m0 = m[st.inv[0]]
                acc.flips.append((side, key, other[o_r], idx[o_k], qp[0, o_k], qp[0, o_k + 1],
                                  m0[o_k + 1] >= -VALID_TOL))
        _needs(acc, c, side, b.shape[0], rows, other, idx, need, need_o)


def _needs(acc: _Bounds, c, side, V, rows, other, idx, need, need_o) -> None:
    """Record where each variant evaluated a candidate (``acc.needed``)."""
    nd = np.empty((V, len(idx)), dtype=bool)
    nd[rows] = need
    nd[other] = need_o
    acc.needed[c, side] = (idx, nd)


def _flips(plan: PathPlan, acc: _Bounds, c, side, rows, idx, need, need_o, other, q,
           valid) -> None:
    """Record where a candidate (placed values ``q``, ``valid``) begins or
    ends between two samples it is evaluated at (``acc.flips``)."""
    nxt = np.diff(idx) == 1
    if nxt.any():
        own = need | need[:1]
        f = ((valid[:, 1:] != valid[:, :-1]) & (need[:, 1:] | need[:, :-1]) & nxt
             & own[:, 1:] & own[:, :-1])
        r_, k_ = np.nonzero(f)
        acc.flips.append((side, plan.key[c], rows[r_], idx[k_], q[r_, k_], q[r_, k_ + 1],
                          valid[r_, k_ + 1]))
        if len(other):
            own = need_o | need[:1]
            f = ((valid[0, 1:] != valid[0, :-1]) & nxt)[None, :] \
                & (need_o[:, 1:] | need_o[:, :-1]) & own[:, 1:] & own[:, :-1]
            r_, k_ = np.nonzero(f)
            acc.flips.append((side, plan.key[c], other[r_], idx[k_], q[0, k_], q[0, k_ + 1],
                              valid[0, k_ + 1]))


def _union(parts) -> np.ndarray:
    """The sorted distinct sample indices of ``parts`` (``np.unique`` of their
    concatenation, the same array; a merge of sorted runs is several times
    faster than numpy's hashing ``unique`` on these sizes)."""
    if len(parts) == 1:
        return parts[0]
    u = np.concatenate(parts)
    if not len(u):
        return u
    u.sort(kind="stable")
    keep = np.empty(len(u), dtype=bool)
    keep[0] = True
    np.not_equal(u[1:], u[:-1], out=keep[1:])
    return u[keep]


def _alone(plan: PathPlan, st, bi: int, at) -> tuple:
    """One curve's values at the samples ``at``, in a kernel call of its own:
    ``(samples, q, m)``, per distinct row of ``st`` (:class:`_Distinct`)."""
    return (at,) + tuple(st.branch(plan.xw[at], bi, plan.window))


#: :func:`_unions_at`: a curve whose distinct rows times samples are at most
#: this many is evaluated in one kernel call with the others of its contact
#: equation (a kernel call costs some 60 array operations whatever its size;
#: a batch of a few variants makes a few hundred small ones).
GROUP_SIZE = 4096


def _unions_at(plan: PathPlan, asked: dict, grouped_only: bool = False) -> dict:
    """Curves' values at the union of sorted sample sets, ``{key: (distinct
    stack, branch, parts)} -> {key: (samples, q, m)}`` (a key names a curve,
    or a curve and side), the same numbers.  Curves with few
    values to compute (:data:`GROUP_SIZE`) that share a contact equation (type,
    owner, feature kinds, branch and the convexity flags the kernel reads
    from its first row, the nominal's) go in few kernel calls
    (:func:`_grouped_call`): every value is computed from its own constants
    and driver value alone (:func:`_point_values` does the same for
    hand-over points).  The others get a call each, or with ``grouped_only``
    are left out (their caller evaluates them one at a time, as it needs
    them)."""
    from .kernels import _CONVEX
    out: dict = {}
    groups: dict = {}
    for c, (st, bi, parts) in asked.items():
        at = _union(parts)
        k = st.stack
        if st.n_distinct * len(at) > GROUP_SIZE or not len(at):
            if not grouped_only:
                out[c] = _alone(plan, st, bi, at)
            continue
        sig = (k.eq, k.owner, k.fp_kind, k.ft_kind, bi, float(k.fp[0, _CONVEX]),
               float(k.ft[0, _CONVEX]))
        groups.setdefault(sig, []).append((c, st, at))
    for sig, group in groups.items():
        # longest first; a curve with less than half the samples of the
        # first of its call starts another (its row is padded to that length)
        group.sort(key=lambda g: -len(g[2]))
        calls = [[group[0]]]
        for g in group[1:]:
            if 2 * len(g[2]) < len(calls[-1][0][2]):
                calls.append([])
            calls[-1].append(g)
        for call in calls:
            _grouped_call(plan, call, sig[4], out)
    return out


def _grouped_call(plan: PathPlan, call, bi: int, out: dict) -> None:
    """One kernel call for the curves of ``call`` (``(curve, distinct stack,
    samples)``, longest first): each distinct row of each curve a row of the
    call, with that curve's driver values, padded to the first's length by
    repeating its last (the same arithmetic on every value as a call of its
    own: :meth:`~cspace.batch.kernels.KernelStack.branch` takes a driver
    value per row and sample)."""
    if len(call) == 1:
        c, st, at = call[0]
        out[c] = _alone(plan, st, bi, at)
        return
    M = len(call[0][2])
    stack = call[0][1].stack.from_packed(np.concatenate([st.stack.packed for _, st, _ in call]))
    X = np.empty((len(stack.ok), M))
    r = 0
    for _, st, at in call:
        x = plan.xw[at]
        X[r:r + st.n_distinct, :len(at)] = x
        X[r:r + st.n_distinct, len(at):] = x[-1]
        r += st.n_distinct
    qq, mm = stack.branch(X, bi, plan.window)
    r = 0
    for c, st, at in call:
        n = st.n_distinct
        out[c] = (at, qq[r:r + n, :len(at)], mm[r:r + n, :len(at)])
        r += n


def _evaluated_once(plan: PathPlan, work, sels):
    """Per work item (in order), the curve's values ``(q, m)`` at its
    samples (``sels``, :func:`_needed`; None: skipped), and the number of
    evaluations.  Each side of a curve is evaluated at its own samples: the
    two sides' samples do not overlap on the built-in models (a curve is a
    candidate below the channel at some samples and above it at others), so
    evaluating them together saved no value and cost a copy of each side's
    share.  Items with few values to compute go in grouped kernel calls
    first (:func:`_unions_at`); the others one at a time, as they come."""
    asked = {(item[0], item[1]): (item[4], item[3].bi, [sel[0]])
             for item, sel in zip(work, sels) if sel is not None}
    kept: dict = _unions_at(plan, asked, grouped_only=True)
    for item, sel in zip(work, sels):
        if sel is None:
            yield None
            continue
        st = item[4]
        got = kept.pop((item[0], item[1]), None)
        if got is None:
            got = _alone(plan, st, item[3].bi, sel[0])
        yield got[1], got[2], len(got[0]) * st.n_distinct


@dataclass(frozen=True, eq=False)
class Envelopes:
    """The channel's bounds of a batch along a plan (:func:`_envelopes`).

    ``lo``, ``hi`` (V, N): the bounds; ``lo_id``, ``hi_id``: the curve keys
    attaining them; ``ok`` (V,): the features supported the evaluation;
    ``n_eval``: curve evaluations; ``ends`` (V, N - 1): the sample intervals
    where a candidate begins or ends near the channel (:func:`_ends`);
    ``needed``: ``(curve, side) -> (samples, (V, M) bool)``, where each
    variant evaluated the candidate; ``ties``: (lower, upper) (V, N) bool,
    the samples where the bound ties with the runner-up; ``stacks``: curve ->
    its :class:`~cspace.batch.kernels.KernelStack` for every variant;
    ``flips``: where a candidate begins or ends between two samples it is
    evaluated at, ``(side, key, rows, first sample, value there, value at
    the next, real at the next)``."""

    lo: np.ndarray
    hi: np.ndarray
    lo_id: np.ndarray
    hi_id: np.ndarray
    ok: np.ndarray
    n_eval: int
    ends: np.ndarray
    needed: dict
    ties: tuple
    stacks: dict = field(default_factory=dict)
    flips: list = field(default_factory=list)


def _ends(flips, lo, hi, lo_id, hi_id):
    """The sample intervals (V, N - 1) where a candidate begins or ends (its
    validity changes sign) and may bound the channel in between: where its
    value (the contact equation's, valid or not) at either sample lies beyond
    the bound, or short of it by no more than twice what the two move over the
    interval."""
    V, N = lo.shape
    out = np.zeros((V, max(N - 1, 0)), dtype=bool)
    for side, key, r, i, qa, qb, _ in flips:
        if not len(r):
            continue
        b, ids = (lo, lo_id) if side > 0 else (hi, hi_id)
        ba, bb = b[r, i], b[r, i + 1]
        with np.errstate(invalid="ignore"):
            ga, gb = side * (ba - qa), side * (bb - qb)
            move = np.abs(qb - qa) + np.abs(bb - ba)
            near = ~(np.minimum(ga, gb) > 2.0 * move)
        # where it bounds the channel at one of the samples, the bound changes
        # curve over the interval: sampled again anyway
        near &= (ids[r, i] != key) & (ids[r, i + 1] != key)
        out[r[near], i[near]] = True
    return out


#: The share of the deviation band (``Accuracy.batch_dev_band``) by which the
#: full test's reading of a variant's output may differ from the batch's
#: beyond what :func:`_interpolated` bounds sample by sample: at the drive's
#: regular samples the two read the same output; between them the reading
#: lies within twice the output's bend of it.  What is left is where the
#: variant's own samples place a bound's peak, which the batch places at the
#: nominal's: the largest such difference seen on the case studies' check
#: lists was 3e-5 rad, 0.05 % of d, against a floor of 0.5 % of d
#: (``docs/margins.md``, "Readings between the variant's samples").
DEV_FLOOR = 0.25

#: Two candidate bounds within this (C-space metric) of each other at a sample
#: tie: the sample lies on their hand-over (an event of the nominal, located to
#: ``Accuracy.root_tol``), and which one is called the bound there is not a
#: step of the contact sequence.
TIE = 1e-7


def _untie(ids, tie):
    """At tied samples, the bound continues the run before it (or the one after
    it): a tie is where a run ends, not a run of its own."""
    V, N = ids.shape
    if N < 2:
        return
    if (fused_bounds.enabled() and ids.dtype == np.int32 and tie.dtype == np.bool_
            and ids.flags.c_contiguous and tie.flags.c_contiguous):
        fused_bounds.untie(ids, tie)
        return
    # the samples copied from are untied, so none of them changes here
    r, i = np.nonzero(tie[:, 1:] & ~tie[:, :-1])
    ids[r, i + 1] = ids[r, i]
    r, i = np.nonzero(tie[:, :-1] & ~tie[:, 1:])
    first = np.zeros(len(r), dtype=bool)
    first[:] = (i == 0) | tie[r, np.maximum(i - 1, 0)]
    ids[r[first], i[first]] = ids[r[first], i[first] + 1]


#: Every this many candidate samples one measures how far the batch moves the
#: curve (the local reach used to skip the samples it cannot matter at).
_STRIDE = 8


def _spread_at(v, cols):
    """Per-sample values (rows, len(cols)) at the candidate samples ``cols``
    from values at every ``_STRIDE``-th sample (rows, ceil(n / _STRIDE)):
    the larger of the two coarse samples around each."""
    w = np.maximum(v, np.concatenate([v[:, 1:], v[:, -1:]], axis=1))
    return w[:, cols // _STRIDE]


class _Distinct:
    """A :class:`~cspace.batch.kernels.KernelStack` evaluated once per distinct
    row: variants whose constants of this contact equation are equal (a
    finite-difference step of a parameter the curve does not depend on, or
    check-list vectors that share the zone extremes it depends on) share one
    evaluation, the same numbers as their own would be.  The first row keeps
    its place (the nominal row, which structural flags are read from)."""

    def __init__(self, stack, rows=None):
        # the rows ``rows`` of ``stack`` (default all), read from its packed
        # fields (the numbers of ``stack.take(rows)``, without that stack)
        key = stack.packed if rows is None else stack.packed[rows]
        V = key.shape[0]
        # rows are the same row when their constants are the same bits (then
        # every operation on them gives the same bits); numbered in order of
        # first appearance
        seen: dict = {}
        first = []
        inv = np.empty(V, dtype=np.intp)
        for v, b in enumerate(map(bytes, key)):
            j = seen.setdefault(b, len(first))
            if j == len(first):
                first.append(v)
            inv[v] = j
        self.inv = inv
        self.stack = (stack if rows is None and len(first) == V
                      else stack.from_packed(key if len(first) == V else key[np.array(first)]))
        self.ok = stack.ok if rows is None else key[:, 0] != 0.0
        self.n_distinct = len(first)

    def branch(self, q1, bi: int, window=None):
        """:meth:`KernelStack.branch` of each distinct row once: (n_distinct,
        ...) values (:meth:`spread` gives them to every row; the batch's
        stages read them through :attr:`inv` instead)."""
        return self.stack.branch(q1, bi, window)

    def spread(self, v):
        """Values of the distinct rows (n_distinct, ...) given to every row."""
        return v if self.n_distinct == len(self.inv) else v[self.inv]


# ------------------------------------------------------------------ stage 3
def _follow(plan: PathPlan, lo, hi, lo_id=None, hi_id=None, band: float = 0.0,
            readings: bool = True):
    """The quasi-static motion through the variants' channels, the rule of
    :func:`cspace.simulate.simulate`: at each sample a form-closed follower
    keeps its place unless a bound pushes it; a force-closed one
    (``plan.bias``) rests on its bias-side bound.  Returns the output (V, N),
    its deviation from the nominal's at the nominal's samples (V, N; C-space
    metric, in the nominal's, as the full test measures it: a sliding
    follower's slide over the nominal's characteristic length; 0 elsewhere)
    and the range ``(least, most)`` ((V,) each, C-space metric) in which the
    full test's reading of the variant's largest deviation lies, less the
    :data:`DEV_FLOOR` widening on either side, which the caller adds
    (:func:`_chunk`, over all pairs).

    Where a force-closed follower's channel has no bound on the bias side (a
    rotating follower's bound is infinite there; a sliding follower's is the
    window edge, curve id -1) while the nominal's has a contact curve, the
    variant's bound there is a contact that the nominal does not have (a
    follower corner riding the cam where its face ran off it), which the
    candidates cannot place, or none.  Its contact sequence differs from the
    nominal's either way, which the sequence margin reads; the follower moves
    there as the nominal does (its deviation kept), since resting it on the
    window edge would report a deviation of the window's size that the full
    test does not see.

    The full test reads a variant's output at the nominal's samples; at those
    that are not the variant's own (the nominal's events, and with a sliding
    driver every sample: its step is a share of each variant's length), by
    linear interpolation between the variant's samples (the drive's regular
    steps, :attr:`PathPlan.on_grid`, and its own events, which the batch does
    not know).  Where the output
    bends between a sample and its neighbours by more than half the deviation
    band, that reading may lie anywhere between the neighbours' values: at a
    jump (a force-closed follower drops where its bound does, a cliff of the
    cam) and at a kink (a bound starts or stops pushing a form-closed follower
    between two of the variant's samples; on the Geneva pair the full test's
    reading there lay 1.3e-3 rad, 2 % of d, from the output's value, more
    than the band).  There the reading is taken to lie anywhere between the
    neighbours' deviations, widened by the deviation ``band`` (C-space
    metric).  At the drive's regular samples the reading is the output; at
    the nominal's other samples it lies within twice the output's bend from
    the chord of the regular samples around it (:func:`_between_regular`).  Every
    bound is widened by :data:`DEV_FLOOR` times the band, for what the batch
    does not bound sample by sample (the variant's own samples of a bound's
    peak, which it places at the nominal's).  With fewer than three samples,
    the range is the largest deviation +- the band.  Without ``readings``
    that range is not computed (None)."""
    V, N = lo.shape
    if not plan.bias and not (np.isnan(lo).any() or np.isnan(hi).any()):
        f = (fused_bounds.clamp_scan(lo, hi, plan.start) if fused_bounds.enabled()
             else _clamp_scan(lo, hi, plan.start))
    else:
        loT, hiT = np.ascontiguousarray(lo.T), np.ascontiguousarray(hi.T)
        out = np.empty((N, V))
        # a force-closed follower rests on its bound from the first sample (the
        # stated start only seats it): where that bound is not a candidate at
        # the first sample, it moves as the nominal does from the nominal's
        # own output there, not from the stated start (a disc cam drawn as two
        # arcs joined where the follower rests: a variant's contact there lies
        # on the arc that ends the drive, at the other end of the plan)
        f = np.full(V, plan.f0[0] if plan.bias else plan.start)
        if plan.bias:
            rest = loT if plan.bias < 0 else hiT
            ids = lo_id if plan.bias < 0 else hi_id
            nominal = plan.lower if plan.bias < 0 else plan.upper
            held = np.isfinite(rest)
            if ids is not None:
                held &= (np.ascontiguousarray(ids.T) >= 0) | (nominal < 0)[:, None]
            step = np.diff(plan.f0, prepend=plan.f0[:1])
        for i in range(N):
            if plan.bias:
                f = np.where(held[i], rest[i], f + step[i])
            np.maximum(f, loT[i], out=f)
            np.minimum(f, hiT[i], out=f)
            out[i] = f
        f = out.T
    f0 = plan.f0[None, :]
    with np.errstate(invalid="ignore"):
        dev = np.where(plan.is_ref[None, :], np.abs(f - f0), 0.0) / plan.scale2
    if not readings:
        return f, dev, None
    # beyond what the batch bounds sample by sample, the full test's reading
    # may differ by this much (:data:`DEV_FLOOR`)
    floor = DEV_FLOOR * band
    if N < 3:
        top = dev.max(axis=1) if N else np.zeros(V)
        return f, dev, (top - (band - floor), top + (band - floor))
    grid = _grid_readings(plan, f, dev, band, floor)
    if grid is not None:
        return f, dev, grid
    jump, h_lo, h_hi, err = _interpolated(plan, f, band, floor)
    with np.errstate(invalid="ignore"):
        d_lo = np.maximum(np.maximum(h_lo - f0, f0 - h_hi), 0.0) / plan.scale2
        d_hi = np.maximum(np.abs(h_lo - f0), np.abs(h_hi - f0)) / plan.scale2
    # at a jump the reading lies anywhere in [d_lo, d_hi], read with the whole
    # band; elsewhere within err of the output
    low = np.where(jump, d_lo - (band - floor), dev - err)
    high = np.where(jump, d_hi + (band - floor), dev + err)
    ref = plan.is_ref[None, :]
    least = np.max(np.where(ref, low, -math.inf), axis=1, initial=-math.inf)
    most = np.max(np.where(ref, high, 0.0), axis=1, initial=0.0)
    return f, dev, (least, most)


def _clamp_scan(lo, hi, start: float):
    """The follower of a form-closed pair, ``f[i] = min(max(f[i - 1], lo[i]),
    hi[i])`` from ``f[-1] = start``, per row of ``lo`` and ``hi`` (V, N; no
    NaN), the same numbers as that loop in far fewer interpreter steps.

    One step is a clamp ``x -> min(max(x, a), b)``, and clamps compose into
    clamps: after ``(a1, b1)``, ``(a2, b2)`` is the clamp by ``(clamp(a1),
    clamp(b1))`` of the second, for every x, infinities and ``a > b``
    included.  The samples are cut into blocks of about ``sqrt(N)``; the
    blocks' own clamps come first (all blocks at once, one step of each at a
    time), then the follower's place where each block begins (one block at a
    time), then every block's samples from there (all blocks at once).  A
    clamp only picks one of its numbers, so every value is one the loop
    would give, bit for bit."""
    V, N = lo.shape
    K = max(1, int(math.sqrt(N / 2.0)))
    nb = -(-N // K)
    pad = nb * K - N

    def blocks(a, fill):
        a = np.concatenate([a, np.full((V, pad), fill)], axis=1) if pad else a
        return np.ascontiguousarray(a.reshape(V, nb, K).transpose(2, 0, 1))   # (K, V, nb)

    L, H = blocks(lo, -math.inf), blocks(hi, math.inf)
    # each block's clamp (A, B), step by step (an empty clamp first: the
    # first step's own, (min(lo, hi), hi), clamps as it does)
    A = np.full((V, nb), -math.inf)
    B = np.full((V, nb), math.inf)
    for k in range(K):
        np.minimum(np.maximum(A, L[k], out=A), H[k], out=A)
        np.minimum(np.maximum(B, L[k], out=B), H[k], out=B)
    # where the follower enters each block
    g = np.empty((V, nb))
    f = np.full(V, float(start))
    for b in range(nb):
        g[:, b] = f
        np.minimum(np.maximum(f, A[:, b], out=f), B[:, b], out=f)
    out = np.empty((K, V, nb))
    for k in range(K):
        np.minimum(np.maximum(g, L[k], out=g), H[k], out=g)
        out[k] = g
    return out.transpose(1, 2, 0).reshape(V, nb * K)[:, :N]


def _grid_readings(plan: PathPlan, f, dev, band: float, floor: float):
    """:func:`_follow`'s reading range ``(least, most)`` where the drive's
    regular samples are known (:attr:`PathPlan.on_grid`, at least two): at
    the nominal's samples between regular ones (few) the reading's range of
    :func:`_between_regular`; at every other nominal sample the reading is
    the output (no jump, no error: ``low = dev - 0``, ``high = dev + 0``,
    the deviation itself, never -0), so those enter the maxima as the
    deviation.  The same numbers as the reduction of those arrays spread
    over every sample.  None where the regular samples are not known."""
    grid = np.nonzero(plan.on_grid)[0] if plan.on_grid is not None else np.zeros(0, int)
    if len(grid) < 2:
        return None
    K = np.nonzero(plan.is_ref & ~plan.on_grid)[0]
    rest = plan.is_ref.copy()
    rest[K] = False
    jump, h_lo, h_hi, err = _between_regular(plan, f, band, floor, grid, K)
    f0 = plan.f0[K][None, :]
    dk = dev[:, K]
    with np.errstate(invalid="ignore"):
        d_lo = np.maximum(np.maximum(h_lo - f0, f0 - h_hi), 0.0) / plan.scale2
        d_hi = np.maximum(np.abs(h_lo - f0), np.abs(h_hi - f0)) / plan.scale2
    low = np.where(jump, d_lo - (band - floor), dk - err)
    high = np.where(jump, d_hi + (band - floor), dk + err)
    dr = dev[:, rest]
    least = np.maximum(np.max(dr, axis=1, initial=-math.inf),
                       np.max(low, axis=1, initial=-math.inf))
    most = np.maximum(np.max(dr, axis=1, initial=0.0), np.max(high, axis=1, initial=0.0))
    return least, most


def _between_regular(plan: PathPlan, f, band: float, floor: float, grid, K) -> tuple:
    """At the nominal samples ``K`` that lie between the drive's regular
    samples ``grid``, which every variant has too (:attr:`PathPlan.on_grid`):
    where the full test's reading of the outputs ``f`` may differ from them
    by more than half the deviation ``band`` (``jump``), the range it lies in
    there (``low``, ``high``) and elsewhere how far from the output it may
    lie (``err``); (V, len(K)) each, C-space metric.

    The full test reads a variant's output at a nominal sample that is not
    one of the variant's own by linear interpolation between two of its own
    samples around it, which lie between the regular samples around the
    nominal one: where the output stays within ``b`` (at most half the band)
    of the chord between those, so does the reading (its ends lie within
    ``b`` of the chord, and the reading between them), and the reading lies
    within ``2 b`` of the output; elsewhere it lies between the smallest and
    largest output there.  Beyond the grid's ends: no jump, ``err`` the band
    less ``floor``, the range the output itself."""
    V = f.shape[0]
    jump = np.zeros((V, len(K)), dtype=bool)
    h_lo, h_hi = f[:, K], f[:, K]
    err = np.zeros((V, len(K)))
    for c, k in enumerate(K):
        g = np.searchsorted(grid, k)
        if g == 0 or g == len(grid):
            err[:, c] = band - floor
            continue
        a, b = grid[g - 1], grid[g]
        seg = f[:, a:b + 1]
        t = (plan.x[a:b + 1] - plan.x[a]) / (plan.x[b] - plan.x[a])
        with np.errstate(invalid="ignore"):
            chord = f[:, a:a + 1] + t[None, :] * (f[:, b:b + 1] - f[:, a:a + 1])
            bend = np.max(np.abs(seg - chord), axis=1) / plan.scale2
        jump[:, c] = ~(bend <= 0.5 * band)
        err[:, c] = np.where(jump[:, c], 0.0, 2.0 * bend)
        h_lo[:, c], h_hi[:, c] = seg.min(axis=1), seg.max(axis=1)
    return jump, h_lo, h_hi, err


def _interpolated(plan: PathPlan, f, band: float, floor: float = 0.0):
    """Where the drive's regular samples are not known (a sliding driver; with
    them, :func:`_grid_readings`): where the full test's reading of the
    outputs ``f`` (V, N) may differ from them by more than half the
    deviation ``band``, (V, N) bool, the range it lies in there (low, high;
    (V, N)), and elsewhere how far from the output it may lie (V, N),
    C-space metric.

    The full test reads a variant's output at a nominal sample that is not
    one of the variant's own by linear interpolation between two of its own
    samples around it.  Here the two plan samples next to it stand for the
    variant's: where the output bends at the sample by more than half the
    band, the reading lies between their outputs; elsewhere it is taken to
    lie within the band, less ``floor``, of the output (:func:`_follow`
    adds ``floor`` to every bound)."""
    V, N = f.shape
    jump = np.zeros((V, N), dtype=bool)
    x = plan.x
    with np.errstate(invalid="ignore"):
        t = (x[1:-1] - x[:-2]) / (x[2:] - x[:-2])
        bend = np.abs(f[:, 1:-1] - (f[:, :-2] + t * (f[:, 2:] - f[:, :-2]))) / plan.scale2
    jump[:, 1:-1] = ~(bend <= 0.5 * band)
    jump &= plan.is_ref[None, :]
    nb = np.stack([f, np.roll(f, 1, axis=1), np.roll(f, -1, axis=1)])
    return jump, nb.min(axis=0), nb.max(axis=0), np.full((V, N), band - floor)


def _born_across(plan: PathPlan, cs, env, f, gap: float):
    """The variants (V,) bool in whose channel a candidate contact begins on
    the far side of the follower while another bound still holds it: a
    contact above the channel that begins below the follower (inside the
    channel: its value at both samples around its beginning lies more than
    ``gap``, C-space metric, below the follower's place) while an upper bound
    of another contact lies within ``gap`` of that place at the next sample,
    or the mirror of that below.  Its blocked region then grows from the
    follower's other side and squeezes it against that bound, where the
    quasi-static rule of :func:`_follow` reads a bound that pushes the
    follower on (on a Geneva variant whose wheel the lock disk held 0.047 rad
    from the nominal's place, the pin met the slot's corner 2.4e-4 rad below
    the wheel's position: a jam, read as a push).  At a hand-over the new
    contact begins where the old one ends, at the follower, and the old bound
    is gone at the next sample, or still there beside it: a contact that at
    the next sample lies within ``gap`` of the other contacts' bound (where
    they take the follower) pushes the follower no farther than they do, and
    is no squeeze (the Geneva pair's own motion, and the variants near it,
    have one where the pin's contact passes between two segments of a slot
    that meet in line while the wheel turns fast: the new segment's value
    before its beginning lies 1.5e-4 rad below the wheel, its value at the
    next sample on the old segment's).  The full test decides them."""
    V = f.shape[0]
    out = np.zeros(V, dtype=bool)
    g = gap * plan.scale2
    found = []          # per flip that begins on the far side: its points
    for side, key, r, i, qa, qb, born in env.flips:
        fi, far = _born_far(env, f, g, side, r, i, qa, qb)
        sel = np.nonzero(born & far)[0]
        if len(sel):
            found.append((np.full(len(sel), side), np.full(len(sel), key), r[sel],
                          (i[sel] + 1).astype(float), fi[sel], qb[sel]))
    if not found:
        return out
    # the bounds of the other contacts at the next sample, every flip's points
    # in one pass (each point without its own contact's curve: the numbers a
    # pass of each flip's points alone over the other candidates gives)
    side, key, rr, pp, fi, qb = (np.concatenate(a) for a in zip(*found))
    lo_o, hi_o = _bounds_at(plan, cs, env.stacks, env.needed, rr, pp, skip=key)[6:8]
    out[rr[_held_by_other(side, lo_o, hi_o, fi, qb, g)]] = True
    return out


def _born_far(env, f, g, side, r, i, qa, qb):
    """Of one flip record (:attr:`Envelopes.flips`): the follower's place at
    its first sample, and where the contact lies on the far side of it there
    (by more than ``g``, follower coordinates) and inside the channel at the
    next sample."""
    with np.errstate(invalid="ignore"):
        fi = f[r, i]
        if side < 0:
            return fi, (np.maximum(qa, qb) < fi - g) & (qb > env.lo[r, i + 1])
        return fi, (np.minimum(qa, qb) > fi + g) & (qb < env.hi[r, i + 1])


def _held_by_other(side, lo_o, hi_o, fi, qb, g):
    """Where another contact's bound (``lo_o``, ``hi_o``) holds the follower
    within ``g`` of its place ``fi`` while the new contact's value ``qb`` lies
    more than ``g`` inside it (``side``: one per point, or one for all)."""
    with np.errstate(invalid="ignore"):
        return np.where(np.asarray(side) < 0, (hi_o <= fi + g) & (qb < hi_o - g),
                        (lo_o >= fi - g) & (qb > lo_o + g))


def _cut_by_reach(plan: PathPlan, cs, env: Envelopes):
    """The variants (V,) bool whose bound hands over from a curve that the
    batch did not evaluate on the other side of the hand-over, and that is
    still a contact there, beyond the bound the batch read.

    A candidate is evaluated where the plan expects a variant's contact: near
    the nominal's, within the plan's reach of driver motion.  A variant whose
    contact lasts beyond that (its events moved farther than the reach, under
    huge tolerances) is not evaluated there, and its bound falls to the next
    candidate as if the contact had ended: a hand-over the variant does not
    have (a Geneva variant of +-1 on a 50 mm centre distance read its lock
    arc's other branch, 0.8 rad below, for 0.03 rad, and a changed contact
    sequence).  So at each of a variant's hand-overs (those the nominal does
    not have at that sample) where the curve it leaves was not evaluated at
    the next sample, it is evaluated there: still real and beyond the bound
    read, or not placeable (no candidate sample there), and the variant is
    not certified."""
    V = env.lo_id.shape[0]
    out = np.zeros(V, dtype=bool)
    where: dict = {}
    for (c, side), (idx, nd) in env.needed.items():
        where.setdefault((int(plan.key[c]), side), []).append((c, idx, nd))
    bounds = {1: env.lo, -1: env.hi}
    for side, ids in ((1, env.lo_id), (-1, env.hi_id)):
        step = ids[:, 1:] != ids[:, :-1]
        # the nominal's own hand-overs are the plan's: the variants' at other
        # samples, or between other curves, are checked
        new = step & ((ids[:, 1:] != ids[:1, 1:]) | (ids[:, :-1] != ids[:1, :-1]))
        vv, ii = np.nonzero(new)
        keys = ids[vv, ii]
        # the hand-overs whose curve was evaluated at the next sample, found
        # per curve key at once: their ends are read as they are
        seen = keys < 0
        for a in np.unique(keys[keys >= 0]).tolist():
            sel = np.nonzero(keys == a)[0]
            for _, idx, nd in where.get((a, side), ()):
                p = np.minimum(np.searchsorted(idx, ii[sel] + 1), len(idx) - 1)
                seen[sel] |= (idx[p] == ii[sel] + 1) & nd[vv[sel], p]
        for v, i in zip(vv[~seen].tolist(), ii[~seen].tolist()):
            if out[v]:
                continue
            out[v] = _still_there(plan, cs, env, where.get((int(ids[v, i]), side), ()), v, i + 1,
                                  side, bounds[side][v, i + 1])
    return out


def _still_there(plan: PathPlan, cs, env: Envelopes, cands, v: int, j: int, side: int,
                 bound: float) -> bool:
    """Whether the curve of a key (its candidates ``cands``: ``(curve,
    samples, needed)``), which the batch did not evaluate for variant ``v``
    at sample ``j`` (:func:`_cut_by_reach`), may bound it there beyond
    ``bound``: real there and beyond the bound, or with no candidate sample
    there to place it at."""
    placeable = []
    for c, idx, _ in cands:
        p = int(np.searchsorted(idx, j))
        if p < len(idx) and idx[p] == j:
            placeable.append((c, p))
    if not placeable:
        return True
    for c, p in placeable:
        st = env.stacks[c].take(np.array([0, v]))
        with np.errstate(all="ignore"):
            q, m = st.branch(np.full((2, 1), plan.xw[j]), cs.curves[c].bi,
                             plan.window)
        if not m[1, 0] >= -VALID_TOL:
            continue
        val = q[1, 0]
        if plan.periodic2:
            val = plan.place[c, side][p] + float(wrap_pi(q[1, 0] - q[0, 0]))
        if (val > bound) if side > 0 else (val < bound):
            return True
    return False


def _gap(plan: PathPlan, lo, hi, lo_id, hi_id):
    """The channel margin (V,), where it is smallest (sample index), and the
    gap at every sample (V, N; -inf where a bound is missing): the smallest
    gap over the samples, refined by a parabola through its neighbours where
    the same two curves bound the channel at all three (a channel's narrowest
    point lies between samples)."""
    g = (hi - lo) / plan.scale2
    g = np.where(np.isnan(g), -math.inf, g)
    i = np.argmin(g, axis=1)
    V, N = g.shape
    rows = np.arange(V)
    best = g[rows, i]
    inner = (i > 0) & (i < N - 1) & np.isfinite(best)
    if inner.any():
        j = np.clip(i, 1, N - 2)
        for ids in (lo_id, hi_id):
            inner &= (ids[rows, j - 1] == ids[rows, j]) & (ids[rows, j + 1] == ids[rows, j])
    if inner.any():
        r = rows[inner]
        j = i[inner]
        x0, x1, x2 = plan.x[j - 1], plan.x[j], plan.x[j + 1]
        y0, y1, y2 = g[r, j - 1], g[r, j], g[r, j + 1]
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            d1 = (y1 - y0) / (x1 - x0)
            d2 = (y2 - y1) / (x2 - x1)
            a = (d2 - d1) / (x2 - x0)
            xm = 0.5 * (x0 + x1) - d1 / (2 * a)
            ym = y1 + d1 * (xm - x1) + a * (xm - x0) * (xm - x1)
        use = np.isfinite(ym) & (a > 0) & (xm > x0) & (xm < x2) & (ym < best[inner])
        best[inner] = np.where(use, ym, best[inner])
    return best, i, g


# ------------------------------------------------------------------ stage 4
def _handovers(plan: PathPlan, cs, env: Envelopes, res: float, rows=None) -> dict:
    """The bounds' curve ids between samples, read again where a variant's
    contacts begin, end or hand over.

    The plan samples the nominal motion at the simulation step (and at the
    nominal's events).  A variant's events move, and where one lands between
    two samples, a contact that lasts less than the sample step but more than
    the resolution ``res`` can come and go unseen between them: on a Geneva
    variant, the pin touched the corner of a lock arc and a slot for 0.003 rad
    (0.067 rad at nominal) between two samples 0.005 rad apart, where the lock
    arc handed over to the slot flank, and the samples read the sequence
    without it.  So, per
    variant, every sample interval over which the lower or upper bound changes
    curve, or a candidate that the variant can bring near its channel begins
    or ends (:func:`_ends`), is sampled again ``res / HANDOVER_STEPS`` apart
    with the candidates the variant evaluated at either end of the interval;
    then the ends of every run whose duration the samples leave undecided (the
    resolution between its shortest and longest extent) are sampled
    ``HANDOVER_SPLIT`` times finer, ``HANDOVER_LEVELS`` times at most.

    ``rows`` (V,) bool: only these rows (default all); a row's samples do
    not depend on the others'.

    An interval is split into :data:`HANDOVER_MAX` pieces at most: a
    resolution so fine (a tiny ``d``) that it would need more leaves the
    row's contact sequence unread between them (``capped``).

    Returns ``{row: (x, lo_id, hi_id, gap, at, capped)}`` for the rows
    sampled again (the plan's samples and the new ones, in drive order, the
    narrowest gap of the channel at the new samples (C-space metric) and
    where it lies: a variant's channel is often narrowest where its bounds
    hand over; and whether an interval was not split as finely as the
    resolution asks), and the number of curve evaluations."""
    N = plan.n
    lo_id, hi_id = env.lo_id, env.hi_id
    wanted = (np.ones(lo_id.shape[0], dtype=bool) if rows is None
              else np.asarray(rows, dtype=bool))
    step = np.abs(np.diff(plan.x)) / plan.scale1
    want = (lo_id[:, 1:] != lo_id[:, :-1]) | (hi_id[:, 1:] != hi_id[:, :-1]) | env.ends
    want &= (step[None, :] > res / HANDOVER_STEPS) & wanted[:, None]
    pr, ivl = np.nonzero(want)
    # per row: positions along the plan (sample i at i, between samples i and
    # i + 1 at i + t), and the lower and upper ids there
    state = {}
    narrow = {}
    n_eval = 0
    pr, pp, capped = _subdivide(pr, ivl.astype(float), np.ones(len(ivl)), step[ivl],
                                res / HANDOVER_STEPS, HANDOVER_MAX)
    base = np.arange(N, dtype=float)
    xbase = plan.x / plan.scale1
    xb = None           # the driver at the plan's samples, as _x_at reads it
    for level in range(HANDOVER_LEVELS + 1):
        if len(pr):
            lo_k, hi_k, t_lo, t_hi, gap, k = _bounds_at(plan, cs, env.stacks, env.needed, pr,
                                                        pp)[:6]
            n_eval += k
            gap = np.where(np.isnan(gap), -math.inf, gap)
            for v in np.unique(pr).tolist():
                sel = np.nonzero(pr == v)[0]
                j = sel[np.argmin(gap[sel])]
                if v not in narrow or gap[j] < narrow[v][0]:
                    narrow[v] = (float(gap[j]), float(_x_at(plan, pp[j:j + 1])[0]))
                if v in state:
                    old = state[v]
                else:
                    if xb is None:
                        xb = _x_at(plan, base)
                    old = (base, lo_id[v], hi_id[v], env.ties[0][v], env.ties[1][v], xb)
                new = pp[sel]
                state[v] = _inserted(old, new, (lo_k[sel], hi_k[sel], t_lo[sel], t_hi[sel],
                                                _x_at(plan, new)))
        if level == HANDOVER_LEVELS:
            break
        # the runs whose duration the samples leave undecided: their ends
        # sampled again, finer
        fine = res / HANDOVER_STEPS / HANDOVER_SPLIT ** (level + 1)
        todo = {}
        for v in np.nonzero(wanted)[0].tolist():
            if v in state:
                pos, lo_v, hi_v, tl, th, xv = state[v]
                lo_v, hi_v = _untied(lo_v, tl), _untied(hi_v, th)
                xv = xv / plan.scale1
            else:
                pos, lo_v, hi_v, xv = base, lo_id[v], hi_id[v], xbase
            for ids in (lo_v, hi_v):
                for k in _undecided(ids, xv, res):
                    w = abs(xv[k + 1] - xv[k])
                    if w > fine:
                        todo[v, pos[k]] = (pos[k + 1] - pos[k], w)
        if not todo:
            break
        (nr, na), (nw, ns) = zip(*todo.keys()), zip(*todo.values())
        pr, pp, more = _subdivide(np.array(nr), np.array(na), np.array(nw), np.array(ns), fine,
                                  HANDOVER_MAX)
        capped |= more
    out = {}
    for v, (pos, lo_v, hi_v, tl, th, xv) in state.items():
        out[v] = ((xv, _untied(lo_v, tl), _untied(hi_v, th)) + narrow[v] + (v in capped,))
    return out, n_eval


def _inserted(old, new, values) -> tuple:
    """A row's sampled positions ``old[0]`` (sorted) and the arrays along them
    (``old[1:]``) with the positions ``new`` and their ``values`` put in
    place: the arrays a stable sort of the concatenations gives (a new
    position equal to an old one comes after it, equal new ones in their
    order), by insertion."""
    o = np.argsort(new, kind="stable")
    new = new[o]
    at = np.searchsorted(old[0], new, side="right")
    return (np.insert(old[0], at, new),) + tuple(np.insert(a, at, b[o])
                                                 for a, b in zip(old[1:], values))


#: :func:`_handovers`: where a variant's bound changes curve, or a contact near
#: its channel begins or ends, between two samples farther apart than the
#: resolution over ``HANDOVER_STEPS``, the interval is sampled that fine (a
#: contact that lasts the resolution spans two samples); the ends of a run
#: whose duration is still undecided are sampled ``HANDOVER_SPLIT`` times
#: finer, ``HANDOVER_LEVELS`` times at most.
HANDOVER_STEPS = 1.25
HANDOVER_SPLIT = 8
HANDOVER_LEVELS = 2

#: :func:`_handovers`: the most pieces one interval is split into.  A
#: resolution that asks for more (a deviation threshold d of 1e-9 asked for
#: 1e9 pieces of a Geneva sample step, 54 GiB) leaves the variant's contact
#: sequence unread (its sequence margin at most 0): the full test decides
#: whether it is healthy.  The case studies' intervals need at most a few
#: dozen.
HANDOVER_MAX = 1024


def _subdivide(rows, a, wpos, wx, fine: float, cap: int | None = None):
    """Points splitting intervals (row, start position a, width wpos in plan
    positions, wx in driver motion) into pieces at most ``fine`` long, or
    into ``cap`` pieces where that would take more: their rows and positions,
    and the set of rows of the intervals split into ``cap`` pieces only."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        need = np.ceil(np.asarray(wx, dtype=float) / fine)
    over = np.zeros(need.shape, dtype=bool) if cap is None else ~(need <= cap)
    k = np.maximum(np.where(over, cap or 1, need), 1).astype(np.int64)
    capped = set(np.asarray(rows)[over].tolist())
    n = k - 1
    pr = np.repeat(rows, n)
    first = np.repeat(np.cumsum(n) - n, n)
    j = np.arange(len(pr)) - first + 1
    pp = np.repeat(a, n) + j / np.repeat(k, n) * np.repeat(wpos, n)
    return pr, pp, capped


def _x_at(plan: PathPlan, pos):
    """Driver value (unwrapped) at plan positions (sample i at i, linear between)."""
    i = np.minimum(np.floor(pos).astype(np.int64), plan.n - 2)
    return plan.x[i] + (pos - i) * (plan.x[i + 1] - plan.x[i])


def _untied(ids, tie):
    """``ids`` with :func:`_untie` applied at the tied samples."""
    if not tie.any():
        return ids
    out = ids[None, :].copy()
    _untie(out, tie[None, :])
    return out[0]


def _undecided(ids, x, res: float):
    """Sample intervals (index of the first sample) at the two ends of every run
    whose duration the samples cannot place on one side of ``res``."""
    n = len(ids)
    starts, ends, dmin, dmax = _run_spans(ids, x)
    out = []
    for s, e in zip(starts[(dmin < res) & (dmax >= res)], ends[(dmin < res) & (dmax >= res)]):
        if s > 0:
            out.append(int(s) - 1)
        if e < n:
            out.append(int(e) - 1)
    return out


def _bounds_at(plan: PathPlan, cs, stacks, needed, pr, pp, skip=None):
    """The channel's bound ids at points (rows pr, plan positions pp between
    samples), from the candidates the variant evaluated at either sample
    around each (``needed``, :class:`Envelopes`), where they tie with the
    runner-up, the channel's gap there (C-space metric), the number of curve
    evaluations, and the bounds (follower coordinates).  ``skip`` (per
    point, a curve key): that curve's candidates left out at that point."""
    N = plan.n
    pi = np.minimum(np.floor(pp).astype(np.int64), N - 2)
    px = _x_at(plan, pp)
    lo1, hi1 = plan.window[0], plan.window[1]
    pxw = (px - lo1) % (hi1 - lo1) + lo1 if cs.periodic[0] else px
    P = len(px)
    periodic2 = plan.periodic2
    lo = np.full(P, -math.inf if periodic2 else plan.window[2])
    hi = np.full(P, math.inf if periodic2 else plan.window[3])
    lo_k = np.full(P, -1, dtype=np.int32)
    hi_k = np.full(P, -1, dtype=np.int32)
    lo2 = np.full(P, -math.inf)
    hi2 = np.full(P, math.inf)
    jobs = _point_jobs(plan, needed, pr, pi, skip)
    n_eval = 0
    for (c, side, sel), (q, m, k) in zip(jobs, _point_values(plan, cs, stacks, jobs, pr, pp,
                                                             pxw)):
        n_eval += k
        valid = m >= -VALID_TOL
        key = plan.key[c]
        if side > 0:
            v = np.where(valid, q, -math.inf)
            cur = lo[sel]
            better = v > cur
            lo2[sel] = np.maximum(lo2[sel], np.minimum(cur, v))
            lo[sel] = np.where(better, v, cur)
            lo_k[sel] = np.where(better, key, lo_k[sel])
        else:
            v = np.where(valid, q, math.inf)
            cur = hi[sel]
            better = v < cur
            hi2[sel] = np.minimum(hi2[sel], np.maximum(cur, v))
            hi[sel] = np.where(better, v, cur)
            hi_k[sel] = np.where(better, key, hi_k[sel])
    with np.errstate(invalid="ignore"):
        return (lo_k, hi_k, (lo - lo2) / plan.scale2 <= TIE, (hi2 - hi) / plan.scale2 <= TIE,
                (hi - lo) / plan.scale2, n_eval, lo, hi)


def _point_jobs(plan: PathPlan, needed, pr, pi, skip=None) -> list:
    """Per candidate of ``needed`` (in its order) that a point's variant
    evaluated at either sample around it (plan samples ``pi`` and
    ``pi + 1``), unless ``skip`` names its curve key at that point:
    ``(curve, side, the points' places)``."""
    col = np.full(plan.n + 1, -1, dtype=np.int64)
    # the points in order of their sample: a candidate's samples span a
    # stretch of the drive, and only the points in it are looked at
    order = np.argsort(pi, kind="stable")
    spi = pi[order]
    jobs = []
    items = [(key, v) for key, v in needed.items() if len(v[0])]
    # a point between samples i and i + 1 needs i or i + 1 among them: the
    # points of each candidate's stretch, every candidate's at once
    ends = np.array([(v[0][0], v[0][-1]) for _, v in items], dtype=np.int64).reshape(-1, 2)
    los = np.searchsorted(spi, ends[:, 0] - 1, side="left").tolist()
    his = np.searchsorted(spi, ends[:, 1], side="right").tolist()
    for ((c, side), (idx, nd)), lo, hi in zip(items, los, his):
        if lo >= hi:
            continue
        near = order[lo:hi]
        # column of each plan sample in the candidate's samples (-1: not among them)
        col[idx] = np.arange(len(idx))
        a, b = col[pi[near]], col[pi[near] + 1]
        col[idx] = -1
        hit = (a >= 0) | (b >= 0)
        if not hit.any():
            continue
        k = np.nonzero(hit)[0]
        sel = near[k]
        at_i = (a[k] >= 0) & nd[pr[sel], np.maximum(a[k], 0)]
        at_j = (b[k] >= 0) & nd[pr[sel], np.maximum(b[k], 0)]
        keep = at_i | at_j
        if skip is not None:
            keep &= skip[sel] != plan.key[c]
        if keep.any():
            # the points' places in increasing order, as a scan of them all gives
            jobs.append((c, side, np.sort(sel[keep])))
    return jobs


def _point_values(plan: PathPlan, cs, stacks, jobs, pr, pp, pxw) -> list:
    """Per job of :func:`_point_jobs`, the curve's values ``(q, m)`` at its
    points (q placed as at the plan's samples, :attr:`PathPlan.place`) and
    the number of curve evaluations.

    Jobs whose curves share a contact equation (type, owner, feature kinds,
    branch and the convexity flags the kernel reads from its first row) are
    evaluated in one kernel call: every value is computed from its own
    constants and driver value alone, so each is the number a call of its
    own gives, at one call's cost instead of many (a hand-over pass
    evaluates some hundred candidates at a few points each).  The placing
    of every job's values is elementwise too, and done for all jobs at
    once."""
    from .kernels import _CONVEX
    periodic2 = plan.periodic2
    calls: dict = {}      # signature -> [(job number, rows, driver values)]
    if periodic2:
        # placed as at the plan's samples (PathPlan.place): the nominal
        # value on its turn beside the nominal channel, and the variant's
        # by its difference from it; a curve can turn by half a turn
        # between two samples (a vertex passing near the follower's axis).
        # The nominal row's values at each job's distinct points (np.unique
        # of its positions: sorted, the first of equal ones) go in the same
        # call.
        lens = np.array([len(sel) for _, _, sel in jobs], dtype=np.int64)
        job = np.repeat(np.arange(len(jobs)), lens)
        every = np.concatenate([sel for _, _, sel in jobs]) if len(jobs) else \
            np.zeros(0, dtype=np.int64)
        pos = pp[every]
        order = np.lexsort((pos, job))
        sp, sj = pos[order], job[order]
        new = np.ones(len(order), dtype=bool)
        new[1:] = (sp[1:] != sp[:-1]) | (sj[1:] != sj[:-1])
        uid = np.cumsum(new) - 1
        inv_all = np.empty(len(order), dtype=np.int64)
        inv_all[order] = uid
        u_all, u_job, u_first = sp[new], sj[new], every[order[new]]
        n_u = np.bincount(u_job, minlength=len(jobs))
        u_off = np.concatenate([[0], np.cumsum(n_u)])
        e_off = np.concatenate([[0], np.cumsum(lens)])
    for j, (c, side, sel) in enumerate(jobs):
        st = stacks[c]
        rows = pr[sel]
        x = pxw[sel]
        if periodic2:
            a, b = u_off[j], u_off[j + 1]
            rows = np.concatenate([rows, np.zeros(b - a, dtype=np.int64)])
            x = np.concatenate([x, pxw[u_first[a:b]]])
        r0 = rows[0]
        sig = (st.eq, st.owner, st.fp_kind, st.ft_kind, cs.curves[c].bi,
               float(st.fp[r0, _CONVEX]), float(st.ft[r0, _CONVEX]))
        calls.setdefault(sig, []).append((j, rows, x))
    out: list = [None] * len(jobs)
    for group in calls.values():
        first = stacks[jobs[group[0][0]][0]]
        stack = first.from_packed(np.concatenate([stacks[jobs[j][0]].packed[rows]
                                                  for j, rows, _ in group]))
        x = np.concatenate([x for _, _, x in group])
        qq, mm = stack.branch(x[:, None], cs.curves[jobs[group[0][0]][0]].bi, plan.window)
        a = 0
        for j, rows, _ in group:
            out[j] = (qq[a:a + len(rows), 0], mm[a:a + len(rows), 0], len(rows))
            a += len(rows)
    if not periodic2 or not len(jobs):
        return out
    # every job's points and the nominal's at its distinct ones, in job order
    q_all = np.concatenate([out[j][0][:lens[j]] for j in range(len(jobs))])
    q0_all = np.concatenate([out[j][0][lens[j]:] for j in range(len(jobs))])
    sides = np.array([side for _, side, _ in jobs])[u_job]
    p0 = placed_on_turn(q0_all, _at(plan.lo0, u_all), _at(plan.hi0, u_all), _at(plan.f0, u_all),
                        sides)
    placed = p0[inv_all] + wrap_pi(q_all - q0_all[inv_all])
    for j in range(len(jobs)):
        out[j] = (placed[e_off[j]:e_off[j + 1]], out[j][1][:lens[j]], out[j][2])
    return out


def _at(v, pos):
    """Plan values ``v`` (N,) at plan positions, linear between samples (an
    infinite end gives its infinity)."""
    i = np.minimum(np.floor(pos).astype(np.int64), len(v) - 2)
    a, b = v[i], v[i + 1]
    with np.errstate(invalid="ignore"):
        out = a + (pos - i) * (b - a)
    return np.where(np.isfinite(a) & np.isfinite(b), out, np.where(np.isfinite(a), b, a))


def _run_spans(ids, x):
    """The runs of one sample row of curve ids: first sample, end (one past the
    last), and the shortest and longest duration each run can have (driver
    motion) given where the samples lie: from its first to its last sample, or
    from the sample before it to the sample after it."""
    n = len(ids)
    cut = np.nonzero(np.diff(ids))[0] + 1
    starts = np.concatenate([[0], cut])
    ends = np.concatenate([cut, [n]])
    dmin = np.abs(x[ends - 1] - x[starts])
    dmax = np.abs(x[np.minimum(ends, n - 1)] - x[np.maximum(starts - 1, 0)])
    return starts, ends, dmin, dmax


def _runs(ids, x, cyclic: bool = False):
    """Run-length form of one sample row of curve ids: ids, and the shortest
    and longest duration each run can have (:func:`_run_spans`).  With
    ``cyclic`` (:attr:`PathPlan.cyclic`) the run the row ends with, when it
    is the curve of the first, is the first run's (their durations added):
    the motion goes on from its end where it started."""
    starts, _, dmin, dmax = _run_spans(ids, x)
    rid = ids[starts]
    if cyclic and len(rid) > 1 and rid[0] == rid[-1]:
        last_min, last_max = dmin[-1], dmax[-1]
        rid, dmin, dmax = rid[:-1], dmin[:-1].copy(), dmax[:-1].copy()
        dmin[0] += last_min
        dmax[0] += last_max
    return rid, dmin, dmax


def _merged(ids):
    out = []
    for v in ids:
        if not out or out[-1] != v:
            out.append(int(v))
    return out


def _readings(ids, dmin, dmax, res, cyclic: bool = False):
    """The contact sequence with the runs surely shorter than ``res``
    contracted, read with the ambiguous runs (those that may be shorter or
    longer) kept and dropped; and the sequence's margin: how far the runs lie
    from ``res`` (>= 0 when nothing is ambiguous).  With ``cyclic`` the
    sequences are cycles, in the form :func:`cspace.match.cycle_form` gives
    (two are the same cycle exactly when their forms are equal)."""
    short = dmax < res
    amb = ~short & (dmin < res)
    keep = _merged(ids[~short])
    drop = _merged(ids[~short & ~amb])
    if cyclic:
        keep, drop = list(cycle_form(keep)), list(cycle_form(drop))
    m_long = float(np.min(dmin[~short] - res)) if (~short).any() else res
    m_short = float(np.min(res - dmax[short])) if short.any() else res
    return keep, drop, min(m_long, m_short, res)


def _sequence_margin(plan: PathPlan, ids, res: float, extra=None, changes=None) -> np.ndarray:
    """Sequence margin (V,) of one bound (lower or upper ids, (V, N)): the
    distance of the closest run from the resolution when the variant's
    contact sequence is surely the nominal's; -res when it surely is not,
    0 when the samples cannot tell.  ``extra``: ``{row: (x, ids)}``, the
    rows read on more samples (:func:`_handovers`).  A motion that ends
    where it starts (:attr:`PathPlan.cyclic`) has its sequences compared as
    cycles.  ``changes`` (a dict): filled, for each row whose sequence surely
    differs, with where it first leaves the nominal's
    (:func:`_first_change`)."""
    V = ids.shape[0]
    extra = extra or {}
    x = plan.x / plan.scale1

    def row(v):
        if v in extra:
            xv, iv = extra[v]
            return _runs(iv, xv / plan.scale1, plan.cyclic)
        return _runs(ids[v], x, plan.cyclic)

    nid, nmin, nmax = row(0)
    nkeep, ndrop, nm = _readings(nid, nmin, nmax, res, plan.cyclic)
    out = np.full(V, min(nm, res))
    same = (ids == ids[:1]).all(axis=1)
    same[list(extra)] = False
    for v in np.nonzero(~same)[0]:
        vid, vmin, vmax = row(v)
        keep, drop, m = _readings(vid, vmin, vmax, res, plan.cyclic)
        if keep == drop == nkeep == ndrop:
            out[v] = min(m, nm)
        elif {tuple(keep), tuple(drop)}.isdisjoint({tuple(nkeep), tuple(ndrop)}):
            out[v] = -res
            if changes is not None:
                xv, iv = extra[v] if v in extra else (plan.x, ids[v])
                changes[v] = _first_change(np.asarray(iv), np.asarray(xv), ids[0], plan.x,
                                           nkeep, res * plan.scale1, plan.cyclic)
        else:
            out[v] = 0.0
    if not nkeep == ndrop:
        out[:] = np.minimum(out, 0.0)
    # a variant with no bound where the nominal has a contact curve: a
    # contact the plan's candidates cannot place (its events moved beyond the
    # plan's reach, under huge tolerances), or none; the samples cannot tell
    lost = ((ids < 0) & (ids[:1] >= 0)).any(axis=1)
    if not (ids[0] < 0).any():
        # read on more samples: where the nominal has a bound all along
        for v, (_, iv) in extra.items():
            lost[v] |= bool((np.asarray(iv) < 0).any())
    out[lost] = np.minimum(out[lost], 0.0)
    return out


def _first_change(ids, x, ids0, x0, nkeep, res: float, cyclic: bool) -> tuple:
    """Where a variant's contact sequence (one bound's curve keys ``ids`` at
    driver values ``x``) first leaves the nominal's (``nkeep``, contracted;
    the nominal's keys ``ids0`` at ``x0``): ``(x, key, nominal key)``, the
    driver value where its first run that the nominal's sequence does not
    have begins (a curve the nominal's does not have, or one that does not
    follow the one before it there), its curve key and the nominal's contact
    there (the one that follows the run before it in the nominal's sequence,
    else the nominal's bound at that place); ``(nan, -1, -1)`` when no run
    stands out (the runs differ only in how they repeat)."""
    starts, _, _, dmax = _run_spans(ids, x)
    kept = starts[dmax >= res]
    rid, at = [], []
    for i in kept.tolist():
        if not rid or rid[-1] != ids[i]:
            rid.append(int(ids[i]))
            at.append(float(x[i]))
    follows = set(zip(nkeep[:-1], nkeep[1:]))
    if cyclic and len(nkeep) > 1:
        follows.add((nkeep[-1], nkeep[0]))
    known = set(nkeep)
    for k, key in enumerate(rid):
        before = rid[k - 1] if k else (rid[-1] if cyclic and len(rid) > 1 else None)
        if key not in known or (before is not None and (before, key) not in follows):
            nxt = [b for a, b in follows if a == before] if before is not None else []
            if len(nxt) == 1:
                return at[k], key, int(nxt[0])
            j = min(int(np.searchsorted(x0, at[k])), len(x0) - 1)
            return at[k], key, int(ids0[j])
    return math.nan, -1, -1


# ------------------------------------------------------------------ stage 5
def _certify(channel, sequence, ok, bad, band_gap, dev_healthy, dev_defective):
    """Verdict codes (V,): HEALTHY, DEFECTIVE or UNCERTAIN.

    Defective needs only the channel's bounds, which the candidate curves give
    whatever else changed: a channel closed by more than the band, or an output
    off by more than d plus the band.  Healthy needs more: the channel open
    and the output within d by more than the bands, and the contact sequence
    surely the nominal's.  A contact sequence that surely differs along a
    channel open all the way is defective too (read with every hand-over of
    the variant sampled finely, :func:`_handovers`).  ``dev_healthy`` and
    ``dev_defective`` (V,): the full test's reading of the largest deviation
    surely within d, surely beyond it (:func:`_follow`); neither: the
    deviation decides nothing (the channel and the contact sequence still
    do)."""
    V = len(ok)
    out = np.full(V, UNCERTAIN, dtype=np.int8)
    shut = (channel <= -band_gap).any(axis=1)
    open_ = (channel >= band_gap).all(axis=1)
    same = (sequence > 0).all(axis=1)
    changed = (sequence < 0).any(axis=1)
    out[ok & open_ & same & dev_healthy] = HEALTHY
    out[ok & open_ & changed] = DEFECTIVE
    out[ok & dev_defective] = DEFECTIVE
    out[ok & shut] = DEFECTIVE
    out[bad] = DEFECTIVE
    return out


# ------------------------------------------------------------------ main
#: Variants evaluated together (with the nominal) in one pass of array
#: operations: large enough to amortise the interpreter over the (variants x
#: samples) arrays, and to let rows that share a curve's constants share its
#: evaluation (:class:`_Distinct`), small enough that those arrays stay
#: within tens of MB.  On the Geneva pair's check list (``fast``) 128 takes
#: about a third less time per vector than 32 (``docs/BENCHMARKS.md``).
CHUNK = 128


def _chunk(model, U, ref, plans, names, handovers=True):
    """Margins of one chunk of variants: per-variant arrays (the nominal row
    first).  Without ``handovers`` (a bool, or one per row of ``U``), the
    channel and sequence margins, which the per-variant hand-over samples
    complete, are NaN (the deviation and start margins do not read them)."""
    d = ref.d
    P = len(plans)
    pairs, bad, msgs, changed = _chunk_rows(model, U, ref)
    V = len(bad)
    if isinstance(handovers, (bool, np.bool_)):
        hrows = np.full(V, bool(handovers))
    else:
        hrows = np.concatenate([[False], np.asarray(handovers, dtype=bool)])
        hrows[0] = hrows[1:].any()
    out = {"channel": np.zeros((V, P)), "sequence": np.zeros((V, P)), "maxdev": np.zeros(V),
           "start": np.full((V, P), math.inf),
           "where_dev": np.zeros((V, 3)), "where_gap": np.zeros((V, P)), "bad": bad,
           "msgs": msgs, "evals": 0, "handover_samples": 0, "seq_change": {}}
    ok = ~bad
    # where the full test's reading of the largest deviation lies (all pairs)
    read_lo, read_hi = np.zeros(V), np.zeros(V)
    res = _resolution(d)
    for plan, cs, row in zip(plans, ref.spaces, pairs):
        table = feature_table(row)
        env = _envelopes(plan, cs, table, changed, _dependency_columns(cs, names))
        lo, hi, lo_id, hi_id = env.lo, env.hi, env.lo_id, env.hi_id
        out["evals"] += env.n_eval
        ok &= env.ok & table.present.all(axis=1)
        gap, gi, g = _gap(plan, lo, hi, lo_id, hi_id)
        out["channel"][:, plan.pair] = gap
        # where the drive meets the jam: the first sample, in drive order,
        # where the channel is closed (as the full test's motion stops
        # there), else where it is narrowest
        first = _first_closed(g, ref.accuracy.batch_gap_band)
        out["where_gap"][:, plan.pair] = plan.x[np.where(first >= 0, first, gi)]
        _start_margin(plan, lo, hi, out)
        f, dev, (least, most) = _follow(plan, lo, hi, lo_id, hi_id,
                                        ref.accuracy.batch_dev_band * d)
        read_lo, read_hi = np.maximum(read_lo, least), np.maximum(read_hi, most)
        ok &= ~_born_across(plan, cs, env, f, ref.accuracy.batch_gap_band)
        ok &= ~_cut_by_reach(plan, cs, env)
        ok &= ~_near_contacts(ref, plan.pair, U, row)
        di = np.argmax(dev, axis=1)
        rows = np.arange(V)
        dm = dev[rows, di]
        upd = dm > out["maxdev"]
        out["maxdev"] = np.where(upd, dm, out["maxdev"])
        out["where_dev"][upd] = np.stack([np.full(V, plan.pair), plan.x[di], f[rows, di]],
                                         axis=1)[upd]
        # the nominal row must reproduce the nominal: its own channel open;
        # otherwise the plan cannot certify anything; nor can a plan not
        # sampled as finely as the resolution asks (a tiny d)
        if not (gap[0] > 0 and np.isfinite(gap[0])) or not plan.resolved:
            ok[:] = False
        if not hrows.any():
            out["channel"][:, plan.pair] = math.nan
            out["sequence"][:, plan.pair] = math.nan
            continue
        ho, n_eval = _chunk_handovers(ref, plan, cs, env, res, hrows)
        out["evals"] += n_eval
        for v, h in ho.items():
            if h[3] < out["channel"][v, plan.pair]:
                out["channel"][v, plan.pair] = h[3]
                if first[v] < 0:
                    # closed only between samples: where it is narrowest
                    out["where_gap"][v, plan.pair] = h[4]
        below, above = {}, {}
        out["sequence"][:, plan.pair] = np.minimum(
            _sequence_margin(plan, lo_id, res, {v: (h[0], h[1]) for v, h in ho.items()}, below),
            _sequence_margin(plan, hi_id, res, {v: (h[0], h[2]) for v, h in ho.items()}, above))
        _named_changes(out["seq_change"], plan, cs, below, above)
        # a row not sampled as finely as the resolution asks: its sequence
        # may have contacts the samples missed (a surely changed one stays so)
        unread = [v for v, h in ho.items() if h[5]]
        out["sequence"][unread, plan.pair] = np.minimum(out["sequence"][unread, plan.pair], 0.0)
        # (the variants' own: the nominal row of every chunk left out)
        out["handover_samples"] += sum(len(h[0]) - plan.n for v, h in ho.items() if v > 0)
        out["channel"][~hrows, plan.pair] = math.nan
        out["sequence"][~hrows, plan.pair] = math.nan
    out["ok"] = ok & ~bad
    _unbuilt(out, bad)
    floor = DEV_FLOOR * ref.accuracy.batch_dev_band * d
    with np.errstate(invalid="ignore"):
        out["dev_healthy"] = read_hi <= d - floor
        out["dev_defective"] = read_lo >= d + floor
    return out


def _near_contacts(ref, pair: int, U, row) -> np.ndarray:
    """(V,) bool, the nominal row first: the variants that may touch with a
    feature pair the nominal's C-space has no curve for
    (:func:`cspace.near.touching`); the full test decides them."""
    near = getattr(ref, "near", ())
    if not near or not len(near[pair]):
        return np.zeros(len(U) + 1, dtype=bool)
    from ..near import touching
    return touching(near[pair], np.vstack([ref.nominal, U]), ref.nominal, row)


def _named_changes(found: dict, plan: PathPlan, cs, below: dict, above: dict) -> None:
    """Per row, where its contact sequence on pair ``plan.pair`` first leaves
    the nominal's (:func:`_first_change`), named: ``found[row][pair] = (q1,
    its text, side, curve label, nominal's label)``; side ``"below"`` or
    ``"above"`` the follower, below when both differ, as the full test reads
    them; label "" for none."""
    from ..defects import _q1_text
    label = {}
    for c, k in zip(cs.curves, plan.key.tolist()):
        label.setdefault(int(k), c.label)
    for v in set(below) | set(above):
        opts = [(ch, side) for ch, side in ((below.get(v), "below"), (above.get(v), "above"))
                if ch is not None and not math.isnan(ch[0])]
        if not opts:
            continue
        (x, key, key0), side = opts[0]
        found.setdefault(v, {})[plan.pair] = (x, _q1_text(cs, x), side, label.get(key, ""),
                                              label.get(key0, ""))


def _chunk_rows(model, U, ref) -> tuple:
    """A chunk's variants with the nominal's first: their pairs, the
    unbuildable ones and why (:func:`_build`), and which parameters of each
    differ from the nominal's."""
    Ub = np.vstack([ref.nominal, U])
    pairs, bad, msgs = _build(model, Ub)
    if bad[0]:
        from ..errors import InputError
        raise InputError("the reference's nominal vector does not build", name="ref")
    from ..defects import check_reference
    check_reference(model, ref, [row[0] for row in pairs])
    return pairs, bad, msgs, Ub != Ub[:1]


def _chunk_handovers(ref, plan: PathPlan, cs, env: Envelopes, res: float, hrows) -> tuple:
    """:func:`_handovers` of the rows ``hrows`` of a chunk, the nominal row's
    (row 0, the same in every chunk: its curves, needs and ends are the
    nominal's) computed once per Reference and pair and kept on it."""
    rows = hrows.copy()
    rows[0] = False
    ho, n_eval = _handovers(plan, cs, env, res, rows=rows) if rows.any() else ({}, 0)
    if hrows[0]:
        kept = ref.__dict__.setdefault("_nominal_handovers", {})
        if plan.pair not in kept:
            only = np.zeros(len(hrows), dtype=bool)
            only[0] = True
            h0, n0 = _handovers(plan, cs, env, res, rows=only)
            kept[plan.pair] = (h0.get(0), n0)
        h0, n0 = kept[plan.pair]
        if h0 is not None:
            ho[0] = h0
        n_eval += n0
    return ho, n_eval


def _lean_chunk(model, U, ref, plans, names):
    """The deviation and start margins of one chunk of variants, the numbers
    :func:`_chunk` gives them, without what only the verdicts and the channel
    and sequence margins read (the bounds' runners-up and ties, where each
    candidate was evaluated and where it begins or ends, the full test's
    reading range): per-variant arrays, the nominal row first; channel and
    sequence NaN."""
    P = len(plans)
    pairs, bad, _, changed = _chunk_rows(model, U, ref)
    V = len(bad)
    out = {"channel": np.full((V, P), math.nan), "sequence": np.full((V, P), math.nan),
           "maxdev": np.zeros(V), "start": np.full((V, P), math.inf)}
    rows = np.arange(V)
    for plan, cs, row in zip(plans, ref.spaces, pairs):
        # a force-closed follower rests on its bound's curve, read with ties
        env = _envelopes(plan, cs, feature_table(row), changed, _dependency_columns(cs, names),
                         lean=not plan.bias)
        _start_margin(plan, env.lo, env.hi, out)
        dev = _follow(plan, env.lo, env.hi, env.lo_id, env.hi_id, readings=False)[1]
        dm = dev[rows, np.argmax(dev, axis=1)]
        out["maxdev"] = np.where(dm > out["maxdev"], dm, out["maxdev"])
    _unbuilt(out, bad)
    return out


def _unbuilt(out, bad) -> None:
    """No margins for the rows that do not build: their pairs were stood in
    for by the nominal's so that the chunk's arrays keep their shape (the
    numbers computed for them are the nominal's, not theirs)."""
    if bad.any():
        for kind in ("channel", "sequence", "start", "maxdev"):
            out[kind][bad] = math.nan


#: :func:`margin_tables`: variants per lean chunk (no hand-over rows).  A
#: batched call costs some 70 ms (Geneva, ``fast``) before its rows, the walk
#: over the candidate curves; a lean row costs less than half a full one, so
#: that walk weighs twice as much on it.  On the finite-difference steps of
#: the Geneva pair (``benchmarks/bench_batch.py``), 256 rows a chunk took
#: 16 % (``fast``) and 23 % (``default``) less time per row than 128, and 512
#: more (the arrays of a chunk outgrow the caches).
LEAN_CHUNK = 256


def margin_tables(model, U, ref, handover_rows=None, chunk: int = CHUNK,
                  lean_chunk: int = LEAN_CHUNK) -> dict:
    """The margins of :func:`defect_margins`, the same numbers, without the
    verdicts: what the finite-difference steps of
    :func:`synthesis.minimal.margin_sensitivities` read.

    Parameters
    ----------
    model, U, ref
        As for :func:`defect_margins` (``U`` (n, p) finite).
    handover_rows : (n,) bool, optional
        The rows whose channel and sequence margins are wanted (default
        all); the others' are NaN.  Those are evaluated apart from these,
        in lean chunks (:func:`_lean_chunk`); these as :func:`defect_margins`
        evaluates them.
    chunk : int
        Rows with hand-overs evaluated together; the numbers do not depend
        on it.
    lean_chunk : int
        Rows without them evaluated together (default :data:`LEAN_CHUNK`);
        the numbers do not depend on it.

    Returns
    -------
    dict
        ``"channel"``, ``"sequence"``, ``"start"``: (n, P) arrays;
        ``"deviation"``: (n,).
    """
    heap.keep()
    _checked_reference(model, ref)
    U, chunk = _checked_rows(U, ref, model), _checked_chunk(chunk)
    lean_chunk = _checked_chunk(lean_chunk, "lean_chunk")
    n = len(U)
    hrows = (np.ones(n, dtype=bool) if handover_rows is None
             else _checked_handover_rows(handover_rows, n))
    plans = plans_of(ref)
    names = list(model.names)
    P = len(plans)
    tabs = {"channel": np.zeros((n, P)), "sequence": np.zeros((n, P)),
            "deviation": np.zeros(n), "start": np.zeros((n, P))}
    # a row's numbers do not depend on the others in its chunk: the rows
    # with hand-overs in chunks of their own, the others in lean ones
    for full, size in ((True, chunk), (False, lean_chunk)):
        rows = np.nonzero(hrows == full)[0]
        for a in range(0, len(rows), size):
            r = rows[a:a + size]
            data = (_chunk(model, U[r], ref, plans, names) if full
                    else _lean_chunk(model, U[r], ref, plans, names))
            for kind in ("channel", "sequence", "start"):
                tabs[kind][r] = data[kind][1:]
            tabs["deviation"][r] = ref.d - data["maxdev"][1:]
    return tabs


def _first_closed(g, band: float):
    """Per variant, the first plan sample (drive order) where its channel's
    gap ``g`` (:func:`_gap`) is closed by more than ``band`` (C-space
    metric), or -1."""
    closed = ~(g > -band)
    first = np.argmax(closed, axis=1)
    return np.where(closed[np.arange(len(first)), first], first, -1)


def _start_margin(plan: PathPlan, lo, hi, out) -> None:
    """The start margin of ``plan``'s pair (:class:`MarginBatch`, ``start``):
    the stated start's distance to the nearer bound of the variant's channel
    at the drive's start (C-space metric; negative outside, where
    :func:`_follow` starts the follower on the bound, as the full test
    assembles it).  A force-closed follower rests on its bias-side bound
    either way."""
    sm = np.minimum(plan.start - lo[:, 0], hi[:, 0] - plan.start) / plan.scale2
    out["start"][:, plan.pair] = np.where(np.isnan(sm), -math.inf, sm)


def _dependency_columns(cs, names) -> dict:
    """Per curve, the columns of the parameters its equation depends on."""
    return {c: np.array([names.index(nm) for nm in curve.depends if nm in names], dtype=int)
            for c, curve in enumerate(cs.curves)}


def _result(code, v, data, d, band_gap):
    """The DefectResult of a certified variant (row v of the chunk data)."""
    from ..defects import DefectResult, Reason
    if data["bad"][v]:
        return DefectResult(True, (Reason.INVALID,), math.inf, d, None, (), (), data["msgs"][v])
    md = float(data["maxdev"][v])
    if code == HEALTHY:
        return DefectResult(False, (), md, d, None, (), (), "healthy")
    ch = data["channel"][v]
    p = int(np.argmin(ch))
    if ch[p] <= -band_gap:
        q1 = float(data["where_gap"][v, p])
        return DefectResult(True, (Reason.TOPOLOGY, Reason.JAM), md, d, (p, q1, float("nan")),
                            (), (), f"pair {p}: the channel closes at about q1 = {q1:.5g} "
                                    f"(narrowest gap {ch[p]:.3g})")
    if data["dev_defective"][v]:
        w = data["where_dev"][v]
        return DefectResult(True, (Reason.DEVIATION,), md, d,
                            (int(w[0]), float(w[1]), float(w[2])), (), (),
                            f"output deviates by {md:.4g} > d = {d:.4g} (C-space "
                            f"metric)")
    sq = data["sequence"][v]
    ps = int(np.argmin(sq))
    ch = data["seq_change"].get(v, {}).get(ps)
    if ch is None:
        return DefectResult(True, (Reason.TOPOLOGY,), md, d, (ps, float("nan"), float("nan")),
                            (), (), f"pair {ps}: the contact sequence along the motion changed")
    x, text, side, new, old = ch
    from ..match import contact_name
    return DefectResult(True, (Reason.TOPOLOGY,), md, d, (ps, float(x), float("nan")), (), (),
                        f"pair {ps}: the contact sequence along the motion changed at about "
                        f"q1 = {text} ({side} the follower: {contact_name(new)} where the "
                        f"nominal's is {contact_name(old)})")


#: The margins of a :class:`MarginBatch`.
KINDS = ("channel", "sequence", "deviation", "start")


def defect_margins(model, U, ref, *, fallback: bool = True, executor=None,
                   chunk: int = CHUNK, kinds=KINDS, handover_rows=None) -> MarginBatch:
    """Verdicts and signed margins of a batch of variants (see module docstring).

    Parameters
    ----------
    model : parametric model
        The design whose Reference ``ref`` is (its ``build``, ``dependencies``).
    U : (n, p) float
        Parameter vectors (model units).
    ref : cspace.defects.Reference
        Nominal data the variants are compared with.
    fallback : bool
        Run the full test on the uncertain variants (default).  Without it,
        their ``defective`` is the batch's best guess (some margin <= 0) and
        ``fallback`` is all False.
    executor : concurrent.futures.Executor, optional
        Runs the fall-back tests (default: in this process).
    chunk : int
        Variants evaluated together; results do not depend on it.
    kinds : iterable of str
        The margins wanted (default all, :data:`KINDS`).  Without
        ``"channel"`` and ``"sequence"`` the per-variant hand-over samples
        (:func:`_handovers`, about a third of the time) are skipped and those
        margins are NaN; the others are the same numbers.  Only a deviation
        beyond the band is then certified (a verdict needs every margin
        otherwise), the rest is uncertain.
    handover_rows : (n,) bool, optional
        With every kind wanted: the rows whose channel and sequence margins
        are wanted; the others are treated as with ``kinds`` without those
        (their hand-over samples skipped, their channel and sequence NaN).
        A caller that needs them for some rows only (the finite-difference
        steps of :func:`synthesis.minimal.margin_sensitivities`) tests all
        its rows in one call.  Every row's numbers are those of a call for
        it alone.

    Returns
    -------
    MarginBatch
    """
    heap.keep()
    from ..defects import DefectResult
    from ..errors import InputError
    _checked_reference(model, ref)
    U, chunk = _checked_rows(U, ref, model), _checked_chunk(chunk)
    kinds = (kinds,) if isinstance(kinds, str) else tuple(kinds)
    if not kinds or not set(kinds) <= set(KINDS):
        raise InputError(f"kinds must name some of {list(KINDS)}, got {list(kinds)}",
                         name="kinds")
    handovers = "channel" in kinds or "sequence" in kinds
    n = len(U)
    if handover_rows is not None:
        handover_rows = _checked_handover_rows(handover_rows, n) & handovers
    d = ref.d
    acc = ref.accuracy
    band_gap = acc.batch_gap_band
    plans = plans_of(ref)
    names = list(model.names)
    P = len(plans)
    channel = np.zeros((n, P))
    sequence = np.zeros((n, P))
    start = np.zeros((n, P))
    deviation = np.zeros(n)
    code = np.full(n, UNCERTAIN, dtype=np.int8)
    results = [None] * n
    evals = extra = 0
    for a in range(0, n, int(chunk)):
        b = min(n, a + int(chunk))
        data = _chunk(model, U[a:b], ref, plans, names,
                      handovers if handover_rows is None else handover_rows[a:b])
        evals += data["evals"]
        extra += data["handover_samples"]
        dev = d - data["maxdev"]
        cc = _certify(data["channel"], data["sequence"], data["ok"], data["bad"], band_gap,
                      data["dev_healthy"], data["dev_defective"])
        channel[a:b], sequence[a:b], deviation[a:b] = (data["channel"][1:],
                                                       data["sequence"][1:], dev[1:])
        start[a:b] = data["start"][1:]
        code[a:b] = cc[1:]
        for v in range(1, b - a + 1):
            if cc[v] != UNCERTAIN:
                results[a + v - 1] = _result(cc[v], v, data, d, band_gap)
            else:
                results[a + v - 1] = DefectResult(
                    bool(data["channel"][v].min() <= 0 or data["sequence"][v].min() <= 0
                         or dev[v] <= 0), (), float(data["maxdev"][v]), d, None, (), (),
                    "uncertain (the batch's guess; the full test decides)")
    unc = np.nonzero(code == UNCERTAIN)[0]
    if fallback and len(unc):
        for v, r in zip(unc, _fallback(model, U[unc], ref, executor)):
            results[v] = r
    defective = np.array([r.defective for r in results], dtype=bool)
    certified = code != UNCERTAIN
    stats = {"variants": n, "certified": int(certified.sum()), "fallback": int(len(unc)),
             "samples": int(sum(p.n for p in plans)), "curve_evaluations": int(evals),
             "handover_samples": int(extra)}
    return MarginBatch(defective, channel, sequence, deviation, certified,
                       ~certified if fallback else np.zeros(n, dtype=bool), tuple(results), d,
                       stats, start)


def _checked_reference(model, ref) -> None:
    """A Reference of ``model`` (:func:`cspace.defects.check_reference`)."""
    from ..defects import check_reference
    check_reference(model, ref, none_ok=False)


def _checked_rows(U, ref, model=None) -> np.ndarray:
    """``U`` as an (n, p) float array of finite parameter vectors (one vector:
    one row; a mapping ``{name: value}`` or a list of them, through
    ``model.vector``, as :func:`cspace.defects.is_defective` takes them), or
    an InputError."""
    from collections.abc import Mapping

    from ..errors import InputError
    if model is not None and hasattr(model, "vector"):
        if isinstance(U, Mapping):
            U = [U]
        if isinstance(U, (list, tuple)) and any(isinstance(r, Mapping) for r in U):
            U = [model.vector(r) if isinstance(r, Mapping) else r for r in U]
    try:
        U = np.asarray(U, dtype=float)
    except (TypeError, ValueError) as e:
        raise InputError(f"U must be an (n, {len(ref.nominal)}) array of parameter vectors "
                         f"(or mappings {{name: value}}), got {type(U).__name__} that is not "
                         f"numeric ({e})", name="U") from None
    if U.ndim == 1:
        U = U[None, :]
    if U.ndim != 2 or U.shape[1] != len(ref.nominal):
        raise InputError(f"U must be an (n, {len(ref.nominal)}) array of parameter vectors, "
                         f"got shape {np.shape(U)}", name="U")
    if not np.all(np.isfinite(U)):
        raise InputError("U must be finite: got NaN or infinite parameter values", name="U")
    return U


def _checked_chunk(chunk, name: str = "chunk") -> int:
    from ..errors import InputError
    if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
        raise InputError(f"{name} must be an int >= 1, got {chunk!r}", name=name, value=chunk)
    return int(chunk)


def _checked_handover_rows(h, n: int) -> np.ndarray:
    from ..errors import InputError
    h = np.asarray(h)
    if h.shape != (n,) or h.dtype != bool:
        raise InputError(f"handover_rows must be {n} bools (one per row of U), got "
                         f"{h.dtype} of shape {h.shape}", name="handover_rows")
    return h


def contact_sequences(model, u, ref) -> tuple:
    """The contact sequence along the motion of one variant as the batch reads
    it: per pair, ``(lower, upper)`` in the form of
    :func:`cspace.match.motion_sequence` (``(label, branch)`` per contact,
    those shorter than the resolution contracted), or None for a pair whose
    samples leave a contact's duration undecided.  For diagnosis and tests:
    :func:`defect_margins` compares the same readings."""
    u = np.asarray(u, dtype=float)
    res = _resolution(ref.d)
    Ub = np.vstack([ref.nominal, u])
    pairs, bad, msgs = _build(model, Ub)
    if bad[1]:
        from ..errors import InputError
        raise InputError(f"the variant does not build: {msgs[1]}", name="u")
    out = []
    for plan, cs, row in zip(plans_of(ref), ref.spaces, pairs):
        table = feature_table(row)
        env = _envelopes(plan, cs, table, Ub != Ub[:1],
                         _dependency_columns(cs, list(model.names)))
        ho, _ = _handovers(plan, cs, env, res)
        label = {}
        for c, k in enumerate(plan.key):
            label.setdefault(int(k), (cs.curves[c].label, cs.curves[c].branch))
        seq = []
        if 1 in ho and ho[1][5]:
            out.append(None)         # not sampled as finely as the resolution asks
            continue
        for side, ids in ((1, env.lo_id), (2, env.hi_id)):
            xv, iv = (ho[1][0], ho[1][side]) if 1 in ho else (plan.x, ids[1])
            keep, drop, _ = _readings(*_runs(iv, xv / plan.scale1, plan.cyclic), res, plan.cyclic)
            seq.append(None if keep != drop else tuple(label.get(k, ("", 0)) for k in keep))
        out.append(None if None in seq else tuple(seq))
    return tuple(out)


def _resolution(d: float) -> float:
    from ..defects import RESOLUTION
    return RESOLUTION * d


def _fallback(model, U, ref, executor=None) -> list:
    """The full per-variant test of the uncertain variants."""
    if executor is None:
        return [_full_task(model, u, ref) for u in U]
    futs = [executor.submit(_full_task, model, u, ref) for u in U]
    return [f.result() for f in futs]


def _full_task(model, u, ref):
    """:func:`cspace.defects.is_defective` of one variant, without the match
    details."""
    import dataclasses

    from ..defects import is_defective
    return dataclasses.replace(is_defective(model, u, ref=ref), matches=())
