"""A default deviation threshold that one large tolerance makes loose is named
(:func:`mechanisms.analysis.deviation_note`): the yoke's follower travels
from R down to -R + (w - r), 39.97 mm; d defaults to 5 max(tol) / L, a slide of 5 max(tol)."""

import numpy as np
import pytest

from cspace.defects import reference
from mechanisms.analysis import LOOSE_D, deviation_note

from tests.cspace.batch.yoke import yoke


def test_a_tolerance_of_two_mm_makes_the_default_d_a_quarter_of_the_stroke():
    m = yoke(t=2.0)                       # d = 10 mm of a 40 mm travel
    warn, text = deviation_note(m, reference(m, "fast"))
    assert warn
    assert "'yoke': d = 10 mm, 25% of the follower's travel 39.97 mm" in text
    assert "(crank +- 2)" in text and "state the model's 'deviation'" in text
    assert LOOSE_D == 0.25


def test_small_tolerances_or_a_stated_threshold_say_nothing():
    m = yoke()                            # d = 0.1 mm of 40
    assert deviation_note(m, reference(m, "fast")) is None
    big = yoke(t=2.0)
    assert deviation_note(big, reference(big, "fast", d=0.01)) is None
    stated = yoke(t=2.0, deviation=0.01)
    assert deviation_note(stated, reference(stated, "fast")) is None


@pytest.mark.parametrize("name", ["geneva", "reciprocating_cam", "optical_filter",
                                  "eccentric_cam"])
def test_the_built_in_models_are_not_flagged(models, name):
    m = models[name]
    assert deviation_note(m, reference(m, "fast")) is None
    assert np.all(m.tol >= 0)


def test_a_stated_threshold_beyond_the_whole_travel_is_named():
    """A stated d of at least the follower's whole travel never fires (a
    threshold in degrees, or in another unit); one below it says nothing."""
    m = yoke()
    L = reference(m, "fast").spaces[0].pair.char_length
    travel = 39.97 / L                    # C-space metric
    warn, text = deviation_note(m, reference(m, "fast", d=1.5 * travel))
    assert warn and "the stated deviation threshold is at least the follower's whole travel" \
        in text and "1.5 times the follower's whole travel 39.97 mm" in text
    assert deviation_note(m, reference(m, "fast", d=0.9 * travel)) is None


def test_an_angle_that_sets_the_default_d_is_named_with_its_arc():
    """The note named the largest tolerance compared as it is; d now counts
    an angle's as the arc it turns through at L, and the note says so."""
    import dataclasses
    m = yoke(t=2.0)
    ps = list(m.parameters)
    ps[1] = dataclasses.replace(ps[1], unit="rad")          # pin_r, as if an angle
    m = dataclasses.replace(m, parameters=tuple(ps))
    ref = reference(m, "fast")
    L = ref.spaces[0].pair.char_length
    assert ref.d == pytest.approx(5 * 2.0 * L / L)
    warn, text = deviation_note(m, ref)
    assert warn and f"(pin_r +- 2 rad, an arc of {2.0 * L:.4g} mm at L)" in text
