"""Ready-made loops: RCCC, RSSR, spherical 4R and the planar four-bar.

Each builder lays out the joint axes in ground coordinates at the start input,
assembles the loop there in closed form (on the stated branch), and reads the HD
parameters off the frames with :func:`hd_from_frames`.  The HD solver never sees
the closed form again: the tests compare its continuation over a revolution with the
closed-form input-output equations in :mod:`.closedform`.

Ground frame (frame 0) is the input joint's frame; :attr:`Linkage.ground` is its pose
in world coordinates (the identity for every builder here, so the HD input angle is
the world input angle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cspace.argcheck import getangle, getscalar
from cspace.errors import InputError, InvalidModelError
from cspace.geom2d import IntersectionKind, angle_spans, circle_circle

from . import closedform as cf
from .loops import Joint, JointType, Loop, make_loop

__all__ = ["Linkage", "hd_from_frames", "planar_fourbar", "spherical_4r", "rccc", "rssr"]

#: Largest inconsistency (relative to the length scale) accepted between a frame
#: layout and the HD rules; layouts are built in closed form, so only rounding remains.
_LAYOUT_TOL = 1e-9


@dataclass(frozen=True)
class Linkage:
    """A built loop with its start pose.

    Attributes
    ----------
    name : str
    loop : Loop
    q0 : (n_vars,) float
        Closed pose at the start input (the loop's reference values).
    output : int
        Index of the output variable (the last joint's theta).
    ground : (4, 4) float
        World pose of frame 0.
    params : dict
        The builder's arguments (SI-free: model units, rad).
    """

    name: str
    loop: Loop
    q0: np.ndarray
    output: int
    ground: np.ndarray = field(repr=False)
    params: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return f"Linkage({self.name}, {self.loop.signature()}, n_vars={self.loop.n_vars})"

    def to_dict(self) -> dict:
        return {"name": self.name, "loop": self.loop.to_dict(), "q0": self.q0.tolist(),
                "output": self.output, "ground": self.ground.tolist(), "params": dict(self.params)}


def _unit(v):
    n = np.linalg.norm(v)
    if n < 1e-12:
        raise InvalidModelError(f"degenerate layout: zero-length direction {v}")
    return v / n


def hd_from_frames(origins, z, x, *, length_scale: float = 1.0):
    """HD rows ``(a_i, alpha_i, theta_i, s_i)`` of a closed chain of frames.

    Parameters
    ----------
    origins, z, x : (n, 3) float
        Origin, unit z (joint axis) and unit x of each frame in one common frame.
        Frame ``i + 1`` (cyclically) must satisfy the HD rules: ``x_{i+1}`` is
        perpendicular to ``z_i`` and ``z_{i+1}``, and ``o_{i+1} - o_i`` lies in the span
        of ``z_i`` and ``x_{i+1}``.

    Returns
    -------
    (n, 4) float
        Rows ``(a, alpha, theta, s)``.

    Raises
    ------
    InvalidModelError
        When the frames break the HD rules (beyond rounding).
    """
    o = np.asarray(origins, float)
    z = np.asarray(z, float)
    x = np.asarray(x, float)
    n = len(o)
    rows = np.zeros((n, 4))
    for i in range(n):
        j = (i + 1) % n
        bad = max(abs(x[j] @ z[i]), abs(x[j] @ z[j]))
        d = o[j] - o[i]
        s = d @ z[i]
        a = d @ x[j]
        off = np.linalg.norm(d - s * z[i] - a * x[j]) / length_scale
        if bad > _LAYOUT_TOL or off > _LAYOUT_TOL:
            raise InvalidModelError(
                f"frames {i}->{j} break the HD rules: x_{j} must be normal to z_{i} and z_{j} "
                f"(|dot| = {bad:.2e}) and o_{j} - o_{i} must lie in span(z_{i}, x_{j}) "
                f"(off by {off:.2e}); allowed: {_LAYOUT_TOL:g}")
        al = math.atan2(np.cross(z[i], z[j]) @ x[j], z[i] @ z[j])
        th = math.atan2(np.cross(x[i], x[j]) @ z[i], x[i] @ x[j])
        rows[i] = (a, al, th, s)
    return rows


def _joints_from_rows(rows, kinds, names):
    """Group HD rows into user joints (S takes three rows)."""
    joints, k = [], 0
    for kind, nm in zip(kinds, names):
        if kind == "S":
            r0, r1, r2 = rows[k], rows[k + 1], rows[k + 2]
            for r in (r0, r1):
                if abs(r[0]) > _LAYOUT_TOL or abs(r[1] - math.pi / 2) > 1e-9 or (r is r1 and abs(r[3]) > _LAYOUT_TOL):
                    raise InvalidModelError("an S joint's first two frames need a = 0, alpha = 90 deg")
            if abs(r2[3]) > _LAYOUT_TOL:
                raise InvalidModelError("an S joint's last frame needs s = 0")
            joints.append(Joint(JointType.S, a=r2[0], alpha=r2[1], theta=(r0[2], r1[2], r2[2]),
                                s=r0[3], name=nm))
            k += 3
        else:
            r = rows[k]
            joints.append(Joint(JointType(kind), a=r[0], alpha=r[1], theta=r[2], s=r[3], name=nm))
            k += 1
    return joints


def _finish(name, o, z, x, kinds, names, *, idle, params, L):
    rows = hd_from_frames(o, z, x, length_scale=L)
    loop = make_loop(_joints_from_rows(rows, kinds, names), idle_dof=idle, length_scale=L)
    ground = np.eye(4)
    ground[:3, 0] = x[0]
    ground[:3, 2] = z[0]
    ground[:3, 1] = np.cross(z[0], x[0])
    ground[:3, 3] = o[0]
    q0 = loop.reference_q()
    return Linkage(name=name, loop=loop, q0=q0, output=loop.n_vars - 1 if kinds[-1] != "C"
                   else loop.n_vars - 2, ground=ground, params=params)


def _branch(branch):
    if branch not in (1, -1):
        raise InputError(f"branch must be +1 or -1; got {branch!r}", name="branch", value=branch)
    return int(branch)


# ----------------------------------------------------------------------------- planar

def _where_it_assembles(closes, n: int = 720) -> str:
    """The end of a "cannot be assembled at theta" message: where over a turn
    of the input the loop does close (``closes(theta) -> bool``, sampled
    ``n`` times), or that it closes nowhere (its dimensions, not its start
    angle, are at fault)."""
    t = np.linspace(-math.pi, math.pi, n, endpoint=False)
    ok = np.array([bool(closes(float(v))) for v in t])
    if not ok.any():
        return (f"; it assembles at no input angle ({n} tried over a turn): the dimensions "
                "do not close the loop")
    return f"; choose a start angle where it assembles: {', '.join(angle_spans(t, ok))}"


def planar_fourbar(crank, coupler, rocker, ground, theta, *, branch: int = 1,
                   unit: str = "rad") -> Linkage:
    """Planar four-bar A-B-C-D as an RRRR loop with parallel axes (alpha = 0, s = 0).

    World layout: ground pivots A = (0, 0), D = (ground, 0); crank AB at angle
    ``theta`` from AD; C is the intersection of the circles about B (radius coupler)
    and D (radius rocker) on side ``branch`` of B -> D (the convention of
    :func:`cspace.geom2d.circle_circle`: +1 = left).  The output is the rocker angle
    of DC, read from the frames (see :func:`.closedform.freudenstein`).
    """
    a, b, c, d = (getscalar(v, n, positive=True) for v, n in
                  ((crank, "crank"), (coupler, "coupler"), (rocker, "rocker"), (ground, "ground")))
    th = getangle(theta, unit, "theta")
    br = _branch(branch)
    A, D = np.zeros(2), np.array([d, 0.0])
    B = a * np.array([math.cos(th), math.sin(th)])
    C, kind = circle_circle(B, b, D, c, br)
    if int(kind) in (IntersectionKind.NONE, IntersectionKind.COINCIDENT):
        def closes(t):
            Bt = a * np.array([math.cos(t), math.sin(t)])
            return int(circle_circle(Bt, b, D, c, br)[1]) not in (IntersectionKind.NONE,
                                                                  IntersectionKind.COINCIDENT)
        raise InvalidModelError(f"the four-bar ({a}, {b}, {c}, {d}) cannot be assembled at "
                                f"theta = {th} rad{_where_it_assembles(closes)}")
    P = [np.append(A, 0.0), np.append(B, 0.0), np.append(C, 0.0), np.append(D, 0.0)]
    o = np.array(P)
    z = np.tile([0.0, 0.0, 1.0], (4, 1))
    # x_i is the common normal from axis i-1 to axis i: the link direction into joint i,
    # except x_0 = +x (world) so that the HD input is the world crank angle; the ground
    # link D -> A then has the signed length a_3 = -ground.
    x = np.array([[1.0, 0.0, 0.0]] + [_unit(o[i] - o[i - 1]) for i in range(1, 4)])
    return _finish("planar four-bar", o, z, x, "RRRR", ["A", "B", "C", "D"], idle=0,
                   params=dict(crank=a, coupler=b, rocker=c, ground=d, theta=th, branch=br),
                   L=max(a, b, c, d))


# --------------------------------------------------------------------------- spherical

def _spherical_axes(al, th, br):
    """Axes z_0..z_3 and x_0..x_3 of a spherical 4R with twists ``al`` at input ``th``."""
    a0, a1, a2, a3 = al
    z0 = np.array([0.0, 0.0, 1.0])
    x0 = np.array([1.0, 0.0, 0.0])
    z3 = np.array([0.0, math.sin(a3), math.cos(a3)])
    z1 = np.array([math.sin(th) * math.sin(a0), -math.cos(th) * math.sin(a0), math.cos(a0)])
    psi, ok = cf.spherical_4r_psi(al, th, br)
    if not ok:
        where = _where_it_assembles(lambda t: cf.spherical_4r_psi(al, t, br)[1])
        raise InvalidModelError(f"the spherical 4R with twists {list(al)} cannot be assembled at "
                                f"theta = {th} rad{where}")
    z2 = cf.spherical_4r_z2(al, psi)
    z = np.array([z0, z1, z2, z3])
    x = [x0]
    for i in range(1, 4):
        x.append(np.cross(z[i - 1], z[i]) / math.sin(al[i - 1]))
    return z, np.array(x)


def _twists(alphas, unit):
    if len(alphas) != 4:
        raise InputError(f"alphas must be 4 twist angles; got {alphas!r}", name="alphas", value=alphas)
    al = tuple(getangle(v, unit, f"alphas[{i}]") for i, v in enumerate(alphas))
    for i, v in enumerate(al):
        if not 1e-6 < v < math.pi - 1e-6:
            raise InputError(f"alphas[{i}] must lie strictly between 0 and 180 deg; got {alphas[i]!r}",
                             name="alphas", value=alphas)
    return al


def spherical_4r(alphas, theta, *, branch: int = 1, unit: str = "rad") -> Linkage:
    """Spherical 4R: four revolute axes through one point (a = s = 0).

    Parameters
    ----------
    alphas : 4 angles
        Twists (arc lengths) of input link, coupler, output link and ground, in
        (0, 180 deg).
    theta : float
        Start input angle (HD theta_0, measured from the ground's common normal).
    branch : +1 or -1
        Root of the input-output equation (:func:`.closedform.spherical_4r_psi`).
    """
    al = _twists(alphas, unit)
    th = getangle(theta, unit, "theta")
    br = _branch(branch)
    z, x = _spherical_axes(al, th, br)
    o = np.zeros((4, 3))
    return _finish("spherical 4R", o, z, x, "RRRR", ["R0", "R1", "R2", "R3"], idle=0,
                   params=dict(alphas=al, theta=th, branch=br), L=1.0)


def rccc(alphas, lengths, s0, theta, *, branch: int = 1, unit: str = "rad") -> Linkage:
    """RCCC: a revolute input and three cylindrical joints ([Kim 1985] Figs. 3-5).

    Parameters
    ----------
    alphas : 4 angles
        Twists alpha_0..alpha_3 (rad, or deg with ``unit="deg"``).
    lengths : 4 floats, length
        Common-normal lengths a_0..a_3.
    s0 : float, length
        Fixed offset of the input revolute.
    theta : float
        Start input angle.
    branch : +1 or -1
        Assembly branch (that of the spherical indicatrix, :func:`.closedform.rccc`).
    """
    al = _twists(alphas, unit)
    if len(lengths) != 4:
        raise InputError(f"lengths must be 4 numbers; got {lengths!r}", name="lengths", value=lengths)
    a = tuple(getscalar(v, f"lengths[{i}]", nonneg=True) for i, v in enumerate(lengths))
    s0 = getscalar(s0, "s0")
    th = getangle(theta, unit, "theta")
    br = _branch(branch)
    sol = cf.rccc(al, a, s0, th, br)
    if not sol.ok:
        where = _where_it_assembles(lambda t: cf.rccc(al, a, s0, t, br).ok)
        raise InvalidModelError(f"the RCCC cannot be assembled at theta = {th} rad "
                                "(spherical indicatrix has no real solution or the slides are "
                                f"indeterminate){where}")
    L = max(list(a) + [abs(s0), 1e-300])
    return _finish("RCCC", sol.origins, sol.z, sol.x, "RCCC", ["R0", "C1", "C2", "C3"], idle=0,
                   params=dict(alphas=al, lengths=a, s0=s0, theta=th, branch=br), L=L)


def rssr(crank, crank_height, coupler, rocker, offset, twist, rocker_height, theta, *,
         branch: int = 1, unit: str = "rad") -> Linkage:
    """RSSR with two spherical joints modelled as 3 R each (one idle freedom: the coupler spin).

    World layout: input axis = z axis; crank pin ``B = (r1 cos th, r1 sin th, h1)``.
    Output axis direction ``u = (0, sin(twist), cos(twist))`` through ``(-offset, 0, 0)``;
    the rocker pin C turns on the circle of radius ``rocker`` about
    ``O2 = (-offset, 0, 0) - rocker_height * u`` in the plane normal to u.  The
    shortest distance between the axes is ``offset`` and their angle ``twist``.

    Parameters
    ----------
    crank, crank_height, coupler, rocker, offset, rocker_height : float, length
    twist : float, rad (or deg)
        Angle between the input and output axes, in (0, 180 deg).
    theta : float, rad (or deg)
        Start input angle.
    branch : +1 or -1
        Root of the input-output equation (:func:`.closedform.rssr_phi`).
    """
    r1 = getscalar(crank, "crank", positive=True)
    h1 = getscalar(crank_height, "crank_height")
    l = getscalar(coupler, "coupler", positive=True)
    r2 = getscalar(rocker, "rocker", positive=True)
    e = getscalar(offset, "offset", nonneg=True)
    tw = getangle(twist, unit, "twist")
    if not 1e-6 < tw < math.pi - 1e-6:
        raise InputError(f"twist must lie strictly between 0 and 180 deg; got {twist!r} {unit}",
                         name="twist", value=twist)
    h2 = getscalar(rocker_height, "rocker_height")
    th = getangle(theta, unit, "theta")
    br = _branch(branch)
    geo = cf.RSSRGeometry(r1, h1, l, r2, e, tw, h2)
    phi, ok = cf.rssr_phi(geo, th, br)
    if not ok:
        where = _where_it_assembles(lambda t: cf.rssr_phi(geo, t, br)[1])
        raise InvalidModelError(f"the RSSR cannot be assembled at theta = {th} rad{where}")
    B = geo.crank_pin(th)
    C = geo.rocker_pin(phi)
    O2 = geo.rocker_centre
    u = geo.axis
    ez = np.array([0.0, 0.0, 1.0])
    dc = _unit(C - B)
    z3 = _unit(np.cross(ez, dc))           # first S: z1 = ez, z3 normal to ez and the coupler
    z2 = np.cross(ez, z3)                  # middle axis normal to both: far from gimbal lock
    z4 = _unit(np.cross(dc, u))            # second S: z4 normal to coupler and output axis
    z5 = _unit(np.cross(z4, u))
    o = np.array([np.zeros(3), B, B, B, C, C, C, O2])
    z = np.array([ez, ez, z2, z3, z4, z5, u, u])
    x = np.array([
        np.array([1.0, 0.0, 0.0]),          # x0: common normal output axis -> input axis
        _unit(B - np.array([0.0, 0.0, h1])),
        np.cross(ez, z2),
        np.cross(z2, z3),
        dc,
        np.cross(z4, z5),
        np.cross(z5, u),
        _unit(O2 - C),
    ])
    L = max(r1, l, r2, e, abs(h1), abs(h2))
    return _finish("RSSR", o, z, x, ["R", "S", "S", "R"], ["R_in", "S_B", "S_C", "R_out"], idle=1,
                   params=dict(crank=r1, crank_height=h1, coupler=l, rocker=r2, offset=e,
                               twist=tw, rocker_height=h2, theta=th, branch=br), L=L)
