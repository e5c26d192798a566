import dataclasses
import pickle

import pytest

from cspace.accuracy import PRESETS, Accuracy, as_accuracy
from cspace.errors import InputError


def test_presets_order_speed_against_accuracy():
    f, d, p = (PRESETS[k] for k in ("fast", "default", "precise"))
    assert f.chord > d.chord > p.chord
    assert f.root_tol > d.root_tol > p.root_tol
    assert f.zone_samples < d.zone_samples < p.zone_samples
    assert f.sim_step > d.sim_step > p.sim_step


def test_frozen_and_replace():
    a = Accuracy.preset("default")
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.chord = 1.0
    b = a.replace(chord=1e-6)
    assert b.name == "custom" and b.chord == 1e-6 and a.chord != 1e-6
    assert pickle.loads(pickle.dumps(b)) == b


@pytest.mark.parametrize("kw", [{"chord": 0.0}, {"chord": float("nan")}, {"root_tol": -1},
                                {"zone_samples": 1}, {"chord": "x"}])
def test_bad_values(kw):
    with pytest.raises(InputError):
        Accuracy(**kw)


def test_as_accuracy():
    assert as_accuracy(None) is PRESETS["default"]
    assert as_accuracy("fast") is PRESETS["fast"]
    with pytest.raises(InputError, match="unknown accuracy preset 'turbo'"):
        as_accuracy("turbo")
    with pytest.raises(InputError):
        as_accuracy(3)
