"""Implicit Runge-Kutta steps (the ``implicit-rk`` family): one Newton template for every tableau.

The step is templates/irk.py with the tableau as module constants (S, A, and D = bᵀA⁻¹, so that
y1 = y + Σ_j d_j Z_j); the stage equations are solved by Newton (``stages_newton``), or with the
method option ``fixed_point = K`` by at most K fixed-point iterations (``stages_fixed_point``,
the count read from ``par`` at ``FIXED_POINT_AT``): the binding ``solve_stages`` names the one
the cell uses.
"""
from __future__ import annotations

from gnibench.methods.assembly.source import INLINE, alias, copy
from gnibench.methods.assembly.templates import irk
from gnibench.methods.tableau import lit


def _matrix(a) -> str:
    return "(" + ", ".join("(" + ", ".join(lit(x) for x in row) + ",)" for row in a) + ",)"


def write_irk(tab, d):
    """The writer of an implicit tableau's step; ``d`` = bᵀA⁻¹ (methods/implicit_rk.py)."""

    def write(ctx) -> str:
        consts = [f"S = {tab.stages}", f"A = {_matrix(tab.a)}",
                  "D = (" + ", ".join(lit(x) for x in d) + ",)"]
        if int(ctx.values.get("fixed_point", 0)):   # fixed-point iteration instead of Newton
            # the number of iterations is read from par: a sweep over it is one kernel
            consts.append(f"FIXED_POINT_AT = {ctx.extra['par_at']['fixed_point']}")
            solver = copy(irk.stages_fixed_point, INLINE) + alias("solve_stages",
                                                                  "stages_fixed_point")
        else:
            solver = copy(irk.stages_newton, INLINE) + alias("solve_stages", "stages_newton")
        return ("\n" + "\n".join(consts) + "\n" + copy(irk.make_ws, INLINE) + solver
                + copy(irk.increment, INLINE) + copy(irk.step, INLINE)
                + copy(irk.step_sum, INLINE))

    return write
