"""``solve``: one cell from spec texts (or typed values), through the driver facade.

The entry point of most tests and of the ledger's identity checks: make the typed cell
(:func:`gnibench.suite.cell.cellspec.build`: parse and validate, choose what ``global_error`` is
measured against, :mod:`gnibench.suite.cell.reference`) and integrate it
(:func:`gnibench.suite.cell.driver.integrate`).
"""
from __future__ import annotations

from gnibench.suite.cell.cellspec import build
from gnibench.suite.cell.driver import integrate
from gnibench.suite.cell.trajectory import Trajectory


def solve(problem, method, steps: int | None = None, t_end: float | None = None,
          every: int = 1, reference=None, section: int | None = None,
          locator: str | None = None, progress=None, dt_out: float | None = None,
          budget: int | None = 0, reverse: bool = False) -> Trajectory:
    """Integrate one cell given by spec strings (or typed values: a parsed problem and method).
    Bad input raises UserError; divergence is a status, not an exception.

    ``reference`` chooses the reference samples attached to the trajectory (what ``global_error``
    is measured against): ``exact``, ``heyoka[:precision=...,tol=...]``, ``rebound[:tol=...]`` or
    ``none``; by default the exact solution when the problem has one. ``section=K`` returns the
    located crossings of the problem's Poincaré section instead of samples (``locator``: how they
    are located); ``dt_out=D`` samples at t = k D (:mod:`gnibench.suite.cell.timegrid`);
    ``reverse`` integrates backward (:class:`~gnibench.suite.cell.cellspec.CellSpec`).
    ``budget``: steps per call of the compiled driver
    (:func:`gnibench.suite.cell.driver.integrate`).
    """
    cell = build(problem, method, steps=steps, t_end=t_end, every=every, dt_out=dt_out,
                 section=section, reference=reference, reverse=reverse, locator=locator)
    return integrate(cell, progress=progress, budget=budget)
