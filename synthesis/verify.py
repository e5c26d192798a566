"""Independent verification of a tolerance box by seeded Monte Carlo sampling.

The synthesis loop tests only its check list.  This module samples the box
``nominal +/- tol`` directly and runs the same defect test on every sample, so
that a designer can confirm that the synthesized box is clean (and that the
initial one was not) without trusting the check list.

Samples
-------
``n`` vectors drawn from ``seed`` (an int seeds ``numpy.random.default_rng(seed)``;
a ``numpy.random.Generator`` is used as it is): the first ``corners``
fraction (default one half) are random box corners (each parameter at ``+tol``
or ``-tol`` with equal probability), the rest are uniform in the box.  Corners
come first because a defect of a monotone interference shows first at a
corner; interior samples catch non-monotone ones.  Parameters with zero
tolerance stay at their nominal value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cspace.argcheck import getint, getseed
from cspace.errors import InputError

__all__ = ["MonteCarloResult", "box_samples", "monte_carlo"]


@dataclass(frozen=True, eq=False)
class MonteCarloResult:
    """Outcome of a Monte Carlo check of one box.

    Attributes
    ----------
    n : int
        Samples tested.
    n_corners : int
        Of which box corners.
    defective : tuple of int
        Indices of the defective samples.
    reasons : dict
        Defective samples per defect reason.
    samples : (n, m) float
        The vectors (model units).
    seed : int or None
        None when a Generator (or no seed) was given.
    fallback : int
        Samples whose verdict the batched margins could not certify and the
        full per-variant test decided.
    messages : tuple of str
        The defect test's message of the first defective samples (at most
        :data:`SHOWN`), in the order of ``defective``: which pair, where along
        the drive and why each fails.
    """

    n: int
    n_corners: int
    defective: tuple
    reasons: dict
    samples: np.ndarray
    seed: int | None
    fallback: int = 0
    messages: tuple = ()

    @property
    def n_defective(self) -> int:
        return len(self.defective)

    @property
    def rate(self) -> float:
        return self.n_defective / self.n if self.n else 0.0

    def __repr__(self):
        return (f"<MonteCarloResult: {self.n_defective}/{self.n} defective "
                f"({100 * self.rate:.2f} %), seed {self.seed}>")

    def to_dict(self) -> dict:
        corners = [i for i in self.defective if i < self.n_corners]
        return {"samples": self.n, "corners": self.n_corners, "seed": self.seed,
                "defective": self.n_defective, "rate": self.rate,
                "defective_corners": len(corners),
                "defective_interior": self.n_defective - len(corners),
                "reasons": dict(self.reasons), "full_test_fallbacks": self.fallback,
                "first_defective": [self.samples[i].tolist() for i in self.defective[:SHOWN]],
                "first_defective_messages": list(self.messages)}


#: The defective samples a :class:`MonteCarloResult` shows (vectors and messages).
SHOWN = 5


#: Most samples one Monte Carlo check takes (about a day of tests on one core).
MAX_SAMPLES = 1_000_000


def check_samples(n) -> int:
    """``n`` as a sample count: an int in [1, MAX_SAMPLES], else an InputError."""
    return getint(n, "n", minimum=1, maximum=MAX_SAMPLES, label="the number of samples")


def check_seed(seed) -> int:
    """``seed`` as a recorded random seed (the command line's ``--seed``): an
    int >= 0, else an InputError."""
    return getint(seed, "seed", minimum=0)


def seed_record(seed) -> int | None:
    """The seed a result records: the int itself, None for a Generator or None
    (nothing to reproduce the draw from).  ``seed`` is already checked."""
    return None if seed is None or isinstance(seed, np.random.Generator) else int(seed)


def box_samples(nominal, tol, n: int, seed=0, corners: float = 0.5) -> np.ndarray:
    """``n`` samples of the box: corners first, then uniform interior.

    ``seed`` is an int, a ``numpy.random.Generator`` or None
    (:func:`cspace.argcheck.getseed`); the same int gives the same samples.
    """
    try:
        nominal = np.asarray(nominal, dtype=float)
        tol = np.asarray(tol, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"nominal and tol must be vectors of numbers, got {nominal!r} and "
                         f"{tol!r}", name="nominal") from None
    if nominal.ndim != 1 or tol.shape != nominal.shape:
        raise InputError(f"nominal and tol must be vectors of one length, got shapes "
                         f"{nominal.shape} and {tol.shape}", name="tol", value=tol.shape)
    if not (np.all(np.isfinite(nominal)) and np.all(np.isfinite(tol)) and np.all(tol >= 0)):
        raise InputError("nominal must be finite and tol finite and >= 0", name="tol")
    n = check_samples(n)
    rng = getseed(seed)
    if (isinstance(corners, (bool, np.bool_))
            or not isinstance(corners, (int, float, np.number)) or not 0.0 <= corners <= 1.0):
        raise InputError(f"corners must be a fraction in [0, 1] (the share of samples at box "
                         f"corners), got {corners!r}", name="corners", value=corners)
    nc = int(round(corners * n))
    s = np.empty((n, len(nominal)))
    s[:nc] = nominal + tol * rng.choice([-1.0, 1.0], size=(nc, len(nominal)))
    s[nc:] = nominal + tol * rng.uniform(-1.0, 1.0, size=(n - nc, len(nominal)))
    return s


def monte_carlo(model, n: int = 2000, *, seed=0, accuracy=None, d: float | None = None,
                executor=None, corners: float = 0.5, progress=None,
                intent=None, phase: str = "Monte Carlo check") -> MonteCarloResult:
    """Defect test of ``n`` seeded samples of the model's tolerance box.

    Parameters
    ----------
    model : mechanisms.models.Model
        Its nominal values and tolerances define the box.
    n : int
        Number of samples (the case studies use 2000).
    seed : int, numpy.random.Generator or None
        An int is recorded in the result and reproduces the samples.
    accuracy : Accuracy or preset name
    d : float, optional
        Output-deviation threshold; default the model's ``deviation`` or the
        library default at ``intent``.  To check a synthesized box, pass the d
        of the synthesis run.
    executor : concurrent.futures.Executor, optional
        Default: a local process pool for this call.
    corners : float
        Fraction of samples placed on box corners.
    progress : callable or synthesis.progress.Progress, optional
        ``progress(done, total)`` after every batch of finished tests; or a
        :class:`~synthesis.progress.Progress` (the synthesis's log or bar),
        whose ``task(phase, done, total, defective)`` is called instead, so
        that a long check logs a line per batch at most every 10 s.
    phase : str
        The name of the check in a ``Progress``'s lines.
    intent : mechanisms.models.Model, optional
        The design whose motion and operating region every sample is compared
        with (default ``model``, the box's own nominal).  To check a
        synthesized box, pass the initial design: the synthesis compares every
        variant with it (:mod:`synthesis.loop`, "The design intent"), and a
        box whose nominal has moved must still drive as the design intended.
    """
    import contextlib

    from cspace.accuracy import as_accuracy
    from cspace.defects import reference

    from cspace.model import check_model

    from .executors import (BatchStats, check_executor, check_sendable, make_executor,
                            remember_reference, run_batched)
    for nm, m in (("model", model), ("intent", intent)):
        if m is not None:
            check_model(m, nm)
    check_executor(executor)
    check_sendable(executor, model, intent)
    acc = as_accuracy(accuracy)
    samples = box_samples(model.nominal, model.tol, n, seed, corners)
    seed = seed_record(seed)
    if intent is None:
        intent = model
    elif tuple(getattr(intent, "names", ())) != tuple(model.names):
        raise InputError("intent must be a design of the same model (the same parameters); "
                         f"got parameters {list(getattr(intent, 'names', ()))}, the box has "
                         f"{list(model.names)}", name="intent")
    ref = reference(intent, acc, d)
    remember_reference(intent, acc, ref.d, ref)
    with contextlib.ExitStack() as stack:
        if executor is None:
            executor = stack.enter_context(make_executor("process"))
        bstats = BatchStats()
        if progress is None:
            tick = None
        elif callable(getattr(progress, "task", None)):
            def tick(i, total, k):
                progress.task(phase, i, total, k)
        else:
            def tick(i, total, k):
                progress(i, total)
        res = run_batched(executor, intent, samples, acc, ref.d, tick, bstats)
    bad = tuple(i for i, r in enumerate(res) if r.defective)
    reasons: dict = {}
    for i in bad:
        for rs in res[i].reasons:
            reasons[rs.name] = reasons.get(rs.name, 0) + 1
    return MonteCarloResult(n, int(round(corners * n)), bad, reasons, samples, seed,
                            int(bstats.get("fallback", 0)),
                            tuple(str(res[i].message) for i in bad[:SHOWN]))
