import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from mechanisms.manipulators import design, ldi_map  # noqa: E402
from mechanisms.manipulators.plotting import plot_ldi_map, plot_workspace  # noqa: E402


def test_ldi_map_and_workspace_plots():
    import matplotlib.pyplot as plt
    m = design("2-PPa", 1.0, 30, unit="deg").model
    ax = plot_ldi_map(m, n=21)
    assert ax.name == "3d"
    plt.close(ax.figure)
    ax = plot_ldi_map(ldi_map(m, n=21), surface=False)
    assert ax.name == "rectilinear"
    plt.close(ax.figure)
    ax = plot_workspace(m)
    # Two leg outlines, the effective square and the origin marker.
    assert len(ax.lines) == 4
    sq = ax.lines[2].get_xydata()
    np.testing.assert_allclose(np.abs(sq).max(), 1.0, atol=1e-9)
    plt.close(ax.figure)
