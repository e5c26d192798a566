"""A reference passed to the defect test must be one of the model tested
(``cspace.defects.check_reference``): another model's reference (another
parameter count, pair count or parts) is an InputError, not a verdict."""

import dataclasses

import numpy as np
import pytest

from cspace.defects import check_reference, is_defective, reference
from cspace.errors import InputError
from cspace.geometry import Assembly, Pair
from mechanisms.models import Model, eccentric_cam

from .batch.yoke import build_yoke, yoke


@pytest.fixture(scope="module")
def yoke_ref():
    m = yoke(deviation=0.25)
    return m, reference(m, "fast")


def _renamed(v):
    p = build_yoke(v)
    return Pair(dataclasses.replace(p.driver, name="cam"), p.follower, units="mm", name="yoke")


def _two_pairs(v):
    p = build_yoke(v)
    return Assembly((p, dataclasses.replace(p, name="yoke2")))


def test_a_reference_of_another_parameter_count_is_refused(yoke_ref):
    _, ref = yoke_ref
    ec = eccentric_cam()
    with pytest.raises(InputError) as e:
        is_defective(ec, ref=ref)
    assert str(e.value) == (
        "ref is the reference of another model: its nominal vector has 3 values, model "
        "'eccentric_cam' has 7 parameters; pass a reference of this model "
        "(cspace.defects.reference(model, accuracy)) or ref=None")
    assert e.value.name == "ref"
    with pytest.raises(InputError, match="its nominal vector has 3 values"):
        is_defective(ec, ec.nominal, ref=ref, stop_early=True)


def test_a_reference_of_other_parts_or_pairs_is_refused(yoke_ref):
    m, ref = yoke_ref
    other = Model("yoke_b", m.parameters, _renamed, window=m.window, drive=m.drive,
                  q2_start=m.q2_start)
    with pytest.raises(InputError, match=r"its pair 0 has the parts \['crank', 'yoke'\], model "
                                         r"'yoke_b' builds \['cam', 'yoke'\]"):
        is_defective(other, ref=ref)
    two = Model("yokes", m.parameters, _two_pairs, window=m.window, drive=m.drive,
                q2_start=m.q2_start)
    with pytest.raises(InputError, match=r"it holds 1 pair\(s\), model 'yokes' builds 2"):
        is_defective(two, ref=ref)


def test_ref_must_be_a_reference(yoke_ref):
    m, _ = yoke_ref
    with pytest.raises(InputError, match="ref must be a cspace.defects.Reference .* got str"):
        is_defective(m, ref="fast")


def test_a_reference_of_another_design_of_the_same_model_is_used(yoke_ref):
    """The synthesis tests shifted designs against the initial reference."""
    m, ref = yoke_ref
    shifted = m.with_nominal(m.nominal + 0.5 * m.tol)
    assert not is_defective(shifted, ref=ref).defective
    check_reference(shifted, ref, shifted.pairs())
    # a variant that cannot be built is still a verdict, not a mismatch
    r = is_defective(m, np.array([20.0, 5.0, -1.0]), ref=ref)
    assert r.defective


def test_the_batch_does_not_offer_ref_none():
    # defect_margins needs a Reference: its message must not offer None
    import numpy as np
    import pytest

    from cspace.batch.margins import defect_margins
    from cspace.errors import InputError
    from mechanisms.models import reciprocating_cam
    m = reciprocating_cam()
    with pytest.raises(InputError) as e:
        defect_margins(m, np.asarray(m.nominal)[None, :], None)
    assert str(e.value).endswith("of model 'reciprocating_cam', got NoneType")
    assert "or None" not in str(e.value)
