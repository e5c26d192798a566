"""The exception tree of the whole library.

Every error raised on bad input derives from :class:`CSpaceError` and, where the
cause is a bad value, also from :class:`ValueError`, so ``except ValueError`` keeps
working for callers that do not know this library.  Each message says what was
expected, what arrived and what is allowed.  Exceptions carry their data as
attributes so that programs need not parse messages.
"""

from __future__ import annotations

import contextlib
from concurrent.futures import BrokenExecutor

__all__ = [
    "CSpaceError",
    "InputError",
    "NonFiniteError",
    "DegenerateGeometryError",
    "ZeroLengthSegmentError",
    "NonPositiveRadiusError",
    "OpenLoopError",
    "SelfIntersectionError",
    "OrientationError",
    "ZeroDirectionError",
    "InvalidModelError",
    "ParameterError",
    "JammedNominalError",
    "FileFormatError",
    "MissingExtraError",
    "WorkerError",
]


class CSpaceError(Exception):
    """Root of every error raised by ``cspace``, ``mechanisms`` and ``synthesis``."""


class InputError(CSpaceError, ValueError):
    """A value passed at a public boundary is not of the expected form."""

    def __init__(self, message: str, *, name: str | None = None, value=None):
        super().__init__(message)
        self.name = name
        self.value = value


class NonFiniteError(InputError):
    """A number is NaN or infinite where a finite value is required."""


class DegenerateGeometryError(CSpaceError, ValueError):
    """Geometry that cannot describe a real part."""

    def __init__(self, message: str, *, where: str | None = None):
        super().__init__(message)
        self.where = where


class ZeroLengthSegmentError(DegenerateGeometryError):
    """A line or arc whose length is zero (within the accuracy's merge distance)."""


class NonPositiveRadiusError(DegenerateGeometryError):
    """An arc radius that is zero or negative."""


class OpenLoopError(DegenerateGeometryError):
    """Consecutive segments of a profile loop do not meet, or the loop does not close."""


class SelfIntersectionError(DegenerateGeometryError):
    """Two segments of a profile loop (or two loops of one part) cross."""


class OrientationError(DegenerateGeometryError):
    """A loop runs the wrong way for the material side it is declared to bound."""


class ZeroDirectionError(DegenerateGeometryError):
    """A translation axis with a zero (or near-zero) direction vector."""


class InvalidModelError(CSpaceError, ValueError):
    """A parametric model is inconsistent (or builds an invalid pair)."""


class ParameterError(InvalidModelError):
    """A parameter vector or name does not fit the model."""


class JammedNominalError(InvalidModelError):
    """The nominal design's own motion jams before its drive ends: every
    defect test compares a variant with the nominal's motion, so there is
    nothing healthy to compare with (:func:`cspace.defects.reference`)."""


class FileFormatError(CSpaceError, ValueError):
    """A JSON (or DXF) file does not follow its documented format.

    Attributes
    ----------
    path : str
        JSON-pointer-like path of the failing item, e.g. ``parts[1].loops[0][3].radius``.
    """

    def __init__(self, message: str, *, path: str = ""):
        full = f"{path}: {message}" if path else message
        super().__init__(full)
        self.path = path


class MissingExtraError(CSpaceError, ImportError):
    """An optional dependency is needed but not installed."""

    def __init__(self, module: str, extra: str):
        super().__init__(
            f"this feature needs the optional package {module!r}; "
            f"install it with: pip install 'cspace-tolerance[{extra}]'"
        )
        self.module = module
        self.extra = extra

    def __reduce__(self):
        # rebuilt from its own arguments (a worker process pickles the error)
        return (type(self), (self.module, self.extra))


class WorkerError(CSpaceError, RuntimeError):
    """A worker process of an executor stopped before it finished its task
    (``concurrent.futures.BrokenExecutor``): most often a script that starts a
    process pool at its top level, without ``if __name__ == "__main__":``
    (every worker imports the script and so runs it again)."""

    def __init__(self, cause: str = ""):
        super().__init__(
            "a worker process stopped before it finished its task"
            + (f" ({cause})" if cause else "") + ".  A script that runs work on a process "
            "pool (synthesize, monte_carlo and yield use one unless given another executor) "
            "must run it under 'if __name__ == \"__main__\":', since every worker imports "
            "the script and would otherwise run it again; or pass "
            "executor=SerialExecutor() (synthesis.executors) to run it in this process.  "
            "A worker killed for memory stops the same way.")
        self.cause = cause

    def __reduce__(self):
        return (type(self), (self.cause,))


@contextlib.contextmanager
def cancelled_on_failure(futures):
    """Wait for tasks of an executor inside this block: when it fails (or is
    interrupted), the tasks of ``futures`` not yet started are cancelled, and
    a pool whose workers stopped (``BrokenExecutor``) is a :class:`WorkerError`
    that says why and what to do.  ``futures`` may still grow inside the
    block (tasks submitted one by one)."""
    try:
        yield
    except BaseException as e:
        for f in futures:
            f.cancel()
        if isinstance(e, BrokenExecutor):
            raise WorkerError(f"{type(e).__name__}: {e}") from e
        raise


class ExpressionError(FileFormatError):
    """An expression in a model file is not allowed, names something unknown, or
    cannot be evaluated (domain error, overflow, non-finite result).

    Attributes
    ----------
    path : str
        Path of the failing item, e.g. ``pairs[0].parts[1].loops[0][2].radius``.
    token : str
        The offending piece of the expression (a name, an operator, a call, or the
        sub-expression whose evaluation failed).
    """

    def __init__(self, message: str, *, path: str = "", token: str = ""):
        super().__init__(message, path=path)
        self.token = token


__all__ += ["ExpressionError"]


class NumericalError(CSpaceError, ArithmeticError):
    """A computation met an invalid floating-point operation (a NaN from 0/0 or
    inf - inf) that input validation did not foresee.  Raised instead of
    returning a result that passed through a NaN."""


__all__ += ["NumericalError"]
