"""Parametric models: named parameters with nominal values and symmetric
tolerances, and a pure ``build(params)`` that returns a :class:`cspace.Pair` (or an
:class:`cspace.geometry.Assembly` of pairs on one driver).

A model is a frozen value.  A shifted design is a new model
(:meth:`Model.with_nominal`); evaluation is a pure function of (model, parameters)
so that it can be cached and run in parallel.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from cspace.errors import CSpaceError, InvalidModelError, ParameterError
from cspace.geometry import Assembly, Line, Pair

__all__ = ["Distribution", "Parameter", "Model", "DEFAULT_DISTRIBUTION", "DISTRIBUTION_KINDS",
           "PARAMETER_UNITS", "unit_label", "MAX_DRIVE_SPAN"]

#: The kinds of :class:`Distribution` and the keys each one takes beside ``kind``.
DISTRIBUTION_KINDS = {"normal": ("sigma", "cp"),
                      "truncated_normal": ("sigma", "cp", "limit"),
                      "uniform": ()}


@dataclass(frozen=True)
class Distribution:
    """How the made values of one dimension spread about its nominal.

    The spread is centred on the nominal and symmetric.  It is stated either
    as a standard deviation ``sigma`` (model length units) or as a process
    capability ``cp``, with ``sigma = tol / (3 cp)``; at most one of the two.

    Kinds
    -----
    ``normal``
        Normal with that sigma, not truncated: parts outside the tolerance are
        made and used (no inspection).  Neither sigma nor cp: cp = 1.
    ``truncated_normal``
        Normal with that sigma, truncated at ``+/- limit * tol`` (``limit`` > 0,
        default 1): inspection rejects the parts beyond it.  Neither sigma nor
        cp: cp = 1.
    ``uniform``
        Uniform over ``nominal +/- tol``.

    A parameter that states none follows :data:`DEFAULT_DISTRIBUTION`: a
    normal of Cp = 1 (sigma = tol / 3) truncated at the tolerance limits,
    since parts made outside the tolerance are rejected at inspection.  A
    spread of zero (tol 0, or sigma 0) keeps the dimension at its nominal.

    Attributes
    ----------
    kind : {"normal", "truncated_normal", "uniform"}
    sigma : float or None
        Standard deviation before truncation (model length units, >= 0).
    cp : float or None
        Process capability (> 0).
    limit : float
        Truncation half-width in tolerances (``truncated_normal`` only).
    """

    kind: str = "truncated_normal"
    sigma: float | None = None
    cp: float | None = None
    limit: float = 1.0

    def __post_init__(self):
        if self.kind not in DISTRIBUTION_KINDS:
            raise ParameterError(f"distribution kind must be one of {sorted(DISTRIBUTION_KINDS)}, "
                                 f"got {self.kind!r}")
        keys = DISTRIBUTION_KINDS[self.kind]
        given = [k for k in ("sigma", "cp") if getattr(self, k) is not None]
        for k in given:
            if k not in keys:
                raise ParameterError(f"a {self.kind} distribution takes no {k} (it spreads "
                                     f"over +/- tol); allowed keys: {['kind', *keys]}")
        if len(given) == 2:
            raise ParameterError(f"a {self.kind} distribution takes sigma or cp, not both; got "
                                 f"sigma={self.sigma!r} and cp={self.cp!r}")
        if self.sigma is not None:
            object.__setattr__(self, "sigma", _positive(self.sigma, "sigma", zero=True))
        if self.cp is not None:
            object.__setattr__(self, "cp", _positive(self.cp, "cp"))
        object.__setattr__(self, "limit", _positive(self.limit, "limit"))
        if self.limit != 1.0 and self.kind != "truncated_normal":
            raise ParameterError(f"only a truncated_normal distribution takes a limit; got "
                                 f"limit={self.limit!r} for kind {self.kind!r}")

    @classmethod
    def from_dict(cls, d) -> "Distribution":
        """A distribution from its model-file entry, e.g. ``{"kind": "normal", "cp": 1.33}``."""
        if isinstance(d, Distribution):
            return d
        if not isinstance(d, Mapping) or "kind" not in d:
            raise ParameterError(f"a distribution must be an object with a 'kind' (one of "
                                 f"{sorted(DISTRIBUTION_KINDS)}), got {d!r}"[:300])
        kind = d["kind"]
        if kind not in DISTRIBUTION_KINDS:
            raise ParameterError(f"distribution kind must be one of {sorted(DISTRIBUTION_KINDS)}, "
                                 f"got {kind!r}")
        allowed = ("kind",) + DISTRIBUTION_KINDS[kind]
        extra = sorted(set(d) - set(allowed))
        if extra:
            raise ParameterError(f"unknown key(s) {extra} in a {kind} distribution; allowed: "
                                 f"{list(allowed)}")
        return cls(**dict(d))

    def to_dict(self) -> dict:
        out = {"kind": self.kind}
        for k in ("sigma", "cp"):
            if getattr(self, k) is not None:
                out[k] = getattr(self, k)
        if self.kind == "truncated_normal" and self.limit != 1.0:
            out["limit"] = self.limit
        return out

    def std(self, tol: float) -> float:
        """Standard deviation of the underlying normal (model units); for a
        uniform, tol / sqrt(3)."""
        if self.kind == "uniform":
            return tol / math.sqrt(3.0)
        if self.sigma is not None:
            return self.sigma
        return tol / (3.0 * (1.0 if self.cp is None else self.cp))

    def half_width(self, tol: float) -> float:
        """Half-width of the support about the nominal (model units; inf for a normal)."""
        if self.kind == "normal":
            return math.inf
        return tol * (self.limit if self.kind == "truncated_normal" else 1.0)


def _positive(v, what, zero=False) -> float:
    ok = (not isinstance(v, (bool, np.bool_)) and isinstance(v, (int, float, np.floating,
                                                                  np.integer))
          and math.isfinite(float(v)) and (float(v) >= 0 if zero else float(v) > 0))
    if not ok:
        raise ParameterError(f"distribution {what} must be a finite number "
                             f"{'>= 0' if zero else '> 0'}, got {v!r}")
    return float(v)


#: The distribution of a parameter that states none: Cp = 1 (sigma = tol / 3),
#: truncated at +/- tol because inspection rejects parts outside the tolerance.
DEFAULT_DISTRIBUTION = Distribution("truncated_normal", cp=1.0)


def _preset_hint(v) -> str:
    """What to say when an accuracy preset's name arrives where a value was
    expected (an argument in the wrong place)."""
    from cspace.accuracy import PRESETS
    if isinstance(v, str) and v in PRESETS:
        return f" (the name of an accuracy preset: pass it as accuracy={v!r})"
    return ""


from cspace.geom2d import MAX_DRIVE_SPAN  # noqa: E402  (re-exported: Model.drive's limit)


#: The units a parameter may have (:attr:`Parameter.unit`): the model's length
#: unit, or rad.
PARAMETER_UNITS = ("", "rad")


def unit_label(p, units: str) -> str:
    """The unit a parameter's values are in: ``"rad"`` for an angle, else the
    model's length unit ``units``."""
    return "rad" if getattr(p, "unit", "") == "rad" else units


@dataclass(frozen=True)
class Parameter:
    """A named model dimension.

    Attributes
    ----------
    name : str
    nominal : float
        Nominal value (model length units; rad for an angle, ``unit``).
    tol : float
        Symmetric tolerance half-width (>= 0): the value may lie in nominal +/- tol.
    description : str
    fixed : bool
        Synthesis may not shift its nominal (a bought part, a standard size).
    hard : bool
        Synthesis may not cut its tolerance (a process limit).
    shift_cost, cut_cost : float
        Relative cost (> 0, default 1) of shifting its nominal by one unit and
        of cutting its tolerance by a given fraction: synthesis prefers the
        cheaper parameters (:mod:`synthesis.guards`).
    min_keep : float or None
        The smallest fraction of its initial tolerance synthesis may keep, in
        [0, 1]; None: the run's global value (``--min-keep``, default 0.25).
    distribution : Distribution or None
        How made values spread about the nominal, for statistical yield
        (:mod:`synthesis.statistics`); a mapping such as ``{"kind": "normal",
        "cp": 1.33}`` is converted.  None: :data:`DEFAULT_DISTRIBUTION`.
    unit : str
        ``""``: a length in the model's unit (the default); ``"rad"``: an
        angle, its nominal, tolerance and distribution in rad (a model file
        may state them in degrees, ``"unit": "deg"``, converted on reading).
        Reports state each parameter's values in its own unit.
    """

    name: str
    nominal: float
    tol: float
    description: str = ""
    fixed: bool = False
    hard: bool = False
    shift_cost: float = 1.0
    cut_cost: float = 1.0
    min_keep: float | None = None
    distribution: Distribution | None = None
    unit: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ParameterError(f"parameter name must be an identifier str, got {self.name!r}")
        if self.unit not in PARAMETER_UNITS:
            raise ParameterError(f"parameter {self.name!r}: unit must be '' (the model's length "
                                 f"unit) or 'rad' (an angle), got {self.unit!r}")
        for f in ("nominal", "tol"):
            v = getattr(self, f)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)):
                raise ParameterError(f"parameter {self.name!r}: {f} must be a number, got {v!r}")
            if not math.isfinite(float(v)):
                raise ParameterError(f"parameter {self.name!r}: {f} must be finite, got {v}")
            object.__setattr__(self, f, float(v))
        if self.tol < 0:
            raise ParameterError(f"parameter {self.name!r}: tol must be >= 0, got {self.tol}")
        for f in ("fixed", "hard"):
            if not isinstance(getattr(self, f), (bool, np.bool_)):
                raise ParameterError(f"parameter {self.name!r}: {f} must be True or False, got "
                                     f"{getattr(self, f)!r}")
            object.__setattr__(self, f, bool(getattr(self, f)))
        for f in ("shift_cost", "cut_cost"):
            v = getattr(self, f)
            ok = (not isinstance(v, bool) and isinstance(v, (int, float, np.floating, np.integer))
                  and math.isfinite(float(v)) and float(v) > 0)
            if not ok:
                raise ParameterError(f"parameter {self.name!r}: {f} must be a finite number > 0 "
                                     f"(a relative cost, default 1), got {v!r}")
            object.__setattr__(self, f, float(v))
        v = self.min_keep
        if v is not None:
            ok = (not isinstance(v, bool) and isinstance(v, (int, float, np.floating, np.integer))
                  and 0.0 <= float(v) <= 1.0)
            if not ok:
                raise ParameterError(f"parameter {self.name!r}: min_keep must be a fraction in "
                                     f"[0, 1] of the initial tolerance, or None, got {v!r}")
            object.__setattr__(self, "min_keep", float(v))
        if self.distribution is not None:
            try:
                dist = Distribution.from_dict(self.distribution)
            except ParameterError as e:
                raise ParameterError(f"parameter {self.name!r}: {e}") from None
            object.__setattr__(self, "distribution", dist)

    @property
    def spread(self) -> Distribution:
        """The stated distribution, else :data:`DEFAULT_DISTRIBUTION`."""
        return DEFAULT_DISTRIBUTION if self.distribution is None else self.distribution


@dataclass(frozen=True, eq=False)
class Model:
    """A parametric mechanism.

    Attributes
    ----------
    name : str
    parameters : tuple of Parameter
    builder : callable
        ``builder(values: dict[str, float]) -> Pair | Assembly``; a module-level
        function so that models pickle for process pools.
    units : str
        Length unit of every parameter and profile.
    description : str
    window : (q1_lo, q1_hi, q2_lo, q2_hi) or None
        C-space window to analyse, four finite numbers with ``q1_lo < q1_hi``
        and ``q2_lo < q2_hi`` (rad for a rotating part, model units for a
        sliding one); None: one period of each rotating coordinate, the
        touching range of a sliding one.  A rotating driver's range spans at
        most one period (2 pi), and a rotating follower's exactly one,
        ``(q2_lo, q2_lo + 2 * math.pi)``: the follower's coordinate wraps
        round.  The model learns which parts rotate only when it builds them,
        so these two rules are checked when a C-space is first computed
        (:func:`mechanisms.analysis.model_cspaces`, the defect test).
    drive : (q1_start, q1_end) or None
        Driver range of the operating motion used by the kinematic simulation,
        two different finite numbers (rad for a rotating driver, model units
        for a sliding one; None: one period from the window start,
        counter-clockwise).  It may run several turns (a Geneva wheel's cycle
        is four), but a rotating driver's drive of :data:`MAX_DRIVE_SPAN` rad
        (about 14 turns) or more that is not whole turns is refused as one
        written in degrees (checked at construction by building the nominal
        once).
    q2_start : tuple of float or None
        Follower start coordinate of each pair at ``drive[0]`` (rad, or model
        units for a sliding follower), one finite number per pair or one for
        all; a single number is taken as that one, ``q2_start=0.1`` as
        ``(0.1,)``.  None: the middle of the widest free interval at
        ``drive[0]`` in each pair's nominal C-space
        (:meth:`cspace.ConfigurationSpace.default_start`).
    deviation : float or None
        The designer's output-deviation threshold d of the defect test, a
        finite number > 0 (C-space metric: rad, or slide / characteristic
        length); None: the library default
        (:func:`cspace.defects.default_deviation`).

    Every field is checked at construction (an :class:`InvalidModelError`,
    or a :class:`ParameterError` for the parameters, saying what is allowed);
    sequences are stored as tuples of floats.
    """

    name: str
    parameters: tuple
    builder: Callable = field(repr=False)
    units: str = "mm"
    description: str = field(default="", repr=False)
    window: tuple | None = field(default=None, repr=False)
    drive: tuple | None = field(default=None, repr=False)
    q2_start: tuple | None = field(default=None, repr=False)
    deviation: float | None = field(default=None, repr=False)

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise InvalidModelError(f"model name must be a non-empty str, got "
                                    f"{type(self.name).__name__} {self.name!r}")
        ps = self._checked_parameters()
        names = [p.name for p in ps]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise InvalidModelError(f"model {self.name!r}: duplicate parameter names {dup}")
        object.__setattr__(self, "parameters", ps)
        if not callable(self.builder):
            raise InvalidModelError(f"model {self.name!r}: builder must be a callable "
                                    f"builder(values: dict[str, float]) -> Pair | Assembly "
                                    f"(a module-level function), got "
                                    f"{type(self.builder).__name__} {self.builder!r}"[:300])
        if not isinstance(self.units, str) or not self.units:
            raise InvalidModelError(f"model {self.name!r}: units must be a non-empty str, the "
                                    f"length unit of every parameter and profile (such as "
                                    f"'mm' or 'cm'), got {type(self.units).__name__} "
                                    f"{self.units!r}")
        if not isinstance(self.description, str):
            raise InvalidModelError(f"model {self.name!r}: description must be a str, got "
                                    f"{type(self.description).__name__}")
        if self.window is not None:
            w = _finite_numbers(self.window)
            if w is None or len(w) != 4 or not (w[0] < w[1] and w[2] < w[3]):
                raise InvalidModelError(f"model {self.name!r}: window must be None or four "
                                        f"finite numbers (q1_lo, q1_hi, q2_lo, q2_hi) with "
                                        f"q1_lo < q1_hi and q2_lo < q2_hi (rad for a rotating "
                                        f"part, model units for a sliding one), got "
                                        f"{self.window!r}"[:400])
            object.__setattr__(self, "window", w)
        if self.drive is not None:
            dv = _finite_numbers(self.drive)
            if dv is None or len(dv) != 2 or dv[0] == dv[1]:
                raise InvalidModelError(f"model {self.name!r}: drive must be two different "
                                        f"finite driver values (q1_start, q1_end) (rad for a "
                                        f"rotating driver, model units for a sliding one), or "
                                        f"None, got {self.drive!r}"[:400])
            object.__setattr__(self, "drive", dv)
        if self.q2_start is not None:
            q2 = self.q2_start
            if isinstance(q2, np.ndarray) and q2.ndim == 0:
                q2 = q2[()]
            if _real(q2):
                q2 = (q2,)              # one number: the start of every pair
            q2v = _finite_numbers(q2)
            if not q2v:
                raise InvalidModelError(f"model {self.name!r}: q2_start must be None, one "
                                        f"finite number, or a sequence of finite numbers (the "
                                        f"follower start of each pair at drive[0], or one for "
                                        f"all: rad, or model units for a sliding follower), "
                                        f"got {self.q2_start!r}"[:400])
            object.__setattr__(self, "q2_start", q2v)
        if self.deviation is not None:
            dev = self.deviation
            if not (_real(dev) and math.isfinite(float(dev)) and float(dev) > 0):
                raise InvalidModelError(f"model {self.name!r}: deviation must be None (the "
                                        f"library default, cspace.defects.default_deviation) "
                                        f"or a finite number > 0 (the output-deviation "
                                        f"threshold d, C-space metric: rad, or slide / "
                                        f"characteristic length), got "
                                        f"{type(dev).__name__} {dev!r}"[:400])
            object.__setattr__(self, "deviation", float(dev))
        object.__setattr__(self, "_cache", {})
        if self.drive is not None and abs(self.drive[1] - self.drive[0]) >= MAX_DRIVE_SPAN:
            self._check_drive_in_rad()

    def _checked_parameters(self) -> tuple:
        """``parameters`` as a tuple of :class:`Parameter`, or a ParameterError
        that says how to make one."""
        ps = self.parameters
        if isinstance(ps, (str, bytes, Mapping, Parameter)) or not _iterable(ps):
            raise ParameterError(f"model {self.name!r}: parameters must be a sequence of "
                                 f"Parameter (mechanisms.models.Parameter(name, nominal, "
                                 f"tol)), got {type(ps).__name__} {ps!r}"[:400])
        ps = tuple(ps)
        for i, p in enumerate(ps):
            if isinstance(p, Parameter):
                continue
            if isinstance(p, (tuple, list)) and 3 <= len(p) <= 4:
                how = f"e.g. Parameter{tuple(p)!r}"
            else:
                how = "e.g. Parameter('ecc', 5.0, 0.02)"
            raise ParameterError(f"model {self.name!r}: parameters[{i}] must be a Parameter, "
                                 f"got {type(p).__name__} {p!r}; make one with "
                                 f"mechanisms.models.Parameter(name, nominal, tol), "
                                 f"{how}"[:400])
        return ps

    def _check_drive_in_rad(self) -> None:
        """Refuse a drive of :data:`MAX_DRIVE_SPAN` rad or more of a rotating
        driver that is not whole turns (most likely written in degrees,
        :func:`cspace.geom2d.drive_in_degrees`).  Which part rotates is known
        only from a build: the nominal is built once; a model whose nominal
        cannot be built is left to the error of its first build."""
        from cspace.geom2d import drive_in_degrees
        from cspace.geometry import Rotation
        degrees = drive_in_degrees(*self.drive)
        if degrees is None:
            return
        try:
            first = self.pairs()[0]
        except Exception:           # noqa: BLE001 - reported where the model is built
            return
        if not isinstance(first.driver.axis, Rotation):
            return
        raise InvalidModelError(f"model {self.name!r}: {degrees}")

    def __repr__(self):
        return f"<Model {self.name!r}: {len(self.parameters)} parameters, units {self.units}>"

    # ---- parameter vectors
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def nominal(self) -> np.ndarray:
        return np.array([p.nominal for p in self.parameters])

    @property
    def tol(self) -> np.ndarray:
        return np.array([p.tol for p in self.parameters])

    @property
    def n(self) -> int:
        return len(self.parameters)

    @property
    def param_units(self) -> tuple[str, ...]:
        """The unit of each parameter's values: the model's length unit, or
        ``"rad"`` for an angle (:attr:`Parameter.unit`)."""
        return tuple(unit_label(p, self.units) for p in self.parameters)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise ParameterError(f"model {self.name!r} has no parameter {name!r}; "
                                 f"allowed: {list(self.names)}") from None

    def vector(self, params=None) -> np.ndarray:
        """A full parameter vector from None (nominal), a mapping of some names, or a
        sequence of all values."""
        if params is None:
            return self.nominal
        if isinstance(params, Mapping):
            u = self.nominal.copy()
            for k, v in params.items():
                i = self.index(k)
                fv = self._number(v, f"parameter {k!r}")
                if not math.isfinite(fv):
                    raise ParameterError(f"parameter {k!r} must be finite, got {fv}")
                u[i] = fv
            return u
        try:
            u = np.asarray(params, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"parameters must be a mapping or a sequence of {self.n} "
                                 f"numbers, got {params!r}{_preset_hint(params)}") from None
        if u.shape != (self.n,):
            raise ParameterError(f"model {self.name!r} needs {self.n} parameter values, got "
                                 f"shape {u.shape}")
        if not np.all(np.isfinite(u)):
            raise ParameterError("parameter values must be finite (no NaN or inf)")
        return u

    @staticmethod
    def _number(v, what) -> float:
        if isinstance(v, (bool, np.bool_, str, bytes)):
            raise ParameterError(f"{what} must be a number, got {type(v).__name__} {v!r}")
        try:
            return float(v)
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(f"{what} must be a finite number, got {v!r}"[:200]) from None

    def values(self, params=None) -> dict:
        return dict(zip(self.names, self.vector(params).tolist()))

    def in_box(self, params, rtol: float = 1e-12) -> bool:
        u = self.vector(params)
        return bool(np.all(np.abs(u - self.nominal) <= self.tol * (1 + rtol) + 1e-15))

    # ---- building
    def build(self, params=None):
        """The pair (or assembly) at a parameter vector (default: nominal).

        Raises
        ------
        InvalidModelError
            The vector gives invalid geometry (the cause is chained).
        """
        vals = self.values(params)
        try:
            out = self.builder(vals)
        except InvalidModelError:
            raise
        except CSpaceError as e:
            raise InvalidModelError(f"model {self.name!r} builds invalid geometry at this "
                                    f"parameter vector: {e}") from e
        except (ValueError, ArithmeticError) as e:
            # the builder's own arithmetic failed (a zero distance, the square
            # root of a negative number): the vector has no geometry
            raise InvalidModelError(f"model {self.name!r} cannot be built at this parameter "
                                    f"vector: {type(e).__name__}: {e}") from e
        if not isinstance(out, (Pair, Assembly)):
            raise InvalidModelError(f"model {self.name!r}: builder returned "
                                    f"{type(out).__name__}, expected Pair or Assembly")
        return out

    def pairs(self, params=None) -> tuple:
        out = self.build(params)
        return out.pairs if isinstance(out, Assembly) else (out,)

    # ---- derived models
    def with_nominal(self, u) -> "Model":
        u = self.vector(u)
        ps = tuple(dataclasses.replace(p, nominal=float(v)) for p, v in zip(self.parameters, u))
        return dataclasses.replace(self, parameters=ps)

    def with_tolerances(self, t) -> "Model":
        """The model with tolerances ``t``: one number for all, or one per parameter
        (a sequence of n, or a mapping of some names; the others keep theirs)."""
        if isinstance(t, Mapping):
            cur = self.tol.copy()
            for k, v in t.items():
                cur[self.index(k)] = self._number(v, f"tolerance of {k!r}")
            t = cur
        try:
            t = np.broadcast_to(np.asarray(t, dtype=float), (self.n,))
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(f"tolerances must be one number or {self.n} numbers (one per "
                                 f"parameter) or a mapping of names, got {t!r}"[:300]) from None
        if not np.all(np.isfinite(t)) or np.any(t < 0):
            raise ParameterError("tolerances must be finite and >= 0")
        ps = tuple(dataclasses.replace(p, tol=float(v)) for p, v in zip(self.parameters, t))
        return dataclasses.replace(self, parameters=ps)

    # ---- dependency tracking
    def dependencies(self) -> tuple:
        """Which parameters move which segments and axes, per pair.

        Found numerically: each parameter is moved by a small step relative to
        the model size (1e-6 of it) and by its tolerance, each to one side (the
        other where that side cannot be built), and every segment and axis that
        changes under either move records it.  The small step finds the
        dependencies of a parameter whose tolerance is 0 or too small to move
        anything measurably; the tolerance step those that act only further
        out.  A tolerance so large that neither side can be built is skipped;
        a parameter that cannot move by the small step either way is an
        :class:`InvalidModelError`.  Returns one mapping per pair:
        ``{(part, loop, seg): frozenset(names), (part, "axis"): frozenset(names)}``.
        """
        if "deps" in self._cache:
            return self._cache["deps"]
        base = self.pairs()
        sigs0 = [_signature(p) for p in base]
        deps = [dict() for _ in base]
        u0 = self.nominal
        scale = max(base[0].size, 1e-12)
        for i, p in enumerate(self.parameters):
            small = 1e-6 * scale
            for h in ((small, p.tol) if p.tol > small else (small,)):
                var = self._probe(u0, i, h)
                if var is None:
                    if h == small:
                        raise InvalidModelError(
                            f"model {self.name!r}: parameter {p.name!r} cannot move by "
                            f"+/-{small:.3g} from its nominal {u0[i]!r} without invalid geometry")
                    continue
                for k, (s0, pv) in enumerate(zip(sigs0, var)):
                    s1 = _signature(pv)
                    if s1.keys() != s0.keys():
                        raise InvalidModelError(
                            f"model {self.name!r}: moving {p.name!r} changes the profile "
                            "topology; a parametric model must keep its segments")
                    for key in s0:
                        if not np.allclose(s0[key], s1[key], rtol=0, atol=1e-12 * scale):
                            deps[k].setdefault(key, set()).add(p.name)
        out = tuple({k: frozenset(v) for k, v in d.items()} for d in deps)
        self._cache["deps"] = out
        return out

    def _probe(self, u0, i: int, h: float):
        """The pairs with parameter i moved by +h, else by -h; None if neither builds."""
        for sgn in (1.0, -1.0):
            u = u0.copy()
            u[i] += sgn * h
            try:
                return self.pairs(u)
            except InvalidModelError:
                continue
        return None


def _real(v) -> bool:
    """Whether ``v`` is a real number (a numpy one too), not a bool or a str."""
    return (not isinstance(v, (bool, np.bool_))
            and isinstance(v, (int, float, np.integer, np.floating)))


def _iterable(v) -> bool:
    try:
        iter(v)
    except TypeError:
        return False
    return True


def _finite_numbers(v) -> tuple | None:
    """``v`` as a tuple of finite floats, or None when it is not a sequence of
    finite real numbers (a str, a bare number, NaN, a nested list)."""
    if isinstance(v, (str, bytes, Mapping)) or not _iterable(v):
        return None
    if isinstance(v, np.ndarray) and v.ndim != 1:
        return None
    items = tuple(v)
    if not all(_real(x) and math.isfinite(float(x)) for x in items):
        return None
    return tuple(float(x) for x in items)


def _signature(pair: Pair) -> dict:
    sig = {}
    for pi, part in enumerate(pair.parts):
        ax = part.axis.to_dict()
        sig[(pi, "axis")] = np.array([v for k in sorted(ax) if k != "type" for v in ax[k]])
        for li, lp in enumerate(part.loops):
            for si, s in enumerate(lp.segments):
                if isinstance(s, Line):
                    sig[(pi, li, si)] = np.array(s.start + s.end)
                else:
                    sig[(pi, li, si)] = np.array(s.center + (s.radius,) + tuple(s.start_point)
                                                 + tuple(s.end_point))
    return sig
