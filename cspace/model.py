"""The parametric model contract: what the defect test and the zones read.

A parametric model is a design whose dimensions are named parameters with
nominal values and tolerances, and that builds its part pairs for any vector of
them.  :mod:`cspace.defects`, :mod:`cspace.zones` and :mod:`cspace.batch` read
it through :class:`ParametricModel`; :class:`mechanisms.models.Model` implements
it, and so may a user's own class.

Members
-------
names : sequence of str
    The parameter names, in vector order.
nominal, tol : (n,) float
    Nominal values and tolerance half-widths (model units).
build(u)
    The :class:`~cspace.geometry.Pair` (or :class:`~cspace.geometry.Assembly`
    of pairs) of parameter vector ``u``; raises ``ValueError`` or
    ``ArithmeticError`` for a vector that does not make valid parts.
dependencies()
    Per pair, a mapping from each segment ``(part, loop, seg)`` and each axis
    ``(part, "axis")`` to the parameter names it moves with (see
    :meth:`mechanisms.models.Model.dependencies`).
window
    The C-space window ``(q1_lo, q1_hi, q2_lo, q2_hi)`` analysed, or None (one
    period of each rotating coordinate).
drive
    The driver range ``(q1_start, q1_end)`` of one full cycle, or None (one
    period from the window's start).

Read when present: ``q2_start`` (the stated follower start per pair),
``deviation`` (the designer's output-deviation threshold d) and ``vector(params)``
(a parameter vector from a mapping of names).

The synthesis (:mod:`synthesis`) needs, besides (:data:`SYNTHESIS_MEMBERS`), a
``name``, the parameter count ``n``, new designs of the same model
(``with_nominal(u)``, ``with_tolerances(t)``) and ``parameters`` (their guards
and distributions); :func:`missing` names what an object lacks.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = ["ParametricModel", "missing", "check_model", "MEMBERS", "SYNTHESIS_MEMBERS"]

#: The members every parametric model has.
MEMBERS = ("names", "nominal", "tol", "build", "dependencies", "window", "drive")

#: The members a model needs for a synthesis.
SYNTHESIS_MEMBERS = MEMBERS + ("name", "n", "with_nominal", "with_tolerances", "parameters")


@runtime_checkable
class ParametricModel(Protocol):
    """A design with named, toleranced parameters that builds its part pairs
    (see the module docstring for each member's meaning)."""

    names: tuple
    nominal: object
    tol: object
    window: object
    drive: object

    def build(self, params=None):
        """The pair or assembly of a parameter vector."""

    def dependencies(self) -> tuple:
        """Per pair, the parameter names each feature moves with."""


def missing(obj, members=MEMBERS) -> list:
    """The members of ``members`` that ``obj`` lacks, in order."""
    return [m for m in members if not hasattr(obj, m)]


def check_model(obj, name: str = "model", members=MEMBERS, *, what: str = "a parametric model"):
    """Refuse an object that lacks a member of ``members``: an
    :class:`~cspace.errors.InputError` naming what it lacks."""
    lacks = missing(obj, members)
    if lacks:
        from .errors import InputError
        raise InputError(f"{name} must be {what} (cspace.model.ParametricModel, e.g. "
                         f"mechanisms.models.Model or a cspace-model file); got "
                         f"{type(obj).__name__}, which lacks {', '.join(lacks)}",
                         name=name, value=obj)
