"""User-input fixes: the jam message names the contact curves that close the
channel, the output plot's axes name their units, and pair files with a UTF-8
byte-order mark load."""

import math

import matplotlib

matplotlib.use("Agg")

import pytest

from cspace import plotting as P
from cspace.simulate import SimStatus, simulate


def _yoke(units="mm"):
    from mechanisms.userfile import model_from_dict

    from .slotted_yoke import yoke_document
    params = [("a", 30.0), ("r", 5.0), ("hw", 5.1), ("s", 40.0), ("B", 60.0), ("H", 60.0)]
    return model_from_dict(yoke_document(
        [{"name": n, "nominal": v, "tol": 0.01} for n, v in params], units=units))


def test_jam_message_names_the_curves_that_meet():
    from mechanisms.analysis import model_cspaces
    from mechanisms.models import geneva
    cs, = model_cspaces(geneva(), {"pin_r": 0.45})   # the pin no longer fits the slots
    r = simulate(cs, 0.0, 2 * math.pi, 0.0)
    assert r.status == SimStatus.JAMMED
    assert r.message.startswith("driver blocked at q1 = ")
    assert ("(driver:pin|wheel:slot2.left^lock3 meets driver:pin|wheel:lock2^slot2.right)"
            in r.message)
    assert r.jam_reason in r.message


def test_jam_message_names_a_curve_whose_branches_close_the_channel():
    from mechanisms.analysis import model_cspaces
    m = _yoke()
    cs, = model_cspaces(m, {"s": 25.0})     # the slot too short: the pin hits the cap
    r = simulate(cs, 0.0, 2 * math.pi, 30.0)
    assert r.status == SimStatus.JAMMED
    assert "the free channel closes ahead (crank:pin|yoke:cap.top meets itself" in r.message


def test_output_plot_axes_name_their_units():
    from mechanisms.analysis import motion_at
    m = _yoke("inch")
    (cs,), (sim,) = motion_at(m, accuracy="fast")
    assert sim.rotating == (True, False) and sim.units == "inch"
    ax = P.plot_output([sim])
    assert ax.get_xlabel() == "driver q1 [rad]"
    assert ax.get_ylabel() == "follower output f(q1) [inch]"
    ax = P.plot_output([sim], unit="deg")
    # a sliding follower's output stays in its length unit
    assert ax.get_ylabel() == "follower output f(q1) [inch]"
    y = ax.lines[0].get_ydata()
    assert max(y) == pytest.approx(max(sim.q2))
    assert ax.get_lines()[0].get_xdata()[-1] == pytest.approx(math.degrees(sim.q1[-1]))


def test_output_plot_of_a_rotating_follower_is_in_the_angle_unit():
    from mechanisms.analysis import motion_at
    from mechanisms.models import geneva
    (cs,), (sim,) = motion_at(geneva(), accuracy="fast")
    ax = P.plot_output([sim], unit="deg")
    assert ax.get_xlabel() == "driver q1 [deg]"
    assert ax.get_ylabel() == "follower output f(q1) [deg]"


def test_a_pair_file_with_a_utf8_bom_loads(tmp_path):
    from cspace.io import load_pair, save_pair
    from mechanisms.models import geneva
    pair = geneva().build()
    save_pair(pair, tmp_path / "p.json")
    f = tmp_path / "p.json"
    f.write_bytes(b"\xef\xbb\xbf" + f.read_bytes())
    assert load_pair(f).name == pair.name
