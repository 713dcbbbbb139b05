"""Which ledger entries bound a measured number on one side only.

A pass criterion such as ``measured >= 10`` reads one side: a bug that makes the number absurdly
large passes it too. Where the seed gives the other side (a number "of order 10⁻¹⁰", a factor
"10⁶ times"), the entry states it; where it does not (the seed says "smaller than", "better",
"grows"; or the number is a distance, ≥ 0 by construction), the entry says why in its field
``one_sided``. :func:`one_sided_terms` finds the one-sided comparisons of a criterion (parsed
with :mod:`ast`, the grammar of :mod:`gnibench.suite.foundation.expressions`), and
tests/ledger/test_ledger.py checks that every entry with one has its reason and no other entry
has one.

A comparison is *two-sided* when its non-constant side is bounded both ways in the criterion
(``0.1 <= x <= 10``, ``x >= a and x <= b``), when it is an ``abs(x - c) <= d`` or an equality,
or when every name it reads is also ordered against another measured number (as in ``ee3 < ee2 <
ee1 < 0``: each bounds the other, and the order is the claim); otherwise it is one-sided.
"""
from __future__ import annotations

import ast

_UPPER = (ast.Lt, ast.LtE)
_LOWER = (ast.Gt, ast.GtE)


def _names(node: ast.AST) -> frozenset[str]:
    """The measured names of a term (not the functions it calls)."""
    called = {id(n.func) for n in ast.walk(node) if isinstance(n, ast.Call)}
    return frozenset(n.id for n in ast.walk(node) if isinstance(n, ast.Name) and id(n) not in called)


def _is_abs(node: ast.AST) -> bool:
    return isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "abs"


def one_sided_terms(text: str) -> list[str]:
    """The terms of ``text`` (a passes or partly expression) bounded on one side only."""
    if not text:
        return []
    tree = ast.parse(text, mode="eval")
    bounds: dict[str, set[str]] = {}          # the text of a bounded term -> {"upper", "lower"}
    names: dict[str, frozenset[str]] = {}
    related: set[str] = set()                 # names ordered against other measured names
    for node in ast.walk(tree):
        if not isinstance(node, ast.Compare):
            continue
        sides = [node.left, *node.comparators]
        for (a, b), op in zip(zip(sides, sides[1:]), node.ops):
            na, nb = _names(a), _names(b)
            if na and nb:                     # an order between two measured numbers
                related |= na | nb
                continue
            if isinstance(op, (ast.Eq, ast.NotEq)) or not (na or nb):
                continue                      # an equality; constants
            term, flip = (a, False) if na else (b, True)
            if _is_abs(term) and not isinstance(op, _LOWER if not flip else _UPPER):
                continue                      # |x - c| <= d: both sides of c
            upper = isinstance(op, _UPPER) != flip
            text = ast.unparse(term)
            names[text] = _names(term)
            bounds.setdefault(text, set()).add("upper" if upper else "lower")
    return [term for term, s in bounds.items() if len(s) == 1 and not names[term] <= related]
