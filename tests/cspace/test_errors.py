"""The exception tree of ``cspace.errors``: bases, attributes and messages."""

import inspect
import pickle

import pytest

from cspace import errors as E


def _exception_classes():
    return [obj for _, obj in inspect.getmembers(E, inspect.isclass)
            if issubclass(obj, BaseException) and obj.__module__ == E.__name__]


def test_every_exception_of_the_module_is_exported_and_rooted_in_cspace_error():
    classes = _exception_classes()
    assert {c.__name__ for c in classes} == set(E.__all__)
    assert all(issubclass(c, E.CSpaceError) for c in classes)
    assert issubclass(E.CSpaceError, Exception) and not issubclass(E.CSpaceError, ValueError)


@pytest.mark.parametrize("cls", ["InputError", "NonFiniteError", "DegenerateGeometryError",
                                 "ZeroLengthSegmentError", "NonPositiveRadiusError",
                                 "OpenLoopError", "SelfIntersectionError", "OrientationError",
                                 "ZeroDirectionError", "InvalidModelError", "ParameterError",
                                 "FileFormatError", "ExpressionError"])
def test_bad_value_errors_are_value_errors(cls):
    """Callers that do not know the library catch bad values with ``except ValueError``."""
    c = getattr(E, cls)
    assert issubclass(c, ValueError) and issubclass(c, E.CSpaceError)
    with pytest.raises(ValueError):
        raise c("bad value")


def test_the_tree_has_the_documented_parents():
    assert issubclass(E.NonFiniteError, E.InputError)
    for c in (E.ZeroLengthSegmentError, E.NonPositiveRadiusError, E.OpenLoopError,
              E.SelfIntersectionError, E.OrientationError, E.ZeroDirectionError):
        assert issubclass(c, E.DegenerateGeometryError)
        assert not issubclass(c, E.InputError)
    assert issubclass(E.ParameterError, E.InvalidModelError)
    assert issubclass(E.ExpressionError, E.FileFormatError)
    # not a bad value: a missing package, an invalid floating-point operation
    assert issubclass(E.MissingExtraError, ImportError)
    assert not issubclass(E.MissingExtraError, ValueError)
    assert issubclass(E.NumericalError, ArithmeticError)
    assert not issubclass(E.NumericalError, ValueError)


def test_input_error_carries_name_and_value():
    e = E.NonFiniteError("x must be finite, got nan", name="x", value=float("nan"))
    assert e.name == "x" and e.value != e.value          # the NaN itself
    assert str(e) == "x must be finite, got nan"
    bare = E.InputError("no details")
    assert bare.name is None and bare.value is None


def test_degenerate_geometry_error_says_where():
    e = E.OpenLoopError("loop does not close", where="cam.rim")
    assert e.where == "cam.rim" and str(e) == "loop does not close"
    assert E.SelfIntersectionError("crosses").where is None


def test_file_format_error_prefixes_the_path():
    e = E.FileFormatError("radius must be > 0", path="parts[1].loops[0][3].radius")
    assert str(e) == "parts[1].loops[0][3].radius: radius must be > 0"
    assert e.path == "parts[1].loops[0][3].radius"
    plain = E.FileFormatError("not JSON")
    assert str(plain) == "not JSON" and plain.path == ""


def test_expression_error_carries_path_and_token():
    e = E.ExpressionError("unknown name", path="let[2].value", token="rb2")
    assert str(e) == "let[2].value: unknown name"
    assert e.path == "let[2].value" and e.token == "rb2"
    assert isinstance(e, E.FileFormatError)


def test_missing_extra_error_names_the_package_and_the_install_command():
    e = E.MissingExtraError("ezdxf", "dxf")
    assert e.module == "ezdxf" and e.extra == "dxf"
    assert "'ezdxf'" in str(e)
    assert "pip install 'cspace-tolerance[dxf]'" in str(e)
    with pytest.raises(ImportError):
        raise e


@pytest.mark.parametrize("err", [
    E.InputError("m", name="a", value=1),
    E.DegenerateGeometryError("d", where="w"),
    E.FileFormatError("bad", path="x[0]"),
    E.ExpressionError("bad", path="p", token="t"),
    E.NumericalError("0/0"),
], ids=lambda e: type(e).__name__)
def test_errors_survive_pickling_with_message_and_attributes(err):
    """Errors raised in a process-pool worker travel to the parent by pickle."""
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is type(err)
    assert str(back) == str(err)
    assert back.__dict__ == err.__dict__


def test_missing_extra_error_survives_pickling():
    err = E.MissingExtraError("distributed", "dask")
    back = pickle.loads(pickle.dumps(err))
    assert str(back) == str(err) and back.extra == "dask"
