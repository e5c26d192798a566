"""Coordinates beyond what double precision resolves are typed errors, and no
C-space is returned that passed through a NaN (issue 23, item 6)."""

import copy
import warnings

import numpy as np
import pytest

from cspace.errors import FileFormatError, InputError, NumericalError
from cspace.freespace import configuration_space
from cspace.geometry import MAX_ARM_REL, Part, Rotation
from cspace.io import pair_from_dict, pair_to_dict


@pytest.fixture(scope="module")
def geneva_dict():
    from mechanisms.models import geneva
    return pair_to_dict(geneva().build())


@pytest.mark.parametrize("far", [1.7e99, 1e50, 1e20, 1e9])
@pytest.mark.parametrize("part", [0, 1])
def test_far_rotation_centre_is_refused(geneva_dict, far, part):
    d = copy.deepcopy(geneva_dict)
    d["parts"][part]["axis"]["center"] = [far, 0.0]
    with pytest.raises(FileFormatError, match=rf"parts\[{part}\].*times its own size.*"
                                              rf"at most {MAX_ARM_REL:g} times"):
        pair_from_dict(d)


def test_part_with_far_centre_is_an_input_error(geneva_dict):
    p = pair_from_dict(geneva_dict)
    size = p.follower.size
    with pytest.raises(InputError, match="rotation centre"):
        Part("w", p.follower.loops, Rotation((2 * MAX_ARM_REL * size, 0.0)))
    # within the bound: accepted
    Part("w", p.follower.loops, Rotation((0.5 * MAX_ARM_REL * size, 0.0)))


def test_far_centre_without_validation_is_a_numerical_error(geneva_dict):
    # with validation off (as synthesis variants are built), the old failure: a
    # 0/0 inside the contact equations must not give a clean-looking C-space
    from cspace.geometry import trusted
    d = copy.deepcopy(geneva_dict)
    d["parts"][1]["axis"]["center"] = [1.7e99, 0.0]
    with trusted():
        pair = pair_from_dict(d)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(NumericalError, match="invalid floating-point operation"):
            configuration_space(pair, "fast")


def test_any_invalid_operation_is_a_numerical_error(monkeypatch, geneva_dict):
    import cspace.freespace as fs
    real = fs.contact_curves

    def nan_inside(*a, **kw):
        np.zeros(1) / np.zeros(1)
        return real(*a, **kw)

    monkeypatch.setattr(fs, "contact_curves", nan_inside)
    with pytest.raises(NumericalError):
        configuration_space(pair_from_dict(geneva_dict), "fast")
