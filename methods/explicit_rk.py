"""Explicit Runge-Kutta methods: tableaus as data, one step writer for the whole family.

The step is written out from the tableau (methods/assembly/steps/erk.py); ``sum=compensated``
(methods/summation.py) adds its increment with the carried rounding error. Adding a method: a
tableau here and one line in :mod:`methods` (``summation="compensated"`` makes that its default).
"""
from __future__ import annotations

from gnibench.methods.assembly.steps.erk import write_erk
from gnibench.methods.base import Method
from gnibench.methods.tableau import tableau

EULER = tableau([[0]], [1], [0], order=1)                               # [HLW] (1.5)
RK4 = tableau([[0, 0, 0, 0], ["1/2", 0, 0, 0], [0, "1/2", 0, 0], [0, 0, 1, 0]],
              ["1/6", "1/3", "1/3", "1/6"], [0, "1/2", "1/2", 1], order=4)  # Kutta (1901)


def erk(id, tab, reference, doc, summation="plain"):
    """An explicit Runge-Kutta method; ``summation``: the default of its option ``sum``."""
    if not tab.explicit:
        raise ValueError(f"{id}: tableau is not explicit")
    return Method(id=id, family="explicit-rk", order=tab.order, reference=reference, doc=doc,
                  generate=write_erk(tab), data=tab, summation=summation)


euler = erk("euler", EULER, "[HLW] (1.5)", "explicit Euler method")
rk4 = erk("rk4", RK4, "classical (Kutta 1901); [B] uses it in §6", "classical 4-stage Runge-Kutta")
