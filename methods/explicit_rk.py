"""Explicit Runge-Kutta methods: tableaus as data, one generator for the whole family.

The generated step unrolls the stages over the tuple state, skipping zero coefficients, so the
compiled code keeps the state in registers (measured: within ~1.1x of a C loop on kepler-2d).
Under ``sum=compensated`` it also writes ``step_sum(y, e, h, par, ws)``: the same stages, the
increment Δ = h Σ b_i k_i formed first (``erk_inc``) and added to y with the carried rounding
error e ([HLW] VIII.5, methods/summation.py). Adding a method: a tableau here and one line in
:mod:`methods` (``summation="compensated"`` makes that its default).
"""
from __future__ import annotations

from gnibench.methods.base import Method
from gnibench.methods.summation import compensated
from gnibench.methods.tableau import Tableau, lit, tableau

EULER = tableau([[0]], [1], [0], order=1)                               # [HLW] (1.5)
RK4 = tableau([[0, 0, 0, 0], ["1/2", 0, 0, 0], [0, "1/2", 0, 0], [0, 0, 1, 0]],
              ["1/6", "1/3", "1/3", "1/6"], [0, "1/2", "1/2", 1], order=4)  # Kutta (1901)


def _lincomb(name: str, n: int, k: int) -> str:
    """name(y, h, c0, v0, ..., c_{k-1}, v_{k-1}) = y + h (c0 v0 + ... ) componentwise."""
    args = ", ".join(f"c{j}, v{j}" for j in range(k))
    comps = ", ".join(f"y[{i}] + h * (" + " + ".join(f"c{j} * v{j}[{i}]" for j in range(k)) + ")"
                      for i in range(n))
    return (f"\n@njit(cache=True)\ndef {name}(y, h, {args}):\n"
            f"    return ({comps}{',' if n == 1 else ''})\n")


def _increment(name: str, n: int, k: int) -> str:
    """name(h, c0, v0, ..., c_{k-1}, v_{k-1}) = h (c0 v0 + ...) componentwise: the increment of
    ``_lincomb``, by the same operations."""
    args = ", ".join(f"c{j}, v{j}" for j in range(k))
    comps = ", ".join("h * (" + " + ".join(f"c{j} * v{j}[{i}]" for j in range(k)) + ")"
                      for i in range(n))
    return (f"\n@njit(cache=True)\ndef {name}(h, {args}):\n"
            f"    return ({comps}{',' if n == 1 else ''})\n")


def stage_lines(tab: Tableau, count: int, first: str = "f(y, par)") -> tuple[list[str], set[int]]:
    """Lines computing stages k0..k{count-1} of ``tab`` (zero coefficients skipped)."""
    lines, arities = [], set()
    a = tab.doubles[0]
    for i in range(count):
        terms = [(a[i][j], j) for j in range(i) if tab.a[i][j] != 0]
        if i == 0:
            lines.append(f"    k0 = {first}")
        elif terms:
            arities.add(len(terms))
            args = ", ".join(f"{lit(c)}, k{j}" for c, j in terms)
            lines.append(f"    k{i} = f(erk_lc{len(terms)}(y, h, {args}), par)")
        else:
            lines.append(f"    k{i} = f(y, par)")
    return lines, arities


def combination(weights, arities: set[int]) -> str:
    """y + h Σ w_j k_j over the non-zero weights (registers the helper arity)."""
    terms = [(w, j) for j, w in enumerate(weights) if w != 0]
    arities.add(len(terms))
    return f"erk_lc{len(terms)}(y, h, " + ", ".join(f"{lit(c)}, k{j}" for c, j in terms) + ")"


def increment(weights) -> tuple[str, int]:
    """h Σ w_j k_j over the non-zero weights (``erk_inc<k>``; add k to the increment arities)."""
    terms = [(w, j) for j, w in enumerate(weights) if w != 0]
    return (f"erk_inc{len(terms)}(h, " + ", ".join(f"{lit(c)}, k{j}" for c, j in terms) + ")",
            len(terms))


def helpers(n: int, arities: set[int], increments: set[int] = frozenset()) -> str:
    return ("".join(_lincomb(f"erk_lc{k}", n, k) for k in sorted(arities))
            + "".join(_increment(f"erk_inc{k}", n, k) for k in sorted(increments)))


def generate_erk(tab: Tableau):
    """Return a generator ``ctx -> source`` of ``make_ws`` and ``step`` for an explicit tableau."""

    def generate(ctx) -> str:
        s = max(j for j, b in enumerate(tab.b) if b != 0) + 1   # trailing zero-weight stages unused
        lines, arities = stage_lines(tab, s)
        lines = ["\n@njit(cache=True)\ndef step(y, h, par, ws):"] + lines
        stages = lines[1:]
        lines.append(f"    return {combination(tab.doubles[1][:s], arities)}, {float(s)!r}, 0.0, STATUS_OK")
        increments = set()
        if compensated(ctx.values):      # the same stages, the increment added with its carry
            inc, k = increment(tab.doubles[1][:s])
            increments.add(k)
            lines += (["\n@njit(cache=True)\ndef step_sum(y, e, h, par, ws):"] + stages
                      + [f"    y1, e1 = carry_add(y, e, {inc})",
                         f"    return y1, e1, {float(s)!r}, 0.0, STATUS_OK"])
        ws = "\n@njit(cache=True)\ndef make_ws():\n    return 0\n"
        return helpers(ctx.n, arities, increments) + ws + "\n".join(lines) + "\n"

    return generate


def erk(id, tab, reference, doc, summation="plain"):
    """An explicit Runge-Kutta method; ``summation``: the default of its option ``sum``."""
    if not tab.explicit:
        raise ValueError(f"{id}: tableau is not explicit")
    return Method(id=id, family="explicit-rk", order=tab.order, reference=reference, doc=doc,
                  generate=generate_erk(tab), data=tab, summation=summation)


euler = erk("euler", EULER, "[HLW] (1.5)", "explicit Euler method")
rk4 = erk("rk4", RK4, "classical (Kutta 1901); [B] uses it in §6", "classical 4-stage Runge-Kutta")
