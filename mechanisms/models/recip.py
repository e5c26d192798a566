"""A reciprocating cam pair (cm).

Cam (rotating about ``(cam_x, cam_y)``): a hub of radius ``hub_r`` with three
fingers at 0, 120 and 240 degrees; finger k ends in a round tip of radius
``tip_r`` centred ``f{k}`` from the axis, its sides tangent to the tip.

Follower (sliding along x): a yoke whose window has inclined inner faces.  The
right face runs from ``(xr_b, -H)`` to ``(xr_t, H)``, the left face from
``(xl_b, -H)`` to ``(xl_t, H)`` (H = 3 cm, beyond the fingers' reach).

Each finger in turn pushes one face, so the follower reciprocates six times per
cam turn: the free space is a row of cups opening up and down.  Between two cups
the cam is widest across the window and the free space narrows to a passage
about 0.09 cm wide; the +/-0.02 cm tolerances on eleven dimensions can
close it.

Closure: form closure (``Pair.bias = 0``).  The yoke moves only when a finger
pushes one of its faces.
"""

from __future__ import annotations

import math

import numpy as np

from cspace.errors import InvalidModelError
from cspace.geometry import Arc, Line, Loop, Pair, Part, Rotation, Translation

from .base import Model, Parameter

__all__ = ["reciprocating_cam", "RECIP_TOL"]

RECIP_TOL = 0.02  # cm
H = 3.0
OUT = 3.6


def _defaults():
    return [
        ("cam_x", 0.0, "cam axis x"),
        ("cam_y", 0.0, "cam axis y"),
        ("f0", 2.0, "finger 0 tip-centre distance"),
        ("f1", 2.0, "finger 1 tip-centre distance"),
        ("f2", 2.0, "finger 2 tip-centre distance"),
        ("tip_r", 0.5, "finger tip radius (half the finger width)"),
        ("hub_r", 1.0, "hub radius"),
        ("xr_b", 2.228, "right face x at the bottom"),
        ("xr_t", 2.328, "right face x at the top"),
        ("xl_b", -2.328, "left face x at the bottom"),
        ("xl_t", -2.228, "left face x at the top"),
    ]


def build_recip(v: dict) -> Pair:
    o = np.array([v["cam_x"], v["cam_y"]])
    rt, rh = v["tip_r"], v["hub_r"]
    if not rh > rt:
        raise InvalidModelError("reciprocating cam: hub_r must exceed tip_r")
    segs = []
    for k in range(3):
        a = 2 * math.pi * k / 3
        u = np.array([math.cos(a), math.sin(a)])
        n = np.array([-u[1], u[0]])
        f = v[f"f{k}"]
        base = math.sqrt(rh * rh - rt * rt)
        if f <= base:
            raise InvalidModelError(f"reciprocating cam: finger {k} is shorter than the hub")
        r0 = o + base * u - rt * n
        r1 = o + f * u - rt * n
        l1 = o + f * u + rt * n
        l0 = o + base * u + rt * n
        tc = o + f * u
        segs.append(Line(tuple(r0), tuple(r1), name=f"finger{k}.right"))
        segs.append(Arc(tuple(tc), rt, a - math.pi / 2, a + math.pi / 2, True, name=f"finger{k}.tip"))
        segs.append(Line(tuple(l1), tuple(l0), name=f"finger{k}.left"))
        an = 2 * math.pi * (k + 1) / 3
        un = np.array([math.cos(an), math.sin(an)])
        nn = np.array([-un[1], un[0]])
        nxt = o + base * un - rt * nn
        segs.append(Arc(tuple(o), rh, math.atan2(*(l0 - o)[::-1]), math.atan2(*(nxt - o)[::-1]),
                        True, name=f"hub{k}"))
    cam = Part("cam", (Loop(tuple(segs)),), Rotation(tuple(o)))
    xr_b, xr_t, xl_b, xl_t = v["xr_b"], v["xr_t"], v["xl_b"], v["xl_t"]
    outer = Loop((Line((-OUT, -OUT), (OUT, -OUT), name="frame.bottom"),
                  Line((OUT, -OUT), (OUT, OUT), name="frame.right"),
                  Line((OUT, OUT), (-OUT, OUT), name="frame.top"),
                  Line((-OUT, OUT), (-OUT, -OUT), name="frame.left")),)
    window = Loop((Line((xr_t, H), (xr_b, -H), name="face.right"),
                   Line((xr_b, -H), (xl_b, -H), name="window.bottom"),
                   Line((xl_b, -H), (xl_t, H), name="face.left"),
                   Line((xl_t, H), (xr_t, H), name="window.top")),)
    yoke = Part("yoke", (outer, window), Translation((1.0, 0.0), (0.0, 0.0)))
    return Pair(cam, yoke, units="cm", name="reciprocating_cam")


def reciprocating_cam(tol: float = RECIP_TOL) -> Model:
    """The built-in reciprocating cam: 11 parameters, +/- ``tol`` cm each;
    form-closed (the yoke moves only when pushed)."""
    params = tuple(Parameter(n, val, tol, desc) for n, val, desc in _defaults())
    return Model("reciprocating_cam", params, build_recip, units="cm",
                 description=__doc__.split("\n\n")[0],
                 window=(0.0, 2 * math.pi, -1.0, 1.0), drive=(0.0, 2 * math.pi), q2_start=(0.45,))
