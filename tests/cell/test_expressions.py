"""The one safe expression evaluator (suite/foundation/expressions.py): every limit refuses with
one UserError line; evaluation is in floats, NaN propagates, arrays never raise."""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.foundation import expressions as ex
from gnibench.suite.foundation.errors import UserError


def refused(text, match, **kw):
    with pytest.raises(UserError, match=match) as e:
        ex.parse(text, "w", **kw)
    message = str(e.value)
    assert "\n" not in message and len(message) < 600 and message.startswith("w: bad expression")
    assert "allowed:" in message


def test_text_size_is_bounded_before_parsing():
    refused("-" * 100000 + "1", "100001 characters; at most 1000")      # MemoryError in ast
    refused("1+" * 600 + "1", "characters; at most 1000")
    ex.parse("1 + " * 60 + "x", "w")


def test_depth_is_bounded():
    refused("-" * 120 + "x", "nested more than 100 deep")
    refused("abs(" * 120 + "x" + ")" * 120, "nested more than 100 deep|too many nested")
    refused("x" + " + x" * 120, "nested more than 100 deep")      # a sum is a left-deep chain
    ex.parse("-" * 90 + "x", "w")
    ex.parse("(" * 150 + "x" + ")" * 150, "w")                     # parentheses are no nodes


def test_node_count_is_bounded():
    refused("min(" + ", ".join(["x"] * 300) + ")", "more than 400 parts")


def test_numbers_are_bounded():
    refused("1e400", "not finite")
    refused("-1e400 + x", "not finite")
    refused("0x" + "f" * 400, "an integer literal of 1600 bits; at most 2\\^53")
    refused(str(2 ** 53 + 1) + " * x", "at most 2\\^53")
    ex.parse(str(2 ** 53) + " * x", "w")
    refused("1j", "not a number")
    refused("True", "not a number")
    refused("'text'", "not a number")


@pytest.mark.parametrize("text", ["1/0", "0/0", "x + 1/0", "2.0 ** 5000", "10 ** 400", "9 ** 9 ** 9",
                                  "log(0)", "sqrt(-1)", "(-8) ** 0.5", "exp(1000)"])
def test_constant_parts_must_be_finite(text):
    refused(text, "is not a finite number")


@pytest.mark.parametrize("text, why", [
    ("x.real", "Attribute"), ("x[0]", "Subscript"), ("__import__('os')", "calls only"),
    ("open('f')", "calls only"), ("abs(x=1)", "calls only"), ("abs(*x)", "calls only"),
    ("[1, 2]", "List"), ("x if x else 1", "IfExp"), ("lambda: 1", "Lambda"), ("x := 1", "invalid syntax|NamedExpr"),
    ("(1).__class__", "Attribute"), ("f'{x}'", "JoinedStr"), ("x @ x", "MatMult"),
    ("x // 2", "FloorDiv"), ("x % 2", "Mod"), ("x << 2", "LShift"), ("x", None),
])
def test_only_the_whitelisted_grammar(text, why):
    if why is None:
        ex.parse(text, "w")
    else:
        refused(text, why)


def test_names_and_grammar_can_be_restricted():
    refused("q1 + 1", "unknown name 'q1'", names=("p2", "q2"))
    refused("p2 > 1", "uses Compare", names=("p2",), logic=False)
    refused("abs(p2)", "calls a function; none is allowed here", names=("p2",), functions=())
    assert ex.parse("0.1 / p2", "w", names=("p2", "q2"), functions=(), logic=False).names == {"p2"}
    refused(3, "a string")


def test_scalar_evaluation_keeps_the_ledger_semantics():
    e = ex.parse("a / b >= 1e6 and 0 < c < 1", "w")
    assert ex.evaluate(e, {"a": 2e6, "b": 1.0, "c": 0.5}) is True
    assert ex.evaluate(e, {"a": math.nan, "b": 1.0, "c": 0.5}) is False
    assert ex.evaluate(ex.parse("x / 0", "w"), {"x": 1.0}) == math.inf
    assert math.isnan(ex.evaluate(ex.parse("x / y", "w"), {"x": 0.0, "y": 0.0}))
    assert ex.evaluate(ex.parse("x ** 5000", "w"), {"x": 10.0}) == math.inf
    assert math.isnan(ex.evaluate(ex.parse("log(x)", "w"), {"x": -1.0}))
    assert math.isnan(ex.evaluate(ex.parse("x ** 0.5", "w"), {"x": -1.0}))
    assert ex.evaluate(ex.parse("min(a, b, 3) + abs(-2)", "w"), {"a": 5, "b": 4}) == 5.0
    big = ex.evaluate(ex.parse("x * 2", "w"), {"x": 10 ** 300})      # an int value becomes a float
    assert isinstance(big, float)
    with pytest.raises(UserError, match="no value named 'y'"):
        ex.evaluate(ex.parse("x + y", "w"), {"x": 1.0})


def test_array_evaluation_never_raises():
    e = ex.parse("0.1 / p2 + p2 ** 400", "w", names=("p2", "q2"), functions=(), logic=False)
    p2 = np.array([-1.0, 0.0, 1e3, 2.0])
    v = ex.evaluate_array(e, {"p2": p2, "q2": p2})
    assert v[0] == pytest.approx(0.9) and np.isinf(v[1]) and np.isinf(v[2])
    assert v[3] == pytest.approx(0.05 + 2.0 ** 400)
