"""An arc whose sweep is tiny but not zero is a typed error, never a full circle
(issue 23, item 8)."""

import json
import math

import pytest

from cspace.errors import DegenerateGeometryError, ZeroLengthSegmentError
from cspace.geometry import Arc, Line, Loop
from cspace.io import load_pair


@pytest.mark.parametrize("sweep", [1e-15, 5e-15, 1e-16, 1e-300, 2e-14])
@pytest.mark.parametrize("ccw", [True, False])
def test_tiny_sweep_is_refused(sweep, ccw):
    a0 = 0.3
    a1 = a0 + sweep if ccw else a0 - sweep
    with pytest.raises(ZeroLengthSegmentError, match="positive length above rounding"):
        Arc((0.0, 0.0), 1.0, a0, a1, ccw)


@pytest.mark.parametrize("turns", [1, 2, -1])
def test_whole_turns_are_a_full_circle(turns):
    a = Arc((1.0, 2.0), 0.5, 0.7, 0.7 + turns * 2 * math.pi, True)
    assert a.is_full_circle
    # rounding of a written-out 2 pi
    b = Arc((1.0, 2.0), 0.5, 0.0, 6.283185307179587, True)
    assert b.is_full_circle


def test_sweep_below_the_loop_resolution_is_refused():
    # a 1e-12 rad arc between two lines of a unit square is below the loop's
    # resolution (VALIDATION_REL of its size)
    tiny = Arc((0.0, 0.0), 1.0, 0.0, 1e-12, True)
    end = tiny.end_point
    with pytest.raises(DegenerateGeometryError):
        Loop((tiny, Line(tuple(end), (0.0, 1.0)), Line((0.0, 1.0), (0.0, 0.0)),
              Line((0.0, 0.0), (1.0, 0.0))))


def test_pair_file_with_tiny_arc(tmp_path):
    circle = {"type": "arc", "center": [0, 0], "radius": 1, "start_angle": 0,
              "end_angle": 1e-15, "ccw": True}
    d = {"format": "cspace-pair", "version": 1, "units": "mm", "parts": [
        {"name": "a", "axis": {"type": "rotation", "center": [0, 0]}, "loops": [[circle]]},
        {"name": "b", "axis": {"type": "rotation", "center": [5, 0]},
         "loops": [[dict(circle, center=[5, 0], end_angle=2 * math.pi)]]}]}
    p = tmp_path / "p.json"
    p.write_text(json.dumps(d))
    with pytest.raises(ZeroLengthSegmentError, match=r"parts\[0\].loops\[0\]\[0\]"):
        load_pair(p)


@pytest.mark.parametrize("bulge", [5e-324, 1e-300, -1e-200])
def test_bulge_at_rounding_is_a_straight_edge(bulge):
    # found by the fuzz suite: the arc's centre at infinity gave inf * 0 = NaN
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lp = Loop.from_bulges([(-30, 21), (30, 21), (30, 29), (-30, 29)], [bulge, 0, 0, 0])
    assert isinstance(lp.segments[0], Line)


@pytest.mark.parametrize("a0, a1, hint", [(0.0, 90.0, True), (-90.0, 270.0, True),
                                          (0.0, 7.0, False), (1.0, -6.0, False)])
def test_angles_more_than_a_turn_apart_are_refused(a0, a1, hint):
    """Not a whole number of turns apart and more than one: a slip, most
    often degrees; the message names both angles and, for degree-sized
    values, what math.radians gives."""
    from cspace.errors import InputError
    with pytest.raises(InputError, match=r"Arc angles must lie within a turn of each other, "
                                         r"or whole turns apart") as e:
        Arc((0.0, 0.0), 1.0, a0, a1, True)
    tail = (f"; written in degrees? radians({a0:.6g}) and radians({a1:.6g}) are "
            f"{math.radians(a0):.6g} and {math.radians(a1):.6g} rad")
    assert str(e.value).endswith(tail) == hint
    assert e.value.name == "Arc.end_angle"
