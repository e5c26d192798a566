"""Named numeric tolerances shared by the C-space modules, with the reason for each.

These are not approximation knobs: they do not trade time for accuracy, so they
are not fields of :class:`cspace.accuracy.Accuracy`.  They say when two floating
point numbers are the same number, when a denominator is zero, and how far a
probe stays inside an interval.  Each is far below any manufacturing tolerance
(1e-9 of a 100 mm part is 0.1 nm) and far above the rounding it absorbs.

Module-specific ones live beside their use with the same kind of note:
:data:`cspace.features.STRAIGHT`, :data:`cspace.equations.VERTICAL_REL`,
:data:`cspace.geometry.VALIDATION_REL`, :data:`cspace.freespace.NODE_Q2_TOL`,
:data:`cspace.batch.plan.VALID_TOL` and the private ``_TIE``/``_SLACK`` values of
the simulation, zones and pruning.
"""

from __future__ import annotations

__all__ = ["TINY", "ROUNDING", "SLACK", "NEAR_PARALLEL", "FULL_CIRCLE_SLACK", "PARALLEL_REL",
           "PROBE_REL", "FD_REL", "EQUAL_REL"]

#: Guard for a denominator or a scale that may be exactly 0: ``max(x, TINY)``
#: keeps a quotient finite without changing any quotient of a nonzero x (the
#: smallest normal double is 2.2e-308).
TINY = 1e-300

#: Absolute slack for order-one quantities (radians, unit-vector lengths,
#: interval parameters in [0, 1]) that agree up to rounding: about 5000 units
#: in the last place at 1, the rounding of a few dozen operations.
ROUNDING = 1e-12

#: Slack relative to a part's size (or absolute for radians) for quantities that
#: went through chains of trigonometric evaluations and root refinement: the
#: floor of a contact or merge tolerance, the pad of a bounding box, the margin
#: a curve value may lie beyond the bound it equals.
SLACK = 1e-9

#: A point-on-line contact whose line is within this (the cosine of the angle
#: between its normal and the slide direction) of parallel to the follower's
#: slide has no contact position: the solution would run off to infinity.
NEAR_PARALLEL = 1e-9

#: An arc whose half sweep is within this (rad) of pi is a full circle: every
#: angle lies on it.  Below the rounding of an arc's end angles, which come
#: from atan2 of its end points.
FULL_CIRCLE_SLACK = 1e-15

#: Two segments are parallel when the sine of the angle between them is below
#: this: their cross product is within rounding of 0 relative to their lengths.
PARALLEL_REL = 1e-14

#: Step of a one-sided finite difference or inset from an interval's end,
#: relative to the interval or to the coordinate's scale: above the square root
#: of machine epsilon (1.5e-8), so rounding does not swamp the difference.
PROBE_REL = 1e-7

#: Step of a central finite difference of a margin along a curve, relative to
#: the sampled range: the truncation error (h**2) and the rounding (eps / h)
#: are then both below 1e-10.
FD_REL = 1e-6

#: Two values are the same value when they differ by less than this relative to
#: their scale: a few units in the last place, so only numbers that were meant
#: to be equal (a box corner and the coordinate it came from) compare equal.
EQUAL_REL = 1e-15
