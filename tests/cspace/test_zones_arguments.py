"""``contact_zones`` checks its arguments before any zone is computed:
pair_index within the pairs the model builds, and a C-space of that pair."""

import pytest

from cspace.errors import InputError
from cspace.zones import contact_zones
from mechanisms.analysis import model_cspaces
from mechanisms.models import eccentric_cam

from .batch.yoke import yoke


@pytest.fixture(scope="module")
def ecc():
    m = eccentric_cam()
    (cs,) = model_cspaces(m, accuracy="fast")
    return m, cs


@pytest.mark.parametrize("index", [1, -1, 5])
def test_pair_index_out_of_range(ecc, index):
    m, cs = ecc
    with pytest.raises(InputError) as e:
        contact_zones(cs, m, pair_index=index, accuracy="fast")
    assert str(e.value) == (f"pair_index {index} is out of range for model 'eccentric_cam'; "
                            f"allowed: 0 (it builds one pair)")
    assert e.value.name == "pair_index"


@pytest.mark.parametrize("index", [True, 0.0, "0", None])
def test_pair_index_must_be_an_int(ecc, index):
    m, cs = ecc
    with pytest.raises(InputError, match="pair_index must be an int, the index of a pair"):
        contact_zones(cs, m, index, accuracy="fast")


def test_the_cspace_must_be_of_that_pair(ecc):
    m, _ = ecc
    y = yoke()
    (cs_y,) = model_cspaces(y, accuracy="fast")
    with pytest.raises(InputError, match=r"cs is not the C-space of pair 0 of model "
                                         r"'eccentric_cam': its parts are \['crank', 'yoke'\], "
                                         r"that pair's are \['cam', 'follower'\]"):
        contact_zones(cs_y, m, accuracy="fast")
    with pytest.raises(InputError, match="cs must be the ConfigurationSpace of a pair"):
        contact_zones(m.build(), m, accuracy="fast")


def test_the_zones_of_a_good_index_are_computed(ecc):
    m, cs = ecc
    z = contact_zones(cs, m, 0, accuracy="fast")
    assert len(z.bands) >= 1
