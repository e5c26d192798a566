"""Figures of a synthesis run and of the statistics (synthesis.cli.plotting)."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from synthesis.cli import plotting as SP  # noqa: E402


@pytest.fixture(scope="module")
def run():
    from mechanisms.models import reciprocating_cam
    from synthesis.executors import make_executor
    from synthesis.loop import synthesize
    m = reciprocating_cam()
    with make_executor("serial") as ex:
        return m, synthesize(m, "fast", executor=ex, max_iter=2)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_defect_history_draws_one_point_per_iteration(run):
    _, r = run
    ax = SP.plot_defect_history(r)
    defects, checklist = ax.get_lines()[:2]
    assert list(defects.get_xdata()) == [h.iteration for h in r.history]
    assert list(defects.get_ydata()) == r.defects_per_iteration()
    assert len(checklist.get_xdata()) == r.nit


def test_changes_draw_a_bar_pair_per_changed_parameter(run):
    _, r = run
    changed = [nm for nm, c in r.changes().items()
               if c["delta"] != 0 or c["tol_final"] != c["tol_initial"]]
    ax = SP.plot_changes(r)
    assert len(ax.patches) == 2 * len(changed) > 0
    assert [t.get_text() for t in ax.get_yticklabels()] == changed


def test_zones_before_after_share_one_figure_and_its_axes(run):
    _, r = run
    zb, za = r.zones_initial[0], r.zones_final[0]
    cb, ca = r.spaces_initial[0], r.spaces_final[0]
    ax = SP.plot_zones_before_after(zb, za, cb, ca, defects=(5, 0))
    left, right = ax.figure.axes[:2]
    assert right is ax and left.get_shared_x_axes().joined(left, right)
    assert left.get_title().startswith(f"before: {len(zb.overlaps)} zone overlap(s), 5 defective")
    assert right.get_title().startswith(f"after: {len(za.overlaps)} zone overlap(s), 0 defective")


def test_parts_before_after_magnify_a_small_change(run):
    m, r = run
    assert np.any(r.nominal != r.initial_nominal)
    ax = SP.plot_parts_before_after(r, m)
    assert ax.patches or ax.lines
    # a change of a fraction of a tolerance is magnified, and the title says by how much
    assert ", changes x" in ax.get_title()


def test_contributors_without_a_design_point_say_so():
    class NoPoints:
        design_points = ()
    ax = SP.plot_contributors(NoPoints())
    assert "no design point" in ax.texts[0].get_text()


def test_report_keeps_its_plot_names():
    from synthesis.cli import report
    for name in ("plot_zones_before_after", "plot_defect_history", "plot_changes",
                 "plot_parts_before_after"):
        assert getattr(report, name) is getattr(SP, name)
