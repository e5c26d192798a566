"""Exhaustive sweeps (run with -m slow)."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cspace.errors import InvalidModelError
from mechanisms.spatial import LoopStatus, closedform as cf, frame_transforms, solve_path, spherical_4r


@pytest.mark.slow
def test_random_spherical_4r_revolutions_match_closed_form():
    rng = np.random.default_rng(2024)
    checked = 0
    while checked < 40:
        al = tuple(rng.uniform(0.2, 2.0, 4))
        th = np.linspace(0, 2 * math.pi, 361)
        if not all(cf.spherical_4r_psi(al, t, 1)[1] for t in th):
            continue               # input cannot turn fully: not a revolution test
        for br in (1, -1):
            try:
                lk = spherical_4r(al, 0.0, branch=br)
            except InvalidModelError:
                break
            path = solve_path(lk.loop, th, lk.q0)
            assert np.all(path.status <= LoopStatus.SINGULAR)
            assert path.residual.max() <= 1e-10
            z3 = np.array([0.0, math.sin(al[3]), math.cos(al[3])])
            u = np.array([1.0, 0.0, 0.0])
            v = np.cross(z3, u)
            hd = np.array([math.atan2(T[2][:3, 2] @ v, T[2][:3, 2] @ u)
                           for T in (frame_transforms(lk.loop, q) for q in path.q)])
            ref = np.array([cf.spherical_4r_psi(al, t, br)[0] for t in th])
            d = (hd - ref + math.pi) % (2 * math.pi) - math.pi
            assert_allclose(d, 0.0, atol=1e-8)
        checked += 1
