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
failure rate of about 3 / samples at best (the rule of three): for targets of
100 ppm and below use ``method="is"`` (design points and importance sampling)
or many samples.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from cspace.argcheck import getint
from cspace.errors import InputError

__all__ = ["YieldTarget", "as_target", "estimate_design", "ppm_text"]

_PPM = re.compile(r"^\s*([0-9.eE+-]+)\s*ppm\s*$")
_PCT = re.compile(r"^\s*([0-9.eE+-]+)\s*%\s*$")


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
                             f"0.9999, got {t!r}", name="target_yield", value=t)
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
            m = _PPM.match(s)
            if m:
                return cls(1.0 - float(m.group(1)) * 1e-6, **kw)
            m = _PCT.match(s)
            if m:
                return cls(float(m.group(1)) / 100.0, **kw)
            return cls(float(s), **kw)
        except ValueError:
            raise InputError(f"target yield must be a yield such as 0.9999, a percentage such "
                             f"as 99.99% or a failure rate such as 100ppm, got {text!r}",
                             name="target_yield", value=text) from None


def as_target(value) -> YieldTarget | None:
    """None, a :class:`YieldTarget`, a yield (float) or a command-line text."""
    if value is None or isinstance(value, YieldTarget):
        return value
    if isinstance(value, str):
        return YieldTarget.parse(value)
    return YieldTarget(value)


def estimate_design(design, intent, target: YieldTarget, accuracy, d, executor) -> dict:
    """The yield estimate of ``design`` against ``intent`` with ``target``'s
    settings: probability, ppm, 95 % interval, failures, samples, tests, and
    whether the interval's upper bound meets the target (``met``)."""
    from .statistics import yield_estimate
    r = yield_estimate(design, target.samples, method=target.method, seed=target.seed,
                       accuracy=accuracy, d=d, executor=executor, cp=target.cp,
                       intent=intent, search=False)
    lo, hi = (float(c) for c in r.ci)
    return {"method": r.method, "probability": float(r.probability), "ppm": float(r.ppm),
            "ci": [lo, hi], "ci_ppm": [1e6 * lo, 1e6 * hi], "failures": int(r.failures),
            "samples": int(r.samples), "tests": int(r.tests),
            "met": bool(hi <= target.failure), "target_ppm": 1e6 * target.failure}


def ppm_text(x: float) -> str:
    """A failure rate in ppm for a reader: whole ppm from 10 up (20000, not
    2e+04), three significant digits below."""
    x = float(x)
    return f"{x:.0f}" if abs(x) >= 10 else f"{x:.3g}"
