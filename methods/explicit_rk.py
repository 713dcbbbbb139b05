"""Explicit Runge-Kutta methods: tableaus as data, one generator for the whole family.

The generated step unrolls the stages over the tuple state, skipping zero coefficients, so the
compiled code keeps the state in registers (measured: within ~1.1x of a C loop on kepler-2d).
Under ``sum=compensated`` it also writes ``step_sum(y, e, h, par, ws)``: the same stages, the
increment Δ = h Σ b_i k_i formed first and added to y with the carried rounding
error e ([HLW] VIII.5, methods/summation.py). Adding a method: a tableau here and one line in
:mod:`methods` (``summation="compensated"`` makes that its default).
"""
from __future__ import annotations

from gnibench.methods.base import Method
from gnibench.methods.summation import compensated
from gnibench.methods.tableau import Tableau, tableau, weighted

EULER = tableau([[0]], [1], [0], order=1)                               # [HLW] (1.5)
RK4 = tableau([[0, 0, 0, 0], ["1/2", 0, 0, 0], [0, "1/2", 0, 0], [0, 0, 1, 0]],
              ["1/6", "1/3", "1/3", "1/6"], [0, "1/2", "1/2", 1], order=4)  # Kutta (1901)


def lincomb(y: str, h: str, terms, n: int) -> str:
    """y + h (c0 v0 + c1 v1 + ...) componentwise over the (coefficient, stage name) ``terms``, as
    a tuple display written where it is used: the same operations a helper function of the
    coefficients did, without compiling one helper per number of terms (numba's per-function cost
    was most of their compile time)."""
    return _tuple([f"{y}[{i}] + {w}" for i, w in enumerate(weighted(h, terms, n))])


def _increment(h: str, terms, n: int) -> str:
    """h (c0 v0 + ...) componentwise: the increment of :func:`lincomb`, by the same operations."""
    return _tuple(weighted(h, terms, n))


def _tuple(comps: list[str]) -> str:
    if len(comps) == 1:
        return f"({comps[0]},)"
    return "(\n" + "".join(f"        {c},\n" for c in comps) + "    )"


def stage_lines(tab: Tableau, count: int, n: int, first: str = "f(y, par)") -> list[str]:
    """Lines computing stages k0..k{count-1} of ``tab`` (zero coefficients skipped)."""
    lines = []
    a = tab.doubles[0]
    for i in range(count):
        terms = [(a[i][j], f"k{j}") for j in range(i) if tab.a[i][j] != 0]
        if i == 0:
            lines.append(f"    k0 = {first}")
        elif terms:
            lines.append(f"    k{i} = f({lincomb('y', 'h', terms, n)}, par)")
        else:
            lines.append(f"    k{i} = f(y, par)")
    return lines


def combination(weights, n: int) -> str:
    """y + h Σ w_j k_j over the non-zero weights."""
    return lincomb("y", "h", [(w, f"k{j}") for j, w in enumerate(weights) if w != 0], n)


def increment(weights, n: int) -> str:
    """h Σ w_j k_j over the non-zero weights."""
    return _increment("h", [(w, f"k{j}") for j, w in enumerate(weights) if w != 0], n)


def generate_erk(tab: Tableau):
    """Return a generator ``ctx -> source`` of ``make_ws`` and ``step`` for an explicit tableau."""

    def generate(ctx) -> str:
        s = max(j for j, b in enumerate(tab.b) if b != 0) + 1   # trailing zero-weight stages unused
        stages = stage_lines(tab, s, ctx.n)
        lines = (["\n@njit(cache=True)\ndef step(y, h, par, ws):"] + stages
                 + [f"    return {combination(tab.doubles[1][:s], ctx.n)}, {float(s)!r}, 0.0, "
                    f"STATUS_OK"])
        if compensated(ctx.values):      # the same stages, the increment added with its carry
            lines += (["\n@njit(cache=True)\ndef step_sum(y, e, h, par, ws):"] + stages
                      + [f"    y1, e1 = carry_add(y, e, {increment(tab.doubles[1][:s], ctx.n)})",
                         f"    return y1, e1, {float(s)!r}, 0.0, STATUS_OK"])
        ws = "\n@njit(cache=True, inline='always')\ndef make_ws():\n    return 0\n"
        return ws + "\n".join(lines) + "\n"

    return generate


def erk(id, tab, reference, doc, summation="plain"):
    """An explicit Runge-Kutta method; ``summation``: the default of its option ``sum``."""
    if not tab.explicit:
        raise ValueError(f"{id}: tableau is not explicit")
    return Method(id=id, family="explicit-rk", order=tab.order, reference=reference, doc=doc,
                  generate=generate_erk(tab), data=tab, summation=summation)


euler = erk("euler", EULER, "[HLW] (1.5)", "explicit Euler method")
rk4 = erk("rk4", RK4, "classical (Kutta 1901); [B] uses it in §6", "classical 4-stage Runge-Kutta")
