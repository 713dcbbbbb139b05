"""Explicit Runge-Kutta steps written out from a tableau (the ``explicit-rk`` family).

The step unrolls the stages over the tuple state, skipping zero coefficients, so the compiled code
keeps the state in registers (measured: within ~1.1x of a C loop on kepler-2d). A generic step
looping over coefficient arrays was measured 1.21-1.27x slower than this for rk4 and 1.24-1.28x
for DOP853 (``benchmarks/generic_tableau.py``), so the explicit steps stay written out. Under
``sum=compensated`` it also writes ``step_sum(y, e, h, par, ws)``: the same stages, the increment
Δ = h Σ b_i k_i formed first and added to y with the carried rounding error e ([HLW] VIII.5,
methods/summation.py).
"""
from __future__ import annotations

from gnibench.methods.assembly.source import INLINE, INTERNAL
from gnibench.methods.summation import compensated
from gnibench.methods.tableau import weighted


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


def stage_lines(tab, count: int, n: int, first: str = "f(y, par)") -> list[str]:
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


def write_erk(tab):
    """The writer ``ctx -> text`` of ``make_ws`` and ``step`` (and ``step_sum``) of a tableau."""

    def write(ctx) -> str:
        s = max(j for j, b in enumerate(tab.b) if b != 0) + 1   # trailing zero-weight stages unused
        stages = stage_lines(tab, s, ctx.n)
        lines = ([f"\n{INTERNAL}\ndef step(y, h, par, ws):"] + stages
                 + [f"    return {combination(tab.doubles[1][:s], ctx.n)}, {float(s)!r}, 0.0, "
                    f"STATUS_OK"])
        if compensated(ctx.values):      # the same stages, the increment added with its carry
            lines += ([f"\n{INTERNAL}\ndef step_sum(y, e, h, par, ws):"] + stages
                      + [f"    y1, e1 = carry_add(y, e, {increment(tab.doubles[1][:s], ctx.n)})",
                         f"    return y1, e1, {float(s)!r}, 0.0, STATUS_OK"])
        ws = f"\n{INLINE}\ndef make_ws():\n    return 0\n"
        return ws + "\n".join(lines) + "\n"

    return write
