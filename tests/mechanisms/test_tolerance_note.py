"""Tolerances below what the engine resolves are named
(:func:`mechanisms.analysis.tolerance_note`): the yoke's size is some 70 mm,
so the floor is 7e-5 mm."""

import json
import warnings

import pytest

from mechanisms.analysis import TOL_FLOOR_REL, ToleranceResolutionWarning, tolerance_note
from mechanisms.models import BUILTIN

from tests.cspace.batch.yoke import yoke


def test_a_tolerance_below_the_floor_is_named():
    m = yoke(t=1e-6)
    size = max(p.size for p in m.pairs())
    assert 1e-6 < TOL_FLOOR_REL * size
    warn, text = tolerance_note(m)
    assert warn and "3 tolerance(s) below 1e-06 of the model's size" in text
    assert "crank +- 1e-06" in text and "docs/limits.md" in text


def test_tolerances_above_the_floor_or_zero_say_nothing():
    assert tolerance_note(yoke()) is None
    assert tolerance_note(yoke(t=0.0)) is None
    size = max(p.size for p in yoke().pairs())
    assert tolerance_note(yoke(t=2 * TOL_FLOOR_REL * size)) is None


@pytest.mark.parametrize("name", sorted(BUILTIN))
def test_the_built_in_models_are_not_flagged(name):
    assert tolerance_note(BUILTIN[name]()) is None


def test_synthesis_and_analyze_warn(tmp_path, capsys):
    """``synthesis.synthesize`` warns (ToleranceResolutionWarning) and
    ``cspace-tol analyze`` logs it."""
    from synthesis import synthesize
    from synthesis.cli.main import main
    m = yoke(t=1e-6)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        synthesize(m, accuracy="fast", max_iter=1)
    assert any(issubclass(w.category, ToleranceResolutionWarning) for w in got)
    from tests.cspace.slotted_yoke import yoke_document
    params = [("a", 30.0, 1e-6), ("r", 5.0, 1e-6), ("hw", 5.1, 0.01), ("s", 40.0, 0.0),
              ("B", 60.0, 0.0), ("H", 60.0, 0.0)]
    f = tmp_path / "yoke.json"
    f.write_text(json.dumps(yoke_document([{"name": n, "nominal": v, "tol": t}
                                           for n, v, t in params])))
    assert main(["analyze", str(f), "--out", str(tmp_path / "a"), "--preset", "fast",
                 "--no-plots"]) == 0
    err = capsys.readouterr().err
    assert "warning: 2 tolerance(s) below 1e-06" in err and "a +- 1e-06, r +- 1e-06" in err
