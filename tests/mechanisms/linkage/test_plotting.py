import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import math  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from cspace.errors import InputError  # noqa: E402
from mechanisms.linkage import (ClearanceLinkage, continuous_contact, coupler_ellipse,  # noqa: E402
                                exact_error, linear_error)
from mechanisms.linkage.plotting import (plot_error_curve, plot_error_ellipse,  # noqa: E402
                                         plot_joint_force, plot_loss_positions)


def test_error_plots(paper_fourbar):
    d = np.linspace(0, 2 * np.pi, 73)
    ex = exact_error(paper_fourbar, 1.1, joint="B", radius=0.1, delta=d)
    li = linear_error(paper_fourbar, 1.1, joint="B", radius=0.1, delta=d)
    ax = plot_error_curve([ex, li], scale=100)
    assert len(ax.lines) == 3                     # two curves and the zero line
    np.testing.assert_allclose(ax.lines[0].get_ydata(), 100 * ex.d_theta4, atol=0)
    ell = coupler_ellipse(paper_fourbar, 1.1, "B", 0.1)
    ax2 = plot_error_ellipse(ell, exact=ex)
    assert len(ax2.lines) == 3
    plt.close("all")
    with pytest.raises(InputError, match="ErrorCurve"):
        plot_error_curve([ell])
    with pytest.raises(InputError, match="ErrorEllipse"):
        plot_error_ellipse(ex)


def test_force_plots():
    link = ClearanceLinkage.reference(ground=0.121)
    rs = [continuous_contact(link, s, 1e-4, n=3600) for s in (50, 100)]
    fig, ax = plt.subplots()
    assert plot_joint_force(rs, ax=ax, ylim=(-5, 80)) is ax
    assert ax.get_ylim() == (-5, 80)
    ax2 = plot_loss_positions(rs)
    xs = np.concatenate([ln.get_xdata() for ln in ax2.lines if len(ln.get_xdata())])
    assert set(np.round(xs).tolist()) <= {50.0, 100.0}
    plt.close("all")
    with pytest.raises(InputError, match="ContactForce"):
        plot_joint_force([])


def test_every_contact_loss_is_plotted():
    """plot_loss_positions shows every loss of every speed (it drew only the
    first of each), on a linkage with two losses per speed."""
    link = ClearanceLinkage(crank=.04, coupler=.12, rocker=.10, ground=.11, m_coupler=.3,
                            m_rocker=.25, J_coupler=.0014, J_rocker=.0008, cg_coupler=.06,
                            cg_rocker=.05)
    rs = [continuous_contact(link, s, 50e-6, n=3600) for s in (50, 100, 200)]
    want = sorted((round(r.rpm), round(math.degrees(math.remainder(a, 2 * math.pi)), 6))
                  for r in rs for a in r.loss_angles())
    assert max(len(r.losses) for r in rs) >= 2
    ax = plot_loss_positions(rs)
    got = sorted((round(x), round(y, 6)) for ln in ax.lines if ln.get_marker() in ("o", "s")
                 for x, y in zip(ln.get_xdata(), ln.get_ydata()))
    assert got == want
    plt.close("all")


def test_the_joint_force_frame_follows_the_force_not_its_spikes():
    """Without ylim, the frame covers the force level (percentiles), not the
    model's narrow spikes; data without spikes keep matplotlib's frame."""
    from mechanisms.linkage.plotting import _robust_range
    link = ClearanceLinkage.reference(ground=0.121)
    r = continuous_contact(link, 100, 1e-4, n=3600)
    ax = plot_joint_force([r])
    lo, hi = ax.get_ylim()
    assert lo <= min(0.0, np.percentile(r.R, 1)) and hi >= np.percentile(r.R, 99)
    assert hi - lo < 3 * (np.percentile(r.R, 99) - min(0.0, np.percentile(r.R, 1))) + 1e-9
    assert _robust_range(np.linspace(0.0, 1.0, 100)) is None
    spiky = np.r_[np.linspace(5.0, 10.0, 200), 9000.0]
    assert _robust_range(spiky)[1] < 100
    plt.close("all")
