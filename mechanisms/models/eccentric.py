"""An eccentric disc cam under a spring-loaded flat-faced follower (cm).

Cam (rotating about ``(cam_x, cam_y)``): a circular disc of radius ``disc_r``
whose centre lies ``ecc`` from the axis, straight below it at q1 = 0.

Follower (sliding along y): a block ``2 half_w`` wide and ``thick`` thick whose
flat face lies at height ``face`` at q2 = 0.  A spring holds it down on the cam
(``Pair.bias = -1``, force closure), so it rises and falls with the disc.

While the disc touches the face, the lift has the closed form of a circular-arc
cam under a flat follower: at driver angle q1 the disc centre lies at
``(cam_x + ecc sin q1, cam_y - ecc cos q1)``, its top at ``disc_r`` above that,
so ``q2(q1) = cam_y + disc_r - face - ecc cos q1``.  At the nominal (``face =
cam_y + disc_r - ecc``) that is ``ecc (1 - cos q1)``: a harmonic lift of stroke
``2 ecc`` = 1 cm.  The contact point runs along the face to ``cam_x +/- ecc``.

The face (1.2 cm wide) is wider than the contact's travel (1 cm) by far more
than the tolerances move either, so the disc never runs off it in the box.

The design is marginal in its lift: the model's deviation threshold d = 0.012
(C-space metric: 0.03 cm of lift over the characteristic length 2.5 cm, the
cam's reach) lies below what four +/-0.01 cm dimensions (``cam_y``,
``disc_r``, ``face``, ``ecc``) can add up to, 0.04 cm, so some corners of the
box lift the follower wrongly.  Shifting the nominal cannot help (the defect
test compares a variant's lift with the nominal design's, which moves with
it); synthesis cuts tolerances.
"""

from __future__ import annotations

import math

from cspace.errors import InvalidModelError
from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation

from .base import Model, Parameter

__all__ = ["eccentric_cam", "ECCENTRIC_TOL"]

ECCENTRIC_TOL = 0.01  # cm


def _defaults():
    return [
        ("cam_x", 0.0, "cam axis x"),
        ("cam_y", 0.0, "cam axis y"),
        ("ecc", 0.5, "eccentricity: disc centre distance from the cam axis"),
        ("disc_r", 2.0, "disc radius"),
        ("face", 1.5, "follower face height at q2 = 0"),
        ("half_w", 0.6, "follower face half-width"),
        ("thick", 0.8, "follower thickness"),
    ]


def build_eccentric(v: dict) -> Pair:
    r, e, w, t = v["disc_r"], v["ecc"], v["half_w"], v["thick"]
    if not (r > e >= 0.0):
        raise InvalidModelError(f"eccentric cam: need disc_r > ecc >= 0 (the axis inside "
                                f"the disc), got disc_r = {r}, ecc = {e}")
    if not (w > 0.0 and t > 0.0):
        raise InvalidModelError(f"eccentric cam: the follower needs half_w > 0 and thick > 0, "
                                f"got {w} and {t}")
    cx, cy, f = v["cam_x"], v["cam_y"], v["face"]
    disc = Arc((cx, cy - e), r, -math.pi / 2, 3 * math.pi / 2, True, name="disc")
    cam = Part("cam", (Loop((disc,)),), Rotation((cx, cy)))
    block = Loop.from_bulges([(-w, f), (w, f), (w, f + t), (-w, f + t)], [0.0] * 4,
                             ["face", "side.right", "back", "side.left"])
    follower = Part("follower", (block,), Translation((0.0, 1.0), (0.0, f)))
    return Pair(cam, follower, units="cm", name="eccentric_cam", bias=-1)


def eccentric_cam(tol: float = ECCENTRIC_TOL) -> Model:
    """The built-in eccentric cam: 7 parameters, +/- ``tol`` cm each; the
    follower is spring-loaded (held toward decreasing q2)."""
    params = tuple(Parameter(n, val, tol, desc) for n, val, desc in _defaults())
    return Model("eccentric_cam", params, build_eccentric, units="cm",
                 description=__doc__.split("\n\n")[0],
                 window=(0.0, 2 * math.pi, -0.5, 2.0), drive=(0.0, 2 * math.pi),
                 q2_start=(1.0,), deviation=0.012)
