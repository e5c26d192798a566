"""Every approximating knob of the library, in one frozen object.

Users trade speed for accuracy by choosing a preset (``Accuracy.preset("fast")``)
or by replacing single fields (``dataclasses.replace(acc, chord=1e-5)``).  Nothing
numeric that affects a result lives in a module global.

C-space quantities are measured in the C-space metric of :mod:`cspace.metric`:
radians for rotation coordinates, and slide / characteristic length for
translation coordinates.  Length quantities are relative to the part size (the
radius of the smallest disk about the origin that holds both parts at q = 0), so a
model scaled by 1000 is analysed with the same relative accuracy.

What each preset guarantees
---------------------------
``fast``
    Polylines within 1e-3 rad of the exact curves; events located to 1e-9 rad;
    zone bands from 24 samples per curve, first-order-guided corner candidates
    only: on strongly nonlinear curves with many parameters (the Geneva pin
    against a slot corner) the band can miss variants near trimmed curve ends
    (measured in ``docs/BENCHMARKS.md``).  For interactive exploration.
``default``
    Polylines within 2e-4 rad; events to 1e-11 rad; zones from 48 samples per curve
    with bounded local optimisation, and where the first-order guide fails a
    margin-constrained guide, a corner hill-climb and a neighbour envelope: the
    bands held every one of 1000 seeded box vectors on each built-in model in the
    zone benchmark.  The middle of the trade.  ``docs/BENCHMARKS.md`` (speed/accuracy section) locates the
    knee of each measured quantity and where ``default`` sits against it: at the
    knee for the Geneva zone bands; for the C-space boundary and the cam's zones
    the measured front has no knee (the error falls faster than the time grows),
    so ``precise`` costs little more there.
``precise``
    Polylines within 2e-5 rad; events to 1e-13 rad; zones from 128 samples per curve
    with more optimisation.  For reference runs.

The synthesis adds its own knobs (bisection stop length, check-list filter,
hand-over reach) in :class:`synthesis.accuracy.SynthesisAccuracy`, a subclass
with presets of the same names.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .argcheck import getint
from .errors import InputError

__all__ = ["Accuracy", "PRESETS", "as_accuracy", "same_geometry"]


@dataclass(frozen=True)
class Accuracy:
    """Approximation settings.

    Attributes
    ----------
    name : str
        Preset name, or ``"custom"``.
    chord : float
        Largest distance (C-space metric) between a contact curve and its polyline.
    max_step : float
        Largest driver step (rad) between polyline vertices, so that short
        features are never stepped over.
    root_tol : float
        Absolute tolerance (rad) on event locations: curve ends, turning points,
        crossings.
    scan_step : float
        Driver-angle step (rad) of the sign scan that brackets events before
        they are refined to ``root_tol``.  A contact that lasts less than one
        step (a short chamfer, an edge of a finely polygonised profile) is
        found by a search inside the steps whose validity margin comes within
        reach of zero at both ends (``cspace.contact._short_runs``).
    merge_rel : float
        Distance, relative to part size, below which two points are the same
        point (loop closure, coincident vertices, contact-point-on-feature tests).
    contact_rel : float
        Relative gap below which two profiles are "in contact" in a point query.
    zone_samples : int
        Sample points per nominal contact curve in the contact-zone computation.
    zone_opt_iter : int
        Sweeps of bounded local refinement (coordinate-wise parabolic steps inside
        the box) per refined sample and direction (0: corners only).
    zone_opt_samples : int
        Samples per curve and direction where the local refinement runs (those
        with the largest band).
    zone_max_corners : int
        Dependency sets with at most log2 of this many parameters get every box
        corner; larger ones get the corners the linear sensitivity marks as
        extreme at each sample, plus ``zone_random_corners`` seeded ones.
    zone_random_corners : int
        Extra seeded random corners for large dependency sets.
    zone_climb : int
        Samples per curve and direction where a corner hill-climb (one coordinate
        flipped at a time, kept while the curve moves further) runs where the
        linear guide fails: near trimmed curve ends, where the first-order extreme
        corner loses the contact (0: off).
    sim_step : float
        Driver step (rad) of the kinematic simulation's output sampling.
    batch_gap_band : float
        Batched defect margins (:mod:`cspace.batch.margins`): a channel margin
        within this of zero (C-space metric) is left to the full per-variant
        test.
    batch_dev_band : float
        The same for the deviation margin, relative to the deviation threshold d.
    """

    name: str = "default"
    chord: float = 2e-4
    max_step: float = 0.02
    root_tol: float = 1e-11
    scan_step: float = 0.01
    merge_rel: float = 1e-9
    contact_rel: float = 1e-7
    zone_samples: int = 48
    zone_opt_iter: int = 1
    zone_opt_samples: int = 1
    zone_max_corners: int = 64
    zone_random_corners: int = 8
    zone_climb: int = 4
    sim_step: float = 2e-3
    batch_gap_band: float = 1e-4
    batch_dev_band: float = 0.02

    def __post_init__(self):
        for f in dataclasses.fields(self):
            if f.name == "name":
                continue
            v = getattr(self, f.name)
            if f.type == "int" or isinstance(v, int) and not isinstance(v, bool):
                v = getint(v, f.name, minimum=0, label=f"Accuracy.{f.name}")
                object.__setattr__(self, f.name, v)
            else:
                try:
                    fv = float(v)
                except (TypeError, ValueError):
                    raise InputError(f"Accuracy.{f.name} must be a positive float, got {v!r}",
                                     name=f.name, value=v) from None
                if not (fv > 0.0 and fv < float("inf")):
                    raise InputError(
                        f"Accuracy.{f.name} must be a positive finite float, got {v!r}",
                        name=f.name, value=v)
        if self.zone_samples < 2:
            raise InputError(f"Accuracy.zone_samples must be >= 2, got {self.zone_samples}",
                             name="zone_samples", value=self.zone_samples)

    @classmethod
    def preset(cls, name: str) -> "Accuracy":
        """The named preset of this class: ``"fast"``, ``"default"`` or ``"precise"``."""
        presets = cls.presets()
        try:
            return presets[name]
        except (KeyError, TypeError):
            raise InputError(
                f"unknown accuracy preset {name!r}; allowed: {sorted(presets)}",
                name="preset", value=name) from None

    @classmethod
    def presets(cls) -> dict:
        """The named presets of this class (a subclass that adds knobs has its own)."""
        return PRESETS

    def replace(self, **changes) -> "Accuracy":
        """A copy with some fields changed (named ``"custom"`` unless given)."""
        changes.setdefault("name", "custom")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


PRESETS: dict[str, Accuracy] = {
    "fast": Accuracy(name="fast", chord=1e-3, max_step=0.04, root_tol=1e-9, scan_step=0.02,
                     zone_samples=24, zone_opt_iter=0, zone_opt_samples=0, zone_max_corners=32,
                     zone_random_corners=0, zone_climb=0,
                     sim_step=5e-3),
    "default": Accuracy(),
    "precise": Accuracy(name="precise", chord=2e-5, max_step=0.01, root_tol=1e-13,
                        scan_step=0.005, zone_samples=128, zone_opt_iter=2, zone_opt_samples=4,
                        zone_max_corners=256, zone_random_corners=32, zone_climb=12,
                        sim_step=5e-4),
}


def as_accuracy(acc) -> Accuracy:
    """Convert ``None`` / a preset name / an :class:`Accuracy` to an :class:`Accuracy`."""
    if acc is None:
        return PRESETS["default"]
    if isinstance(acc, Accuracy):
        return acc
    if isinstance(acc, str):
        return Accuracy.preset(acc)
    raise InputError(
        f"accuracy must be an Accuracy, a preset name {sorted(PRESETS)} or None; "
        f"got {type(acc).__name__}", name="accuracy", value=acc)


def same_geometry(a: Accuracy, b: Accuracy) -> bool:
    """Whether two accuracies set the same knobs of this class (a subclass's
    own knobs, such as the synthesis's, are not compared)."""
    return all(getattr(a, f.name) == getattr(b, f.name)
               for f in dataclasses.fields(Accuracy) if f.name != "name")
