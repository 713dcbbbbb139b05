"""Why a claim's pass criterion failed, and how far off it was: the conjuncts of ``passes`` that do
not hold, with both sides' numbers and the factor between them; over a sweep, the point that came
closest. Read by the verdicts (``failing``, ``closest``) and shown on the ledger page beside the
entry's own ``needed`` ("what would have been needed", in words).
"""
from __future__ import annotations

import ast
import math

from gnibench.suite.foundation import expressions

_OPS = {ast.Lt: "<", ast.LtE: "≤", ast.Gt: ">", ast.GtE: "≥", ast.Eq: "=", ast.NotEq: "≠"}


def conjuncts(expression) -> list[ast.AST]:
    """The top-level ``and`` terms of a parsed expression."""
    out, todo = [], [expression.tree.body]
    while todo:
        node = todo.pop(0)
        if isinstance(node, ast.BoolOp) and isinstance(node.op, ast.And):
            todo = list(node.values) + todo
        else:
            out.append(node)
    return out


def _part(node: ast.AST) -> expressions.Expression:
    """A sub-tree of a checked expression as an expression of its own."""
    calls = {id(n.func) for n in ast.walk(node) if isinstance(n, ast.Call)}
    read = frozenset(n.id for n in ast.walk(node) if isinstance(n, ast.Name) and id(n) not in calls)
    return expressions.Expression(ast.unparse(node), ast.Expression(body=node), read)


def _num(x) -> str:
    return f"{x:.3g}" if isinstance(x, float) else str(x)


def _factor(a: float, b: float) -> float:
    """How far a is from b, as a factor ≥ 1 (inf when one is 0 or they differ in sign)."""
    if not (math.isfinite(a) and math.isfinite(b)) or a == 0 or b == 0 or (a > 0) != (b > 0):
        return math.inf
    r = abs(a / b)
    return max(r, 1 / r)


def failing(text: str, values: dict, where: str = "passes") -> list[tuple[str, float]]:
    """The failing conjuncts of ``text`` as (description, factor off), in order."""
    out = []
    for node in conjuncts(expressions.parse(text, where)):
        if expressions.evaluate(_part(node), values):
            continue
        src = ast.unparse(node)
        if isinstance(node, ast.Compare) and len(node.ops) == 1:
            a = expressions.evaluate(_part(node.left), values)
            b = expressions.evaluate(_part(node.comparators[0]), values)
            needs = f"needs {ast.unparse(node.left)} {_OPS[type(node.ops[0])]} {_num(b)}"
            out.append((f"{src} fails: {ast.unparse(node.left)} = {_num(a)}; {needs}",
                        _factor(a, b)))
        else:
            out.append((f"{src} fails", math.inf))
    return out


def describe(items: list[tuple[str, float]]) -> str:
    parts = []
    for text, factor in items:
        off = "" if not (math.isfinite(factor) and factor > 1) else \
            f" (off by ×{factor:.3g})" if factor >= 1.1 else f" (off by {100 * (factor - 1):.2g} %)"
        parts.append(text + off)
    return "; ".join(parts)


def closeness(items: list[tuple[str, float]]) -> tuple[int, float]:
    """Sort key of a sweep point: fewer failing conjuncts, then the smallest factor off."""
    worst = max((f for _, f in items), default=1.0)
    return (len(items), math.log(worst) if math.isfinite(worst) else math.inf)
