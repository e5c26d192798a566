"""Exhaustive sweeps (run with -m slow)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mechanisms.manipulators import (design, forward_kinematics, global_design_index,
                                     inverse_kinematics, ldi_map, closed_form_design_indices)


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["2-PaP", "2-PPa"])
def test_gdi_and_fk_ik_over_theta_l_sweep(kind):
    top = 85 if kind == "2-PaP" else 44
    for th in np.arange(5, top + 1, 3):
        m = design(kind, 1.0, th, unit="deg").model
        cf = closed_form_design_indices(m)
        res = global_design_index(m)
        assert_allclose(res.gdi, cf["gdi"], atol=1e-10)
        grid = ldi_map(m, n=301).ldi
        assert_allclose(grid.min() / grid.max(), cf["gdi"], atol=1e-10)
        x = np.linspace(-m.half_width, m.half_width, 301)
        X, Y = np.meshgrid(x, x)
        p = np.stack([X.ravel(), Y.ravel()], -1)
        ik = inverse_kinematics(m, p)
        assert ik.success
        fk = forward_kinematics(m, ik.q)
        assert fk.success
        assert_allclose(fk.p, p, atol=1e-11)
