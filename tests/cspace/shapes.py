"""Synthetic pairs that contain every planar contact type."""

import math

from cspace.geometry import Arc, Loop, Pair, Part, Rotation, Translation


def driver(scale=1.0):
    s = scale
    body = Loop.from_bulges([(0.6 * s, -0.5 * s), (1.8 * s, -0.5 * s), (1.8 * s, 0.5 * s),
                             (0.6 * s, 0.5 * s)], [0.0, 0.4, 0.0, -0.3],
                            names=["d.bot", "d.arc", "d.top", "d.notch"])
    pin = Loop((Arc((-1.6 * s, 0.0), 0.25 * s, 0.0, 2 * math.pi, name="pin"),))
    return Part("driver", (body, pin), Rotation((0.0, 0.0)))


def follower_loop(s=1.0, dx=0.0):
    return Loop.from_bulges([(1.7 * s + dx, -0.4 * s), (2.4 * s + dx, -0.4 * s),
                             (2.4 * s + dx, 0.4 * s), (1.7 * s + dx, 0.4 * s)],
                            [0.0, 0.3, 0.0, -0.5], names=["f.bot", "f.arc", "f.top", "f.cup"])


def knob(s=1.0, dx=0.0):
    return Loop((Arc((3.0 * s + dx, 1.3 * s), 0.2 * s, 0.0, 2 * math.pi, name="f.knob"),))


def rr_pair(scale=1.0):
    return Pair(driver(scale), Part("follower", (follower_loop(scale), knob(scale)),
                                    Rotation((3.0 * scale, 0.0))), units="mm", name="rr")


def rt_pair(scale=1.0):
    return Pair(driver(scale), Part("slider", (follower_loop(scale, 0.3 * scale),
                                               knob(scale, 0.3 * scale)),
                                    Translation((0.6, 0.8))), units="mm", name="rt")


ALL_KINDS = {"vertex-line", "line-vertex", "vertex-arc", "arc-vertex", "arc-line",
             "line-arc", "arc-arc-ext", "arc-arc-int"}
