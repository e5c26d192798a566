"""The start of a variant whose channel moved by more than its width
(:func:`cspace.defects.assembled_start`): an eccentric disc in a yoke window
0.01 mm taller than the disc, whose axis sits off the nominal.  The variant's
free interval at the start no longer overlaps the nominal's, yet it is the
same channel (the same curves bound it): the full test starts the follower
there, as the batched test does, and the part runs free."""

import copy
import math

import numpy as np

from cspace.batch.margins import defect_margins
from cspace.defects import assembled_start, is_defective, reference
from cspace.freespace import configuration_space
from mechanisms.userfile import model_from_dict

YOKE = {
    "format": "cspace-model", "version": 1, "name": "ecc_yoke", "units": "mm",
    "parameters": [
        {"name": "cx", "nominal": 0.0, "tol": 0.01},
        {"name": "cy", "nominal": 0.0, "tol": 0.01},
        {"name": "ecc", "nominal": 5.0, "tol": 0.02},
        {"name": "ph", "nominal": 30.0, "tol": 0.5, "unit": "deg"},
        {"name": "R", "nominal": 15.0, "tol": 0.02},
        {"name": "H", "nominal": 30.1, "tol": 0.15},
        {"name": "W", "nominal": 50.0, "tol": 0.1}],
    "let": [{"name": "dx", "value": "cx + ecc*cos(ph)"},
            {"name": "dy", "value": "cy + ecc*sin(ph)"}],
    "drive": [0, "2*pi"], "q2_start": [2.5],
    "pairs": [{"name": "cam_yoke", "parts": [
        {"name": "disc", "axis": {"type": "rotation", "center": ["cx", "cy"]},
         "loops": [[{"type": "arc", "name": "rim", "center": ["dx", "dy"], "radius": "R",
                     "start_angle": 0, "end_angle": "2*pi", "ccw": True}]]},
        {"name": "yoke", "axis": {"type": "translation", "direction": [0, 1],
                                  "origin": [0, 0]},
         "loops": [{"polyline": [[-35, -25], [35, -25], [35, 25], [-35, 25]]},
                   {"polyline": [["-W/2", "-H/2"], ["-W/2", "H/2"], ["W/2", "H/2"],
                                 ["W/2", "-H/2"]]}]}]}]}

#: inside the box: H - 2R = 0.01 mm of play, the disc's centre 0.058 mm above
#: the nominal's
VARIANT = np.array([0.0, 0.01, 5.02, math.radians(30.5), 15.02, 30.05, 50.0])


def test_a_variant_starts_in_its_channel_when_it_moved_past_its_width():
    m = model_from_dict(copy.deepcopy(YOKE))
    ref = reference(m, "fast")
    nom_cs = ref.spaces[0]
    var_cs = configuration_space(m.build(VARIANT), ref.accuracy, window=m.window)
    (lo0, hi0, _), = [iv for iv in nom_cs.free_intervals(0.0) if iv[0] <= 2.5 <= iv[1]]
    # the variant's interval nearest to the start, between the same curves
    (lo, hi, _), = [iv for iv in var_cs.free_intervals(0.0) if 0.0 < iv[0] < 10.0]
    # no overlap: the variant's channel lies above the nominal's
    assert lo > hi0 and hi - lo < 0.011
    q2 = assembled_start(nom_cs, var_cs, (0.0, 2.5))
    assert lo < q2 < hi
    r = is_defective(m, VARIANT, ref=ref)
    assert not r.defective, r
    mb = defect_margins(m, VARIANT[None, :], ref)
    assert not mb.defective[0]
    # a variant whose window is smaller than its disc still jams, at the start
    jam = VARIANT.copy()
    jam[5] = 30.03
    assert is_defective(m, jam, ref=ref).defective
    assert defect_margins(m, jam[None, :], ref).defective[0]
