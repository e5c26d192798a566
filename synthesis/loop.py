"""The tolerance synthesis loop of [Tolerance synthesis] §4.

One iteration, for the current design (nominal u0, tolerances t):

1. the nominal C-spaces, operating channels and motion
   (:func:`cspace.defects.reference`);
2. the contact zones of the curves bounding each operating channel, per pair
   (:func:`cspace.zones.contact_zones`);
3. the check list: zone extremes, parameter combination, ε-filter
   (:func:`synthesis.checklist.build_checklist`);
4. the defect test of every check-list vector on an executor
   (:func:`synthesis.executors.defect_task`), against the *initial* design
   (see "The design intent" below);
5. if none is defective the run has converged; otherwise transition points
   by bisection, the shift vector and any shrinks, every defective vector
   bisected coarsely and those the shift plan uses bisected on to ε
   (:func:`synthesis.removal.plan_with_refinement`), and the next design.

The output-deviation threshold d is fixed at the start (the model's, or the
library default at the initial design) so that every iteration applies the same
test.  The loop stops at convergence, at ``max_iter`` (status ``MAX_ITER``), or
when removal cannot change the design (``STALLED``); none of these raises.

The design intent
-----------------
Every defect test of the run (check list and search) compares the variant
with the initial design: its motion (the output deviation) and its operating
region (the topology).  The check list and the zones belong to the current
box, the comparison does not move with it.  Compared with each iteration's
shifted nominal instead, a shift could never remove an output-deviation
defect (the reference would move with the box), and the nominal could drift:
on the Geneva pair six iterations moved the nominal's own output 0.056 rad
away from the initial motion, with d = 0.06, so that a "clean" box would have
admitted parts almost 2 d off the intended motion.  Because the shifted
nominal is no longer healthy by definition, it is tested too; if it is
defective the run stops (``STALLED``), as no bisection can start from it.

After every iteration ``on_iteration(state)`` receives the new
:class:`~synthesis.result.SynthesisState`; passing that state back as ``state``
continues the run and gives the same result as an uninterrupted run.

Within an iteration, ``on_partial(state)`` receives the state before the
iteration with the tests finished so far (:attr:`SynthesisState.partial`):
when the iteration starts, then at most every ``checkpoint_every`` seconds
while its tests run, and once more when the run is stopped inside it (an
interrupt, SIGTERM or an error, which then propagates).  Passing such a state
back as ``state`` replays the iteration with those tests' results instead of
testing them again (:mod:`synthesis.memo`), again with the result of an
uninterrupted run.
"""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass

import numpy as np

from cspace.accuracy import Accuracy
from cspace.argcheck import getint
from cspace.defects import contact_parameters
from cspace.errors import InputError

from .accuracy import as_synthesis_accuracy
from .checklist import (build_checklist, channel_partners, handover_partners, motion_scale,
                        seeds_from_zones)
from .executors import (BatchStats, check_executor, check_sendable, make_executor,
                        margins_task, remember_reference, run_batched, run_ordered,
                        share_reference)
from .guards import WARN_KEEP, Guards
from .memo import DEFAULT_CHECKPOINT_EVERY, TestMemo
from .minimal import REMOVALS, describe_defect, lp_removal
from .progress import Progress
from .removal import SEARCHES, axis_evidence, binding_shifts, plan_with_refinement
from .result import (DEFAULT_MAX_CHECKLIST, DEFAULT_PATIENCE, IterationRecord, SynthesisResult,
                     SynthesisState, SynthesisStatus)
from .target import YieldTarget, as_target, estimate_design, ppm_text

__all__ = ["synthesize", "initial_state", "operating_zones", "checklist_of",
           "with_unbuildable_ends", "interrupted_result", "deep_cuts"]


def operating_zones(model, ref, accuracy, executor=None):
    """Contact zones of the curves bounding each pair's operating region: the
    cells of its operating channel that the nominal motion passes through (the
    region the defect test compares, :mod:`cspace.defects`); with
    ``executor``, the curves' zones in its tasks (the same zones)."""
    from cspace.zones import contact_zones
    return tuple(contact_zones(cs, model, i, accuracy, faces=[f], cells=sim.cells,
                               executor=executor)
                 for i, (cs, f, sim) in enumerate(zip(ref.spaces, ref.faces, ref.sims)))


def checklist_of(model, ref, zones, accuracy, *, max_vectors: int = 4000, scale=None):
    """The check list of one iteration: the zone extremes of ``zones``, combined
    between channel partners of the operating region and, when
    ``accuracy.handover_reach`` > 0, between hand-over partners of the nominal
    motions (:mod:`synthesis.checklist`)."""
    acc = as_synthesis_accuracy(accuracy)
    paths = [s.cells for s in ref.sims]
    ho = (handover_partners(ref.spaces, paths, reach=acc.handover_reach)
          if acc.handover_reach > 0 else None)
    return build_checklist(seeds_from_zones(zones, model.names), model.nominal, model.tol,
                           acc.filter_eps, partners=channel_partners(ref.spaces, ref.faces, paths),
                           handover=ho, max_vectors=max_vectors,
                           scale=motion_scale(model, ref) if scale is None else scale)


def _check_model(model):
    from cspace.model import SYNTHESIS_MEMBERS, check_model
    check_model(model, members=SYNTHESIS_MEMBERS,
                what="a parametric model with tolerances, as the synthesis needs it")
    if not np.any(model.tol > 0):
        raise InputError(f"model {model.name!r} has no positive tolerance: nothing to "
                         "synthesize", name="model", value=model)


def initial_state(model, accuracy=None, d: float | None = None):
    """The state before the first iteration, and the nominal Reference when it had
    to be computed to find the default d (else None)."""
    from cspace.defects import check_deviation, reference
    _check_model(model)
    acc = as_synthesis_accuracy(accuracy)
    ref = None
    if d is None:
        d = getattr(model, "deviation", None)
    if d is None:
        ref = reference(model, acc)
        d = ref.d
    d = check_deviation(d)
    state = SynthesisState(model.name, tuple(model.names), model.nominal, model.tol,
                           model.nominal, model.tol, acc.to_dict(), d)
    return state, ref


_LEGACY_ACCURACY = {"zone_climb": 0, "handover_reach": 0,
                    # the batch bands decide only which variants the full test
                    # decides, never a verdict: any checkpoint resumes with them
                    "batch_gap_band": Accuracy().batch_gap_band,
                    "batch_dev_band": Accuracy().batch_dev_band}


def _check_state(state: SynthesisState, model, acc, d, patience=None, two_sided=None,
                 max_checklist=None, search=None, removal=None):
    if tuple(state.names) != tuple(model.names):
        raise InputError(f"the checkpoint is for parameters {list(state.names)}, the model has "
                         f"{list(model.names)}", name="state", value=state.model)
    if not (np.array_equal(state.initial_nominal, model.nominal)
            and np.array_equal(state.initial_tol, model.tol)):
        raise InputError(f"the checkpoint was made from another design of model "
                         f"{state.model!r} (initial nominal or tolerances differ)",
                         name="state", value=state.model)
    # knobs added after a checkpoint was written take the value that reproduces
    # the older behaviour
    saved = {**_LEGACY_ACCURACY, **state.accuracy}
    now = acc.to_dict()
    if saved != now:
        diff = ", ".join(f"{k} {saved.get(k)!r} (now {now.get(k)!r})"
                         for k in sorted(set(saved) | set(now))
                         if k != "name" and saved.get(k) != now.get(k))
        raise InputError(f"the checkpoint used accuracy {state.accuracy.get('name')!r}, this "
                         f"run asks for {acc.name!r}; they differ in {diff or 'the name'}. "
                         "Resume with the accuracy the checkpoint was made with (a checkpoint "
                         "of an older version whose preset has changed since can only be "
                         "restarted: --fresh)", name="accuracy", value=acc.name)
    if d is not None and float(d) != state.d:
        raise InputError(f"the checkpoint used d = {state.d!r}, this run asks for {d!r}",
                         name="d", value=d)
    why = (state.partial.mismatch(state.iterations, state.nominal, state.tol)
           if state.partial is not None else "")
    if why:
        raise InputError(f"the state cannot be continued: {why}", name="state",
                         value=state.model)
    for nm, v in (("patience", patience), ("two_sided", two_sided),
                  ("max_checklist", max_checklist), ("search", search),
                  ("removal", removal)):
        if v is not None and v != getattr(state, nm):
            raise InputError(f"the checkpoint used {nm} {getattr(state, nm)}, this run "
                             f"asks for {v}; resume with the checkpoint's value",
                             name=nm, value=v)


def synthesize(model, accuracy=None, *, d: float | None = None, executor=None,
               max_iter: int = 30, state: SynthesisState | None = None,
               on_iteration=None, progress: Progress | None = None,
               max_checklist: int | None = None, patience: int | None = None,
               two_sided: bool | None = None, on_partial=None,
               checkpoint_every: float = DEFAULT_CHECKPOINT_EVERY,
               accept_start: bool = False, guards: Guards | None = None,
               search: str | None = None, removal: str | None = None,
               target_yield=None) -> SynthesisResult:
    """Tolerance synthesis of a parametric model ([Tolerance synthesis] §4).

    Parameters
    ----------
    model : mechanisms.models.Model
        The initial design: nominal values and tolerances (model units).
    accuracy : SynthesisAccuracy, Accuracy or preset name
        The geometry's knobs and the synthesis's own: ``search_eps``,
        ``filter_eps`` and ``handover_reach`` set the bisection stop length,
        the check-list filter radius (both relative to the largest tolerance
        of a parameter that changes the motion,
        :func:`synthesis.checklist.motion_scale`)
        and the hand-over partners (:mod:`synthesis.accuracy`).
    d : float, optional
        Output-deviation threshold (C-space metric); default the model's
        ``deviation`` or :func:`cspace.defects.default_deviation` at the initial
        design.
    executor : concurrent.futures.Executor, optional
        Runs the defect tests; default a local process pool for this call.
    max_iter : int
        Iteration cap (counted over the whole run, resumed or not).
    state : SynthesisState, optional
        A checkpoint to continue from.
    on_iteration : callable, optional
        ``on_iteration(state)`` after every iteration (checkpointing).
    on_partial : callable, optional
        ``on_partial(state)`` within an iteration: the state before it with
        the tests finished so far (``state.partial``), when it starts, at
        most every ``checkpoint_every`` seconds, and when the run is stopped
        inside it (see the module docstring).
    checkpoint_every : float
        Seconds between ``on_partial`` calls while tests run (default 30;
        0: after every finished batch of tests).
    accept_start : bool
        A model that states no follower start gets the middle of the widest
        free interval at the drive's start.  When that interval is one of
        several, the run is refused (:class:`mechanisms.analysis.AmbiguousStartError`)
        unless ``accept_start`` is True: another interval would be another
        mechanism.  Which start was chosen, and a follower that never moves,
        are reported through ``progress.note``.  A resumed run was accepted
        when it started.
    search : {"margin", "bisect"}, optional
        How transition points are searched (:func:`synthesis.removal.transition_points`):
        ``"margin"`` (default for a new run) places each test where the
        batched margin interpolates to zero (Illinois, bracketed by the
        verdicts); ``"bisect"`` halves the bracket (the paper's search, and
        the choice of checkpoints written before the option existed).  Both
        stop at the same bracket length; the margin search needs fewer tests
        (``docs/synthesis.md``, "Transition points from margins").
    removal : {"lp", "greedy"}, optional
        How defects are removed.  ``"lp"`` (default for a new run): the
        smallest shift, else the smallest cuts, that make every known defect's
        linearised margin positive at the box corners, from margin
        sensitivities (:mod:`synthesis.minimal`); defects without a continuous
        margin (a changed contact sequence) by the paper's rule.
        ``"greedy"``: the paper's Eqs. 3–5 for every defect
        (:mod:`synthesis.removal`; the choice of checkpoints written before
        the option existed).  A resumed run keeps the checkpoint's.
    target_yield : float, str or synthesis.target.YieldTarget, optional
        Synthesis to a target yield (:mod:`synthesis.target`): every
        iteration also estimates the failure rate of the current design
        (against the initial design); when its upper 95 % bound is at or below
        ``1 - target``, the run stops ``TARGET_YIELD`` with the worst-case
        defects that are left.  A float is the yield (0.9999), a string may
        also be ``"99.99%"`` or ``"100ppm"``.  Default None: worst case.  A
        resumed run keeps the checkpoint's target (another one is refused).
    guards : synthesis.guards.Guards, optional
        What the run may change, and at what cost (fixed parameters, hard
        tolerances, the smallest fraction of a tolerance to keep, shift and
        cut costs).  Default ``Guards.of(model)``: the model's parameter
        settings and ``min_keep`` 0.25.  A defect that only a forbidden
        change removes ends the run ``INFEASIBLE``.  A resumed run keeps the
        checkpoint's guards (another value is refused).
    progress : Progress, optional
    max_checklist : int, optional
        Safety cap on the check-list size (default 4000 for a new run, the
        checkpoint's value on a resume; a capped list says so in the
        iteration's counts, ``truncated``).  No built-in model comes near it.
    patience : int, optional
        How often the vector of one origin (the same zone extremes) may be
        removed by a shift (its own, or a larger one that already excluded it)
        before its return counts as a cycle and a shrink removes it.
        Its first shift moves the cheapest axis (Eq. 4); when it returns, it is
        shifted on every axis (:mod:`synthesis.removal`, "spread shift"); after
        ``patience`` removals its return is cured by a spread shrink (every
        tolerance the defect moves is cut so that the corner lands on a
        healthy point).  Default 4 for a new run, the checkpoint's value on a
        resume.  Smaller values cut tolerances sooner and move the nominal
        less (measured in ``docs/synthesis.md``, "Patience").
    two_sided : bool, optional
        Test the mirror ``2 u0 - u_w`` of every defective vector too; a vector
        defective on both sides of the nominal is removed by a spread shrink
        of both sides at once instead of being shifted (a shift that moves
        the box away from one side moves it towards the other).  Default True
        for a new run, the checkpoint's value on a resume (a checkpoint
        written before the option existed ran without it).  ``False`` is the
        paper's order: shift first, cut only a vector that keeps returning
        (the two compared in ``docs/synthesis.md``, "Two-sided defects").

    Returns
    -------
    SynthesisResult
    """
    _check_arguments(model, max_iter, patience, max_checklist, two_sided, executor,
                     checkpoint_every, guards, search, removal, on_partial, state,
                     on_iteration=on_iteration, progress=progress)
    acc = as_synthesis_accuracy(accuracy)
    state, ref0 = _start(model, acc, d, state, patience, two_sided, max_checklist, guards,
                         search, removal, target_yield)
    run = _Run(model, acc, state.d, executor, progress or Progress(), on_iteration, max_iter,
               None if state.guards is None else Guards.from_dict(state.guards, model.names),
               state.patience)
    state = _within_max_iter(state, run)
    # the design intent: every defect test compares with the initial design
    model.dependencies()  # filled once here, travels with every task to the workers
    with contextlib.ExitStack() as stack:
        if executor is None and state.status is SynthesisStatus.RUNNING:
            run.executor = stack.enter_context(make_executor("process"))
        if state.status is SynthesisStatus.RUNNING:
            run.ref = _intent_reference(run, ref0, accept_start or state.iterations > 0
                                        or state.partial is not None)
        while state.status is SynthesisStatus.RUNNING:
            state = _iteration(state, run, on_partial, checkpoint_every)
    return _result(state, model, run.zones_initial, run.zones_final, run.spaces_initial,
                   run.spaces_final)


def _check_arguments(model, max_iter, patience, max_checklist, two_sided, executor,
                     checkpoint_every, guards, search, removal, on_partial, state, *,
                     on_iteration=None, progress=None) -> None:
    """The checks of :func:`synthesize`'s arguments, in the order of its signature."""
    _check_model(model)
    getint(max_iter, "max_iter", minimum=0)
    for nm, v, what in (("patience", patience, "removals of one origin before a shrink"),
                        ("max_checklist", max_checklist, "check-list vectors at most")):
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 1):
            raise InputError(f"{nm} must be an int >= 1 ({what}), got {v!r}", name=nm, value=v)
    if two_sided is not None and not isinstance(two_sided, (bool, np.bool_)):
        raise InputError(f"two_sided must be True, False or None, got {two_sided!r}",
                         name="two_sided", value=two_sided)
    check_executor(executor)
    if (isinstance(checkpoint_every, bool) or not isinstance(checkpoint_every, (int, float))
            or not math.isfinite(checkpoint_every) or checkpoint_every < 0):
        raise InputError(f"checkpoint_every must be a finite number of seconds >= 0, got "
                         f"{checkpoint_every!r}", name="checkpoint_every",
                         value=checkpoint_every)
    if guards is not None and (not isinstance(guards, Guards)
                               or tuple(guards.names) != tuple(model.names)):
        raise InputError(f"guards must be a synthesis.guards.Guards of this model's parameters "
                         f"(Guards.of(model, ...)), got {guards!r}", name="guards",
                         value=guards)
    if search is not None and search not in SEARCHES:
        raise InputError(f"search must be one of {list(SEARCHES)} or None, got {search!r}",
                         name="search", value=search)
    if removal is not None and removal not in REMOVALS:
        raise InputError(f"removal must be one of {list(REMOVALS)} or None, got {removal!r}",
                         name="removal", value=removal)
    for nm, v in (("on_iteration", on_iteration), ("on_partial", on_partial)):
        if v is not None and not callable(v):
            raise InputError(f"{nm} must be callable or None, got {v!r}", name=nm, value=v)
    missing = [m for m in ("begin", "task", "end", "note")
               if not callable(getattr(progress, m, None))]
    if progress is not None and missing:
        raise InputError(f"progress must be a synthesis.progress.Progress (an object with "
                         f"begin, task, end and note; subclass Progress and override task to "
                         f"follow the phases), got {progress!r}, which has no "
                         f"{', '.join(missing)}",
                         name="progress", value=progress)
    if state is not None and not isinstance(state, SynthesisState):
        raise InputError(f"state must be a SynthesisState (from on_iteration or "
                         f"SynthesisState.from_dict) or None, got {type(state).__name__}",
                         name="state", value=state)
    check_sendable(executor, model)


def _start(model, acc, d, state, patience, two_sided, max_checklist, guards, search, removal,
           target_yield):
    """The state a run starts from: a new one with the run's settings, or the
    checkpoint's after checking that this run asks for the same.  Returns it
    and the nominal reference when one was computed on the way (else None)."""
    ref0 = None
    if state is None:
        state, ref0 = initial_state(model, acc, d)
        state = _replace(state, patience=DEFAULT_PATIENCE if patience is None else patience,
                         two_sided=True if two_sided is None else bool(two_sided),
                         max_checklist=(DEFAULT_MAX_CHECKLIST if max_checklist is None
                                        else max_checklist),
                         guards=(guards or Guards.of(model)).to_dict(),
                         search="margin" if search is None else search,
                         removal="lp" if removal is None else removal,
                         target=None if target_yield is None
                         else as_target(target_yield).to_dict())
        return state, ref0
    _check_state(state, model, acc, d, patience, two_sided, max_checklist, search, removal)
    asked = None if target_yield is None else as_target(target_yield).to_dict()
    if asked is not None and state.target != asked:
        raise InputError(f"the checkpoint's target yield is {state.target}, this run asks "
                         f"for {asked}; resume with the checkpoint's",
                         name="target_yield", value=target_yield)
    if guards is not None and (state.guards is None or not guards.same_as(
            Guards.from_dict(state.guards, model.names))):
        raise InputError(f"the checkpoint used guards {state.guards}, this run asks for "
                         f"{guards.to_dict()}; resume with the checkpoint's",
                         name="guards", value=guards)
    return state, ref0


@dataclass(eq=False)
class _Run:
    """What the iterations of one run share, and the zones it reports."""

    model: object           #: the initial design: the design intent of every test
    acc: object
    d: float
    executor: object
    progress: Progress
    on_iteration: object
    max_iter: int
    guards: object
    patience: int
    ref: object = None      #: the initial design's reference
    zones_initial: tuple = None
    spaces_initial: tuple = None
    zones_final: tuple = None
    spaces_final: tuple = None

    def finish(self, state, status, tested=None):
        """End the run with ``status`` (:func:`_finish_with`), keeping the final
        design's zones."""
        state, (self.zones_final, self.spaces_final) = _finish_with(
            state, self.model, self.acc, self.d, status, tested)
        return state

    def stop(self, memo, state, rec, note, status, tested):
        """End the run after iteration record ``rec`` with ``status`` and
        ``note`` on the design the iteration ``tested``: the iteration's
        ``memo`` is committed (a stop from here on keeps what ``on_iteration``
        writes), the final zones are the tested design's and ``on_iteration``
        sees the final state."""
        memo.commit()
        state = _replace(state, history=state.history + (rec,), note=note)
        self.progress.end(rec)
        state = self.finish(state, status, tested)
        if self.on_iteration is not None:
            self.on_iteration(state)
        return state


def _within_max_iter(state, run):
    """A run resumed with a larger ``max_iter`` continues; one at its cap ends."""
    if state.status is SynthesisStatus.MAX_ITER and state.iterations < run.max_iter:
        state = _replace(state, status=SynthesisStatus.RUNNING,
                         note="" if state.note.startswith("max_iter") else state.note)
    if state.status is SynthesisStatus.RUNNING and state.iterations >= run.max_iter:
        if state.iterations == 0:
            state = _replace(state, note=f"max_iter = {run.max_iter}: stopped before the first "
                                         f"iteration; no variant was tested")
        # (the result of a run that tested nothing reports no final zones)
        state = _finish_with(state, run.model, run.acc, run.d, SynthesisStatus.MAX_ITER)[0]
    return state


def _intent_reference(run, ref0, accepted: bool):
    """The initial design's reference (``ref0`` when it was computed with this
    d), its operating point checked and handed to the workers."""
    from cspace.defects import reference
    ref = ref0 if (ref0 is not None and ref0.d == run.d) else reference(run.model, run.acc, run.d)
    _check_operating_point(ref, run.progress, accepted, run.model)
    remember_reference(run.model, run.acc, run.d, ref)
    share_reference(run.executor, run.model, run.acc, run.d, ref)
    return ref


def _iteration(state, run, on_partial, checkpoint_every):
    """One iteration: test the design, then stop (the shifted nominal is
    defective, the target yield is met, or nothing is defective) or remove the
    defects and move on."""
    k = state.iterations + 1
    resumed = state.partial
    state = _replace(state, partial=None)
    memo = _iteration_memo(state, k, resumed, on_partial, checkpoint_every)
    with _saved_on_stop(memo):
        run.progress.begin(k)
        t_all = time.perf_counter()
        tested = _test_design(state, run.model, run.model, run.ref, run.acc, run.d,
                              run.executor, memo, run.progress)
        if state.iterations == 0:
            run.zones_initial, run.spaces_initial = tested.zones, tested.ref.spaces
        if tested.nominal_result is not None and tested.nominal_result.defective:
            rec = _record_without_removal(state, tested, k, t_all)
            note = ("the shifted nominal is itself defective against the initial "
                    f"design ({tested.nominal_result.message})")
            return run.stop(memo, state, rec, note, SynthesisStatus.STALLED, tested)
        ye = None
        if state.target is not None:
            t = time.perf_counter()
            ye = estimate_design(tested.design, run.model, YieldTarget.from_dict(state.target),
                                 run.acc, run.d, run.executor)
            tested.times["yield"] = time.perf_counter() - t
        if ye is not None and ye["met"] and tested.defective:
            rec = _record_without_removal(state, tested, k, t_all, ye)
            return run.stop(memo, state, rec, _target_note(ye, len(tested.defective)),
                            SynthesisStatus.TARGET_YIELD, tested)
        if not tested.defective:
            return _converged(state, tested, run, memo, k, t_all, ye)
        return _remove_and_move(state, tested, run, memo, k, t_all, ye)


def _record_without_removal(state, tested, k, t_all, ye=None) -> IterationRecord:
    """The record of an iteration that ends before any removal."""
    times = tested.times
    times["search"] = times["plan"] = 0.0
    times["total"] = time.perf_counter() - t_all
    defective, reasons = (tested.defective, tested.reasons) if tested.defective else ((), {})
    return IterationRecord(k, state.nominal, state.tol, _counts(tested.cl, tested.stats),
                           sum(len(z.overlaps) for z in tested.zones), defective, reasons,
                           np.zeros(tested.design.n), (), False, tested.tests, times,
                           yield_estimate=ye)


def _converged(state, tested, run, memo, k, t_all, ye):
    """Nothing defective: the tested design is the result."""
    rec = _record_without_removal(state, tested, k, t_all, ye)
    state = _replace(state, history=state.history + (rec,), status=SynthesisStatus.CONVERGED,
                     overlaps=_overlap_dicts(tested.zones, tested.design.names))
    run.zones_final, run.spaces_final = tested.zones, tested.ref.spaces
    memo.commit()
    run.progress.end(rec)
    if run.on_iteration is not None:
        run.on_iteration(state)
    return state


def _remove_and_move(state, tested, run, memo, k, t_all, ye):
    """Remove the defects (:func:`_remove_defects`) and move to the next design,
    or stop: ``INFEASIBLE`` when no allowed change removes them, ``STALLED``
    when the plan changes nothing, ``MAX_ITER`` at the cap."""
    removal = _remove_defects(state, tested, run.model, run.acc, run.d, run.executor, memo,
                              run.progress, run.guards, run.patience, k)
    plan, trs = removal.plan, removal.trs
    tests = tested.tests + removal.tests
    counts_cl = removal.counts
    counts = removal_counts(dict(state.shifted), removal.keys, plan.placements)
    times = tested.times
    times["total"] = time.perf_counter() - t_all
    counts_cl.update(_counts(None, tested.stats))
    overlaps = sum(len(z.overlaps) for z in tested.zones)
    n = tested.design.n
    if plan.infeasible:
        # stop on the tested design: no allowed change removes these
        rec = IterationRecord(k, state.nominal, state.tol, counts_cl, overlaps,
                              tested.defective, tested.reasons, np.zeros(n), (), plan.cycle,
                              tests, times)
        return run.stop(memo, state, rec,
                        _infeasible_note(plan.infeasible, tested.cl, tested.results,
                                         moved=contact_parameters(tested.design,
                                                                  tested.ref.spaces,
                                                                  tested.ref.sims),
                                         names=tested.design.names),
                        SynthesisStatus.INFEASIBLE, tested)
    rec = IterationRecord(k, state.nominal, state.tol, counts_cl, overlaps, tested.defective,
                          tested.reasons, plan.delta, tuple(s.to_dict() for s in plan.shrinks),
                          plan.cycle, tests, times, removal.required, yield_estimate=ye)
    state = _replace(state, nominal=state.nominal + plan.delta, tol=plan.tol,
                     history=state.history + (rec,),
                     removed=state.removed + tuple(tr.defective for tr in trs),
                     shifted=tuple(sorted(counts.items())), known=removal.known)
    memo.commit()
    run.progress.end(rec)
    if not plan.progress:
        state = run.finish(state, SynthesisStatus.STALLED)
    elif state.iterations >= run.max_iter:
        state = run.finish(state, SynthesisStatus.MAX_ITER)
    if run.on_iteration is not None:
        run.on_iteration(state)
    return state


@dataclass(frozen=True, eq=False)
class _Tested:
    """One iteration's design tested (:func:`_test_design`)."""

    design: object
    ref: object
    zones: tuple
    cl: object
    results: list           #: the check list's defect results, in its order
    margins: list           #: their search margins
    stats: object           #: the batch's counts (BatchStats)
    nominal_result: object  #: the shifted nominal's result (None: not shifted)
    times: dict
    defective: tuple        #: check-list positions of the defective vectors
    reasons: dict           #: defect reason name -> count
    tests: int
    scale: float = 0.0      #: the tolerance the filter and search are relative to
    tables: list = ()       #: every margin of each check-list vector (None: from the memo)


def _test_design(state, model, intent, ref_intent, acc, d, executor, memo,
                 progress) -> _Tested:
    """The first stage of an iteration: the design of ``state``, its reference
    and operating zones, its check list, and the defect test of every check-list
    vector (and, after a shift, of the shifted nominal itself) against the
    initial design ``intent``."""
    from cspace.defects import reference
    times = {}
    t = time.perf_counter()
    if np.array_equal(state.nominal, intent.nominal) and np.array_equal(state.tol, intent.tol):
        # the initial design itself: its dependencies already found
        design = intent
        ref = ref_intent
    else:
        design = model.with_nominal(state.nominal).with_tolerances(state.tol)
    ends = _unbuildable_soon(executor, design)
    if design is not intent:
        design.dependencies()
        # a shifted design whose own motion jams is kept: its nominal, tested
        # against the initial design below, stops the run
        ref = reference(design, acc, d, allow_jam=True)
    times["reference"] = time.perf_counter() - t
    t = time.perf_counter()
    zones = operating_zones(design, ref, acc, executor)
    times["zones"] = time.perf_counter() - t
    t = time.perf_counter()
    # what the filter radius and the search's stop are relative to (the
    # margins from the workers, which keep the initial design's plans)
    scale = motion_scale(design, ref, margins=lambda U: run_ordered(
        executor, margins_task, [(intent, U, acc, d)])[0])
    cl = checklist_of(design, ref, zones, acc, max_vectors=state.max_checklist, scale=scale)
    cl = with_unbuildable_ends(design, cl, None if ends is None else ends.result())
    cl = with_near_contacts(design, ref, cl)
    cl = with_sampled(design, cl, state.sampled)
    times["checklist"] = time.perf_counter() - t
    t = time.perf_counter()
    # the check list, and (after a shift) the shifted nominal itself
    own = [] if np.array_equal(state.nominal, intent.nominal) else [design.nominal]
    bstats = BatchStats()
    margins: list = []
    tables: list = []
    results = run_batched(executor, intent, [v.u for v in cl.vectors] + own, acc, d,
                          lambda i, n, k: progress.task("defect tests", i, n, defective=k),
                          bstats, memo, margins, tables)
    nominal_result = results[len(cl.vectors)] if own else None
    results = results[:len(cl.vectors)]
    times["defects"] = time.perf_counter() - t
    defective = tuple(i for i, r in enumerate(results) if r.defective)
    reasons: dict = {}
    for i in defective:
        for rs in results[i].reasons:
            reasons[rs.name] = reasons.get(rs.name, 0) + 1
    return _Tested(design, ref, zones, cl, results, margins, bstats, nominal_result, times,
                   defective, reasons, len(results) + len(own), scale, tables)


def with_sampled(design, cl, sampled):
    """``cl`` and, after its vectors, the kept Monte Carlo samples
    (:attr:`~synthesis.result.SynthesisState.sampled`) at their places in the
    box of ``design`` (``nominal + z * tol``), each a vector of its own
    (origin ``"sample k"``)."""
    if not len(sampled):
        return cl
    from dataclasses import replace

    from .checklist import CheckVector
    c = np.asarray(design.nominal, dtype=float)
    t = np.asarray(design.tol, dtype=float)
    extra = [CheckVector(c + np.asarray(z) * t, frozenset(int(i) for i in np.nonzero(z)[0]),
                         (f"sample {k}",)) for k, z in enumerate(sampled)]
    return replace(cl, vectors=tuple(cl.vectors) + tuple(extra))


def _unbuildable_soon(executor, design):
    """:func:`mechanisms.analysis.unbuildable_tolerances` of ``design`` started
    on a worker of a process pool, a future (else None: computed where it is
    read).  The caller meanwhile builds the design's reference and zones: the
    Geneva pair's 52 builds took 0.19 s of the caller's each iteration, the
    workers idle."""
    from concurrent.futures import ProcessPoolExecutor

    from mechanisms.analysis import unbuildable_tolerances
    if not isinstance(executor, ProcessPoolExecutor):
        return None
    return executor.submit(unbuildable_tolerances, design)


def with_unbuildable_ends(design, cl, found=None):
    """``cl`` and, after its vectors, every end of a parameter's range (the
    nominal moved by ``-tol`` or ``+tol``, the others at nominal) at which
    ``design`` does not build (:func:`mechanisms.analysis.unbuildable_tolerances`,
    or ``found``, what it gave), each a vector of its own (origin ``"NAME+
    (does not build)"``).

    The zones evaluate only variants that build, so no zone extreme, and no
    check-list vector, lies where the geometry cannot be made: without these
    a box reaching such values (a radius the builder refuses above some
    value) would converge with invalid parts in it.  2 builds per parameter."""
    from dataclasses import replace

    from mechanisms.analysis import unbuildable_tolerances

    from .checklist import CheckVector
    index = {nm: i for i, nm in enumerate(design.names)}
    extra = []
    for name, value, _ in (unbuildable_tolerances(design) if found is None else found):
        i = index[name]
        u = np.array(design.nominal, dtype=float)
        u[i] = value
        side = "+" if value > design.nominal[i] else "-"
        extra.append(CheckVector(u, frozenset({i}), (f"{name}{side} (does not build)",)))
    return replace(cl, vectors=tuple(cl.vectors) + tuple(extra)) if extra else cl


def with_near_contacts(design, ref, cl):
    """``cl`` and, after its vectors, per feature pair that the nominal keeps
    apart by a gap the box can close (:mod:`cspace.near`), the box corner that
    narrows that gap the most (first order; origin ``"near contact DRIVER |
    FOLLOWER"``).

    The zones are those of the nominal's contact curves, so no zone extreme
    lies where such a contact begins: without these a box in which a pin
    reaches a slot's end only at some corners converged with those corners
    jammed."""
    from dataclasses import replace

    from cspace.features import feature_by_key

    from .checklist import CheckVector
    extra = []
    seen = set()
    for near, pair in zip(getattr(ref, "near", ()), design.pairs()):
        if not len(near):
            continue
        for (ka, kb), u, sg in zip(near.keys, near.corners(design.nominal, design.tol),
                                   near.closing):
            if u.tobytes() in seen or not np.any(sg):
                continue
            seen.add(u.tobytes())
            fa, fb = feature_by_key(pair.driver, ka), feature_by_key(pair.follower, kb)
            label = f"near contact {pair.driver.name}:{getattr(fa, 'name', ka)} | " \
                    f"{pair.follower.name}:{getattr(fb, 'name', kb)}"
            extra.append(CheckVector(u, frozenset(int(i) for i in np.flatnonzero(sg)),
                                     (label,)))
    return replace(cl, vectors=tuple(cl.vectors) + tuple(extra)) if extra else cl


@dataclass(frozen=True, eq=False)
class _Removal:
    """The removal step of one iteration (:func:`_remove_defects`)."""

    plan: object            #: the ShiftPlan (shifts, cuts, infeasible defects)
    trs: list               #: one Transition per target
    known: tuple            #: the run's linearised defects after this iteration
    required: tuple         #: the defect that required each change
    keys: list              #: the targets' origins (a mirror's end in " (mirror)")
    counts: dict            #: the check list's counts, with the removal's
    tests: int              #: defect tests of the search


def _remove_defects(state, tested, intent, acc, dd, executor, memo, progress, guards,
                    patience, k) -> _Removal:
    """The second stage of an iteration with defective vectors: their mirrors
    tested (two-sided), then the removal, the LP of :mod:`synthesis.minimal`
    or the paper's Eqs. 3-5 (:func:`synthesis.removal.plan_with_refinement`),
    with the search of the transition points; ``tested.times`` gets the
    search and plan times."""
    design, cl, results = tested.design, tested.cl, tested.results
    defective, cl_margins, bstats = tested.defective, tested.margins, tested.stats
    times = tested.times
    t = time.perf_counter()
    n_search = [0]
    t_search = [0.0]

    def batch(us, first, tables=None):
        t0 = time.perf_counter()
        n_search[0] += len(us)
        mg: list = []
        out = run_batched(executor, intent, us, acc, dd, stats=bstats, memo=memo,
                          margins=mg, tables=tables)
        t_search[0] += time.perf_counter() - t0
        return [(r.defective, m) for r, m in zip(out, mg)]

    # relative to the tolerances that matter (a loose one on an edge that
    # never touches would end every search early)
    eps = acc.search_eps * tested.scale
    counts = dict(state.shifted)
    keys = [_origin_key(cl.vectors[i]) for i in defective]
    targets = [cl.vectors[i].u for i in defective]
    indices = list(defective)
    hints = [results[i].where[0] if results[i].where else None for i in defective]
    returning = [p for p, key in enumerate(keys) if counts.get(key, 0) >= patience]
    spread = [p for p, key in enumerate(keys) if 0 < counts.get(key, 0) < patience]
    counts_cl = cl.counts()
    # the search margins at the segments' ends: the nominal's (tested
    # once) and each target's own; the mirror of each defective vector
    # through the nominal (a defect on both sides is cut at once: see
    # "Two-sided defects"), in the same batch as the nominal
    head = [design.nominal] if state.search == "margin" else []
    mirrors = [2.0 * design.nominal - u for u in targets] if state.two_sided else []
    got_tables: list = []
    got = batch(head + mirrors, None, got_tables) if head or mirrors else []
    m_nom = got[0][1] if head else float("nan")
    ends = [(m_nom, cl_margins[i]) for i in defective]
    # every margin of each target as its test computed it (the margin
    # sensitivities start from them)
    tables = [tested.tables[i] for i in defective]
    if state.two_sided:
        mres = got[len(head):]
        two = [p for p, (bad, _) in enumerate(mres) if bad]
        tables += [got_tables[len(head) + p] for p in two]
        ends += [(m_nom, mres[p][1]) for p in two]
        m0 = len(targets)
        targets += [mirrors[p] for p in two]
        indices += [defective[p] for p in two]
        hints += [hints[p] for p in two]
        keys += [keys[p] + " (mirror)" for p in two]
        cut = set(returning) | set(two) | set(range(m0, m0 + len(two)))
        returning = sorted(cut)
        spread = [p for p in spread if p not in cut]
        counts_cl.update(mirror_tests=len(mirrors), two_sided=len(two))
    ev = axis_evidence(design.nominal, [v.u for v in cl.vectors],
                       [r.defective for r in results])
    known = state.known
    if state.removal == "lp":
        t_lp, s_lp = time.perf_counter(), t_search[0]
        plan, trs, known, required = lp_removal(
            design, intent, acc, dd, executor, targets, indices, keys, ends, batch,
            eps, iteration=k, memo=memo,
            n_own=m0 if state.two_sided else len(targets), hints=hints,
            removed=state.removed, spread=spread, returning=returning,
            evidence=ev, guards=guards, initial_tol=state.initial_tol,
            known=state.known, method=state.search, stats=counts_cl,
            progress=lambda what, i, m: progress.task(what, i, m), tables=tables)
        # outside the search (its time before the LP step is not the LP's)
        times["lp"] = time.perf_counter() - t_lp - (t_search[0] - s_lp)
    else:
        plan, trs = plan_with_refinement(
            design.nominal, design.tol, targets, batch, eps,
            indices=indices,
            progress=lambda s, m: progress.task(f"search batch {s + 1}", 0, m),
            hints=hints,
            removed=state.removed, spread=spread, returning=returning,
            names=design.names, evidence=ev, guards=guards,
            initial_tol=state.initial_tol, method=state.search, end_margins=ends)
        required = _provenance(plan, trs, m0 if state.two_sided else len(trs),
                               memo, design.names)
    times["search"] = t_search[0]
    times["plan"] = time.perf_counter() - t - t_search[0]
    return _Removal(plan, trs, known, required, keys, counts_cl, n_search[0])


def _provenance(plan, trs, n_own, memo, names) -> tuple:
    """The defect that required each change of ``plan``: for a shift the vector
    whose distance set it (:func:`synthesis.removal.binding_shifts`), for a cut
    the vector it removes; described by the test of the first defective point
    found on that vector's segment (kept in the iteration's ``memo``).
    Positions from ``n_own`` on are mirrors; ``both_sides`` says that the
    vector is defective at its mirror through the nominal too."""
    out = []
    two = {int(tr.index) for tr in trs[n_own:]}
    changes = [("shift", names[i], pos) for i, pos in sorted(binding_shifts(plan).items())]
    changes += [("cut", sh.name, sh.position) for sh in plan.shrinks if sh.position >= 0]
    for change, name, pos in changes:
        tr = trs[pos]
        out.append({"parameter": name, "change": change, "vector": tr.index,
                    "mirror": bool(pos >= n_own), "both_sides": int(tr.index) in two,
                    **describe_defect(memo, tr.defective)})
    return tuple(out)


def _target_note(ye: dict, left: int) -> str:
    """The note of a run that reached its target yield."""
    lo, hi = (ppm_text(v) for v in ye["ci_ppm"])
    return (f"target yield reached: estimated failure rate {ppm_text(ye['ppm'])} ppm "
            f"({ye['failures']}/{ye['samples']} {ye['method']} samples; 95 % interval "
            f"[{lo}, {hi}] ppm, upper bound <= target {ppm_text(ye['target_ppm'])} ppm); "
            f"worst case: {left} defective check-list vector(s) left")


def _infeasible_note(blocked, cl, results, shown: int = 3, moved=None, names=()) -> str:
    """Why the run stopped INFEASIBLE: the defects no allowed change removes, with
    where they fail and the parameters in conflict.  A check-list vector
    defective at both of its sides (it and its mirror through the nominal) is
    one defect, named once; ``moved`` (per parameter of ``names``, whether it
    moves a contact of the motion, :func:`cspace.defects.contact_parameters`)
    leaves out the parameters that cannot change the motion."""
    keep = set(names) if moved is None else {nm for nm, m in zip(names, moved) if m}
    by_vector: dict = {}
    for b in blocked:
        by_vector.setdefault(b["vector"], []).append(b)
    parts = []
    for i, bs in list(by_vector.items())[:shown]:
        r = results[i]
        what = r.message or ", ".join(x.value for x in r.reasons) or "defective"
        groups: dict = {}
        seen: set = set()
        for b in bs:
            for nm, why in b["parameters"].items():
                if nm in seen or (names and nm not in keep):
                    continue
                seen.add(nm)
                groups.setdefault(why, []).append(nm)
        params = "; ".join(f"{', '.join(nms)} ({why})" for why, nms in groups.items())
        both = " at both of its sides" if len(bs) > 1 else ""
        parts.append(f"check-list vector {i}{both} ({' & '.join(sorted(cl.vectors[i].origin))}: "
                     f"{what}) would need a change of {params or 'no parameter'}")
    more = f"; and {len(by_vector) - shown} more" if len(by_vector) > shown else ""
    return (f"{len(by_vector)} defect(s) can only be removed by a change the guard rails "
            f"forbid (fixed parameters, hard tolerances, cuts below min_keep): "
            + " | ".join(parts) + more + ". Relax a guard (--min-keep, --fixed, --hard, or the "
            "model file's parameter keys) or change the design by hand")


def _check_operating_point(ref, progress, accepted: bool, model=None) -> None:
    """Report the default start, a follower at rest and a loose default
    deviation threshold of ``model`` (``progress.note``), and refuse an
    ambiguous default start unless it was ``accepted``."""
    import warnings

    from mechanisms.analysis import (AmbiguousStartError, OperatingPointWarning,
                                     ToleranceResolutionWarning, deviation_note,
                                     operating_point_notes, tolerance_note)
    notes = operating_point_notes(ref.spaces, ref.sims, ref.start_choices)
    loose = deviation_note(model, ref) if model is not None else None
    for warn, text in notes + ([loose] if loose else []):
        progress.note(("warning: " if warn else "") + text)
        if warn:
            warnings.warn(text, OperatingPointWarning, stacklevel=3)
    small = tolerance_note(model) if model is not None else None
    if small:
        progress.note("warning: " + small[1])
        warnings.warn(small[1], ToleranceResolutionWarning, stacklevel=3)
    bad = [c for c in ref.start_choices if c is not None and c.ambiguous]
    if bad and not accepted:
        pairs = ", ".join(f"{c.pair!r} ({len(c.intervals)} free intervals at q1 = {c.q1:.6g})"
                          for c in bad)
        raise AmbiguousStartError(
            f"the model states no follower start, and the default (the middle of the widest "
            f"free interval) is ambiguous for {pairs}: synthesis would keep the motion of a "
            f"follower that may start elsewhere.  Expected a stated start ('q2_start' in the "
            f"model file, import-dxf --q2-start) or an explicit acceptance of the default "
            f"(accept_start=True, --accept-start)", bad)


def _iteration_memo(state, k, resumed, on_partial, every) -> TestMemo:
    """The test memo of iteration ``k`` of ``state``'s design, seeded with the
    tests a checkpoint kept (``resumed``), and saved at once through
    ``on_partial`` so that a checkpoint exists from the iteration's start."""
    def save(partial, pre=state):
        on_partial(_replace(pre, partial=partial))

    memo = TestMemo(k, state.nominal, state.tol, None if on_partial is None else save, every,
                    resumed)
    memo.flush()
    return memo


@contextlib.contextmanager
def _saved_on_stop(memo):
    """Save the memo's tests when the iteration is stopped (an interrupt,
    SIGTERM or an error), then let the stop propagate."""
    try:
        yield
    except BaseException:
        memo.flush()
        raise


def _counts(cl, bstats) -> dict:
    """The check list's counts and the batched tests': how many vectors the
    margins decided (``batch_certified``) and how many the full per-variant
    test decided (``batch_fallback``)."""
    out = {} if cl is None else dict(cl.counts())
    out.update(batch_tests=int(bstats.get("variants", 0)),
               batch_certified=int(bstats.get("certified", 0)),
               batch_fallback=int(bstats.get("fallback", 0)))
    return out


def removal_counts(counts: dict, keys, placements) -> dict:
    """How often the vector of each origin has been removed from the box.

    A vector is removed when the shift moves the box past its transition point:
    by its own shift, or because a larger shift already did (skipped), or when
    a tolerance cut excludes it (conflict).  All count, so that a vector that is
    defective again in the next design is recognised as returning (spread
    shift, then a spread shrink after ``patience`` returns), whichever shift or
    cut removed it; a vector cut one axis at a time would otherwise come back
    by a little less every iteration.

    An origin counts once per iteration, however many of its check-list
    vectors were removed in it (one zone's extremes often give two vectors of
    the same origin): a return is a defect coming back in a *later* design.
    """
    out = dict(counts)
    done = {keys[pl.vector] for pl in placements
            if pl.action.name in ("SHIFT", "SKIPPED", "CONFLICT")}
    for k in sorted(done):
        out[k] = out.get(k, 0) + 1
    return out


def _origin_key(v) -> str:
    return " & ".join(sorted(v.origin))


def _replace(state, **kw):
    import dataclasses
    return dataclasses.replace(state, **kw)


def _overlap_dicts(zones, names) -> tuple:
    out = []
    for z in zones:
        for o in z.overlaps:
            d = o.to_dict(names)
            d["pair"] = z.pair
            out.append(d)
    return tuple(out)


def _finish_with(state, model, acc, d, status, tested=None):
    """End the run with ``status``: the overlaps and the final zones of the
    state's design (those of ``tested`` when it is that design, just tested)."""
    from cspace.defects import reference
    design = model.with_nominal(state.nominal).with_tolerances(state.tol)
    if tested is not None:
        ref, zones = tested.ref, tested.zones
    else:
        ref = reference(design, acc, d, allow_jam=True)
        zones = operating_zones(design, ref, acc)
    return (_replace(state, status=status, overlaps=_overlap_dicts(zones, design.names)),
            (zones, ref.spaces))


_MESSAGES = {
    SynthesisStatus.CONVERGED: "no defective variant left in the check list",
    SynthesisStatus.MAX_ITER: "the iteration cap was reached with defects left; rerun with "
                              "a larger cap (the checkpoint resumes)",
    SynthesisStatus.STALLED: "removal could neither shift nor shrink; the defects that are "
                             "left cannot be removed this way",
    SynthesisStatus.INFEASIBLE: "a defect can only be removed by a change the guard rails "
                                "forbid",
}


def interrupted_result(state: SynthesisState, model) -> SynthesisResult:
    """The result of a run stopped inside an iteration, for its report:
    status ``INTERRUPTED``, the finished iterations and the current design,
    and what the iteration in progress had done (``state`` is the last one
    handed to ``on_partial`` or ``on_iteration``)."""
    import dataclasses
    k = state.iterations + 1
    tests = state.partial.tests if state.partial is not None else ()
    bad = sum(1 for _, r, _, _ in tests if r.defective)
    note = (f"interrupted in iteration {k} with {len(tests)} of its defect tests finished "
            f"({bad} defective) and kept in the checkpoint; rerun with --resume to continue "
            f"from them")
    st = _replace(state, status=SynthesisStatus.INTERRUPTED, note=note)
    res = _result(st, model, None, None, None, None)
    return dataclasses.replace(res, interrupted={"iteration": k, "tests_kept": len(tests),
                                                 "defective_so_far": bad})


def deep_cuts(names, initial_tol, tol) -> list:
    """``[(name, kept fraction)]`` of the tolerances cut below
    :data:`synthesis.guards.WARN_KEEP` of their initial value, smallest first."""
    out = [(nm, float(b / a)) for nm, a, b in zip(names, initial_tol, tol)
           if a > 0 and b / a < WARN_KEEP]
    return sorted(out, key=lambda x: x[1])


def _shift_yardstick(state, lengths, units: str) -> str:
    """What e (the largest shift of a length) is against the tolerances: the
    shift that is the largest share of its own parameter's initial
    tolerance (a shift of a parameter whose tolerance is small may matter
    more than e), or nothing when nothing moved."""
    shift = np.abs(state.nominal - state.initial_nominal)
    t0 = np.asarray(state.initial_tol, dtype=float)
    share = np.where(t0 > 0, shift / np.where(t0 > 0, t0, 1.0), np.where(shift > 0, np.inf, 0.0))
    share = np.where(lengths, share, 0.0)
    if not np.any(share > 0):
        return ""
    i = int(np.argmax(share))
    name = state.names[i]
    if not math.isfinite(share[i]):
        return f"; {name} moved {shift[i]:.6g} {units} with no tolerance of its own"
    return (f"; the largest shift against its own tolerance: {name} by {shift[i]:.6g} {units}, "
            f"{share[i]:.3g} of its initial +- {t0[i]:.6g}")


def _result(state, model, zi, zf, si, sf) -> SynthesisResult:
    # e over the lengths ([Tolerance synthesis] Eq. 6), the angles' apart (rad)
    angle = np.array([p.unit == "rad" for p in model.parameters], dtype=bool)
    shift = np.abs(state.nominal - state.initial_nominal)
    e = float(np.max(shift[~angle], initial=0.0))
    e_angle = float(np.max(shift[angle])) if angle.any() else None
    ok = state.status in (SynthesisStatus.CONVERGED, SynthesisStatus.TARGET_YIELD)
    msg = state.note or _MESSAGES.get(state.status, state.status.value)
    if ok:
        msg += f"; e = {e:.6g} {model.units}{_shift_yardstick(state, ~angle, model.units)}"
        if e_angle is not None:
            msg += f"; the largest angle shift {e_angle:.6g} rad"
        low = deep_cuts(state.names, state.initial_tol, state.tol)
        if low:
            msg += (f"; warning: {len(low)} tolerance(s) kept below {100 * WARN_KEEP:.0f} % of "
                    f"the initial value (" + ", ".join(f"{nm} {100 * f:.0f} %"
                                                      for nm, f in low[:5])
                    + (", ..." if len(low) > 5 else "") + ")")
    return SynthesisResult(ok, state.status, msg, state.iterations, state.model,
                           tuple(state.names), model.units, state.initial_nominal,
                           state.initial_tol, state.nominal, state.tol, e, state.history,
                           state.overlaps, state.d, dict(state.accuracy), state.patience,
                           state.two_sided, state.max_checklist, zi, zf, si, sf,
                           guards=state.guards, search=state.search, removal=state.removal,
                           target=state.target, param_units=model.param_units, e_angle=e_angle,
                           sampled=tuple(state.sampled))
