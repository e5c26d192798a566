import dataclasses
import pickle

import pytest

from cspace.accuracy import PRESETS as GEOMETRY
from cspace.accuracy import Accuracy, as_accuracy
from cspace.errors import InputError
from synthesis.accuracy import PRESETS, SynthesisAccuracy, as_synthesis_accuracy


def test_presets_extend_the_geometry_presets_of_the_same_name():
    assert set(PRESETS) == set(GEOMETRY)
    for name, p in PRESETS.items():
        assert isinstance(p, Accuracy) and p.name == name
        assert p.geometry == GEOMETRY[name]
        assert as_accuracy(p) is p                    # passes unchanged to cspace
    f, d, pr = (PRESETS[k] for k in ("fast", "default", "precise"))
    assert f.search_eps > d.search_eps > pr.search_eps
    assert f.filter_eps > d.filter_eps > pr.filter_eps
    assert f.handover_reach <= d.handover_reach < pr.handover_reach


def test_the_record_has_the_keys_of_the_combined_accuracy_of_earlier_versions():
    """Checkpoints keep SynthesisState.accuracy as one flat mapping; a record
    rebuilds the same accuracy."""
    d = PRESETS["fast"].to_dict()
    assert {"chord", "zone_samples", "batch_gap_band", "search_eps", "filter_eps",
            "handover_reach", "name"} <= set(d)
    assert SynthesisAccuracy(**d) == PRESETS["fast"]


def test_conversions():
    assert as_synthesis_accuracy(None) is PRESETS["default"]
    assert as_synthesis_accuracy("precise") is PRESETS["precise"]
    # a plain geometry preset takes the synthesis knobs of its name
    assert as_synthesis_accuracy(GEOMETRY["fast"]) == PRESETS["fast"]
    # a custom one keeps its knobs and takes the default synthesis knobs
    c = as_synthesis_accuracy(GEOMETRY["fast"].replace(chord=1e-5))
    assert c.chord == 1e-5 and c.name == "custom" and c.search_eps == PRESETS["default"].search_eps
    s = PRESETS["default"].replace(search_eps=1e-4)
    assert isinstance(s, SynthesisAccuracy) and s.name == "custom" and s.search_eps == 1e-4
    assert as_synthesis_accuracy(s) is s
    assert pickle.loads(pickle.dumps(s)) == s
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.search_eps = 1.0


@pytest.mark.parametrize("bad", ["coarse", 3, object()])
def test_bad_accuracy(bad):
    with pytest.raises(InputError, match="accuracy|preset"):
        as_synthesis_accuracy(bad)


@pytest.mark.parametrize("kw", [{"search_eps": 0.0}, {"filter_eps": float("nan")},
                                {"handover_reach": -1}, {"handover_reach": 1.5}])
def test_bad_knobs(kw):
    with pytest.raises(InputError):
        PRESETS["default"].replace(**kw)


def test_geometry_accuracy_has_no_synthesis_knobs():
    for k in ("search_eps", "filter_eps", "handover_reach"):
        assert not hasattr(GEOMETRY["default"], k)
        with pytest.raises(TypeError):
            Accuracy(**{k: 1})
