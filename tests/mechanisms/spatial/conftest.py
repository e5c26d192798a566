import math

import numpy as np
import pytest

from mechanisms.spatial import SolverOptions, planar_fourbar, rccc, rssr, solve_path, spherical_4r

# Example linkages, all with a fully rotatable input.
# Spherical 4R: the paper's experimental arcs 100, 300, 200 mm on a 200 mm sphere
# (0.5, 1.5, 1.0 rad); the ground arc (1.2 rad) is not printed and is assumed.
SPH_ALPHAS = (0.5, 1.5, 1.0, 1.2)
RCCC_ARGS = dict(alphas=(30, 80, 60, 70), lengths=(1.0, 3.0, 2.5, 3.5), s0=0.5, theta=20)
RSSR_ARGS = dict(crank=1.0, crank_height=0.5, coupler=3.0, rocker=2.0, offset=2.5,
                 twist=math.radians(60), rocker_height=0.5, theta=0.3)
PLANAR_ARGS = dict(crank=2.0, coupler=7.0, rocker=9.0, ground=6.0, theta=0.3)

TIGHT = SolverOptions(tol=1e-14)


def build(name, branch=1):
    if name == "planar":
        return planar_fourbar(**PLANAR_ARGS, branch=branch)
    if name == "spherical":
        return spherical_4r(SPH_ALPHAS, 0.3, branch=branch)
    if name == "rccc":
        return rccc(**RCCC_ARGS, branch=branch, unit="deg")
    if name == "rssr":
        return rssr(**RSSR_ARGS, branch=branch)
    raise ValueError(name)


def revolution(lk, n=361):
    x0 = lk.q0[lk.loop.input]
    return x0 + np.linspace(0.0, 2 * math.pi, n)


@pytest.fixture(scope="session")
def paths():
    """Full-revolution paths (361 inputs, both branches) of the four example linkages."""
    out = {}
    for name in ("planar", "spherical", "rccc", "rssr"):
        for br in (1, -1):
            lk = build(name, br)
            out[name, br] = (lk, solve_path(lk.loop, revolution(lk), lk.q0))
    return out
