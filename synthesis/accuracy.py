"""The accuracy of a synthesis run: the geometry's knobs plus the synthesis's own.

:class:`SynthesisAccuracy` is a :class:`cspace.accuracy.Accuracy` (it passes
unchanged to every C-space, zone and defect computation) with three more
fields that only the synthesis reads:

``search_eps``
    Bisection stop length for transition points, relative to the largest
    tolerance half-width of a parameter that changes the nominal's motion
    (:func:`synthesis.checklist.motion_scale`; :mod:`synthesis.removal`).
``filter_eps``
    Check-list ε-filter radius, relative to the same tolerance, in the
    max-norm (:mod:`synthesis.checklist`).
``handover_reach``
    Check-list hand-over partners: the zone extremes of the curves bounding
    each cell of the nominal motion are combined with those of the curves
    bounding the next ``handover_reach`` cells
    (:func:`synthesis.checklist.handover_partners`; 0: off, the paper's list).

The presets carry the names of the geometry's presets, so that a run asked
for ``"fast"`` uses the geometry's ``fast`` and the synthesis's ``fast``:

=============  ==========  ==========  ================
preset         search_eps  filter_eps  handover_reach
=============  ==========  ==========  ================
``fast``       5e-3        0.35        2
``default``    1e-3        0.25        2
``precise``    2e-4        0.15        3
=============  ==========  ==========  ================

Why these values: ``docs/synthesis.md`` (the table of the loop's constants)
and ``docs/BENCHMARKS.md`` (the ``search_eps`` sweep).

A run's record (``SynthesisState.accuracy``) is :meth:`SynthesisAccuracy.to_dict`:
all the knobs in one flat mapping, as before the split, so that checkpoints
written earlier resume unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from cspace.accuracy import PRESETS as GEOMETRY_PRESETS
from cspace.accuracy import Accuracy, as_accuracy

__all__ = ["SynthesisAccuracy", "PRESETS", "as_synthesis_accuracy"]


@dataclass(frozen=True)
class SynthesisAccuracy(Accuracy):
    """Approximation settings of a synthesis run.

    All the fields of :class:`cspace.accuracy.Accuracy`, and:

    Attributes
    ----------
    search_eps : float
        Binary-search stop length for transition points, relative to the
        largest tolerance half-width of a parameter that changes the
        nominal's motion (:func:`synthesis.checklist.motion_scale`).
    filter_eps : float
        Check-list ε-filter radius, relative to the same tolerance
        (max-norm).
    handover_reach : int
        Cells ahead whose bounding curves' zone extremes are combined with
        those of each cell of the nominal motion (0: off).
    """

    search_eps: float = 1e-3
    filter_eps: float = 0.25
    handover_reach: int = 2

    @classmethod
    def presets(cls) -> dict:
        """The synthesis presets, named as the geometry's."""
        return PRESETS

    @property
    def geometry(self) -> Accuracy:
        """The geometry's knobs alone, as a plain :class:`~cspace.accuracy.Accuracy`."""
        own = {f.name for f in fields(SynthesisAccuracy)} - {f.name for f in fields(Accuracy)}
        return Accuracy(**{k: v for k, v in self.to_dict().items() if k not in own})


def _preset(name: str, **synthesis) -> SynthesisAccuracy:
    return SynthesisAccuracy(**{**GEOMETRY_PRESETS[name].to_dict(), **synthesis})


PRESETS: dict[str, SynthesisAccuracy] = {
    "fast": _preset("fast", search_eps=5e-3, filter_eps=0.35, handover_reach=2),
    "default": _preset("default", search_eps=1e-3, filter_eps=0.25, handover_reach=2),
    "precise": _preset("precise", search_eps=2e-4, filter_eps=0.15, handover_reach=3),
}


def as_synthesis_accuracy(acc) -> SynthesisAccuracy:
    """Convert ``None`` / a preset name / an :class:`~cspace.accuracy.Accuracy`
    to a :class:`SynthesisAccuracy`.

    A plain ``Accuracy`` keeps its knobs; its synthesis knobs are those of the
    preset it is named after, or of ``default`` when it is ``"custom"``.
    """
    if isinstance(acc, SynthesisAccuracy):
        return acc
    if acc is None or isinstance(acc, str):
        return SynthesisAccuracy.preset("default" if acc is None else acc)
    acc = as_accuracy(acc)
    base = PRESETS.get(acc.name, PRESETS["default"])
    own = {f.name: getattr(base, f.name) for f in fields(SynthesisAccuracy)
           if not hasattr(acc, f.name)}
    return SynthesisAccuracy(**acc.to_dict(), **own)
