"""The Python DXF import takes the operating point the ``import-dxf`` command
takes (``--q2-start``, ``--drive``, ``--window``, ``--deviation``): into the
Model it returns with ``tol``; a Pair holds none."""

import math

import pytest

pytest.importorskip("ezdxf")

from cspace.errors import InputError, InvalidModelError
from mechanisms.analysis import motion_at
from mechanisms.dxf import dxf_to_model, export_dxf, import_dxf
from mechanisms.models import eccentric_cam

WINDOW = (0.0, 2 * math.pi, -0.5, 2.0)


@pytest.fixture(scope="module")
def drawing(tmp_path_factory):
    m = eccentric_cam()
    path = export_dxf(m, tmp_path_factory.mktemp("dxf") / "ecc.dxf")
    parts = [{"layer": p.name, "name": p.name, "axis": p.axis} for p in m.build().parts]
    return path, parts


def test_the_operating_point_goes_into_the_model(drawing):
    path, parts = drawing
    m = dxf_to_model(path, parts=parts, tol=0.01, units="cm", bias=-1, q2_start=1.0,
                     drive=[0, 2 * math.pi], window=WINDOW, deviation=0.012)
    assert m.q2_start == (1.0,) and m.drive == (0.0, 2 * math.pi)
    assert m.window == WINDOW and m.deviation == 0.012
    (_,), (sim,) = motion_at(m, accuracy="fast")
    assert sim.success and sim.q2[0] == pytest.approx(0.0, abs=1e-9)   # on the cam at once
    same = import_dxf(path, parts=parts, tol=0.01, units="cm", bias=-1, q2_start=(1.0,),
                      deviation=0.012)
    assert same.q2_start == (1.0,) and same.deviation == 0.012 and same.drive is None
    plain = dxf_to_model(path, parts=parts, tol=0.01, units="cm")
    assert (plain.q2_start, plain.drive, plain.window, plain.deviation) == (None,) * 4


def test_a_pair_holds_no_operating_point(drawing):
    path, parts = drawing
    with pytest.raises(InputError, match=r"q2_start, drive given without tol: a Pair holds no "
                                         r"operating point; pass tol="):
        import_dxf(path, parts=parts, units="cm", q2_start=1.0, drive=(0, 1))


def test_the_operating_point_is_checked_as_the_commands(drawing):
    path, parts = drawing
    with pytest.raises(InputError, match=r"window for rotating coordinate q1 spans 360 rad.*"
                                         r"written in degrees\?"):
        dxf_to_model(path, parts=parts, tol=0.01, units="cm", window=(0, 360, -0.5, 2.0))
    with pytest.raises(InvalidModelError, match=r"turns the rotating driver 360 rad.*written "
                                                r"in degrees\?"):
        dxf_to_model(path, parts=parts, tol=0.01, units="cm", drive=(0, 360))
    with pytest.raises(InvalidModelError, match="deviation must be None"):
        dxf_to_model(path, parts=parts, tol=0.01, units="cm", deviation=-1.0)
    with pytest.raises(InvalidModelError, match="q2_start must be None"):
        dxf_to_model(path, parts=parts, tol=0.01, units="cm", q2_start="1.0")
