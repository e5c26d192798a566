"""Values of the synthesis loop: the per-iteration record, the resumable state
(checkpoint) and the final :class:`SynthesisResult`.

Every value here is frozen and has ``to_dict()``; the state also has
``from_dict()`` so that a checkpoint file continues a run exactly (floats are
written with ``repr`` precision, so they come back bit for bit).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np

from cspace.errors import FileFormatError

__all__ = ["SynthesisStatus", "IterationRecord", "PartialIteration", "SynthesisState",
           "SynthesisResult", "CHECKPOINT_FORMAT", "REPORT_FORMAT", "with_samples"]

CHECKPOINT_FORMAT = "cspace-synthesis-checkpoint"
#: 2: every defect test compares with the initial design (version 1 compared with
#: the shifted nominal of each iteration and cannot be continued)
CHECKPOINT_VERSION = 2

#: How often a vector of one origin may be removed before its return is cured
#: by a spread shrink (:func:`synthesis.synthesize`, ``patience``).
DEFAULT_PATIENCE = 4
#: The safety cap on the check-list size (:func:`synthesis.synthesize`,
#: ``max_checklist``).
DEFAULT_MAX_CHECKLIST = 4000
REPORT_FORMAT = "cspace-synthesis-report"


class SynthesisStatus(enum.Enum):
    RUNNING = "running"
    CONVERGED = "converged: no defective vector in the check list"
    MAX_ITER = "iteration cap reached with defects left"
    STALLED = "no shift or shrink could remove the defects"
    #: a defect that only a change the guard rails forbid could remove
    #: (:mod:`synthesis.guards`)
    INFEASIBLE = "a defect can only be removed by a change the guard rails forbid"
    #: a target-yield run (:mod:`synthesis.target`) whose estimated failure
    #: rate, upper 95 % bound, is at or below the target
    TARGET_YIELD = "target yield reached: the estimated failure rate is below the target"
    #: stopped by a signal (SIGINT, SIGTERM) or an error; only in the report of
    #: the stopped run, never in a checkpoint (which stays ``RUNNING``)
    INTERRUPTED = "interrupted: stopped before the run ended; --resume continues it"


@dataclass(frozen=True, eq=False)
class IterationRecord:
    """One pass of check list, defect tests and removal.

    Attributes
    ----------
    iteration : int
        1-based.
    nominal, tol : (n,) float
        The design tested in this iteration (model units).
    counts : dict
        Check-list sizes: seeds, seeds_kept, combined, added, checklist,
        truncated; with two-sided testing also ``mirror_tests`` (mirrors of
        defective vectors tested) and ``two_sided`` (those defective too).
    overlaps : int
        Zone overlaps of the operating channels at this design.
    defective : tuple of int
        Check-list indices of the defective vectors.
    reasons : dict
        Number of defective vectors per defect reason.
    shift : (n,) float
        Δu0 applied after this iteration (zero when converged).
    shrinks : tuple of dict
        Tolerance cuts (parameter, old, new, vector, reason).
    cycle : bool
        A shift was refused because a removed defect would have come back.
    tests : int
        Defect tests run (check list plus bisection).
    times : dict
        Seconds spent: reference, zones, checklist, defects, search, total.
    required : tuple of dict
        Per change of this iteration, the defect that required it:
        ``parameter``, ``change`` ("shift" or "cut"), ``vector`` (check-list
        index), ``mirror`` (the defect was at its mirror through the nominal),
        ``u``, ``pair``, ``kind`` (defect reasons), ``q1``, ``q2`` (where it
        fails) and ``message``: the defective vector (model units; the first
        defective point found on the vector's segment where the paper's
        search removed it) and its test.
    """

    iteration: int
    nominal: np.ndarray
    tol: np.ndarray
    counts: dict
    overlaps: int
    defective: tuple
    reasons: dict
    shift: np.ndarray
    shrinks: tuple
    cycle: bool
    tests: int
    times: dict
    required: tuple = ()
    yield_estimate: dict | None = None

    @property
    def n_defects(self) -> int:
        return len(self.defective)

    def __repr__(self):
        return (f"<Iteration {self.iteration}: {self.counts.get('checklist', 0)} vectors, "
                f"{self.n_defects} defective, {len(self.shrinks)} shrink(s)>")

    def to_dict(self, names=None, timing: bool = True) -> dict:
        d = {"iteration": self.iteration, "nominal": self.nominal.tolist(),
             "tol": self.tol.tolist(), "counts": dict(self.counts), "overlaps": self.overlaps,
             "defects": len(self.defective), "defective": list(self.defective),
             "reasons": dict(self.reasons), "shift": self.shift.tolist(),
             "shrinks": [dict(s) for s in self.shrinks], "cycle": self.cycle,
             "tests": self.tests, "required": [dict(r) for r in self.required]}
        if self.yield_estimate is not None:
            d["yield"] = dict(self.yield_estimate)
        if names is not None:
            d["shift_by_name"] = {k: v for k, v in zip(names, self.shift.tolist()) if v != 0}
        if timing:
            d["times"] = dict(self.times)
        return d

    @classmethod
    def from_dict(cls, d) -> "IterationRecord":
        return cls(int(d["iteration"]), np.array(d["nominal"], dtype=float),
                   np.array(d["tol"], dtype=float), dict(d["counts"]), int(d["overlaps"]),
                   tuple(int(i) for i in d["defective"]), dict(d["reasons"]),
                   np.array(d["shift"], dtype=float), tuple(dict(s) for s in d["shrinks"]),
                   bool(d["cycle"]), int(d["tests"]), dict(d.get("times", {})),
                   tuple(dict(r) for r in d.get("required", [])),
                   None if d.get("yield") is None else dict(d["yield"]))


@dataclass(frozen=True, eq=False)
class PartialIteration:
    """The defect tests already finished in the iteration in progress.

    A checkpoint written within an iteration carries them, so that a run
    stopped there resumes without testing those vectors again.  Every defect
    test of a run compares with the initial design, so a test's result depends
    only on its vector: on resume the iteration is replayed (reference, zones,
    check list, search) and each vector found here takes its stored result,
    which gives the same iteration as an uninterrupted run.

    Attributes
    ----------
    iteration : int
        The iteration in progress (1-based): the state's ``iterations + 1``.
    nominal, tol : (n,) float
        Its design (the state's current design).
    tests : tuple of (u, DefectResult, certified, margin)
        Each finished test: the vector (model units), its result (without the
        match details), whether the batched margins decided it (False: the
        full per-variant test did) and its search margin (NaN when unknown).
    """

    iteration: int
    nominal: np.ndarray
    tol: np.ndarray
    tests: tuple = ()

    def __repr__(self):
        return f"<PartialIteration {self.iteration}: {len(self.tests)} test(s) finished>"

    def mismatch(self, iterations: int, nominal, tol) -> str:
        """Why these tests cannot continue a state after ``iterations`` finished
        iterations at design ``nominal``, ``tol`` ("" when they can): they must
        be the next iteration's, of that design."""
        if self.iteration != iterations + 1:
            return (f"the partial iteration must be the next one ({iterations + 1}), got "
                    f"{self.iteration}")
        if not (np.array_equal(self.nominal, nominal) and np.array_equal(self.tol, tol)):
            return "the partial iteration must be of the current design (nominal and tol)"
        return ""

    def to_dict(self) -> dict:
        return {"iteration": self.iteration, "nominal": self.nominal.tolist(),
                "tol": self.tol.tolist(),
                "tests": [{"u": np.asarray(u, dtype=float).tolist(), "result": r.to_dict(),
                           "certified": bool(c),
                           "margin": float(m) if math.isfinite(m) else None}
                          for u, r, c, m in self.tests]}

    @classmethod
    def from_dict(cls, d) -> "PartialIteration":
        from cspace.defects import DefectResult
        tests = []
        for t in d["tests"]:
            c = t["certified"]
            if not isinstance(c, bool):
                raise TypeError(f"certified must be true or false, got {c!r}")
            m = t.get("margin")
            tests.append((np.array(t["u"], dtype=float), DefectResult.from_dict(t["result"]),
                          c, math.nan if m is None else float(m)))
        return cls(int(d["iteration"]), np.array(d["nominal"], dtype=float),
                   np.array(d["tol"], dtype=float), tuple(tests))


@dataclass(frozen=True, eq=False)
class SynthesisState:
    """Everything a run needs to continue: the checkpoint.

    Attributes
    ----------
    model : str
        Model name.
    names : tuple of str
    initial_nominal, initial_tol : (n,) float
    nominal, tol : (n,) float
        The current design (after the last completed iteration).
    accuracy : dict
        ``Accuracy.to_dict()`` of the run.
    d : float
        Output-deviation threshold (C-space metric), fixed for the whole run.
    history : tuple of IterationRecord
    removed : tuple of (n,) float
        Defective points removed so far (cycle detection).
    status : SynthesisStatus
    overlaps : tuple of dict
        Zone overlaps at the final design (when finished).
    shifted : tuple of (str, int)
        How often the check-list vector of each origin (its zone extremes) was
        removed from the box by a shift (its own, or a larger one that already
        excluded it): a vector that comes back more than ``patience`` times is a
        cycle and is removed by a shrink.
    note : str
        Why the run stopped, when the status alone does not say it.
    patience, two_sided, max_checklist
        The run's settings (:func:`synthesis.synthesize`); a resume keeps them.
    partial : PartialIteration or None
        The tests already finished in the iteration in progress (a checkpoint
        written within an iteration), else None.
    guards : dict or None
        The run's guard rails (:meth:`synthesis.guards.Guards.to_dict`); None
        for a checkpoint written before they existed (no guard).
    search : str
        How transition points are searched (``"margin"`` or ``"bisect"``; a
        checkpoint without it bisected).
    removal : str
        How defects are removed (``"lp"`` or ``"greedy"``; a checkpoint without
        it used the greedy).
    target : dict or None
        A target-yield run's :class:`synthesis.target.YieldTarget` (None: worst
        case).
    known : tuple of synthesis.minimal.Linearised
        The linearised margins of the defects found so far (``removal="lp"``),
        which every later removal keeps clear.
    sampled : tuple of (n,) float
        Defective samples of a Monte Carlo check that the check list had
        missed, kept as check-list vectors from then on (:func:`with_samples`):
        each as its place in the box, ``(u - nominal) / tol`` (0 on an axis of
        zero tolerance), so that it moves with the box.
    """

    model: str
    names: tuple
    initial_nominal: np.ndarray
    initial_tol: np.ndarray
    nominal: np.ndarray
    tol: np.ndarray
    accuracy: dict
    d: float
    history: tuple = ()
    removed: tuple = ()
    status: SynthesisStatus = SynthesisStatus.RUNNING
    overlaps: tuple = ()
    shifted: tuple = ()
    note: str = ""
    patience: int = DEFAULT_PATIENCE
    two_sided: bool = False
    max_checklist: int = DEFAULT_MAX_CHECKLIST
    partial: PartialIteration | None = None
    guards: dict | None = None
    search: str = "bisect"
    removal: str = "greedy"
    known: tuple = ()
    target: dict | None = None
    sampled: tuple = ()

    @property
    def iterations(self) -> int:
        return len(self.history)

    def __repr__(self):
        e = float(np.max(np.abs(self.nominal - self.initial_nominal))) if len(self.names) else 0.0
        return (f"<SynthesisState {self.model!r}: {self.status.name} after {self.iterations} "
                f"iteration(s), defects {[h.n_defects for h in self.history]}, e = {e:.4g}, "
                f"{int(np.sum(self.tol != self.initial_tol))} tolerance(s) cut, d = {self.d:.4g}>")

    def to_dict(self, timing: bool = True) -> dict:
        return {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION, "model": self.model,
                "names": list(self.names), "initial_nominal": self.initial_nominal.tolist(),
                "initial_tol": self.initial_tol.tolist(), "nominal": self.nominal.tolist(),
                "tol": self.tol.tolist(), "accuracy": dict(self.accuracy), "d": self.d,
                "history": [h.to_dict(timing=timing) for h in self.history],
                "removed": [r.tolist() for r in self.removed], "status": self.status.name,
                "overlaps": [dict(o) for o in self.overlaps],
                "shifted": [[k, v] for k, v in self.shifted], "note": self.note,
                "patience": self.patience, "two_sided": self.two_sided,
                "max_checklist": self.max_checklist,
                "partial": None if self.partial is None else self.partial.to_dict(),
                "guards": None if self.guards is None else dict(self.guards),
                "search": self.search, "removal": self.removal,
                "known": [c.to_dict() for c in self.known],
                "target": None if self.target is None else dict(self.target),
                "sampled": [z.tolist() for z in self.sampled]}

    @classmethod
    def from_dict(cls, d, path: str = "") -> "SynthesisState":
        if not isinstance(d, dict) or d.get("format") != CHECKPOINT_FORMAT:
            raise FileFormatError(f"expected a {CHECKPOINT_FORMAT!r} document, got "
                                  f"{d.get('format') if isinstance(d, dict) else type(d).__name__!r}",
                                  path=path)
        if d.get("version") == 1:
            raise FileFormatError("this checkpoint (version 1) was made by an earlier version "
                                  "of the loop, which compared each iteration's variants with "
                                  "that iteration's shifted nominal instead of the initial "
                                  "design; it cannot be continued: restart the run (--fresh)",
                                  path=path)
        if d.get("version") != CHECKPOINT_VERSION:
            raise FileFormatError(f"checkpoint version must be {CHECKPOINT_VERSION}, got "
                                  f"{d.get('version')!r}", path=path)
        try:
            st = cls(str(d["model"]), tuple(d["names"]),
                       np.array(d["initial_nominal"], dtype=float),
                       np.array(d["initial_tol"], dtype=float),
                       np.array(d["nominal"], dtype=float), np.array(d["tol"], dtype=float),
                       dict(d["accuracy"]), float(d["d"]),
                       tuple(IterationRecord.from_dict(h) for h in d["history"]),
                       tuple(np.array(r, dtype=float) for r in d["removed"]),
                       SynthesisStatus[d["status"]], tuple(dict(o) for o in d["overlaps"]),
                       tuple((str(k), int(v)) for k, v in d.get("shifted", [])),
                       str(d.get("note", "")),
                       # a checkpoint without it was written when the value was fixed
                       _count(d.get("patience", DEFAULT_PATIENCE), "patience", path),
                       _flag(d.get("two_sided", False), "two_sided", path),
                       _count(d.get("max_checklist", DEFAULT_MAX_CHECKLIST), "max_checklist",
                              path),
                       None if d.get("partial") is None
                       else PartialIteration.from_dict(d["partial"]),
                       _guards(d.get("guards"), d["names"]),
                       _search(d.get("search", "bisect"), path),
                       _removal(d.get("removal", "greedy"), path),
                       _known(d.get("known", []), len(d["names"])),
                       _target(d.get("target"), path),
                       tuple(np.array(z, dtype=float) for z in d.get("sampled", [])))
        except FileFormatError:
            raise
        except (KeyError, TypeError, ValueError, OverflowError) as e:
            raise FileFormatError(f"damaged checkpoint: {type(e).__name__}: {e}",
                                  path=path) from None
        _check_consistent(st, path)
        return st


def _check_consistent(st, path):
    """The vectors of a checkpoint have one entry per parameter and are finite;
    tolerances are >= 0 and d is a positive number."""
    n = len(st.names)

    def bad(what, got):
        raise FileFormatError(f"damaged checkpoint: {what}, got {got}", path=path)

    for nm in ("initial_nominal", "initial_tol", "nominal", "tol"):
        v = getattr(st, nm)
        if v.shape != (n,):
            bad(f"{nm} must hold {n} values (one per parameter)", f"shape {v.shape}")
        if not np.all(np.isfinite(v)):
            bad(f"{nm} must be finite", v.tolist())
    for nm in ("initial_tol", "tol"):
        if np.any(getattr(st, nm) < 0):
            bad(f"{nm} must be >= 0", getattr(st, nm).tolist())
    if not (math.isfinite(st.d) and st.d > 0):
        bad("d must be a positive finite number", repr(st.d))
    for i, r in enumerate(st.removed):
        if r.shape != (n,) or not np.all(np.isfinite(r)):
            bad(f"removed[{i}] must be {n} finite values", r.tolist())
    for i, z in enumerate(st.sampled):
        if z.shape != (n,) or not np.all(np.abs(z) <= 1.0):
            bad(f"sampled[{i}] must be {n} places in the box, each in [-1, 1]", z.tolist())
    if st.status is SynthesisStatus.INTERRUPTED:
        bad("status INTERRUPTED is a report's, a checkpoint of a stopped run stays RUNNING",
            "INTERRUPTED")
    p = st.partial
    if p is not None:
        if st.status is not SynthesisStatus.RUNNING:
            bad("only a running state has a partial iteration", st.status.name)
        why = p.mismatch(st.iterations, st.nominal, st.tol)
        if why:
            raise FileFormatError(f"damaged checkpoint: {why}", path=path)
        for i, (u, _, _, _) in enumerate(p.tests):
            if u.shape != (n,) or not np.all(np.isfinite(u)):
                bad(f"partial test {i} must be {n} finite values", u.tolist())


def _search(v, path):
    from .removal import SEARCHES
    if v not in SEARCHES:
        raise FileFormatError(f"damaged checkpoint: search must be one of {list(SEARCHES)}, "
                              f"got {v!r}", path=path)
    return v


def _removal(v, path):
    from .minimal import REMOVALS
    if v not in REMOVALS:
        raise FileFormatError(f"damaged checkpoint: removal must be one of {list(REMOVALS)}, "
                              f"got {v!r}", path=path)
    return v


def _target(v, path):
    """The yield target of a checkpoint, checked (None: a worst-case run)."""
    if v is None:
        return None
    from .target import YieldTarget
    if not isinstance(v, dict):
        raise FileFormatError(f"damaged checkpoint: target must be an object or null, got "
                              f"{type(v).__name__}", path=path)
    return YieldTarget.from_dict(v).to_dict()


def _known(docs, n):
    from .minimal import known_from_dicts
    if not isinstance(docs, list):
        raise TypeError(f"known must be a list, got {type(docs).__name__}")
    return known_from_dicts(docs, n)


def _guards(g, names):
    """The guards of a checkpoint, checked (None: written before they existed)."""
    if g is None:
        return None
    from .guards import Guards
    return Guards.from_dict(g, names).to_dict()


def _count(v, name, path):
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise FileFormatError(f"damaged checkpoint: {name} must be an int >= 1, got {v!r}",
                              path=path)
    return v


def _flag(v, name, path):
    if not isinstance(v, bool):
        raise FileFormatError(f"damaged checkpoint: {name} must be true or false, got {v!r}",
                              path=path)
    return v


@dataclass(frozen=True, eq=False)
class SynthesisResult:
    """Outcome of a tolerance synthesis ([Tolerance synthesis] §4).

    Attributes
    ----------
    success : bool
        The final design's check list has no defective vector (``CONVERGED``),
        or a target-yield run reached its target (``TARGET_YIELD``; defective
        check-list vectors may be left, see ``history[-1]``).
    status : SynthesisStatus
    message : str
    nit : int
        Iterations run (the last one only tests when it converges).
    model : str
    names : tuple of str
    units : str
    initial_nominal, initial_tol, nominal, tol : (n,) float
        Design before and after (model units).
    e : float
        ``max_i |u0'[i] - u0[i]|`` (model units; [Tolerance synthesis] Eq. 6),
        over the parameters that are lengths.
    history : tuple of IterationRecord
    overlaps : tuple of dict
        Zone overlaps left at the final design (``ZoneOverlap.to_dict``).
    d : float
        Output-deviation threshold used (C-space metric).
    accuracy : dict
    patience : int
        Removals of one origin before its return is cured by a shrink.
    two_sided : bool
        Whether the mirror of every defective vector was tested too.
    max_checklist : int
        The safety cap on the check-list size.
    zones_initial, zones_final : tuple of ZoneAnalysis or None
        Zones of the operating channels (not serialised; None after a resume).
    spaces_initial, spaces_final : tuple of ConfigurationSpace or None
    interrupted : dict or None
        For a run stopped inside an iteration (status ``INTERRUPTED``): the
        iteration, its defect tests finished and kept in the checkpoint, and
        the defective ones among them.
    guards : dict or None
        The run's guard rails (:meth:`synthesis.guards.Guards.to_dict`).
    search, removal : str
        The transition-point search and the removal method of the run.
    param_units : tuple of str
        The unit each parameter is reported in (:meth:`changes`, the
        ``changes``, ``changed`` and ``shrunk`` of :meth:`to_dict`): ``units``,
        ``"rad"`` for an angle (:attr:`mechanisms.models.Parameter.unit`), or
        the unit its model file states it in (``"deg"``, with
        ``param_scales``); empty: all in ``units``.
    sampled : tuple of (n,) float
        Defective Monte Carlo samples of a final box the run went on with
        (:attr:`SynthesisState.sampled`; ``cspace-tol synthesize
        --verify-rounds``), as places in the box.
    param_scales : tuple of float
        Per parameter, what one of its reported unit is in the library's units
        (pi/180 for an angle reported in degrees, else 1); empty: all 1.  The
        vectors (``initial_nominal`` ... ``tol``, ``history``) stay in the
        library's units (:meth:`vector_unit_of`: angles in rad), as the
        checkpoint holds them.
    e_angle : float or None
        ``max |u0'[i] - u0[i]|`` over the angle parameters (rad); None
        without any.
    """

    success: bool
    status: SynthesisStatus
    message: str
    nit: int
    model: str
    names: tuple
    units: str
    initial_nominal: np.ndarray
    initial_tol: np.ndarray
    nominal: np.ndarray
    tol: np.ndarray
    e: float
    history: tuple
    overlaps: tuple
    d: float
    accuracy: dict
    patience: int = DEFAULT_PATIENCE
    two_sided: bool = False
    max_checklist: int = DEFAULT_MAX_CHECKLIST
    zones_initial: tuple | None = field(default=None, repr=False)
    zones_final: tuple | None = field(default=None, repr=False)
    spaces_initial: tuple | None = field(default=None, repr=False)
    spaces_final: tuple | None = field(default=None, repr=False)
    interrupted: dict | None = None
    guards: dict | None = None
    search: str = "bisect"
    removal: str = "greedy"
    target: dict | None = None
    param_units: tuple = ()
    e_angle: float | None = None
    param_scales: tuple = ()
    sampled: tuple = ()

    def unit_of(self, i: int) -> str:
        """The unit parameter ``i`` is reported in (:attr:`param_units`)."""
        return self.param_units[i] if self.param_units else self.units

    def scale_of(self, i: int) -> float:
        """What one of parameter ``i``'s reported unit is in the library's
        units (:attr:`param_scales`; 1 but for an angle reported in degrees)."""
        return float(self.param_scales[i]) if self.param_scales else 1.0

    def vector_unit_of(self, i: int) -> str:
        """The unit of parameter ``i`` in the vectors (``initial_nominal``,
        ``nominal``, the tolerances, ``history``): the library's, rad for an
        angle whatever unit it is reported in."""
        return "rad" if self.scale_of(i) != 1.0 else self.unit_of(i)

    @property
    def yield_estimate(self) -> dict | None:
        """The last iteration's yield estimate of a target-yield run (else None)."""
        for h in reversed(self.history):
            if h.yield_estimate is not None:
                return dict(h.yield_estimate)
        return None

    def __repr__(self):
        return (f"<SynthesisResult {self.model!r}: {self.status.name}, {self.nit} iteration(s), "
                f"defects {self.defects_per_iteration()}, e = {self.e:.4g} {self.units}>")

    def defects_per_iteration(self) -> list:
        return [h.n_defects for h in self.history]

    def changes(self) -> dict:
        """Per parameter: initial and final nominal and tolerance, and the
        change, in the parameter's reported unit (:meth:`unit_of`)."""
        out = {}
        for i, nm in enumerate(self.names):
            k = self.scale_of(i)
            out[nm] = {"initial": float(self.initial_nominal[i]) / k,
                       "final": float(self.nominal[i]) / k,
                       "delta": float(self.nominal[i] - self.initial_nominal[i]) / k,
                       "tol_initial": float(self.initial_tol[i]) / k,
                       "tol_final": float(self.tol[i]) / k}
        return out

    def to_dict(self, timing: bool = True) -> dict:
        # e is over the lengths: so is the tolerance it is set against (report.md's too)
        lengths = [float(t) for i, t in enumerate(self.initial_tol)
                   if self.vector_unit_of(i) == self.units]
        tmax = max(lengths) if lengths else 0.0
        shrunk = {nm: c for nm, c in self.changes().items() if c["tol_final"] != c["tol_initial"]}
        d = {"format": REPORT_FORMAT, "version": 1, "model": self.model, "units": self.units,
             "success": self.success, "status": self.status.name, "message": self.message,
             "nit": self.nit, "e": self.e,
             "e_over_tolerance": self.e / tmax if tmax > 0 else None,
             "defects_per_iteration": self.defects_per_iteration(),
             "checklist_sizes": [h.counts.get("checklist", 0) for h in self.history],
             "parameters": list(self.names),
             "parameter_units": [self.unit_of(i) for i in range(len(self.names))],
             "vector_units": [self.vector_unit_of(i) for i in range(len(self.names))],
             "initial": {"nominal": self.initial_nominal.tolist(), "tol": self.initial_tol.tolist()},
             "final": {"nominal": self.nominal.tolist(), "tol": self.tol.tolist()},
             "changes": self.changes(),
             "changed": {nm: c["delta"] for nm, c in self.changes().items() if c["delta"] != 0},
             "shrunk": {nm: [c["tol_initial"], c["tol_final"]] for nm, c in shrunk.items()},
             "overlaps": [dict(o) for o in self.overlaps], "d": self.d,
             "accuracy": dict(self.accuracy), "patience": self.patience,
             "two_sided": self.two_sided, "max_checklist": self.max_checklist,
             "history": [h.to_dict(self.names, timing=timing) for h in self.history]}
        if self.e_angle is not None:
            d["e_angle"] = self.e_angle
        if self.interrupted is not None:
            d["interrupted"] = dict(self.interrupted)
        if self.guards is not None:
            d["guards"] = dict(self.guards)
        d["search"] = self.search
        d["removal"] = self.removal
        if self.sampled:
            d["sampled"] = [np.asarray(z, dtype=float).tolist() for z in self.sampled]
        if self.target is not None:
            d["target"] = dict(self.target)
            d["yield"] = self.yield_estimate
            d["worst_case"] = {"defective_left": self.history[-1].n_defects
                               if self.history else None}
        if timing:
            d["time"] = float(sum(h.times.get("total", 0.0) for h in self.history))
        return d



def with_samples(state: SynthesisState, samples, nominal=None, tol=None) -> SynthesisState:
    """``state`` continued with the defective ``samples`` (model units) of a
    Monte Carlo check of its box ``nominal +/- tol`` (default the state's
    design) kept as check-list vectors (:attr:`SynthesisState.sampled`): the
    run goes on (status RUNNING) and every later iteration tests them, at
    their places in its box, with its check list; a defective one is
    removed as a check-list vector is.  A sample outside the box (rounding
    aside) raises :class:`~cspace.errors.InputError`."""
    from dataclasses import replace

    from cspace.errors import InputError
    c = np.asarray(state.nominal if nominal is None else nominal, dtype=float)
    t = np.asarray(state.tol if tol is None else tol, dtype=float)
    U = np.atleast_2d(np.asarray(samples, dtype=float))
    if U.size == 0:
        return state
    if U.ndim != 2 or U.shape[1] != len(c) or not np.all(np.isfinite(U)):
        raise InputError(f"samples must be (k, {len(c)}) finite parameter vectors, got shape "
                         f"{U.shape}", name="samples")
    safe = np.where(t > 0, t, 1.0)
    Z = np.where(t > 0, (U - c) / safe, 0.0)
    if np.any(np.abs(Z) > 1 + 1e-9):
        raise InputError("samples must lie in the box nominal +/- tol (they are its Monte "
                         f"Carlo samples); the farthest lies {np.abs(Z).max():.6g} tolerances "
                         "out", name="samples")
    Z = np.clip(Z, -1.0, 1.0)
    have = {z.tobytes() for z in state.sampled}
    new = tuple(z for z in Z if z.tobytes() not in have)
    return replace(state, sampled=tuple(state.sampled) + new, status=SynthesisStatus.RUNNING,
                   note="")
