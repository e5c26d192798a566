"""The parametric-model contract: a user's own class that has its members works
with the defect test and the zones; an object that lacks one is refused with
a message naming what it lacks."""

import numpy as np
import pytest

from cspace.errors import InputError
from cspace.model import MEMBERS, SYNTHESIS_MEMBERS, ParametricModel, check_model, missing
from mechanisms.models import reciprocating_cam


class OwnModel:
    """Not a mechanisms.models.Model: only the members of the contract,
    delegated to a built-in model."""

    def __init__(self, inner):
        self._m = inner
        self.names, self.nominal, self.tol = inner.names, inner.nominal, inner.tol
        self.window, self.drive = inner.window, inner.drive

    def build(self, params=None):
        return self._m.build(params)

    def dependencies(self):
        return self._m.dependencies()


def test_the_builtin_model_and_an_own_class_satisfy_the_contract():
    m = reciprocating_cam()
    assert isinstance(m, ParametricModel) and missing(m, SYNTHESIS_MEMBERS) == []
    own = OwnModel(m)
    assert isinstance(own, ParametricModel) and missing(own) == []
    assert missing(own, SYNTHESIS_MEMBERS) == ["name", "n", "with_nominal", "with_tolerances",
                                               "parameters"]
    assert not isinstance(object(), ParametricModel)
    assert missing(object()) == list(MEMBERS)


def test_an_own_class_gets_the_same_defect_verdicts_and_zones():
    from cspace.defects import is_defective, reference
    from cspace.zones import contact_zones
    m = reciprocating_cam()
    own = OwnModel(m)
    ref_m, ref_o = reference(m, "fast"), reference(own, "fast")
    assert ref_o.d == ref_m.d
    rng = np.random.default_rng(2)
    for u in m.nominal + m.tol * rng.uniform(-1, 1, (4, m.n)):
        a = is_defective(m, u, ref=ref_m)
        b = is_defective(own, u, ref=ref_o)
        assert (a.defective, a.reasons, a.max_deviation) == (b.defective, b.reasons,
                                                             b.max_deviation)
    za = contact_zones(ref_m.spaces[0], m, 0, faces=[ref_m.faces[0]])
    zb = contact_zones(ref_o.spaces[0], own, 0, faces=[ref_o.faces[0]])
    assert za.to_dict() == zb.to_dict()


def test_what_lacks_a_member_is_refused_naming_it():
    from cspace.defects import reference
    with pytest.raises(InputError, match="lacks names, nominal, tol, build"):
        reference(object(), "fast")
    with pytest.raises(InputError, match="intent must be .* lacks dependencies"):
        check_model(type("M", (), {k: 1 for k in MEMBERS if k != "dependencies"})(), "intent")


def test_synthesis_refuses_a_model_without_what_it_adds():
    from synthesis import synthesize
    with pytest.raises(InputError, match="lacks name, n, with_nominal, with_tolerances, "
                                         "parameters"):
        synthesize(OwnModel(reciprocating_cam()), "fast")


def test_is_defective_refuses_an_accuracy_that_is_not_the_references():
    from cspace.defects import is_defective, reference
    m = reciprocating_cam()
    ref = reference(m, "fast")
    assert is_defective(m, m.nominal, ref=ref, accuracy="fast").defective is False
    with pytest.raises(InputError, match="differs from the accuracy"):
        is_defective(m, m.nominal, ref=ref, accuracy="default")
