"""What synthesis may change, and at what cost: the guard rails of a run.

Per parameter (model file keys of a parameter entry, or ``synthesize``
options; :class:`mechanisms.models.Parameter`):

``fixed``
    Its nominal is never shifted (a bought part, a standard size).
``hard``
    Its tolerance is never cut (a process limit).
``shift_cost``
    Relative cost of moving its nominal by one model unit (default 1).  The
    shift of Eq. 4 takes, per defective vector, the axis of smallest
    ``shift_cost * |d|`` instead of the smallest ``|d|``.
``cut_cost``
    Relative cost of cutting its tolerance (default 1).  A single-axis cut
    takes the axis of smallest ``cut_cost * (1 - t_new / t)`` instead of the
    smallest relative cut.
``min_keep``
    The smallest fraction of its *initial* tolerance a cut may keep (default:
    the run's ``min_keep``, 0.25).

A defect that only a forbidden change could remove (every axis that can move
the box past it is fixed, and every cut that would exclude it is hard or goes
below its floor) ends the run with status ``INFEASIBLE``, whose message names
the defect and the parameters in conflict.  It is never reported as converged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cspace.errors import InputError

__all__ = ["Guards", "DEFAULT_MIN_KEEP", "WARN_KEEP"]

#: The default smallest fraction of a tolerance a cut may keep.
DEFAULT_MIN_KEEP = 0.25
#: A converged run that kept less than this fraction of some tolerance warns.
WARN_KEEP = 0.5


@dataclass(frozen=True, eq=False)
class Guards:
    """Per-parameter guard rails of a synthesis run (see the module docstring).

    Attributes
    ----------
    names : tuple of str
    fixed, hard : (n,) bool
    shift_cost, cut_cost : (n,) float
    min_keep : (n,) float
        Fractions of the initial tolerance.
    """

    names: tuple
    fixed: np.ndarray
    hard: np.ndarray
    shift_cost: np.ndarray
    cut_cost: np.ndarray
    min_keep: np.ndarray

    def __repr__(self):
        f = [n for n, x in zip(self.names, self.fixed) if x]
        h = [n for n, x in zip(self.names, self.hard) if x]
        return (f"<Guards: fixed {f or 'none'}, hard {h or 'none'}, min_keep "
                f"{_range(self.min_keep)}, shift_cost {_range(self.shift_cost)}, cut_cost "
                f"{_range(self.cut_cost)}>")

    @classmethod
    def of(cls, model, *, min_keep: float | None = None, fixed=(), hard=(),
           shift_cost=None, cut_cost=None) -> "Guards":
        """The guards of ``model``'s parameters, with the run's options on top.

        Parameters
        ----------
        model : mechanisms.models.Model
        min_keep : float, optional
            Floor for every parameter that states none (default
            :data:`DEFAULT_MIN_KEEP`).
        fixed, hard : iterable of str
            More parameters to fix / to keep uncut.
        shift_cost, cut_cost : mapping of str to float, optional
            Costs that replace the model's.
        """
        names = tuple(model.names)
        idx = {n: i for i, n in enumerate(names)}
        g = _global_keep(min_keep)
        ps = model.parameters
        fx = np.array([bool(getattr(p, "fixed", False)) for p in ps], dtype=bool)
        hd = np.array([bool(getattr(p, "hard", False)) for p in ps], dtype=bool)
        sc = np.array([float(getattr(p, "shift_cost", 1.0)) for p in ps])
        cc = np.array([float(getattr(p, "cut_cost", 1.0)) for p in ps])
        mk = np.array([g if getattr(p, "min_keep", None) is None else float(p.min_keep)
                       for p in ps])
        for what, arr, given in (("fixed", fx, fixed), ("hard", hd, hard)):
            if isinstance(given, str):
                given = [given]
            for nm in given:
                arr[_index(idx, nm, what)] = True
        for what, arr, given in (("shift_cost", sc, shift_cost), ("cut_cost", cc, cut_cost)):
            for nm, v in dict(given or {}).items():
                arr[_index(idx, nm, what)] = _cost(v, f"{what} of {nm!r}")
        return cls(names, fx, hd, sc, cc, mk)

    def to_dict(self) -> dict:
        return {"fixed": [n for n, x in zip(self.names, self.fixed) if x],
                "hard": [n for n, x in zip(self.names, self.hard) if x],
                "shift_cost": self.shift_cost.tolist(), "cut_cost": self.cut_cost.tolist(),
                "min_keep": self.min_keep.tolist()}

    @classmethod
    def from_dict(cls, d, names) -> "Guards":
        """Read what :meth:`to_dict` wrote (raises KeyError, TypeError or
        ValueError on another document)."""
        names = tuple(names)
        n = len(names)
        idx = {nm: i for i, nm in enumerate(names)}
        fx = np.zeros(n, dtype=bool)
        hd = np.zeros(n, dtype=bool)
        for arr, key in ((fx, "fixed"), (hd, "hard")):
            for nm in d[key]:
                if nm not in idx:
                    raise ValueError(f"{key} names {nm!r}, not a parameter")
                arr[idx[nm]] = True
        arrs = []
        for key in ("shift_cost", "cut_cost", "min_keep"):
            a = np.array(d[key], dtype=float)
            if a.shape != (n,) or not np.all(np.isfinite(a)):
                raise ValueError(f"{key} must hold {n} finite values")
            arrs.append(a)
        sc, cc, mk = arrs
        if np.any(sc <= 0) or np.any(cc <= 0) or np.any(mk < 0) or np.any(mk > 1):
            raise ValueError("costs must be > 0 and min_keep in [0, 1]")
        return cls(names, fx, hd, sc, cc, mk)

    def same_as(self, other: "Guards") -> bool:
        return (self.names == other.names and all(
            np.array_equal(getattr(self, k), getattr(other, k))
            for k in ("fixed", "hard", "shift_cost", "cut_cost", "min_keep")))

    def floor(self, initial_tol) -> np.ndarray:
        """The smallest tolerance a cut may leave, per parameter (model units)."""
        return self.min_keep * np.asarray(initial_tol, dtype=float)


def _range(a) -> str:
    if not len(a):
        return "-"
    lo, hi = float(np.min(a)), float(np.max(a))
    return f"{lo:g}" if lo == hi else f"{lo:g}..{hi:g}"


def _index(idx, name, what) -> int:
    if name not in idx:
        raise InputError(f"{what}: {name!r} is not a parameter of the model; allowed: "
                         f"{sorted(idx)}", name=what, value=name)
    return idx[name]


def _cost(v, what) -> float:
    ok = (not isinstance(v, bool) and isinstance(v, (int, float, np.floating, np.integer))
          and math.isfinite(float(v)) and float(v) > 0)
    if not ok:
        raise InputError(f"{what} must be a finite number > 0 (a relative cost, default 1), "
                         f"got {v!r}", name=what, value=v)
    return float(v)


def _global_keep(v) -> float:
    if v is None:
        return DEFAULT_MIN_KEEP
    ok = (not isinstance(v, bool) and isinstance(v, (int, float, np.floating, np.integer))
          and 0.0 <= float(v) <= 1.0)
    if not ok:
        raise InputError(f"min_keep must be a fraction in [0, 1] of the initial tolerance "
                         f"(default {DEFAULT_MIN_KEEP}), got {v!r}", name="min_keep", value=v)
    return float(v)
