"""The check list of [Tolerance synthesis] §4.1: zone extremes, parameter combination, ε-filter.

Seeds
-----
Every contact zone of an operating channel gives two seeds: the parameter vector
that pushes its curve furthest outward and the one that pulls it furthest inward
(:meth:`cspace.zones.ZoneAnalysis.seeds`).  A seed differs from the nominal
vector only on its curve's *dependency set* X.

Parameter combination (Table 1, Eq. 1)
--------------------------------------
Two list vectors u_i (set X1) and u_j (set X2) combine into u_w with
``u_w[k] = u_i[k]`` for k in X1, ``u_j[k]`` for k in X2, the nominal value
otherwise; its set is X1 ∪ X2 and it goes back into the list so that it can
combine further (the work list of Table 1).

The paper combines only vectors whose sets are disjoint.  Here two vectors also
combine when their sets overlap but the vectors *agree* on every shared
parameter (within the filter radius below).  This extension is needed because
the curves that bound one channel nearly always share the axis parameters (the
Geneva driver and wheel centres appear in every contact equation), so strictly
disjoint sets would never meet; where the shared parameters take the same value
the two extreme variations are realised together by one vector, exactly as the
disjoint case intends.

Unrestricted, the extended closure explodes on the Geneva pair (its 128 seeds
gave 3427 vectors, 143745 combinations, about an hour of defect tests per
iteration).  So when *channel partners* are given (``partners``), the extension
applies only between them.  Channel partners are the two closing extremes of one
free cell of an operating channel: the seed pushing its lower curve up and the
seed pushing its upper curve down (Fig. 4b).

Such a closing pair rarely agrees on its shared parameters (a centre moved one
way lifts both curves), and then neither rule combines it, although it is the
very variation that closes the channel.  So two partner *seeds* that disagree
are combined by Eq. 1 read literally, once in each order: the first vector's
values win on the shared parameters.  These partner vectors go back into the
list like any other and combine further by the rules above.

Hand-over partners
------------------
The paper's list, and the channel partners above, vary one contact (or one
closing pair) at a time.  Where the motion passes from one contact to the next
(the Geneva wheel leaves its locking arc and the pin picks it up in the slot,
touching the slot's corner on the way in), the output and the contact sequence
depend on both contacts at once: on where the first left the follower and on
where the second picks it up.  A Geneva design whose check list had no
defective vector still had 31 defective corners in 1000 random box corners,
every one of them such a hand-over (deviations just above d, or a corner
contact appearing or vanishing as the pin enters).  So the seeds of the curves
that bound consecutive cells of the nominal motion (``handover`` pairs,
:func:`handover_partners`, within ``SynthesisAccuracy.handover_reach`` cells) are
combined by Eq. 1 in both orders.  They join the list but do not combine
further: the list grows about five times on the Geneva pair (124 to 622
vectors) instead of exploding.

ε-filter
--------
A combined vector enters the list only if no list vector lies within the filter
radius ``r = SynthesisAccuracy.filter_eps * t`` in the max-norm (every coordinate
within r), t the largest tolerance of a parameter that changes the nominal's
motion (:func:`motion_scale`: a loose tolerance on an edge that never touches
must not merge vectors that differ where it matters; a stem's +-1 mm merged a
roller cam's list of 10 seeds into one vector, and the final box of that run
had 5 defective parts in 400).  Vectors that close are kinematically alike
([Tolerance synthesis] §4.1.1).  The
presets use ε = 0.35 (fast), 0.25 (default) and 0.15 (precise): below 1, so
two box corners that differ in any parameter whose tolerance is near the
largest one stay distinct, while vectors that differ only in parameters with
much smaller tolerances (or by interior refinements) merge.  The same filter
removes duplicate seeds.

``max_vectors`` caps the list as a safety net against an exponential closure; a
capped list says so in :attr:`CheckList.truncated`.

Ties at rounding noise
----------------------
The seeds are floating-point results (zone extremes) whose last bits differ
between machines, BLAS builds and numpy versions, and the filter radius is a
product of floats.  A difference of exactly the radius in exact arithmetic
is not rare: the two corners of a parameter whose tolerance is ε/2 of the
largest, or a corner against the nominal value where it is ε of the largest.
Read literally, ``<= r`` would then be decided by those last bits, and with it
the rest of the list (a vector dropped or kept changes what combines later).
So the filter and the agreement test compare with a slack:

    two values are *within the radius* when they differ by at most
    ``r + s``, ``s = max(1e-6 r, 1e-9 max|nominal|)``
    (:data:`TIE_REL`, :data:`ROUND_REL`, :func:`tie_slack`),

far above rounding noise (a few units in the last place of the values) and
far below any distance the radius is meant to separate.  A distance at the
radius up to rounding noise therefore always counts as within it.  Where two
vectors are within the radius of each other the first offered is kept: the
order is that of the seeds (zones in curve order, upper extreme before lower)
and of Table 1, never that of values, so no decision of the list rests on the
last bits.  The zone extremes themselves are chosen the same way
(:mod:`cspace.zones`, "Ties").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cspace.errors import InputError

__all__ = ["CheckVector", "CheckList", "combinable", "combine", "build_checklist",
           "seeds_from_zones", "channel_partners", "handover_partners", "tie_slack",
           "motion_scale"]


@dataclass(frozen=True, eq=False)
class CheckVector:
    """One check-list vector.

    Attributes
    ----------
    u : (n,) float
        Parameter vector (model units).
    depends : frozenset of int
        Indices of the parameters it sets (its dependency set X).
    origin : tuple of str
        The zone extremes it combines, e.g. ``("pair:lab+", "pair:lab2-")``.
    keys : frozenset of (int, int, int)
        (pair index, curve index, direction +1/-1) of the zone extremes it
        combines; used to find channel partners.
    """

    u: np.ndarray
    depends: frozenset
    origin: tuple
    keys: frozenset = frozenset()

    def __repr__(self):
        return f"<CheckVector from {len(self.origin)} seed(s), {len(self.depends)} parameters>"


@dataclass(frozen=True, eq=False)
class CheckList:
    """The check list and how it was made.

    Attributes
    ----------
    vectors : tuple of CheckVector
        In a deterministic order: surviving seeds first, then combined vectors in
        the order they were made.
    n_seeds : int
        Zone extremes offered.
    n_seeds_kept : int
        Seeds left after the ε-filter (duplicates removed).
    n_combined : int
        Combined vectors made (before the filter).
    n_added : int
        Combined vectors that passed the filter.
    radius : float
        Filter radius (model units, max-norm).
    truncated : bool
        True when ``max_vectors`` stopped the combination.
    """

    vectors: tuple
    n_seeds: int
    n_seeds_kept: int
    n_combined: int
    n_added: int
    radius: float
    truncated: bool = False
    extended: bool = True

    def __len__(self):
        return len(self.vectors)

    def __repr__(self):
        return (f"<CheckList: {self.n_seeds} seeds -> {self.n_seeds_kept} kept, "
                f"{self.n_combined} combined -> {len(self.vectors)} vectors>")

    def array(self) -> np.ndarray:
        """(m, n) float: the vectors stacked."""
        if not self.vectors:
            return np.zeros((0, 0))
        return np.array([v.u for v in self.vectors])

    def counts(self) -> dict:
        return {"seeds": self.n_seeds, "seeds_kept": self.n_seeds_kept,
                "combined": self.n_combined, "added": self.n_added,
                "checklist": len(self.vectors), "truncated": self.truncated}


#: Slack of the radius comparisons, relative to the radius (see "Ties at rounding noise").
TIE_REL = 1e-6
#: The same relative to the largest nominal value (rounding noise scales with the values).
ROUND_REL = 1e-9


#: :func:`motion_scale`: a parameter moved by its tolerance changes the
#: nominal's motion when its channel or deviation margin moves by more than
#: this share of d.
INFLUENCE = 1e-3

#: :func:`motion_scale`: parameters tried per batched call.
INFLUENCE_BATCH = 4


def motion_scale(model, ref, margins=None) -> float:
    """The largest tolerance of a parameter that changes the nominal's motion:
    what the check-list filter radius and the search's stop length are
    relative to (``SynthesisAccuracy.filter_eps``, ``search_eps``).

    A parameter changes the motion when, moved alone to either end of its
    tolerance, the batched channel or deviation margin
    (:func:`cspace.batch.margins.defect_margins`) moves by more than
    :data:`INFLUENCE` times d; a variant that does not build counts as a
    change.  Only parameters that some curve bounding the motion's cells
    depends on are tried (:func:`cspace.defects.contact_parameters`), the
    largest tolerances first, :data:`INFLUENCE_BATCH` at a time, until one
    changes the motion.  None does: ``max(tol)``; and when all those
    parameters have the largest tolerance (the case studies), that is the
    answer whichever does, without a batched call.

    Without it a loose tolerance on an edge that never touches (a stem +-1 mm
    beside +-0.08 mm on a roller cam; a slot's length, whose walls the pin
    never reaches the ends of) set both: the filter merged the check list
    into one or two vectors and the runs converged on boxes of which 5/400
    and 185/400 samples were defective.

    Parameters
    ----------
    model : parametric model
        The design (its nominal and tolerances).
    ref : cspace.defects.Reference
        Its reference (of its nominal).
    margins : callable, optional
        ``margins(U) -> (n, 3)`` the batched margins of the rows of ``U``
        against a reference of this model (the synthesis passes the workers',
        against the initial design, whose plans they keep); default
        :func:`cspace.batch.margins.defect_margins` against ``ref``.

    Returns
    -------
    float
        A tolerance of ``model`` (model units), 0 when it has none.
    """
    from cspace.batch.margins import defect_margins
    from cspace.defects import contact_parameters
    tol = np.asarray(model.tol, dtype=float)
    if not len(tol) or not np.any(tol > 0):
        return 0.0
    u0 = np.asarray(ref.nominal, dtype=float)
    moved = contact_parameters(model, ref.spaces, ref.sims)
    if moved is None:
        moved = np.ones(len(tol), dtype=bool)
    order = [i for i in np.argsort(-tol, kind="stable") if moved[i] and tol[i] > 0]
    if not order or tol[order[-1]] == tol.max():
        # none to try, or all of the largest tolerance: max(tol) whichever
        # changes the motion (no batched call; the case studies)
        return float(tol.max())
    if margins is None:
        def margins(U):
            return defect_margins(model, U, ref, fallback=False).margins()
    base = None
    for a in range(0, len(order), INFLUENCE_BATCH):
        axes = order[a:a + INFLUENCE_BATCH]
        U = np.repeat(u0[None, :], 2 * len(axes), axis=0)
        for k, i in enumerate(axes):
            U[2 * k, i] += tol[i]
            U[2 * k + 1, i] -= tol[i]
        if base is None:
            # the nominal's own margins in the first call
            m = np.asarray(margins(np.vstack([u0[None, :], U])), dtype=float)
            base, m = m[0], m[1:]
        else:
            m = np.asarray(margins(U), dtype=float)
        with np.errstate(invalid="ignore"):
            change = np.fmax(np.abs(m[:, 0] - base[0]), np.abs(m[:, 2] - base[2]))
        # a NaN margin (unbuildable, or not computed) counts as a change
        hit = ~(change <= INFLUENCE * ref.d)
        for k, i in enumerate(axes):
            if hit[2 * k] or hit[2 * k + 1]:
                return float(tol[i])
    return float(tol.max())


def tie_slack(radius: float, nominal=None) -> float:
    """Slack added to ``radius`` in every within-the-radius comparison:
    ``max(TIE_REL * radius, ROUND_REL * max|nominal|)``."""
    scale = float(np.max(np.abs(nominal))) if nominal is not None and np.size(nominal) else 0.0
    return max(TIE_REL * float(radius), ROUND_REL * scale)


def combinable(a: CheckVector, b: CheckVector, radius: float, *, extended: bool = True,
               partners=None, slack: float | None = None) -> bool:
    """Whether two list vectors combine (Table 1).

    Disjoint dependency sets always combine; with ``extended`` overlapping sets
    combine when the vectors agree (within ``radius`` plus ``slack``, default
    ``TIE_REL * radius``: a difference of the radius up to rounding noise
    agrees) on every shared parameter
    and, if ``partners`` (a set of frozenset key pairs) is given, when a key of
    ``a`` and a key of ``b`` are partners.  A vector whose set holds the other's
    adds nothing and does not combine.
    """
    shared = a.depends & b.depends
    if not shared:
        return bool(a.depends) and bool(b.depends)
    if not extended or b.depends <= a.depends or a.depends <= b.depends:
        return False
    if partners is not None and not any(frozenset((ka, kb)) in partners
                                        for ka in a.keys for kb in b.keys):
        return False
    if slack is None:
        slack = tie_slack(radius)
    idx = np.fromiter(shared, dtype=int, count=len(shared))
    return bool(np.all(np.abs(a.u[idx] - b.u[idx]) <= radius + slack))


def combine(a: CheckVector, b: CheckVector, nominal) -> CheckVector:
    """Eq. 1: ``a`` on its set, ``b`` on the rest of its set, nominal elsewhere
    (``a`` wins where the sets overlap)."""
    u = np.array(nominal, dtype=float, copy=True)
    ib = np.fromiter(b.depends, dtype=int, count=len(b.depends))
    ia = np.fromiter(a.depends, dtype=int, count=len(a.depends))
    u[ib] = b.u[ib]
    u[ia] = a.u[ia]
    return CheckVector(u, a.depends | b.depends, a.origin + b.origin, a.keys | b.keys)


def _partner_seeds(a: CheckVector, b: CheckVector, partners) -> bool:
    return (partners is not None and len(a.origin) == 1 and len(b.origin) == 1
            and any(frozenset((ka, kb)) in partners for ka in a.keys for kb in b.keys))


class _Index:
    """Vectors seen so far, for the max-norm ε query (radius plus the tie slack)."""

    def __init__(self, n, radius, slack=0.0):
        self.rows = np.zeros((64, n))
        self.m = 0
        self.reach = radius + slack

    def near(self, u) -> bool:
        if self.m == 0:
            return False
        return bool(np.any(np.max(np.abs(self.rows[:self.m] - u), axis=1) <= self.reach))

    def add(self, u):
        if self.m == len(self.rows):
            self.rows = np.vstack([self.rows, np.zeros_like(self.rows)])
        self.rows[self.m] = u
        self.m += 1


def build_checklist(seeds, nominal, tol, filter_eps: float, *, extended: bool = True,
                    partners=None, handover=None, max_vectors: int = 4000,
                    scale: float | None = None) -> CheckList:
    """The check list from zone seeds (Table 1 with the ε-filter).

    Parameters
    ----------
    seeds : sequence of CheckVector
        Zone extremes (see :func:`seeds_from_zones`).
    nominal, tol : (n,) float
        Box centre and half-widths (model units).
    filter_eps : float
        Filter radius relative to ``scale`` (max-norm); distances at the
        radius up to rounding noise count as within it (:func:`tie_slack`).
    extended : bool
        Also combine overlapping sets that agree on their shared parameters.
    partners : set of frozenset, optional
        Key pairs allowed to combine by the extension (see
        :func:`channel_partners`); None: any two vectors.
    handover : set of frozenset, optional
        Key pairs of hand-over partners (see :func:`handover_partners`): two
        seeds of such a pair are combined by Eq. 1 in both orders, once; these
        vectors join the list but do not combine further.
    max_vectors : int
        Stop combining when the list reaches this size.
    scale : float, optional
        What the filter radius is relative to: the largest tolerance of a
        parameter that changes the nominal's motion (:func:`motion_scale`, as
        the synthesis passes it); default ``max(tol)``.
    """
    nominal = np.asarray(nominal, dtype=float)
    tol = np.asarray(tol, dtype=float)
    if nominal.shape != tol.shape or nominal.ndim != 1:
        raise InputError(f"nominal and tol must be (n,) arrays of one length, got shapes "
                         f"{nominal.shape} and {tol.shape}")
    if not filter_eps > 0:
        raise InputError(f"filter_eps must be > 0, got {filter_eps!r}")
    if scale is None:
        scale = float(tol.max() if tol.size else 0.0)
    elif not (isinstance(scale, (int, float, np.floating)) and math.isfinite(scale)
              and scale >= 0):
        raise InputError(f"scale must be a finite length >= 0, got {scale!r}", name="scale",
                         value=scale)
    radius = float(filter_eps) * float(scale)
    slack = tie_slack(radius, nominal)
    index = _Index(len(nominal), radius, slack)
    work: list = []
    for s in seeds:
        if not index.near(s.u):
            index.add(s.u)
            work.append(s)
    n_kept = len(work)
    done: list = []
    n_combined = n_added = 0
    truncated = False
    head = 0

    def offer(made, dest) -> bool:
        """Append to ``dest`` (the whole list) each vector of ``made`` that no
        listed vector lies within the filter radius of; False once it is full."""
        nonlocal n_combined, n_added
        for uw in made:
            n_combined += 1
            if index.near(uw.u):
                continue
            if len(dest) >= max_vectors:
                return False
            index.add(uw.u)
            dest.append(uw)
            n_added += 1
        return True

    # Table 1: take u_i off V0, combine it with every vector still in V0 (new
    # vectors are appended and combine when their turn comes), then move u_i to V1.
    while head < len(work) and not truncated:
        ui = work[head]
        head += 1
        for j in range(head, len(work)):
            uj = work[j]
            if combinable(ui, uj, radius, extended=extended, partners=partners, slack=slack):
                made = (combine(ui, uj, nominal),)
            elif extended and _partner_seeds(ui, uj, partners):
                made = (combine(ui, uj, nominal), combine(uj, ui, nominal))
            else:
                continue
            if not offer(made, work):
                truncated = True
                break
        done.append(ui)
    done.extend(work[head:])
    if handover and not truncated:
        seeds_kept = [v for v in done if len(v.origin) == 1]
        for a_i, a in enumerate(seeds_kept):
            for b in seeds_kept[a_i + 1:]:
                if not _partner_seeds(a, b, handover):
                    continue
                if not offer((combine(a, b, nominal), combine(b, a, nominal)), done):
                    truncated = True
                    break
            if truncated:
                break
    return CheckList(tuple(done), len(seeds), n_kept, n_combined, n_added, radius, truncated,
                     extended)


def seeds_from_zones(zone_analyses, names) -> list:
    """Check-list seeds (zone extremes) of the ZoneAnalysis of each pair, in order.

    The dependency set of a seed is the parameters of its curve that have a
    positive tolerance (the others never move)."""
    index = {nm: i for i, nm in enumerate(names)}
    out = []
    for pi, za in enumerate(zone_analyses):
        tol = np.asarray(za.tol, dtype=float)
        for b in za.bands:
            idx = frozenset(index[nm] for nm in b.depends if nm in index and tol[index[nm]] > 0)
            for u, vals, sgn in ((b.u_upper, b.upper, 1), (b.u_lower, b.lower, -1)):
                if np.isfinite(vals).any():
                    tag = f"{za.pair}:{b.label}{'+' if sgn > 0 else '-'}"
                    out.append(CheckVector(np.asarray(u, dtype=float), idx, (tag,),
                                           frozenset({(pi, b.curve, sgn)})))
    return out


def handover_partners(spaces, paths, reach: int = 2) -> set:
    """Hand-over pairs of the nominal motions: for every cell of ``paths[i]``
    (the (slab, cell) sequence a motion passes through, e.g.
    ``SimulationResult.cells``) and each of the next ``reach`` cells, every
    curve bounding the first and every other curve bounding the later cell, in
    all four directions: the key pairs {(i, a, ±1), (i, b, ±1)}.

    Where the motion passes from one contact to the next (the locking arc lets
    the wheel go and the pin enters the slot), how the output and the contact
    sequence go depends on both curves at once: on where the first left the
    follower and on where the second picks it up.  Their zone extremes vary
    different parameter sets, and neither the disjoint rule nor a closing pair
    of one cell combines them.  ``reach = 2`` also pairs the curves on either
    side of a contact that lasts only one cell (the pin touching a slot's
    corner on the way in)."""
    out = set()
    for pi, (cs, path) in enumerate(zip(spaces, paths)):
        seq = []
        for k, j in path:
            c = cs.cells[int(k)][int(j)]
            b = frozenset(x for x in (c.lower, c.upper) if x >= 0)
            if b and (not seq or seq[-1] != b):
                seq.append(b)
        for t, first in enumerate(seq):
            for later in seq[t + 1:t + 1 + reach]:
                for a in first:
                    for b in later:
                        if a == b:
                            continue
                        for sa in (1, -1):
                            for sb in (1, -1):
                                out.add(frozenset({(pi, a, sa), (pi, b, sb)}))
    return out


def channel_partners(spaces, faces, regions=None) -> set:
    """Closing pairs of the operating channels: for every free cell of face
    ``faces[i]`` of ``spaces[i]`` bounded below by curve L and above by U, the
    key pair {(i, L, +1), (i, U, -1)}.

    ``regions[i]`` (an iterable of (slab, cell), e.g. the cells the nominal
    motion passes through) limits pair i to those cells."""
    out = set()
    for pi, (cs, face) in enumerate(zip(spaces, faces)):
        if regions is None:
            cells = [c for row in cs.cells for c in row]
        else:
            cells = [cs.cells[int(k)][int(j)] for k, j in set(regions[pi])]
        for c in cells:
            if c.free and c.face == face and c.lower >= 0 and c.upper >= 0 \
                    and c.lower != c.upper:
                out.add(frozenset({(pi, c.lower, 1), (pi, c.upper, -1)}))
    return out
