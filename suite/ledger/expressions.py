"""The small expression language of the ledger: arithmetic and comparisons over named numbers.

A claim states what it measures and when it passes as expressions, e.g. ``measured = "a / b"``,
``passes = "measured >= 1e6"``. They are parsed with :mod:`ast` and evaluated by walking the tree:
numbers, names, + - * / **, unary minus, comparisons (chained), ``and``/``or``/``not``, and the
functions below. Nothing else is accepted (no attribute access, no calls of other functions), so a
ledger entry is data, not code.
"""
from __future__ import annotations

import ast
import math
import operator

import numpy as np
from gnibench.suite.foundation.errors import UserError

FUNCTIONS = {"abs": abs, "min": min, "max": max, "log10": math.log10, "log": math.log,
             "exp": math.exp, "sqrt": math.sqrt}
_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.Pow: operator.pow}
_COMPARE = {ast.Lt: operator.lt, ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge,
            ast.Eq: operator.eq, ast.NotEq: operator.ne}


def parse(text: str, where: str) -> ast.Expression:
    """Parse and check an expression (a UserError naming ``where`` when it is not allowed)."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as e:
        raise UserError(f"{where}: bad expression {text!r} ({e.msg})") from None
    for node in ast.walk(tree):
        ok = isinstance(node, (ast.Expression, ast.Constant, ast.Name, ast.Load, ast.BinOp,
                               ast.UnaryOp, ast.USub, ast.UAdd, ast.Compare, ast.BoolOp,
                               ast.And, ast.Or, ast.Not, ast.Call, *_BINARY, *_COMPARE))
        if isinstance(node, ast.Call):
            ok = isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS and not node.keywords
        if isinstance(node, ast.Constant):
            ok = isinstance(node.value, (int, float)) and not isinstance(node.value, bool)
        if not ok:
            raise UserError(f"{where}: expression {text!r} uses {type(node).__name__}; allowed: "
                            f"numbers, names, + - * / **, comparisons, and/or/not, "
                            f"{', '.join(FUNCTIONS)}")
    return tree


def names(tree: ast.Expression) -> set[str]:
    """The variable names an expression reads (function names excluded)."""
    calls = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and id(n) not in calls}


def evaluate(tree: ast.Expression, values: dict):
    """The value of a parsed expression; NaN propagates, a comparison with NaN is False."""
    return _eval(tree.body, values)


def _eval(node, values):
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        value = values[node.id]
        return value if isinstance(value, bool) else float(value)
    if isinstance(node, ast.BinOp):
        a, b = _eval(node.left, values), _eval(node.right, values)
        with np.errstate(all="ignore"):
            try:
                return _BINARY[type(node.op)](a, b)
            except ZeroDivisionError:
                return math.inf if a != 0 else math.nan
            except OverflowError:
                return math.inf
    if isinstance(node, ast.UnaryOp):
        v = _eval(node.operand, values)
        return (not v) if isinstance(node.op, ast.Not) else (-v if isinstance(node.op, ast.USub)
                                                             else v)
    if isinstance(node, ast.BoolOp):
        vals = [bool(_eval(v, values)) for v in node.values]
        return all(vals) if isinstance(node.op, ast.And) else any(vals)
    if isinstance(node, ast.Compare):
        left = _eval(node.left, values)
        for op, comp in zip(node.ops, node.comparators):
            right = _eval(comp, values)
            if not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True
    if isinstance(node, ast.Call):
        args = [_eval(a, values) for a in node.args]
        try:
            return float(FUNCTIONS[node.func.id](*args))
        except (ValueError, OverflowError):
            return math.nan
    raise TypeError(type(node).__name__)                  # unreachable after parse()
