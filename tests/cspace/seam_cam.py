"""An eccentric disc cam drawn as two arcs joined at the top of the disc,
where the flat-faced follower rests when the drive starts (cm).

A turn of the cam is a motion that ends where it starts, and the contact hands
over from the right arc to the left one exactly at the drive's start.  The
face's slope (a parameter, 0 at nominal) moves that hand-over to just after
the start or just before the end: read as a line, every such variant's contact
sequence differs from the nominal's; read as a cycle it is the same."""

import math

from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from mechanisms.models.base import Model, Parameter

PARAMS = [("cam_x", 0.0), ("cam_y", 0.0), ("ecc", 0.5), ("disc_r", 2.0), ("face", 1.5),
          ("half_w", 0.6), ("thick", 0.8), ("slope", 0.0)]
TOL = {"slope": 0.02}


def build(v: dict) -> Pair:
    r, e, w, t, k = v["disc_r"], v["ecc"], v["half_w"], v["thick"], v["slope"]
    cx, cy, f = v["cam_x"], v["cam_y"], v["face"]
    left = Arc((cx, cy - e), r, math.pi / 2, 3 * math.pi / 2, True, name="left")
    right = Arc((cx, cy - e), r, 3 * math.pi / 2, 5 * math.pi / 2, True, name="right")
    cam = Part("cam", (Loop((left, right)),), Rotation((cx, cy)))
    block = Loop.from_bulges([(-w, f - k * w), (w, f + k * w), (w, f + t), (-w, f + t)],
                             [0.0] * 4, ["face", "side.right", "back", "side.left"])
    follower = Part("follower", (block,), Translation((0.0, 1.0), (0.0, f)))
    return Pair(cam, follower, units="cm", name="seam_cam", bias=-1)


def seam_cam() -> Model:
    params = tuple(Parameter(n, val, TOL.get(n, 0.01), n) for n, val in PARAMS)
    return Model("seam_cam", params, build, units="cm", window=(0.0, 2 * math.pi, -0.5, 2.0),
                 drive=(0.0, 2 * math.pi), q2_start=(1.0,), deviation=0.012)
