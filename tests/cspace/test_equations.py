"""The closed-form contact equations (cspace.equations): which equation a
feature pair gives, and the kernel's solution against a hand-derived one."""

import json
import math

import numpy as np
import pytest

from cspace.contact import contact_curves
from cspace.equations import Equation, Kernel, equation_types
from cspace.features import Feature

from .batch.yoke import build_yoke


def _f(kind, **kw):
    return Feature(0, kind, (0, 0, 0), kind, (0.0, 0.0), **kw)


def test_equation_tags_are_an_enum_interchangeable_with_their_values():
    assert Equation.POINT_LINE == "pl" and Equation.POINT_CIRCLE == "pc"
    assert {"pl": 1}[Equation.POINT_LINE] == 1 and str(Equation.POINT_CIRCLE) == "pc"
    assert json.dumps([Equation.POINT_LINE]) == '["pl"]'


@pytest.mark.parametrize("a, b, want", [
    (_f("vertex"), _f("line"), [(Equation.POINT_LINE, 0, 0.0)]),
    (_f("line"), _f("vertex"), [(Equation.POINT_LINE, 1, 0.0)]),
    (_f("vertex"), _f("arc", radius=2.0), [(Equation.POINT_CIRCLE, 0, 2.0)]),
    (_f("arc", radius=2.0), _f("vertex"), [(Equation.POINT_CIRCLE, 1, 2.0)]),
    (_f("arc", radius=2.0), _f("line"), [(Equation.POINT_LINE, 0, 2.0)]),
    (_f("arc", radius=2.0, convex=False), _f("line"), []),        # a concave arc on a line
    (_f("arc", radius=1.0), _f("arc", radius=2.0), [(Equation.POINT_CIRCLE, 0, 3.0)]),
    # a convex arc inside a larger concave one: internal contact
    (_f("arc", radius=1.0), _f("arc", radius=3.0, convex=False),
     [(Equation.POINT_CIRCLE, 0, 2.0)]),
    (_f("arc", radius=3.0, convex=False), _f("arc", radius=1.0),
     [(Equation.POINT_CIRCLE, 0, 2.0)]),
    # a convex arc larger than the concave one holding it cannot touch it inside
    (_f("arc", radius=3.0), _f("arc", radius=1.0, convex=False), []),
    (_f("vertex"), _f("vertex"), []),
    (_f("line"), _f("line"), []),
])
def test_which_equation_a_feature_pair_gives(a, b, want):
    got = equation_types(a, b)
    assert got == want
    assert all(isinstance(t[0], Equation) for t in got)


def test_the_pin_on_a_yoke_face_solves_to_the_closed_form():
    """A pin of radius r at R from the crank centre against the yoke's right
    face x = s + w: the point-line equation with offset r, solved for the
    slide s = R cos q1 - (w - r)."""
    R, r, w = 20.0, 5.0, 5.03
    pair = build_yoke({"crank": R, "pin_r": r, "half_width": w})
    cs = contact_curves(pair, "fast", window=(0.0, 2 * math.pi, -30.0, 30.0))
    kernels = {c.label: c.kernel for c in cs.curves}
    k = next(k for lab, k in kernels.items() if "pin" in lab and "r.face" in lab)
    assert isinstance(k, Kernel) and k.eq == Equation.POINT_LINE and k.r == r
    q1 = np.linspace(0.0, 2 * math.pi, 17)
    q2, exist = k.solve(q1)
    assert q2.shape == (1, len(q1)) and np.all(exist >= 0)
    np.testing.assert_allclose(q2[0], R * np.cos(q1) - (w - r), atol=1e-12)
    m, q = k.margin(q1, 0)
    assert np.all(m > 0)            # the pin always touches the face inside its ends
    np.testing.assert_array_equal(q, q2[0])
