"""Every dimension of a fixed pair as a parameter."""

import numpy as np
import pytest

from cspace.errors import InputError
from mechanisms.dimensions import PARAM_MODES, parametric_model


def test_every_vertex_and_centre_is_a_parameter_and_the_nominal_rebuilds_the_pair(models):
    pair = models["reciprocating_cam"].build()
    m = parametric_model(pair, 0.01)
    assert m.n > 10 and np.all(m.tol == 0.01)
    assert any(nm.endswith("_axis_x") for nm in m.names)
    rebuilt = m.build()
    for a, b in ((pair.driver, rebuilt.driver), (pair.follower, rebuilt.follower)):
        assert len(a.loops) == len(b.loops)
        for la, lb in zip(a.loops, b.loops):
            for sa, sb in zip(la.segments, lb.segments):
                np.testing.assert_allclose(sa.start_point, sb.start_point, atol=1e-12)


def test_profile_mode_leaves_the_axes_fixed(models):
    pair = models["reciprocating_cam"].build()
    m = parametric_model(pair, 0.01, param_mode="profile")
    assert "profile" in PARAM_MODES
    assert not any(nm.endswith("_axis_x") or nm.endswith("_axis_y") for nm in m.names)


@pytest.mark.parametrize("tol", [-1.0, float("nan"), "x"])
def test_a_bad_tolerance_is_an_input_error(models, tol):
    with pytest.raises(InputError):
        parametric_model(models["reciprocating_cam"].build(), tol)


def test_still_importable_from_the_model_file_module():
    from mechanisms.userfile import parametric_model as p
    assert p is parametric_model


def test_repeated_segment_names_of_a_part_are_made_unique(models):
    """A pair built in Python may name two segments of a part alike (a model
    file may not: the names label the part's contacts); the model keeps the
    first and numbers the others, and a full circle's two halves get .1 and .2."""
    from dataclasses import replace

    from cspace.geometry import Arc, Loop, Pair, Part
    pair = models["reciprocating_cam"].build()
    lp = pair.follower.loops[0]
    segs = tuple(replace(s, name="edge") for s in lp.segments)
    follower = replace(pair.follower, loops=(Loop(segs),) + pair.follower.loops[1:])
    disk = Part("disk", (Loop((Arc((0.0, 0.0), 1.0, 0.0, 2 * np.pi, True, "rim"),)),),
                pair.driver.axis)
    m = parametric_model(Pair(disk, follower, pair.units, name=pair.name), 0.01)
    built = m.build()
    names = [s.name for s in built.follower.loops[0].segments]
    assert names[0] == "edge" and len(set(names)) == len(names)
    assert names[1:] == [f"edge.{k}" for k in range(2, len(names) + 1)]
    assert [s.name for s in built.driver.loops[0].segments] == ["rim.1", "rim.2"]
