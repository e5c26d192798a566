"""Two user models (drawn in a CAD program, imported with ``import-dxf --tol
0.02 --bias -1``) on which the batched margins and the full per-variant test
disagreed, each vector's verdict checked against the full test:

* a tangent cam (two arcs joined by tangent lines) under a flat follower: a
  variant turns at a tangent join by 0.0016 rad, a convex vertex the nominal
  has not, whose contact the full test sees appear in the sequence; the batch,
  which follows the nominal's curves, certified the variant healthy;
* a disc cam with a flat follower stated on it (``q2_start = 0``): a variant's
  disc reaches 1e-6 mm above the start, which the C-space classifies as a
  contact but the simulation refuses as blocked; the full test called the
  part jammed at the start, where the batch starts it on its channel's bound.
"""

from pathlib import Path

import numpy as np
import pytest

from cspace.batch.margins import defect_margins
from cspace.defects import is_defective, reference
from mechanisms.userfile import load_model

DATA = Path(__file__).resolve().parent.parent / "data"

TANGENT_CAM_VARIANT = [0.02, 0.02, 4.98, 0.02, -4.98, -0.02, 17.565369759569055, 9.58,
                       6.998147903827619, 28.82, -6.998147903827618, 28.82,
                       -17.525369759569045, 9.580000000000002, -30.02, 33.98, 30.02, 34.02,
                       29.98, 43.98, -30.02, 43.98]
DISC_VARIANT = [-0.02, -0.02, 20.02, -4.98, -19.98, -5.02, -29.98, 14.98, 29.98, 15.02, 30.02,
                24.98, -29.98, 24.98]


def test_a_new_convex_vertex_is_left_to_the_full_test():
    m = load_model(DATA / "tangent_cam_flat_follower.json")
    ref = reference(m, "fast")
    u = np.array(TANGENT_CAM_VARIANT)
    full = is_defective(m, u, ref=ref)
    assert full.defective and "curves appeared" in full.message
    mb = defect_margins(m, u[None, :], ref)
    assert not mb.certified[0] and mb.defective[0]
    # without the fall-back the batch does not claim it either way
    assert not defect_margins(m, u[None, :], ref, fallback=False).certified[0]
    # the nominal has no such vertex: it stays certified
    assert defect_margins(m, m.nominal[None, :], ref, fallback=False).certified[0]


@pytest.mark.parametrize("seed", [7])
def test_a_start_stated_on_the_cam_agrees(seed):
    m = load_model(DATA / "disc_flat_follower.json")
    ref = reference(m, "fast")
    u = np.array(DISC_VARIANT)
    full = is_defective(m, u, ref=ref)
    assert not full.defective, full
    mb = defect_margins(m, u[None, :], ref)
    assert mb.certified[0] and not mb.defective[0]
    assert mb.start[0, 0] < 0          # the stated start lies just inside the disc
    # corners and interior points of the box: the two tests agree on each
    rng = np.random.default_rng(seed)
    U = m.nominal + m.tol * np.vstack([rng.choice([-1.0, 1.0], size=(20, len(m.nominal))),
                                       rng.uniform(-1, 1, size=(20, len(m.nominal)))])
    mb = defect_margins(m, U, ref)
    assert [bool(is_defective(m, x, ref=ref).defective) for x in U] == mb.defective.tolist()
