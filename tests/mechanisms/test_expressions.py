"""The expression language of model files."""

import pickle

import pytest

from cspace.errors import ExpressionError
from mechanisms.expressions import CONSTANTS, Expr, compile_expression, evaluate


def test_an_expression_evaluates_over_its_names():
    x = compile_expression("2 * r + sin(pi / 2) - d ** 2", "parameters[0]")
    assert isinstance(x, Expr) and {"r", "d"} <= x.names
    assert evaluate(x, {"r": 3.0, "d": 2.0, **CONSTANTS}) == pytest.approx(6.0 + 1.0 - 4.0)


def test_a_number_slot_passes_through():
    assert evaluate(1.25, {}) == 1.25


@pytest.mark.parametrize("src, token", [("__import__('os')", "__import__"),
                                        ("r.real", "r.real"), ("[1, 2]", "[1, 2]")])
def test_anything_outside_the_whitelist_is_refused_with_its_token(src, token):
    with pytest.raises(ExpressionError) as e:
        compile_expression(src, "let[0].value")
    assert e.value.path == "let[0].value"
    assert token in str(e.value)


def test_a_value_that_is_not_finite_is_an_error_naming_its_path():
    x = compile_expression("1 / (r - r)", "window[1]")
    with pytest.raises(ExpressionError) as e:
        evaluate(x, {"r": 2.0})
    assert e.value.path == "window[1]"


def test_a_compiled_expression_pickles():
    x = compile_expression("hypot(a, b)", "p")
    y = pickle.loads(pickle.dumps(x))
    assert evaluate(y, {"a": 3.0, "b": 4.0}) == 5.0
