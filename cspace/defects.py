"""The defect test of [Tolerance synthesis] §4.2: is a variant of a parametric model defective?

A variant is defective when its free-space topology differs from nominal (a
channel closes, a new free component appears, the contact sequence changes) or
when its output function deviates from nominal by more than ``d`` somewhere; a
jammed drive and an unbuildable variant are defects too.

The model is a :class:`cspace.model.ParametricModel` (e.g.
:class:`mechanisms.models.Model`): ``build(u)``, ``nominal``, ``tol``, ``names``,
``dependencies()``, ``window`` and ``drive``, and ``q2_start`` and ``deviation``
when it states them.

Operating region
----------------
The topology is compared where the mechanism works: in the cells of the free
space that the nominal motion and the variant's motion pass through, over the
model's whole ``drive`` (:func:`cspace.match.match`, ``paths``).  A free pocket
of the same face that the motion never enters (a wheel position a slot width
away from any indexing position, reachable only by turning the wheel by hand
through the relief) may split off or change its contacts: the part neither jams
nor drives wrongly because of it.  A model's ``drive`` must therefore cover its
full cycle, e.g. four driver turns for a four-slot Geneva wheel, so that every
slot's motion is simulated and compared.

A motion of whole driver turns that ends where it started (a cam's follower
after a turn of the cam, :func:`cspace.match.closed_motion`; not a Geneva
wheel, which a turn indexes on) repeats, and where its drive begins is only
where the drawing begins it: its contact sequences are compared as cycles
(:func:`cspace.match.same_cycle`).  A disc drawn as two arcs joined where the
follower rests at the start hands over from one arc to the other there; a
variant moves that hand-over to just after the start or just before the end,
which read as a line is a changed sequence, though the motion is the same.

Start
-----
The stated follower start (``q2_start``) picks the free interval the follower
starts in.  A variant's follower starts at the stated value when that is free
in the variant; otherwise at the nearest point of the variant's free interval
that overlaps the nominal's one there (:func:`assembled_start`): a part is
assembled where it fits, and a crank a little longer than drawn does not jam
because the drawing put the follower at the nominal's start.  Only a variant
without such an interval (the channel closed at the start) is blocked.

Closure
-------
Each pair's follower is simulated with its own closure (``Pair.bias``), the
nominal and every variant alike: a form-closed follower moves only when pushed,
a spring-loaded one rests on the bias-side bound of its channel
(:mod:`cspace.simulate`).  Its stated start picks the channel in both cases
and must be free in the variant too, or the start is blocked.

Default deviation threshold
---------------------------
A model may state its own ``deviation`` (the designer's d).  Otherwise
``d = 5 * t / L`` in the C-space metric (rad for a rotating follower; for a
sliding follower, ``d * L`` in model units), where L is the pair's characteristic
length and t the largest tolerance of a parameter that moves a contact of
the nominal motion (:func:`contact_tolerance`): five times the largest
tolerance that matters, seen at the part's reach.  A parameter that moves no
curve bounding the motion's cells (an edge that never touches) does not
count, however loose.  Every
variant's deviation is measured in the nominal's metric (its L), so that ``d *
L`` is one length for every part; a variant's own L moves with its dimensions.

Resolution
----------
A contact that lasts less than ``RESOLUTION * d`` of driver motion (d/100) is an
instant of the motion, not a step of its contact sequence: the contact-sequence
comparison contracts such boundary pieces (:func:`cspace.match.match`,
``resolution``).  They occur where two contacts hand over at a near-tangency,
as where the Geneva pin leaves a locking arc and the relief takes over: there a
box corner adds or drops a piece of 1e-5 to 6e-4 rad, on one side of the
tangency or the other.  What such an instant does to the output (the follower
may jump) is measured by the deviation test.  Channel closures and new free
components are found by probing, at any size.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np

from .accuracy import Accuracy, as_accuracy, same_geometry
from .errors import CSpaceError, InputError, JammedNominalError
from .freespace import ConfigurationSpace, Status, configuration_space
from .geom2d import TWO_PI
from .geometry import Assembly, Rotation, trusted
from .match import ChangeKind, cell_labels, match, operating_face
from .metric import follower_scale
from .model import check_model
from .simulate import SimStatus, SimulationResult, simulate
from .tolerances import SLACK

__all__ = ["assembled_start", "Reason", "DefectResult", "Reference", "reference", "is_defective",
           "default_deviation", "contact_parameters", "contact_tolerance", "check_deviation",
           "check_reference", "main_reason"]


#: Contacts lasting less than this share of d of driver motion are below the
#: resolution of the contact-sequence comparison (module docstring, "Resolution").
RESOLUTION = 0.01


class Reason(enum.Enum):
    TOPOLOGY = "free-space topology changed"
    DEVIATION = "output deviates by more than d"
    JAM = "the drive jams"
    INVALID = "the variant has invalid geometry"


@dataclass(frozen=True, eq=False)
class Reference:
    """Nominal data a defect test compares against (computed once per design)."""

    spaces: tuple          #: nominal ConfigurationSpace per pair
    sims: tuple            #: nominal SimulationResult per pair
    faces: tuple           #: operating face per pair
    starts: tuple          #: start configuration per pair
    drive: tuple
    accuracy: Accuracy
    nominal: np.ndarray
    d: float
    #: CurveCache filled with the nominal curves; variants tested against this
    #: reference reuse every curve their changed parameters do not touch
    cache: object = field(default=None, repr=False)
    #: per pair, how its follower start was chosen (a
    #: :class:`~cspace.freespace.StartChoice`) when the model states none, else None
    start_choices: tuple = ()
    #: per pair, the feature pairs the nominal keeps apart by a gap the
    #: tolerance box can close (:class:`cspace.near.NearPairs`; empty without
    #: tolerances)
    near: tuple = ()


def _pairs(out):
    return out.pairs if isinstance(out, Assembly) else (out,)


def _drive(model, cs: ConfigurationSpace):
    if getattr(model, "drive", None) is not None:
        return tuple(float(x) for x in model.drive)
    lo = cs.window[0]
    return (lo, lo + 2 * math.pi) if cs.periodic[0] else (cs.window[0], cs.window[1])


def default_deviation(model, spaces, sims=None) -> float:
    """``5 * t / L`` (C-space metric), ``t`` the largest tolerance of a
    parameter that moves a contact of the nominal motions ``sims``
    (:func:`contact_tolerance`), an angle's (a parameter of unit ``"rad"``)
    counted as the arc it turns through at ``L``, ``tol * L``: 5 times its
    tolerance in radians (:func:`deviation_parameter`).  (Compared as a
    length in the model's unit, an angle of 0.1 deg made d 0.0044 rad for a
    rocker drawn in inches and 0.0025 rad for the same rocker in
    millimetres.)"""
    L = min(cs.pair.char_length for cs in spaces)
    t = deviation_parameter(model, spaces, sims)[1]
    return 5.0 * t / L if t > 0 else 1e-3


def deviation_parameter(model, spaces, sims=None) -> tuple:
    """``(index or None, t)``: the parameter whose tolerance sets the default
    deviation threshold (:func:`default_deviation`) and that tolerance as a
    length (an angle's ``tol * L``); None where the model has no
    tolerances."""
    tol = np.asarray(getattr(model, "tol", ()), dtype=float)
    if not len(tol):
        return None, 0.0
    L = min(cs.pair.char_length for cs in spaces)
    angles = np.array([getattr(p, "unit", "") == "rad"
                       for p in getattr(model, "parameters", ())], dtype=bool)
    if angles.shape == tol.shape:
        tol = np.where(angles, tol * L, tol)
    i = _largest_moving(tol, contact_parameters(model, spaces, sims))
    return i, float(tol[i])


def _largest_moving(tol, moved) -> int:
    """The index of the largest of ``tol`` among the parameters ``moved``
    (:func:`contact_parameters`), of all where none is or it does not say."""
    pick = moved if moved is not None and moved.any() else np.ones(len(tol), dtype=bool)
    return int(np.argmax(np.where(pick, tol, -np.inf)))


def contact_parameters(model, spaces, sims=None):
    """Per parameter of ``model``, whether it moves a contact: a curve that
    bounds a cell the nominal motion (``sims``, one per space) passes through,
    or with no motions any contact curve of the C-spaces ``spaces``; (n,)
    bool, or None when the spaces do not say (no curves: a stand-in that has
    only its pair)."""
    names = list(getattr(model, "names", ()))
    if len(names) != len(getattr(model, "tol", ())):
        return None
    moved: set = set()
    for i, cs in enumerate(spaces):
        curves = getattr(cs, "curves", None)
        if curves is None:
            return None
        sim = sims[i] if sims is not None else None
        if sim is None:
            which = range(len(curves))
        else:
            which = {b for k, j in sim.cells for b in (cs.cells[k][j].lower,
                                                      cs.cells[k][j].upper) if b >= 0}
        for c in which:
            moved.update(curves[c].depends)
    return np.array([nm in moved for nm in names], dtype=bool)


def contact_tolerance(model, spaces, sims=None) -> float:
    """The largest tolerance of a parameter that moves a contact of the
    nominal motions (:func:`contact_parameters`); the largest of all where
    none does or the spaces do not say.

    A parameter that moves no contact of the motion (the length of a stem
    that never touches the cam) cannot change it, whatever its tolerance: a
    loose one must not loosen what scales with the tolerances (the default
    deviation threshold here, the synthesis's check-list filter and search
    stop), or a box that drives wrongly passes."""
    tol = np.asarray(getattr(model, "tol", ()), dtype=float)
    if not len(tol):
        return 0.0
    return float(tol[_largest_moving(tol, contact_parameters(model, spaces, sims))])


def main_reason(reasons):
    """Of a defect's ``reasons`` (:attr:`DefectResult.reasons`), the one that
    :attr:`DefectResult.where` places: a jam when the drive jams (it is placed
    where the drive jams), else the first; None for none."""
    reasons = tuple(reasons or ())
    if Reason.JAM in reasons:
        return Reason.JAM
    return reasons[0] if reasons else None


def reference(model, accuracy: Accuracy | str | None = None, d: float | None = None,
              u=None, *, allow_jam: bool = False) -> Reference:
    """Nominal C-spaces, simulations and operating channels of a model (at ``u``,
    default the nominal vector).

    A nominal whose own motion jams raises :class:`JammedNominalError`: there
    is no healthy motion to test variants against.  ``allow_jam=True`` keeps
    it (the synthesis loop's reference of a shifted design, which it tests
    against the initial one and stops on when it is defective)."""
    check_model(model)
    acc = as_accuracy(accuracy)
    u0 = model.nominal if u is None else np.asarray(u, dtype=float)
    pairs = _pairs(model.build(u0))
    deps = model.dependencies()
    from .cache import CurveCache
    cache = CurveCache()
    spaces = tuple(configuration_space(p, acc, window=model.window, deps=dd, cache=cache)
                   for p, dd in zip(pairs, deps))
    drive = _drive(model, spaces[0])
    q2s = getattr(model, "q2_start", None)
    choices = (None,) * len(spaces)
    if q2s is None:
        choices = tuple(cs.start_choice(drive[0]) for cs in spaces)
        q2s = tuple(c.q2 for c in choices)
    q2s = tuple(float(v) for v in q2s)
    if len(q2s) == 1 and len(pairs) > 1:
        q2s = q2s * len(pairs)
    if len(q2s) != len(pairs):
        raise InputError(f"model {getattr(model, 'name', '')!r}: q2_start must give one follower "
                         f"start per pair ({len(pairs)}) or one for all, got {len(q2s)}: "
                         f"{list(q2s)}", name="q2_start", value=list(q2s))
    sims, faces, starts = [], [], []
    for cs, q2 in zip(spaces, q2s):
        start = (drive[0], float(q2))
        f = operating_face(cs, start)
        if f < 0:
            raise CSpaceError(_blocked_start(model, cs, start))
        sim = simulate(cs, drive[0], drive[1], q2)
        if sim.status == SimStatus.START_BLOCKED:
            raise CSpaceError(_blocked_start(model, cs, start))
        ch = choices[len(sims)]
        if sim.status == SimStatus.JAMMED and ch is not None:
            ch, start, f, sim = _completing_start(cs, ch, drive, (ch, start, f, sim))
            choices = choices[:len(sims)] + (ch,) + choices[len(sims) + 1:]
        sims.append(sim)
        faces.append(f)
        starts.append(start)
    jammed = [i for i, s in enumerate(sims) if s.status == SimStatus.JAMMED]
    if jammed and not allow_jam:
        i = jammed[0]
        err = JammedNominalError(_jammed_nominal(model, spaces[i], sims[i], i, drive))
        err.sims = tuple(sims)      # the nominal motions, for a caller that draws them
        raise err
    if d is None:
        d = getattr(model, "deviation", None)
    dd = default_deviation(model, spaces, sims) if d is None else check_deviation(d)
    tol = np.asarray(getattr(model, "tol", ()), dtype=float)
    near = ()
    if tol.shape == u0.shape and np.any(tol > 0):
        from .near import near_pairs
        near = tuple(near_pairs(model, i, p, cs, u0, tol)
                     for i, (p, cs) in enumerate(zip(pairs, spaces)))
    return Reference(spaces, tuple(sims), tuple(faces), tuple(starts), drive, acc,
                     np.array(u0, dtype=float), dd, cache, choices, near)


def _completing_start(cs, choice, drive, jammed) -> tuple:
    """A default start (``choice``, :meth:`ConfigurationSpace.start_choice`)
    from which the nominal motion jams: the middle of the widest other free
    interval from which it completes the drive, as ``(choice, start, face,
    simulation)``, else ``jammed`` (the same tuple for the jamming start)."""
    from dataclasses import replace
    ivs = choice.intervals
    tried = [choice.chosen]
    for k in sorted(range(len(ivs)), key=lambda i: -(ivs[i][1] - ivs[i][0])):
        if k == choice.chosen:
            continue
        q2 = 0.5 * (ivs[k][0] + ivs[k][1])
        if cs.periodic[1]:
            from .freespace import _wrap
            q2 = float(_wrap(np.array([q2]), cs.window[2])[0])
        start = (drive[0], q2)
        f = operating_face(cs, start)
        if f >= 0:
            sim = simulate(cs, drive[0], drive[1], q2)
            if sim.status == SimStatus.OK:
                jams = tuple(i for i in tried if ivs[i][1] - ivs[i][0] >= ivs[k][1] - ivs[k][0])
                return replace(choice, q2=float(q2), chosen=k, jams=jams), start, f, sim
        tried.append(k)
    return jammed


def _jammed_nominal(model, cs, sim, i: int, drive) -> str:
    """What to say of a nominal design whose own motion jams (pair ``i``)."""
    name = getattr(model, "name", "")
    pair = getattr(cs.pair, "name", "") or f"pair {i}"
    q1, q2 = sim.jam_q
    return (f"model {name!r}: the nominal design's motion jams, so there is no healthy motion "
            f"to test variants against: {pair}: driver blocked at q1 = {_q1_text(cs, q1)} "
            f"(q2 = {q2:.6g}), {sim.jam_reason}; the drive runs q1 from {drive[0]:.6g} to "
            f"{drive[1]:.6g}.  A defect test, a synthesis or a yield needs a nominal that "
            f"completes its drive: change the nominal geometry or the drive range "
            f"('cspace-tol analyze' draws where it jams)")


def _q1_text(cs, q1: float) -> str:
    """A driver value along the drive, with its place in the window when a
    turning driver has gone round (a Geneva drive runs four turns)."""
    lo, hi = cs.window[0], cs.window[1]
    if cs.periodic[0] and not lo <= q1 <= hi:
        return f"{q1:.5g} ({(q1 - lo) % (hi - lo) + lo:.5g} in the window)"
    return f"{q1:.5g}"


def _blocked_start(model, cs, start) -> str:
    """What to say of a stated follower start that is not free in the C-space
    ``cs`` of the vector the reference is made for: where it lies, and the
    free follower positions at the drive's start."""
    q1, q2 = start
    lo2, hi2 = cs.window[2], cs.window[3]
    if not cs.periodic[1] and not lo2 <= q2 <= hi2:
        where = f"outside the follower window [{lo2:.6g}, {hi2:.6g}]"
    else:
        where = "blocked (the parts overlap there" + _contacts_around(cs, q1, q2) + ")"
    try:
        ivs = [(a, b) for a, b, _ in cs.free_intervals(q1)]
    except CSpaceError:
        ivs = []
    if not ivs:
        where += ("; no follower position is free at the drive's start: the parts do not "
                  "fit together there (a pin wider than its slot, a channel of zero or "
                  "negative width)")
    free = (", ".join(f"[{a:.6g}, {b:.6g}]" for a, b in ivs) if ivs else "none")
    rot = isinstance(cs.pair.follower.axis, Rotation)
    unit = "rad" if rot else (getattr(model, "units", "") or "model length units")
    return (f"model {getattr(model, 'name', '')!r}: the start configuration (q1, q2) = "
            f"({q1:.6g}, {q2:.6g}) of pair {cs.pair.name!r} is {where}; q2_start must be a "
            f"free follower position at the drive's start: free q2 at q1 = {q1:.6g}: {free} "
            f"({unit})")


def _contacts_around(cs, q1: float, q2: float) -> str:
    """``", between the contacts A (below) and B (above)"``: the contact curves
    that bound the blocked cell around (q1, q2), or "" where the C-space
    cannot say."""
    try:
        lo, hi = cell_labels(cs, q1, q2)
    except (CSpaceError, IndexError, ValueError):
        return ""
    if lo and hi:
        return f", between the contacts {lo} (below) and {hi} (above)"
    if lo or hi:
        return f", beyond the contact {lo or hi}"
    return ""


def check_deviation(d) -> float:
    """A deviation threshold: a finite number > 0 (C-space metric)."""
    try:
        v = float(d)
    except (TypeError, ValueError, OverflowError):
        v = math.nan
    if isinstance(d, (bool, str, bytes)) or not (math.isfinite(v) and v > 0):
        from .accuracy import PRESETS
        hint = (f" (the name of an accuracy preset: pass it as accuracy={d!r})"
                if isinstance(d, str) and d in PRESETS else "")
        raise InputError(f"deviation threshold d must be a finite number > 0 (C-space "
                         f"metric), got {d!r}{hint}", name="d", value=d)
    return v


@dataclass(frozen=True)
class DefectResult:
    """Whether a variant is defective, and why.

    Attributes
    ----------
    defective : bool
    reasons : tuple of Reason
    max_deviation : float
        Largest |f - f0| over the common driver range (C-space metric).
    d : float
        Threshold used.
    where : tuple or None
        A configuration where it goes wrong, with the pair index: (pair, q1,
        q2): where the drive jams when it does (unless a change of the contact
        sequence comes earlier along the drive), else where the topology
        changes, else where the output deviates most.
    matches : tuple of MatchResult
    sims : tuple of SimStatus
    message : str
    """

    defective: bool
    reasons: tuple
    max_deviation: float
    d: float
    where: tuple | None
    matches: tuple = ()
    sims: tuple = ()
    message: str = ""

    def __bool__(self) -> bool:
        """True iff the variant is defective, so that ``if is_defective(m, u):``
        reads as it says (a result object is otherwise always true)."""
        return bool(self.defective)

    @property
    def main_reason(self):
        """The reason that ``where`` places (:func:`main_reason`)."""
        return main_reason(self.reasons)

    def __repr__(self):
        if not self.defective:
            return f"<DefectResult: healthy (max deviation {self.max_deviation:.3g} <= d {self.d:.3g})>"
        return f"<DefectResult: DEFECTIVE - {self.message}>"

    def to_dict(self) -> dict:
        return {"defective": self.defective, "reasons": [r.value for r in self.reasons],
                "max_deviation": self.max_deviation if math.isfinite(self.max_deviation) else None,
                "d": self.d,
                # a coordinate the test could not place (NaN) is written as null
                "where": ([self.where[0]] + [float(x) if math.isfinite(x) else None
                                             for x in self.where[1:]]
                          if self.where else None),
                "matches": [m.to_dict() for m in self.matches],
                "sims": [s.name for s in self.sims], "message": self.message}

    @classmethod
    def from_dict(cls, d: dict) -> "DefectResult":
        """The result written by :meth:`to_dict`, without the match details
        (``matches`` is empty).  Raises ``KeyError``, ``TypeError`` or
        ``ValueError`` on a document that is not one."""
        if not isinstance(d, dict):
            raise TypeError(f"a defect result must be a JSON object, got {type(d).__name__}")
        where = d["where"]
        if where is not None:
            if not isinstance(where, list) or len(where) != 3:
                raise ValueError(f"where must be [pair, q1, q2] or null, got {where!r}")
            where = (int(where[0]),) + tuple(math.nan if x is None else float(x)
                                             for x in where[1:])
        dev = d["max_deviation"]
        return cls(_bool(d["defective"]), tuple(Reason(r) for r in d["reasons"]),
                   math.inf if dev is None else float(dev), float(d["d"]), where, (),
                   tuple(SimStatus[s] for s in d["sims"]), str(d["message"]))


def check_reference(model, ref, pairs=None, *, none_ok: bool = True) -> None:
    """Refuse a ``ref`` that is not a :class:`Reference` of ``model`` (of its
    nominal or of another design of the same model): an
    :class:`~cspace.errors.InputError` when it is no Reference, when its
    nominal vector does not have one value per parameter of ``model``, or,
    given the ``pairs`` a vector of ``model`` builds, when it holds another
    number of pairs or pairs of other parts.  ``none_ok``: the caller
    takes ``ref=None`` too (it then makes the reference itself), and the
    messages offer it."""
    name = getattr(model, "name", type(model).__name__)
    alt = ", or None" if none_ok else ""
    alt_ref = " or ref=None" if none_ok else ""
    if not isinstance(ref, Reference):
        raise InputError(f"ref must be a cspace.defects.Reference (reference(model, accuracy)) "
                         f"of model {name!r}{alt}, got {type(ref).__name__}", name="ref",
                         value=ref)
    n = len(np.atleast_1d(np.asarray(model.nominal)))
    nr = int(np.size(ref.nominal))
    if np.ndim(ref.nominal) != 1 or nr != n:
        raise InputError(f"ref is the reference of another model: its nominal vector has {nr} "
                         f"values, model {name!r} has {n} parameters; pass a reference of this "
                         f"model (cspace.defects.reference(model, accuracy)){alt_ref}",
                         name="ref", value=ref)
    if pairs is None:
        return
    if len(pairs) != len(ref.spaces):
        raise InputError(f"ref is the reference of another model: it holds {len(ref.spaces)} "
                         f"pair(s), model {name!r} builds {len(pairs)}; pass a reference of "
                         f"this model (cspace.defects.reference(model, accuracy)){alt_ref}",
                         name="ref", value=ref)
    for i, (p, cs) in enumerate(zip(pairs, ref.spaces)):
        got, want = tuple(q.name for q in p.parts), tuple(q.name for q in cs.pair.parts)
        if got != want:
            raise InputError(f"ref is the reference of another model: its pair {i} has the "
                             f"parts {list(want)}, model {name!r} builds {list(got)}; pass a "
                             f"reference of this model (cspace.defects.reference(model, "
                             f"accuracy)){alt_ref}", name="ref", value=ref)


def is_defective(model, params=None, d: float | None = None, *,
                 accuracy: Accuracy | str | None = None, ref: Reference | None = None,
                 cache=None, stop_early: bool = False, first_pair: int | None = None
                 ) -> DefectResult:
    """Defect test of one variant.

    Parameters
    ----------
    model : parametric model
    params : parameter vector or mapping (default nominal)
    d : float, optional
        Output deviation threshold (C-space metric); default the reference's
        (``ref.d``: the model's ``deviation`` when it states one, else
        :func:`default_deviation`).
    accuracy : Accuracy or preset name
        Used to compute the reference when ``ref`` is None; with a ``ref``,
        it must set the same knobs as the reference's (an
        :class:`~cspace.errors.InputError` otherwise), or be None.
    ref : Reference, optional
        Precomputed nominal reference (reuse it across many variants), of
        this model (of its nominal or of another design of it): a reference
        of another model (another parameter count, pair count or parts) is
        an :class:`~cspace.errors.InputError` (:func:`check_reference`).
    cache : CurveCache, optional
        Reuse of contact curves across variants (see :mod:`cspace.cache`);
        default the reference's own cache (filled with the nominal curves).
    stop_early : bool
        Return at the first defect found (for a search that needs only the
        verdict): the pairs are tested from ``first_pair`` on, and in each pair
        the jam and the deviation (cheap once the motion is simulated) before
        the topology.  ``defective`` is the same as without it; ``reasons``,
        ``where`` and ``max_deviation`` then describe only what was tested.
    first_pair : int, optional
        With ``stop_early``, the pair to test first (e.g. the one where the end
        of the searched segment was defective).
    """
    if ref is None:
        ref = reference(model, accuracy, d)
    else:
        check_reference(model, ref)
    if accuracy is not None and not same_geometry(as_accuracy(accuracy), ref.accuracy):
        raise InputError(f"accuracy {as_accuracy(accuracy).name!r} differs from the accuracy "
                         f"{ref.accuracy.name!r} the reference was computed with; pass one "
                         "of them (the reference's is used when accuracy is None)",
                         name="accuracy", value=accuracy)
    dd = ref.d if d is None else check_deviation(d)
    acc = ref.accuracy
    if cache is None:
        cache = ref.cache
    u = model.vector(params) if hasattr(model, "vector") else np.asarray(params, dtype=float)
    try:
        with trusted():
            pairs = _pairs(model.build(u))
    except (ValueError, ArithmeticError) as e:
        return DefectResult(True, (Reason.INVALID,), math.inf, dd, None, (), (),
                            f"invalid geometry: {e}")
    check_reference(model, ref, pairs)
    deps = model.dependencies()
    if stop_early:
        return _first_defect(model, pairs, deps, ref, acc, dd, cache, first_pair)
    reasons, matches, sims = [], [], []
    where = None
    maxdev = 0.0
    msgs = []
    for i, (pair, cs0, sim0, start) in enumerate(zip(pairs, ref.spaces, ref.sims, ref.starts)):
        cs = configuration_space(pair, acc, window=model.window, deps=deps[i], cache=cache)
        q2v = assembled_start(cs0, cs, start)
        sim = simulate(cs, ref.drive[0], ref.drive[1], q2v)
        m = match(cs0, cs, start, resolution=RESOLUTION * dd, paths=(sim0, sim),
                  variant_start=(start[0], q2v))
        matches.append(m)
        if not m.same:
            if Reason.TOPOLOGY not in reasons:
                reasons.append(Reason.TOPOLOGY)
            ch = m.changes[0]
            where = where or (i, ch.q[0], ch.q[1])
            msgs.append(f"{pair.name}: {ch.kind.value} at q1 = {_q1_text(cs0, ch.q[0])} "
                        f"({ch.detail})")
        sims.append(sim.status)
        if sim.status != SimStatus.OK:
            if Reason.JAM not in reasons:
                reasons.append(Reason.JAM)
            jq = sim.jam_q or (ref.drive[0], start[1])
            # where the drive meets the closure: before where a probe of the
            # split channel (or a new component) lies, and before a change of
            # the contact sequence that the motion reaches only after it
            way = 1.0 if ref.drive[1] >= ref.drive[0] else -1.0
            if where is None or (where[0] == i and m.changes and (
                    m.changes[0].kind is not ChangeKind.SEQUENCE_CHANGED
                    or way * (where[1] - jq[0]) > 0)):
                where = (i, jq[0], jq[1])
            msgs.append(f"{pair.name}: {sim.message}")
        dev = _deviation(sim, sim0, cs0)
        if dev[0] > maxdev:
            maxdev = dev[0]
            if dev[0] > dd:
                where = where or (i, dev[1], dev[2])
    if maxdev > dd:
        reasons.append(Reason.DEVIATION)
        msgs.append(f"output deviates by {maxdev:.4g} > d = {dd:.4g} (C-space metric)")
    return DefectResult(bool(reasons), tuple(reasons), float(maxdev), dd, where, tuple(matches),
                        tuple(sims), "; ".join(msgs) if msgs else "healthy")


def _first_defect(model, pairs, deps, ref, acc, dd, cache, first) -> DefectResult:
    """:func:`is_defective` with ``stop_early``: the first defect found."""
    n = len(pairs)
    if first is not None and not (isinstance(first, (int, np.integer)) and 0 <= first < n):
        raise InputError(f"first_pair must be a pair index in [0, {n - 1}], got {first!r}",
                         name="first_pair", value=first)
    k0 = 0 if first is None else int(first)
    maxdev, sims, matches = 0.0, [], []
    for i in [k0] + [k for k in range(n) if k != k0]:
        pair, cs0, sim0, start = pairs[i], ref.spaces[i], ref.sims[i], ref.starts[i]
        cs = configuration_space(pair, acc, window=model.window, deps=deps[i], cache=cache)
        sim = simulate(cs, ref.drive[0], ref.drive[1], assembled_start(cs0, cs, start))
        sims.append(sim.status)
        if sim.status != SimStatus.OK:
            jq = sim.jam_q or (ref.drive[0], start[1])
            return DefectResult(True, (Reason.JAM,), maxdev, dd, (i, jq[0], jq[1]), (),
                                tuple(sims), f"{pair.name}: {sim.message}")
        dev = _deviation(sim, sim0, cs0)
        maxdev = max(maxdev, dev[0])
        if dev[0] > dd:
            return DefectResult(True, (Reason.DEVIATION,), float(maxdev), dd,
                                (i, dev[1], dev[2]), (), tuple(sims),
                                f"output deviates by {dev[0]:.4g} > d = {dd:.4g} "
                                f"(C-space metric)")
        m = match(cs0, cs, start, resolution=RESOLUTION * dd, paths=(sim0, sim))
        matches.append(m)
        if not m.same:
            ch = m.changes[0]
            return DefectResult(True, (Reason.TOPOLOGY,), float(maxdev), dd,
                                (i, ch.q[0], ch.q[1]), tuple(matches), tuple(sims),
                                f"{pair.name}: {ch.kind.value} at q1 = {ch.q[0]:.5g} "
                                f"({ch.detail})")
    return DefectResult(False, (), float(maxdev), dd, None, tuple(matches), tuple(sims),
                        "healthy")


def assembled_start(nominal: ConfigurationSpace, variant: ConfigurationSpace, start) -> float:
    """Where a variant's follower starts (module docstring, "Start").

    The stated start ``start = (q1, q2)`` when it is free or in contact in the
    variant; otherwise the point nearest to it, a hair inside, of the
    variant's channel at ``q1``: its free interval that overlaps the nominal's
    free interval containing the start (of those that do, the one nearest to
    the start), else, when the channel moved by more than its width (a tight
    fit whose parts are both off: no overlap), its free interval bounded by
    the same contact curves (features and branch) as the nominal's, the one
    nearest to the start; the stated value when there is none (the start is
    blocked).  The batched test (:mod:`cspace.batch.margins`) follows the
    nominal channel's bounding curves in the variant, so both start a variant
    in the same channel.
    """
    q1, q2 = float(start[0]), float(start[1])
    st = variant.classify(np.array([[q1, q2]]))[0]
    if st == Status.FREE or (st == Status.CONTACT and _on_free_interval(variant, q1, q2)):
        return q2
    scale = follower_scale(variant.pair)
    tol = max(nominal.accuracy.contact_rel, SLACK) * scale
    periodic = bool(variant.periodic[1])
    shifts = (-TWO_PI, 0.0, TWO_PI) if periodic else (0.0,)
    home = [(lo, hi, c) for lo, hi, c in nominal.free_cells(q1)
            if any(lo - tol <= q2 + sh <= hi + tol for sh in shifts)]
    if not home:
        return q2
    lo0, hi0, cell0 = home[0]
    # the stated start on the turn of the nominal's interval (a rotating
    # follower's interval may run past the window's top)
    turn = next(t for t in shifts if lo0 - tol <= q2 + t <= hi0 + tol)
    at = q2 + turn
    inset = SLACK * scale
    cells = [fc for fc in variant.free_cells(q1) if fc[1] - fc[0] > 2 * inset]
    best = _nearest_in(cells, shifts, at, inset, lambda a, b: min(b, hi0) - max(a, lo0) > 0)
    if best is None:
        # no overlap: the interval between the nominal channel's own curves
        want = _cell_curves(nominal, cell0)
        same = [fc for fc in cells if _cell_curves(variant, fc[2]) == want]
        best = _nearest_in(same, shifts, at, inset, lambda a, b: True)
    return q2 if best is None else best - turn


def _on_free_interval(cs: ConfigurationSpace, q1: float, q2: float) -> bool:
    """Whether ``q2`` lies on a free interval of ``cs`` at ``q1`` (its ends
    included) within the tolerance the simulation places a start with
    (:class:`cspace.simulate.simulate`: a start in contact).  A start the
    C-space classifies as a contact may lie a little deeper than that in the
    part (a force-closed follower stated on its cam, whose variant's cam is
    1e-6 higher): the simulation would refuse it, so the variant is placed
    as a blocked one is."""
    tol = max(cs.accuracy.contact_rel, SLACK)
    shifts = (-TWO_PI, 0.0, TWO_PI) if cs.periodic[1] else (0.0,)
    return any(lo - tol <= q2 + sh <= hi + tol for lo, hi, _ in cs.free_intervals(q1)
               for sh in shifts)


def _nearest_in(intervals, shifts, at: float, inset: float, keep):
    """The point nearest to ``at``, ``inset`` inside, of the intervals ``(lo,
    hi, ...)`` (on each turn of ``shifts``) that ``keep(lo, hi)`` accepts; None
    when there is none."""
    best = None
    for lo, hi, _ in intervals:
        for sh in shifts:
            a, b = lo + sh, hi + sh
            if not keep(a, b):
                continue
            c = min(max(at, a + inset), b - inset)
            if best is None or abs(c - at) < abs(best - at):
                best = c
    return best


def _cell_curves(cs: ConfigurationSpace, cell) -> tuple:
    """The contact curves (label and branch; None for a window edge) bounding a
    free cell of ``cs`` below and above: what names a channel in any variant."""
    def key(i):
        return None if i < 0 else (cs.curves[i].label, cs.curves[i].branch)
    return key(cell.lower), key(cell.upper)


def _deviation(sim: SimulationResult, sim0: SimulationResult, cs: ConfigurationSpace):
    """Largest |f - f0| over the common driver range, in the C-space metric of
    ``cs``, the nominal's: a sliding follower's slide over the nominal's
    characteristic length, so that d is the same length for every variant
    (a variant's own characteristic length moves with its dimensions)."""
    if len(sim.q1) < 2:
        return (0.0, sim.q1[0] if len(sim.q1) else 0.0, 0.0)
    lo = max(min(sim.q1), min(sim0.q1))
    hi = min(max(sim.q1), max(sim0.q1))
    x = sim0.q1[(sim0.q1 >= lo) & (sim0.q1 <= hi)]
    if not len(x):
        return (0.0, lo, 0.0)
    f0 = sim0.output_at(x)
    f = sim.output_at(x)
    dv = np.abs(f - f0) / follower_scale(cs.pair)
    i = int(np.argmax(dv))
    return (float(dv[i]), float(x[i]), float(f[i]))


def _bool(v) -> bool:
    if not isinstance(v, bool):
        raise TypeError(f"expected true or false, got {v!r}")
    return v
