"""A four-slot external Geneva pair (cm).

Driver (rotating about ``(drv_x, drv_y)``): a pin of radius ``pin_r`` on a crank of
radius ``crank``, pointing at angle pi at q = 0, and a locking disk of radius
``lock_r`` with a relief cut (a concave arc of radius ``relief_r`` centred
``relief_d`` from the axis on the pin side).

Wheel (rotating about ``(whl_x, whl_y)``): four radial slots at 45 + 90 k degrees,
each with its own half-widths ``s{k}_wl`` (left, counter-clockwise side) and
``s{k}_wr`` (right) and a round bottom whose centre lies ``s{k}_depth`` from the
wheel axis; between the slots four concave locking arcs of radius ``lock{k}_r``
centred ``lock_cd`` from the wheel axis (at 90 k degrees).

At q = (0, 0) the wheel is locked: locking arc 2 embraces the locking disk.  One
driver turn counter-clockwise indexes the wheel by -pi/2 (clockwise): the pin
enters slot 2 at q1 = 3 pi/4 and leaves slot 2 at 5 pi/4.  The model's drive is
four turns, the wheel's full cycle: slots 2, 3, 0 and 1 index in turn, so that
every slot's motion is simulated and compared by the defect test.

The design is marginal where the pin has just entered (and is about to leave) the
slot: the wheel tips must pass through the relief while the locking disk still
guards the locking arcs, and some variants in the +/-0.018 cm tolerance box
close that channel (about one random box corner in six at the nominal relief
radius 3.26 cm).

The model's output-deviation threshold is d = 0.06 rad.  In a dwell the
locking arc holds the wheel in a channel 0.0898 rad wide (+/-0.0449 rad about
the locked pose: the wheel turns until a wheel tip touches the locking disk),
and a quasi-static wheel rests where the pin left it, so a variant's output
there differs from the nominal's by how differently the two were left, not by
the play.

Closure: form closure (``Pair.bias = 0``).  The wheel moves only when the pin
or the locking disk pushes it; in the lock play it rests where it was left.
"""

from __future__ import annotations

import math

import numpy as np

from cspace.errors import InvalidModelError
from cspace.geometry import Arc, Line, Loop, Pair, Part, Rotation

from .base import Model, Parameter

__all__ = ["geneva", "GENEVA_TOL"]

GENEVA_TOL = 0.018  # cm

C = 5.0
A = C / math.sqrt(2.0)


def _defaults():
    p = [
        ("drv_x", 0.0, "driver axis x"),
        ("drv_y", 0.0, "driver axis y"),
        ("whl_x", C, "wheel axis x"),
        ("whl_y", 0.0, "wheel axis y"),
        ("crank", A, "crank radius (driver axis to pin centre)"),
        ("pin_r", 0.30, "pin radius"),
        ("lock_r", 3.13, "locking disk radius"),
        ("relief_d", 5.00, "relief arc centre distance from the driver axis"),
        ("relief_r", 3.26, "relief arc radius"),
        ("lock_cd", C, "locking arc centre distance from the wheel axis"),
    ]
    for k in range(4):
        p.append((f"lock{k}_r", 3.25, f"locking arc {k} radius"))
    for k in range(4):
        p.append((f"s{k}_wl", 0.36, f"slot {k} half-width, counter-clockwise side"))
        p.append((f"s{k}_wr", 0.36, f"slot {k} half-width, clockwise side"))
        p.append((f"s{k}_depth", 1.20, f"slot {k} bottom-centre distance from the wheel axis"))
    return p


def circle_intersections(c1, r1, c2, r2):
    """Both intersections of two circles (raises InvalidModelError if none).

    Shared by the Geneva and optical-filter builders for the locking-disk relief.
    The scalar form of :func:`cspace.geom2d.radical_foot`, kept apart so that
    the built-in models' geometry stays bit for bit what their case studies
    were computed with (``math.hypot`` here, ``numpy.hypot`` there).
    """
    c1, c2 = np.asarray(c1, float), np.asarray(c2, float)
    d = c2 - c1
    D = math.hypot(*d)
    a = (D * D + r1 * r1 - r2 * r2) / (2 * D)
    h2 = r1 * r1 - a * a
    if D == 0 or h2 <= 0:
        raise InvalidModelError(
            f"the relief and locking disk circles do not intersect (centres {D:.6g} apart, "
            f"radii {r1:.6g} and {r2:.6g}); they must cross, so that the relief cuts the disk")
    h = math.sqrt(h2)
    u = d / D
    n = np.array([-u[1], u[0]])
    return c1 + a * u + h * n, c1 + a * u - h * n


def angle_about(p, c):
    """Polar angle (rad) of point ``p`` about centre ``c``."""
    return math.atan2(p[1] - c[1], p[0] - c[0])


def build_geneva(v: dict) -> Pair:
    oa = np.array([v["drv_x"], v["drv_y"]])
    ob = np.array([v["whl_x"], v["whl_y"]])
    a, rp = v["crank"], v["pin_r"]
    pin_c = oa + a * np.array([-1.0, 0.0])
    pin = Loop((Arc(tuple(pin_c), rp, 0.0, 2 * math.pi, name="pin"),))
    rl, rd, rr = v["lock_r"], v["relief_d"], v["relief_r"]
    rc = oa + rd * np.array([-1.0, 0.0])
    x_up, x_lo = circle_intersections(oa, rl, rc, rr)
    if x_up[1] < x_lo[1]:
        x_up, x_lo = x_lo, x_up
    disk = Loop((Arc(tuple(oa), rl, angle_about(x_lo, oa), angle_about(x_up, oa), True,
                     name="lock_disk"),
                 Arc(tuple(rc), rr, angle_about(x_up, rc), angle_about(x_lo, rc), False,
                     name="relief")),
                )
    driver = Part("driver", (pin, disk), Rotation(tuple(oa)))

    segs = []
    cd = v["lock_cd"]
    centers = [ob + cd * np.array([math.cos(k * math.pi / 2), math.sin(k * math.pi / 2)])
               for k in range(4)]

    def rim(k, side):
        psi = math.pi / 4 + k * math.pi / 2
        u = np.array([math.cos(psi), math.sin(psi)])
        vv = np.array([-math.sin(psi), math.cos(psi)])
        s = v[f"s{k}_wl"] if side > 0 else -v[f"s{k}_wr"]
        j = (k + 1) % 4 if side > 0 else k
        m = ob + s * vv - centers[j]
        R = v[f"lock{j}_r"]
        mu = float(m @ u)
        disc = mu * mu - float(m @ m) + R * R
        if disc <= 0:
            raise InvalidModelError(f"geneva: slot {k} side does not meet locking arc {j}")
        t = -mu - math.sqrt(disc)
        if t <= v[f"s{k}_depth"]:
            raise InvalidModelError(f"geneva: slot {k} is deeper than its mouth")
        return ob + t * u + s * vv, u, vv, s

    for k in range(4):
        psi = math.pi / 4 + k * math.pi / 2
        d = v[f"s{k}_depth"]
        wl, wr = v[f"s{k}_wl"], v[f"s{k}_wr"]
        pr, u, vv, _ = rim(k, -1)
        pl, _, _, _ = rim(k, +1)
        br = ob + d * u - wr * vv
        bl = ob + d * u + wl * vv
        bc = ob + d * u + 0.5 * (wl - wr) * vv
        segs.append(Line(tuple(pr), tuple(br), name=f"slot{k}.right"))
        segs.append(Arc(tuple(bc), 0.5 * (wl + wr), psi - math.pi / 2, psi - 3 * math.pi / 2,
                        False, name=f"slot{k}.bottom"))
        segs.append(Line(tuple(bl), tuple(pl), name=f"slot{k}.left"))
        j = (k + 1) % 4
        nxt, _, _, _ = rim(j, -1)
        segs.append(Arc(tuple(centers[j]), v[f"lock{j}_r"], angle_about(pl, centers[j]),
                        angle_about(nxt, centers[j]), False, name=f"lock{j}"))
    wheel = Part("wheel", (Loop(tuple(segs)),), Rotation(tuple(ob)))
    return Pair(driver, wheel, units="cm", name="geneva")


def geneva(tol: float = GENEVA_TOL) -> Model:
    """The built-in Geneva model: 26 parameters, tolerance +/- ``tol`` cm each;
    form-closed (the wheel moves only when pushed)."""
    params = tuple(Parameter(n, val, tol, desc) for n, val, desc in _defaults())
    return Model("geneva", params, build_geneva, units="cm",
                 description=__doc__.split("\n\n")[0],
                 window=(0.0, 2 * math.pi, -math.pi, math.pi), drive=(0.0, 8 * math.pi),
                 q2_start=(0.0,), deviation=0.06)
