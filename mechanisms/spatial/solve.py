"""Displacement, velocity and acceleration of a closed HD loop ([Kim 1985] Eqs. 2-18).

Displacement (Eqs. 2-5)
    With estimates ``q`` the loop product is ``F = A_0 ... A_{n-1}``.  A change ``dq_v``
    of variable v in frame i changes it to first order by ``B_v dq_v`` with
    ``B_v = T_i Q_v S_i``, where ``T_i = A_0..A_{i-1}``, ``S_i = A_i..A_{n-1}`` and ``Q_v``
    the derivative operator (Eq. 3).  The paper keeps nine entries of
    ``sum_v B_v dq_v = I - F``: the translation and the lower triangle (with diagonal) of
    the rotation block (Eq. 5); together they vanish only when ``F = I``.  The nine
    rows, translation rows divided by the loop's length scale, form ``M``; each
    Newton-Raphson step is the least-squares (minimum-norm) solution of
    ``M dq = V``, so idle freedoms (RSSR coupler spin) do not disturb it.

Scale
    Slides are solved for in units of the loop's length scale L (``u = s / L``): the
    columns of M that belong to slides are multiplied by L, so that M, the step, its
    cap, the minimum-norm choice and the singularity test are all dimensionless.  A
    loop given in millimetres therefore takes the same steps, iterations and statuses
    as the same loop in metres.

Damping
    A step is scaled so that no variable moves by more than ``max_step`` (rad, or
    units of the length scale L for a slide), and then halved until the residual
    decreases.

Velocity and acceleration (Eqs. 8-18)
    At a closed pose ``B_v = T_i Q_v T_i^-1``.  Velocity: ``M qd = -B_in qd_in``.
    Acceleration: ``M qdd = -B_in qdd_in - sum_v sum_{u before v} [B_u, B_v] qd_u qd_v``,
    ``[X, Y] = XY - YX``; this is the paper's Eq. 13/17 (``dB_v/dt = sum_u B_u B_v qd_u``
    with the full product kept) written with the loop closed.  Same ``M`` as the
    displacement step.

Continuation
    :func:`solve_path` steps along the input, predicting each pose from the previous
    one with its velocity and acceleration, correcting by damped Newton-Raphson, and
    halving the input step when the corrector fails or lands farther from the
    prediction than the step warrants (a branch jump).  Input steps longer than
    ``max_step`` (rad, or L for a prismatic input) are first cut into equal parts no
    longer than that.  :func:`solve_pose` falls back on the same continuation, from the
    estimate's own input value, when Newton-Raphson from the estimate alone fails.

Non-convergence is a status (:class:`LoopStatus`), never NaN or an exception.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from cspace.argcheck import getangles, getint, getscalar, getunit
from cspace.errors import InputError, NonFiniteError

from .loops import Q_S, Q_THETA, Loop

__all__ = ["SolverOptions", "LoopStatus", "LoopPose", "LoopPath", "PointMotion",
           "loop_product", "loop_residual", "solve_pose", "solve_path", "velocity",
           "acceleration", "frame_transforms", "point_motion", "SELECTED_ENTRIES"]

#: The nine entries of Eq. 5 in the standard layout: translation (x, y, z), then the
#: rotation block's (x,x), (y,x), (z,x), (y,y), (z,y), (z,z).
SELECTED_ENTRIES = ((0, 3), (1, 3), (2, 3), (0, 0), (1, 0), (2, 0), (1, 1), (2, 1), (2, 2))
#: Residuals below this are rounding noise of products of O(1) matrices (64 ulps):
#: a stalled line search there counts as converged even if ``tol`` asked for less.
RESIDUAL_FLOOR = 64 * np.finfo(float).eps
#: Largest loop residual (as :func:`loop_residual`) of a pose given to :func:`velocity`,
#: :func:`acceleration` or :func:`point_motion`: their formulas hold only at a closed
#: pose, and a residual r perturbs the rates by about r (relative).  1e-8 leaves the
#: solver's poses (<= 1e-10) a margin of 100 and refuses poses that are not closed.
CLOSURE_TOL = 1e-8

_ROWS = np.array([r for r, _ in SELECTED_ENTRIES])
_COLS = np.array([c for _, c in SELECTED_ENTRIES])


@dataclass(frozen=True)
class SolverOptions:
    """Every numerical knob of the loop solver.

    Attributes
    ----------
    tol : float
        Convergence: largest entry of ``F - I`` (translation / length scale).  1e-12 is
        a few thousand ulps of O(1) entries, reached in one or two quadratic steps
        after 1e-6, and leaves two orders of margin to the 1e-10 acceptance bar.
    max_iter : int
        Newton-Raphson iterations per pose.
    max_step : float
        Largest change of one variable per Newton-Raphson step (rad, or units of the
        loop's length scale for a slide), and the longest input step of the
        continuation (likewise); 0.5 keeps steps inside the region where the
        linearisation holds.
    max_halvings : int
        Line-search halvings before a step counts as stalled.
    singular_rel : float
        ``sigma_min / sigma_max`` of M (slide columns in length-scale units, so the
        ratio does not depend on the length unit) below which a converged pose is
        SINGULAR (beyond the loop's idle freedoms).  1e-7 ~ sqrt(eps): velocities there
        have lost half their digits.
    max_subdivisions : int
        Halvings of one continuation step before the pose is given up.
    jump_factor : float
        Continuation accepts a corrected pose only if it lies within
        ``jump_factor * (|predicted change| + max_step * 1e-3)`` of the prediction
        (slides in length-scale units).
    """

    tol: float = 1e-12
    max_iter: int = 50
    max_step: float = 0.5
    max_halvings: int = 30
    singular_rel: float = 1e-7
    max_subdivisions: int = 6
    jump_factor: float = 0.5

    def __post_init__(self):
        for name in ("tol", "max_step", "singular_rel", "jump_factor"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"SolverOptions.{name} must be a positive finite float; got {v!r}",
                                 name=name, value=v)
        for name in ("max_iter", "max_halvings", "max_subdivisions"):
            v = getint(getattr(self, name), name, minimum=1, label=f"SolverOptions.{name}")
            object.__setattr__(self, name, v)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


class LoopStatus(enum.IntEnum):
    """Outcome of solving one pose."""

    CONVERGED = 0        #: residual <= tol, M of full rank (less idle freedoms)
    SINGULAR = 1         #: residual <= tol, but M lost rank: velocities not unique
    NOT_ASSEMBLABLE = 2  #: residual stalled at a positive minimum: no closure near here
    MAX_ITER = 3         #: still decreasing when the iterations ran out
    #: (paths only) closed, but continuation could reach this input only by a jump to
    #: what looks like another branch: the pose is a true closure, its continuity with
    #: the previous row is not established
    BRANCH_JUMP = 4


@dataclass(frozen=True)
class LoopPose:
    """One solved pose.

    Attributes
    ----------
    q : (n_vars,) float
        Joint variables (rad / length); the best estimate when not converged.
    residual : float
        Largest entry of ``F - I`` (translation / length scale).
    iterations : int
    status : LoopStatus
    rank : int
        Numerical rank of M at ``q``.
    sigma_ratio : float
        ``sigma_min / sigma_max`` of M over its expected rank (slide columns in units
        of the length scale: the same for any length unit).
    """

    q: np.ndarray
    residual: float
    iterations: int
    status: LoopStatus
    rank: int
    sigma_ratio: float

    @property
    def success(self) -> bool:
        return self.status in (LoopStatus.CONVERGED, LoopStatus.SINGULAR)

    @property
    def message(self) -> str:
        return {LoopStatus.CONVERGED: "loop closed",
                LoopStatus.SINGULAR: "loop closed at a singular pose (velocity not unique)",
                LoopStatus.NOT_ASSEMBLABLE: "loop cannot be closed near the estimate",
                LoopStatus.MAX_ITER: "iteration limit reached",
                LoopStatus.BRANCH_JUMP: "loop closed, but on what looks like another branch"
                }[self.status]

    def __repr__(self) -> str:
        return (f"LoopPose({self.status.name}, residual={self.residual:.2e}, "
                f"iterations={self.iterations})")

    def to_dict(self) -> dict:
        return {"q": self.q.tolist(), "residual": self.residual, "iterations": self.iterations,
                "status": self.status.name, "rank": self.rank, "sigma_ratio": self.sigma_ratio}


@dataclass(frozen=True)
class LoopPath:
    """Poses, velocities and accelerations along the input.

    Velocities and accelerations are per unit input rate: ``qd`` is ``dq/dq_in`` and
    ``qdd`` is ``d2q/dq_in2``.  For an input turning at ``w`` with acceleration ``a``,
    joint rates are ``qd * w`` and accelerations ``qdd * w**2 + qd * a``.  Where a pose
    failed, its row repeats the last good pose and its status says so.  A
    ``BRANCH_JUMP`` row holds the closed pose that was found (its residual is that
    of a closure); the path continues from it.

    Attributes
    ----------
    inputs : (m,) float
        Input values (rad or length).
    q, qd, qdd : (m, n_vars) float
    residual : (m,) float
    iterations : (m,) int
        Newton-Raphson iterations, summed over subdivisions.
    status : (m,) int, :class:`LoopStatus` values
    gap_before : (m,) bool
        The pose follows a failed one (continuity across the gap is not guaranteed).
    """

    inputs: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    residual: np.ndarray
    iterations: np.ndarray
    status: np.ndarray
    gap_before: np.ndarray

    @property
    def success(self) -> bool:
        return bool(np.all(self.status <= LoopStatus.SINGULAR))

    @property
    def message(self) -> str:
        jumps = np.count_nonzero(self.status == LoopStatus.BRANCH_JUMP)
        bad = np.count_nonzero(self.status > LoopStatus.SINGULAR) - jumps
        sing = np.count_nonzero(self.status == LoopStatus.SINGULAR)
        extra = f", {jumps} reached by a branch jump" if jumps else ""
        return (f"{len(self.inputs) - bad} of {len(self.inputs)} poses closed "
                f"({sing} singular{extra})")

    def __repr__(self) -> str:
        return (f"LoopPath(m={len(self.inputs)}, max_residual={np.max(self.residual):.2e}, "
                f"{self.message})")

    def to_dict(self) -> dict:
        return {"inputs": self.inputs.tolist(), "q": self.q.tolist(), "qd": self.qd.tolist(),
                "qdd": self.qdd.tolist(), "residual": self.residual.tolist(),
                "iterations": self.iterations.tolist(),
                "status": [LoopStatus(int(s)).name for s in self.status],
                "gap_before": self.gap_before.tolist()}


@dataclass(frozen=True)
class PointMotion:
    """Position, velocity and acceleration of a point fixed in one frame.

    Attributes
    ----------
    position, velocity, acceleration : (3,) float
        In ground coordinates; velocity and acceleration per unit input rate (as
        :class:`LoopPath`).
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray

    def __repr__(self) -> str:
        return f"PointMotion(position={np.round(self.position, 6)})"

    def to_dict(self) -> dict:
        return {"position": self.position.tolist(), "velocity": self.velocity.tolist(),
                "acceleration": self.acceleration.tolist()}


# --------------------------------------------------------------------------- core

def _frames(loop: Loop, q: np.ndarray):
    """HD matrices (n, 4, 4) for variables q."""
    n = loop.n_frames
    th = np.array([f.theta for f in loop.frames])
    s = np.array([f.s for f in loop.frames])
    a = np.array([f.a for f in loop.frames])
    al = np.array([f.alpha for f in loop.frames])
    for k, (fi, kind) in enumerate(loop.variables):
        if kind == "theta":
            th[fi] = q[k]
        else:
            s[fi] = q[k]
    ct, st, ca, sa = np.cos(th), np.sin(th), np.cos(al), np.sin(al)
    A = np.zeros((n, 4, 4))
    A[:, 0, 0], A[:, 0, 1], A[:, 0, 2], A[:, 0, 3] = ct, -st * ca, st * sa, a * ct
    A[:, 1, 0], A[:, 1, 1], A[:, 1, 2], A[:, 1, 3] = st, ct * ca, -ct * sa, a * st
    A[:, 2, 1], A[:, 2, 2], A[:, 2, 3] = sa, ca, s
    A[:, 3, 3] = 1.0
    return A


def _prefix_suffix(A):
    n = A.shape[0]
    T = np.empty((n + 1, 4, 4))
    S = np.empty((n + 1, 4, 4))
    T[0] = np.eye(4)
    S[n] = np.eye(4)
    for i in range(n):
        T[i + 1] = T[i] @ A[i]
    for i in range(n - 1, -1, -1):
        S[i] = A[i] @ S[i + 1]
    return T, S


def _Q(kind):
    return Q_THETA if kind == "theta" else Q_S


def _residual_of(F, L):
    D = F - np.eye(4)
    return max(float(np.max(np.abs(D[:3, :3]))), float(np.max(np.abs(D[:3, 3]))) / L)


def _weights(L):
    return np.array([1 / L, 1 / L, 1 / L, 1, 1, 1, 1, 1, 1])


def _B_all(loop, T, S):
    """B_v = T_i Q_v S_i for every variable, (n_vars, 4, 4)."""
    return np.array([T[fi] @ _Q(kind) @ S[fi] for fi, kind in loop.variables])


def _M(loop, B):
    """Weighted 9-row matrix of all variables' columns, (9, n_vars).

    The Jacobian of the weighted residual with respect to ``q`` itself: a slide
    column has the dimension 1 / length (see :func:`_var_scale`).
    """
    return (B[:, _ROWS, _COLS] * _weights(loop.length_scale)).T


def _var_scale(loop):
    """Unit of each variable in the solver: 1 (rad) for an angle, the loop's length
    scale for a slide.  ``M * _var_scale(loop)`` is dimensionless."""
    return np.array([1.0 if kind == "theta" else loop.length_scale
                     for _, kind in loop.variables])


def _rank_info(loop, Mu):
    """Numerical rank and ``sigma_min / sigma_max`` of the dimensionless ``Mu``
    (unknown columns of ``M * _var_scale(loop)``)."""
    sv = np.linalg.svd(Mu, compute_uv=False)
    if sv.size == 0 or sv[0] == 0:
        return 0, 0.0
    expected = min(Mu.shape[1] - loop.idle_dof, Mu.shape[0])
    rank = int(np.count_nonzero(sv > 1e-12 * sv[0]))
    ratio = float(sv[expected - 1] / sv[0]) if expected >= 1 else 1.0
    return rank, ratio


def loop_product(loop: Loop, q) -> np.ndarray:
    """``A_0 A_1 ... A_{n-1}`` (4, 4) for variables ``q``."""
    q = _q(loop, q)
    T, _ = _prefix_suffix(_frames(loop, q))
    return T[-1]


def loop_residual(loop: Loop, q) -> float:
    """Largest entry of ``F - I`` (translations divided by the length scale)."""
    q = _q(loop, q)
    return _residual_of(loop_product(loop, q), loop.length_scale)


def _q(loop, q):
    if not isinstance(loop, Loop):
        raise InputError(f"loop must be a Loop; got {type(loop).__name__}", name="loop", value=loop)
    try:
        a = np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"q must be {loop.n_vars} numbers; got {q!r}", name="q", value=q) from None
    if a.shape != (loop.n_vars,):
        raise InputError(f"q must have shape ({loop.n_vars},) for this loop; got {a.shape}",
                         name="q", value=q)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError("q must be finite", name="q", value=q)
    return a


def _newton(loop, q, opts):
    """Damped Newton-Raphson with the input held fixed.

    Returns ``(q, residual, iterations, status, rank, sigma_ratio)``.
    """
    unk = np.array(loop.unknowns)
    L = loop.length_scale
    w = _weights(L)
    D = _var_scale(loop)[unk]
    A = _frames(loop, q)
    T, S = _prefix_suffix(A)
    res = _residual_of(T[-1], L)
    it = 0
    slow = 0
    stalled = False
    while res > opts.tol and it < opts.max_iter:
        it += 1
        B = _B_all(loop, T, S)
        Mu = _M(loop, B)[:, unk] * D
        V = (np.eye(4) - T[-1])[_ROWS, _COLS] * w
        # Solve in dimensionless variables (slides / L), then convert back.
        du = np.linalg.lstsq(Mu, V, rcond=None)[0]
        big = np.max(np.abs(du))
        if big > opts.max_step:
            du *= opts.max_step / big
        dq = du * D
        step = 1.0
        for _ in range(opts.max_halvings):
            qt = q.copy()
            qt[unk] += step * dq
            At = _frames(loop, qt)
            Tt, St = _prefix_suffix(At)
            rt = _residual_of(Tt[-1], L)
            if rt < res:
                # Count steps that barely help: a residual creeping towards a positive
                # minimum means there is no closure nearby.
                slow = slow + 1 if rt > 0.9 * res else 0
                q, T, S, res = qt, Tt, St, rt
                break
            step *= 0.5
        else:
            stalled = True
            break
        if slow >= 5 and res > opts.tol:
            stalled = True
            break
    if res <= opts.tol or (stalled and res <= RESIDUAL_FLOOR):
        Mu = _M(loop, _B_all(loop, T, S))[:, unk] * D
        rank, ratio = _rank_info(loop, Mu)
        status = LoopStatus.SINGULAR if ratio < opts.singular_rel else LoopStatus.CONVERGED
        return q, res, it, status, rank, ratio
    status = LoopStatus.NOT_ASSEMBLABLE if stalled else LoopStatus.MAX_ITER
    if not stalled and res > 1e-3:
        # Many iterations without closing and still far: treat as no assembly nearby.
        status = LoopStatus.NOT_ASSEMBLABLE
    Mu = _M(loop, _B_all(loop, T, S))[:, unk] * D
    rank, ratio = _rank_info(loop, Mu)
    return q, res, it, status, rank, ratio


def _options(options):
    if options is None:
        return SolverOptions()
    if not isinstance(options, SolverOptions):
        raise InputError(f"options must be SolverOptions or None; got {type(options).__name__}",
                         name="options", value=options)
    return options


def solve_pose(loop: Loop, input_value, guess=None, *, unit: str = "rad",
               options: SolverOptions | None = None) -> LoopPose:
    """Close the loop at one input value, starting from ``guess``.

    Parameters
    ----------
    loop : Loop
    input_value : float
        rad (or deg with ``unit="deg"``) for a revolute input, length for a prismatic one.
    guess : (n_vars,) float, optional
        Initial estimate (selects the assembly branch), in radians and lengths
        as every pose's ``q``, whatever ``unit`` says (``unit`` is that of
        ``input_value`` only: a guess in degrees is read as radians, and the
        pose found from it has angles many turns out); defaults to the loop's
        reference values.
    options : SolverOptions, optional

    Notes
    -----
    Newton-Raphson starts from the estimate with its input replaced by
    ``input_value``.  Far from the estimate's own input it may stall although the
    loop closes (about half a turn away the loop product's rotation error is near a
    half turn, where the nine entries barely change with the variables);
    then, if the estimate closes the loop at its own input value, the pose is reached
    by continuation from there (as :func:`solve_path`, both ways round for a revolute
    input).  If that fails too (the input cannot get there from the estimate, e.g. the
    pose lies on another circuit of the linkage), a fixed set of further starts with
    the unknown angles spread over a turn is tried; a pose found that way may lie on
    another branch or circuit than the estimate.  ``NOT_ASSEMBLABLE`` thus means that
    none of these found a closure; the iterations of every attempt are counted.
    """
    opts = _options(options)
    if not isinstance(loop, Loop):
        raise InputError(f"loop must be a Loop; got {type(loop).__name__}", name="loop", value=loop)
    start = loop.reference_q() if guess is None else _q(loop, guess).copy()
    fi, kind = loop.variables[loop.input]
    x = getscalar(input_value, "input_value") * (getunit(unit) if kind == "theta" else 1.0)
    q, res, it, status, rank, ratio = _solve_at(loop, start, x, opts)
    return LoopPose(q=q, residual=res, iterations=it, status=status, rank=rank, sigma_ratio=ratio)


def _solve_at(loop, start, x, opts):
    """One pose at input ``x`` from the estimate ``start``, with the fallbacks of
    :func:`solve_pose`; returns as :func:`_newton` (iterations of every attempt)."""
    q = start.copy()
    q[loop.input] = x
    q, res, it, status, rank, ratio = _newton(loop, q, opts)
    if status == LoopStatus.NOT_ASSEMBLABLE and it < opts.max_iter:
        # Stalled (not merely out of iterations, a limit the caller chose).
        found, extra = _from_start(loop, start, x, loop.variables[loop.input][1], opts)
        it += extra
        if found is None:
            found, extra = _spread_starts(loop, start, x, opts)
            it += extra
        if found is not None:
            q, res, _, status, rank, ratio = found
    return q, res, it, status, rank, ratio


#: Further starts of :func:`solve_pose` when both the estimate and the continuation
#: from it fail (on the example linkages of the tests every input that closes did so
#: within the first 7), at a bounded cost for an input where the loop does not close.
_SPREAD_STARTS = 12


def _spread_starts(loop, start, x, opts):
    """Newton-Raphson from a fixed set of starts: the unknown angles spread over a
    turn (a fixed-seed sequence, so results repeat), slides at the estimate's values.

    Returns ``(result of _newton or None, iterations spent)``.
    """
    rng = np.random.default_rng(20240601)
    ang = np.array([i != loop.input and kind == "theta" for i, (_, kind) in
                    enumerate(loop.variables)])
    total = 0
    for _ in range(_SPREAD_STARTS):
        q = start.copy()
        q[ang] = rng.uniform(-math.pi, math.pi, np.count_nonzero(ang))
        q[loop.input] = x
        found = _newton(loop, q, opts)
        total += found[2]
        if found[3] <= LoopStatus.SINGULAR:
            return found, total
    return None, total


def _from_start(loop, start, x, kind, opts):
    """Continuation to input ``x`` from the estimate ``start`` closed at its own input.

    Returns ``(result of _newton or None, iterations spent)``.
    """
    q, _, total, status, _, _ = _newton(loop, start, opts)
    if status > LoopStatus.SINGULAR:
        return None, total
    x0 = q[loop.input]
    d = x - x0
    if kind == "theta":
        # The shorter way round first, then the other.
        d = (d + math.pi) % (2 * math.pi) - math.pi
        targets = [x0 + d] + ([x0 + d - math.copysign(2 * math.pi, d)] if d != 0 else [])
    else:
        targets = [x]
    qd, qdd, _ = _vel_acc(loop, q)
    jumped = None
    for xt in targets:
        ok, out, it = _march(loop, (q, qd, qdd), xt, opts)
        total += it
        if ok:
            qe = out[0].copy()
            qe[loop.input] = x          # the same pose when xt differs from x by turns
            found = _newton(loop, qe, opts)
            total += found[2]
            if found[3] <= LoopStatus.SINGULAR:
                if out[2] != LoopStatus.BRANCH_JUMP:
                    return found, total
                jumped = jumped or found
    return jumped, total


def _vel_acc(loop, q, input_rate=1.0, input_accel=0.0):
    """Rates at the closed pose q; minimum norm over the dimensionless unknowns."""
    A = _frames(loop, q)
    T, _ = _prefix_suffix(A)
    # At a closed pose S_i = T_i^-1; use the inverse of the rigid prefix exactly.
    Tinv = np.array([_rigid_inv(t) for t in T])
    B = np.array([T[fi] @ _Q(kind) @ Tinv[fi] for fi, kind in loop.variables])
    unk = np.array(loop.unknowns)
    D = _var_scale(loop)[unk]
    W = (B[:, _ROWS, _COLS] * _weights(loop.length_scale)).T
    Mu = W[:, unk] * D
    qd = np.zeros(loop.n_vars)
    qd[loop.input] = input_rate
    qd[unk] = np.linalg.lstsq(Mu, -W[:, loop.input] * input_rate, rcond=None)[0] * D
    C = np.zeros((4, 4))
    frame_of = [fi for fi, _ in loop.variables]
    for v in range(loop.n_vars):
        for u in range(loop.n_vars):
            if frame_of[u] < frame_of[v]:
                C -= (B[u] @ B[v] - B[v] @ B[u]) * (qd[u] * qd[v])
    rhs = C[_ROWS, _COLS] * _weights(loop.length_scale) - W[:, loop.input] * input_accel
    qdd = np.zeros(loop.n_vars)
    qdd[loop.input] = input_accel
    qdd[unk] = np.linalg.lstsq(Mu, rhs, rcond=None)[0] * D
    return qd, qdd, B


def _rigid_inv(t):
    r = t[:3, :3]
    out = np.eye(4)
    out[:3, :3] = r.T
    out[:3, 3] = -r.T @ t[:3, 3]
    return out


def _closed(loop, q, closure_tol, what):
    """``q`` checked to be a pose that closes the loop (rates hold only there)."""
    q = _q(loop, q)
    tol = getscalar(closure_tol, "closure_tol", positive=True)
    r = _residual_of(loop_product(loop, q), loop.length_scale)
    if not r <= tol:
        raise InputError(
            f"{what} needs a closed pose: q must close the loop to a residual <= "
            f"closure_tol = {tol:g}, got residual {r:.3g}; solve the pose first "
            "(solve_pose / solve_path) or pass a larger closure_tol", name="q", value=q)
    return q


def velocity(loop: Loop, q, input_rate=1.0, *, closure_tol=CLOSURE_TOL) -> np.ndarray:
    """Joint rates (n_vars,) at a closed pose ``q`` for the given input rate (Eq. 9).

    With idle freedoms the minimum-norm rates are returned (idle rate zero).

    Raises
    ------
    InputError
        When ``q`` does not close the loop (:func:`loop_residual` above
        ``closure_tol``, default :data:`CLOSURE_TOL`): the rates of Eq. 9 hold only at
        a closed pose, and elsewhere they would be numbers without meaning.
    """
    q = _closed(loop, q, closure_tol, "velocity")
    return _vel_acc(loop, q, getscalar(input_rate, "input_rate"))[0]


def acceleration(loop: Loop, q, input_rate=1.0, input_accel=0.0, *,
                 closure_tol=CLOSURE_TOL) -> np.ndarray:
    """Joint accelerations (n_vars,) at a closed pose ``q`` (Eq. 18).

    Raises
    ------
    InputError
        When ``q`` does not close the loop (as :func:`velocity`).
    """
    q = _closed(loop, q, closure_tol, "acceleration")
    return _vel_acc(loop, q, getscalar(input_rate, "input_rate"),
                    getscalar(input_accel, "input_accel"))[1]


def solve_path(loop: Loop, inputs, guess=None, *, unit: str = "rad",
               options: SolverOptions | None = None) -> LoopPath:
    """Solve the loop along a sequence of input values by continuation.

    Parameters
    ----------
    loop : Loop
    inputs : (m,) float
        Input values in order (rad, or deg with ``unit="deg"``; length for a prismatic
        input).  Consecutive values should be close enough that one pose predicts the
        next; steps are subdivided automatically otherwise.
    guess : (n_vars,) float, optional
        Estimate of the first pose (selects the branch), in radians and lengths as
        :func:`solve_pose` reads it; the first pose is found from it as by
        :func:`solve_pose`, the others by continuation.
    options : SolverOptions, optional

    Returns
    -------
    LoopPath
    """
    opts = _options(options)
    if not isinstance(loop, Loop):
        raise InputError(f"loop must be a Loop; got {type(loop).__name__}", name="loop", value=loop)
    fi, kind = loop.variables[loop.input]
    x = np.atleast_1d(getangles(inputs, unit, "inputs") if kind == "theta"
                      else getangles(inputs, "rad", "inputs", direction=False)).astype(float)
    if x.ndim != 1 or x.size == 0:
        raise InputError(f"inputs must be a non-empty 1-D sequence; got shape {x.shape}",
                         name="inputs", value=inputs)
    m, nv = x.size, loop.n_vars
    Q = np.zeros((m, nv))
    QD = np.zeros((m, nv))
    QDD = np.zeros((m, nv))
    res = np.zeros(m)
    its = np.zeros(m, dtype=int)
    st = np.zeros(m, dtype=int)
    gap = np.zeros(m, dtype=bool)
    q0 = loop.reference_q() if guess is None else _q(loop, guess).copy()
    q, r, it, status, _, _ = _solve_at(loop, q0, x[0], opts)
    q0[loop.input] = x[0]
    q_first = q0.copy()
    last = None
    if status <= LoopStatus.SINGULAR:
        qd, qdd, _ = _vel_acc(loop, q)
        last = (q, qd, qdd)
    Q[0], res[0], its[0], st[0] = q, r, it, status
    if last is not None:
        QD[0], QDD[0] = last[1], last[2]
    failed_before = last is None
    for k in range(1, m):
        if last is None:
            # Nothing closed yet: retry from the guess at this input.
            q0 = Q[k - 1].copy()
            q0[loop.input] = x[k]
            q, r, it, status, _, _ = _newton(loop, q0, opts)
            Q[k], res[k], its[k], st[k] = q, r, it, status
            gap[k] = True
            if status <= LoopStatus.SINGULAR:
                qd, qdd, _ = _vel_acc(loop, q)
                last = (q, qd, qdd)
                QD[k], QDD[k] = qd, qdd
                failed_before = False
            continue
        if failed_before:
            # After a gap, continuity is lost anyway (``gap_before`` flags the result):
            # try the last closed pose, its extrapolation and the first pose's guess as
            # starts, without the jump test.
            h = x[k] - last[0][loop.input]
            starts = [last[0].copy(), last[0] + last[1] * h + 0.5 * last[2] * h * h, q_first.copy()]
            total_it = 0
            for q0 in starts:
                q0[loop.input] = x[k]
                q, r, it, status, _, _ = _newton(loop, q0, opts)
                total_it += it
                ok = status <= LoopStatus.SINGULAR
                if ok:
                    break
        else:
            ok, out, total_it = _march(loop, last, x[k], opts)
            q, r, status = out
        its[k] = total_it
        if ok:
            qd, qdd, _ = _vel_acc(loop, q)
            last = (q, qd, qdd)
            Q[k], QD[k], QDD[k], res[k], st[k] = q, qd, qdd, r, status
            gap[k] = failed_before
            failed_before = False
        else:
            Q[k], QD[k], QDD[k] = last
            res[k], st[k] = r, status
            failed_before = True
    return LoopPath(inputs=x, q=Q, qd=QD, qdd=QDD, residual=res, iterations=its, status=st,
                    gap_before=gap)


#: Most input steps one continuation step is cut into (:func:`_march`); bounds the
#: work for an input step of very many turns.
_MAX_SUBSTEPS = 2000


def _march(loop, last, x_new, opts):
    """Advance from ``last`` = (q, qd, qdd) to input ``x_new`` in equal input steps no
    longer than ``max_step`` (rad, or the length scale for a prismatic input).

    A revolute input step that would need more than :data:`_MAX_SUBSTEPS` steps is
    first shortened by whole pairs of turns (the input variable itself still ends at
    ``x_new``).  Returns ``(ok, (q, residual, status), iterations)`` as
    :func:`_continue`; ``BRANCH_JUMP`` if any part of the way needed a jump.
    """
    x0 = last[0][loop.input]
    x_end = x_new
    hmax = opts.max_step * _var_scale(loop)[loop.input]
    kind = loop.variables[loop.input][1]
    if kind == "theta" and abs(x_new - x0) > _MAX_SUBSTEPS * hmax:
        x_end = x0 + math.fmod(x_new - x0, 4 * math.pi)
    n = max(1, min(_MAX_SUBSTEPS, math.ceil(abs(x_end - x0) / hmax)))
    total, jumped = 0, False
    for i in range(1, n + 1):
        xi = x_end if i == n else x0 + (x_end - x0) * i / n
        ok, out, it = _continue(loop, last, xi, opts, 0)
        total += it
        if not ok:
            return False, out, total
        jumped = jumped or out[2] == LoopStatus.BRANCH_JUMP
        if i < n:
            qd, qdd, _ = _vel_acc(loop, out[0])
            last = (out[0], qd, qdd)
    q = out[0]
    if x_end != x_new:
        q = q.copy()
        q[loop.input] = x_new
    return True, (q, out[1], LoopStatus.BRANCH_JUMP if jumped else out[2]), total


def _continue(loop, last, x_new, opts, depth):
    """Advance from ``last`` = (q, qd, qdd) to input ``x_new``; subdivide on failure.

    Returns ``(ok, (q, residual, status), iterations)``: ``ok`` when ``q`` closes the
    loop at ``x_new``, with status ``BRANCH_JUMP`` if the finest subdivision still
    landed farther from the prediction than its step warrants.
    """
    q_prev, qd, qdd = last
    h = x_new - q_prev[loop.input]
    pred = q_prev + qd * h + 0.5 * qdd * h * h
    pred[loop.input] = x_new
    q, r, it, status, _, _ = _newton(loop, pred, opts)
    D = _var_scale(loop)
    change = np.max(np.abs((pred - q_prev) / D))
    jump = np.max(np.abs((q - pred) / D)) > opts.jump_factor * (change + opts.max_step * 1e-3)
    if status == LoopStatus.CONVERGED and not jump or status == LoopStatus.SINGULAR:
        # At a singular pose branches meet and the velocity predictor is unreliable,
        # so a large correction there is not evidence of a branch jump.
        return True, (q, r, status), it
    if depth >= opts.max_subdivisions:
        if status <= LoopStatus.SINGULAR and jump:
            # Closed, but on what looks like another branch: say so.
            return True, (q, r, LoopStatus.BRANCH_JUMP), it
        return False, (q, r, status), it
    mid = q_prev[loop.input] + 0.5 * h
    ok, out, it1 = _continue(loop, last, mid, opts, depth + 1)
    if not ok:
        return False, out, it + it1
    qm = out[0]
    qdm, qddm, _ = _vel_acc(loop, qm)
    ok, out2, it2 = _continue(loop, (qm, qdm, qddm), x_new, opts, depth + 1)
    if ok and out[2] == LoopStatus.BRANCH_JUMP:
        out2 = (out2[0], out2[1], LoopStatus.BRANCH_JUMP)
    return ok, out2, it + it1 + it2


def frame_transforms(loop: Loop, q) -> np.ndarray:
    """Ground-frame poses ``T_k = A_0 .. A_{k-1}`` of every frame, (n_frames, 4, 4).

    ``T_k[:3, 3]`` is the origin of frame k (on joint axis k) and ``T_k[:3, 2]`` the
    axis direction.
    """
    q = _q(loop, q)
    T, _ = _prefix_suffix(_frames(loop, q))
    return T[:-1]


def point_motion(loop: Loop, q, frame: int, point=(0.0, 0.0, 0.0), *, qd=None,
                 qdd=None, closure_tol=CLOSURE_TOL) -> PointMotion:
    """Motion of a point fixed in frame ``frame`` (a coupler point, a joint centre).

    Parameters
    ----------
    loop : Loop
    q : (n_vars,) float
        A closed pose.
    frame : int
        Frame the point is fixed in (its coordinates are in that frame).
    point : (3,) float, length
    qd, qdd : (n_vars,) float, optional
        Joint rates/accelerations per unit input rate; computed from ``q`` if absent.
    closure_tol : float
        Largest loop residual accepted for ``q`` (as :func:`velocity`).

    Raises
    ------
    InputError
        For a ``point`` that is not 3 numbers, or a ``q`` that does not close the loop.
    NonFiniteError
        For a ``point`` with NaN or infinity.
    """
    q = _closed(loop, q, closure_tol, "point_motion")
    frame = getint(frame, "frame", minimum=0, maximum=loop.n_frames - 1)
    if isinstance(point, (str, bytes)):
        raise InputError(f"point must be 3 finite numbers (x, y, z in frame {frame}); got "
                         f"{type(point).__name__} {point!r}", name="point", value=point)
    try:
        x = np.asarray(point, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"point must be 3 finite numbers (x, y, z in frame {frame}); got "
                         f"{point!r}", name="point", value=point) from None
    x = np.append(x, 1.0) if x.shape == (3,) else x
    if x.shape != (4,):
        raise InputError(f"point must be 3 finite numbers; got {point!r}", name="point", value=point)
    if not np.all(np.isfinite(x)):
        raise NonFiniteError(f"point must be 3 finite numbers; got {point!r}", name="point",
                             value=point)
    qd_c, qdd_c, B = _vel_acc(loop, q)
    qd = qd_c if qd is None else _q(loop, qd)
    qdd = qdd_c if qdd is None else _q(loop, qdd)
    T, _ = _prefix_suffix(_frames(loop, q))
    P = T[frame] @ x
    frame_of = [fi for fi, _ in loop.variables]
    act = [v for v in range(loop.n_vars) if frame_of[v] < frame]
    V = sum((B[v] @ P * qd[v] for v in act), np.zeros(4))
    Acc = np.zeros(4)
    for v in act:
        Bdot = sum(((B[u] @ B[v] - B[v] @ B[u]) * qd[u] for u in range(loop.n_vars)
                    if frame_of[u] < frame_of[v]), np.zeros((4, 4)))
        Acc += B[v] @ P * qdd[v] + Bdot @ P * qd[v] + B[v] @ V * qd[v]
    return PointMotion(position=P[:3], velocity=V[:3], acceleration=Acc[:3])
