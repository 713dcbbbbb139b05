"""Expressions of user definitions, parsed by sympy from a safe subset of Python syntax.

A definition's Hamiltonian, right-hand side, integrals, exact solution, period and coefficients
are texts such as ``p^2/2 - cos(q)`` or ``1/(2-2^(1/3))``. They are read with Python's ``ast``
and built into sympy expressions node by node, never evaluated as Python: only numbers, the names
the definition allows (its states, parameters, ``t`` where it applies, ``pi``, ``E``), the
arithmetic operators (``^`` and ``**`` are powers) and calls of sympy's elementary functions by
name. Attribute access, subscripts, keywords, strings, comparisons, lambdas and every other call
are refused with a one-line error naming what is not allowed. A decimal literal is the exact
rational it writes (``0.1`` is 1/10), so coefficients stay exact.
"""
from __future__ import annotations

import ast
import math

FUNCTIONS = ("sqrt", "cbrt", "exp", "log", "sin", "cos", "tan", "asin", "acos", "atan", "atan2",
             "sinh", "cosh", "tanh", "asinh", "acosh", "atanh", "Abs", "abs", "sign")
CONSTANTS = ("pi", "E")
MAX_LENGTH = 20000
MAX_DEPTH = 200
MAX_EXPONENT = 1000          # |numeric exponent|: 10^(10^9) would never finish
MAX_MAGNITUDE = 1e300        # |a constant part|: exp(exp(exp(100))) would never finish either
MAX_DIGITS = 10000           # digits of an exact rational part: ((1+10^-99)^1000)^1000 neither


class ExpressionError(ValueError):
    """A text outside the safe subset (the message says what is not allowed)."""


def parse(text, names: dict | None = None):
    """The sympy expression of ``text``; ``names`` maps each allowed name to its sympy value
    (symbols, numbers). Numbers (int, float) are taken as they are, a float as the exact
    rational of its shortest repr."""
    import sympy as sp

    names = names or {}
    if isinstance(text, bool) or not isinstance(text, (str, int, float)):
        raise ExpressionError(f"{text!r} is not an expression (a number or a text)")
    if isinstance(text, float) and not math.isfinite(text):
        raise ExpressionError(f"{text!r} is not a finite number; allowed: numbers within ±1e300")
    if not isinstance(text, str):
        return sp.Integer(text) if isinstance(text, int) else sp.Rational(repr(float(text)))
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"the expression has {len(text)} characters (at most {MAX_LENGTH})")
    bad = next((c for c in text if not c.isprintable()), None)
    if bad is not None:
        raise ExpressionError(f"the expression contains {bad!r}; allowed: one line")
    source = text.strip().replace("^", "**")     # ^ binds as ** (Python's ^ binds below -)
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError as e:
        raise ExpressionError(f"{_short(text)} is not an expression ({e.msg})") from None
    except (ValueError, MemoryError, RecursionError) as e:   # the parser's own stack
        raise ExpressionError(f"{_short(text)} is not an expression ({type(e).__name__}: "
                              f"nested or chained too deep for Python's parser)") from None
    return _Builder(source, names, sp).build(tree.body, 0)


def _short(text: str) -> str:
    """``text`` quoted for a one-line error, at most 80 characters of it."""
    return repr(text if len(text) <= 80 else f"{text[:60]}...{text[-15:]} ({len(text)} "
                f"characters)")


class _Builder:
    def __init__(self, text: str, names: dict, sp):
        self.text, self.names, self.sp = text, names, sp
        self.functions = {"sqrt": sp.sqrt, "cbrt": sp.cbrt, "exp": sp.exp, "log": sp.log,
                          "sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "asin": sp.asin,
                          "acos": sp.acos, "atan": sp.atan, "atan2": sp.atan2, "sinh": sp.sinh,
                          "cosh": sp.cosh, "tanh": sp.tanh, "asinh": sp.asinh,
                          "acosh": sp.acosh, "atanh": sp.atanh, "Abs": sp.Abs, "abs": sp.Abs,
                          "sign": sp.sign}

    def refuse(self, node, what: str):
        segment = ast.get_source_segment(self.text, node) or what
        raise ExpressionError(f"{what} ({segment!r}) is not allowed; allowed: numbers, the names "
                              f"{', '.join(sorted(self.names)) or '(none)'}, {', '.join(CONSTANTS)}, "
                              f"+ - * / ^ and the functions {', '.join(FUNCTIONS)}")

    def bounded(self, node, value):
        """``value`` if it has free names or is a moderate number: a constant part beyond
        ±1e300 (or not finite, or an exact rational of more than 10^4 digits) is refused, so
        that nesting (exp(exp(exp(100))), powers of powers) cannot make the next step of the
        parse or evaluation run without end."""
        if value.free_symbols or not value.is_number:
            return value
        if isinstance(value, self.sp.Rational):
            if max(len(str(abs(value.p))), len(str(value.q))) > MAX_DIGITS:
                self.refuse(node, f"a number of more than {MAX_DIGITS} digits")
            if abs(value.p) > 10 ** 300 * value.q:
                self.refuse(node, f"a number beyond ±{MAX_MAGNITUDE:g}")
            return value
        try:
            v = complex(value.evalf(15))
        except (TypeError, ValueError, OverflowError):
            v = complex("nan")
        if not (abs(v) <= MAX_MAGNITUDE):            # also NaN
            self.refuse(node, f"a number beyond ±{MAX_MAGNITUDE:g} (or not finite)")
        return value

    def chain(self, node, depth: int) -> list:
        """The terms of a sum a + b - c + ... (a left-nested chain of + and -), each built one
        level down: a Hamiltonian of many terms is long, not deep."""
        terms = []
        while isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            term = self.build(node.right, depth + 1)
            terms.append(-term if isinstance(node.op, ast.Sub) else term)
            node = node.left
        terms.append(self.build(node, depth + 1))
        return terms[::-1]

    def build(self, node, depth: int):
        sp = self.sp
        if depth > MAX_DEPTH:
            raise ExpressionError(f"the expression is nested more than {MAX_DEPTH} deep")
        if isinstance(node, ast.Constant):
            v = node.value
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                self.refuse(node, f"the constant {v!r}")
            if isinstance(v, int):
                if abs(v) >= 10 ** 100:
                    self.refuse(node, "an integer of more than 100 digits")
                return sp.Integer(v)
            segment = ast.get_source_segment(self.text, node) or repr(v)
            return self.bounded(node, sp.Rational(segment.replace("_", "")))
        if isinstance(node, ast.Name):
            if node.id in self.names:
                return self.names[node.id]
            if node.id == "pi":
                return sp.pi
            if node.id == "E":
                return sp.E
            self.refuse(node, f"the name {node.id!r}")
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
            x = self.build(node.operand, depth + 1)
            return -x if isinstance(node.op, ast.USub) else x
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            return self.bounded(node, sp.Add(*self.chain(node, depth)))
        if isinstance(node, ast.BinOp):
            a, b = self.build(node.left, depth + 1), self.build(node.right, depth + 1)
            op = node.op
            if isinstance(op, ast.Mult):
                return self.bounded(node, a * b)
            if isinstance(op, ast.Div):
                if b == 0:
                    self.refuse(node, "a division by zero")
                return self.bounded(node, a / b)
            if isinstance(op, ast.Pow):
                if b.is_number and (not b.is_finite or abs(complex(b)) > MAX_EXPONENT):
                    self.refuse(node, f"an exponent beyond ±{MAX_EXPONENT}")
                if isinstance(a, sp.Rational) and isinstance(b, sp.Rational) and \
                        abs(b) * max(len(str(abs(a.p))), len(str(a.q))) > MAX_DIGITS:
                    self.refuse(node, f"a power of more than {MAX_DIGITS} digits")
                return self.bounded(node, a ** b)
            self.refuse(node, f"the operator {type(op).__name__}")
        if isinstance(node, ast.Call):
            fn = node.func
            if not isinstance(fn, ast.Name) or fn.id not in self.functions:
                self.refuse(node, "this call")
            if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
                self.refuse(node, "keyword or starred arguments")
            args = [self.build(a, depth + 1) for a in node.args]
            want = 2 if fn.id == "atan2" else 1
            if len(args) != want:
                self.refuse(node, f"{fn.id} with {len(args)} arguments (it takes {want})")
            return self.bounded(node, self.functions[fn.id](*args))
        if isinstance(node, ast.Attribute):
            self.refuse(node, "attribute access")
        self.refuse(node, f"the syntax {type(node).__name__}")


def number(text, names: dict | None = None):
    """A constant expression (a coefficient, a parameter value): its sympy value, refused when
    it has free names or is not a finite real number."""
    expr = parse(text, names)
    if expr.free_symbols:
        raise ExpressionError(f"{text!r} is not a number (free names "
                              f"{', '.join(sorted(map(str, expr.free_symbols)))})")
    value = complex(expr.evalf(30))
    if value.imag != 0 or value.real != value.real or abs(value.real) == float("inf"):
        raise ExpressionError(f"{text!r} is not a finite real number")
    return expr
