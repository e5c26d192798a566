"""Statistical yield: how many parts per million fail, and which dimensions
drive the failures.

The worst-case question ("can some part inside the box fail?") is answered by
the synthesis and by :func:`synthesis.verify.monte_carlo`.  This module answers
the statistical one: with every dimension spread by its
:class:`mechanisms.models.Distribution`, what fraction of the parts made is
defective?  The defect test is the same batched test
(:func:`synthesis.executors.run_batched`), against the same design intent.

Standard space
--------------
Every parameter with a spread is mapped from a standard normal coordinate z
through its own marginal (the Rosenblatt transform of independent marginals):
``x = nominal + sigma z`` for a normal, the quantile of the truncated normal at
``Phi(z)`` for a truncated one, ``nominal + tol erf(z / sqrt 2)`` for a uniform.
Parameters without spread (tol 0 with no stated sigma, or sigma 0) stay at
their nominal and have no coordinate; a normal with a stated sigma spreads
whatever its tolerance.  With no spread at all, one test of the nominal gives
P = 0 or 1 exactly (``ci_method`` ``exact``).  The defect test's search margin
(C-space metric, > 0 healthy) is a function ``g(z)``; a part fails where
``g <= 0``.

Stages
------
``mc``
    Plain Monte Carlo: ``n`` parts drawn from the distributions, the fraction
    defective, and its exact (Clopper-Pearson) 95 % interval.
``is``
    1. *Probe*: the nominal and the corners of the supports (each coordinate
       0.1 % of its half-width inside its support, at the box's edge for an
       untruncated normal); the defective ones
       (or the caller's defective ``starts``) point towards the failure
       region.  When none is defective, an untruncated normal's coordinate
       (whose spread reaches beyond the box) is probed again at
       :data:`PROBE_FAR` standard units.
    2. *Ray search*: along the ray from the nominal to each defective start,
       the first defective point, by a grid and then regula falsi on the margin
       (bisection where the margin is unknown).
    3. *HL-RF*: from each boundary point, Hasofer-Lind-Rackwitz-Fiessler steps
       with forward-difference gradients of the margin (all points batched),
       to the most probable failure point, the FORM *design point*, at
       distance beta from the origin.  FORM estimates ``Phi(-beta)``.  A
       second round starts along both signs of every contributing
       parameter and the corner rays of the contributing parameters, so
       that every failure region is found (see :func:`design_points`).
    4. *Importance sampling*: ``n`` parts drawn from a mixture of unit normals
       centred at the design points, with a defensive share of the nominal
       density so that no weight exceeds ``1 / DEFENSIVE``; the weighted mean
       of the defect indicator and its 95 % interval from the weighted
       estimator's variance (with too few failing samples a conservative
       one, see :func:`weighted_interval`); with no failing sample
       ``[0, 3 / (DEFENSIVE n)]``.
       Without a design point (the nominal defective, or no defective start)
       the mixture is the nominal density itself: the ``n`` parts are plain
       Monte Carlo, with its exact interval.

Contributors
------------
At a design point the margin's gradient in standard space is ``a_i =
dg/dx_i sigma_i`` for a normal; parameter i's share of the margin variance is
``a_i^2 / sum a_j^2`` (the CETOL/3DCS sensitivity share, the squared FORM
importance factor).  The failing samples give an independent cross-check:
per parameter, the mean standard coordinate of failing parts and the fraction
of them beyond two sigma (4.6 % of all parts are).
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field

import numpy as np

from cspace.argcheck import getseed
from cspace.errors import InputError

__all__ = ["YieldResult", "DesignPoint", "StandardSpace", "standard_space", "to_model",
           "to_standard", "yield_estimate", "METHODS"]

METHODS = ("mc", "is")

#: Standard-space distance beyond which the ray search stops: Phi(-8) is 6e-16.
Z_MAX = 8.0
#: Forward-difference step of the margin gradient, in standard units: small
#: against beta, large against the margin's numerical noise (about 1e-12 of
#: the C-space metric).
FD_STEP = 0.02
#: Share of the nominal density in the importance-sampling mixture (defensive
#: importance sampling): it bounds every weight by 1 / DEFENSIVE.
DEFENSIVE = 0.1
#: Box corners are probed this fraction inside the support, where a truncated
#: or uniform marginal still has a finite standard coordinate.
PROBE_INSET = 1e-3
#: Where the box corners are probed again, in standard units, along the
#: coordinates of untruncated normals, when no corner at the box's edge is
#: defective (:func:`probe_starts`): Phi(-5) is 2.9e-7, below the failure
#: rates importance sampling is asked for.
PROBE_FAR = 5.0
#: Most corners probed (all of them when there are fewer).
PROBE_CORNERS = 64
#: Rays searched from the defective starts, and HL-RF searches run per round.
MAX_STARTS = 16
#: Most design points sampled around (the most probable).
MAX_DESIGN_POINTS = 8
#: Design points whose FORM probability is below this fraction of the most
#: probable one's are not sampled around (the defensive share still covers them).
FORM_RATIO = 1e-3
#: Share of the margin variance from which a parameter contributes: the second
#: search round starts along both signs of every contributing direction and
#: along the corner rays of the contributing parameters.
CONTRIBUTING = 0.01
#: Most contributing parameters whose corner rays are all searched (2^k rays);
#: beyond, MAX_STARTS random corner rays.
MAX_CORNER_DIMS = 5
#: A ray hit lies in a known failure region when the linearised margin of one
#: of its design points is below this (standard units) there.
EXPLAINED = 0.1
#: Failing importance samples, and their effective number (Kish), below which
#: the weighted standard error is not trusted (see :func:`weighted_interval`).
IS_MIN_FAILURES = 10
#: Grid points per ray before the refinement, and refinement rounds.
RAY_GRID = 8
RAY_ROUNDS = 8
#: HL-RF iterations, and the standard-space step below which they stop.
HLRF_ITER = 8
HLRF_TOL = 1e-3
#: Design points closer than this (standard units) are one point.
SAME_POINT = 0.1
#: Two-sided 95 % normal quantile.
Z95 = 1.959963984540054


# ----------------------------------------------------------------------- results

@dataclass(frozen=True, eq=False)
class DesignPoint:
    """A most probable failure point (FORM design point).

    Attributes
    ----------
    beta : float
        Distance from the nominal in standard space.
    z : (m,) float
        Standard coordinates (0 for parameters without spread).
    x : (m,) float
        The parameter vector (model units).
    gradient : (m,) float
        Margin gradient in standard space (C-space metric per sigma).
    shares : dict
        Parameter name -> share of the margin variance, ``a_i^2 / sum a_j^2``.
    reasons : tuple of str
        Defect reasons just beyond the point.
    pair : str or None
        The pair that fails there.
    converged : bool
        HL-RF stopped by its step tolerance and the margin there is near 0.
    iterations : int
    """

    beta: float
    z: np.ndarray
    x: np.ndarray
    gradient: np.ndarray
    shares: dict
    reasons: tuple
    pair: str | None
    converged: bool
    iterations: int

    @property
    def p_form(self) -> float:
        """FORM estimate of the failure probability, ``Phi(-beta)``."""
        from scipy.special import ndtr
        return float(ndtr(-self.beta))

    def __repr__(self):
        top = max(self.shares, key=self.shares.get) if self.shares else "-"
        return (f"<DesignPoint beta {self.beta:.3f}, FORM {self.p_form:.3g}, "
                f"{'/'.join(self.reasons) or '?'}, top {top} "
                f"{100 * self.shares.get(top, 0.0):.0f} %>")

    def to_dict(self) -> dict:
        return {"beta": self.beta, "p_form": self.p_form, "ppm_form": 1e6 * self.p_form,
                "z": self.z.tolist(), "x": self.x.tolist(), "gradient": self.gradient.tolist(),
                "shares": dict(self.shares), "reasons": list(self.reasons), "pair": self.pair,
                "converged": self.converged, "iterations": self.iterations}


@dataclass(frozen=True, eq=False)
class YieldResult:
    """Estimated failure probability of parts made with the model's spreads.

    Attributes
    ----------
    method : {"mc", "is"}
    probability : float
        Estimated probability that a part is defective.
    ci : (float, float)
        95 % confidence interval of it.
    ci_method : str
        ``clopper-pearson`` (plain Monte Carlo, also ``is`` without a design
        point), ``weighted-normal`` (importance sampling: mean +/- 1.96
        standard errors, clipped to [0, 1]; with no failing sample
        ``[0, 3 / (DEFENSIVE n)]``), ``weighted-conservative`` (importance
        sampling with fewer than :data:`IS_MIN_FAILURES` failing samples or
        effective ones: ``[0, hi]``, see :func:`weighted_interval`) or
        ``exact`` (no parameter has a spread: P is 0 or 1).  Both ends are
        always finite.
    samples : int
        Parts drawn by the estimator (plain or importance samples).
    failures : int
        Of which defective.
    tests : int
        Defect tests in all: the samples, and the probes and search.
    tests_search : int
        Of which spent finding design points.
    by_reason, by_pair : dict
        Estimated probability of a defect with that reason (a defect may have
        several) and in that pair.
    design_points : tuple of DesignPoint
        Most probable first.
    failing_parts : dict
        Parameter name -> ``{"mean_z", "beyond_2sigma"}`` over the failing
        samples (weighted for importance sampling; alike where every weight
        underflows).
    seed : int or None
        None when a Generator (or no seed) was given.
    fallback : int
        Tests the batched margins could not certify (decided by the full test).
    success : bool
    message : str
    """

    method: str
    probability: float
    ci: tuple
    ci_method: str
    samples: int
    failures: int
    tests: int
    tests_search: int
    by_reason: dict
    by_pair: dict
    design_points: tuple
    failing_parts: dict
    seed: int | None
    fallback: int = 0
    success: bool = True
    message: str = ""
    names: tuple = field(default=(), repr=False)

    @property
    def ppm(self) -> float:
        return 1e6 * self.probability

    @property
    def p_form(self) -> float | None:
        """FORM estimate of the most probable design point, or None."""
        return self.design_points[0].p_form if self.design_points else None

    @property
    def contributors(self) -> dict:
        """Variance shares at the most probable design point (empty without one)."""
        return dict(self.design_points[0].shares) if self.design_points else {}

    def __repr__(self):
        lo, hi = self.ci
        form = (f", FORM {self.p_form:.3g} (beta {self.design_points[0].beta:.3f})"
                if self.design_points else "")
        return (f"<YieldResult {self.method}: P = {self.probability:.3g} ({self.ppm:.4g} ppm), "
                f"95 % CI [{lo:.3g}, {hi:.3g}], {self.failures}/{self.samples} failing "
                f"samples{form}, {self.tests} tests>")

    def to_dict(self) -> dict:
        return {"method": self.method, "probability": self.probability, "ppm": self.ppm,
                "ci": list(self.ci), "ci_ppm": [1e6 * c for c in self.ci],
                "ci_method": self.ci_method, "samples": self.samples,
                "failures": self.failures, "tests": self.tests,
                "tests_search": self.tests_search, "by_reason": dict(self.by_reason),
                "by_pair": dict(self.by_pair), "p_form": self.p_form,
                "contributors": self.contributors,
                "design_points": [p.to_dict() for p in self.design_points],
                "failing_parts": self.failing_parts, "seed": self.seed,
                "full_test_fallbacks": self.fallback, "success": self.success,
                "message": self.message, "names": list(self.names)}


# ----------------------------------------------------------------------- standard space

@dataclass(frozen=True, eq=False)
class StandardSpace:
    """The marginals of a model's parameters (see the module docstring).

    Attributes
    ----------
    names : tuple of str
    nominal, tol, sigma, half : (m,) float
        Nominal, tolerance, sigma of the underlying normal and the support's
        half-width (inf for a normal), model units.
    kinds : tuple of str
    active : (m,) bool
        Parameters with a spread (a standard coordinate).
    """

    names: tuple
    nominal: np.ndarray
    tol: np.ndarray
    sigma: np.ndarray
    half: np.ndarray
    kinds: tuple
    active: np.ndarray


def standard_space(model, cp: float | None = None) -> StandardSpace:
    """The standard space of ``model``'s distributions; ``cp`` replaces the
    capability of every parameter that states no distribution."""
    from mechanisms.models.base import Distribution
    dists = [p.spread if (p.distribution is not None or cp is None)
             else Distribution("truncated_normal", cp=cp) for p in model.parameters]
    tol = model.tol
    sigma = np.array([d.std(t) for d, t in zip(dists, tol)])
    half = np.array([d.half_width(t) for d, t in zip(dists, tol)])
    kinds = tuple(d.kind for d in dists)
    active = np.array([s > 0 and h > 0 for s, h in zip(sigma, half)])
    return StandardSpace(tuple(model.names), model.nominal, tol, sigma, half, kinds, active)


def to_model(space: StandardSpace, Z) -> np.ndarray:
    """Parameter vectors (n, m) of standard coordinates ``Z`` (n, m); inactive
    columns are ignored."""
    from scipy.special import erf
    Z = np.atleast_2d(np.asarray(Z, dtype=float))
    X = np.tile(space.nominal, (len(Z), 1))
    for i in np.flatnonzero(space.active):
        z, s = Z[:, i], space.sigma[i]
        if space.kinds[i] == "normal":
            X[:, i] += s * z
        elif space.kinds[i] == "uniform":
            X[:, i] += space.tol[i] * erf(z / math.sqrt(2.0))
        else:
            X[:, i] += s * _truncated_quantile(z, space.half[i] / s)
    return X


def to_standard(space: StandardSpace, X) -> np.ndarray:
    """Standard coordinates (n, m) of parameter vectors ``X`` inside the
    supports (0 in inactive columns)."""
    from scipy.special import erfinv
    X = np.atleast_2d(np.asarray(X, dtype=float))
    Z = np.zeros_like(X)
    for i in np.flatnonzero(space.active):
        t, s = X[:, i] - space.nominal[i], space.sigma[i]
        if space.kinds[i] == "normal":
            Z[:, i] = t / s
        elif space.kinds[i] == "uniform":
            Z[:, i] = math.sqrt(2.0) * erfinv(np.clip(t / space.tol[i], -1.0, 1.0))
        else:
            Z[:, i] = _truncated_coordinate(t / s, space.half[i] / s)
    return Z


def _truncated_quantile(z, b):
    """Standardised value of a normal truncated at +/- b whose cdf is Phi(z),
    from the nearer tail for accuracy."""
    from scipy.special import ndtr
    from scipy.stats import truncnorm
    d = truncnorm(-b, b)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = np.where(z > 0, d.isf(ndtr(-np.abs(z))), d.ppf(ndtr(-np.abs(z))))
    # scipy's quantile loses the tail beyond some 5 standard units (it works
    # from 1 - p: at b = 10 every z above 8.2 gave 8.198)
    far = (np.abs(z) > 5.0) & np.isfinite(z)
    if np.any(far):
        t = np.where(far, np.sign(z) * _tail_value(np.abs(z), b), t)
    return t


def _truncated_coordinate(t, b):
    from scipy.special import ndtri
    from scipy.stats import truncnorm
    d = truncnorm(-b, b)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        z = np.where(t > 0, -ndtri(d.sf(t)), ndtri(d.cdf(t)))
    far = ~np.isfinite(z) & (np.abs(t) < b)
    if np.any(far):
        z = np.where(far, np.sign(t) * _tail_coordinate(np.abs(t), b), z)
    return z


# A normal truncated at +/- b with b beyond some 37 (a tolerance of 39 sigma,
# a capability of 13) has tail probabilities below the smallest double:
# scipy's functions gave an infinite coordinate inside the support (and the
# probe's corners, design points and weights turned to inf and NaN), and its
# quantile is off beyond some 5 standard units.  There the tails are computed
# from logarithms: the upper tail of the truncated law beyond t is
# (Q(t) - Q(b)) / (1 - 2 Q(b)), Q(x) = Phi(-x).

def _tail_coordinate(t, b):
    """The standard coordinate z >= 0 of a value 0 <= t < b of the normal
    truncated at +/- b, from logarithms of the tails."""
    from scipy.special import log_ndtr, ndtri_exp
    lq_t, lq_b = log_ndtr(-t), log_ndtr(-b)
    with np.errstate(divide="ignore"):
        log_sf = (lq_t + np.log1p(-np.exp(lq_b - lq_t))
                  - np.log1p(-2.0 * np.exp(lq_b)))
    return -ndtri_exp(log_sf)


def _tail_value(z, b):
    """The value 0 <= t <= b of the normal truncated at +/- b whose upper tail
    is Phi(-z), z >= 0, from logarithms of the tails (inverse of
    :func:`_tail_coordinate`)."""
    from scipy.special import log_ndtr, ndtri_exp
    lq_b = log_ndtr(-b)
    log_q_t = np.logaddexp(lq_b, log_ndtr(-z) + np.log1p(-2.0 * np.exp(lq_b)))
    return np.minimum(-ndtri_exp(log_q_t), b)


# ----------------------------------------------------------------------- defect tests

class _Tests:
    """The defect test of standard-space points, counting what it runs."""

    def __init__(self, executor, intent, space, accuracy, d, memo=None):
        from .executors import BatchStats
        self.executor, self.intent, self.space = executor, intent, space
        self.accuracy, self.d = accuracy, d
        self.memo = memo
        self.stats = BatchStats()
        self.count = 0
        self.pairs = [p.name for p in intent.pairs()]

    def __call__(self, Z):
        """(results, margins (n,)) at standard points ``Z`` (n, m)."""
        from .executors import run_batched
        X = to_model(self.space, Z)
        marg: list = []
        res = run_batched(self.executor, self.intent, X, self.accuracy, self.d,
                          stats=self.stats, margins=marg, memo=self.memo)
        self.count += len(X)
        return res, np.asarray(marg, dtype=float)

    def pair_name(self, r):
        return self.pairs[r.where[0]] if r.where else None


# ----------------------------------------------------------------------- design points

def probe_starts(tests: _Tests, rng) -> tuple:
    """Stage 1: (nominal result, defective corners (k, m) in standard space).

    The corners lie at the edge of the supports (each coordinate
    :data:`PROBE_INSET` of its support's half-width inside it: at ``+/- tol``
    for a uniform spread, at ``+/- limit * tol`` for a truncated normal, at the
    box's edge for an untruncated normal).  When none of them is
    defective and some spread is an untruncated normal (its support reaches
    beyond the box: a stated sigma of half the tolerance puts the box's edge
    at 2 sigma), the corners are probed again with those coordinates at
    :data:`PROBE_FAR` standard units, where a failure region of the
    probabilities importance sampling is for still lies."""
    sp = tests.space
    act = np.flatnonzero(sp.active)
    # the support's edge (a truncated normal's may lie beyond the tolerance:
    # its `limit`), the box's for an untruncated normal
    edge = np.where(np.isfinite(sp.half), sp.half, sp.tol)
    zc = to_standard(sp, (sp.nominal + edge * (1 - PROBE_INSET))[None, :])[0]
    zc = np.where(np.isfinite(sp.half) | (sp.tol > 0), zc, 3.0)
    if 2 ** len(act) <= PROBE_CORNERS:
        signs = np.array(np.meshgrid(*[[-1.0, 1.0]] * len(act))).reshape(len(act), -1).T
    else:
        signs = rng.choice([-1.0, 1.0], size=(PROBE_CORNERS, len(act)))
    Z = np.zeros((len(signs) + 1, len(sp.names)))
    Z[1:, act] = signs * zc[act]
    res, _ = tests(Z)
    bad = np.array([r.defective for r in res[1:]], dtype=bool)
    far = np.where(~np.isfinite(sp.half), np.maximum(zc, PROBE_FAR), zc)
    if bad.any() or np.array_equal(far[act], zc[act]):
        return res[0], Z[1:][bad]
    Zf = np.zeros((len(signs), len(sp.names)))
    Zf[:, act] = signs * far[act]
    resf, _ = tests(Zf)
    badf = np.array([r.defective for r in resf], dtype=bool)
    return res[0], Zf[badf]


def ray_search(tests: _Tests, starts, known_bad: bool = True) -> list:
    """Stage 2: per ray from the nominal to a start, (z just on the failing
    side of the first boundary crossing, result there), or None where no
    defective point was found.  ``known_bad``: the starts themselves are
    defective (a ray failing only there ends at its start)."""
    starts = np.asarray(starts, dtype=float)
    k = len(starts)
    ts = np.arange(1, RAY_GRID + (0 if known_bad else 1)) / RAY_GRID
    res, mg = tests((ts[None, :, None] * starts[:, None, :]).reshape(-1, starts.shape[1]))
    lo, hi = np.zeros(k), np.ones(k)
    glo, ghi = np.full(k, np.nan), np.full(k, np.nan)
    hres = [None] * k
    for j in range(k):
        for i, t in enumerate(ts):
            r, g = res[j * len(ts) + i], mg[j * len(ts) + i]
            if r.defective:
                hi[j], ghi[j], hres[j] = t, g, r
                break
            lo[j], glo[j] = t, g
    found = np.array([known_bad or r is not None for r in hres], dtype=bool)
    for _ in range(RAY_ROUNDS):
        if not found.any():
            break
        t = _regula_falsi(lo, hi, glo, ghi)
        idx = np.flatnonzero(found)
        res, mg = tests(t[idx, None] * starts[idx])
        for j, r, g in zip(idx, res, mg):
            if r.defective:
                hi[j], ghi[j], hres[j] = t[j], g, r
            else:
                lo[j], glo[j] = t[j], g
    return [(hi[j] * starts[j], hres[j]) if found[j] else None for j in range(k)]


def _regula_falsi(lo, hi, glo, ghi):
    """Next trial per ray: the margin's linear zero where both ends have a
    consistent margin and it falls in the bracket's middle 80 %, else the
    midpoint."""
    mid = 0.5 * (lo + hi)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = lo + (hi - lo) * glo / (glo - ghi)
    ok = (glo > 0) & (ghi <= 0) & np.isfinite(t)
    inner = (t > lo + 0.1 * (hi - lo)) & (t < hi - 0.1 * (hi - lo))
    return np.where(ok & inner, t, mid)


def hlrf(tests: _Tests, points) -> list:
    """Stage 3: HL-RF from each boundary point (all points batched).  Each
    step is projected back onto the boundary along its ray from the nominal,
    and halved while it does not bring the point nearer the nominal: a plain
    HL-RF step oscillates where the margin curves, as it does where a
    truncated marginal saturates.  Returns per point (z, gradient at z,
    converged, iterations)."""
    act = np.flatnonzero(tests.space.active)
    m = len(tests.space.names)
    z = np.array(points, dtype=float)
    grad = np.full_like(z, np.nan)
    lam = np.ones(len(z))
    state = np.zeros(len(z), dtype=int)       # 0 running, 1 converged, -1 stopped
    its = np.zeros(len(z), dtype=int)
    for _ in range(HLRF_ITER):
        todo = np.flatnonzero(state == 0)
        if not len(todo):
            break
        g, a = _margin_gradient(tests, z[todo], act, m)
        its[todo] += 1
        cand = {}
        for j, gj, aj in zip(todo, g, a):
            if not (np.isfinite(gj) and np.all(np.isfinite(aj))) or not aj @ aj > 0:
                state[j] = -1
                continue
            grad[j] = aj
            new = (aj @ z[j] - gj) / (aj @ aj) * aj
            if np.linalg.norm(new - z[j]) < HLRF_TOL * max(1.0, np.linalg.norm(z[j])):
                state[j] = 1
                continue
            cand[j] = z[j] + lam[j] * (new - z[j])
        _accept(tests, z, lam, state, cand)
    return [(z[j], grad[j], bool(state[j] == 1), int(its[j])) for j in range(len(z))]


def _accept(tests, z, lam, state, cand) -> None:
    """Project the candidate steps onto the boundary; take those that come
    nearer the nominal, halve the others' step."""
    if not cand:
        return
    idx = list(cand)
    C = np.array([cand[j] for j in idx])
    ends = C * (Z_MAX / np.maximum(np.linalg.norm(C, axis=1), 1e-12))[:, None]
    for j, hit in zip(idx, ray_search(tests, ends, known_bad=False)):
        if hit is not None and np.linalg.norm(hit[0]) < np.linalg.norm(z[j]):
            z[j] = hit[0]
        else:
            lam[j] *= 0.5
            if lam[j] < 1.0 / 16:
                state[j] = -1


def _margin_gradient(tests, Z, act, m):
    """Margins at ``Z`` (k, m) and their forward-difference gradients (k, m)."""
    k = len(Z)
    rows = np.repeat(Z, len(act) + 1, axis=0).reshape(k, len(act) + 1, m)
    for c, i in enumerate(act):
        rows[:, c + 1, i] += FD_STEP
    _, mg = tests(rows.reshape(-1, m))
    mg = mg.reshape(k, len(act) + 1)
    a = np.zeros((k, m))
    a[:, act] = (mg[:, 1:] - mg[:, :1]) / FD_STEP
    return mg[:, 0], a


def design_points(tests: _Tests, starts) -> tuple:
    """Stages 2 and 3: (distinct design points, most probable first; notes).

    Round 1 searches from up to :data:`MAX_STARTS` defective ``starts``
    (spread out in direction).  Round 2 starts along both signs of every
    contributing direction (share above :data:`CONTRIBUTING` at a design
    point) and along the corner rays of the contributing parameters, and runs
    HL-RF from each ray hit that no design point found so far explains (its
    linearised margin there is above :data:`EXPLAINED`): a failure region that
    round 1 missed (the defective corners need not reach every region) is
    found there.  Converged points that coincide in standard space are one
    point; the parameters without influence do not tell points apart, since
    HL-RF sets their coordinates to 0.  ``notes`` says where regions may have
    been missed."""
    starts = np.asarray(starts, dtype=float)
    notes: list = []
    hits = [f for f in ray_search(tests, _spread_out(starts, MAX_STARTS)) if f is not None]
    pts = _hlrf_points(tests, hits)
    if not pts:
        return (), notes
    ends, partial = _subspace_rays(tests.space, pts, len(hits))
    if partial:
        notes.append(partial)
    if len(ends):
        more = [f for f in ray_search(tests, ends, known_bad=False) if f is not None]
        new = [f for f in more if not _explained(f[0], pts)]
        if len(new) > MAX_STARTS:
            notes.append(f"{len(new) - MAX_STARTS} of {len(new)} unexplained ray hits of "
                         "the second search round were not searched from")
        found = _hlrf_points(tests, _distinct(new, key=lambda f: f[0])[:MAX_STARTS])
        still = [p for p in found if not p.converged]
        if still:
            notes.append(f"{len(still)} search(es) from the second round did not converge: "
                         "a failure region may be sampled around an approximate point")
        pts = _distinct(list(pts) + found, key=lambda p: p.z)
    return tuple(sorted(pts, key=lambda p: p.beta)), notes


def _hlrf_points(tests, found) -> list:
    """HL-RF from the ray hits ``found`` [(z, result)]; distinct design points."""
    if not found:
        return []
    out = []
    for (z0, r), (z, a, conv, it) in zip(found, hlrf(tests, [f[0] for f in found])):
        if not np.all(np.isfinite(a)):
            z = z0
        out.append(_design_point(tests, z, a, r, conv, it))
    return _distinct(out, key=lambda p: p.z)


def _spread_out(starts, k):
    """Up to ``k`` of ``starts`` (rows), nearest first, then each the one whose
    direction is farthest from those chosen."""
    if len(starts) <= k:
        return starts
    u = starts / np.maximum(np.linalg.norm(starts, axis=1), 1e-12)[:, None]
    chosen = [int(np.argmin(np.linalg.norm(starts, axis=1)))]
    cos = u @ u[chosen[0]]
    for _ in range(k - 1):
        nxt = int(np.argmin(cos))
        chosen.append(nxt)
        cos = np.maximum(cos, u @ u[nxt])
    return starts[chosen]


def _subspace_rays(space, pts, hits) -> tuple:
    """(ray ends (k, m) at distance Z_MAX, note): both signs of every
    contributing coordinate and the corner rays of the contributing ones."""
    m = len(space.names)
    share = np.max([[p.shares[n] for n in space.names] for p in pts], axis=0)
    con = np.flatnonzero((share > CONTRIBUTING) & space.active)
    if not len(con):
        return np.zeros((0, m)), ""
    rays = []
    for i in con:
        for sgn in (-1.0, 1.0):
            e = np.zeros(m)
            e[i] = sgn
            rays.append(e)
    note = ""
    if len(con) > 1:
        if len(con) <= MAX_CORNER_DIMS:
            signs = np.array(np.meshgrid(*[[-1.0, 1.0]] * len(con))).reshape(len(con), -1).T
        else:
            signs = np.random.default_rng(len(con)).choice([-1.0, 1.0],
                                                           size=(MAX_STARTS, len(con)))
            note = (f"{len(con)} contributing parameters: {MAX_STARTS} of their "
                    f"{2 ** len(con)} corner rays were searched")
        for sg in signs:
            e = np.zeros(m)
            e[con] = sg / math.sqrt(len(con))
            rays.append(e)
    return Z_MAX * np.array(rays), note


def _explained(z, pts) -> bool:
    """Whether ``z`` lies in the linearised failure region of one of ``pts``."""
    for p in pts:
        a = p.gradient
        na = float(np.linalg.norm(a))
        if na > 0 and float(a @ (z - p.z)) / na <= EXPLAINED:
            return True
    return False


def _distinct(items, key) -> list:
    items = sorted(items, key=lambda it: np.linalg.norm(key(it)))
    kept: list = []
    for it in items:
        if all(np.linalg.norm(key(it) - key(k)) > SAME_POINT * max(1.0, np.linalg.norm(key(k)))
               for k in kept):
            kept.append(it)
    return kept


def _design_point(tests, z, a, r, converged, iterations) -> DesignPoint:
    sp = tests.space
    a = np.where(np.isfinite(a), a, 0.0)
    tot = float(a @ a)
    shares = {n: (float(a[i] ** 2 / tot) if tot > 0 else 0.0) for i, n in enumerate(sp.names)}
    reasons = tuple(x.name for x in r.reasons) if r is not None else ()
    return DesignPoint(float(np.linalg.norm(z)), z, to_model(sp, z)[0], a, shares, reasons,
                       tests.pair_name(r) if r is not None else None, converged, iterations)


# ----------------------------------------------------------------------- estimators

def plain_samples(space, n, rng):
    """Standard points (n, m) of ``n`` parts; inactive columns 0."""
    Z = np.zeros((n, len(space.names)))
    Z[:, space.active] = rng.standard_normal((n, int(space.active.sum())))
    return Z


def importance_samples(space, centres, n, rng):
    """(Z (n, m), weights (n,)): ``n`` points of the defensive mixture around
    ``centres`` (k, m) and their likelihood ratios to the standard normal."""
    act = space.active
    C = np.asarray(centres, dtype=float)[:, act]
    comp = rng.choice(len(C) + 1, size=n, p=[DEFENSIVE] + [(1 - DEFENSIVE) / len(C)] * len(C))
    Za = rng.standard_normal((n, int(act.sum())))
    Za[comp > 0] += C[comp[comp > 0] - 1]
    Z = np.zeros((n, len(space.names)))
    Z[:, act] = Za
    return Z, _weights(Za, C)


def _weights(Za, C):
    from scipy.special import logsumexp
    lp0 = -0.5 * np.sum(Za ** 2, axis=1)
    lq = np.column_stack([np.log(DEFENSIVE) + lp0]
                         + [math.log((1 - DEFENSIVE) / len(C)) - 0.5 * np.sum((Za - c) ** 2, axis=1)
                            for c in C])
    return np.exp(lp0 - logsumexp(lq, axis=1))


def clopper_pearson(k: int, n: int) -> tuple:
    """Exact two-sided 95 % interval of a binomial proportion k / n."""
    from scipy.stats import beta
    lo = 0.0 if k == 0 else float(beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(0.975, k + 1, n - k))
    return lo, hi


def weighted_interval(v) -> tuple:
    """(mean, 95 % interval) of importance-sampling terms ``v`` (n,), all in
    [0, 1 / DEFENSIVE].

    With no failure the upper end is the rule of three over the largest
    possible weight: the mixture density q is at least DEFENSIVE times the
    nominal one, so the failure region's probability under q is at least
    DEFENSIVE P; no failure in n draws from q bounds that by 3 / n (95 %,
    one-sided), hence P <= 3 / (DEFENSIVE n).

    With at least :data:`IS_MIN_FAILURES` failing terms, and at least as many
    effective ones (Kish, ``(sum v)^2 / sum v^2``), the interval is the mean
    +/- 1.96 standard errors.  With fewer, the standard error itself is too
    uncertain to trust (a missing rare large weight is the usual error, and
    it makes the estimate low): the interval is ``[0, hi]``, ``hi`` the larger
    of the mean + t standard errors (Student t, n - 1 degrees of freedom) and
    the exact bound of the failures: k failures in n draws bound the failure
    region's probability under q by the Clopper-Pearson upper end u, hence
    P <= u / DEFENSIVE."""
    from scipy.stats import t as student
    n = len(v)
    p = float(np.mean(v))
    if not np.any(v > 0):
        return 0.0, (0.0, min(1.0, 3.0 / (n * DEFENSIVE)))
    se = float(np.std(v, ddof=1) / math.sqrt(n)) if n > 1 else p
    k = int(np.count_nonzero(v > 0))
    if k >= IS_MIN_FAILURES and _effective(v) >= IS_MIN_FAILURES:
        return min(p, 1.0), (min(1.0, max(0.0, p - Z95 * se)), min(1.0, p + Z95 * se))
    tq = float(student.ppf(0.975, n - 1)) if n > 1 else math.inf
    hi = max(p + tq * se, clopper_pearson(k, n)[1] / DEFENSIVE)
    return min(p, 1.0), (0.0, min(1.0, hi))


def _effective(v) -> float:
    """Kish's effective number of the positive terms of ``v``."""
    s2 = float(np.sum(v ** 2))
    return float(np.sum(v)) ** 2 / s2 if s2 > 0 else 0.0


def breakdown(tests, res, w) -> tuple:
    """(by reason, by pair): the estimated probability of each, ``w`` the
    per-sample weights."""
    n = len(res)
    by_reason: dict = {}
    by_pair: dict = {}
    for r, wi in zip(res, w):
        if not r.defective:
            continue
        for rs in r.reasons:
            by_reason[rs.name] = by_reason.get(rs.name, 0.0) + float(wi) / n
        pn = tests.pair_name(r)
        if pn is not None:
            by_pair[pn] = by_pair.get(pn, 0.0) + float(wi) / n
    # a probability, as the estimate of the whole is (weights up to
    # 1 / DEFENSIVE: a spread so wide that every part fails gave 1.3)
    return ({k: min(v, 1.0) for k, v in by_reason.items()},
            {k: min(v, 1.0) for k, v in by_pair.items()})


def failing_parts(space, Z, bad, w) -> dict:
    """Per parameter with a spread: the weighted mean standard coordinate of
    the failing samples and the weighted fraction of them beyond 2 sigma."""
    if not np.any(bad):
        return {}
    total = np.sum(w[bad])
    # weights that all underflow (failing samples some 38 standard units out,
    # whose densities are below the smallest double): each sample alike
    wb = w[bad] / total if total > 0 else np.full(int(np.sum(bad)), 1.0 / np.sum(bad))
    return {n: {"mean_z": float(wb @ Z[bad, i]),
                "beyond_2sigma": float(wb @ (np.abs(Z[bad, i]) > 2.0))}
            for i, n in enumerate(space.names) if space.active[i]}


# ----------------------------------------------------------------------- entry point

def check_method(method) -> str:
    """A yield estimation method: one of :data:`METHODS`."""
    if method not in METHODS:
        raise InputError(f"method must be one of {list(METHODS)}, got {method!r}",
                         name="method", value=method)
    return method


def check_cp(cp) -> float | None:
    """A process capability: None (the default, 1) or a finite number > 0."""
    if cp is not None and (isinstance(cp, bool) or not isinstance(cp, (int, float, np.number))
                           or not math.isfinite(cp) or cp <= 0):
        raise InputError(f"cp must be a finite number > 0 (a process capability, e.g. 1.33), "
                         f"got {cp!r}", name="cp", value=cp)
    return None if cp is None else float(cp)


def _check(model, intent, method, cp, starts):
    from cspace.model import SYNTHESIS_MEMBERS, check_model
    for nm, m in (("model", model), ("intent", intent)):
        if m is not None:
            check_model(m, nm, SYNTHESIS_MEMBERS)
    if intent is not None and tuple(intent.names) != tuple(model.names):
        raise InputError("intent must be a design of the same model (the same parameters); "
                         f"got parameters {list(intent.names)}, the model has "
                         f"{list(model.names)}", name="intent")
    check_method(method)
    check_cp(cp)
    if starts is not None:
        want = f"starts must be finite parameter vectors of shape (k, {model.n})"
        if isinstance(starts, (str, bytes)):
            raise InputError(f"{want}, got {type(starts).__name__} {starts!r}"[:300],
                             name="starts")
        try:
            s = np.asarray(starts, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{want}, got {starts!r} (not a table of numbers: rows of "
                             f"unequal length, or not numbers)"[:300], name="starts") from None
        if s.ndim != 2 or s.shape[1] != model.n or not np.all(np.isfinite(s)):
            raise InputError(f"{want}, got shape {s.shape}", name="starts")


def check_starts(space: StandardSpace, starts) -> np.ndarray:
    """Standard coordinates (k, m) of the start vectors ``starts`` (model
    units, already of shape (k, m) and finite).

    A start must lie in every parameter's support: within ``+/- half`` of the
    nominal where the support is bounded (truncated normal, uniform), and at
    the nominal for a parameter without spread.  A start on a support's edge
    (a box corner of a truncated or uniform spread) has an infinite standard
    coordinate; it is moved :data:`PROBE_INSET` of the half-width inside, as
    the probed corners are.  Others raise :class:`InputError`."""
    X = np.array(starts, dtype=float)
    t = X - space.nominal
    for i, nm in enumerate(space.names):
        if not space.active[i]:
            off = np.flatnonzero(np.abs(t[:, i]) > 1e-12 * max(1.0, abs(space.nominal[i])))
            if len(off):
                raise InputError(
                    f"starts must keep {nm!r} at its nominal {space.nominal[i]:g}: it has no "
                    f"spread (tolerance and sigma 0); start {off[0]} has "
                    f"{X[off[0], i]:g}", name="starts")
            continue
        h = space.half[i]
        if not math.isfinite(h):
            continue
        out = np.flatnonzero(np.abs(t[:, i]) > h * (1 + 1e-9))
        if len(out):
            raise InputError(
                f"starts must lie inside the support of {nm!r} ({space.kinds[i]}: nominal "
                f"{space.nominal[i]:g} +/- {h:g}); start {out[0]} has {X[out[0], i]:g}",
                name="starts")
        t[:, i] = np.clip(t[:, i], -h * (1 - PROBE_INSET), h * (1 - PROBE_INSET))
    return to_standard(space, space.nominal + t)


def yield_estimate(model, n: int = 2000, *, method: str = "mc", seed=0, accuracy=None,
                   d: float | None = None, executor=None, cp: float | None = None,
                   intent=None, starts=None, search: bool = True, memo=None) -> YieldResult:
    """Estimate the probability that a part made with the model's spreads is
    defective.

    Parameters
    ----------
    model : mechanisms.models.Model
        Its nominal values, tolerances and distributions
        (:class:`mechanisms.models.Distribution`) define the parts.
    n : int
        Samples of the estimator (plain Monte Carlo or importance samples).
    method : {"mc", "is"}
        Plain Monte Carlo, or design points and importance sampling.
    seed : int, numpy.random.Generator or None
    accuracy : Accuracy or preset name
    d : float, optional
        Output-deviation threshold; default the intent's ``deviation`` or the
        library default.
    executor : concurrent.futures.Executor, optional
        Default: a local process pool for this call.
    cp : float, optional
        Process capability of every parameter that states no distribution (its
        default truncated normal gets sigma = tol / (3 cp)); default 1.
    intent : mechanisms.models.Model, optional
        The design every part is compared with (default ``model``), as in
        :func:`synthesis.verify.monte_carlo`.
    starts : (k, m) float, optional
        Defective parameter vectors (model units, inside the supports) to
        search design points from, e.g. a check list's defective vectors;
        default the defective probed box corners.  A vector outside a
        support (or moving a parameter without spread) raises
        :class:`InputError`; one on a support's edge is moved
        :data:`PROBE_INSET` inside; healthy ones are skipped (``message``).
    search : bool
        With ``mc``, also find design points from the failing samples (FORM
        estimate and contributors); none when the nominal is defective.
        ``is`` always searches.
    memo : synthesis.memo.TestMemo, optional
        Defect tests already finished (by the vector's exact bits), which are
        not run again, and into which every finished test goes (the memo may
        save itself as tests finish, :meth:`~synthesis.memo.TestMemo.tick`).
        The samples and the design-point search are determined by ``seed`` (an
        int) and the tests' results, so an estimate stopped and run again
        with its memo is the uninterrupted one (``cspace-tol yield
        --resume``).  Its tests must be against this ``intent``, accuracy and
        ``d``.

    Returns
    -------
    YieldResult
        Not finding a failure is a result, not an exception: with ``is``, no
        design point means plain Monte Carlo of the ``n`` parts (``message``
        says so, ``ci_method`` is ``clopper-pearson``).

    Examples
    --------
    >>> from mechanisms.models import reciprocating_cam
    >>> r = yield_estimate(reciprocating_cam(), 200, method="is")  # doctest: +SKIP
    >>> r.ppm, r.ci, r.contributors                                 # doctest: +SKIP
    """
    from cspace.accuracy import as_accuracy
    from cspace.defects import reference

    from .executors import check_executor, check_sendable, make_executor, remember_reference
    from .verify import check_samples, seed_record
    _check(model, intent, method, cp, starts)
    _check_memo(memo)
    check_samples(n)
    check_executor(executor)
    check_sendable(executor, model, intent)
    rng, seed_rec = getseed(seed), seed_record(seed)
    intent = model if intent is None else intent
    acc = as_accuracy(accuracy)
    ref = reference(intent, acc, d)
    remember_reference(intent, acc, ref.d, ref)
    space = standard_space(model, cp)
    zs = None if starts is None else check_starts(space, starts)
    with contextlib.ExitStack() as stack:
        if executor is None:
            executor = stack.enter_context(make_executor("process"))
        tests = _Tests(executor, intent, space, acc, ref.d, memo)
        run = (_run_fixed if not space.active.any() else
               _run_mc if method == "mc" else _run_is)
        out = run(tests, space, n, rng, zs, search)
    return YieldResult(method=method, seed=seed_rec, tests=tests.count,
                       fallback=int(tests.stats.get("fallback", 0)), names=space.names, **out)


def _check_memo(memo) -> None:
    from .memo import TestMemo
    if memo is not None and not isinstance(memo, TestMemo):
        raise InputError(f"memo must be a synthesis.memo.TestMemo or None, got "
                         f"{type(memo).__name__}", name="memo")


def _estimate(tests, space, Z, w, ci_method):
    """The estimator's fields from samples ``Z`` with weights ``w``."""
    res, _ = tests(Z)
    bad = np.array([r.defective for r in res], dtype=bool)
    extra = {}
    if ci_method == "clopper-pearson":
        p, ci = bad.mean(), clopper_pearson(int(bad.sum()), len(bad))
    else:
        v = np.where(bad, w, 0.0)
        p, ci = weighted_interval(v)
        ess = _effective(v)
        if bad.any() and (bad.sum() < IS_MIN_FAILURES or ess < IS_MIN_FAILURES):
            ci_method, extra = "weighted-conservative", {"_ess": ess}
    by_reason, by_pair = breakdown(tests, res, w)
    return {**extra, "probability": float(p), "ci": tuple(float(c) for c in ci),
            "ci_method": ci_method,
            "samples": len(Z), "failures": int(bad.sum()), "by_reason": by_reason,
            "by_pair": by_pair, "failing_parts": failing_parts(space, Z, bad, w)}, Z[bad]


def _run_mc(tests, space, n, rng, starts, search) -> dict:
    out, Zbad = _estimate(tests, space, plain_samples(space, n, rng), np.ones(n),
                          "clopper-pearson")
    before = tests.count
    pts, notes = (), []
    if search and (len(Zbad) or starts is not None):
        nom, _ = tests(np.zeros((1, len(space.names))))
        if nom[0].defective:
            # every point is "beyond" a defective nominal: no boundary to find
            notes.append("no design point: the nominal itself is defective, so there is no "
                         "failure boundary to search for (no FORM estimate or contributors)")
        else:
            s = Zbad
            if starts is not None:
                s, skipped = _defective_starts(tests, starts)
                notes += skipped
            if len(s):
                pts, more = design_points(tests, s)
                notes += more
    out.update(design_points=pts, tests_search=tests.count - before,
               message="; ".join([f"plain Monte Carlo of {n} parts"] + notes))
    return out


def _defective_starts(tests, starts) -> tuple:
    """(the defective ones of the standard-space ``starts``, notes)."""
    res, _ = tests(starts)
    bad = np.array([r.defective for r in res], dtype=bool)
    notes = []
    if not bad.all():
        notes.append(f"{int((~bad).sum())} of the {len(bad)} given starts are not defective "
                     "and were not searched from (a start must be a defective part)")
    return starts[bad], notes


def _mixture(pts) -> tuple:
    """(design points sampled around, notes): the most probable, at most
    :data:`MAX_DESIGN_POINTS`, none with FORM below :data:`FORM_RATIO` of the
    most probable one's."""
    keep = [p for p in pts if p.p_form >= FORM_RATIO * pts[0].p_form]
    notes = []
    if len(keep) > MAX_DESIGN_POINTS:
        notes.append(f"{len(keep) - MAX_DESIGN_POINTS} further design point(s) of comparable "
                     "probability were not sampled around (only the defensive share covers "
                     "their regions): the estimate is unbiased but its interval may be wide "
                     "or, with few failing samples there, too narrow")
        keep = keep[:MAX_DESIGN_POINTS]
    if len(keep) < len(pts):
        notes.append(f"{len(pts) - len(keep)} design point(s) less probable than "
                     f"{FORM_RATIO:g} of the most probable one (FORM) not sampled around")
    return keep, notes


def _run_is(tests, space, n, rng, starts, search) -> dict:
    nom, probe = probe_starts(tests, rng)
    if nom.defective:
        return _plain_fallback(tests, space, n, rng,
                               "the nominal itself is defective: the failure probability is "
                               "not small, so no importance sampling; plain Monte Carlo of "
                               f"{n} parts instead")
    notes: list = []
    if starts is None:
        s = probe
    else:
        s, notes = _defective_starts(tests, starts)
    pts, more = design_points(tests, s) if len(s) else ((), [])
    notes += more
    if not pts:
        why = ("none of the given starts is defective" if starts is not None
               else "no probed box corner is defective")
        return _plain_fallback(tests, space, n, rng,
                               "; ".join([f"no defective start point ({why}): no failure "
                                          "region was found to sample around; plain Monte "
                                          f"Carlo of {n} parts instead"] + notes))
    searched = tests.count
    centres, more = _mixture(pts)
    notes += more
    Z, w = importance_samples(space, [p.z for p in centres], n, rng)
    out, _ = _estimate(tests, space, Z, w, "weighted-normal")
    if out["ci_method"] != "weighted-normal":
        notes.append(f"{out['failures']} failing sample(s) of {n}, {out.pop('_ess'):.1f} "
                     f"effective (Kish, their weights' spread counted): too few for the "
                     "normal interval, so the conservative one (see ci_method)")
    out.pop("_ess", None)
    conv = sum(p.converged for p in pts)
    stopped = ("" if conv == len(pts) else
               f" ({len(pts) - conv} of them where the search stopped after {HLRF_ITER} "
               "HL-RF steps without settling: failure points, not shown to be the most "
               "probable, so FORM there is rough; the weighted samples stay unbiased)")
    out.update(design_points=pts, tests_search=searched,
               message="; ".join([f"importance sampling around {len(centres)} of "
                                  f"{len(pts)} design point(s){stopped}"] + notes))
    return out


def _run_fixed(tests, space, n, rng, starts, search) -> dict:
    """No parameter has a spread: every part is the nominal, so one test
    decides the probability exactly (0 or 1)."""
    res, _ = tests(np.zeros((1, len(space.names))))
    p = 1.0 if res[0].defective else 0.0
    by_reason, by_pair = breakdown(tests, res, np.ones(1))
    return {"probability": p, "ci": (p, p), "ci_method": "exact", "samples": 1,
            "failures": int(p), "by_reason": by_reason, "by_pair": by_pair,
            "failing_parts": {}, "design_points": (), "tests_search": 0,
            "message": "no parameter has a spread (every tolerance and sigma is 0): every "
                       f"part is the nominal, which is {'defective' if p else 'healthy'}, "
                       f"so P = {p:g} exactly (one test instead of {n} samples)"}


def _plain_fallback(tests, space, n, rng, message) -> dict:
    """Importance sampling without a design point: the mixture is then the
    nominal density itself, every weight 1, so the ``n`` samples are plain
    Monte Carlo and their interval the exact binomial one."""
    searched = tests.count
    out, _ = _estimate(tests, space, plain_samples(space, n, rng), np.ones(n),
                       "clopper-pearson")
    out.update(design_points=(), tests_search=searched, message=message)
    return out
