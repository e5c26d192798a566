"""Synthesis to a target yield: stop removing defects once the estimated
failure rate is low enough, instead of once no worst-case corner fails.

Worst-case synthesis removes every defective vector of the check list: box
corners that a capable process almost never makes.  With a target yield
(``synthesize(..., target_yield=0.9999)``, ``cspace-tol synthesize
--target-yield 0.9999`` or ``--target-yield 100ppm``), every iteration also
estimates the probability that a part made with the model's spreads is
defective (:func:`synthesis.statistics.yield_estimate`, against the initial
design, as every defect test of the run).  When the upper bound of its 95 %
interval is at or below the target failure rate, the run stops with status
``TARGET_YIELD``, keeping the tolerance the remaining (improbable) defects
would have cost.  The report states both: the estimated yield and the
worst-case status (the defective check-list vectors left).

The estimate's method, sample count, process capability and seed are a
:class:`YieldTarget`; the same seed is used every iteration, so a resumed run
repeats the same estimates.  Plain Monte Carlo (the default) can confirm a
failure rate of about 3.69 / samples at best (no failure in ``n`` samples
gives a 95 % upper bound of ``1 - 0.025 ** (1 / n)``, :func:`mc_floor`): for
targets of 100 ppm and below use ``method="is"`` (design points and
importance sampling) or many samples (:func:`samples_needed`).  The command
line refuses a plain Monte Carlo target that its sample count can never
confirm.

The stopping rule does not rest on one unverified estimate.  The target is
met (``met``) only when the upper end of the 95 % interval is at or below the
target failure rate and, with ``method="is"``, a second importance-sampling
estimate with an independent seed (``seed + 1``, :data:`CHECK_SEED_OFFSET`)
agrees: its upper end is also at or below the target and the two intervals
overlap.  Otherwise the estimate is reported as unconfirmed
(``confirmed`` False, ``unconfirmed`` says why) and the run goes on removing
defects.  A second seed catches the estimator's random error, not a bias both
runs share (e.g. design points that miss a failure region); a plain Monte
Carlo check of the final design (``--verify``) remains the independent test.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from cspace.argcheck import getint
from cspace.errors import InputError

__all__ = ["YieldTarget", "as_target", "estimate_design", "ppm_text", "mc_floor",
           "samples_needed", "CHECK_SEED_OFFSET"]

_PPM = re.compile(r"^\s*([0-9.eE+-]+)\s*ppm\s*$")
_PCT = re.compile(r"^\s*([0-9.eE+-]+)\s*%\s*$")

#: the confirming importance-sampling estimate of a met ``is`` target uses
#: the target's seed plus this
CHECK_SEED_OFFSET = 1

_ALLOWED = ("allowed: a yield Y with 0 < Y < 1 such as 0.9999, a percentage P% with "
            "0 < P < 100 such as 99.99%, or a failure rate Fppm with 0 < F < 1000000 "
            "such as 100ppm")


def mc_floor(samples: int) -> float:
    """The smallest 95 % upper bound plain Monte Carlo can give with
    ``samples`` parts: no failure, Clopper-Pearson ``1 - 0.025 ** (1 / n)``
    (about 3.69 / n)."""
    return -math.expm1(math.log(0.025) / int(samples))


def samples_needed(failure: float) -> int:
    """The fewest plain Monte Carlo samples whose upper bound can reach
    ``failure`` (with no failing part)."""
    return int(math.ceil(math.log(0.025) / math.log1p(-float(failure))))


@dataclass(frozen=True)
class YieldTarget:
    """What a target-yield synthesis aims at, and how it estimates.

    Attributes
    ----------
    target : float
        The yield to reach, in (0, 1): 0.9999 is at most 100 ppm defective.
    samples : int
        Samples of each estimate (plain Monte Carlo or importance samples).
    method : {"mc", "is"}
        :func:`synthesis.statistics.yield_estimate`'s method.
    cp : float or None
        Process capability of every parameter whose model states no
        distribution (default 1: sigma = tol / 3).
    seed : int
        Seed of every estimate.
    """

    target: float
    samples: int = 2000
    method: str = "mc"
    cp: float | None = None
    seed: int = 0

    def __post_init__(self):
        from .statistics import check_cp, check_method
        t = self.target
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not 0.0 < float(t) < 1.0:
            raise InputError(f"target yield must be a number between 0 and 1 (exclusive), e.g. "
                             f"0.9999, got {t!r} ({_ALLOWED})", name="target_yield", value=t)
        object.__setattr__(self, "target", float(t))
        object.__setattr__(self, "samples", getint(self.samples, "samples", minimum=100,
                                                    label="yield samples"))
        check_method(self.method)
        object.__setattr__(self, "cp", check_cp(self.cp))
        object.__setattr__(self, "seed", getint(self.seed, "seed", minimum=0))

    @property
    def failure(self) -> float:
        """The largest failure rate allowed (1 - target)."""
        return 1.0 - self.target

    def to_dict(self) -> dict:
        return {"target": self.target, "ppm": 1e6 * self.failure, "samples": self.samples,
                "method": self.method, "cp": self.cp, "seed": self.seed}

    @classmethod
    def from_dict(cls, d) -> "YieldTarget":
        return cls(d["target"], d.get("samples", 2000), d.get("method", "mc"), d.get("cp"),
                   d.get("seed", 0))

    @classmethod
    def parse(cls, text, **kw) -> "YieldTarget":
        """From a command-line value: a yield (``0.9999``), a percentage
        (``99.99%``) or a failure rate in parts per million (``100ppm``)."""
        s = str(text)
        try:
            m, p = _PPM.match(s), _PCT.match(s)
            y = (1.0 - float(m.group(1)) * 1e-6 if m else
                 float(p.group(1)) / 100.0 if p else float(s))
        except ValueError:
            y = math.nan
        if not 0.0 < y < 1.0:
            raise InputError(f"target yield must be a yield, a percentage or a failure rate, "
                             f"got {text!r} ({_ALLOWED})", name="target_yield", value=text)
        return cls(y, **kw)


def as_target(value) -> YieldTarget | None:
    """None, a :class:`YieldTarget`, a yield (float) or a command-line text."""
    if value is None or isinstance(value, YieldTarget):
        return value
    if isinstance(value, str):
        return YieldTarget.parse(value)
    return YieldTarget(value)


def estimate_design(design, intent, target: YieldTarget, accuracy, d, executor) -> dict:
    """The yield estimate of ``design`` against ``intent`` with ``target``'s
    settings, and whether it meets the target.

    Returns
    -------
    dict
        ``method``, ``probability``, ``ppm``, the 95 % interval (``ci``,
        ``ci_ppm``), ``failures``, ``samples``, ``tests``, ``target_ppm`` and
        ``met``, ``ci_method`` and ``message`` (of the estimate), and ``plain``
        (importance sampling found no failure region to sample around and drew
        plain Monte Carlo samples: its interval is then the exact one, and more
        samples are what narrows it).  ``met``: the interval's upper end is at
        or below the target failure rate and, with ``is``, a second estimate
        with seed ``seed + 1`` (``check``) agrees (its upper end at or below
        the target, the two intervals overlapping).  ``confirmed`` says whether the upper bound is
        confirmed (always True for ``mc``, whose interval is exact); when the
        first upper bound is below the target but the check disagrees,
        ``confirmed`` is False, ``met`` False and ``unconfirmed`` says why.
    """
    from .statistics import yield_estimate

    def one(seed):
        return yield_estimate(design, target.samples, method=target.method, seed=seed,
                              accuracy=accuracy, d=d, executor=executor, cp=target.cp,
                              intent=intent, search=False)

    r = one(target.seed)
    lo, hi = (float(c) for c in r.ci)
    out = {"method": r.method, "probability": float(r.probability), "ppm": float(r.ppm),
           "ci": [lo, hi], "ci_ppm": [1e6 * lo, 1e6 * hi], "failures": int(r.failures),
           "samples": int(r.samples), "tests": int(r.tests),
           "met": bool(hi <= target.failure), "target_ppm": 1e6 * target.failure,
           "confirmed": True, "ci_method": r.ci_method,
           "plain": bool(r.method == "is" and not r.design_points), "message": r.message}
    if out["met"] and target.method == "is":
        c = one(target.seed + CHECK_SEED_OFFSET)
        clo, chi = (float(v) for v in c.ci)
        out["check"] = {"seed": target.seed + CHECK_SEED_OFFSET, "ppm": float(c.ppm),
                        "ci_ppm": [1e6 * clo, 1e6 * chi], "failures": int(c.failures),
                        "tests": int(c.tests)}
        out["tests"] += int(c.tests)
        why = None
        if chi > target.failure:
            why = (f"a second estimate (seed {target.seed + CHECK_SEED_OFFSET}) has an upper "
                   f"bound of {ppm_text(1e6 * chi)} ppm, above the target")
        elif clo > hi or lo > chi:
            why = (f"a second estimate (seed {target.seed + CHECK_SEED_OFFSET}) gives "
                   f"[{ppm_text(1e6 * clo)}, {ppm_text(1e6 * chi)}] ppm, an interval that "
                   f"does not overlap the first")
        if why is not None:
            out.update(met=False, confirmed=False, unconfirmed=why)
    return out


def ppm_text(x: float) -> str:
    """A failure rate in ppm for a reader: whole ppm from 10 up (20000, not
    2e+04), three significant digits below."""
    x = float(x)
    return f"{x:.0f}" if abs(x) >= 10 else f"{x:.3g}"
