"""Implicit Runge-Kutta methods: tableaus as data, one Newton kernel for the family.

Stages are solved by full Newton with the field's Jacobian to round-off (methods/assembly/templates/irk.py).
A step that does not converge in ``newton_maxit`` iterations ends the run with status
``newton_failed``. With ``fixed_point = K`` the stages are solved instead by at most K fixed-point
iterations (no Jacobian); a step that has not converged then is accepted with its last iterate and
counted in ``njev`` ([HLW] Fig 2.4's implicit Euler, see methods/assembly/templates/irk.py).
``sum=compensated`` adds the increment Σ d_j Z_j with the carried rounding
error (methods/summation.py).
"""
from __future__ import annotations

from fractions import Fraction as Fr

from gnibench.methods.assembly.steps.irk import write_irk
from gnibench.methods.base import H_PARAM, NEWTON_PARAMS, Method
from gnibench.methods.tableau import Tableau, tableau
from gnibench.suite.foundation.params import Param

IMPLICIT_EULER = tableau([[1]], [1], [1], order=1)                      # [HLW] (1.6)
IMPLICIT_MIDPOINT = tableau([["1/2"]], [1], ["1/2"], order=2)           # [HLW] (1.7)

# Gauss-Legendre collocation (HLW II.1.3, Table 1.1-1.2); entries with sqrt(3), sqrt(15) are the
# nearest doubles (so the order conditions hold to tol = 1e-15, not exactly). 2 stages: Butcher's
# 4th-order implicit symplectic method ([B] §6, §8).
_R3, _R15 = 3 ** 0.5, 15 ** 0.5
GAUSS4 = tableau([[1 / 4, 1 / 4 - _R3 / 6], [1 / 4 + _R3 / 6, 1 / 4]], ["1/2", "1/2"],
                 [1 / 2 - _R3 / 6, 1 / 2 + _R3 / 6], order=4, tol=1e-15)
GAUSS6 = tableau([[5 / 36, 2 / 9 - _R15 / 15, 5 / 36 - _R15 / 30],
                  [5 / 36 + _R15 / 24, 2 / 9, 5 / 36 - _R15 / 24],
                  [5 / 36 + _R15 / 30, 2 / 9 + _R15 / 15, 5 / 36]],
                 ["5/18", "4/9", "5/18"], [1 / 2 - _R15 / 10, 1 / 2, 1 / 2 + _R15 / 10],
                 order=6, tol=1e-15)


def _d_coefficients(tab: Tableau) -> tuple[Fr, ...]:
    """d = b^T A^{-1}, exactly (Gauss-Jordan on A^T d = b in rationals), so y1 = y + sum_j d_j Z_j."""
    s = tab.stages
    rows = [[Fr(tab.a[j][i]) for j in range(s)] + [Fr(tab.b[i])] for i in range(s)]
    for k in range(s):
        p = next(i for i in range(k, s) if rows[i][k] != 0)
        rows[k], rows[p] = rows[p], rows[k]
        rows[k] = [x / rows[k][k] for x in rows[k]]
        for i in range(s):
            if i != k and rows[i][k] != 0:
                rows[i] = [x - rows[i][k] * y for x, y in zip(rows[i], rows[k])]
    return tuple(rows[i][s] for i in range(s))


FIXED_POINT_PARAM = Param(
    "fixed_point", 0, "solve the stages by at most this many fixed-point iterations instead of "
    "Newton (0: Newton); a step not converged then is accepted and counted in njev",
    kind="int", low=0, high=100000, show_default=False)


def irk_method(id, tab, reference, doc, summation="plain", **props):
    return Method(id=id, family="implicit-rk", order=tab.order, reference=reference, doc=doc,
                  generate=write_irk(tab, _d_coefficients(tab)), data=tab, implicit=True,
                  params=(H_PARAM,) + NEWTON_PARAMS + (FIXED_POINT_PARAM,), summation=summation,
                  runtime=("fixed_point",), **props)


implicit_euler = irk_method("implicit-euler", IMPLICIT_EULER, "[HLW] (1.6)", "implicit Euler method")
gauss4 = irk_method("gauss4", GAUSS4, "[B] §6, §8 (Butcher's 4th-order method); HLW II.1.3",
                    "2-stage Gauss-Legendre collocation (Butcher 1964)", symplectic=True,
                    symmetric=True, aliases=("butcher4",))
gauss6 = irk_method("gauss6", GAUSS6, "HLW II.1.3", "3-stage Gauss-Legendre collocation",
                    symplectic=True, symmetric=True)
implicit_midpoint = irk_method("implicit-midpoint", IMPLICIT_MIDPOINT, "[HLW] (1.7)",
                               "implicit midpoint rule", symplectic=True, symmetric=True)
