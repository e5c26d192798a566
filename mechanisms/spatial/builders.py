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

from cspace.argcheck import getangle, getscalar, getunit
from cspace.errors import InputError, InvalidModelError, NonFiniteError
from cspace.geom2d import IntersectionKind, circle_circle

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


def _frame_rows(v, name: str) -> np.ndarray:
    """An (n, 3) array of finite numbers, else an InputError naming it."""
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be an (n, 3) array of numbers, got {v!r}"[:300],
                         name=name) from None
    if a.ndim != 2 or a.shape[1] != 3:
        raise InputError(f"{name} must be an (n, 3) array (one row per frame), got shape "
                         f"{a.shape}", name=name)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} must be finite, got NaN or infinite entries", name=name)
    return a


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
    o, z, x = (_frame_rows(v, nm) for v, nm in ((origins, "origins"), (z, "z"), (x, "x")))
    if not (o.shape == z.shape == x.shape) or len(o) < 2:
        raise InputError(f"origins, z and x must be (n, 3) arrays of one n >= 2 (one row per "
                         f"frame), got shapes {o.shape}, {z.shape} and {x.shape}",
                         name="origins")
    length_scale = getscalar(length_scale, "length_scale", positive=True)
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
    """``branch`` as +1 or -1; an int (or numpy integer) only, not a bool or a float."""
    is_int = isinstance(branch, (int, np.integer)) and not isinstance(branch, (bool, np.bool_))
    if not is_int or branch not in (1, -1):
        kind = "" if is_int else f" ({type(branch).__name__}; an int is required)"
        raise InputError(f"branch must be +1 or -1; got {branch!r}{kind}", name="branch",
                         value=branch)
    return int(branch)


def _four(values, name, what):
    """``values`` as a list of exactly four items (not yet checked one by one)."""
    if isinstance(values, (str, bytes, dict)):
        seq = None
    else:
        try:
            seq = list(values)
        except TypeError:
            seq = None
    if seq is None or len(seq) != 4:
        got = f"{len(seq)} of them: {values!r}" if seq is not None else \
            f"{type(values).__name__} {values!r}"
        raise InputError(f"{name} must be 4 {what} (a sequence); got {got}", name=name,
                         value=values)
    return seq


# ----------------------------------------------------------------------------- planar

def _assembly_arcs(margin):
    """The input angles over a turn where a loop assembles, in closed form.

    ``margin(theta)`` must be >= 0 exactly where the loop closes and be a
    trigonometric polynomial of degree <= 2 in theta (true for every builder here).
    Its coefficients follow exactly from 8 samples, its zeros from the quartic
    ``z^2 margin(z)``, ``z = exp(i theta)``, polished by Newton's method.

    Returns
    -------
    list of (lo, hi)
        Arcs in rad, ``-pi <= lo < hi <= lo + 2 pi`` (``hi`` may pass pi), in order.
    """
    k = 8
    t = 2 * math.pi * np.arange(k) / k
    c = np.fft.fft([margin(float(v)) for v in t]) / k
    n = np.array([2, 1, 0, -1, -2])
    coef = c[n % k]                            # c_2 .. c_-2: z^2 margin(z), highest first
    top = np.max(np.abs(coef))
    if top == 0.0:
        return [(-math.pi, math.pi)]
    while coef.size > 1 and abs(coef[0]) <= 1e-13 * top:
        coef, n = coef[1:-1], n[1:-1]
    cand = []
    for z in (np.roots(coef) if coef.size > 1 else []):
        if abs(abs(z) - 1.0) > 1e-6:
            continue
        th = float(np.angle(z))
        for _ in range(8):                     # polish on the true margin
            d = float(np.real(np.sum(1j * n * coef * np.exp(1j * n * th))))
            if d == 0.0:
                break
            step = margin(th) / d
            if abs(step) > 1e-3:
                break
            th -= step
        cand.append((th + math.pi) % (2 * math.pi) - math.pi)
    if not cand:
        return [(-math.pi, math.pi)] if margin(0.0) >= 0 else []
    cand.sort()
    ends = cand + [cand[0] + 2 * math.pi]
    arcs = []
    for lo, hi in zip(ends[:-1], ends[1:]):
        if hi - lo > 0 and margin(0.5 * (lo + hi)) > 0:
            if arcs and abs(arcs[-1][1] - lo) < 1e-12:
                arcs[-1] = (arcs[-1][0], hi)    # through a tangency
            else:
                arcs.append((lo, hi))
    if len(arcs) > 1 and abs(arcs[-1][1] - 2 * math.pi - arcs[0][0]) < 1e-12:
        arcs = [(arcs[-1][0], arcs[0][1] + 2 * math.pi)] + arcs[1:-1]
    return arcs


def _where_it_assembles(margin, unit) -> str:
    """The end of a "cannot be assembled at theta" message: the exact input ranges
    over a turn where the loop closes (see :func:`_assembly_arcs`), in ``unit``,
    rounded inwards so that every angle shown assembles; or that it closes nowhere
    (its dimensions, not its start angle, are at fault)."""
    arcs = _assembly_arcs(margin)
    if not arcs:
        return "; it assembles at no input angle: the dimensions do not close the loop"
    per = getunit(unit)
    digits = 2 if unit == "deg" else 4
    q = 10.0 ** digits
    shown = []
    for lo, hi in arcs:
        if hi > math.pi and hi - lo < 2 * math.pi:
            # across +-180 deg: shown as its two pieces
            shown += [(lo, math.pi), (-math.pi, hi - 2 * math.pi)]
        else:
            shown.append((lo, hi))
    spans = []
    for lo, hi in sorted(shown):
        a, b = lo / per, hi / per
        ar, br = math.ceil(a * q - 1e-9) / q, math.floor(b * q + 1e-9) / q
        if ar > br:
            spans.append(f"[{a:.{digits + 3}f}, {b:.{digits + 3}f}] {unit}")
        else:
            spans.append(f"[{ar:.{digits}f}, {br:.{digits}f}] {unit}")
    return f"; choose a start angle where it assembles: {', '.join(spans)}"


def _as_given(value, unit):
    """An angle echoed as the caller gave it: ``20 deg``, ``0.349 rad``."""
    return f"{float(value):g} {unit}"


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
        s = max(a, b, c, d)

        def margin(t):
            # |B - D|^2 between (b - c)^2 and (b + c)^2
            bd2 = (a * a + d * d - 2 * a * d * math.cos(t)) / (s * s)
            return ((b + c) ** 2 / (s * s) - bd2) * (bd2 - (b - c) ** 2 / (s * s))
        raise InvalidModelError(f"the four-bar ({a}, {b}, {c}, {d}) cannot be assembled at "
                                f"theta = {_as_given(theta, unit)}"
                                f"{_where_it_assembles(margin, unit)}")
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

def _spherical_margin(al):
    """>= 0 exactly where the spherical 4R (or the RCCC's indicatrix) closes: the
    angle between the coupler's input-side axis z1(theta) and the output axis z3 must
    lie in [|alpha_1 - alpha_2|, alpha_1 + alpha_2]."""
    a0, a1, a2, a3 = al

    def margin(t):
        w = math.cos(a0) * math.cos(a3) - math.sin(a0) * math.sin(a3) * math.cos(t)
        return (w - math.cos(a1 + a2)) * (math.cos(a1 - a2) - w)
    return margin


def _spherical_axes(al, th, br, given=None):
    """Axes z_0..z_3 and x_0..x_3 of a spherical 4R with twists ``al`` at input ``th``.

    ``given`` = (alphas, theta, unit) as the caller wrote them, for the message.
    """
    a0, a1, a2, a3 = al
    z0 = np.array([0.0, 0.0, 1.0])
    x0 = np.array([1.0, 0.0, 0.0])
    z3 = np.array([0.0, math.sin(a3), math.cos(a3)])
    z1 = np.array([math.sin(th) * math.sin(a0), -math.cos(th) * math.sin(a0), math.cos(a0)])
    psi, ok = cf.spherical_4r_psi(al, th, br)
    if not ok:
        alphas, theta, unit = given if given is not None else (al, th, "rad")
        where = _where_it_assembles(_spherical_margin(al), unit)
        raise InvalidModelError(f"the spherical 4R with twists {[float(v) for v in alphas]} "
                                f"{unit} cannot be assembled at theta = "
                                f"{_as_given(theta, unit)}{where}")
    z2 = cf.spherical_4r_z2(al, psi)
    z = np.array([z0, z1, z2, z3])
    x = [x0]
    for i in range(1, 4):
        x.append(np.cross(z[i - 1], z[i]) / math.sin(al[i - 1]))
    return z, np.array(x)


def _twists(alphas, unit):
    alphas = _four(alphas, "alphas", "twist angles")
    al = tuple(getangle(v, unit, f"alphas[{i}]") for i, v in enumerate(alphas))
    for i, v in enumerate(al):
        if not 1e-6 < v < math.pi - 1e-6:
            raise InputError(f"alphas[{i}] must lie strictly between 0 and pi rad (0 and 180 "
                             f"deg); got {alphas[i]!r} {unit}{_deg_hint(alphas[i], unit)}",
                             name="alphas", value=alphas)
    return al


def _deg_hint(v, unit: str) -> str:
    """A hint for an angle in (1, 180) read in radians: written in degrees?"""
    try:
        x = float(v)
    except (TypeError, ValueError):
        return ""
    if unit == "rad" and math.pi <= x < 180.0:
        return f"; written in degrees? pass unit='deg' (radians({x:g}) = {math.radians(x):.6g})"
    return ""


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
    z, x = _spherical_axes(al, th, br, given=(alphas, theta, unit))
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
    lengths = _four(lengths, "lengths", "numbers")
    a = tuple(getscalar(v, f"lengths[{i}]", nonneg=True) for i, v in enumerate(lengths))
    s0 = getscalar(s0, "s0")
    th = getangle(theta, unit, "theta")
    br = _branch(branch)
    sol = cf.rccc(al, a, s0, th, br)
    if not sol.ok:
        margin = _spherical_margin(al)
        if margin(th) >= 0:
            raise InvalidModelError(
                f"the RCCC cannot be assembled at theta = {_as_given(theta, unit)}: its "
                "spherical indicatrix closes there but the three slides are indeterminate "
                "(the C axes are parallel to one plane); choose another start angle")
        raise InvalidModelError(f"the RCCC cannot be assembled at theta = "
                                f"{_as_given(theta, unit)} (its spherical indicatrix has no "
                                f"real solution){_where_it_assembles(margin, unit)}")
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
        raise InputError(f"twist must lie strictly between 0 and pi rad (0 and 180 deg); got "
                         f"{twist!r} {unit}{_deg_hint(twist, unit)}", name="twist", value=twist)
    h2 = getscalar(rocker_height, "rocker_height")
    th = getangle(theta, unit, "theta")
    br = _branch(branch)
    geo = cf.RSSRGeometry(r1, h1, l, r2, e, tw, h2)
    phi, ok = cf.rssr_phi(geo, th, br)
    if not ok:
        e1, e2 = geo.basis
        s = max(r1, l, r2, e, abs(h1), abs(h2))

        def margin(t):
            # the circle of C meets the sphere of radius l about B(t)
            d = (geo.crank_pin(t) - geo.rocker_centre) / s
            k = (d @ d + (r2 * r2 - l * l) / (s * s)) / (2 * r2 / s)
            return (d @ e1) ** 2 + (d @ e2) ** 2 - k * k
        raise InvalidModelError(f"the RSSR cannot be assembled at theta = "
                                f"{_as_given(theta, unit)}{_where_it_assembles(margin, unit)}")
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
