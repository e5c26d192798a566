"""Conversion and checking of user input at public boundaries.

Private helpers trust their input; public functions call these once.
"""

from __future__ import annotations

import math
from numbers import Real

import numpy as np

from .errors import InputError, NonFiniteError

__all__ = ["getvector", "getpoint", "getscalar", "getint", "getangle", "getangles", "getunit",
           "getseed", "ANGLE_UNITS", "MAX_ANGLE"]

ANGLE_UNITS = ("rad", "deg")


def getunit(unit: str) -> float:
    """Factor that converts angles in ``unit`` to radians."""
    if unit == "rad":
        return 1.0
    if unit == "deg":
        return math.pi / 180.0
    raise InputError(f"unit must be one of {ANGLE_UNITS}, got {unit!r}", name="unit", value=unit)


def getscalar(x, name: str = "value", *, positive: bool = False, nonneg: bool = False) -> float:
    """A finite real scalar (optionally > 0 or >= 0)."""
    if type(x) is float:
        v = x
    else:
        if isinstance(x, bool) or not isinstance(x, (Real, np.floating, np.integer)):
            if isinstance(x, np.ndarray) and x.shape == ():
                x = x.item()
            else:
                raise InputError(f"{name} must be a real number, got {type(x).__name__} {x!r}",
                                 name=name, value=x)
        v = float(x)
    if not math.isfinite(v):
        raise NonFiniteError(f"{name} must be finite, got {v}", name=name, value=v)
    if positive and not v > 0:
        raise InputError(f"{name} must be > 0, got {v}", name=name, value=v)
    if nonneg and v < 0:
        raise InputError(f"{name} must be >= 0, got {v}", name=name, value=v)
    return v


def getvector(x, n: int | None = None, name: str = "vector") -> np.ndarray:
    """A finite 1-D float array (of length ``n`` if given)."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a sequence of numbers, got {x!r}",
                         name=name, value=x) from None
    if a.ndim != 1 or (n is not None and a.shape[0] != n):
        want = f"length {n}" if n is not None else "1-D"
        raise InputError(f"{name} must be a {want} sequence of numbers, got shape {a.shape}",
                         name=name, value=x)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} must be finite, got {a.tolist()}", name=name, value=x)
    return a


def getpoint(x, name: str = "point") -> tuple[float, float]:
    """A finite 2-D point as a tuple of floats."""
    if type(x) is tuple and len(x) == 2:
        # the common case (a point built from floats), without an array
        p, q = x
        if isinstance(p, float) and isinstance(q, float) and math.isfinite(p) \
                and math.isfinite(q):
            return (float(p), float(q))
    a = getvector(x, 2, name)
    return (float(a[0]), float(a[1]))


#: The largest angle (rad, either sign) read as a direction: 2**22 rad, some
#: 670,000 turns, where neighbouring doubles lie 9.3e-10 rad apart.  Beyond it
#: the number no longer says which way a link points (at 1e20 rad they lie
#: 16,384 rad apart, and cos and sin of it are those of whichever double the
#: value was rounded to).
MAX_ANGLE = float(2 ** 22)


def getangle(x, unit: str = "rad", name: str = "angle") -> float:
    """A finite angle converted to radians, at most :data:`MAX_ANGLE` either
    way."""
    a = getscalar(x, name) * getunit(unit)
    _check_turns(abs(a), x, unit, name)
    return a


def getangles(x, unit: str = "rad", name: str = "angles", *,
              direction: bool = True) -> np.ndarray:
    """A finite array of angles (any shape) converted to radians, each at most
    :data:`MAX_ANGLE` either way (``direction=False``: numbers that are not
    directions, a slide's say, read by the same rules without that bound)."""
    try:
        kind = None if isinstance(x, (str, bytes)) else np.asarray(x).dtype.kind
    except (TypeError, ValueError):
        # a ragged nesting (lists of different lengths): no array at all
        kind = None
    if kind is None or kind not in "iuf":
        raise InputError(f"{name} must be numbers (an angle or an array of them, every row "
                         f"of the same length), got {type(x).__name__} {x!r}", name=name,
                         value=x)
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be numbers, got {x!r}", name=name, value=x) from None
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} must be finite", name=name, value=x)
    a = a * getunit(unit)
    if direction and a.size:
        _check_turns(float(np.max(np.abs(a))), x, unit, name)
    return a


def _check_turns(big: float, x, unit: str, name: str) -> None:
    """Refuse an angle (its magnitude ``big``, rad) beyond :data:`MAX_ANGLE`."""
    if big > MAX_ANGLE:
        got = (f"{big:.6g} rad" if unit == "rad"
               else f"{big / getunit(unit):.6g} {unit} ({big:.6g} rad)")
        raise InputError(
            f"{name} must be an angle of at most {MAX_ANGLE:.7g} rad "
            f"({math.degrees(MAX_ANGLE):.7g} deg) either way, got {got}: doubles that large "
            f"lie {math.ulp(big):.3g} rad apart and no longer give a direction; reduce it "
            f"to a turn first (math.remainder(angle, 2 * math.pi) in radians, "
            f"math.remainder(angle, 360) in degrees)", name=name, value=x)


def getint(x, name: str = "value", *, minimum: int | None = None,
           maximum: int | None = None, label: str | None = None) -> int:
    """An integer in ``[minimum, maximum]`` (either bound optional), as a Python int.

    Accepts ``int`` and numpy integers; refuses ``bool``, floats (also ``3.0``)
    and strings.

    Parameters
    ----------
    x
        The value to check.
    name : str
        The argument's name, kept as :attr:`InputError.name`.
    minimum, maximum : int, optional
        Inclusive bounds.
    label : str, optional
        How the message names the value (default ``name``), e.g.
        ``"Accuracy.zone_samples"``.

    Raises
    ------
    InputError
        Saying what was expected, what arrived and the allowed range, e.g.
        ``frames must be an int >= 2, got 1.5``.

    >>> getint(5, "n", minimum=2)
    5
    """
    ok = isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_))
    if ok and (minimum is None or x >= minimum) and (maximum is None or x <= maximum):
        return int(x)
    if minimum is not None and maximum is not None:
        allowed = f" in [{minimum}, {maximum}]"
    elif minimum is not None:
        allowed = f" >= {minimum}"
    elif maximum is not None:
        allowed = f" <= {maximum}"
    else:
        allowed = ""
    raise InputError(f"{label or name} must be an int{allowed}, got {x!r}", name=name, value=x)


def getseed(seed) -> np.random.Generator:
    """A numpy Generator from ``int | numpy.random.Generator | None``.

    An int (>= 0) seeds a new ``numpy.random.default_rng(seed)``, so the same
    int gives the same stream; a Generator is used as it is (and advanced);
    None draws fresh entropy from the operating system.

    Raises
    ------
    InputError
        For anything else (a negative int, a float, a bool, a string), naming
        what is allowed.
    """
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None:
        return np.random.default_rng()
    ok = isinstance(seed, (int, np.integer)) and not isinstance(seed, (bool, np.bool_))
    if not ok or seed < 0:
        raise InputError(f"seed must be an int >= 0, a numpy.random.Generator or None, "
                         f"got {seed!r}", name="seed", value=seed)
    return np.random.default_rng(int(seed))
