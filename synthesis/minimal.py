"""Minimal changes from defect margins: the removal step ``removal="lp"``.

The paper's removal ([Tolerance synthesis] §4.3, Eqs. 3–5; :mod:`synthesis.removal`)
moves one box edge per defective vector onto its transition point, and cuts
every tolerance a returning vector's segment moves.  Its closing section names
the next step: let the cost of each change decide.  This module takes it for
every defect that has a continuous margin.

Margin sensitivities
--------------------
A defective vector fails one or more of the batched margins of
:func:`cspace.batch.margins.defect_margins` (``channel`` and ``start`` per
pair, ``deviation``; ``sequence`` per pair): those <= 0.  The sensitivities
of its failing defect margins (:data:`LINEARISED`: channel and deviation;
not the start margin, whose failing is no defect: the variant starts at the
nearest point of its channel) to each parameter are central finite
differences,

    g_i = (m(u + h_i e_i) - m(u - h_i e_i)) / (2 h_i),    h_i = FD_STEP * t_i,

for every axis with a positive tolerance t_i (current box), all vectors of
all defects in batched calls (:func:`margin_sensitivities`): the defects'
vectors, then 2 n steps per defect that fails a continuous margin.  A defect
that fails only its sequence margin gets no steps (its differences would be
at the noise level, below, and are never used: gradient 0, noise infinite).
Steps of a defect whose channel margin holds skip the per-variant hand-over
samples of the batch, which only the channel and sequence margins read (the
same numbers, about a third less time), and every step is evaluated without
verdicts (:func:`cspace.batch.margins.margin_tables`: no certification, and a
chunk of such steps without what only the verdicts read; the same numbers,
about a sixth less time).  On the Geneva pair's first check
list, 128 of the 223 defects fail only their sequence, the other 95 only
their deviation.  (One-sided differences across the whole box, half the
vectors, were tried: on the reciprocating cam their slopes, secants over a
kink of the narrowest gap, gave a shift whose next check list had 46
deviation defects instead of none.)

**Noise level.**  The batch trusts a margin only to within its band: a
channel or start margin within ``Accuracy.batch_gap_band`` of zero is left to
the full test, a deviation margin is trusted to ``Accuracy.batch_dev_band *
d`` (the most the full test's reading may differ by where the batch cannot
bound it sample by sample; :mod:`cspace.batch.margins`); a
sequence margin moves in steps of its resolution (``RESOLUTION * d`` of driver
motion, :mod:`cspace.defects`).  Each of the two margins of a difference may
be off by that band ``b``, so a sensitivity is known to ``2 b / (2 h_i)``:
that is its noise level,

    noise_i = b / h_i = b / (FD_STEP * t_i),

and a sensitivity *counts* only where ``|g_i| > noise_i``, i.e. where moving the
parameter across one tolerance width (from ``u - t_i/2`` to ``u + t_i/2``)
changes the margin by more than twice its band.  Sensitivities below the noise
are set to zero: the defect is taken not to depend on that parameter.  A
sequence margin is piecewise constant (a contact sequence changes or it does
not), so its sensitivities are at the noise level; a defect that fails only
its sequence (or whose failing margins have no sensitivity above the noise,
or which only the full test found defective) has no usable margin and is
removed by the paper's rule (below).

Linearised margins
------------------
A failing margin m at u_j with sensitivities g (above the noise) gives the
linear model m(u) ~ m_j + g . (u - u_j).  Over the box ``c +/- t'`` its
smallest value is at the corner ``c - sign(g) t'``:

    m_j + g . (c - u_j) - sum_i |g_i| t'_i.

For a deviation margin, ``d - max |f - f0|``, the linear model of the
deviation itself at the failing instant is kept on both sides: the defect's
constraint says the deviation must not exceed d on its own side, and a
*companion* (margin ``2 d - m_j``, gradient ``-g``, the same point) says a shift
must not push it past d on the other side.  Without it a shift that cures one
side of a two-sided deviation is free to create the other (on the Geneva pair
the first LP moved 14 parameters by 0.0066 cm and the next check list had 225
defective vectors instead of 223).

The box is clear of that defect when this is at least the target
``TARGET * b`` (a tenth of the margin's band: positive, and far below any
manufacturing resolution; a larger target widens every fix by the same
amount of margin).  This is a linear constraint in the shift ``c - u0`` and
the new tolerances ``t'`` (:class:`Linearised`).

The smallest change (:func:`minimal_change`)
--------------------------------------------
Every known defect's constraint (this iteration's, and those of earlier
iterations, which the run keeps so that a shift does not bring an earlier
defect back; a defect of the same origin, kind and pair found again replaces
its earlier linearisation) is put into a small LP (:func:`scipy.optimize.linprog`,
HiGHS), solved lexicographically:

1. **shift only**: minimise the weighted largest move ``max_i w_i |Δu_i|``
   (``w`` = :attr:`synthesis.guards.Guards.shift_cost`; ``e`` of the run is
   this maximum for w = 1), then, at that maximum, the weighted sum
   ``sum_i w_i |Δu_i|`` (so that no parameter moves without need).  Fixed
   parameters do not move; no parameter moves more than ``SHIFT_TRUST`` times
   its initial tolerance in one iteration (the linear model is a local one);
2. **cuts, as the last resort**, only when no such shift exists: minimise

       sum_i c_i (-log(t'_i / t0_i)) + SHIFT_PRICE sum_i w_i |Δu_i| / t0_i

   (``c`` = :attr:`~synthesis.guards.Guards.cut_cost`, ``t0`` the initial
   tolerances; ``-log`` is replaced by the largest of its tangents at kept
   fractions 1, 0.95, ..., 0.02, so that the problem stays an LP), then the
   largest and the summed shift as in 1.  With unit costs the first sum is
   minus the log of the box volume kept: the cut takes from the largest
   tolerances first (a cut of 0.01 from 0.03 keeps more volume than from
   0.02), and neither cuts one parameter down to its floor to spare another
   a little nor spreads one relative cut over all.  In this phase a shift is no
   longer free: moving a nominal by its initial tolerance costs as much as
   keeping 1/e of a tolerance (``SHIFT_PRICE`` = 1); with shifts free, the
   first Geneva LP shifted ten parameters by a whole tolerance to spare a
   little of a cut.  A tolerance may be cut only if some defect's sensitivity
   to it counts (above the noise), never a hard one, and never below its
   ``min_keep`` floor.  So the cut is the smallest that makes the linearised
   margins positive at the box corners, not one relative cut of every
   parameter a vector moves.

Cuts for two-sided defects
--------------------------
A defect found at one side of the nominal only (its mirror through the
nominal is healthy) can be cleared by a shift; a cut is what a defect found
at both sides needs, since a shift that clears one side moves the other
towards its limit.  So in phase 2 a one-sided defect's constraint is *shift
only*: it must hold with the tolerances before the cut (a cut does not count
for it), and the cuts serve the two-sided defects alone
(:func:`shift_only`).  Only when that has no solution are the cuts let count
for every defect (on the Geneva pair the rule has none: shifting away its
106 one-sided deviations moves them into the two-sided ones' companions).
Either way, a cut is attributed to a defect found at both sides that it
serves (active, and depending on the parameter) before a one-sided one.

A linearised defect that no allowed change clears (its linear model may not
hold over the box: a deviation that jumps where a contact hands over, as on
the optical cams, where the first LP asked for cuts below ``min_keep``) is
handed to the paper's rule, which moves the box by tested points; an earlier
iteration's linearisation that no allowed change satisfies is forgotten.  A
defect that the paper's rule cannot remove either makes the plan
*infeasible* (:attr:`synthesis.removal.ShiftPlan.infeasible`, status
``INFEASIBLE``).

Every change is attributed to the defect that required it: among the
constraints active at the solution (zero slack), the one that depends most on
that parameter (``|g_i| t0_i / b`` largest; this iteration's before earlier
ones).

The removal step (:func:`lp_removal`)
-------------------------------------
Per iteration: the defective vectors whose search margin (channel or
deviation) fails get sensitivities; those with a usable margin become
constraints, the others are removed by the paper's search and greedy
(:func:`synthesis.removal.plan_with_refinement`); the LP then finds the
smallest change that also keeps the greedy's shifts (at least as far, in the
same direction) and cuts.  The next iteration's defect tests confirm it, and a
defect still there is linearised again where it now fails (a Newton step).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from cspace.errors import InputError

__all__ = ["FD_STEP", "TARGET", "SHIFT_TRUST", "SHIFT_PRICE", "KINDS", "CONTINUOUS", "LINEARISED",
           "REMOVALS",
           "MarginSensitivity", "margin_bands", "margin_sensitivities", "sensitivity_task",
           "Linearised", "linearise", "MinimalChange", "minimal_change", "lp_removal",
           "shift_only",
           "known_from_dicts"]

#: Removal methods of :func:`synthesis.synthesize`: ``"lp"`` (this module) and
#: ``"greedy"`` (the paper's Eqs. 3–5, :mod:`synthesis.removal`).
REMOVALS = ("lp", "greedy")
#: Finite-difference step, relative to the current tolerance of the axis.
FD_STEP = 0.5
#: The margin a fix aims at, relative to the margin's band.
TARGET = 0.1
#: The largest shift of one parameter in one iteration, relative to its
#: initial tolerance.
SHIFT_TRUST = 1.0
#: In the cut phase, the price of a shift by one initial tolerance, against the
#: cut cost ``-log(kept fraction)`` of a tolerance (1: as much as keeping 1/e of it).
SHIFT_PRICE = 1.0
#: The margins of :class:`cspace.batch.margins.MarginBatch`, and those with a
#: continuous value (a sequence margin jumps).
KINDS = ("channel", "sequence", "deviation", "start")
CONTINUOUS = ("channel", "deviation", "start")
#: The continuous margins a fix must keep positive: those whose failing is a
#: defect.  Not the start margin: a variant whose channel lies off the stated
#: start starts at the nearest point of it, as the full test assembles it
#: (:class:`cspace.batch.margins.MarginBatch`); a channel closed there is the
#: channel margin's.  Kept as a constraint, it asked the fix to keep every
#: corner's channel around the stated start, and cut tolerances that no
#: defect depends on (a Scotch yoke whose slot the shift moved: the crank
#: radius, crank centre and slot place cut to half).
LINEARISED = ("channel", "deviation")

_SLACK = 1e-6       # band units: a constraint with less slack is active
_NEGLIGIBLE = 1e-6  # of the initial tolerance: a smaller shift or cut is none
#: Kept fractions at which -log(kept) is replaced by its tangent (the cut cost of
#: :func:`minimal_change` is the largest of these tangents).
_KEPT = (1.0, 0.95, 0.9, 0.85, 0.8, 0.75, 0.7, 0.65, 0.6, 0.55, 0.5, 0.45, 0.4, 0.35, 0.3,
         0.25, 0.2, 0.15, 0.1, 0.05, 0.02)


def margin_bands(accuracy, d: float) -> dict:
    """The band of each margin kind (C-space metric): how far the batch trusts
    it (see "Noise level" in the module docstring)."""
    from cspace.accuracy import as_accuracy
    from cspace.defects import RESOLUTION
    acc = as_accuracy(accuracy)
    return {"channel": acc.batch_gap_band, "start": acc.batch_gap_band,
            "deviation": acc.batch_dev_band * float(d), "sequence": RESOLUTION * float(d)}


@dataclass(frozen=True, eq=False)
class MarginSensitivity:
    """One failing margin of one vector and its sensitivities.

    Attributes
    ----------
    kind : str
        ``"channel"``, ``"sequence"``, ``"deviation"`` or ``"start"``.
    pair : int
        Pair index (-1 for the deviation, which covers all pairs).
    margin : float
        Its value at the vector (<= 0; C-space metric).
    gradient : (n,) float
        Central finite differences, per model unit (0 on axes of zero
        tolerance; one-sided where one side does not build).
    noise : (n,) float
        The noise level of each sensitivity, ``band / h_i`` (twice that for a
        one-sided difference; inf on axes of zero tolerance, or where neither
        side builds).
    band : float
        The margin's band (:func:`margin_bands`).
    """

    kind: str
    pair: int
    margin: float
    gradient: np.ndarray
    noise: np.ndarray
    band: float

    @property
    def significant(self) -> np.ndarray:
        """(n,) bool: the sensitivities above the noise."""
        return np.abs(self.gradient) > self.noise

    @property
    def usable(self) -> bool:
        """A defect margin with a continuous value (:data:`LINEARISED`) and some
        sensitivity above the noise."""
        return (self.kind in LINEARISED and math.isfinite(self.margin)
                and bool(np.any(self.significant)))

    def __repr__(self):
        return (f"<MarginSensitivity {self.kind} pair {self.pair}: margin {self.margin:.3g}, "
                f"{int(np.sum(self.significant))} of {len(self.gradient)} sensitivities "
                f"above the noise>")


def margin_sensitivities(model, U, ref, tol, *, step: float = FD_STEP, base=None) -> list:
    """The failing margins of every row of ``U`` and their sensitivities to each
    parameter, by central finite differences in batched calls of
    :func:`cspace.batch.margins.defect_margins` (without the full test; see
    "Margin sensitivities" in the module docstring).

    Parameters
    ----------
    model : mechanisms.models.Model
        The model ``ref`` was made from (the synthesis passes the initial design).
    U : (m, n) float
        Vectors (model units), normally defective ones.
    ref : cspace.defects.Reference
    tol : (n,) float
        The current tolerances: the step of axis i is ``step * tol[i]``; axes of
        zero tolerance are not perturbed.
    step : float
        Relative step (default :data:`FD_STEP`).
    base : sequence, optional
        Per row of ``U``, its margins as a batched test already computed them
        (:func:`synthesis.executors.margin_rows`: the same numbers), or None
        where they are to be computed here.

    Returns
    -------
    list of tuple of MarginSensitivity
        Per row, one entry per margin <= 0 (channel, sequence and start per
        pair, deviation), in that order; empty when no margin fails (the full
        test found the defect).  A sequence or start margin's entry has no
        differences (gradient 0, noise infinite: never usable).

    Examples
    --------
    >>> from mechanisms.models import reciprocating_cam
    >>> from cspace.defects import reference
    >>> m = reciprocating_cam()
    >>> ref = reference(m, "fast")
    >>> s = margin_sensitivities(m, [m.nominal], ref, m.tol)
    >>> s[0]           # the nominal fails no margin
    ()
    """
    n = len(ref.nominal)
    U = np.asarray(U, dtype=float)
    if U.ndim == 1:
        U = U[None, :]
    if U.ndim != 2 or U.shape[1] != n or not np.all(np.isfinite(U)):
        raise InputError(f"U must be an (m, {n}) array of finite parameter vectors, got shape "
                         f"{np.shape(U)}", name="U")
    tol = np.asarray(tol, dtype=float)
    if tol.shape != (n,) or not np.all(np.isfinite(tol)) or np.any(tol < 0):
        raise InputError(f"tol must hold {n} finite tolerances >= 0, got {tol.tolist()}",
                         name="tol")
    if isinstance(step, bool) or not isinstance(step, (int, float)) or not 0 < step <= 1:
        raise InputError(f"step must be a fraction in (0, 1] of each tolerance, got {step!r}",
                         name="step", value=step)
    m = len(U)
    if m == 0:
        return []
    axes = np.nonzero(tol > 0)[0]
    h = step * tol
    bands = margin_bands(ref.accuracy, ref.d)
    base = _base_tables(model, U, ref, base)
    failing = [[(kind, p) for kind, tab in base.items() for p in range(tab.shape[1])
                if math.isfinite(tab[r, p]) and tab[r, p] <= 0] for r in range(m)]
    # the steps only where a continuous margin fails (a sequence margin's
    # differences are never used: :attr:`MarginSensitivity.usable`); without a
    # failing channel margin, the steps need no hand-over samples (the
    # deviation and start margins do not read them: the same numbers)
    kinds_of = [{k for k, _ in failing[r]} for r in range(m)]
    rows = [r for r in range(m) if not kinds_of[r].isdisjoint(LINEARISED)]
    steps = {}
    if rows:
        # one batched call: the steps of the rows whose channel fails with
        # their hand-over samples, the others without
        tabs = _stepped(model, U[rows], ref, axes, h, ["channel" in kinds_of[r] for r in rows])
        k = 2 * len(axes)
        for j, r in enumerate(rows):
            steps[r] = {kind: tab[j * k:(j + 1) * k] for kind, tab in tabs.items()}
    out = []
    for r in range(m):
        found = []
        for kind, p in failing[r]:
            v = float(base[kind][r, p])
            g = np.zeros(n)
            noise = np.full(n, np.inf)
            if kind in LINEARISED:
                tab = steps[r][kind]
                for a_, i in enumerate(axes):
                    plus, minus = float(tab[2 * a_, p]), float(tab[2 * a_ + 1, p])
                    if math.isfinite(plus) and math.isfinite(minus):
                        g[i] = (plus - minus) / (2 * h[i])
                        noise[i] = bands[kind] / h[i]
                    elif math.isfinite(plus) or math.isfinite(minus):
                        # one side does not build: a one-sided difference,
                        # twice as noisy
                        g[i] = ((plus - v) if math.isfinite(plus) else (v - minus)) / h[i]
                        noise[i] = 2 * bands[kind] / h[i]
            found.append(MarginSensitivity(kind, -1 if kind == "deviation" else p, v, g, noise,
                                           bands[kind]))
        out.append(tuple(found))
    return out


def _base_tables(model, U, ref, given) -> dict:
    """The margins (as :func:`_margin_tables`) of the rows of ``U``: those
    ``given`` (per row a :func:`synthesis.executors.margin_rows` entry or
    None), the others from one batched call."""
    from cspace.batch.margins import defect_margins
    m = len(U)
    try:
        given = [None] * m if given is None else list(given)
    except TypeError:
        raise InputError(f"base must be a sequence of one entry per row of U ({m}): a row's "
                         f"margins (synthesis.executors.margin_rows) or None, got "
                         f"{given!r}", name="base") from None
    if len(given) != m:
        raise InputError(f"base must hold one entry per row of U ({m}), got {len(given)}",
                         name="base")
    todo = [r for r in range(m) if given[r] is None]
    if len(todo) == m:
        return _margin_tables(defect_margins(model, U, ref, fallback=False))
    P = len(ref.spaces)
    out = {"channel": np.zeros((m, P)), "sequence": np.zeros((m, P)),
           "deviation": np.zeros((m, 1)), "start": np.zeros((m, P))}
    if todo:
        got = _margin_tables(defect_margins(model, U[todo], ref, fallback=False))
        for kind, tab in got.items():
            out[kind][todo] = tab
    for r in range(m):
        g = given[r]
        if g is None:
            continue
        try:
            for kind in ("channel", "sequence", "start"):
                out[kind][r] = np.asarray(g[kind], dtype=float).reshape(P)
            out["deviation"][r, 0] = float(g["deviation"])
        except (KeyError, TypeError, ValueError) as e:
            raise InputError(f"base[{r}] must hold a row's margins (channel, sequence and "
                             f"start of {P} pair(s), deviation), got {g!r}",
                             name="base") from e
    return out


def _margin_tables(mb) -> dict:
    """``kind -> (rows, columns) values`` of a MarginBatch, in the order of the
    entries of :func:`margin_sensitivities`."""
    P = mb.channel.shape[1]
    start = mb.start if mb.start is not None else np.full((len(mb.defective), P), np.nan)
    return {"channel": mb.channel, "sequence": mb.sequence,
            "deviation": mb.deviation[:, None], "start": start}


def _stepped(model, U, ref, axes, h, channel):
    """The margins (as :func:`_margin_tables`) of the central steps ``+- h[i]``
    of every row of ``U`` along each of ``axes``, one batched call without
    verdicts (:func:`cspace.batch.margins.margin_tables`): per vector, + and -
    along each axis in turn (a batch chunk then holds the steps of few vectors, and a curve
    that does not depend on an axis is evaluated once for the two steps along
    it; the rows' numbers do not depend on their neighbours).  ``channel``:
    per row of ``U``, whether its steps need the channel and sequence margins
    (the hand-over samples); the others get the deviation and start margins
    only."""
    from cspace.batch.margins import margin_tables
    m, n = U.shape
    k = 2 * len(axes)
    steps = np.zeros((k, n))
    steps[0::2][np.arange(len(axes)), axes] = h[axes]
    steps[1::2][np.arange(len(axes)), axes] = -h[axes]
    X = U[:, None, :] + steps[None, :, :]
    tabs = margin_tables(model, X.reshape(m * k, n), ref,
                         np.repeat(np.asarray(channel, dtype=bool), k))
    tabs["deviation"] = tabs["deviation"][:, None]
    return tabs


def sensitivity_task(model, U, accuracy, d, tol, step=FD_STEP, base=None):
    """:func:`margin_sensitivities` of the rows of ``U`` in a worker, against the
    nominal Reference of ``model`` (kept per worker): the unit of work of
    :func:`lp_removal`.  ``base``: the rows' margins where a batched test
    already computed them (:func:`margin_sensitivities`)."""
    from .executors import cached_reference
    ref = cached_reference(model, accuracy, d)
    return margin_sensitivities(model, U, ref, tol, step=step, base=base)


@dataclass(frozen=True, eq=False)
class Linearised:
    """A known defect's linearised margin: the box ``c +/- t`` is clear of it
    when ``margin + gradient . (c - point) - |gradient| . t >= target``.

    Attributes
    ----------
    key : str
        Which defect: its origin (the zone extremes of its check-list vector),
        kind and pair; a later linearisation of the same key replaces it.
    point : (n,) float
        Where it was linearised (model units).
    margin, target, band : float
        C-space metric.
    gradient : (n,) float
        The sensitivities above the noise, zero elsewhere (per model unit).
    kind : str
    pair : int
    about : dict
        What the report says of it: ``vector``, ``iteration``, ``mirror``,
        ``pair``, ``kind`` (defect reasons), ``q1``, ``q2``, ``message``.
    """

    key: str
    point: np.ndarray
    margin: float
    gradient: np.ndarray
    target: float
    band: float
    kind: str
    pair: int
    about: dict = field(default_factory=dict)

    def __repr__(self):
        return (f"<Linearised {self.kind} pair {self.pair} of {self.key!r}: margin "
                f"{self.margin:.3g}, {int(np.count_nonzero(self.gradient))} parameter(s)>")

    def worst(self, center, tol) -> float:
        """The linearised margin at the worst corner of the box ``center +/- tol``."""
        g = self.gradient
        return float(self.margin + g @ (np.asarray(center) - self.point)
                     - np.abs(g) @ np.asarray(tol))

    def to_dict(self) -> dict:
        return {"key": self.key, "point": self.point.tolist(), "margin": self.margin,
                "gradient": self.gradient.tolist(), "target": self.target, "band": self.band,
                "kind": self.kind, "pair": self.pair, "about": dict(self.about)}

    @classmethod
    def from_dict(cls, d, n: int) -> "Linearised":
        """Read what :meth:`to_dict` wrote (KeyError, TypeError or ValueError on
        another document)."""
        point = np.array(d["point"], dtype=float)
        grad = np.array(d["gradient"], dtype=float)
        vals = [float(d[k]) for k in ("margin", "target", "band")]
        if point.shape != (n,) or grad.shape != (n,):
            raise ValueError(f"a known defect's point and gradient must hold {n} values")
        if not (np.all(np.isfinite(point)) and np.all(np.isfinite(grad))
                and all(math.isfinite(v) for v in vals)):
            raise ValueError("a known defect's values must be finite")
        if d["kind"] not in KINDS:
            raise ValueError(f"kind must be one of {list(KINDS)}, got {d['kind']!r}")
        return cls(str(d["key"]), point, vals[0], grad, vals[1], vals[2], str(d["kind"]),
                   int(d["pair"]), dict(d.get("about", {})))


def known_from_dicts(docs, n: int) -> tuple:
    """The known defects of a checkpoint (:meth:`Linearised.from_dict` of each)."""
    return tuple(Linearised.from_dict(d, n) for d in docs)


def linearise(sens: MarginSensitivity, point, key: str, about=None,
              target: float = TARGET, d: float | None = None) -> tuple:
    """The :class:`Linearised` constraints of one failing margin: the
    sensitivities below the noise dropped, the target ``target * band``; for a
    deviation margin with ``d`` given, also its companion on the other side
    (margin ``2 d - m``, gradient ``-g``; see "Linearised margins" in the module
    docstring)."""
    g = np.where(sens.significant, sens.gradient, 0.0)
    point = np.asarray(point, dtype=float).copy()
    out = [Linearised(key, point, float(sens.margin), g, float(target * sens.band),
                      float(sens.band), sens.kind, int(sens.pair), dict(about or {}))]
    if sens.kind == "deviation" and d is not None:
        out.append(Linearised(key + "|other side", point, float(2 * d - sens.margin), -g,
                              float(target * sens.band), float(sens.band), sens.kind,
                              int(sens.pair), dict(about or {})))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class MinimalChange:
    """The result of :func:`minimal_change`.

    Attributes
    ----------
    success : bool
        Some allowed change clears every constraint.
    status : str
        ``"none"`` (the box is already clear), ``"shift"`` (shifts alone),
        ``"cut"`` (cuts were needed) or ``"infeasible"``.
    message : str
    delta : (n,) float
        The shift of the nominal (model units).
    tol : (n,) float
        The new tolerances.
    binding : dict
        ``{("shift" | "cut", axis): constraint index}``: the defect that
        required each change.
    infeasible : tuple of int
        The constraints that no allowed change clears (empty on success).
    nit : int
        Linear programs solved.
    """

    success: bool
    status: str
    message: str
    delta: np.ndarray
    tol: np.ndarray
    binding: dict
    infeasible: tuple = ()
    nit: int = 0

    def __repr__(self):
        return (f"<MinimalChange {self.status}: max |shift| "
                f"{float(np.max(np.abs(self.delta), initial=0.0)):.4g}, "
                f"{len([k for k in self.binding if k[0] == 'cut'])} cut(s)>")


def minimal_change(u0, tol, constraints, *, guards=None, initial_tol=None,
                   trust: float = SHIFT_TRUST, at_least=None, at_most=None,
                   current=None, shift_only=None) -> MinimalChange:
    """The smallest shift, else the smallest cuts, that clear every constraint
    (see "The smallest change" in the module docstring).

    Parameters
    ----------
    u0, tol : (n,) float
        The current nominal and tolerances (model units).
    constraints : sequence of Linearised
    guards : synthesis.guards.Guards, optional
        Fixed parameters, hard tolerances, ``min_keep`` floors and costs.
    initial_tol : (n,) float, optional
        The run's initial tolerances (the scale of shifts and cuts, and what
        ``min_keep`` is a fraction of); default ``tol``.
    trust : float
        The largest shift of one parameter, relative to its initial tolerance.
    at_least : (n,) float, optional
        Shifts the result must reach or pass in the same direction (0: free).
    at_most : (n,) float, optional
        Tolerances the result must not exceed (cuts made elsewhere).
    current : sequence of bool, optional
        Per constraint, whether it is this iteration's (preferred when naming
        the defect that required a change).
    shift_only : sequence of bool, optional
        Per constraint: it must hold with the tolerances before the cut (a
        cut does not count for it).  :func:`lp_removal` passes the one-sided
        defects ("Cuts for two-sided defects" in the module docstring).

    Returns
    -------
    MinimalChange

    Examples
    --------
    A pin (axis 0, radius) in a slot (axis 1, half-width) whose clearance
    ``w - r`` is -0.01 at the worst corner: the smallest largest move splits the
    0.01 between the two.

    >>> c = Linearised("jam", np.array([5.02, 5.01]), -0.01, np.array([-1.0, 1.0]),
    ...                0.0, 1e-4, "channel", 0)
    >>> r = minimal_change([5.0, 5.03], [0.02, 0.02], [c])
    >>> np.round(r.delta, 6).tolist()
    [-0.005, 0.005]
    """
    u0, tol, t0, cons = _checked_change_inputs(u0, tol, constraints, initial_tol, trust)
    cur = [True] * len(cons) if current is None else [bool(x) for x in current]
    two = [_both_sides(c) for c in cons]
    lim = _change_limits(tol, t0, guards, at_least, at_most)
    if not cons:
        delta = lim.need.copy()
        changed = bool(np.any(delta != 0) or np.any(lim.cap < tol))
        return MinimalChange(True, "shift" if changed else "none",
                             "no constraint", delta, lim.cap, {}, (), 0)
    lp = _change_lp(u0, tol, t0, cons, lim, trust, shift_only)
    status, res = _solve_change(lp)
    if res.status != 0:
        return _infeasible_change(lp, tol)
    return _attributed_change(lp, res.x, status, tol, lim.cap, cur, two)


def _checked_change_inputs(u0, tol, constraints, initial_tol, trust) -> tuple:
    """Check the arguments of :func:`minimal_change`: ``(u0, tol, t0, cons)``,
    the nominal, current and initial tolerances as arrays and the constraints
    as a list."""
    u0 = np.asarray(u0, dtype=float)
    tol = np.asarray(tol, dtype=float)
    n = len(u0)
    if tol.shape != (n,) or np.any(tol < 0) or not np.all(np.isfinite(tol)):
        raise InputError(f"tol must hold {n} finite tolerances >= 0, got {tol.tolist()}",
                         name="tol")
    t0 = tol if initial_tol is None else np.asarray(initial_tol, dtype=float)
    if not (isinstance(trust, (int, float)) and not isinstance(trust, bool) and trust > 0):
        raise InputError(f"trust must be a number > 0 (shift bound relative to the initial "
                         f"tolerance), got {trust!r}", name="trust", value=trust)
    cons = list(constraints)
    for c in cons:
        if not isinstance(c, Linearised) or c.gradient.shape != (n,):
            raise InputError(f"constraints must be Linearised of {n} parameters, got {c!r}",
                             name="constraints")
    return u0, tol, t0, cons


@dataclass(frozen=True, eq=False)
class _ChangeLimits:
    """What :func:`minimal_change` may change, per parameter: ``fixed`` and
    ``hard`` (bool), the ``floor`` of each tolerance, the shift and cut costs,
    the shifts it must keep (``need``) and the tolerances it must not exceed
    (``cap``), all model units."""

    fixed: np.ndarray
    hard: np.ndarray
    floor: np.ndarray
    shift_cost: np.ndarray
    cut_cost: np.ndarray
    need: np.ndarray
    cap: np.ndarray


def _change_limits(tol, t0, guards, at_least, at_most) -> _ChangeLimits:
    """The guard rails and the greedy's changes as :class:`_ChangeLimits`
    (no guard rails: nothing fixed or hard, no floor, unit costs)."""
    n = len(tol)
    fixed = np.zeros(n, dtype=bool) if guards is None else np.asarray(guards.fixed)
    hard = np.zeros(n, dtype=bool) if guards is None else np.asarray(guards.hard)
    floor = np.zeros(n) if guards is None else guards.floor(t0)
    w = np.ones(n) if guards is None else np.asarray(guards.shift_cost, dtype=float)
    cc = np.ones(n) if guards is None else np.asarray(guards.cut_cost, dtype=float)
    need = np.zeros(n) if at_least is None else np.asarray(at_least, dtype=float)
    cap = tol.copy() if at_most is None else np.minimum(tol, np.asarray(at_most, dtype=float))
    return _ChangeLimits(fixed, hard, floor, w, cc, need, cap)


@dataclass(eq=False)
class _ChangeLP:
    """The LP of :func:`minimal_change` in scaled variables ``x = [p (n), q (n),
    s (n), y (n), z]``: shifts up and down, cuts, the cost of each tolerance
    kept (``y_i >= -log(t'_i / t0_i)``) and the largest move, in units of the
    variable scales ``S``.

    ``G`` holds the constraints' gradients, ``Gs`` and ``Ga`` their rows for the
    shifts and the cuts (band units; ``Ga`` zero where a cut does not count);
    ``A_*``, ``b_*`` the inequality blocks (constraints, largest move, cut
    cost tangents); ``*_lo``, ``*_hi`` the variable bounds (``s_lo``: no cut
    beyond ``cap``, ``s_hi_cut``: the cuts allowed); ``c_*`` the objectives;
    ``nit`` the LPs solved so far."""

    S: np.ndarray
    G: np.ndarray
    Gs: np.ndarray
    Ga: np.ndarray
    A_con: np.ndarray
    b_con: np.ndarray
    A_z: np.ndarray
    b_z: np.ndarray
    A_log: np.ndarray
    b_log: np.ndarray
    p_lo: np.ndarray
    p_hi: np.ndarray
    q_lo: np.ndarray
    q_hi: np.ndarray
    s_lo: np.ndarray
    s_hi_cut: np.ndarray
    y_lo: np.ndarray
    y_hi: np.ndarray
    c_z: np.ndarray
    c_sum: np.ndarray
    c_cut: np.ndarray
    nit: int = 0


def _change_lp(u0, tol, t0, cons, lim, trust, shift_only) -> _ChangeLP:
    """Build the LP of :func:`minimal_change`: scales, constraint rows,
    variable bounds, cut cost tangents and objectives."""
    n = len(u0)
    pos = t0[t0 > 0]
    S = np.where(t0 > 0, t0, pos.max() if len(pos) else 1.0)     # variable scales
    Sbar = float(np.mean(S))
    G, Gs, Ga, A_con, b_con = _constraint_rows(u0, tol, S, cons, shift_only)
    cuttable = (~lim.hard) & (tol > 0) & np.any(G != 0, axis=0)
    p_lo, p_hi, q_lo, q_hi, s_lo, s_hi_cut = _variable_bounds(tol, S, cuttable, lim, trust)
    A_z = np.hstack([np.diag(lim.shift_cost * S / Sbar), np.diag(lim.shift_cost * S / Sbar),
                     np.zeros((n, 2 * n)), -np.ones((n, 1))])
    b_z = np.zeros(n)
    A_log, b_log, y_lo, y_hi = _cut_cost_tangents(tol, t0, cuttable)
    c_z, c_sum, c_cut = _change_objectives(lim, S, Sbar)
    return _ChangeLP(S, G, Gs, Ga, A_con, b_con, A_z, b_z, A_log, b_log, p_lo, p_hi, q_lo,
                     q_hi, s_lo, s_hi_cut, y_lo, y_hi, c_z, c_sum, c_cut)


def _constraint_rows(u0, tol, S, cons, shift_only) -> tuple:
    """The constraints' rows ``A_con x <= b_con`` in band units, with their
    gradients ``G`` and shift and cut parts ``Gs``, ``Ga``: ``(G, Gs, Ga, A_con,
    b_con)``.  A cut does not count for a ``shift_only`` constraint."""
    n = len(u0)
    G = np.array([c.gradient for c in cons])
    B = np.array([c.band for c in cons])
    # rows in band units: g.(p - q) + |g|.s >= rhs
    rhs = np.array([c.target - c.margin - c.gradient @ (u0 - c.point)
                    + np.abs(c.gradient) @ tol for c in cons]) / B
    Gs = G * S / B[:, None]
    Ga = np.abs(G) * S / B[:, None]
    nc = len(cons)
    if shift_only is not None:
        only = np.asarray(shift_only, dtype=bool)
        if only.shape != (nc,):
            raise InputError(f"shift_only must hold one flag per constraint ({nc}), got "
                             f"shape {only.shape}", name="shift_only")
        # a cut does not count for these: their corner term keeps the old box
        Ga = np.where(only[:, None], 0.0, Ga)
    A_con = np.hstack([-Gs, Gs, -Ga, np.zeros((nc, n)), np.zeros((nc, 1))])
    return G, Gs, Ga, A_con, -rhs


def _variable_bounds(tol, S, cuttable, lim, trust) -> tuple:
    """The scaled bounds of the shifts up and down and of the cuts: ``(p_lo,
    p_hi, q_lo, q_hi, s_lo, s_hi_cut)``.  Shifts lie in [0, trust] (fixed: 0),
    stretched to reach the forced moves of ``need``; cuts reach ``cap``, and in
    the cut phase the floor of a cuttable tolerance."""
    need, cap, floor = lim.need, lim.cap, lim.floor
    # bounds (scaled): p, q in [0, trust] (fixed: 0); forced moves of at_least
    lim_pq = np.maximum(trust, np.abs(need) / S)
    p_lo = np.where(need > 0, need / S, 0.0)
    q_lo = np.where(need < 0, -need / S, 0.0)
    p_hi = np.where(lim.fixed, p_lo, np.where(need < 0, 0.0, lim_pq))
    q_hi = np.where(lim.fixed, q_lo, np.where(need > 0, 0.0, lim_pq))
    s_lo = (tol - cap) / S
    s_hi_cut = np.where(cuttable, np.maximum(tol - np.maximum(floor, 0.0), tol - cap) / S, s_lo)
    s_hi_cut = np.maximum(s_hi_cut, s_lo)
    return p_lo, p_hi, q_lo, q_hi, s_lo, s_hi_cut


def _cut_cost_tangents(tol, t0, cuttable) -> tuple:
    """The rows that keep each cuttable tolerance's cost ``y_i`` above the
    tangents of ``-log`` (its kept fraction) at the fractions of ``_KEPT``, and
    the bounds of ``y``: ``(A_log, b_log, y_lo, y_hi)``."""
    n = len(tol)
    k0 = np.where(t0 > 0, tol / np.where(t0 > 0, t0, 1.0), 1.0)   # fraction kept so far
    # tangents of -log k at the breakpoints: y_i >= -log k_j + 1 - k_i / k_j, with the
    # kept fraction k_i = k0_i - s_i (s in units of t0)
    rows, rhs_log = [], []
    for i in np.nonzero(cuttable)[0]:
        for kj in _KEPT:
            r = np.zeros(4 * n + 1)
            r[2 * n + i] = 1.0 / kj
            r[3 * n + i] = -1.0
            rows.append(r)
            rhs_log.append(math.log(kj) - 1.0 + k0[i] / kj)
    A_log = np.array(rows).reshape(-1, 4 * n + 1)
    b_log = np.array(rhs_log)
    y_lo = np.where(cuttable, np.maximum(-np.log(np.maximum(k0, 1e-300)), 0.0), 0.0)
    y_hi = np.where(cuttable, None, 0.0)
    return A_log, b_log, y_lo, y_hi


def _change_objectives(lim, S, Sbar) -> tuple:
    """The objectives ``(c_z, c_sum, c_cut)``: the weighted largest move, the
    weighted summed move, and the cut phase's cost of cuts and shifts."""
    n = len(S)
    w, cc = lim.shift_cost, lim.cut_cost
    zero = np.zeros(4 * n + 1)
    c_z = zero.copy()
    c_z[-1] = 1.0
    c_sum = zero.copy()
    c_sum[:2 * n] = np.concatenate([w * S / Sbar, w * S / Sbar])
    # the cut phase: each tolerance's -log(kept fraction), weighted by its cut cost,
    # plus each shift in units of its initial tolerance, weighted by its shift cost
    c_cut = zero.copy()
    c_cut[3 * n:4 * n] = cc
    c_cut[:2 * n] = SHIFT_PRICE * np.concatenate([w, w])
    return c_z, c_sum, c_cut


def _lp_bounds(lp: _ChangeLP, s_hi) -> list:
    """The (lower, upper) bound of every variable, with ``s_hi`` for the cuts."""
    return (list(zip(lp.p_lo, lp.p_hi)) + list(zip(lp.q_lo, lp.q_hi)) + list(zip(lp.s_lo, s_hi))
            + list(zip(lp.y_lo, lp.y_hi)) + [(0, None)])


def _solve_lp(lp: _ChangeLP, cost, s_hi, extra=(), rows=None):
    """Solve one LP (HiGHS): minimise ``cost`` under the constraints (only
    ``rows`` of them when given), the largest-move and tangent rows and the
    ``extra`` (row, bound) pairs."""
    from scipy.optimize import linprog
    A = [lp.A_con if rows is None else lp.A_con[rows], lp.A_z, lp.A_log] + [a for a, _ in extra]
    b = ([lp.b_con if rows is None else lp.b_con[rows], lp.b_z, lp.b_log]
         + [np.atleast_1d(v) for _, v in extra])
    lp.nit += 1
    return linprog(cost, A_ub=np.vstack(A), b_ub=np.concatenate(b), bounds=_lp_bounds(lp, s_hi),
                   method="highs")


def _lexicographic(lp: _ChangeLP, first, s_hi):
    """Minimise the objectives in turn, each later one at the optimum of
    the earlier ones."""
    extra = []
    res = None
    for cost in first:
        res = _solve_lp(lp, cost, s_hi, extra)
        if res.status != 0:
            return res
        extra.append((cost[None, :], res.fun * (1 + 1e-7) + 1e-12))
    return res


def _solve_change(lp: _ChangeLP) -> tuple:
    """The two phases: shifts only, else cuts as the last resort.  Returns
    ``(status, linprog result)``."""
    status = "shift"
    res = _lexicographic(lp, [lp.c_z, lp.c_sum], lp.s_lo)
    if res.status != 0:
        status = "cut"
        res = _lexicographic(lp, [lp.c_cut, lp.c_z, lp.c_sum], lp.s_hi_cut)
    return status, res


def _infeasible_change(lp: _ChangeLP, tol) -> MinimalChange:
    """The result when no allowed change clears every constraint: those that
    no allowed change clears on their own (all when each can be)."""
    nc = len(lp.b_con)
    alone = _clearable_alone(lp)
    bad = tuple(j for j in range(nc)
                if not (alone[j] if alone[j] is not None else
                        _solve_lp(lp, lp.c_cut, lp.s_hi_cut, rows=slice(j, j + 1)).status == 0))
    bad = bad or tuple(range(nc))
    return MinimalChange(False, "infeasible",
                         f"{len(bad)} defect(s) cannot be cleared by the changes the "
                         f"guard rails allow", np.zeros(len(tol)), tol.copy(), {}, bad, lp.nit)


#: :func:`_clearable_alone` decides a constraint without an LP only when its
#: best corner clears or misses it by more than this (band units, and a share
#: of the row's terms): HiGHS's own feasibility tolerance is 1e-7.
_CLEAR_BY = 1e-6


def _clearable_alone(lp: _ChangeLP) -> list:
    """Per constraint row, whether some allowed change clears it on its own
    (True or False), or None where an LP has to say.

    With one constraint row, the largest-move and cut-cost rows always hold
    (``z`` and a cuttable ``y`` have no upper bound), so the row is clearable
    exactly when its smallest value over the variables' bounds is at most
    its right-hand side: each variable at the bound its coefficient's sign
    picks.  Where that smallest value lies within :data:`_CLEAR_BY` of the
    right-hand side, or the bounds are inconsistent, HiGHS decides (as it
    decided every row before: the same answers, without an LP per row)."""
    nc, n = lp.A_con.shape[0], len(lp.S)
    lo = np.concatenate([lp.p_lo, lp.q_lo, lp.s_lo]).astype(float)
    hi = np.concatenate([lp.p_hi, lp.q_hi, lp.s_hi_cut]).astype(float)
    unbounded_y = np.array([v is None for v in lp.y_hi], dtype=bool)
    # the cost rows bind only the y they hold, each with no upper bound; the
    # constraint rows hold neither y nor z
    y_in_rows = np.any(lp.A_log[:, 3 * n:4 * n] != 0, axis=0)
    y_lo = np.asarray(lp.y_lo, dtype=float)
    y_hi = np.array([np.inf if v is None else v for v in lp.y_hi], dtype=float)
    if (np.any(lo > hi) or not np.all(np.isfinite(lo)) or not np.all(np.isfinite(hi))
            or np.any(y_lo > y_hi) or np.any(y_in_rows & ~unbounded_y)
            or np.any(lp.A_con[:, 3 * n:] != 0)):
        return [None] * nc
    A = lp.A_con[:, :3 * n]
    least = np.where(A > 0, A * lo, A * hi).sum(axis=1)
    scale = 1.0 + np.abs(A * np.where(A > 0, lo, hi)).sum(axis=1) + np.abs(lp.b_con)
    gap = lp.b_con - least
    out = []
    for j in range(nc):
        if gap[j] >= _CLEAR_BY * scale[j]:
            out.append(True)
        elif gap[j] <= -_CLEAR_BY * scale[j]:
            out.append(False)
        else:
            out.append(None)
    return out


def _attributed_change(lp: _ChangeLP, x, status, tol, cap, cur, two) -> MinimalChange:
    """The result of a solution ``x``: the shift and the new tolerances (a
    negligible change dropped), the defect that required each change, and the
    status the changes made."""
    n = len(tol)
    S = lp.S
    delta = (x[:n] - x[n:2 * n]) * S
    cut = x[2 * n:3 * n] * S
    # the lexicographic steps leave each earlier optimum 1e-7 of slack: a change
    # below a millionth of the initial tolerance is that slack, not a change
    delta = np.where(np.abs(delta) > _NEGLIGIBLE * S, delta, 0.0)
    new_tol = np.where(cut > _NEGLIGIBLE * S, tol - cut, tol)
    new_tol = np.minimum(new_tol, cap)
    binding = _binding_constraints(lp, x, delta, new_tol, tol, cur, two)
    if status == "cut" and not np.any(new_tol < cap):
        status = "shift"
    if status == "shift" and not np.any(delta != 0) and not np.any(new_tol < tol):
        status = "none"
    msg = {"none": "the box is already clear of every linearised defect",
           "shift": "shifts alone clear every linearised defect",
           "cut": "no allowed shift clears every linearised defect: the smallest cuts"}[status]
    return MinimalChange(True, status, msg, delta, new_tol, binding, (), lp.nit)


def _binding_constraints(lp: _ChangeLP, x, delta, new_tol, tol, cur, two) -> dict:
    """``{("shift" | "cut", axis): constraint index}``: per change, the active
    constraint at ``x`` that depends most on that parameter."""
    slack = lp.A_con @ x - lp.b_con
    active = np.nonzero(-slack <= _SLACK)[0]
    binding = {}
    for what, moved in (("shift", delta != 0), ("cut", new_tol < tol)):
        for i in np.nonzero(moved)[0]:
            # a cut is required by a constraint the cut counts for
            dep = lp.Ga[:, i] if what == "cut" else lp.G[:, i]
            cand = [j for j in active if dep[j] != 0]
            if not cand:
                continue
            # this iteration's first; for a cut, a defect found at both sides
            # (which needs it) before a one-sided one (which a shift could
            # clear, when the cuts had to count for it too)
            rank = two if what == "cut" else [False] * len(two)
            binding[(what, int(i))] = max(cand, key=lambda j: (cur[j], rank[j], abs(lp.Gs[j, i])))
    return binding

def describe_defect(memo, u) -> dict:
    """What the report says of the defect at ``u``: ``u`` itself (model
    units: the vector a reader can test again) and its test in the
    iteration's memo (pair, reasons, where, message)."""
    hit = memo.get(u) if memo is not None else None
    r = hit[0] if hit is not None else None
    where = r.where if r is not None and r.where else (None, None, None)
    return {"u": [float(v) for v in np.asarray(u, dtype=float)],
            "pair": None if where[0] is None else int(where[0]),
            "kind": [] if r is None else [x.name.lower() for x in r.reasons],
            "q1": _num(where[1]), "q2": _num(where[2]),
            "message": "" if r is None else r.message}


def _num(x):
    return None if x is None or not math.isfinite(float(x)) else float(x)


#: The most vectors per sensitivity task (each vector becomes 2 n rows of a
#: batched call, after one for the vectors themselves): :func:`sens_chunks`.
#: On the Geneva pair's first iteration (``fast``, two workers) the 102
#: vectors took 5.0 s as 14 tasks of at most 8, 4.7 s as 4 of at most 32,
#: 4.6 s as 2: every task pays a batched call for its vectors and a partly
#: filled last chunk of steps (:data:`cspace.batch.margins.LEAN_CHUNK`);
#: four tasks keep two workers evenly loaded when some vectors cost more
#: (those whose channel fails step with hand-over samples).
SENS_CHUNK = 32


def sens_chunks(n: int, workers: int | None = None) -> list:
    """The sizes of the sensitivity tasks for ``n`` vectors: at most
    :data:`SENS_CHUNK` vectors each, at least four tasks, as many as a
    multiple of the executor's ``workers`` (when known), the vectors shared
    among them as evenly as they go (sizes differ by one at most).

    A batched call costs about as much as 5 to 12 rows before its first row
    (Geneva, ``default`` and ``fast``: the interpreter's walk over the
    candidate curves; "one-row call" in ``benchmarks/bench_batch.py``), so
    few large tasks beat many small ones, as long as every worker gets some;
    and a worker left with the last task alone waits for nothing: the first
    Geneva iteration's 102 vectors are 4 tasks of 26 or 25 on two workers
    (:data:`SENS_CHUNK`).  A vector's sensitivities do not depend on the
    task it travels in."""
    if n < 1:
        return []
    k = max(-(-n // SENS_CHUNK), min(4, n))
    if workers:
        k = min(n, workers * -(-k // workers))
    q, r = divmod(n, k)
    return [q + 1] * r + [q] * (k - r)


def lp_removal(design, intent, acc, d, executor, targets, indices, keys, ends, batch, eps,
               *, iteration, memo=None, n_own=None, hints=None, removed=(), spread=(),
               returning=(), evidence=None, guards=None, initial_tol=None, known=(),
               method="margin", progress=None, stats=None, tables=None) -> tuple:
    """The removal step with ``removal="lp"`` (see the module docstring).

    Parameters
    ----------
    design : Model
        The current design (nominal, tolerances).
    intent : Model
        The initial design every test compares with.
    acc, d
        Accuracy and deviation threshold of the run.
    executor : concurrent.futures.Executor
    targets : sequence of (n,) float
        Defective vectors (this iteration's, then their defective mirrors).
    indices : sequence of int
        Their check-list indices.
    keys : sequence of str
        Their origins (a mirror's ends in " (mirror)").
    ends : sequence of (float, float)
        Search margins at the nominal and at each target.
    batch, eps, hints, removed, spread, returning, evidence, guards, initial_tol, method
        As for :func:`synthesis.removal.plan_with_refinement`, for the targets
        without a usable margin.
    iteration : int
    memo : synthesis.memo.TestMemo, optional
        The iteration's tests (what the report says of each defect).
    n_own : int, optional
        Targets from this position on are mirrors.
    known : sequence of Linearised
        The run's known defects before this iteration.
    progress : callable, optional
        ``progress(label, done, total)``.
    stats : dict, optional
        Filled with ``lp_defects`` (linearised), ``greedy_defects`` (by the
        paper's rule), ``lp_handed_to_greedy`` (linearised, but their LP fix
        is forbidden) and ``margin_evaluations`` (vectors of the finite
        differences: the distinct targets, and the steps of those that fail a
        continuous margin).
    tables : sequence, optional
        Per target, its margins as its defect test computed them
        (:func:`synthesis.executors.margin_rows`), or None: computed again.

    Returns
    -------
    (ShiftPlan, list of Transition, tuple of Linearised, tuple of dict)
        The plan, one transition per target (a linearised target's is its whole
        segment: no search), the known defects after this iteration, and the
        defect that required each change (``IterationRecord.required``).
    """
    from .removal import ShiftPlan
    u0 = np.asarray(design.nominal, dtype=float)
    tol = np.asarray(design.tol, dtype=float)
    names = list(design.names)
    m = len(targets)
    n_own = m if n_own is None else n_own
    stats = {} if stats is None else stats
    targets = [np.asarray(u, dtype=float) for u in targets]
    # the check-list vectors defective at their mirror through the nominal too
    two = {int(i) for i in indices[n_own:]}
    cand = [j for j in range(m) if math.isfinite(ends[j][1]) and ends[j][1] <= 0]
    sens, distinct = _target_sensitivities(executor, intent, targets, cand, acc, d, tol,
                                           progress, tables)
    # the distinct targets, and the steps of those that fail a continuous margin
    stepped = sum(1 for j in distinct if any(e.kind in LINEARISED for e in sens[j]))
    stats["margin_evaluations"] = len(distinct) + stepped * 2 * int(np.sum(tol > 0))
    lp_pos, new = _linearise_targets(cand, sens, targets, indices, keys, d, iteration=iteration,
                                     n_own=n_own, two=two, memo=memo)
    paper = functools.partial(
        _paper_removal, u0, tol, targets, indices, ends, batch, eps, names=names,
        progress=progress, hints=hints, removed=removed, spread=spread, returning=returning,
        evidence=evidence, guards=guards, initial_tol=initial_tol, method=method)
    part, cons, owner, mc, lp_pos, handed = _remove_jointly(paper, m, u0, tol, lp_pos, new,
                                                            known, guards, initial_tol)
    stats["lp_defects"] = len(lp_pos)
    stats["greedy_defects"] = m - len(lp_pos)
    if handed:
        stats["lp_handed_to_greedy"] = len(handed)
    _place_linearised(part, lp_pos, targets, indices, u0, mc.status)
    shrinks, required = _lp_cuts(mc, cons, owner, part.shrinks, part.cap, tol, names)
    required = _required_changes(required, mc, cons, shrinks, part, names, n_own, memo, two)
    plan = ShiftPlan(mc.delta, mc.tol, tuple(part.placements), tuple(shrinks), part.distances,
                     part.cycle, tuple(part.infeasible))
    return plan, part.transitions, tuple(cons), tuple(required)


def _target_sensitivities(executor, intent, targets, cand, acc, d, tol, progress,
                          tables=None) -> tuple:
    """The failing margins and sensitivities of the targets at positions
    ``cand``, :func:`sens_chunks` vectors per :func:`sensitivity_task` on
    ``executor``: ``{position: tuple of MarginSensitivity}``, and the
    positions differenced (the first of each distinct target).  A target
    repeated (the same bits: a defective vector whose mirror through the
    nominal is another defective check-list vector) is differenced once; on
    the Geneva pair's first iteration 102 of the 144 targets are distinct.
    ``tables``: per target, its margins as its defect test computed them
    (:func:`synthesis.executors.margin_rows`), or None."""
    from .executors import executor_workers, run_ordered
    first: dict = {}      # a target's bits -> its first position in cand
    for j in cand:
        first.setdefault(np.asarray(targets[j], dtype=float).tobytes(), j)
    distinct = list(first.values())
    chunks, a = [], 0
    for size in sens_chunks(len(distinct), executor_workers(executor)):
        chunks.append(distinct[a:a + size])
        a += size

    def tick(k, total):
        if progress is not None:
            progress("margin sensitivities", k, total)

    tables = [None] * len(targets) if tables is None else tables
    sens_out = run_ordered(executor, sensitivity_task,
                           [(intent, np.array([targets[j] for j in ch]), acc, d, tol, FD_STEP,
                             [tables[j] for j in ch])
                            for ch in chunks], progress=tick)
    got = {}
    for ch, out in zip(chunks, sens_out):
        for j, s in zip(ch, out):
            got[j] = s
    return ({j: got[first[np.asarray(targets[j], dtype=float).tobytes()]] for j in cand},
            distinct)


def _linearise_targets(cand, sens, targets, indices, keys, d, *, iteration, n_own, two,
                       memo) -> tuple:
    """The :class:`Linearised` constraints of the targets with a usable failing
    margin: ``(positions, [(position, Linearised), ...])``, each constraint
    carrying what the report says of its defect."""
    new = []
    lp_pos = []
    for j in cand:
        use = [s for s in sens[j] if s.usable]
        if not use:
            continue
        lp_pos.append(j)
        about = {"vector": int(indices[j]), "iteration": int(iteration),
                 "mirror": bool(j >= n_own), "both_sides": int(indices[j]) in two,
                 **describe_defect(memo, targets[j])}
        for s in use:
            for c in linearise(s, targets[j], f"{keys[j]}|{s.kind}|{s.pair}", about, d=d):
                new.append((j, c))
    return lp_pos, new


@dataclass(eq=False)
class _PaperPart:
    """What the paper's rule did with the targets it was given, per target
    position of :func:`lp_removal` (``None`` and NaN at the others): their
    transitions, placements and distances, its cuts (positions in
    :func:`lp_removal`'s targets), infeasible vectors and cycle flag, its
    shifts (``need``, which the LP keeps) and tolerances (``cap``, which the
    LP does not exceed), and per shifted axis the position of the target that
    required it (``binding``)."""

    transitions: list
    placements: list
    distances: np.ndarray
    shrinks: list
    infeasible: list
    cycle: bool
    need: np.ndarray
    cap: np.ndarray
    binding: dict


def _paper_removal(u0, tol, targets, indices, ends, batch, eps, rest, *, names, progress,
                   hints, removed, spread, returning, evidence, guards, initial_tol,
                   method) -> _PaperPart:
    """The paper's removal (:func:`synthesis.removal.plan_with_refinement`) of
    the targets at positions ``rest`` (those without a usable margin), mapped
    back to the positions of all targets."""
    from .removal import Placement, Shrink, binding_shifts, plan_with_refinement
    m, n = len(targets), len(u0)
    part = _PaperPart([None] * m, [None] * m, np.full((m, n), np.nan), [], [], False,
                      np.zeros(n), tol.copy(), {})
    if not rest:
        return part
    sub = {j: k for k, j in enumerate(rest)}
    plan_g, trs_g = plan_with_refinement(
        u0, tol, [targets[j] for j in rest], batch, eps,
        indices=[indices[j] for j in rest],
        progress=None if progress is None else (lambda s, k: progress(
            f"search batch {s + 1}", 0, k)),
        hints=None if hints is None else [hints[j] for j in rest],
        removed=removed, spread=[sub[j] for j in spread if j in sub],
        returning=[sub[j] for j in returning if j in sub], names=names,
        evidence=evidence, guards=guards, initial_tol=initial_tol, method=method,
        end_margins=[ends[j] for j in rest], support=True)
    for k, j in enumerate(rest):
        part.transitions[j] = trs_g[k]
        p = plan_g.placements[k]
        part.placements[j] = Placement(j, p.action, p.axis, p.distance, p.order, p.cycle,
                                       p.axes)
        part.distances[j] = plan_g.distances[k]
    for sh in plan_g.shrinks:
        pos = rest[sh.position] if sh.position >= 0 else -1
        part.shrinks.append(Shrink(sh.axis, sh.name, sh.old, sh.new, sh.vector, sh.reason,
                                   pos))
    part.infeasible += list(plan_g.infeasible)
    part.cycle = plan_g.cycle
    part.need = plan_g.delta.copy()
    part.cap = plan_g.tol.copy()
    part.binding = {i: rest[k] for i, k in binding_shifts(plan_g).items()}
    return part


def _remove_jointly(paper, m, u0, tol, lp_pos, new, known, guards, initial_tol) -> tuple:
    """The paper's rule (``paper(rest)``, :func:`_paper_removal`) for the
    targets without a usable margin (of ``m`` targets), then the smallest
    change that clears the linearised ones and keeps the greedy's changes.  A
    linearised defect that no allowed change clears goes to the paper's rule,
    an earlier one is forgotten, and both run again.  Returns ``(paper part,
    constraints, owner of each, MinimalChange, positions left to the LP,
    positions handed to the paper's rule)``."""
    lp_set = set(lp_pos)
    # every known defect: earlier ones unless linearised again, then this iteration's
    again = {c.key for _, c in new}
    kept = [c for c in known if c.key not in again]
    handed = []        # linearised defects whose LP fix the guards forbid
    while True:
        part = paper([j for j in range(m) if j not in lp_set])
        cons, owner, mc = _joint_change(u0, tol, kept, new, lp_set, part, guards, initial_tol)
        if mc.success:
            return part, cons, owner, mc, [j for j in lp_pos if j in lp_set], handed
        # A linear model that no allowed change satisfies may not hold over the
        # box (a deviation that jumps where a contact hands over): those defects
        # go to the paper's rule, which moves the box by tested points; an
        # earlier defect's linearisation is forgotten.
        bad_now = {owner[k] for k in mc.infeasible if owner[k] is not None}
        bad_old = {id(cons[k]) for k in mc.infeasible if owner[k] is None}
        if not bad_now and not bad_old:
            bad_now = set(lp_set)
        kept = [c for c in kept if id(c) not in bad_old]
        handed += sorted(bad_now)
        lp_set -= bad_now


def _joint_change(u0, tol, kept, new, lp_set, part, guards, initial_tol) -> tuple:
    """The smallest change for the earlier defects ``kept`` and this
    iteration's linearised targets in ``lp_set``, at least the paper part's
    shifts and at most its tolerances; one-sided defects shift only, unless
    that has no solution.  Returns ``(constraints, owner of each (target
    position, None for an earlier one), MinimalChange)``."""
    mine = [(j, c) for j, c in new if j in lp_set]
    cons = kept + [c for _, c in mine]
    owner = [None] * len(kept) + [j for j, _ in mine]
    cur = [False] * len(kept) + [True] * len(mine)
    if cons:
        kw = dict(guards=guards, initial_tol=tol if initial_tol is None else initial_tol,
                  at_least=part.need, at_most=part.cap, current=cur)
        mc = minimal_change(u0, tol, cons, shift_only=shift_only(cons), **kw)
        if not mc.success:
            mc = minimal_change(u0, tol, cons, **kw)
    else:
        mc = MinimalChange(True, "none", "no linearised defect", part.need, part.cap, {}, (), 0)
    return cons, owner, mc


def _place_linearised(part, lp_pos, targets, indices, u0, status) -> None:
    """Record the linearised targets in ``part``: each one's transition is its
    whole segment (no search), its placement a shift, or a conflict when the
    LP cut."""
    from .removal import Action, Placement, Transition
    for j in lp_pos:
        part.transitions[j] = Transition(int(indices[j]), targets[j], u0.copy(),
                                         targets[j].copy(), (0.0, 1.0), 0)
        part.placements[j] = Placement(j, Action.CONFLICT if status == "cut" else Action.SHIFT,
                                       order=-1, axes=())


def _lp_cuts(mc, cons, owner, shrinks, cap, tol, names) -> tuple:
    """The LP's cuts beyond the greedy's as :class:`synthesis.removal.Shrink`
    (replacing the greedy's cut of the same axis), and the defect that required
    each: ``(shrinks, required)``."""
    from .removal import Shrink
    required = []
    for i in np.nonzero(mc.tol < cap)[0]:
        k = mc.binding.get(("cut", int(i)))
        c = cons[k] if k is not None else None
        pos = owner[k] if k is not None and owner[k] is not None else -1
        vec = int(c.about.get("vector", -1)) if c is not None else -1
        shrinks = [s for s in shrinks if s.axis != i]
        shrinks.append(Shrink(int(i), names[i], float(tol[i]), float(mc.tol[i]), vec, "lp",
                              pos))
        if c is not None:
            required.append(_required(names[i], "cut", c))
    return shrinks, required


def _required_changes(required, mc, cons, shrinks, part, names, n_own, memo, two) -> list:
    """The defect that required each change (``IterationRecord.required``):
    after the LP's cuts (``required``), the greedy's cuts and every shift,
    shifts first, each kind in parameter order."""
    for sh in shrinks:
        if sh.reason != "lp" and sh.position >= 0:
            required.append(_greedy_required(sh.name, "cut", part.transitions[sh.position],
                                             sh.position, n_own, memo, two))
    for i in np.nonzero(mc.delta != 0)[0]:
        k = mc.binding.get(("shift", int(i)))
        if k is not None:
            required.insert(0, _required(names[i], "shift", cons[k]))
        elif int(i) in part.binding:
            pos = part.binding[int(i)]
            required.insert(0, _greedy_required(names[i], "shift", part.transitions[pos], pos,
                                                n_own, memo, two))
    required.sort(key=lambda r: (r["change"] != "shift", names.index(r["parameter"])))
    return required

def shift_only(constraints) -> list:
    """Per constraint: its defect was found at one side of the nominal only, so
    a shift, not a cut, clears it ("Cuts for two-sided defects" in the module
    docstring)."""
    return [not _both_sides(c) for c in constraints]


def _both_sides(c: Linearised) -> bool:
    """Whether the defect of ``c`` was found at its mirror through the nominal too."""
    return bool(c.about.get("both_sides", False))


def _required(name, change, c: Linearised) -> dict:
    a = dict(c.about)
    return {"parameter": name, "change": change, "vector": a.get("vector"),
            "mirror": bool(a.get("mirror", False)), "pair": a.get("pair"),
            "kind": list(a.get("kind", [])), "q1": a.get("q1"), "q2": a.get("q2"),
            "message": a.get("message", ""), "u": a.get("u"), "margin": c.kind,
            "both_sides": _both_sides(c),
            "margin_pair": None if c.pair < 0 else c.pair, "iteration": a.get("iteration")}


def _greedy_required(name, change, tr, pos, n_own, memo, two=frozenset()) -> dict:
    return {"parameter": name, "change": change, "vector": int(tr.index),
            "mirror": bool(pos >= n_own), "both_sides": int(tr.index) in two,
            **describe_defect(memo, tr.defective)}
