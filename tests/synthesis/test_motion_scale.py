"""A loose tolerance on a dimension that never changes the motion does not
loosen the check-list filter, the search's stop or the default deviation
threshold (synthesis.checklist.motion_scale, cspace.defects.contact_tolerance)."""

import json
from pathlib import Path

import numpy as np
import pytest

from cspace.defects import contact_parameters, contact_tolerance, default_deviation, reference
from mechanisms.models import eccentric_cam, geneva
from mechanisms.userfile import model_from_dict
from synthesis.checklist import motion_scale
from synthesis.loop import checklist_of, operating_zones

DATA = Path(__file__).parent / "data"


def _model(name, **tol):
    d = json.loads((DATA / name).read_text())
    for p in d["parameters"]:
        if p["name"] in tol:
            p["tol"] = tol[p["name"]]
    d.pop("deviation", None)
    return model_from_dict(d)


@pytest.fixture(scope="module")
def stem():
    """A roller cam whose stem (+-0.5 and +-1 mm) never touches the cam; the
    dimensions that matter have +-0.02 to +-0.08 mm."""
    m = _model("roller_cam_stem.json")
    return m, reference(m, "fast")


def test_the_stem_moves_no_contact_of_the_motion(stem):
    m, ref = stem
    moved = dict(zip(m.names, contact_parameters(m, ref.spaces, ref.sims)))
    assert not moved["stem_w"] and not moved["stem_len"]
    assert all(v for k, v in moved.items() if not k.startswith("stem"))
    # every curve of the C-space counts without the motions: the stem's do exist
    assert contact_parameters(m, ref.spaces).all()
    assert contact_tolerance(m, ref.spaces, ref.sims) == 0.08
    assert contact_tolerance(m, ref.spaces) == 1.0
    # the default threshold: 5 x 0.08 at the reach, not 5 x 1 mm
    assert ref.d == pytest.approx(5 * 0.08 / ref.spaces[0].pair.char_length)
    assert ref.d == default_deviation(m, ref.spaces, ref.sims)


def test_the_check_list_does_not_depend_on_the_stem(stem):
    m, ref = stem
    assert motion_scale(m, ref) == 0.08
    tight = _model("roller_cam_stem.json", stem_w=0.02, stem_len=0.02)
    rt = reference(tight, "fast")
    a = checklist_of(m, ref, operating_zones(m, ref, "fast"), "fast")
    b = checklist_of(tight, rt, operating_zones(tight, rt, "fast"), "fast")
    assert len(a.vectors) == len(b.vectors) >= 5
    cols = [i for i, nm in enumerate(m.names) if not nm.startswith("stem")]
    assert np.array_equal(a.array()[:, cols], b.array()[:, cols])


def test_a_slot_length_that_only_moves_its_walls_ends():
    """The slot's walls run from -h to h: their curves depend on h, but the
    pin never reaches their ends, so h (+-1) does not change the motion."""
    m = model_from_dict(json.loads((DATA / "yoke_long_slot.json").read_text()))
    ref = reference(m, "fast")
    assert dict(zip(m.names, contact_parameters(m, ref.spaces, ref.sims)))["h"]
    assert motion_scale(m, ref) == pytest.approx(0.06)


def test_equal_tolerances_keep_the_largest():
    for mk in (eccentric_cam, geneva):
        m = mk()
        ref = reference(m, "fast")
        assert motion_scale(m, ref) == float(np.max(m.tol))
