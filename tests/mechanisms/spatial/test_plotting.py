import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mechanisms.spatial.plotting import (plot_acceleration, plot_displacement,  # noqa: E402
                                         plot_linkage, plot_velocity)


def test_plots_draw_one_line_per_variable(paths):
    import matplotlib.pyplot as plt
    lk, path = paths["rccc", 1]
    for fn in (plot_displacement, plot_velocity, plot_acceleration):
        ax = fn(path, loop=lk.loop)
        assert len(ax.lines) == lk.loop.n_vars - 1
        y = ax.lines[0].get_ydata()
        assert np.all(np.isfinite(y))
        plt.close(ax.figure)
    ax = plot_linkage(lk)
    assert len(ax.lines) == 1 + lk.loop.n_frames
    plt.close(ax.figure)
    with pytest.raises(ValueError, match="expected a LoopPath"):
        plot_velocity(lk)
