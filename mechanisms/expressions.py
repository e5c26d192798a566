"""The expression language of model files: numbers, parameter and ``let``
names, ``+ - * / **``, unary minus and plus, parentheses, the constants
:data:`CONSTANTS` and the functions :data:`FUNCTIONS`.

Expressions are parsed with :mod:`ast` and checked against that whitelist;
anything else is rejected with :class:`~cspace.errors.ExpressionError` naming
the JSON path and the offending token.  Nothing from a file is ever executed.
A compiled :class:`Expr` is immutable and picklable, so a model built from a
file can go to a process pool.

Functions
---------
compile_expression(src, path) -> Expr
evaluate(x, env) -> float          a number slot: a float or an Expr
"""

from __future__ import annotations

import ast
import math
from dataclasses import dataclass

from cspace.errors import ExpressionError

__all__ = ["Expr", "compile_expression", "evaluate", "CONSTANTS", "FUNCTIONS",
           "MAX_EXPRESSION_CHARS", "ALLOWED_TEXT"]

MAX_EXPRESSION_CHARS = 2000

CONSTANTS = {"pi": math.pi, "e": math.e}


def _min(*a):
    return min(a)


def _max(*a):
    return max(a)


#: name -> (function, least number of arguments, most number of arguments or None)
FUNCTIONS = {
    "sin": (math.sin, 1, 1), "cos": (math.cos, 1, 1), "tan": (math.tan, 1, 1),
    "asin": (math.asin, 1, 1), "acos": (math.acos, 1, 1), "atan": (math.atan, 1, 1),
    "atan2": (math.atan2, 2, 2), "sqrt": (math.sqrt, 1, 1), "hypot": (math.hypot, 1, None),
    "abs": (abs, 1, 1), "min": (_min, 1, None), "max": (_max, 1, None),
    "radians": (math.radians, 1, 1), "degrees": (math.degrees, 1, 1),
}

_BINOPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
ALLOWED_TEXT = ("numbers, parameter and let names, + - * / **, unary minus, parentheses, "
                 "the constants pi and e, and the functions " + ", ".join(FUNCTIONS))

_FORBIDDEN = {  # node type -> how to name it in a message
    ast.Attribute: "attribute access", ast.Subscript: "subscript", ast.Lambda: "lambda",
    ast.ListComp: "comprehension", ast.SetComp: "comprehension",
    ast.DictComp: "comprehension", ast.GeneratorExp: "comprehension",
    ast.Compare: "comparison", ast.BoolOp: "boolean operator", ast.IfExp: "conditional",
    ast.List: "list", ast.Tuple: "tuple", ast.Dict: "dict", ast.Set: "set",
    ast.JoinedStr: "f-string", ast.Starred: "starred argument",
    ast.NamedExpr: "assignment expression", ast.Await: "await", ast.Yield: "yield",
    ast.YieldFrom: "yield",
}


# ----------------------------------------------------------------------- expressions
#
# A compiled expression is a tree of tuples ``(kind, src, ...)``: immutable and
# picklable, so a model built from a file can go to a process pool.
#   ("num", src, value)        ("name", src, name)
#   ("bin", src, op, a, b)     ("neg", src, a)     ("call", src, fname, (args...))

@dataclass(frozen=True)
class Expr:
    """A compiled expression: source text, tree, JSON path and the names it uses."""

    src: str
    tree: tuple
    path: str
    names: frozenset


def _seg(src, node) -> str:
    s = ast.get_source_segment(src, node)
    return s if s is not None else type(node).__name__


def _compile_node(src, node, path):
    if isinstance(node, ast.Constant):
        v = node.value
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ExpressionError(f"literal {v!r} is not a number in expression {src!r}; "
                                  f"allowed: {ALLOWED_TEXT}", path=path, token=repr(v))
        try:
            fv = float(v)
        except OverflowError:
            fv = math.inf
        if not math.isfinite(fv):
            raise ExpressionError(f"number literal {_seg(src, node)!r} is too large for a "
                                  f"float in {src!r}; literals must be finite", path=path,
                                  token=_seg(src, node))
        return ("num", _seg(src, node), fv)
    if isinstance(node, ast.Name):
        return ("name", node.id, node.id)
    if isinstance(node, ast.BinOp):
        op = _BINOPS.get(type(node.op))
        if op is None:
            tok = {ast.Mod: "%", ast.FloorDiv: "//", ast.MatMult: "@", ast.BitAnd: "&",
                   ast.BitOr: "|", ast.BitXor: "^", ast.LShift: "<<",
                   ast.RShift: ">>"}.get(type(node.op), type(node.op).__name__)
            raise ExpressionError(f"operator {tok!r} is not allowed in expression {src!r}; "
                                  f"allowed: {ALLOWED_TEXT}", path=path, token=tok)
        return ("bin", _seg(src, node), op, _compile_node(src, node.left, path),
                _compile_node(src, node.right, path))
    if isinstance(node, ast.UnaryOp):
        if isinstance(node.op, ast.USub):
            return ("neg", _seg(src, node), _compile_node(src, node.operand, path))
        if isinstance(node.op, ast.UAdd):
            return _compile_node(src, node.operand, path)
        tok = "not" if isinstance(node.op, ast.Not) else "~"
        raise ExpressionError(f"operator {tok!r} is not allowed in expression {src!r}; "
                              f"allowed: {ALLOWED_TEXT}", path=path, token=tok)
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name):
            tok = _seg(src, node.func)
            raise ExpressionError(f"only calls of the listed functions by name are allowed, "
                                  f"got {tok!r} in {src!r}; allowed: {ALLOWED_TEXT}",
                                  path=path, token=tok)
        fname = node.func.id
        if fname not in FUNCTIONS:
            raise ExpressionError(f"unknown function {fname!r} in expression {src!r}; "
                                  f"allowed functions: {', '.join(FUNCTIONS)}",
                                  path=path, token=fname)
        if node.keywords:
            raise ExpressionError(f"keyword arguments are not allowed in {src!r}", path=path,
                                  token=_seg(src, node))
        for a in node.args:
            if isinstance(a, ast.Starred):
                raise ExpressionError(f"starred arguments are not allowed in {src!r}",
                                      path=path, token=_seg(src, a))
        _, lo, hi = FUNCTIONS[fname]
        n = len(node.args)
        if n < lo or (hi is not None and n > hi):
            want = f"{lo}" if hi == lo else (f"at least {lo}" if hi is None else f"{lo}..{hi}")
            raise ExpressionError(f"{fname}() takes {want} argument(s), got {n} in {src!r}",
                                  path=path, token=_seg(src, node))
        return ("call", _seg(src, node), fname,
                tuple(_compile_node(src, a, path) for a in node.args))
    what = _FORBIDDEN.get(type(node), type(node).__name__)
    tok = _seg(src, node)
    raise ExpressionError(f"{what} is not allowed in expression {src!r} (at {tok!r}); "
                          f"allowed: {ALLOWED_TEXT}", path=path, token=tok)


def _names(tree, out):
    kind = tree[0]
    if kind == "name":
        out.add(tree[2])
    elif kind == "bin":
        _names(tree[3], out)
        _names(tree[4], out)
    elif kind == "neg":
        _names(tree[2], out)
    elif kind == "call":
        for a in tree[3]:
            _names(a, out)
    return out


def compile_expression(src: str, path: str = "") -> Expr:
    """Parse and check one expression string (nothing is evaluated).

    Raises
    ------
    ExpressionError
        Syntax errors and every construct outside the whitelist.
    """
    if not isinstance(src, str):
        raise ExpressionError(f"expected a number or an expression string, got "
                              f"{type(src).__name__} {src!r}", path=path, token=repr(src))
    if len(src) > MAX_EXPRESSION_CHARS:
        raise ExpressionError(f"expression longer than {MAX_EXPRESSION_CHARS} characters",
                              path=path, token=src[:40] + "...")
    if not src.strip():
        raise ExpressionError("empty expression", path=path, token=src)
    try:
        tree = ast.parse(src.strip(), mode="eval")
    except SyntaxError as e:
        tok = (e.text or src).strip()
        if e.offset:
            tok = src.strip()[max(e.offset - 1, 0):][:20] or tok
        raise ExpressionError(f"invalid expression {src!r}: {e.msg}", path=path,
                              token=tok) from None
    except (RecursionError, MemoryError, ValueError) as e:
        raise ExpressionError(f"invalid expression {src!r}: {type(e).__name__}", path=path,
                              token=src[:40]) from None
    try:
        node = _compile_node(src.strip(), tree.body, path)
    except RecursionError:
        raise ExpressionError(f"expression {src[:40]!r}... is nested too deeply", path=path,
                              token=src[:40]) from None
    return Expr(src, node, path, frozenset(_names(node, set())))


def _eval_tree(t, env, x: Expr):
    kind = t[0]
    if kind == "num":
        return t[2]
    if kind == "name":
        return env[t[2]]
    try:
        if kind == "bin":
            a = _eval_tree(t[3], env, x)
            b = _eval_tree(t[4], env, x)
            op = t[2]
            if op == "+":
                v = a + b
            elif op == "-":
                v = a - b
            elif op == "*":
                v = a * b
            elif op == "/":
                v = a / b
            else:
                v = a ** b
                if isinstance(v, complex):
                    raise ValueError("negative number raised to a fractional power")
        elif kind == "neg":
            v = -_eval_tree(t[2], env, x)
        else:
            fn = FUNCTIONS[t[2]][0]
            v = fn(*[_eval_tree(a, env, x) for a in t[3]])
    except ExpressionError:
        raise
    except (ValueError, ZeroDivisionError, OverflowError) as e:
        raise ExpressionError(f"cannot evaluate {t[1]!r} in {x.src!r}: {e}", path=x.path,
                              token=t[1]) from None
    v = float(v)
    if not math.isfinite(v):
        raise ExpressionError(f"{t[1]!r} in {x.src!r} evaluates to {v}; values must be finite",
                              path=x.path, token=t[1])
    return v


def evaluate(x, env) -> float:
    """Value of a number slot: a float or an Expr."""
    if isinstance(x, Expr):
        try:
            return _eval_tree(x.tree, env, x)
        except RecursionError:
            raise ExpressionError(f"expression {x.src[:40]!r}... is nested too deeply",
                                  path=x.path, token=x.src[:40]) from None
    return x
