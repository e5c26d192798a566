"""Removal of defective variants ([Tolerance synthesis] §4.3, Eqs. 2–5): transition points,
the shift vector, and the tolerance shrink of last resort.

Transition points
-----------------
For a defective check-list vector u_w the segment u0 -> u_w is searched for the
first defective point, by bisection (the paper's search, ``method="bisect"``)
or by interpolating the batched search margin (``method="margin"``; see
:func:`transition_points`); both keep the same bracket and stopping rule.  The search keeps a bracket (last healthy point h, first
defective point c) and stops when ``max|c - h| < eps`` with
``eps = SynthesisAccuracy.search_eps * t`` (fast 5e-3, default 1e-3, precise 2e-4
of t, the largest tolerance of a parameter that changes the motion,
:func:`synthesis.checklist.motion_scale`; the paper's digit is garbled).  All brackets advance in
lock step, so every step is one batch of defect tests for an executor.

Refinement on demand
--------------------
Not every transition point needs the full ε.  A vector the shift already
excludes (see "Shift vector" below) is skipped, and it is skipped on its healthy
end h: a coarser bracket has its h nearer u0, a larger distance |d|, so a
vector the shift excludes at the coarse h is excluded at the fine one too.  So
the loop (:func:`plan_with_refinement`) bisects every defective vector only
``COARSE_STEPS`` times (2: the bracket is a quarter of the segment) and makes
the plan; then, round by round, it bisects one step further every vector the plan
did not skip (those that set the shift or need a cut) whose bracket is not yet
shorter than ε, and makes the plan again, until every vector the plan uses
has its bracket shorter than ε.  A refined bracket is the one a search to ε
at once would have reached (bisection is deterministic).  The shift shrinks
as its vectors are refined, so a vector skipped before may be used by a later
plan; it is then refined in its turn.  The final plan is therefore made from
transition points bisected to ε wherever it uses one, and every vector it
skips is excluded at its true transition point as well.  On the Geneva pair,
where about half of the check list is defective in the first iterations, most
defective vectors are skipped behind a few large shifts: the first iteration's
search takes 675 defect tests instead of 2280 (with 2 coarse steps; 907
with 3) and gives the same shift (on hand-made cases too, see the tests).  The price is more,
smaller batches: one per round, each as large as the number of vectors still
being refined.  The skipped vectors' brackets stay coarse; their defective
ends (real defective points) are what later iterations keep as removed
points.

Per-axis distance (Eq. 3)
-------------------------
``d[i] = (u_c[i] - u0[i]) - sign(u_c[i] - u0[i]) * t[i]``: the signed shift of
axis i that puts the box edge on u_c.  Eq. 3 is applied to the *healthy* end h of
the bracket: the shifted closed box then ends on a point known to be healthy and
excludes the defective end c strictly.  (Applied to c, the next corner of the box
would land on c again and the iteration could stall.)  Only axes on which u_w
differs from u0 and whose tolerance is positive can move the box past u_c.

Shift vector (Eqs. 4–5)
-----------------------
Vectors are processed in decreasing order of ``|d_j[k_j]|``, k_j the cheapest
axis (smallest |d_j[i]|); vectors of equal |d_j[k_j]| keep check-list order.  A
vector already outside the shifted box is skipped.  Otherwise
``Δu[k] = max_abs(d_j[k], Δu[k])``; when d_j[k] and Δu[k] have opposite signs, or
the move would bring a previously removed defective point back into the box (a
*cycle*), the next-cheapest axis is tried.  A vector for which every axis
conflicts is removed by shrinking one tolerance after Δu is final: the axis
whose tolerance needs the smallest relative cut to put the box edge on h.

Axes of equal cost (the paper is silent on these ties) are ranked by the
iteration's own evidence (:func:`axis_evidence`): how much more often the
defective check-list vectors than the healthy ones lie on u_w's side of the
nominal on that axis.  Ties are the rule, not the exception: every axis on which
a box-corner vector sits at ±t has the same distance (1 - λ) t, and a check-list
vector of a Geneva pair has 11-12 such axes.  Broken by axis number instead, the
shift moves the lowest-numbered axis (a centre coordinate, say), which may
hardly affect the defect, and the next design's corners fail again; the loop
then wanders through the parameters without converging.  The evidence costs no
extra defect test: it is read from the check-list results the iteration
already has.

Returning vectors (spread shift)
--------------------------------
A single-axis shift moves one box edge onto u_c.  When the defect is caused by
several parameters together (the interference is a sum over the corner's axes,
as when the three fingers, the tip radius and both follower faces close the
reciprocating cam's passage), the box corner of the next design is defective
again, by a little less: moved one axis at a time the corner approaches the
defect boundary only geometrically (by the factor 1 - t_k / Σ t per step), so
the loop would never end.  So a vector whose origin (the zone extremes it
combines) was shifted out before and is defective again is shifted on *every*
axis of its distance vector: Δu = d_j, each axis combined by max_abs and
dropped on a sign conflict.  That moves the whole corner onto u_c, which is
healthy (to the search ε) when the defect boundary is near-linear over the
box.  The max-norm change of this move, max_i (1 - λ) t_i, is no larger than
the single-axis moves it replaces would accumulate.  The loop passes these
vectors as ``spread``.  With evidence (see "Shift vector"), the spread moves
only the axes whose evidence is positive, so that parameters the defect does
not depend on stay where they are.

A vector that keeps returning (more often than the loop's ``patience``) is
not shifted again: shifting it moves the defect to the other side of the box
(a symmetric output deviation, say, which no shift can cure) or back and
forth.  It is removed by a tolerance cut.  A cut of one axis, the smallest
relative cut that puts that box edge on the healthy end h, is minimal, but
when the defect depends on many axes together the corner of the cut box is
defective again by a little less, and one axis at a time the loop again
approaches the defect boundary only geometrically (observed on the Geneva
pair: ``whl_x`` cut by 5 % per iteration for five iterations without removing
the same six vectors).  So a returning vector gets a *spread shrink*: every
axis the segment u0 -> u_w moves is cut to |h_i - c_i|, the same relative cut
1 - λ on each, so that the corner of the new box on u_w's side *is* h, a point
the bisection tested healthy.  It is the smallest uniform relative cut that
makes that corner healthy, and it ends the return in one iteration.

The support of a defect (``support=True``)
-------------------------------------------
A box-corner vector moves every parameter, but its defect seldom needs all of
them: on the Geneva pair, a contact-sequence defect of one corner moved 26
parameters and the spread shrink cut the 11 on which the healthy end lay
inside the box, among them slot flanks and relief radii of other slots.
Such a defect has no continuous margin whose sensitivities would say which
parameters it depends on (:mod:`synthesis.minimal`), so with ``support=True``
(the removal ``"lp"`` passes it; the paper's greedy does not) the vector that
would get a spread shrink is first reduced to its *support*
(:func:`defect_support`): one parameter at a time, it is put back to the
nominal, and kept there when the vector stays defective.  What remains moved
is a set of parameters each of which the defect needed when it was tried.
The search then runs along u0 -> (the reduced vector), and the spread shrink
cuts only the parameters of the support.  It costs one defect test per
parameter the vector moves, all reduced vectors in one batch per parameter:
first those the plan would spread-shrink; if the smaller cuts then let
other returning vectors spread, all returning vectors left, at once (a
vector at a time, the optical cams' first plan took thousands of batches).
A batch of a few vectors costs mostly its call, so while fewer than
``SUPPORT_AHEAD`` vectors are left, each tries its next parameters in the
same batch too, on the guess that those before it stay put back (most do: a
defect needs few of the parameters); a trial after a guess that failed is not
used.  The result is the same; on the Geneva pair's first plan the 17
parameters of a lone vector took 6 batches instead of 17.
A cut that turns out too small is found by the next iteration's check list,
as for any other change.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from cspace.argcheck import getint
from cspace.errors import InputError

__all__ = ["Transition", "transition_points", "plan_with_refinement", "COARSE_STEPS", "SEARCHES",
           "distance_vector", "max_abs", "shift_vector", "axis_evidence",
           "Placement", "Shrink", "ShiftPlan", "plan_removal", "excluded", "binding_shifts",
           "defect_support"]

_REL = 1e-12  # relative slack of box-membership tests (floating-point rounding only)


@dataclass(frozen=True, eq=False)
class Transition:
    """The bracketed transition point on the segment u0 -> u_w.

    Attributes
    ----------
    index : int
        Check-list index of u_w.
    u_w : (n,) float
        The defective vector.
    healthy, defective : (n,) float
        Bracket ends: last healthy and first defective point found.
    lam : (float, float)
        Their positions on the segment (0 = u0, 1 = u_w).
    steps : int
        Bisection steps taken.
    """

    index: int
    u_w: np.ndarray
    healthy: np.ndarray
    defective: np.ndarray
    lam: tuple
    steps: int
    #: the search margins at the bracket ends (healthy > 0, defective <= 0),
    #: as the Illinois rule uses them (NaN: unknown); see :func:`transition_points`
    margins: tuple = (float("nan"), float("nan"))
    #: which end the last step kept (-1 the healthy, +1 the defective, 0 none)
    kept: int = 0

    @property
    def u_c(self) -> np.ndarray:
        """The point Eq. 3 is applied to (the healthy end of the bracket)."""
        return self.healthy

    def to_dict(self) -> dict:
        return {"index": self.index, "u_w": self.u_w.tolist(), "healthy": self.healthy.tolist(),
                "defective": self.defective.tolist(), "lam": list(self.lam), "steps": self.steps}


#: Ways to place the next test point of a bracket (:func:`transition_points`).
SEARCHES = ("margin", "bisect")


#: :func:`transition_points` with ``known``: while at most this many brackets
#: are open, each round also tests the next point of both halves of every
#: bracket, so that the round after it (or the next call's first, with the
#: same ``known``) finds its points answered.  A batched call costs about as
#: much as 5 to 12 vectors before its first (:data:`SUPPORT_AHEAD`); the
#: refinement of :func:`plan_with_refinement` asks one step of a few vectors
#: per round.
SEARCH_AHEAD = 8


def transition_points(u0, targets, is_defective_batch, eps: float, *, indices=None,
                      progress=None, hints=None, start=None, max_steps=None,
                      method: str = "bisect", end_margins=None, known=None) -> list:
    """Search every segment u0 -> u_w for its first defective point.

    ``method="bisect"`` halves each bracket (the paper's search).
    ``method="margin"`` places the next point where the search margin (see
    below), interpolated linearly between the bracket's ends, crosses zero,
    with the Illinois rule (the margin of an end kept twice in a row is
    halved, so that the bracket closes from both sides) and a guard that keeps
    the point at least 0.45 eps from either end, so that a good estimate ends
    the search with a bracket shorter than eps at once.  An end whose margin is
    unknown, or whose sign contradicts its verdict (the full test decided
    otherwise), makes that step a bisection.  The verdicts alone move the
    bracket: the margins only choose where to test.

    Parameters
    ----------
    u0 : (n,) float
        A healthy vector (the nominal).
    targets : sequence of (n,) float
        Defective vectors u_w.
    is_defective_batch : callable
        ``f(list of (n,) arrays) -> list of bool`` or a list of ``(bool,
        margin)``; called once per step with the next point of every open
        bracket (so it may run them in parallel).  The margin is the search
        margin of the point (:func:`synthesis.executors.search_margin`; > 0
        healthy, <= 0 defective, NaN unknown).
    eps : float
        Stop when the bracket is shorter than ``eps`` (max-norm, model units).
    indices : sequence of int, optional
        Check-list indices to record (default 0, 1, ...).
    progress : callable, optional
        ``progress(step, open_brackets)`` before each batch (a round that
        ``known`` answers whole asks for none).
    hints : sequence, optional
        One value per target, passed on with the batch: ``f(vectors, hints)``
        is then called with the hints of the vectors' targets (the loop passes
        the pair where each target was found defective, to be tested first).
    start : sequence of Transition or None, optional
        One per target: continue from that bracket (and step count) instead of
        the whole segment.  The bracket sequence of a target does not depend on
        how its steps were split between calls.
    max_steps : int, optional
        Stop a bracket after this many steps of this call even if it is not
        yet shorter than ``eps``.
    method : {"bisect", "margin"}
    end_margins : sequence of (float, float), optional
        Per target, the search margins at u0 and at u_w (for a target without
        ``start``); default unknown (the first step bisects).
    known : dict, optional
        Answers by vector (``u.tobytes() -> (verdict, margin)``), read before
        asking and filled with every answer.  With it, a round of at most
        :data:`SEARCH_AHEAD` open brackets also asks for the point each
        bracket would test next after either verdict when that point is a
        bisection (the next round, or a later call with the same ``known``,
        then finds it answered): the same brackets in fewer rounds, for a few
        more tests.

    Returns
    -------
    list of Transition, in the order of ``targets``.
    """
    u0 = np.asarray(u0, dtype=float)
    if not eps > 0:
        raise InputError(f"search eps must be > 0, got {eps!r}")
    if max_steps is not None:
        getint(max_steps, "max_steps", minimum=0, label="max_steps (or None)")
    targets = [np.asarray(u, dtype=float) for u in targets]
    m = len(targets)
    indices = list(range(m)) if indices is None else list(indices)
    start = [None] * m if start is None else list(start)
    if len(start) != m:
        raise InputError(f"start must have one entry per target ({m}), got {len(start)}",
                         name="start")
    if method not in SEARCHES:
        raise InputError(f"search method must be one of {list(SEARCHES)}, got {method!r}",
                         name="method", value=method)
    nan = float("nan")
    ends = [(nan, nan)] * m if end_margins is None else [tuple(e) for e in end_margins]
    lo = np.array([0.0 if s is None else s.lam[0] for s in start])
    hi = np.array([1.0 if s is None else s.lam[1] for s in start])
    mlo = np.array([_healthy_margin(e[0]) if s is None else s.margins[0]
                    for s, e in zip(start, ends)])
    mhi = np.array([_defective_margin(e[1]) if s is None else s.margins[1]
                    for s, e in zip(start, ends)])
    kept = np.array([0 if s is None else s.kept for s in start], dtype=int)
    steps = np.array([0 if s is None else s.steps for s in start], dtype=int)
    span = np.array([_span(u, u0) for u in targets])
    cap = steps + (np.iinfo(np.int32).max if max_steps is None else max_steps)
    step = 0
    while True:
        open_ = [j for j in range(m) if _open(lo[j], hi[j], span[j], eps) and steps[j] < cap[j]]
        if not open_:
            break
        pts = [_next_point(lo[j], hi[j], mlo[j], mhi[j], eps / span[j])
               if method == "margin" else 0.5 * (lo[j] + hi[j]) for j in open_]
        us = [u0 + t * (targets[j] - u0) for j, t in zip(open_, pts)]
        # a batch of defect tests unless ``known`` answers every point (the
        # points ahead are asked only with a batch that is made anyway)
        asking = known is None or any(u.tobytes() not in known for u in us)
        if progress is not None and asking:
            progress(step, len(open_))
        if known is None:
            out = _ask(is_defective_batch, us,
                       None if hints is None else [hints[j] for j in open_])
        else:
            ahead = ([(j, q) for j, t in zip(open_, pts)
                      for q in _ahead(lo[j], hi[j], t, mlo[j], mhi[j], span[j], eps, method)]
                     if asking and len(open_) <= SEARCH_AHEAD else [])
            out = _answered(is_defective_batch, known, us + [u0 + q * (targets[j] - u0)
                                                             for j, q in ahead],
                            None if hints is None else [hints[j] for j in open_]
                            + [hints[j] for j, _ in ahead])[:len(us)]
        for j, t, (b, mg) in zip(open_, pts, out):
            if b:
                hi[j], mhi[j] = t, _defective_margin(mg)
                if kept[j] == -1:           # the healthy end kept twice: Illinois
                    mlo[j] *= 0.5
                kept[j] = -1
            else:
                lo[j], mlo[j] = t, _healthy_margin(mg)
                if kept[j] == 1:
                    mhi[j] *= 0.5
                kept[j] = 1
            steps[j] += 1
        step += 1
    return [Transition(indices[j], targets[j], u0 + lo[j] * (targets[j] - u0),
                       u0 + hi[j] * (targets[j] - u0), (float(lo[j]), float(hi[j])),
                       int(steps[j]), (float(mlo[j]), float(mhi[j])), int(kept[j]))
            for j in range(m)]


def _ahead(lo, hi, t, mlo, mhi, span, eps, method) -> list:
    """The points a bracket [lo, hi] tested at ``t`` asks next, after either
    verdict, where they are bisections, and only where the half is still
    open: with ``method="bisect"``; with the margin rule where the margin kept
    is unknown (then it bisects whatever ``t`` gives), or where the end
    replaced has none (a guess: a contact-sequence defect's defective points
    have no usable margin, so ``t``'s is likely unknown too; a wrong guess
    costs a test, never an answer: the answers are used only for the very
    vectors asked).  The same expressions as the next round's, so the same
    bits."""
    out = []
    # defective at t: [lo, t], the healthy end's margin kept and the
    # defective end's replaced; healthy at t: [t, hi], the other way round
    for a, b, kept, replaced in ((lo, t, mlo, mhi), (t, hi, mhi, mlo)):
        if not _open(a, b, span, eps):
            continue
        if method == "bisect" or not np.isfinite(kept) or not np.isfinite(replaced):
            out.append(0.5 * (a + b))       # the midpoint, as _next_point's
    return out


def _answered(is_defective_batch, known: dict, us, hints) -> list:
    """:func:`_ask` of the vectors ``us`` not already in ``known`` (each asked
    once), every answer kept in ``known``; the answers of all of ``us``."""
    keys = [u.tobytes() for u in us]
    ask, seen = [], set()
    for k, key in enumerate(keys):
        if key not in known and key not in seen:
            seen.add(key)
            ask.append(k)
    if ask:
        got = _ask(is_defective_batch, [us[k] for k in ask],
                   None if hints is None else [hints[k] for k in ask])
        for k, r in zip(ask, got):
            known[keys[k]] = r
    return [known[key] for key in keys]


def _healthy_margin(v) -> float:
    """A margin usable at a healthy end: > 0 (else unknown)."""
    v = float(v)
    return v if v > 0 else float("nan")


def _defective_margin(v) -> float:
    """A margin usable at a defective end: <= 0 (else unknown)."""
    v = float(v)
    return v if v <= 0 else float("nan")


#: The guard of the margin search: a point at least this share of eps away from
#: each end of its bracket.
_GUARD = 0.45


def _next_point(lo, hi, mlo, mhi, eps_t) -> float:
    """The next test point of a bracket [lo, hi] (segment fractions) by the
    margin rule: where the margins ``mlo > 0`` and ``mhi <= 0`` interpolate to
    zero, kept ``_GUARD * eps_t`` (and at most a quarter of the bracket) from
    either end; the midpoint when a margin is unknown."""
    mid = 0.5 * (lo + hi)
    if not (np.isfinite(mlo) and np.isfinite(mhi) and mlo > 0 and mhi <= 0):
        return mid
    t = lo + (hi - lo) * mlo / (mlo - mhi)
    g = min(_GUARD * eps_t, 0.25 * (hi - lo))
    return float(min(max(t, lo + g), hi - g))


def _open(lo: float, hi: float, span: float, eps: float) -> bool:
    """The stopping rule of the bisection: is the bracket [lo, hi] (fractions of a
    segment of max-norm length ``span``) still not shorter than ``eps``?"""
    return (hi - lo) * span >= eps


def _span(u, u0) -> float:
    """Max-norm length of the segment u0 -> u (0 for empty vectors)."""
    return float(np.max(np.abs(u - u0), initial=0.0))


#: Bisection steps every defective vector gets before the first shift plan
#: (:func:`plan_with_refinement`): its bracket is then a quarter of its segment.
COARSE_STEPS = 2


def _ask(is_defective_batch, us, hints=None) -> list:
    """``is_defective_batch`` of the vectors ``us`` (and their hints, when given)
    as ``(verdict, search margin)`` pairs; the margin is NaN where the batch
    answers with verdicts only."""
    out = is_defective_batch(us) if hints is None else is_defective_batch(us, hints)
    return [o if isinstance(o, tuple) else (o, float("nan")) for o in out]


#: The fewest vectors a round of :func:`defect_support` asks for while it has
#: axes left to try: with fewer targets than this, each target also tries its
#: next axes ahead, on the guess that those before stay put back (see
#: "The support of a defect" in the module docstring).  A batched call costs
#: about as much as 5 to 12 vectors before its first
#: (:func:`synthesis.executors.task_rows`), so a round of a few vectors is
#: mostly that cost.
SUPPORT_AHEAD = 16


def defect_support(u0, targets, is_defective_batch, *, order=None, hints=None,
                   ahead: int = SUPPORT_AHEAD) -> list:
    """Each defective target reduced to its support: the parameters its defect needs.

    Per target, the parameters it moves are tried one at a time (in ``order``,
    first tried first): the parameter is put back to ``u0``, and left there when
    the vector stays defective.  Every target takes its next parameter in the
    same batch, so the call makes one batch of defect tests per parameter
    moved (at most).  With fewer targets left than ``ahead``, each also tries
    its next parameters in that batch, each on the guess that those before it
    stay put back; the trials after a guess that fails are not used.  So the
    result is that of one parameter at a time, in fewer batches, for a few
    more tests.  See "The support of a defect" in the module docstring.

    Parameters
    ----------
    u0 : (n,) float
        The healthy nominal.
    targets : sequence of (n,) float
        Defective vectors.
    is_defective_batch : callable
        As for :func:`transition_points` (``f(vectors, hints)``).
    order : sequence of (n,) int arrays, optional
        Per target, the axes in the order to try (default: by axis number).
        Axes the target does not move are skipped.
    hints : sequence, optional
        Passed on per target, as in :func:`transition_points`.
    ahead : int
        The fewest trials a batch asks for while the targets have that many
        axes left (default :data:`SUPPORT_AHEAD`); 1: one parameter per
        target and batch.

    Returns
    -------
    list of (n,) float
        The reduced targets: each defective (tested), equal to its target on
        its support and to ``u0`` elsewhere.
    """
    u0 = np.asarray(u0, dtype=float)
    cur = [np.asarray(t, dtype=float).copy() for t in targets]
    n = len(u0)
    ahead = getint(ahead, "ahead", minimum=1)
    bad = [k for k, t in enumerate(cur) if t.shape != u0.shape]
    if bad:
        raise InputError(f"every target must have the nominal's shape {u0.shape}; target "
                         f"{bad[0]} has shape {cur[bad[0]].shape}", name="targets")
    if order is None:
        order = [np.arange(n)] * len(cur)
    if len(order) != len(cur):
        raise InputError(f"order must hold one axis order per target ({len(cur)}), got "
                         f"{len(order)}", name="order")
    todo = [[int(i) for i in o if cur[k][i] != u0[i]] for k, o in enumerate(order)]
    while True:
        live = [k for k in range(len(cur)) if todo[k]]
        if not live:
            return cur
        depth = max(1, ahead // len(live))
        trials, owner = [], []
        for k in live:
            # the next axes of target k, each put back on top of those before
            t = cur[k]
            for i in todo[k][:depth]:
                t = t.copy()
                t[i] = u0[i]
                trials.append(t)
                owner.append(k)
        out = _ask(is_defective_batch, trials,
                   None if hints is None else [hints[k] for k in owner])
        stop = set()
        for k, t, (b, _) in zip(owner, trials, out):
            if k in stop:
                continue        # a guess before it failed: not the next trial
            todo[k].pop(0)
            if b:
                cur[k] = t
            else:
                stop.add(k)


def plan_with_refinement(u0, tol, targets, is_defective_batch, eps: float, *, indices=None,
                         progress=None, hints=None, coarse_steps: int = COARSE_STEPS,
                         method: str = "bisect", end_margins=None, support: bool = False,
                         **plan) -> tuple:
    """Transition points and the shift plan, bisecting to ``eps`` only the
    vectors the plan uses.

    Every target is first bisected ``coarse_steps`` times.  Then, until every
    vector the plan uses has its bracket shorter than ``eps``: the shift plan
    (:func:`plan_removal`) is made from the current brackets, and every vector
    it does not skip (it sets the shift, or it needs a cut) whose bracket is
    not yet short enough is bisected one step further (see "Refinement on
    demand" in the module docstring).

    Parameters
    ----------
    u0, tol : (n,) float
        Current nominal and tolerances.
    targets : sequence of (n,) float
        Defective vectors u_w.
    is_defective_batch, eps, indices, hints, method, end_margins
        As in :func:`transition_points`.
    progress : callable, optional
        ``progress(batch, open_brackets)`` before each batch of defect tests
        (``batch`` counts from 0 over the whole call).
    coarse_steps : int
        Bisection steps of every target before the first plan.
    support : bool
        Reduce a vector that would get a spread shrink to its support first
        (:func:`defect_support`, "The support of a defect" in the module
        docstring), so that the shrink cuts only the parameters its defect
        needs.
    **plan
        Passed on to :func:`plan_removal` (``removed``, ``spread``,
        ``returning``, ``names``, ``evidence``).

    Returns
    -------
    (ShiftPlan, list of Transition)
        The plan and the transitions it was made from (brackets shorter than
        ``eps`` for every vector the plan does not skip).
    """
    getint(coarse_steps, "coarse_steps", minimum=0)
    u0 = np.asarray(u0, dtype=float)
    targets = [np.asarray(u, dtype=float) for u in targets]
    batches = [0]

    def counted(*a):
        batches[0] += 1
        return is_defective_batch(*a)

    prog = None if progress is None else (lambda _, m: progress(batches[0], m))
    span = [_span(u, u0) for u in targets]
    # every answer, so that the points a round asks ahead serve the next
    # rounds (SEARCH_AHEAD)
    known: dict = {}
    trs = transition_points(u0, targets, counted, eps, indices=indices, progress=prog,
                            hints=hints, max_steps=coarse_steps, method=method,
                            end_margins=end_margins, known=known)
    reduced: set = set()
    returning = sorted(set(plan.get("returning", ())))
    while True:
        out = plan_removal(u0, tol, trs, **plan)
        spreading = sorted({sh.position for sh in out.shrinks if sh.reason == "spread"}
                           - reduced) if support else []
        if spreading and reduced:
            # a smaller cut excludes fewer vectors, so others come to spread
            # in turn: reduce every returning vector left at once (one batch
            # per parameter) rather than a few per round
            spreading = sorted(set(spreading) | (set(returning) - reduced))
        if spreading:
            _reduce(u0, targets, spreading, counted, plan, hints)
            reduced.update(spreading)
            fresh = transition_points(
                u0, [targets[j] for j in spreading], counted, eps,
                indices=[trs[j].index for j in spreading], progress=prog,
                hints=None if hints is None else [hints[j] for j in spreading],
                max_steps=coarse_steps, method=method, known=known)
            for j, tr in zip(spreading, fresh):
                trs[j] = tr
                span[j] = _span(targets[j], u0)
            continue
        need = [p.vector for p in out.placements if p.action is not Action.SKIPPED
                and _open(*trs[p.vector].lam, span[p.vector], eps)]
        if not need:
            return out, trs
        more = transition_points(u0, [targets[j] for j in need], counted, eps,
                                 indices=[trs[j].index for j in need], progress=prog,
                                 hints=None if hints is None else [hints[j] for j in need],
                                 start=[trs[j] for j in need], max_steps=1, method=method,
                                 known=known)
        for j, tr in zip(need, more):
            trs[j] = tr


def _reduce(u0, targets, which, is_defective_batch, plan, hints) -> None:
    """Replace ``targets[j]`` (j in ``which``) by its support
    (:func:`defect_support`), trying first the parameters whose cut costs most
    and, among equals, those with the least evidence for the defect on the
    target's side (:func:`axis_evidence`)."""
    n = len(u0)
    guards = plan.get("guards")
    cost = np.asarray(guards.cut_cost if guards is not None else np.ones(n), dtype=float)
    ev = plan.get("evidence")
    order = []
    for j in which:
        side = (targets[j] > u0).astype(int)
        e = np.asarray(ev)[side, np.arange(n)] if ev is not None else np.zeros(n)
        order.append(np.lexsort((np.arange(n), e, -cost)))
    out = defect_support(u0, [targets[j] for j in which], is_defective_batch, order=order,
                         hints=None if hints is None else [hints[j] for j in which])
    for j, t in zip(which, out):
        targets[j] = t


def distance_vector(u0, tol, u_c, u_w=None) -> np.ndarray:
    """Eq. 3: per-axis signed shift that puts the box edge on ``u_c``.

    Axes on which the segment u0 -> u_w does not move (or whose tolerance is 0)
    cannot exclude the point and get NaN.
    """
    u0 = np.asarray(u0, dtype=float)
    tol = np.asarray(tol, dtype=float)
    u_c = np.asarray(u_c, dtype=float)
    ref = u_c if u_w is None else np.asarray(u_w, dtype=float)
    s = np.sign(ref - u0)
    d = (u_c - u0) - s * tol
    ok = (s != 0) & (tol > 0)
    return np.where(ok, d, np.nan)


def axis_evidence(u0, vectors, defective) -> np.ndarray:
    """Per-axis, per-side evidence of what drives the defects of one check list.

    Parameters
    ----------
    u0 : (n,) float
        The nominal of the iteration.
    vectors : (m, n) float
        The check-list vectors.
    defective : (m,) bool
        Their defect-test outcomes.

    Returns
    -------
    (2, n) float
        Row 0 for the side below the nominal, row 1 for the side above: the share
        of defective vectors on that side minus the share of healthy vectors on
        it, in [-1, 1].  Positive where lying on that side goes with the defect,
        so that moving the box away from it is likely to help.  Zero rows when
        either group is empty.
    """
    u0 = np.asarray(u0, dtype=float)
    U = np.asarray(vectors, dtype=float)
    bad = np.asarray(defective)
    if U.ndim != 2 or U.shape[1] != u0.size or bad.shape != (U.shape[0],):
        raise InputError(f"axis_evidence needs vectors of shape (m, {u0.size}) and m defect "
                         f"flags, got vectors of shape {U.shape} and {bad.shape[0] if bad.ndim else 0}"
                         " flags")
    bad = bad.astype(bool)
    ev = np.zeros((2, U.shape[1]))
    if not bad.any() or bad.all():
        return ev
    s = np.sign(U - u0)
    for row, side in ((0, -1.0), (1, 1.0)):
        on = s == side
        ev[row] = on[bad].mean(axis=0) - on[~bad].mean(axis=0)
    return ev


def _preference(ev, u0, u_w) -> np.ndarray:
    """The evidence of each axis of u_w's side (0 where u_w is on the nominal)."""
    s = np.sign(np.asarray(u_w, dtype=float) - u0)
    return np.where(s > 0, ev[1], np.where(s < 0, ev[0], 0.0))


_TIE = 1e-9  # relative: axis costs this close count as equal


def _axis_order(c, pref) -> list:
    """Finite axes by cost ``c``; axes of equal cost (within ``_TIE``) by
    decreasing preference, then by axis number.  Costs equal but for
    rounding (two axes of equal tolerance shifted to the same transition
    point) are ordered by the axes, never by their rounding, which differs
    with the model's length unit."""
    fin = [int(i) for i in np.argsort(c, kind="stable") if np.isfinite(c[i])]
    out, k = [], 0
    while k < len(fin):
        base = c[fin[k]]
        grp = [i for i in fin[k:] if c[i] <= base * (1 + _TIE) + 1e-300]
        out += sorted(grp, key=lambda i: (0.0 if pref is None else -pref[i], i))
        k += len(grp)
    return out


def max_abs(a: float, b: float) -> float:
    """The argument with the larger magnitude (``a`` on a tie)."""
    return a if abs(a) >= abs(b) else b


def _excluded_by(d, delta) -> bool:
    """Whether shift ``delta`` already moves the box past the point of ``d``."""
    ok = np.isfinite(d)
    return bool(np.any(ok & (np.sign(delta) == np.sign(d)) & (d != 0)
                       & (np.abs(delta) >= np.abs(np.where(ok, d, 0)) * (1 - _REL))))


class Action(enum.Enum):
    SHIFT = "shift"
    SKIPPED = "skipped"      #: already outside the shifted box
    CONFLICT = "conflict"    #: every axis conflicts: needs a shrink


@dataclass(frozen=True)
class Placement:
    """What the shift-vector pass did with one vector."""

    vector: int              #: position in the input list
    action: Action
    axis: int = -1           #: axis moved (SHIFT)
    distance: float = 0.0    #: d_j[axis]
    order: int = -1          #: processing rank
    cycle: bool = False      #: an axis was refused because a removed point would return
    axes: tuple = ()         #: every axis moved (SHIFT; several for a spread shift)


def _spread(d, delta, admissible):
    """Tentative shift of every usable axis of ``d`` (max_abs, conflicts dropped)."""
    trial = delta.copy()
    moved = []
    for i in np.nonzero(np.isfinite(d) & (d != 0))[0]:
        if delta[i] != 0 and np.sign(delta[i]) != np.sign(d[i]):
            continue
        trial[i] = max_abs(d[i], delta[i])
        moved.append(int(i))
    if not moved or (admissible is not None and not admissible(trial)):
        return None, ()
    return trial, tuple(moved)


def shift_vector(ds, *, admissible=None, spread=(), returning=(), preference=None,
                 cost=None):
    """Eqs. 4–5 over distance vectors.

    Parameters
    ----------
    ds : sequence of (n,) float
        Distance vectors d_j (Eq. 3); NaN marks axes that cannot move the box past
        the point.
    admissible : callable, optional
        ``admissible(delta) -> bool``: False refuses a tentative shift (used to
        keep previously removed defects out of the box).
    spread : collection of int
        Vectors shifted on every usable axis (see "Returning vectors" above);
        when that is refused they fall back to the single-axis rule.
    returning : collection of int
        Vectors that came back too often (a cycle): they are not shifted again
        but marked for a shrink.
    preference : (m, n) float, optional
        Per vector, a score per axis that orders axes of equal cost (higher
        first; see :func:`axis_evidence`).  Without it, equal-cost axes keep
        their axis order.
    cost : (n,) float, optional
        Relative cost of moving each axis by one unit (:mod:`synthesis.guards`,
        ``shift_cost``): the cheapest axis is the one of smallest
        ``cost * |d|``.  Default 1 for every axis (Eq. 4).

    Returns
    -------
    delta : (n,) float
    placements : list of Placement, in input order

    Examples
    --------
    The paper's example: d1 = (3, 2), d2 = (3, 3) gives Δu = (3, 0).

    >>> shift_vector([[3.0, 2.0], [3.0, 3.0]])[0]
    array([3., 0.])
    """
    ds = [np.asarray(d, dtype=float) for d in ds]
    if not ds:
        return np.zeros(0), []
    n = len(ds[0])
    delta = np.zeros(n)

    w = np.ones(n) if cost is None else np.asarray(cost, dtype=float)

    def cheapest(d):
        ok = np.isfinite(d)
        return np.where(ok, w * np.abs(np.where(ok, d, 0)), np.inf)

    keys = []
    for j, d in enumerate(ds):
        c = cheapest(d)
        keys.append((-(c.min() if np.isfinite(c).any() else np.inf), j))
    order = [j for _, j in sorted(keys)]
    out: list = [None] * len(ds)
    for rank, j in enumerate(order):
        d = ds[j]
        if _excluded_by(d, delta):
            out[j] = Placement(j, Action.SKIPPED, order=rank)
            continue
        if j in returning:
            out[j] = Placement(j, Action.CONFLICT, order=rank, cycle=True)
            continue
        if j in spread:
            ds_ = d
            if preference is not None and np.any(np.isfinite(d) & (preference[j] > 0)):
                # only the axes the evidence ties to the defect
                ds_ = np.where(preference[j] > 0, d, np.nan)
            trial, moved = _spread(ds_, delta, admissible)
            if moved:
                delta = trial
                k = max(moved, key=lambda i: abs(d[i]))
                out[j] = Placement(j, Action.SHIFT, k, float(d[k]), rank, False, moved)
                continue
        c = cheapest(d)
        axes = _axis_order(c, None if preference is None else preference[j])
        placed = None
        cycle = False
        for i in axes:
            if delta[i] != 0 and np.sign(delta[i]) != np.sign(d[i]):
                continue
            trial = delta.copy()
            trial[i] = max_abs(d[i], delta[i])
            if admissible is not None and not admissible(trial):
                cycle = True
                continue
            delta = trial
            placed = i
            break
        if placed is None:
            out[j] = Placement(j, Action.CONFLICT, order=rank, cycle=cycle)
        else:
            out[j] = Placement(j, Action.SHIFT, placed, float(d[placed]), rank, cycle, (placed,))
    return delta, out


def excluded(tr: Transition, center, tol) -> bool:
    """Whether the box ``center +/- tol`` excludes the defective side of ``tr``:
    its healthy end lies on or beyond the box edge in the direction of u_w on
    some axis, or its defective end lies outside the box."""
    center = np.asarray(center, dtype=float)
    tol = np.asarray(tol, dtype=float)
    s = np.sign(tr.u_w - tr.healthy)
    edge = s * (tr.healthy - center) >= tol * (1 - _REL)
    if np.any((s != 0) & edge):
        return True
    return bool(np.any(np.abs(tr.defective - center) > tol * (1 + _REL)))


def inside(point, center, tol) -> bool:
    """Whether ``point`` lies in the closed box ``center +/- tol``."""
    return bool(np.all(np.abs(np.asarray(point) - center) <= tol * (1 + _REL)))


@dataclass(frozen=True)
class Shrink:
    """One tolerance cut."""

    axis: int
    name: str
    old: float
    new: float
    vector: int            #: check-list index of the vector it removes
    reason: str            #: "conflict", "cycle" or "spread" (one of several cuts)
    position: int = -1     #: position of that vector's transition in the plan's input

    def to_dict(self) -> dict:
        return {"parameter": self.name, "axis": self.axis, "old": self.old, "new": self.new,
                "vector": self.vector, "reason": self.reason}


@dataclass(frozen=True, eq=False)
class ShiftPlan:
    """The removal step of one iteration.

    Attributes
    ----------
    delta : (n,) float
        Shift of the nominal vector (model units).
    tol : (n,) float
        Tolerances after the shrinks.
    placements : tuple of Placement
        Per transition (input order).
    shrinks : tuple of Shrink
    distances : (m, n) float
        The d_j vectors (NaN where an axis cannot help).
    cycle : bool
        A shift was refused because it would re-admit a removed defect.
    infeasible : tuple of dict
        Vectors that no change the guards allow can remove
        (:mod:`synthesis.guards`): ``{"vector": check-list index,
        "parameters": {name: what forbids changing it}}``.
    """

    delta: np.ndarray
    tol: np.ndarray
    placements: tuple
    shrinks: tuple
    distances: np.ndarray
    cycle: bool = False
    infeasible: tuple = ()

    @property
    def progress(self) -> bool:
        return bool(np.any(self.delta != 0) or self.shrinks)


def _shrink_for(tr: Transition, center, tol, cuttable=None, floor=None, cost=None):
    """(axis, new tolerance) of the cheapest cut that excludes ``tr``: the
    smallest relative cut, weighted by ``cost`` (default 1), among the axes
    ``cuttable`` (default all) whose new tolerance stays at or above ``floor``
    (default 0).  None when no allowed axis can exclude it."""
    n = len(tol)
    cuttable = np.ones(n, dtype=bool) if cuttable is None else np.asarray(cuttable, dtype=bool)
    floor = np.zeros(n) if floor is None else np.asarray(floor, dtype=float)
    w = np.ones(n) if cost is None else np.asarray(cost, dtype=float)
    safe = np.where(tol > 0, tol, 1.0)
    s = np.sign(tr.u_w - tr.healthy)
    a = s * (tr.healthy - center)          # where h lies, measured toward u_w
    if np.any((s != 0) & (tol > 0) & (a > 0)):
        new = np.minimum(a, tol)
        cand = (s != 0) & (tol > 0) & (a > 0) & _cut_allowed(new, cuttable, floor)
    else:
        # The centre has passed h on every axis: exclude the defective point itself.
        new = np.minimum(np.abs(tr.defective - center), tol) * (1 - 1e-9)
        cand = (tol > 0) & _cut_allowed(new, cuttable, floor)
    if not np.any(cand):
        return None
    price = np.where(cand, w * (1.0 - new / safe), np.inf)
    # the first axis among those of the least price but for rounding
    best = price.min()
    i = int(np.nonzero(price <= best + abs(best) * _TIE + 1e-300)[0][0])
    return i, float(new[i])


def _cut_allowed(new, cuttable, floor):
    """Whether cutting to tolerances ``new`` is allowed: on ``cuttable`` axes,
    at or above ``floor`` (rounding aside)."""
    return np.asarray(cuttable, dtype=bool) & (np.asarray(new) >= floor * (1 - _REL))


def _spread_shrink_for(tr: Transition, center, tol) -> list:
    """[(axis, new tolerance)] that puts the box corner on u_w's side onto the
    healthy end ``h``: every axis on which the segment moves and ``h`` lies
    between the centre and the box edge is cut to ``|h - c|``.

    The corner ``c + s * t'`` of the new box is then ``h`` itself on those
    axes, a point the bisection found healthy, so the vector cannot come back
    by the same corner (see "Returning vectors" in the module docstring).  Empty
    when no axis qualifies.
    """
    s = np.sign(tr.u_w - tr.healthy)
    a = s * (tr.healthy - center)
    cand = (s != 0) & (tol > 0) & (a > 0) & (a < tol)
    return [(int(i), float(a[i])) for i in np.nonzero(cand)[0]]


def plan_removal(u0, tol, transitions, *, removed=(), spread=(), returning=(),
                 names=None, evidence=None, guards=None, initial_tol=None) -> ShiftPlan:
    """Shift vector (Eqs. 3–5) and last-resort shrinks for one iteration.

    Parameters
    ----------
    u0, tol : (n,) float
        Current nominal and tolerances (model units).
    transitions : sequence of Transition
    removed : sequence of (n,) float
        Defective points removed in earlier iterations; a shift that would bring
        one back into the box is refused (cycle), so the vector falls back to the
        next axis or to a shrink.
    spread : collection of int
        Positions in ``transitions`` of vectors to shift on every axis.
    returning : collection of int
        Positions in ``transitions`` of vectors that returned too often after
        earlier removals (a cycle): they are removed by a *spread shrink*, which
        cuts every tolerance the segment u0 -> u_w moves so that the box corner
        lands on the healthy end (see "Returning vectors" in the module
        docstring); the single-axis minimal cut is kept for vectors whose axes
        merely conflict.
    names : sequence of str, optional
        Parameter names for the shrink records.
    evidence : (2, n) float, optional
        :func:`axis_evidence` of the iteration's check list: it orders axes of
        equal cost.
    guards : synthesis.guards.Guards, optional
        What may change, and at what cost: fixed axes are never shifted, hard
        tolerances never cut, no cut goes below ``min_keep`` of
        ``initial_tol`` (default ``tol``), and shifts and single-axis cuts
        take the cheapest axis by ``shift_cost`` and ``cut_cost``.  A vector
        that no allowed change removes is listed in
        :attr:`ShiftPlan.infeasible` instead.
    """
    u0 = np.asarray(u0, dtype=float)
    tol = np.asarray(tol, dtype=float)
    names = list(names) if names is not None else [f"u{i}" for i in range(len(u0))]
    ds = [distance_vector(u0, tol, tr.u_c, tr.u_w) for tr in transitions]
    if guards is not None:
        ds = [np.where(guards.fixed, np.nan, d) for d in ds]
        floor = guards.floor(tol if initial_tol is None else initial_tol)
        cuttable, shift_cost, cut_cost = ~guards.hard, guards.shift_cost, guards.cut_cost
    else:
        floor = cuttable = shift_cost = cut_cost = None
    removed = [np.asarray(r, dtype=float) for r in removed]

    def admissible(delta):
        c = u0 + delta
        return not any(inside(r, c, tol) for r in removed)

    pref = None
    if evidence is not None and len(transitions):
        ev = np.asarray(evidence, dtype=float)
        if ev.shape != (2, len(u0)):
            raise InputError(f"evidence must have shape (2, {len(u0)}), got {ev.shape}")
        pref = np.array([_preference(ev, u0, tr.u_w) for tr in transitions])
    delta, placements = shift_vector(ds, admissible=admissible if removed else None,
                                     spread=frozenset(spread), returning=frozenset(returning),
                                     preference=pref, cost=shift_cost)
    center = u0 + delta
    new_tol = tol.copy()
    shrinks = []
    infeasible = []
    cycle = any(p.cycle for p in placements)
    ret = frozenset(returning)
    for p in sorted((p for p in placements if p.action is Action.CONFLICT), key=lambda p: p.order):
        tr = transitions[p.vector]
        if excluded(tr, center, new_tol):
            continue
        if p.vector in ret:
            cuts = _spread_shrink_for(tr, center, new_tol)
            if cuts and guards is not None and not all(
                    _cut_allowed(t_new, cuttable[i], floor[i]) for i, t_new in cuts):
                cuts = []       # a guarded axis: the cheapest single cut instead
            if cuts:
                for i, t_new in cuts:
                    shrinks.append(Shrink(i, names[i], float(new_tol[i]), t_new, tr.index,
                                          "spread", p.vector))
                    new_tol[i] = t_new
                continue
        cut = _shrink_for(tr, center, new_tol, cuttable, floor, cut_cost)
        if cut is None:
            infeasible.append(_blocked(tr, u0, center, new_tol, names, guards, floor))
            continue
        i, t_new = cut
        shrinks.append(Shrink(i, names[i], float(new_tol[i]), t_new, tr.index,
                              "cycle" if p.cycle else "conflict", p.vector))
        new_tol[i] = t_new
    dist = np.array(ds) if ds else np.zeros((0, len(u0)))
    return ShiftPlan(delta, new_tol, tuple(placements), tuple(shrinks), dist, cycle,
                     tuple(infeasible))


def _blocked(tr, u0, center, tol, names, guards, floor) -> dict:
    """Why no allowed change removes ``tr``: the parameters that could, and what
    forbids each (``fixed``, ``hard``, or the cut below its ``min_keep`` floor)."""
    s = np.sign(tr.u_w - u0)
    why = {}
    for i in np.nonzero((s != 0) & (tol > 0))[0]:
        r = []
        if guards is not None and guards.fixed[i]:
            r.append("fixed")
        if guards is not None and guards.hard[i]:
            r.append("hard")
        elif floor is not None:
            r.append(f"a cut below min_keep {guards.min_keep[i]:g}")
        why[names[i]] = ", ".join(r)
    return {"vector": tr.index, "parameters": why}


def binding_shifts(plan: ShiftPlan) -> dict:
    """Per shifted axis, the position (in the plan's input) of the vector whose
    distance set the final shift: the defect that required it."""
    out = {}
    ranked = sorted(plan.placements, key=lambda p: p.order)
    for i in np.nonzero(plan.delta != 0)[0]:
        for p in ranked:
            if p.action is Action.SHIFT and i in p.axes:
                d = plan.distances[p.vector][i]
                if np.isfinite(d) and abs(abs(d) - abs(plan.delta[i])) <= 1e-12 * abs(d):
                    out[int(i)] = p.vector
                    break
    return out
