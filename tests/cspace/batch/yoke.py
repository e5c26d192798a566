"""A Scotch yoke whose channel and motion have closed forms.

A crank of radius R carries a pin of radius r; the follower slides along x and
holds the pin between two vertical faces at x = s - w and x = s + w.  The pin
fits where ``R cos q1 + r - w <= s <= R cos q1 - r + w``: a channel of constant
width ``2 (w - r)`` (model units).  The follower rests until a face is pushed:
from the start s = R it follows the upper bound ``R cos q1 + (w - r)`` down to
q1 = pi, then rests at ``-R + (w - r)`` until the lower bound
``R cos q1 - (w - r)`` lifts it.
"""

import math

import numpy as np

from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation
from mechanisms.models import Model, Parameter

H = 40.0     # half height of the faces: the pin never reaches their ends
B = 5.0      # bar width


def build_yoke(v):
    R, r, w = v["crank"], v["pin_r"], v["half_width"]
    pin = Loop((Arc((R, 0.0), r, 0.0, 2 * math.pi, name="pin"),))
    left = Loop.from_bulges([(-w - B, -H), (-w, -H), (-w, H), (-w - B, H)],
                            names=["l.bot", "l.face", "l.top", "l.back"])
    right = Loop.from_bulges([(w, -H), (w + B, -H), (w + B, H), (w, H)],
                             names=["r.bot", "r.back", "r.top", "r.face"])
    return Pair(Part("crank", (pin,), Rotation((0.0, 0.0))),
                Part("yoke", (left, right), Translation((1.0, 0.0))), units="mm",
                name="yoke")


def yoke(R=20.0, r=5.0, w=5.03, t=0.02, deviation=None) -> Model:
    return Model("yoke", (Parameter("crank", R, t), Parameter("pin_r", r, t),
                          Parameter("half_width", w, t)), build_yoke, units="mm",
                 window=(0.0, 2 * math.pi, -R - 10.0, R + 10.0), drive=(0.0, 2 * math.pi),
                 q2_start=(R,), deviation=deviation)


def output(u, q1):
    """The closed-form motion s(q1) from s = R at q1 = 0 (model units)."""
    R, r, w = u
    c = w - r
    q1 = np.asarray(q1, dtype=float)
    down = np.minimum(R, R * np.cos(q1) + c)
    low = -R + c
    up = np.maximum(low, R * np.cos(q1) - c)
    return np.where(q1 <= math.pi, down, up)
