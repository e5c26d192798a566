"""Optical-filter cam mechanism (cm): three identical cam/follower pairs on one shaft.

Each cam (rotating about ``(drv_x, drv_y)``) carries a pin of radius ``pin_r`` on a
crank of radius ``crank`` and a locking disk of radius ``lock_r`` with a relief cut
(radius ``relief_r``, centred ``relief_d`` from the axis on the pin side).  The
three cams are the same profile turned by 0, 90 and 180 degrees on the shaft.

Each follower is a lever pivoted at ``(piv_x, piv_y)`` carrying a filter.  It has
one slot (half-widths ``slot_wl``/``slot_wr``, bottom centre ``slot_depth`` from the
pivot) between two concave locking faces A and B (radii ``lockA_r``/``lockB_r``,
centred ``lockA_cd``/``lockB_cd`` from the pivot), and a back arc of radius
``arm_r`` about the pivot.

Turning the cam counter-clockwise, the pin enters the slot and swings the follower
clockwise by 90 degrees; when the pin leaves, the cam's outer surface locks the
follower's face B and the filter stays over the lens.  Turning back returns it.
The three followers swing in windows staggered by 90 degrees of cam rotation.

Closure: form closure (``Pair.bias = 0``) for all three pairs.  A follower
moves only when its cam's pin or outer surface pushes it.
"""

from __future__ import annotations

import math

import numpy as np

from cspace.errors import InvalidModelError
from cspace.geometry import Arc, Assembly, Line, Loop, Pair, Part, Rotation

from .base import Model, Parameter
from .geneva import angle_about, circle_intersections

__all__ = ["optical_filter", "OPTICAL_TOL", "PHASES"]

OPTICAL_TOL = 0.002  # cm
PHASES = (0.0, math.pi / 2, math.pi)
CD = 2.0


def _defaults():
    a = CD / math.sqrt(2)
    return [
        ("drv_x", 0.0, "cam shaft x"),
        ("drv_y", 0.0, "cam shaft y"),
        ("piv_x", CD, "follower pivot x"),
        ("piv_y", 0.0, "follower pivot y"),
        ("crank", a, "crank radius (shaft to pin centre)"),
        ("pin_r", 0.12, "pin radius"),
        ("lock_r", 1.236, "locking disk radius"),
        ("relief_d", CD, "relief arc centre distance from the shaft"),
        ("relief_r", 1.32, "relief arc radius"),
        ("lockA_cd", CD, "locking face A centre distance from the pivot"),
        ("lockB_cd", CD, "locking face B centre distance from the pivot"),
        ("lockA_r", 1.28, "locking face A radius"),
        ("lockB_r", 1.28, "locking face B radius"),
        ("slot_wl", 0.144, "slot half-width, counter-clockwise side"),
        ("slot_wr", 0.144, "slot half-width, clockwise side"),
        ("slot_depth", 0.48, "slot bottom-centre distance from the pivot"),
        ("arm_r", 1.5, "back arc radius about the pivot"),
    ]


def _cam(v: dict, phase: float, name: str) -> Part:
    oa = np.array([v["drv_x"], v["drv_y"]])
    d = np.array([math.cos(math.pi + phase), math.sin(math.pi + phase)])
    pin_c = oa + v["crank"] * d
    pin = Loop((Arc(tuple(pin_c), v["pin_r"], 0.0, 2 * math.pi, name="pin"),))
    rc = oa + v["relief_d"] * d
    p1, p2 = circle_intersections(oa, v["lock_r"], rc, v["relief_r"])
    # p1 lies left of oa->rc; the disk runs ccw from p1 round the far side to p2
    disk = Loop((Arc(tuple(oa), v["lock_r"], angle_about(p1, oa), angle_about(p2, oa), True,
                     name="lock_disk"),
                 Arc(tuple(rc), v["relief_r"], angle_about(p2, rc), angle_about(p1, rc), False,
                     name="relief")),
                )
    return Part(name, (pin, disk), Rotation(tuple(oa)))


def _follower(v: dict, name: str) -> Part:
    ob = np.array([v["piv_x"], v["piv_y"]])
    psi = 5 * math.pi / 4
    u = np.array([math.cos(psi), math.sin(psi)])
    vv = np.array([-math.sin(psi), math.cos(psi)])
    ma = ob + v["lockA_cd"] * np.array([-1.0, 0.0])
    mb = ob + v["lockB_cd"] * np.array([0.0, -1.0])
    ra, rb = v["lockA_r"], v["lockB_r"]
    wl, wr, dep = v["slot_wl"], v["slot_wr"], v["slot_depth"]

    def rim(s, m, R):
        mm = ob + s * vv - m
        mu = float(mm @ u)
        disc = mu * mu - float(mm @ mm) + R * R
        if disc <= 0:
            raise InvalidModelError("optical filter: slot side does not meet its locking face")
        t = -mu - math.sqrt(disc)
        if t <= dep:
            raise InvalidModelError("optical filter: slot is deeper than its mouth")
        return ob + t * u + s * vv

    pr = rim(-wr, ma, ra)
    pl = rim(wl, mb, rb)
    qa1, qa2 = circle_intersections(ob, v["arm_r"], ma, ra)
    qa = qa1 if qa1[1] > qa2[1] else qa2
    qb1, qb2 = circle_intersections(ob, v["arm_r"], mb, rb)
    qb = qb1 if qb1[0] > qb2[0] else qb2
    br = ob + dep * u - wr * vv
    bl = ob + dep * u + wl * vv
    bc = ob + dep * u + 0.5 * (wl - wr) * vv
    segs = (
        Arc(tuple(ma), ra, angle_about(qa, ma), angle_about(pr, ma), False, name="faceA"),
        Line(tuple(pr), tuple(br), name="slot.right"),
        Arc(tuple(bc), 0.5 * (wl + wr), psi - math.pi / 2, psi - 3 * math.pi / 2, False,
            name="slot.bottom"),
        Line(tuple(bl), tuple(pl), name="slot.left"),
        Arc(tuple(mb), rb, angle_about(pl, mb), angle_about(qb, mb), False, name="faceB"),
        Arc(tuple(ob), v["arm_r"], angle_about(qb, ob), angle_about(qa, ob), True, name="back"),
    )
    return Part(name, (Loop(segs),), Rotation(tuple(ob)))


def build_optical(v: dict) -> Assembly:
    pairs = []
    for i, ph in enumerate(PHASES):
        pairs.append(Pair(_cam(v, ph, f"cam{i + 1}"), _follower(v, f"follower{i + 1}"),
                          units="cm", name=f"filter{i + 1}"))
    return Assembly(tuple(pairs), name="optical_filter")


def optical_filter(tol: float = OPTICAL_TOL) -> Model:
    """The built-in optical-filter mechanism: 17 parameters, +/- ``tol`` cm each;
    form-closed (each follower moves only when its cam pushes it)."""
    params = tuple(Parameter(n, val, tol, desc) for n, val, desc in _defaults())
    return Model("optical_filter", params, build_optical, units="cm",
                 description=__doc__.split("\n\n")[0],
                 window=(-math.pi / 2, 3 * math.pi / 2, 0.0, 2 * math.pi),
                 drive=(-math.pi / 2, 3 * math.pi / 2), q2_start=(0.0, 0.0, 0.0),
                 deviation=0.012)
