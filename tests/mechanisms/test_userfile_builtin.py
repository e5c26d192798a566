"""Model files that name a built-in model (written by synthesize for built-in models)."""

import numpy as np
import pytest

from cspace.errors import FileFormatError
from mechanisms.models import BUILTIN
from mechanisms.userfile import model_from_dict, model_to_dict


@pytest.mark.parametrize("name", sorted(BUILTIN))
def test_builtin_round_trip_is_exact(name):
    m = BUILTIN[name]()
    m2 = m.with_nominal(m.nominal + 0.3 * m.tol).with_tolerances(0.5 * m.tol)
    d = model_to_dict(m2)
    assert d["builtin"] == name and "pairs" not in d
    m3 = model_from_dict(d)
    assert np.array_equal(m3.nominal, m2.nominal) and np.array_equal(m3.tol, m2.tol)
    assert m3.build() == m2.build()
    assert (m3.window, m3.drive, m3.q2_start, m3.deviation) == \
        (m2.window, m2.drive, m2.q2_start, m2.deviation)


def test_builtin_documents_are_checked():
    d = model_to_dict(BUILTIN["reciprocating_cam"]())
    bad = dict(d, builtin="nope")
    with pytest.raises(FileFormatError, match="builtin must name a built-in model"):
        model_from_dict(bad)
    bad = dict(d, parameters=d["parameters"][1:])
    with pytest.raises(FileFormatError, match=r"needs every parameter; missing \['cam_x'\]"):
        model_from_dict(bad)
    bad = dict(d, parameters=d["parameters"] + [{"name": "zz", "nominal": 1, "tol": 0}])
    with pytest.raises(FileFormatError, match="'zz' is not a parameter"):
        model_from_dict(bad)
    bad = dict(d, units="mm")
    with pytest.raises(FileFormatError, match="is in 'cm'"):
        model_from_dict(bad)
    bad = dict(d, extra=1)
    with pytest.raises(FileFormatError):
        model_from_dict(bad)
    # a length of the built-in model stated as an angle
    bad = dict(d, parameters=[dict(d["parameters"][0], unit="deg")] + d["parameters"][1:])
    with pytest.raises(FileFormatError, match=r"'cam_x' of the built-in model "
                                              r"'reciprocating_cam' is a length, in 'cm', the "
                                              r"file says unit 'deg'") as e:
        model_from_dict(bad)
    assert e.value.path == "parameters[0].unit"
    ok = dict(d, parameters=[dict(d["parameters"][0], unit="cm")] + d["parameters"][1:])
    assert np.array_equal(model_from_dict(ok).nominal, BUILTIN["reciprocating_cam"]().nominal)


def test_builtin_documents_read_the_operating_point_as_model_files_do():
    """The operating point of a ``builtin`` document passes the same checks as a
    model file's (one reader for both)."""
    d = model_to_dict(BUILTIN["reciprocating_cam"]())
    m = model_from_dict(dict(d, window=[0.0, 6.0, -5.0, 5.0], deviation=0.05))
    assert m.window == (0.0, 6.0, -5.0, 5.0) and m.deviation == 0.05
    for key, value, match in (("window", [6.0, 0.0, -5.0, 5.0], "q1_lo < q1_hi"),
                              ("window", [0.0, 6.0], "window"),
                              ("deviation", 0, "deviation must be a positive finite number"),
                              ("q2_start", [0.0, 1.0], "one start value per pair")):
        with pytest.raises(FileFormatError, match=match):
            model_from_dict(dict(d, **{key: value}))
