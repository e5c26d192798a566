"""Full-revolution solve time of the HD loop solver against scipy.optimize.fsolve.

For each example linkage (planar four-bar, spherical 4R, RCCC, RSSR) the loop is
solved at 361 input values (360 steps over one revolution):

* ``hd``: :func:`mechanisms.spatial.solve_path` (damped Newton-Raphson on the paper's
  nine equations, second-order predictor);
* ``fsolve``: ``scipy.optimize.fsolve`` on the same loop-closure entries, warm-started
  from the previous pose, with its own finite-difference Jacobian;
* ``fsolve+J``: the same with the analytic Jacobian (the paper's M) as ``fprime``.

fsolve needs a square system, so the equations are the independent rows of the nine
(chosen by QR with column pivoting at the start pose) and, for RSSR, the idle spin
is removed by freezing one S angle (also chosen by pivoting).  Ratios are measured in
the same run.  Plain script:  python benchmarks/bench_spatial.py [repeats]
"""

import math
import sys
import time

import numpy as np
from scipy.linalg import qr
from scipy.optimize import fsolve

from mechanisms.spatial import loop_residual, planar_fourbar, rccc, rssr, solve_path, spherical_4r
from mechanisms.spatial.solve import _B_all, _M, _ROWS, _COLS, _frames, _prefix_suffix, _weights

LINKAGES = {
    "planar 4R": lambda: planar_fourbar(2.0, 7.0, 9.0, 6.0, 0.3),
    "spherical 4R": lambda: spherical_4r((0.5, 1.5, 1.0, 1.2), 0.3),
    "RCCC": lambda: rccc((30, 80, 60, 70), (1.0, 3.0, 2.5, 3.5), 0.5, 20, unit="deg"),
    "RSSR": lambda: rssr(1.0, 0.5, 3.0, 2.0, 2.5, math.radians(60), 0.5, 0.3),
}


def square_problem(loop, q0):
    """Unknown columns and equation rows giving a square, full-rank system at q0."""
    T, S = _prefix_suffix(_frames(loop, q0))
    M = _M(loop, _B_all(loop, T, S))
    unk = np.array(loop.unknowns)
    n_keep = len(unk) - loop.idle_dof
    _, _, pc = qr(M[:, unk], pivoting=True)
    cols = np.sort(unk[pc[:n_keep]])
    _, _, pr = qr(M[:, cols].T, pivoting=True)
    rows = np.sort(pr[:n_keep])
    return cols, rows


def fsolve_path(loop, xs, q0, use_jac):
    cols, rows = square_problem(loop, q0)
    w = _weights(loop.length_scale)
    q = q0.copy()
    out = np.empty((len(xs), loop.n_vars))
    worst = 0.0

    def full(z, x):
        qq = q.copy()
        qq[loop.input] = x
        qq[cols] = z
        return qq

    def fun(z, x):
        T, _ = _prefix_suffix(_frames(loop, full(z, x)))
        return ((T[-1] - np.eye(4))[_ROWS, _COLS] * w)[rows]

    def jac(z, x):
        T, S = _prefix_suffix(_frames(loop, full(z, x)))
        return _M(loop, _B_all(loop, T, S))[np.ix_(rows, cols)]

    for k, x in enumerate(xs):
        z = fsolve(fun, q[cols], args=(x,), fprime=jac if use_jac else None, xtol=1e-13)
        q = full(z, x)
        out[k] = q
        worst = max(worst, loop_residual(loop, q))
    return out, worst


def timeit(fn, repeats):
    best = math.inf
    for _ in range(repeats):
        t = time.perf_counter()
        res = fn()
        best = min(best, time.perf_counter() - t)
    return best, res


def main(repeats=3):
    print(f"{'linkage':14s} {'hd [ms]':>9s} {'fsolve [ms]':>12s} {'fsolve+J [ms]':>14s} "
          f"{'ratio':>7s} {'ratio+J':>8s} {'hd res':>9s} {'fs res':>9s} {'hd iters':>9s}")
    for name, make in LINKAGES.items():
        lk = make()
        xs = lk.q0[lk.loop.input] + np.linspace(0, 2 * math.pi, 361)
        t_hd, path = timeit(lambda: solve_path(lk.loop, xs, lk.q0), repeats)
        assert path.success
        t_fs, (qf, rf) = timeit(lambda: fsolve_path(lk.loop, xs, lk.q0, False), repeats)
        t_fj, (qj, rj) = timeit(lambda: fsolve_path(lk.loop, xs, lk.q0, True), repeats)
        # Same branch: compare the output variable.
        dq = np.max(np.abs(np.angle(np.exp(1j * (qf[:, lk.output] - path.q[:, lk.output])))))
        print(f"{name:14s} {1e3 * t_hd:9.1f} {1e3 * t_fs:12.1f} {1e3 * t_fj:14.1f} "
              f"{t_fs / t_hd:7.2f} {t_fj / t_hd:8.2f} {path.residual.max():9.1e} "
              f"{max(rf, rj):9.1e} {int(path.iterations.sum()):9d}   (|d output| {dq:.1e})")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
