"""The one safe expression language of gnibench: arithmetic (and, for the ledger, comparisons and
logic) over named numbers, parsed with :mod:`ast` and evaluated by walking a checked tree.

Used by the claims ledger (``measured = "a / b"``, ``passes = "measured >= 1e6"``) and by the
figures (a field's ``fixed = { q1 = "0.1 / p2" }``). Everything is checked when the file is read,
before any work, and a bad expression is one :class:`UserError` line:

* the text is at most :data:`MAX_CHARS` characters (before :func:`ast.parse` sees it: the parser
  itself runs out of memory on 100000 unary minus signs), its tree at most :data:`MAX_DEPTH`
  deep and :data:`MAX_NODES` nodes;
* only the node types of the chosen grammar: numbers, names, + - * / **, unary + -, and with
  ``logic=True`` comparisons (chained) and ``and``/``or``/``not``; calls only of the whitelisted
  functions by name (no attribute access, no subscripts, no keywords, no other literals);
* names only those given (when the caller knows them);
* numbers bounded: an integer literal at most 2^53 in magnitude (so every literal is an exact
  float: ``0x`` followed by 400 hex digits is refused), a float literal finite (``1e400`` is
  refused);
* every part without names is evaluated once while parsing, in floats, and must give a finite
  number (``1/0``, ``2.0 ** 5000``, ``log(0)``, ``0/0`` are refused).

Evaluation is in floats (never Python's unbounded integers). :func:`evaluate` works on scalars
with the ledger's semantics (NaN propagates, a comparison with NaN is False, x/0 is inf);
:func:`evaluate_array` evaluates arithmetic on numpy arrays (a figure's grid), where division by
zero and overflow give inf or NaN at those points, as the drawing expects.
"""
from __future__ import annotations

import ast
import math
import operator
from dataclasses import dataclass

import numpy as np
from gnibench.suite.foundation.errors import UserError

MAX_CHARS = 1000
MAX_DEPTH = 100
MAX_NODES = 400
MAX_INT = 2 ** 53

#: name -> (scalar function, array function); scalar results outside a function's domain are NaN
FUNCTIONS = {"abs": (abs, np.abs), "min": (min, None), "max": (max, None),
             "log10": (math.log10, np.log10), "log": (math.log, np.log), "exp": (math.exp, np.exp),
             "sqrt": (math.sqrt, np.sqrt)}
_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.Pow: operator.pow}
_ARRAY = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide,
          ast.Pow: np.power}
_COMPARE = {ast.Lt: operator.lt, ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge,
            ast.Eq: operator.eq, ast.NotEq: operator.ne}
_ARITHMETIC = (ast.Expression, ast.Constant, ast.Name, ast.Load, ast.BinOp, ast.UnaryOp, ast.USub,
               ast.UAdd, *_BINARY)
_LOGIC = (ast.Compare, ast.BoolOp, ast.And, ast.Or, ast.Not, *_COMPARE)


@dataclass(frozen=True)
class Expression:
    """A checked expression: its text, its tree and the names it reads."""

    text: str
    tree: ast.Expression
    names: frozenset[str]


def _short(text: str) -> str:
    return repr(text if len(text) <= 60 else text[:57] + "...")


def parse(text, where: str, *, names=None, functions=tuple(FUNCTIONS), logic: bool = True
          ) -> Expression:
    """Check an expression (one UserError line naming ``where`` when it is not allowed).

    ``names``: the names it may read (None: any; the caller supplies them when evaluating);
    ``functions``: the whitelisted functions it may call; ``logic``: comparisons and/or/not."""
    allowed = ("numbers" + (", the names " + ", ".join(sorted(names)) if names is not None
                            else ", names") + ", + - * / **, parentheses"
               + (", comparisons, and/or/not" if logic else "")
               + (", " + ", ".join(functions) if functions else ""))

    def bad(why: str) -> UserError:
        return UserError(f"{where}: bad expression {_short(text)} ({why}); allowed: {allowed}")

    if not isinstance(text, str):
        raise UserError(f"{where}: bad expression {text!r}; allowed: a string: {allowed}")
    if len(text) > MAX_CHARS:
        raise bad(f"{len(text)} characters; at most {MAX_CHARS}")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as e:
        raise bad(e.msg) from None
    except (ValueError, MemoryError, RecursionError) as e:
        raise bad(type(e).__name__) from None
    _check_shape(tree, bad)
    kinds = _ARITHMETIC + (_LOGIC if logic else ())
    calls = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            if not (isinstance(node.func, ast.Name) and node.func.id in functions
                    and not node.keywords and node.args
                    and not any(isinstance(a, ast.Starred) for a in node.args)):
                raise bad("calls only " + ", ".join(functions) if functions
                          else "calls a function; none is allowed here")
            calls.add(id(node.func))
            continue
        if not isinstance(node, kinds):
            raise bad(f"uses {type(node).__name__}")
        if isinstance(node, ast.Constant):
            value = node.value
            if type(value) not in (int, float):
                raise bad(f"the literal {_short(repr(value))} is not a number")
            if type(value) is int and abs(value) > MAX_INT:
                raise bad(f"an integer literal of {value.bit_length()} bits; at most 2^53")
            if type(value) is float and not math.isfinite(value):
                raise bad("a number literal that is not finite")
    read = frozenset(n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and id(n) not in calls)
    if names is not None and read - set(names):
        raise bad(f"unknown name {min(read - set(names))!r}")
    _fold_constants(tree.body, bad)
    return Expression(text, tree, read)


def _check_shape(tree: ast.AST, bad) -> None:
    """At most MAX_NODES nodes and MAX_DEPTH levels (iteratively: no recursion on user input)."""
    stack, count = [(tree, 1)], 0
    while stack:
        node, depth = stack.pop()
        count += 1
        if count > MAX_NODES:
            raise bad(f"more than {MAX_NODES} parts")
        if depth > MAX_DEPTH:
            raise bad(f"nested more than {MAX_DEPTH} deep")
        stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))


def _fold_constants(node: ast.AST, bad) -> bool:
    """Evaluate every part without names once (in floats); True when ``node`` has no names."""
    if isinstance(node, ast.Name):
        return False
    children = node.args if isinstance(node, ast.Call) else list(ast.iter_child_nodes(node))
    folded = [_fold_constants(c, bad) for c in children]     # every child, no short cut
    constant = all(folded)
    if constant and not isinstance(node, ast.Constant) and isinstance(node, ast.expr):
        try:
            value = _eval(node, {}, strict=True)
        except (ZeroDivisionError, OverflowError, ValueError, TypeError) as e:
            raise bad(f"{ast.unparse(node)} is not a finite number: {e}") from None
        if isinstance(value, float) and not math.isfinite(value):
            raise bad(f"{ast.unparse(node)} is not a finite number")
    return constant


def names(expression: Expression) -> set[str]:
    """The variable names an expression reads (function names excluded)."""
    return set(expression.names)


def evaluate(expression: Expression, values: dict):
    """The value of a checked expression over named numbers (floats, or booleans); NaN propagates,
    a comparison with NaN is False, x/0 is inf (NaN for 0/0), an overflow is inf."""
    missing = expression.names - set(values)
    if missing:
        raise UserError(f"expression {_short(expression.text)}: no value named "
                        f"{min(missing)!r}; known: {', '.join(sorted(values))}")
    return _eval(expression.tree.body, values, strict=False)


def _eval(node, values, strict: bool):
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        value = values[node.id]
        return value if isinstance(value, bool) else float(value)
    if isinstance(node, ast.BinOp):
        a, b = _eval(node.left, values, strict), _eval(node.right, values, strict)
        try:
            out = _BINARY[type(node.op)](a, b)
        except ZeroDivisionError:
            if strict:
                raise
            return math.inf if a != 0 else math.nan
        except OverflowError:
            if strict:
                raise
            return math.inf
        if isinstance(out, complex):       # a negative number to a fractional power
            if strict:
                raise ValueError("a complex result")
            return math.nan
        return out
    if isinstance(node, ast.UnaryOp):
        v = _eval(node.operand, values, strict)
        return (not v) if isinstance(node.op, ast.Not) else (-v if isinstance(node.op, ast.USub)
                                                             else v)
    if isinstance(node, ast.BoolOp):
        vals = [bool(_eval(v, values, strict)) for v in node.values]
        return all(vals) if isinstance(node.op, ast.And) else any(vals)
    if isinstance(node, ast.Compare):
        left = _eval(node.left, values, strict)
        for op, comp in zip(node.ops, node.comparators):
            right = _eval(comp, values, strict)
            if not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True
    if isinstance(node, ast.Call):
        args = [_eval(a, values, strict) for a in node.args]
        try:
            return float(FUNCTIONS[node.func.id][0](*args))
        except (ValueError, OverflowError, TypeError):
            if strict:
                raise
            return math.nan
    raise TypeError(type(node).__name__)                  # unreachable after parse()


def evaluate_array(expression: Expression, arrays: dict) -> np.ndarray | float:
    """An arithmetic expression on numpy arrays (a figure's grid): inf or NaN where a division by
    zero or an overflow happens, never an exception."""
    def ev(node):
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name):
            return np.asarray(arrays[node.id], dtype=float)
        if isinstance(node, ast.UnaryOp) and not isinstance(node.op, ast.Not):
            v = ev(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.BinOp):
            return _ARRAY[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.Call) and FUNCTIONS[node.func.id][1] is not None:
            return FUNCTIONS[node.func.id][1](*[ev(a) for a in node.args])
        raise UserError(f"expression {_short(expression.text)}: {type(node).__name__} is not "
                        "arithmetic on arrays")

    with np.errstate(all="ignore"):
        return ev(expression.tree.body)
