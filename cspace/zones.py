"""Contact zones: the band each contact curve sweeps over the tolerance box.

For every contact curve of a pair, and a parametric model whose parameters vary
in the box ``nominal +/- tol``, sample the nominal curve and find, at each sample,
the largest outward and inward displacement of the varied curve along the
nominal normal.  The varied contact equation is re-solved exactly (nonlinearly) at
candidate parameter vectors:

* every corner of the box over the curve's dependency set, when there are at
  most ``Accuracy.zone_max_corners`` of them;
* otherwise the corners that the first-order (linear) sensitivity says are
  extreme at each sample, plus a seeded set of further corners;
* where the first-order extreme corner loses the contact at a sample (near a
  trimmed curve end), up to ``Accuracy.zone_climb`` samples per direction get a
  margin-constrained first-order guide (a small linear programme over the box:
  the displacement gradient as objective, the linearised contact margin kept
  non-negative) and a corner hill-climb from the best candidate, and the band
  there takes the envelope of its neighbours (a conservative widening);
* then a bounded local refinement (coordinate-wise parabolic steps inside the box)
  from the extreme candidates, ``Accuracy.zone_opt_iter`` sweeps at
  ``Accuracy.zone_opt_samples`` samples per direction.

Every vector evaluated contributes to the band at every sample.

C-space metric
--------------
Displacements are measured in the C-space metric: radians for a rotating
follower; for a sliding follower, the slide divided by the characteristic length
``L = pair.char_length`` (the largest reach of a rotating part about its axis), so
that a slide of L counts as one radian.  ``ZoneBand.vertical_*`` give the same
bands as plain q2 offsets (rad or model length units).

The first-order band (linear sensitivity: ``sum |dd/du_i| tol_i``) is kept beside
the nonlinear one as a baseline.

Ties
----
Many candidates reach a curve's extreme equally: a parameter the curve depends
on only formally (the Geneva slot flanks list the locking-arc centre distance)
moves nothing, so the corners that differ only in it give the same displacement
up to the last bits, which differ between machines, BLAS builds and numpy
versions.  No discrete choice here is left to those bits:

* two displacements closer than ``_TIE_REL`` (1e-9) times the curve's largest
  first-order displacement are equal.  The extreme vector of a band (the
  check-list seed) is the *first evaluated* of the candidates that reach the
  extreme within that slack; the evaluation order is fixed by the corner
  enumeration, and does not depend on the values;
* a climb or refinement step is taken only when it improves by more than that
  slack, and the parabolic step only where the three values differ by more;
* rankings (the samples refined, the weak coordinates flipped, the overlaps)
  sort on values snapped to that grid, stably, so that equal values keep their
  index order;
* sensitivities below ``_GRAD_NOISE`` of the largest at their sample count as
  zero (corner signs +1, the constrained guide ignores them).

Zone overlap
------------
Where a free channel is bounded below by curve L and above by curve U, the
channel can close inside the box if L's upward band edge passes U's downward band
edge: the early warning of jamming.  :class:`ZoneOverlap` reports where, which
curves, and the parameter vectors that push each curve into the channel there.
The edges are compared as q2 offsets from the exact nominal curves, measured
point by point along the traced edges (:func:`_band_edge`), so that a curved
channel's own curvature between the band's samples is not taken for an offset.

Evaluation in stacked passes
----------------------------
Each stage knows its next vectors before it reads their values: the
sensitivity steps, the corners, the guide searches' flips and shorter steps,
the constrained guides, a climb's flips from its current vector, a
refinement's three points.  It evaluates them in one stacked pass
(:meth:`_Evaluator.many`: every variant's contact equation as one row of a
:class:`cspace.batch.kernels.KernelStack`, the batch engine of the defect
margins) and then asks for them in its own order.  The pool, the band and
every choice are those of asking one vector at a time: a value computed ahead
that a stage does not ask for (a climb that improves early, a search that
succeeds at its first step) counts nowhere.  The stacked arithmetic is the
single call's, operation for operation; values agree to rounding, and the
tie rules above keep rounding from deciding anything
(``tests/cspace/test_zones.py``; ``benchmarks/bench_batch.py`` times both).
"""

from __future__ import annotations

import hashlib
import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from .accuracy import Accuracy, as_accuracy
from .contact import ContactCurve
from .equations import Kernel, equation_types
from .errors import cancelled_on_failure
from .features import feature_by_key
from .metric import coord_scale, follower_scale
from .freespace import ConfigurationSpace
from .geom2d import TWO_PI, wrap_pi
from .geometry import Assembly, Rotation, trusted
from .model import check_model
from .tolerances import EQUAL_REL, FD_REL, PROBE_REL, ROUNDING, SLACK, TINY

__all__ = ["ZoneBand", "ZoneOverlap", "ZoneAnalysis", "contact_zones", "varied_curve_values"]


@dataclass(frozen=True, eq=False)
class ZoneBand:
    """The contact zone of one curve.

    Attributes
    ----------
    curve : int
        Index into ``ConfigurationSpace.curves``.
    label : str
    branch : int
    depends : tuple of str
        The curve's dependency set (parameter names).
    q1, q2 : (S,) float
        Samples on the nominal curve.
    normal : (S, 2) float
        Unit normal (C-space metric) at the samples, pointing to larger q2.
    upper, lower : (S,) float
        Largest and smallest displacement along the normal over the box (metric
        units); NaN where no varied curve reaches the sample.
    vertical_upper, vertical_lower : (S,) float
        The same band as q2 offsets at fixed q1 (q2 units).
    linear_upper, linear_lower : (S,) float
        First-order band (metric units).
    u_upper, u_lower : (n,) float
        Parameter vectors attaining the largest outward (max ``upper``) and inward
        (min ``lower``) displacement over the curve: the check-list seeds.
    q1_extent : (float, float)
        q1 range reached by the varied curves (may extend beyond the nominal
        curve, or fall short of it).
    n_evaluated : int
        Parameter vectors evaluated for this band.
    reliable : (S,) bool
        Samples where every one-parameter probe (u0 +/- tol_i) still has the
        contact.  Near a trimmed curve end some variants lose the contact; there
        the band rests on fewer candidates and may underestimate (the end effect
        is reported, not hidden).
    u_upper_at, u_lower_at : (S, n) float
        Per sample, the parameter vector attaining ``upper`` (``lower``) there
        (where the band is a neighbours' envelope, the neighbour's; the curve's
        ``u_upper`` / ``u_lower`` where no variant reaches the sample): the
        vectors a zone overlap names.  Not in :meth:`to_dict`.
    """

    curve: int
    label: str
    branch: int
    depends: tuple
    q1: np.ndarray
    q2: np.ndarray
    normal: np.ndarray
    upper: np.ndarray
    lower: np.ndarray
    vertical_upper: np.ndarray
    vertical_lower: np.ndarray
    linear_upper: np.ndarray
    linear_lower: np.ndarray
    u_upper: np.ndarray
    u_lower: np.ndarray
    q1_extent: tuple
    n_evaluated: int
    reliable: np.ndarray = None
    u_upper_at: np.ndarray = None
    u_lower_at: np.ndarray = None

    def __repr__(self):
        w = np.nanmax(self.upper) - np.nanmin(self.lower) if np.isfinite(self.upper).any() else 0
        return (f"<ZoneBand {self.label} b{self.branch}: width up to {w:.3g}, "
                f"{len(self.depends)} parameters>")

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower

    def to_dict(self, names=None) -> dict:
        def arr(a):
            return [None if not np.isfinite(v) else float(v) for v in np.asarray(a).ravel()]
        d = {"curve": self.curve, "label": self.label, "branch": self.branch,
             "depends": list(self.depends), "q1": arr(self.q1), "q2": arr(self.q2),
             "upper": arr(self.upper), "lower": arr(self.lower),
             "vertical_upper": arr(self.vertical_upper), "vertical_lower": arr(self.vertical_lower),
             "linear_upper": arr(self.linear_upper), "linear_lower": arr(self.linear_lower),
             "q1_extent": list(self.q1_extent), "n_evaluated": self.n_evaluated,
             "reliable": [bool(x) for x in self.reliable]}
        if names is not None:
            d["u_upper"] = dict(zip(names, self.u_upper.tolist()))
            d["u_lower"] = dict(zip(names, self.u_lower.tolist()))
        else:
            d["u_upper"] = self.u_upper.tolist()
            d["u_lower"] = self.u_lower.tolist()
        return d


@dataclass(frozen=True)
class ZoneOverlap:
    """Zones of the two curves bounding one free channel overlap.

    Attributes
    ----------
    q1_range : (float, float)
        Driver range of the overlap, to the samples on either side of those
        where the band edges were found to pass (it begins and ends between
        samples).
    q : (float, float)
        Configuration of the deepest overlap (on the channel's mid-line).
    depth : float
        Largest overlap (q2 units): how far the two band edges pass each other.
    gap : float
        Nominal channel width there (q2 units).
    lower_label, upper_label : str
        The channel's lower and upper curves.
    lower_curve, upper_curve : int
    u_lower_curve_up, u_upper_curve_down : (n,) float
        Vectors pushing the lower curve up and the upper curve down at the
        deepest point ``q`` (the bands' extreme vectors there, not over the
        whole curves: those may push the other way at q).
    depends : tuple of str
        Union of the two curves' dependency sets.
    kind : str
        ``"overlap"``: the band edges pass each other; ``"closure"``: the
        channel lies between the two branches of one contact, and a vector
        of the box (``u_lower_curve_up``, which is ``u_upper_curve_down``
        then) makes that contact impossible there with its features
        overlapping: the branches have met and the channel is closed
        (:func:`_closures`; ``depth`` is then the whole nominal gap).
    """

    q1_range: tuple
    q: tuple
    depth: float
    gap: float
    lower_label: str
    upper_label: str
    lower_curve: int
    upper_curve: int
    u_lower_curve_up: np.ndarray
    u_upper_curve_down: np.ndarray
    depends: tuple
    kind: str = "overlap"

    def to_dict(self, names=None) -> dict:
        def vec(u):
            return dict(zip(names, u.tolist())) if names is not None else u.tolist()
        return {"q1_range": list(self.q1_range), "q": list(self.q), "depth": self.depth,
                "gap": self.gap, "lower": self.lower_label, "upper": self.upper_label,
                "lower_curve": self.lower_curve, "upper_curve": self.upper_curve,
                "u_lower_curve_up": vec(self.u_lower_curve_up),
                "u_upper_curve_down": vec(self.u_upper_curve_down),
                "depends": list(self.depends), "kind": self.kind}


@dataclass(frozen=True, eq=False)
class ZoneAnalysis:
    """Contact zones of one pair of a model, with their overlaps.

    ``stats``: bands, vectors evaluated (into the bands), builds, overlaps,
    curves in the C-space and zones skipped; ``stacked`` (values computed in
    stacked passes, those a stage did not ask for among them) and
    ``stack_fallbacks`` (vectors a stacked pass left to the single call:
    they do not build, or their features changed kind or convexity)."""

    pair: str
    units: str
    names: tuple
    nominal: np.ndarray
    tol: np.ndarray
    bands: tuple
    overlaps: tuple
    accuracy: Accuracy
    stats: dict = field(default_factory=dict)
    #: the pair's characteristic length L (model units): a sliding
    #: follower's C-space values times L are slides
    char_length: float | None = None

    def __repr__(self):
        return (f"<ZoneAnalysis {self.pair!r}: {len(self.bands)} bands, "
                f"{len(self.overlaps)} overlaps>")

    def band(self, curve: int) -> ZoneBand | None:
        for b in self.bands:
            if b.curve == curve:
                return b
        return None

    def seeds(self) -> list:
        """Check-list seeds: (vector, dependency set, label, direction) per band."""
        out = []
        for b in self.bands:
            if np.isfinite(b.upper).any():
                out.append((b.u_upper, frozenset(b.depends), b.label, +1))
            if np.isfinite(b.lower).any():
                out.append((b.u_lower, frozenset(b.depends), b.label, -1))
        return out

    def to_dict(self) -> dict:
        return {"format": "cspace-zones", "version": 1, "pair": self.pair, "units": self.units,
                "metric": "rad for rotations; slide / char_length for slides",
                "char_length": self.char_length,
                # which numbers are in that metric, which in q2's own unit
                "fields": {"bands[].upper, lower, linear_upper, linear_lower": "metric",
                           "bands[].vertical_upper, vertical_lower, overlaps[].depth, gap":
                           "q2's own unit: rad for a turning follower, else units"},
                "parameters": list(self.names), "nominal": self.nominal.tolist(),
                "tol": self.tol.tolist(), "accuracy": self.accuracy.to_dict(),
                "stats": dict(self.stats),
                "bands": [b.to_dict(self.names) for b in self.bands],
                "overlaps": [o.to_dict(self.names) for o in self.overlaps]}


# ------------------------------------------------------------------ evaluation

def _varied_kernel(c: ContactCurve, pair) -> Kernel | None:
    fa = feature_by_key(pair.driver, c.features[0])
    fb = feature_by_key(pair.follower, c.features[1])
    if fa is None or fb is None:
        return None
    for eq, owner, r in equation_types(fa, fb):
        if eq == c.kernel.eq and owner == c.kernel.owner:
            return Kernel(eq, owner, float(r), fa, fb, pair.driver.axis, pair.follower.axis,
                           c.kernel.scale)
    return None


def varied_curve_values(c: ContactCurve, pair, q1):
    """q2 of curve ``c``'s features on ``pair`` (a variant) at q1, NaN where the
    varied contact is not real (trimmed away)."""
    k = _varied_kernel(c, pair)
    q1 = np.atleast_1d(np.asarray(q1, dtype=float))
    if k is None:
        return np.full(q1.shape, np.nan)
    m, q2 = k.margin(q1, c.bi)
    return np.where(m >= -_ON_FEATURE, q2, np.nan)


class _Evaluator:
    """Displacements of one curve's variants at fixed samples."""

    def __init__(self, c: ContactCurve, build, q1s, q2s, normals, s2, periodic2):
        self.c = c
        self.build = build
        self.q1s = q1s
        self.q2s = q2s
        self.n = normals
        self.s2 = s2
        self.periodic2 = periodic2
        self.slope = -normals[:, 0] / np.where(normals[:, 1] != 0, normals[:, 1], TINY) / s2
        self.bound = None  # (S,) search half-width for the local intersection
        self.last_margin = None  # (S,) contact margin at the samples' q1, last call
        self.nominal = None  # the nominal pair (the structural flags of :meth:`many`)
        self.counts = {"stacked": 0, "stack_fallbacks": 0}

    def _trials(self):
        """The offsets along the normal (S, 25) that the search scans: 25 even
        steps over +/- :attr:`bound`."""
        return self.bound[:, None] * np.linspace(-1.0, 1.0, 25)[None, :]

    def __call__(self, u):
        """(normal displacement (S,), vertical displacement (S,)); NaN where absent."""
        pair = self.build(u)
        k = _varied_kernel(self.c, pair) if pair is not None else None
        S = len(self.q1s)
        if k is None:
            # no margin either: not the previous vector's
            self.last_margin = None
            return np.full(S, np.nan), np.full(S, np.nan)
        bi = self.c.bi
        tau, v, self.last_margin = self._displacements(lambda x: k.solve(x)[0][bi],
                                                       lambda x: k.margin(x, bi))
        return tau, v

    def _displacements(self, solve, mq):
        """Normal and vertical displacements of a varied curve at the samples,
        NaN where it is not real, and its contact margin at the samples' q1:
        ``solve(q1)`` gives its q2, ``mq(q1)`` its (margin, q2); one variant
        (q1 and results 1-D) or the rows of a stack (a leading axis).

        Newton alone can jump to a far intersection where the curve is steep:
        once :attr:`bound` is set, the intersection with the nominal normal
        nearest to the nominal point within +/- bound is searched instead
        (:func:`_nearest_crossing`)."""
        nt, ny = self.n[:, 0], self.n[:, 1]
        v = self._wrapped(solve(self.q1s) - self.q2s)
        if self.bound is not None:
            tau = _nearest_crossing(lambda t: self._h(mq, t), self._trials())
        else:
            # intersect the varied curve with the nominal normal
            tau = v * self.s2 * ny
            dh = self.slope * self.s2 * nt - ny
            dh = np.where(np.abs(dh) > ROUNDING, dh, -1.0)
            for _ in range(3):
                x = self.q1s + tau * nt
                ref = self.q2s + tau * ny / self.s2
                tau = tau - self._wrapped(solve(x) - ref) * self.s2 / dh
            mx = mq(self.q1s + tau * nt)[0]
            tau = np.where(mx >= -_ON_FEATURE, tau, np.nan)
        mv = mq(self.q1s)[0]
        return tau, np.where(mv >= -_ON_FEATURE, v, np.nan), mv

    def _wrapped(self, d):
        return (d + math.pi) % TWO_PI - math.pi if self.periodic2 else d

    def _h(self, mq, tau):
        """Signed distance (C-space metric) from the points ``tau`` along the
        nominal normals to the varied curve, along q2; NaN where the contact
        is not real.  ``tau`` (S, n), or (V, S, 1) per stack row; the result
        has the leading axis of ``mq``'s."""
        nt, ny = self.n[:, 0], self.n[:, 1]
        X = self.q1s[:, None] + tau * nt[:, None]
        R = self.q2s[:, None] + tau * ny[:, None] / self.s2
        flat = X.shape[:-2] + (-1,)
        mg, q2v = mq(X.reshape(flat))
        shape = mg.shape[:-1] + X.shape[-2:]
        h = (self._wrapped(q2v - R.reshape(flat)) * self.s2).reshape(shape)
        return np.where((mg >= -_ON_FEATURE).reshape(shape), h, np.nan)

    # ---------------------------------------------------------- many at once
    def many(self, us) -> list:
        """:meth:`__call__` of several vectors in one stacked pass
        (:func:`cspace.batch.kernels.curve_stack`): per vector ``(tau, v,
        margin)``, ``margin`` the :attr:`last_margin` the call sets (None where
        it sets none: the vector does not build or lacks the curve's features).
        A vector the stack cannot take (its features changed kind or
        convexity) gets the single call.  The arithmetic is that of
        :meth:`__call__` (:meth:`_displacements`) on ``(V, S)`` arrays."""
        from .batch.kernels import curve_stack
        c = self.c
        pairs = [self.build(u) for u in us]
        if self.nominal is None:
            pairs = [None] * len(us)
        st = curve_stack([self.nominal] + pairs, c.features, c.kernel.eq, c.kernel.owner,
                         c.kernel.scale)
        ok = st.ok[1:] if st is not None else np.zeros(len(us), dtype=bool)
        out = [None] * len(us)
        rows = np.nonzero(ok)[0]
        self.counts["stacked"] += len(rows)
        self.counts["stack_fallbacks"] += len(us) - len(rows)
        if len(rows):
            sub = st.take(rows + 1)
            bi = c.bi
            tau, v, mv = self._displacements(lambda x: sub.solve(x)[0][bi],
                                             lambda x: sub.branch(x, bi)[::-1])
            for j, r in enumerate(rows):
                out[r] = (tau[j], v[j], mv[j])
        for r in np.nonzero(~ok)[0]:
            keep = self.last_margin
            t, v_ = self(us[r])
            out[r] = (t, v_, self.last_margin)
            self.last_margin = keep
        return out


def _nearest_crossing(h_of, T):
    """The root of ``h_of`` nearest to the middle of each row of trial offsets
    ``T`` (S, n): a sign scan over ``T``, six vectorised bisection steps and a
    secant step; NaN where no sign change is found.  ``h_of(tau)`` takes
    offsets (S, n) or (..., S, 1) and returns (..., S, n) (leading axes:
    variants)."""
    H = h_of(T)
    mid = T.shape[-1] // 2
    sc = np.isfinite(H[..., :-1]) & np.isfinite(H[..., 1:]) & (H[..., :-1] * H[..., 1:] <= 0)
    j_idx = np.arange(T.shape[-1] - 1)
    dist = np.minimum(np.abs(j_idx - mid), np.abs(j_idx + 1 - mid))
    score = np.where(sc, dist, 10 ** 6)
    jb = np.argmin(score, axis=-1)[..., None]
    found = np.take_along_axis(sc, jb, -1)[..., 0]
    Tb = np.broadcast_to(T, H.shape)
    a = np.take_along_axis(Tb, jb, -1)[..., 0].copy()
    b = np.take_along_axis(Tb, jb + 1, -1)[..., 0].copy()
    ha = np.take_along_axis(H, jb, -1)[..., 0].copy()
    hb = np.take_along_axis(H, jb + 1, -1)[..., 0].copy()
    for _ in range(6):
        c = 0.5 * (a + b)
        hc = h_of(c[..., None])[..., 0]
        left = np.isfinite(hc) & (ha * hc <= 0)
        b = np.where(left, c, b)
        hb = np.where(left, hc, hb)
        a = np.where(~left, c, a)
        ha = np.where(~left, hc, ha)
    den = hb - ha
    tau = np.where(np.isfinite(den) & (den != 0), a - ha * (b - a) / np.where(den != 0, den, 1.0),
                   0.5 * (a + b))
    tau = np.where((tau >= np.minimum(a, b)) & (tau <= np.maximum(a, b)), tau, 0.5 * (a + b))
    return np.where(found, tau, np.nan)


def _search_bound(lin):
    """Half-width of the local intersection search at each sample: three times the
    first-order band, plus 5 % of its largest value."""
    return 3.0 * lin + SLACK + 0.05 * np.nanmax(np.append(lin, 0.0))


def _band_evaluator(cs: ConfigurationSpace, band: "ZoneBand", build) -> _Evaluator:
    """Displacements of ``band``'s varied curve at its samples, for ``build(u)`` ->
    pair, measured exactly as :func:`contact_zones` measured the band (checks of
    containment use this)."""
    periodic2 = bool(cs.periodic[1])
    s2 = 1.0 / follower_scale(cs.pair)
    ev = _Evaluator(cs.curves[band.curve], build, band.q1, band.q2, band.normal, s2, periodic2)
    ev.bound = _search_bound(np.abs(band.linear_upper))
    return ev


def _curve_normals(c: ContactCurve, q1s, s2):
    """Unit normals (C-space metric, pointing to larger q2) of curve ``c`` at
    ``q1s`` (inside its trimmed range), from a central difference of its exact
    q2: those the zone bands are measured along."""
    a, b = c.q1_start, c.q1_end
    h = max(PROBE_REL * coord_scale(c.kernel.axis_a, c.kernel.scale), 1e-4 * (b - a))
    slope = (c.raw(np.minimum(q1s + h, b)) - c.raw(np.maximum(q1s - h, a))) / \
        (np.minimum(q1s + h, b) - np.maximum(q1s - h, a))
    nrm = np.stack([-slope * s2, np.ones_like(slope)], 1)
    nrm /= np.hypot(nrm[:, 0], nrm[:, 1])[:, None]
    return nrm


def _seed_for(c: ContactCurve, base: int) -> int:
    h = hashlib.sha256(f"{c.label}|{c.branch}|{c.q1_start:.9f}".encode()).digest()
    return (int.from_bytes(h[:4], "little") + base) % (2 ** 32)


def _check_pair_index(cs, model, pair_index) -> None:
    """The arguments of :func:`contact_zones`: ``cs`` a ConfigurationSpace,
    ``pair_index`` an int naming one of the pairs ``model`` builds (0 for a
    one-pair model), whose parts are those of ``cs``; else an InputError.  A
    model whose nominal does not build is left to the zones' own builds."""
    from .errors import InputError
    if not isinstance(cs, ConfigurationSpace):
        raise InputError(f"cs must be the ConfigurationSpace of a pair of the model "
                         f"(mechanisms.analysis.model_cspaces(model)[pair_index]), got "
                         f"{type(cs).__name__}", name="cs", value=cs)
    if isinstance(pair_index, (bool, np.bool_)) or not isinstance(pair_index,
                                                                   (int, np.integer)):
        raise InputError(f"pair_index must be an int, the index of a pair of the model (0 for "
                         f"a one-pair model), got {type(pair_index).__name__} {pair_index!r}",
                         name="pair_index", value=pair_index)
    try:
        with trusted():
            out = model.build(np.asarray(model.nominal, dtype=float))
    except (ValueError, ArithmeticError):
        return
    pairs = out.pairs if isinstance(out, Assembly) else (out,)
    name = getattr(model, "name", type(model).__name__)
    if not 0 <= int(pair_index) < len(pairs):
        allowed = "0 (it builds one pair)" if len(pairs) == 1 else \
            f"0 to {len(pairs) - 1} (it builds {len(pairs)} pairs)"
        raise InputError(f"pair_index {int(pair_index)} is out of range for model {name!r}; "
                         f"allowed: {allowed}", name="pair_index", value=pair_index)
    got = tuple(p.name for p in cs.pair.parts)
    want = tuple(p.name for p in pairs[int(pair_index)].parts)
    if got != want:
        raise InputError(f"cs is not the C-space of pair {int(pair_index)} of model {name!r}: "
                         f"its parts are {list(got)}, that pair's are {list(want)}; pass "
                         f"model_cspaces(model)[{int(pair_index)}] (mechanisms.analysis)",
                         name="cs", value=cs)


def contact_zones(cs: ConfigurationSpace, model, pair_index: int = 0,
                  accuracy: Accuracy | str | None = None, *, curves=None, faces=None,
                  cells=None, boundary_only: bool = True, seed: int = 0,
                  executor=None) -> ZoneAnalysis:
    """Contact zones of a pair of a parametric model.

    Parameters
    ----------
    cs : ConfigurationSpace
        The nominal C-space of pair ``pair_index`` of ``model``.
    model : cspace.model.ParametricModel
        e.g. :class:`mechanisms.models.Model`; the zones read its ``build(u)``,
        ``nominal``, ``tol`` and ``names``.
    pair_index : int
        Which pair of an assembly model, ``0 <= pair_index < number of
        pairs`` (0 for a one-pair model); the parts of ``cs`` must be that
        pair's (an :class:`~cspace.errors.InputError` otherwise).
    accuracy : Accuracy or preset name (default: the C-space's accuracy)
    curves : iterable of int, optional
        Curve indices to compute (default: the curves that bound free space, or
        all curves with ``boundary_only=False``).
    faces : iterable of int, optional
        Only the curves bounding these free faces (e.g. the operating channel,
        ``cs.face_at([q_start])``); the other zones are skipped.
    cells : iterable of (slab, cell), optional
        Only the curves bounding these cells, e.g. the operating region, the
        cells a motion passes through (:attr:`SimulationResult.cells`); with
        ``faces`` too, only those of the cells in these faces.
    seed : int
        Seed of the random corner subsets (results do not depend on workers).
    executor : concurrent.futures.Executor, optional
        Computes the curves' zones in tasks of a few curves each (a curve's
        zone does not depend on the others': the same bands as without it).
        ``stats["builds"]`` counts the distinct vectors built over all tasks.
    """
    from .batch import heap
    heap.keep()
    check_model(model, members=("build", "nominal", "tol", "names"))
    _check_pair_index(cs, model, pair_index)
    if executor is not None and not callable(getattr(executor, "submit", None)):
        from .errors import InputError
        raise InputError("executor must be a concurrent.futures.Executor (with submit) or "
                         f"None, got {type(executor).__name__}", name="executor",
                         value=executor)
    acc = cs.accuracy if accuracy is None else as_accuracy(accuracy)
    u0 = np.asarray(model.nominal, dtype=float)
    tol = np.asarray(model.tol, dtype=float)
    names = tuple(model.names)
    pair = cs.pair
    skipped = 0
    if curves is None and cells is not None:
        fs = None if faces is None else set(int(f) for f in np.atleast_1d(faces))
        bounding = set()
        for k, j in cells:
            c = cs.cells[int(k)][int(j)]
            if c.free and (fs is None or c.face in fs):
                bounding |= {c.lower, c.upper}
        bounding.discard(-1)
        curves = sorted(bounding)
        skipped = len({b.curve for b in cs.boundary} - bounding)
    elif curves is None and faces is not None:
        fs = set(int(f) for f in np.atleast_1d(faces))
        curves = sorted({b.curve for b in cs.boundary if b.free_face in fs})
        skipped = len({b.curve for b in cs.boundary}) - len(curves)
    if curves is None:
        if boundary_only:
            curves = sorted({b.curve for b in cs.boundary})
        else:
            curves = range(len(cs.curves))
    curves = [int(ci) for ci in curves]
    if executor is None or len(curves) < 2:
        parts = [_zones_of_curves(cs, model, pair_index, acc, curves, seed)]
    else:
        parts = _on_executor(executor, cs, model, pair_index, acc, curves, seed)
    bands = [b for part in parts for b in part[0]]
    counts = {"stacked": 0, "stack_fallbacks": 0}
    for part in parts:
        for k in counts:
            counts[k] += part[1][k]
    built = set().union(*(part[2] for part in parts))
    n_eval = sum(b.n_evaluated for b in bands)
    overlaps = _overlaps(cs, {b.curve: b for b in bands}, u0)
    overlaps += _closures(cs, {b.curve: b for b in bands}, model, pair_index, u0, tol,
                          {(o.lower_curve, o.upper_curve) for o in overlaps})
    stats = {"bands": len(bands), "vectors_evaluated": n_eval, "builds": len(built),
             "overlaps": len(overlaps), "curves_total": len(cs.curves), "zones_skipped": skipped,
             **counts}
    return ZoneAnalysis(pair.name, pair.units, names, u0, tol, tuple(bands), tuple(overlaps),
                        acc, stats, float(pair.char_length))


#: :func:`contact_zones` on an executor: tasks per worker (the curves' zones
#: cost unequally; a few tasks each keep the workers busy to the end).
ZONE_TASKS_PER_WORKER = 4


def _on_executor(executor, cs, model, pair_index, acc, curves, seed) -> list:
    """:func:`_zones_of_curves` of consecutive runs of ``curves`` as tasks of
    ``executor``, in order; the tasks not yet started are cancelled when one
    fails (or on an interrupt)."""
    workers = getattr(executor, "_max_workers", None)
    k = min(len(curves), ZONE_TASKS_PER_WORKER * (workers if isinstance(workers, int)
                                                  and workers > 0 else 2))
    bounds = np.linspace(0, len(curves), k + 1).round().astype(int)
    futures = []
    with cancelled_on_failure(futures):
        for a, b in zip(bounds[:-1], bounds[1:]):
            futures.append(executor.submit(_zones_of_curves, cs, model, pair_index, acc,
                                           curves[a:b], seed))
        return [f.result() for f in futures]


def _zones_of_curves(cs, model, pair_index, acc, curves, seed) -> tuple:
    """The :class:`ZoneBand` of each curve of ``curves`` (indices into
    ``cs.curves``), the counts of their stacked passes, and the vectors built
    (their bits): the unit of work of :func:`contact_zones`."""
    u0 = np.asarray(model.nominal, dtype=float)
    tol = np.asarray(model.tol, dtype=float)
    index = {nm: i for i, nm in enumerate(model.names)}
    periodic2 = isinstance(cs.pair.follower.axis, Rotation)
    s2 = 1.0 / follower_scale(cs.pair)
    cache: dict = {}

    def build(u):
        key = np.asarray(u, dtype=float).tobytes()
        if key not in cache:
            cache[key] = _built_pair(model, pair_index, u)
        return cache[key]

    bands = []
    counts = {"stacked": 0, "stack_fallbacks": 0}
    for ci in curves:
        c = cs.curves[ci]
        band, done = _zone_of_curve(ci, c, build, u0, tol, index, acc, s2, periodic2,
                                    _seed_for(c, seed))
        for k in counts:
            counts[k] += done[k]
        bands.append(band)
    return bands, counts, set(cache)


def _built_pair(model, pair_index: int, u):
    """Pair ``pair_index`` of ``model`` built at ``u`` (the loop checks
    skipped, as for every variant of a validated nominal), or None where the
    geometry cannot be built."""
    try:
        with trusted():
            out = model.build(u)
        return out.pairs[pair_index] if isinstance(out, Assembly) else out
    except (ValueError, ArithmeticError):
        return None


def _zone_of_curve(ci, c, build, u0, tol, index, acc, s2, periodic2, seed):
    """The :class:`ZoneBand` of curve ``c``: the stages of :class:`_CurveZone`,
    top to bottom (module docstring), and the counts of its stacked passes
    (:attr:`_Evaluator.counts`)."""
    z = _CurveZone(c, build, u0, tol, index, acc, s2, periodic2)
    z.sensitivities()
    z.corners(seed)
    z.lost_guides()
    z.climb()
    z.refine()
    return z.band(ci), z.ev.counts


class _CurveZone:
    """The variants of one curve evaluated so far (the pool), and the stages
    that add to it: first-order sensitivities, box corners, searches where the
    extreme corner loses the contact, a corner hill-climb and a bounded local
    refinement.  Every vector evaluated contributes to the band at every
    sample (:meth:`band`)."""

    def __init__(self, c, build, u0, tol, index, acc, s2, periodic2):
        self.c, self.build, self.u0, self.tol, self.acc = c, build, u0, tol, acc
        S = self.S = acc.zone_samples
        a, b = c.q1_start, c.q1_end
        inset = PROBE_REL * max(b - a, ROUNDING)
        q1s = self.q1s = np.linspace(a + inset, b - inset, S)
        q2s = self.q2s = c.raw(q1s)
        nrm = self.nrm = _curve_normals(c, q1s, s2)
        self.ev = _Evaluator(c, build, q1s, q2s, nrm, s2, periodic2)
        self.ev.nominal = build(u0)
        self.dep = tuple(sorted(c.depends, key=lambda nm: index.get(nm, 1 << 30)))
        self.idx = np.array([index[nm] for nm in self.dep if nm in index and tol[index[nm]] > 0],
                            dtype=int)
        self.m = len(self.idx)
        self.pool_u, self.pool_t, self.pool_v = [], [], []
        # the rounding slack of displacements (set once the first-order band is known)
        self.tie = 0.0
        self.seen_u: dict = {}
        # values computed ahead (:meth:`prefetch`), not yet in the pool
        self.ahead: dict = {}

    def prefetch(self, us) -> None:
        """Evaluate the vectors ``us`` not evaluated yet in one stacked pass
        (:meth:`_Evaluator.many`) and keep their values for :meth:`evaluate`.
        The pool grows only as :meth:`evaluate` is called, in the stages'
        order: a value computed ahead that a stage then does not ask for (a
        climb that stops early) counts nowhere, so the band is that of the
        stages asking one vector at a time."""
        todo, keys = [], set()
        for u in us:
            key = np.asarray(u, dtype=float).tobytes()
            if key in self.seen_u or key in self.ahead or key in keys:
                continue
            keys.add(key)
            todo.append(np.asarray(u, dtype=float))
        if len(todo) < 2:
            return
        for u, res in zip(todo, self.ev.many(todo)):
            self.ahead[u.tobytes()] = res

    def evaluate(self, u):
        got = self.ahead.pop(np.asarray(u, dtype=float).tobytes(), None)
        if got is None:
            t, v = self.ev(u)
        else:
            t, v, mg = got
            self.ev.last_margin = mg
        self.seen_u.setdefault(np.asarray(u, dtype=float).tobytes(), len(self.pool_u))
        self.pool_u.append(np.array(u, dtype=float))
        self.pool_t.append(t)
        self.pool_v.append(v)
        return t

    def known_or_evaluate(self, u):
        kk = self.seen_u.get(u.tobytes())
        return self.pool_t[kk] if kk is not None else self.evaluate(u)

    def sensitivities(self) -> None:
        """Linear sensitivity (central differences): the baseline band and the
        guide to the extreme corners."""
        S, m, ev, u0, tol = self.S, self.m, self.ev, self.u0, self.tol
        grad = np.zeros((S, m))
        mgrad = np.zeros((S, m))  # the same for the contact margin at the samples' q1
        reliable = np.ones(S, dtype=bool)
        steps = []
        for i in self.idx:
            up = u0.copy()
            up[i] += tol[i]
            dn = u0.copy()
            dn[i] -= tol[i]
            steps.append((up, dn))
        self.prefetch([w for st in steps for w in st])
        for jj, (up, dn) in enumerate(steps):
            tp = self.evaluate(up)
            mp = ev.last_margin
            tn = self.evaluate(dn)
            mn = ev.last_margin
            if mp is not None and mn is not None:
                mgrad[:, jj] = 0.5 * (mp - mn)
            # central difference; one-sided where a side's varied curve is trimmed
            # away there (near curve ends), since tau = 0 at the nominal vector
            g = 0.5 * (tp - tn)
            reliable &= np.isfinite(g)
            g = np.where(np.isfinite(g), g, np.where(np.isfinite(tp), tp, -tn))
            grad[:, jj] = np.nan_to_num(g)
        self.grad, self.mgrad, self.reliable = grad, mgrad, reliable
        self.lin = np.abs(grad).sum(1)
        self.tie = _TIE_REL * max(float(np.nanmax(np.append(self.lin, 0.0))), TINY)
        # from here on, displacements are the local intersections within 3x the
        # linear band
        ev.bound = _search_bound(self.lin)
        self.ahead.clear()

    def corners(self, seed) -> None:
        """Every box corner over the curve's dependencies when there are few;
        else the first-order extreme corners and a seeded set of others."""
        m, acc, u0, tol, idx = self.m, self.acc, self.u0, self.tol, self.idx
        corners = []
        if m and 2 ** m <= acc.zone_max_corners:
            corners = [np.array(sg) for sg in itertools.product((-1.0, 1.0), repeat=m)]
        elif m:
            sg = _signs(self.grad)
            seen = set()
            for row in np.vstack([sg, -sg]):
                key = row.tobytes()
                if key not in seen:
                    seen.add(key)
                    corners.append(row)
            rng = np.random.default_rng(seed)
            for _ in range(acc.zone_random_corners):
                corners.append(rng.choice([-1.0, 1.0], m))
        us = []
        for sgn in corners:
            u = u0.copy()
            u[idx] += sgn * tol[idx]
            us.append(u)
        self.prefetch(us)
        for u in us:
            self.evaluate(u)
        if not m:
            # no parameter the curve depends on has a tolerance: the band is the
            # nominal curve itself (zero width where it exists)
            self.evaluate(u0.copy())

    def lost_guides(self) -> None:
        """Where the linearly extreme corner loses the contact at a sample (the
        varied curve is trimmed before it), the extreme lies inside the box:
        search along the same direction towards the nominal vector."""
        self.guide_lost = ~self.reliable
        if not self.m:
            return
        u0, tol, idx, grad, m = self.u0, self.tol, self.idx, self.grad, self.m
        sg = _signs(grad)
        tried = set()
        for s_ in range(self.S):
            for direction in (1.0, -1.0):
                row = direction * sg[s_]
                key = row.tobytes()
                u = u0.copy()
                u[idx] += row * tol[idx]
                t_corner = self.known_or_evaluate(u)
                if np.isfinite(t_corner[s_]):
                    continue
                self.guide_lost[s_] = True
                if key in tried:
                    continue
                tried.add(key)
                # first: the corner with one weak coordinate flipped (the contact
                # often survives), then shorter steps along the same direction
                weak = _stable_order(_denoised(np.abs(grad[s_])))[:min(4, m)]
                flips = []
                for jj in weak:
                    w = u.copy()
                    w[idx[jj]] = u0[idx[jj]] - row[jj] * tol[idx[jj]]
                    flips.append(w)
                shorter = []
                for frac in (0.8, 0.6, 0.4, 0.2):
                    w = u0.copy()
                    w[idx] += frac * row * tol[idx]
                    shorter.append(w)
                self.prefetch(flips + shorter)
                found = False
                for w in flips:
                    if np.isfinite(self.evaluate(w)[s_]):
                        found = True
                if found:
                    continue
                for w in shorter:
                    if np.isfinite(self.evaluate(w)[s_]):
                        break

    def climb(self) -> None:
        """Corner hill-climb where the linear guide fails (near trimmed curve
        ends many variants lose the contact and the first-order signs no longer
        point to the extreme corner): from the best candidate at the sample,
        flip one coordinate at a time while that moves the curve further, at up
        to ``zone_climb`` samples per direction, spread over the samples
        concerned."""
        acc, m = self.acc, self.m
        if not (m and acc.zone_climb > 0 and self.guide_lost.any()):
            return
        u0, tol, idx = self.u0, self.tol, self.idx
        lost = np.flatnonzero(self.guide_lost)
        picks = lost[np.unique(np.linspace(0, len(lost) - 1, min(acc.zone_climb, len(lost)))
                               .round().astype(int))]
        guided = _constrained_guide(self.c, self.build, u0, tol, idx, self.grad, self.mgrad,
                                    self.q1s, self.nrm, picks)
        self.prefetch(guided)
        for u in guided:
            self.evaluate(u)
        for direction in (1.0, -1.0):
            for s in picks:
                col = np.array([t[s] for t in self.pool_t])
                if not np.isfinite(col).any():
                    continue
                k_best = _first_extreme(direction * col[:, None], self.tie)
                u = self.pool_u[k_best].copy()
                f_u = direction * col[k_best]
                for _ in range(2):
                    improved = False
                    self.prefetch([_flipped(u, i, u0, tol) for i in idx])
                    for j, i in enumerate(idx):
                        w = _flipped(u, i, u0, tol)
                        val = self.known_or_evaluate(w)[s]
                        if np.isfinite(val) and direction * val > f_u + self.tie:
                            u, f_u, improved = w, direction * val, True
                            self.prefetch([_flipped(u, i_, u0, tol) for i_ in idx[j + 1:]])
                    if not improved:
                        break

    def refine(self) -> None:
        """Bounded local refinement: coordinate-wise parabolas inside the box,
        from the extreme candidates at ``zone_opt_samples`` samples per
        direction."""
        acc = self.acc
        if not (self.m and acc.zone_opt_iter > 0 and acc.zone_opt_samples > 0):
            return
        T = np.array(self.pool_t)
        for direction in (1.0, -1.0):
            best_per_sample = np.nanmax(np.where(np.isfinite(T), direction * T, -np.inf), axis=0)
            if not np.isfinite(best_per_sample).any():
                continue
            order = _stable_order(-_snapped(best_per_sample, self.tie))
            for s in list(order[:acc.zone_opt_samples]):
                k_best = _first_extreme(direction * T[:, s:s + 1], self.tie)
                self._refine_at(s, direction, self.pool_u[k_best].copy(),
                                direction * self.pool_t[k_best][s])

    def _refine_at(self, s, direction, u, f_u) -> None:
        """Coordinate-wise parabolic steps at sample s from vector u (value f_u,
        signed by ``direction``)."""
        u0, tol, tie = self.u0, self.tol, self.tie
        # only coordinates whose first-order effect is small can have an
        # interior optimum; the corners already settle the others
        gs = np.abs(self.grad[s])
        flat = self.idx[gs <= 0.1 * max(gs.max(), TINY)]
        def points(u, coords):
            # the three points of each coordinate's parabola that differ from u
            out = []
            for i in coords:
                for x in (-tol[i], 0.0, tol[i]):
                    if not abs(x - (u[i] - u0[i])) < EQUAL_REL * max(tol[i], TINY):
                        w = u.copy()
                        w[i] = u0[i] + x
                        out.append(w)
            return out

        for _ in range(self.acc.zone_opt_iter):
            improved = False
            self.prefetch(points(u, flat))
            for j, i in enumerate(flat):
                x0 = u[i] - u0[i]
                cand = {}
                for x in (-tol[i], 0.0, tol[i]):
                    if abs(x - x0) < EQUAL_REL * max(tol[i], TINY):
                        cand[x] = f_u
                        continue
                    w = u.copy()
                    w[i] = u0[i] + x
                    val = self.evaluate(w)[s]
                    cand[x] = direction * val if np.isfinite(val) else -np.inf
                fm, f0_, fp = cand[-tol[i]], cand[0.0], cand[tol[i]]
                xs = [(-tol[i], fm), (0.0, f0_), (tol[i], fp)]
                if all(np.isfinite([fm, f0_, fp])) and \
                        max(fm, f0_, fp) - min(fm, f0_, fp) > tie:
                    den = fm - 2 * f0_ + fp
                    if den < 0:
                        xv = 0.5 * tol[i] * (fm - fp) / den
                        if -tol[i] < xv < tol[i]:
                            w = u.copy()
                            w[i] = u0[i] + xv
                            val = self.evaluate(w)[s]
                            if np.isfinite(val):
                                xs.append((xv, direction * val))
                top = max(p[1] for p in xs)
                xb, fb = next(p for p in xs if p[1] >= top - tie)
                if fb > f_u + tie:
                    u[i] = u0[i] + xb
                    f_u = fb
                    improved = True
                    self.prefetch(points(u, flat[j + 1:]))
            if not improved:
                break

    def band(self, ci) -> ZoneBand:
        """The band over everything evaluated, and its extreme vectors."""
        acc = self.acc
        T = np.array(self.pool_t)
        V = np.array(self.pool_v)
        with np.errstate(all="ignore"):
            upper = np.where(np.isfinite(T).any(0),
                             np.nanmax(np.where(np.isfinite(T), T, -np.inf), 0), np.nan)
            lower = np.where(np.isfinite(T).any(0),
                             np.nanmin(np.where(np.isfinite(T), T, np.inf), 0), np.nan)
            vup = np.where(np.isfinite(V).any(0),
                           np.nanmax(np.where(np.isfinite(V), V, -np.inf), 0), np.nan)
            vlo = np.where(np.isfinite(V).any(0),
                           np.nanmin(np.where(np.isfinite(V), V, np.inf), 0), np.nan)
        # where the linear guide is lost (near a trimmed curve end, most variants
        # lose the contact at the sample and the few that keep it are isolated
        # corners), the band takes the envelope of its neighbours within 1/8 of
        # the curve: a conservative widening, only there (the band rises steeply
        # towards an end)
        src_up = src_lo = np.arange(self.S)
        if acc.zone_climb > 0 and self.guide_lost.any():
            half = max(2, self.S // 8)
            src_up = _envelope_source(upper, self.guide_lost, 1, half)
            src_lo = _envelope_source(lower, self.guide_lost, -1, half)
            upper, lower, vup, vlo = (_envelope(a_, self.guide_lost, w, half)
                                      for a_, w in ((upper, 1), (lower, -1), (vup, 1),
                                                    (vlo, -1)))
        # extreme vectors over the whole curve: the first evaluated of those that
        # reach the extreme within rounding noise (see "Ties" in the module docstring)
        pool_u, u0 = self.pool_u, self.u0
        k_up = _first_extreme(T, self.tie) if len(self.pool_t) else 0
        k_lo = _first_extreme(-T, self.tie) if len(self.pool_t) else 0
        u_up = pool_u[k_up] if pool_u else u0.copy()
        u_lo = pool_u[k_lo] if pool_u else u0.copy()
        # and at each sample (the same rule per sample), for the overlaps there
        u_up_at = _vectors_at(pool_u, T, self.tie, src_up, u_up)
        u_lo_at = _vectors_at(pool_u, -T, self.tie, src_lo, u_lo)
        extent = _extent(self.c, self.build, [u_up, u_lo], acc)
        return ZoneBand(ci, self.c.label, self.c.branch, self.dep, self.q1s, self.q2s,
                        self.nrm, upper, lower, vup, vlo, self.lin, -self.lin, u_up, u_lo,
                        extent, len(pool_u), self.reliable, u_up_at, u_lo_at)


#: A sensitivity below this share of the largest at its sample is rounding noise.
_GRAD_NOISE = 1e-9

#: A varied contact counts as real (on both features) down to this validity
#: margin (C-space metric): the margin of a point exactly at a feature's end
#: is zero up to rounding.
_ON_FEATURE = 1e-9

#: Displacements closer than this share of the curve's largest first-order
#: displacement are equal (the rounding noise of the Geneva slot flanks is about
#: 1e-14 of it).
_TIE_REL = 1e-9


def _first_extreme(values, tie) -> int:
    """Row of ``values`` (rows: candidates in evaluation order; columns: samples;
    NaN: no contact) whose largest entry is within ``tie`` of the largest of all:
    the first such row, so that candidates equal up to rounding noise are decided
    by their order, never by their last bits.  0 when no entry is finite."""
    v = np.asarray(values, dtype=float)
    if v.ndim == 1:
        v = v[:, None]
    fin = np.isfinite(v)
    if not fin.any():
        return 0
    best = np.max(np.where(fin, v, -np.inf), axis=1)
    return int(np.flatnonzero(best >= best.max() - tie)[0])


def _vectors_at(pool_u, values, tie, src, fallback):
    """Per sample s, the first vector of ``pool_u`` whose entry of ``values``
    (rows: candidates in evaluation order; columns: samples) at sample
    ``src[s]`` is within ``tie`` of the largest there (:func:`_first_extreme`
    column by column); ``fallback`` where no entry there is finite.  (S, n)."""
    S = len(src)
    out = np.tile(np.asarray(fallback, dtype=float), (S, 1))
    v = np.asarray(values, dtype=float)
    if not pool_u or v.ndim != 2:
        return out
    fin = np.isfinite(v)
    best = np.max(np.where(fin, v, -np.inf), axis=0)
    hit = fin & (v >= best[None, :] - tie)
    k = np.argmax(hit, axis=0)
    has = fin.any(axis=0)
    U = np.asarray(pool_u, dtype=float)
    for s in range(S):
        j = int(src[s])
        if has[j]:
            out[s] = U[k[j]]
    return out


def _snapped(values, tie):
    """``values`` snapped to multiples of ``tie`` (NaN -> -inf): equal within
    rounding noise becomes equal."""
    v = np.where(np.isfinite(values), values, -np.inf)
    if not tie > 0:
        return v
    with np.errstate(invalid="ignore"):
        return np.where(np.isfinite(v), np.round(v / tie) * tie, v)


def _denoised(a):
    """Non-negative sensitivities with rounding noise (below ``_GRAD_NOISE`` of the
    largest) set to 0 and the rest snapped to that grid."""
    a = np.asarray(a, dtype=float)
    top = float(np.max(a)) if a.size else 0.0
    if not top > 0:
        return np.zeros_like(a)
    q = _GRAD_NOISE * top
    return np.where(a > q, np.round(a / q) * q, 0.0)


def _stable_order(keys):
    """Indices sorting ``keys`` ascending; equal keys keep their index order."""
    return np.argsort(np.asarray(keys), kind="stable")


def _signs(grad):
    """Corner signs from the sensitivities (S, m): the sign of each, and +1 where
    it is 0 or rounding noise (below ``_GRAD_NOISE`` of the largest at that
    sample), so that a parameter without first-order effect does not take its
    side from the last bits of the geometry."""
    floor = _GRAD_NOISE * np.max(np.abs(grad), axis=1, keepdims=True)
    sg = np.where(np.abs(grad) > floor, np.sign(grad), 1.0)
    sg[sg == 0] = 1.0
    return sg


def _envelope(a, where, sign, half):
    """``a`` with the entries at ``where`` replaced by the signed extreme of their
    ``+/- half`` neighbours (NaN-aware)."""
    out = a.copy()
    n = len(a)
    for s in np.flatnonzero(where):
        w = a[max(0, s - half):min(n, s + half + 1)]
        w = w[np.isfinite(w)]
        if len(w):
            out[s] = sign * np.max(sign * w)
    return out


def _envelope_source(a, where, sign, half):
    """The sample whose value :func:`_envelope` puts at each sample: itself,
    or at ``where`` the first of its ``+/- half`` neighbours with the signed
    extreme finite value (itself where none is finite)."""
    src = np.arange(len(a))
    n = len(a)
    for s in np.flatnonzero(where):
        lo = max(0, s - half)
        w = sign * a[lo:min(n, s + half + 1)]
        fin = np.isfinite(w)
        if fin.any():
            src[s] = lo + int(np.argmax(np.where(fin, w, -np.inf)))
    return src


def _flipped(u, i, u0, tol):
    """``u`` with coordinate i moved to the opposite face of the box (to the
    lower face from the nominal value)."""
    w = u.copy()
    off = u[i] - u0[i]
    w[i] = u0[i] - (np.sign(off) if off != 0 else -1.0) * tol[i]
    return w


def _constrained_guide(c, build, u0, tol, idx, grad, mgrad, q1s, nrm, picks) -> list:
    """Where the first-order extreme corner loses the contact, the extreme over the
    box is the first-order optimum *subject to the contact staying real*: a linear
    programme over the box (displacement gradient as objective, the linearised
    contact margin at the displaced point >= 0 as constraint).  Returns the
    vectors to evaluate exactly, in order: each solution and its nearest
    corner."""
    from scipy.optimize import linprog
    out: list = []
    pair = build(u0)
    k = _varied_kernel(c, pair) if pair is not None else None
    if k is None:
        return out
    h = FD_REL * max(float(np.ptp(q1s)), 1e-3)
    m0 = k.margin(q1s, c.bi)[0]
    dm = (k.margin(q1s + h, c.bi)[0] - k.margin(q1s - h, c.bi)[0]) / (2 * h)
    m = len(idx)
    for s in picks:
        if not (np.isfinite(m0[s]) and np.isfinite(dm[s])):
            continue
        # margin at the displaced point ~ m0 + (mgrad + dm * n_t * grad) . x, x in [-1, 1]^m
        a = mgrad[s] + dm[s] * nrm[s, 0] * grad[s]
        g = np.sign(grad[s]) * _denoised(np.abs(grad[s]))
        for direction in (1.0, -1.0):
            res = linprog(-direction * g, A_ub=-a[None, :], b_ub=[m0[s]],
                          bounds=[(-1.0, 1.0)] * m, method="highs")
            if res.status != 0:
                continue
            x = np.clip(res.x, -1.0, 1.0)
            for cand in (x, np.where(x >= 0, 1.0, -1.0)):
                u = u0.copy()
                u[idx] += cand * tol[idx]
                out.append(u)
    return out


def _extent(c: ContactCurve, build, us, acc) -> tuple:
    """q1 range reached by the varied curves at vectors ``us`` near the nominal ends."""
    from .roots import vroots
    lo, hi = c.q1_start, c.q1_end
    s1 = coord_scale(c.kernel.axis_a, c.kernel.scale)
    span = 0.05 * max(hi - lo, 1e-3 * s1)
    for u in us:
        pair = build(u)
        k = _varied_kernel(c, pair) if pair is not None else None
        if k is None:
            continue
        fn = (lambda x, k=k: k.margin(x, c.bi)[0])
        for end, sgn in ((c.q1_start, -1.0), (c.q1_end, 1.0)):
            if not (c.start_closed if sgn < 0 else c.end_closed):
                continue
            a, b = end - sgn * span, end + sgn * span
            fa, fb = fn(np.array([a]))[0], fn(np.array([b]))[0]
            if fa >= 0 and fb < 0:
                r = float(vroots(fn, np.array([a]), np.array([b]), acc.root_tol * s1)[0])
            elif fb >= 0:
                r = b
            else:
                r = end
            lo, hi = (min(lo, r), hi) if sgn < 0 else (lo, max(hi, r))
    return (float(lo), float(hi))


def _overlaps(cs: ConfigurationSpace, bands: dict, u0) -> list:
    """Channels whose lower curve's upward band meets the upper curve's downward band."""
    out = []
    periodic2 = cs.periodic[1]
    raw = []
    edges: dict = {}

    def edge(band, side):
        key = (band.curve, side)
        if key not in edges:
            edges[key] = _band_edge(band, side, cs, periodic2)
        return edges[key]
    for k, row in enumerate(cs.cells):
        a, b = cs.events[k], cs.events[k + 1]
        for cell in row:
            if not cell.free or cell.lower < 0 or cell.upper < 0 or cell.lower == cell.upper:
                continue
            bl, bu = bands.get(cell.lower), bands.get(cell.upper)
            if bl is None or bu is None:
                continue
            xs = np.unique(np.concatenate([bl.q1[(bl.q1 >= a) & (bl.q1 <= b)],
                                           bu.q1[(bu.q1 >= a) & (bu.q1 <= b)],
                                           np.linspace(a, b, 5)]))
            fl = cs.curves[cell.lower].evaluate(xs)
            fu = cs.curves[cell.upper].evaluate(xs)
            gap = fu - fl
            if periodic2:
                gap = gap % TWO_PI
            # band edges as offset curves (normal displacement), compared at common q1
            up_l = _edge_offset(bl, xs, +1, cs, periodic2, edge(bl, +1))
            dn_u = _edge_offset(bu, xs, -1, cs, periodic2, edge(bu, -1))
            sep = gap - np.maximum(up_l, 0) + np.minimum(dn_u, 0)
            bad = np.isfinite(sep) & (sep < 0)
            if bad.any():
                raw.append((k, cell, xs, sep, gap, fl, bad))
    # merge runs of the same (lower, upper) curve pair across consecutive slabs
    merged: dict = {}
    for k, cell, xs, sep, gap, fl, bad in raw:
        key = (cell.lower, cell.upper)
        i = int(np.argmin(np.where(bad, sep, np.inf)))
        rec = merged.get(key)
        cand = (*_bracket(xs, bad), float(-sep[i]), float(xs[i]),
                float(fl[i] + 0.5 * gap[i]), float(gap[i]))
        if rec is None:
            merged[key] = cand
        else:
            lo, hi, depth, x, y, g = rec
            merged[key] = (min(lo, cand[0]), max(hi, cand[1]),
                           *(cand[2:] if cand[2] > depth else (depth, x, y, g)))
    for (il, iu), (lo, hi, depth, x, y, g) in merged.items():
        bl, bu = bands[il], bands[iu]
        if periodic2:
            y = (y - cs.window[2]) % TWO_PI + cs.window[2]
        out.append(ZoneOverlap((lo, hi), (x, y), depth, g, bl.label, bu.label, il, iu,
                               _vector_at(bl, +1, x, cs, periodic2),
                               _vector_at(bu, -1, x, cs, periodic2),
                               tuple(sorted(set(bl.depends) | set(bu.depends)))))
    scale = max((o.depth for o in out), default=0.0)
    out.sort(key=lambda o: (-float(_snapped(o.depth, _TIE_REL * scale)), o.lower_curve,
                            o.upper_curve))
    return out


def _bracket(xs, hit) -> tuple:
    """The driver range of the samples ``hit`` (a mask over the sorted
    ``xs``), widened to the samples on either side: an overlap begins and
    ends between samples, so this range holds it (the hit samples alone lie
    inside it: a slot end's closure of [1.526, 1.615] rad read as [1.530,
    1.612])."""
    j = np.nonzero(hit)[0]
    a, b = int(j[0]), int(j[-1])
    return float(xs[max(a - 1, 0)]), float(xs[min(b + 1, len(xs) - 1)])


#: :func:`_closures`: the corners of a contact's dependency set are tried
#: when it has at most this many parameters.
CLOSURE_CORNER_DIMS = 6


def _closures(cs: ConfigurationSpace, bands: dict, model, pair_index: int, u0, tol,
              seen) -> list:
    """Channels that lie between the two branches of one contact (a pin in a
    round slot end, a disc in a concave arc) and that a vector of the box
    closes: there the contact has no solution (its branches met and
    vanished) and its features overlap.  The bands cannot show it: a band is
    made of the vectors that still have the contact, and the edge of the one
    that comes closest stops short of the other branch (a pin 0.01 mm
    narrower than the slot's end needs read as two bands 0.039 apart each
    from a gap of 0.080).  Tried: the bands' extreme vectors at the cell's
    samples and over the curves, each pushed on to the box's edge along its
    move from the nominal, and the corners of the contact's dependency set
    (when it has at most :data:`CLOSURE_CORNER_DIMS` parameters).  Returns
    :class:`ZoneOverlap` entries of kind ``"closure"`` for the curve pairs
    not in ``seen`` (already overlapping): the range where any of them closes
    the channel, and the one that closes it at the most samples (the first
    such) as the seed."""
    index = {nm: i for i, nm in enumerate(model.names)}
    found: dict = {}
    built: dict = {}        # a vector tried for several cells is built once

    def pair_at(u):
        key = u.tobytes()
        if key not in built:
            built[key] = _built_pair(model, pair_index, u)
        return built[key]
    for k, row in enumerate(cs.cells):
        a, b = cs.events[k], cs.events[k + 1]
        for cell in row:
            il, iu = cell.lower, cell.upper
            if not cell.free or il < 0 or iu < 0 or il == iu or (il, iu) in seen:
                continue
            cl, cu = cs.curves[il], cs.curves[iu]
            if (cl.features != cu.features or cl.kernel.eq != cu.kernel.eq
                    or cl.kernel.owner != cu.kernel.owner or cl.bi == cu.bi):
                continue
            bl, bu = bands.get(il), bands.get(iu)
            if bl is None or bu is None:
                continue
            xs = np.unique(np.concatenate([bl.q1[(bl.q1 >= a) & (bl.q1 <= b)],
                                           np.linspace(a, b, 9)]))
            fl, fu = cl.evaluate(xs), cu.evaluate(xs)
            mid, gap = 0.5 * (fl + fu), fu - fl
            if cs.periodic[1]:
                gap = gap % TWO_PI
            # every candidate: the range any closes, and the vector that
            # closes the most samples (the first of those) as the seed
            union = np.zeros(len(xs), dtype=bool)
            best, worst = None, 0
            for u in _closing_candidates(bl, bu, a, b, u0, tol, index):
                closed = _closed_at(cl, pair_at(u), xs, mid)
                if closed is None:
                    continue
                union |= closed
                if int(closed.sum()) > worst:
                    best, worst = (u, closed), int(closed.sum())
            if best is None:
                continue
            u, closed = best
            hit = np.nonzero(closed)[0]
            j = int(hit[len(hit) // 2])
            lo, hi = _bracket(xs, union)
            rec = found.get((il, iu))
            if rec is None:
                found[il, iu] = [lo, hi, float(xs[j]), float(mid[j]), float(gap[j]), u]
            else:
                rec[0], rec[1] = min(rec[0], lo), max(rec[1], hi)
    out = []
    for (il, iu), (lo, hi, x, y, g, u) in found.items():
        bl, bu = bands[il], bands[iu]
        if cs.periodic[1]:
            y = (y - cs.window[2]) % TWO_PI + cs.window[2]
        out.append(ZoneOverlap((lo, hi), (x, y), g, g, bl.label, bu.label, il, iu, u.copy(),
                               u.copy(), tuple(sorted(set(bl.depends) | set(bu.depends))),
                               "closure"))
    return out


def _closing_candidates(bl: ZoneBand, bu: ZoneBand, a: float, b: float, u0, tol, index):
    """The vectors :func:`_closures` tries for the channel between ``bl`` and
    ``bu`` over [a, b] (both bands' extreme vectors, over the curves and at
    the samples there, either way along the normal), in a fixed order, each
    once."""
    base = []
    for band in (bl, bu):
        base += [band.u_upper, band.u_lower]
        for j in np.nonzero((band.q1 >= a) & (band.q1 <= b))[0]:
            if band.u_upper_at is not None:
                base += [band.u_upper_at[j], band.u_lower_at[j]]
    out, seen = [], set()

    def add(u):
        key = np.asarray(u, dtype=float).tobytes()
        if key not in seen:
            seen.add(key)
            out.append(np.asarray(u, dtype=float))
    for u in base:
        d = np.asarray(u, dtype=float) - u0
        move = (np.abs(d) > 0) & (tol > 0)
        if not move.any():
            continue
        add(u)
        s = float(np.min(tol[move] / np.abs(d[move])))
        add(np.clip(u0 + s * d, u0 - tol, u0 + tol))
    dep = [index[n] for n in sorted(set(bl.depends) | set(bu.depends)) if n in index
           and tol[index[n]] > 0]
    if 0 < len(dep) <= CLOSURE_CORNER_DIMS:
        for signs in itertools.product((-1.0, 1.0), repeat=len(dep)):
            u = u0.copy()
            u[dep] += np.array(signs) * tol[dep]
            add(u)
    return out


def _closed_at(c: ContactCurve, pair, xs, mid):
    """Where (bool over ``xs``) the contact of ``c`` has no solution on the
    variant ``pair`` while its parts overlap at the nominal channel's
    mid-line ``mid``; None where nowhere (or ``pair`` is None: the vector
    does not build)."""
    from .overlap import parts_overlap
    k = _varied_kernel(c, pair) if pair is not None else None
    if k is None:
        return None
    _, ex = k.solve(xs)
    gone = np.asarray(ex) < 0
    if not gone.any():
        return None
    q = np.column_stack([xs[gone], mid[gone]])
    closed = np.zeros(len(xs), dtype=bool)
    closed[np.nonzero(gone)[0][parts_overlap(pair, q)]] = True
    return closed if closed.any() else None


def _vector_at(band: ZoneBand, side: int, x: float, cs, periodic2):
    """The vector that moves ``band``'s curve furthest towards ``side`` (+1 up,
    -1 down) at driver value ``x``: of the two band samples whose edge points
    bracket ``x``, the one whose edge lies further that way from the nominal
    curve (its ``u_upper_at`` / ``u_lower_at``).  The curve's extreme over its
    whole range (``u_upper`` / ``u_lower``) may move it the other way at x (a
    Scotch yoke's crank radius lifts ``a cos q1`` at q1 = 0 and lowers it at
    q1 = pi)."""
    whole = band.u_upper if side > 0 else band.u_lower
    vecs = band.u_upper_at if side > 0 else band.u_lower_at
    ok, ex, ey = _edge_points(band, side, cs)
    if vecs is None or not len(ok):
        return whole
    with np.errstate(invalid="ignore"):
        off = ey - cs.curves[band.curve].raw(ex)
    if periodic2:
        off = wrap_pi(off)
    cand = []
    below, above = np.flatnonzero(ex <= x), np.flatnonzero(ex >= x)
    if len(below):
        cand.append(below[np.argmax(ex[below])])
    if len(above):
        cand.append(above[np.argmin(ex[above])])
    score = [side * off[j] if np.isfinite(off[j]) else -np.inf for j in cand]
    return np.array(vecs[ok[cand[int(np.argmax(score))]]], dtype=float)


def _edge_points(band: ZoneBand, side: int, cs):
    """The band's own samples on its edge ``side`` (+1 upper, -1 lower): the
    samples where the band is finite, and the edge's points there (driver
    value, q2): the nominal curve moved along its normal by the band."""
    tau = band.upper if side > 0 else band.lower
    ok = np.flatnonzero(np.isfinite(tau))
    s2 = 1.0 / follower_scale(cs.pair)
    return (ok, band.q1[ok] + tau[ok] * band.normal[ok, 0],
            band.q2[ok] + tau[ok] * band.normal[ok, 1] / s2)


#: Points per sample interval at which :func:`_band_edge` traces a band edge
#: (the nominal curve moved along its normal by the band, both taken between
#: the band's samples).
_EDGE_SUBDIVISIONS = 8


def _band_edge(band: ZoneBand, side: int, cs, periodic2):
    """The band edge ``side`` (+1 upper, -1 lower) as ``(ex, off, reach)``: driver
    values ``ex`` (ascending) of points on the edge, the edge's q2 offset ``off``
    there from the exact nominal curve at the same driver value, and the
    largest driver spacing of the band's own edge samples; None where the band
    has fewer than two samples.

    The edge is the nominal curve moved along its normal by the band, which
    stays well conditioned where the curve is steep.  Between the band's
    samples it is traced at ``_EDGE_SUBDIVISIONS`` points per interval: the
    exact nominal curve and its normal there, moved by the band interpolated
    along the curve.  The offsets are measured at each point against the exact
    curve at that point's own driver value (``ey - raw(ex)``), never between
    points: the band's samples are sparse (24 at ``fast``), and a chord
    between two edge points measured against the exact curve counts the
    curve's own curvature between them (the chord sag, ``a (1 - cos(dq1 /
    2))`` on a Scotch yoke's ``q2 = a cos q1``) as offset, which reported
    channels that cannot close.  On a straight curve the edge points lie on the
    chords, and the offsets are those of the chords."""
    ok, ex0, ey0 = _edge_points(band, side, cs)
    if len(ok) < 2:
        return None
    curve = cs.curves[band.curve]
    s2 = 1.0 / follower_scale(cs.pair)
    t, tk = band.q1[ok], (band.upper if side > 0 else band.lower)[ok]
    reach = float(np.max(np.diff(np.sort(ex0))))
    # the points between consecutive samples: nominal curve, normal and band there
    f = np.arange(1, _EDGE_SUBDIVISIONS)[None, :] / _EDGE_SUBDIVISIONS
    ts = (t[:-1, None] + f * np.diff(t)[:, None]).ravel()
    taus = (tk[:-1, None] + f * np.diff(tk)[:, None]).ravel()
    with np.errstate(invalid="ignore", divide="ignore"):
        ns = _curve_normals(curve, ts, s2)
        exs = ts + taus * ns[:, 0]
        eys = curve.raw(ts) + taus * ns[:, 1] / s2
        ex = np.concatenate([ex0, exs])
        ey = np.concatenate([ey0, eys])
        off = ey - curve.raw(ex)
    if periodic2:
        off = wrap_pi(off)
    # an edge point moved along q1 past where the nominal curve has a solution
    # (next to a tangency end) has no offset of its own
    fin = np.isfinite(ex) & np.isfinite(off)
    if fin.sum() < 2:
        return None
    ex, off = ex[fin], off[fin]
    order = np.argsort(ex, kind="stable")
    return ex[order], off[order], reach


def _edge_offset(band: ZoneBand, xs, side: int, cs, periodic2, edge=None):
    """q2 offset, at driver values xs, of the band edge ``side`` (+1 upper, -1 lower)
    from the nominal curve (:func:`_band_edge`, or ``edge`` when given: its
    result for this band and side), interpolated between the edge's points;
    NaN outside the edge."""
    if edge is None:
        edge = _band_edge(band, side, cs, periodic2)
    out = np.full(len(xs), np.nan)
    if edge is None:
        return out
    ex, off, reach = edge
    inside = (xs >= ex[0]) & (xs <= ex[-1])
    if inside.any():
        out[inside] = np.interp(xs[inside], ex, off)
    # past the first or last edge sample, by less than the samples' spacing
    # (the band's samples start a hair inside the curve, and the normal moves
    # the edge along q1), the offset of the nearest edge sample: an overlap
    # that reaches the end of the drive is reported to it
    for near, end in ((xs < ex[0]) & (xs >= ex[0] - reach), 0), \
                     ((xs > ex[-1]) & (xs <= ex[-1] + reach), -1):
        if near.any():
            out[near] = off[end]
    return out
