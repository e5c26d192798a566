"""Closed kinematic loops described by Hartenberg-Denavit (HD) parameters.

Matrix layout
-------------
[Kim 1985] (Eq. 2) writes the 4x4 HD matrix with the homogeneous coordinate
first, so that the translation sits in the first column.  Here the usual layout is
used, translation in the last column:

``A_i = Rz(theta_i) Tz(s_i) Tx(a_i) Rx(alpha_i)``

        [[cos th, -sin th cos al,  sin th sin al, a cos th],
         [sin th,  cos th cos al, -cos th sin al, a sin th],
         [0,       sin al,         cos al,        s       ],
         [0,       0,              0,             1       ]]

which is the paper's matrix with rows and columns permuted (paper index 1 -> 4,
2..4 -> 1..3); :func:`hd_matrix` with ``layout="paper"`` returns the paper's form.
``A_i`` maps coordinates in frame i+1 to frame i; frame 0 is the ground; the loop
closes when ``A_0 A_1 ... A_{n-1} = I`` (Eq. 1).

Joints
------
R
    one frame, ``theta`` variable.
P
    one frame, ``s`` variable.
C
    cylindrical = R + P on one axis: one frame with ``theta`` and ``s`` both variable.
S
    spherical = 3 R with intersecting axes: three frames
    ``(a=0, alpha=90 deg, theta_a, s)``, ``(a=0, alpha=90 deg, theta_b, 0)``,
    ``(a, alpha, theta_c, 0)``.  The first and third axes line up (gimbal lock) at
    ``theta_b = 0`` or ``pi``; builders start S joints at ``theta_b = 90 deg``.

Derivative operators (Eq. 3, 7): ``dA/dtheta = Q_theta A`` and ``dA/ds = Q_s A``
with ``Q_theta = [[0,-1,0,0],[1,0,0,0],0,0]`` and ``Q_s`` the unit z translation.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from cspace.argcheck import getangle, getangles, getint, getscalar
from cspace.errors import InputError, InvalidModelError

__all__ = ["JointType", "Joint", "HDFrame", "Loop", "make_loop", "hd_matrix", "Q_THETA", "Q_S"]

Q_THETA = np.array([[0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0],
                    [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]])
Q_THETA.setflags(write=False)
Q_S = np.zeros((4, 4))
Q_S[2, 3] = 1.0
Q_S.setflags(write=False)


class JointType(enum.Enum):
    """Lower pairs of a loop."""

    R = "R"  #: revolute
    P = "P"  #: prismatic
    C = "C"  #: cylindrical = R + P on one axis
    S = "S"  #: spherical = 3 R


@dataclass(frozen=True)
class Joint:
    """One joint and the link that leaves it, as given by the user.

    Attributes
    ----------
    kind : JointType
    a : float, length
        Common-normal length to the next joint axis.
    alpha : float, rad
        Twist from this axis to the next, about the common normal.
    theta : float or (3,) float, rad
        Rotation (reference value; the initial guess where variable).  Three values
        for S.
    s : float, length
        Offset along the axis (reference value; initial guess for P and C).
    name : str
    """

    kind: JointType
    a: float = 0.0
    alpha: float = 0.0
    theta: object = 0.0
    s: float = 0.0
    name: str = ""


@dataclass(frozen=True)
class HDFrame:
    """One row of the HD table (one 1-DOF or C joint after expansion).

    Attributes
    ----------
    a, alpha, theta, s : float
        HD parameters (length, rad, rad, length).
    theta_var, s_var : bool
        Which of theta / s is a joint variable.
    joint : int
        Index of the user joint it came from.
    name : str
    """

    a: float
    alpha: float
    theta: float
    s: float
    theta_var: bool
    s_var: bool
    joint: int
    name: str


@dataclass(frozen=True)
class Loop:
    """A single closed loop of HD frames.

    Attributes
    ----------
    frames : tuple of HDFrame
    variables : tuple of (int, str)
        Joint variables in chain order: (frame index, ``"theta"`` or ``"s"``).
    input : int
        Index into ``variables`` of the input (driven) variable.
    idle_dof : int
        Idle freedoms (e.g. 1 for RSSR with two 3R spherical joints: the coupler's spin).
    length_scale : float, length
        Characteristic length used to make translation residuals dimensionless.
    joints : tuple of Joint
        The user joints, for reference.
    """

    frames: tuple
    variables: tuple
    input: int
    idle_dof: int
    length_scale: float
    joints: tuple

    @property
    def n_frames(self) -> int:
        return len(self.frames)

    @property
    def n_vars(self) -> int:
        return len(self.variables)

    @property
    def unknowns(self) -> tuple:
        """Indices of the variables solved for (all but the input)."""
        return tuple(i for i in range(self.n_vars) if i != self.input)

    def reference_q(self) -> np.ndarray:
        """Variable values stored in the frames (the reference pose / initial guess)."""
        return np.array([getattr(self.frames[f], k) for f, k in self.variables])

    def signature(self) -> str:
        return "".join(j.kind.value for j in self.joints)

    def __repr__(self) -> str:
        return (f"Loop({self.signature()}, frames={self.n_frames}, vars={self.n_vars}, "
                f"input={self.variables[self.input]}, idle_dof={self.idle_dof})")

    def to_dict(self) -> dict:
        return {"signature": self.signature(),
                "frames": [dict(a=f.a, alpha=f.alpha, theta=f.theta, s=f.s, theta_var=f.theta_var,
                                s_var=f.s_var, joint=f.joint, name=f.name) for f in self.frames],
                "variables": [list(v) for v in self.variables], "input": self.input,
                "idle_dof": self.idle_dof, "length_scale": self.length_scale}


def hd_matrix(a, alpha, theta, s, *, layout: str = "standard") -> np.ndarray:
    """The HD matrix ``Rz(theta) Tz(s) Tx(a) Rx(alpha)``.

    ``layout="paper"`` returns the arrangement of [Kim 1985] (homogeneous coordinate first).

    Parameters
    ----------
    a, s : float, length
    alpha, theta : float, rad
    layout : ``"standard"`` or ``"paper"``

    Raises
    ------
    InputError
        For a parameter that is not a real number, or an unknown ``layout``.
    NonFiniteError
        For a NaN or infinite parameter.
    """
    a, alpha = getscalar(a, "a"), getscalar(alpha, "alpha")
    theta, s = getscalar(theta, "theta"), getscalar(s, "s")
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    m = np.array([[ct, -st * ca, st * sa, a * ct],
                  [st, ct * ca, -ct * sa, a * st],
                  [0.0, sa, ca, s],
                  [0.0, 0.0, 0.0, 1.0]])
    if layout == "standard":
        return m
    if layout == "paper":
        perm = [3, 0, 1, 2]
        return m[np.ix_(perm, perm)]
    raise InputError(f"layout must be 'standard' or 'paper'; got {layout!r}", name="layout",
                     value=layout)


def _as_joint(j, k) -> Joint:
    if isinstance(j, Joint):
        return j
    if isinstance(j, dict):
        try:
            return Joint(**j)
        except TypeError as exc:
            raise InputError(f"joints[{k}]: {exc}", name="joints", value=j) from None
    raise InputError(f"joints[{k}] must be a Joint or a dict; got {type(j).__name__}",
                     name="joints", value=j)


def make_loop(joints, *, input_variable: int = 0, idle_dof: int = 0, unit: str = "rad",
              length_scale=None) -> Loop:
    """Build a closed loop from a list of joints.

    Parameters
    ----------
    joints : sequence of Joint (or dicts of its fields)
        In loop order, starting at the ground joint; ``kind`` may be a
        :class:`JointType` or its letter.
    input_variable : int
        Index of the driven variable in the expanded variable list (0 = the first
        joint's theta, or its s for P).
    idle_dof : int
        Known idle freedoms (not counted as singularities).
    unit : ``"rad"`` or ``"deg"``
        Unit of every ``alpha`` and ``theta`` given.
    length_scale : float, optional
        Defaults to the largest ``|a|`` or ``|s|`` (1 if all are zero).

    Examples
    --------
    >>> lp = make_loop([Joint("R", a=1), Joint("R", a=3), Joint("R", a=2), Joint("R", a=4)])
    >>> lp.signature(), lp.n_vars
    ('RRRR', 4)
    """
    try:
        seq = list(joints)
    except TypeError:
        raise InputError(f"joints must be a sequence of Joint; got {joints!r}", name="joints",
                         value=joints) from None
    if len(seq) < 2:
        raise InvalidModelError(f"a loop needs at least 2 joints; got {len(seq)}")
    frames, variables, norm = [], [], []
    for k, raw in enumerate(seq):
        j = _as_joint(raw, k)
        try:
            kind = j.kind if isinstance(j.kind, JointType) else JointType(str(j.kind).upper())
        except ValueError:
            raise InputError(f"joints[{k}].kind must be one of R, P, C, S; got {j.kind!r}",
                             name="kind", value=j.kind) from None
        a = getscalar(j.a, f"joints[{k}].a")
        al = getangle(j.alpha, unit, f"joints[{k}].alpha")
        s = getscalar(j.s, f"joints[{k}].s")
        nm = j.name or f"{kind.value}{k}"
        if kind is JointType.S:
            bad = InputError(f"joints[{k}].theta must be 3 finite angles for S (its three "
                             f"rotations); got {j.theta!r}"[:300], name="theta", value=j.theta)
            if isinstance(j.theta, (str, bytes)):
                raise bad
            try:
                th = np.atleast_1d(np.asarray(j.theta, dtype=float))
            except (TypeError, ValueError):
                raise bad from None
            if th.shape != (3,) or not np.all(np.isfinite(th)):
                raise bad
            th = getangles(th, unit, f"joints[{k}].theta")
            specs = [(0.0, math.pi / 2, th[0], s), (0.0, math.pi / 2, th[1], 0.0), (a, al, th[2], 0.0)]
            for i, (fa, fal, fth, fs) in enumerate(specs):
                frames.append(HDFrame(fa, fal, float(fth), fs, True, False, k, f"{nm}.{'abc'[i]}"))
                variables.append((len(frames) - 1, "theta"))
        else:
            th = getangle(j.theta, unit, f"joints[{k}].theta")
            tv = kind in (JointType.R, JointType.C)
            sv = kind in (JointType.P, JointType.C)
            frames.append(HDFrame(a, al, th, s, tv, sv, k, nm))
            if tv:
                variables.append((len(frames) - 1, "theta"))
            if sv:
                variables.append((len(frames) - 1, "s"))
        norm.append(Joint(kind, a, al, tuple(float(x) for x in th) if kind is JointType.S
                          else th, s, nm))
    input_variable = getint(input_variable, "input_variable", minimum=0,
                            maximum=len(variables) - 1)
    idle_dof = getint(idle_dof, "idle_dof", minimum=0)
    if length_scale is None:
        L = max([abs(f.a) for f in frames] + [abs(f.s) for f in frames] + [0.0]) or 1.0
    else:
        L = getscalar(length_scale, "length_scale", positive=True)
    return Loop(frames=tuple(frames), variables=tuple(variables), input=int(input_variable),
                idle_dof=int(idle_dof), length_scale=float(L), joints=tuple(norm))
