"""``solve``: one cell from its spec strings, through the driver facade.

The entry point of ``gnibench solve`` and of most tests: parse and validate the specs
(:func:`gnibench.suite.cell.spec.prepare`), choose what ``global_error`` is measured against
(:mod:`gnibench.suite.cell.reference`), integrate (:func:`gnibench.suite.cell.driver.integrate`).
"""
from __future__ import annotations

from gnibench.suite.cell.driver import integrate
from gnibench.suite.cell.reference import default_reference, parse_reference
from gnibench.suite.cell.spec import prepare
from gnibench.suite.cell.trajectory import Trajectory


def solve(problem_text: str, method_text: str, steps: int | None = None,
          t_end: float | None = None, every: int = 1, reference: str | None = None,
          section: int | None = None, locator: str | None = None,
          progress=None, dt_out: float | None = None, budget: int | None = 0) -> Trajectory:
    """Integrate one cell given by spec strings. Bad input raises UserError; divergence is a
    status, not an exception.

    ``reference`` chooses the reference samples attached to the trajectory (what ``global_error``
    is measured against): ``exact``, ``heyoka[:precision=...,tol=...]``, ``rebound[:tol=...]`` or
    ``none``; by default the exact solution when the problem has one. ``section=K`` returns the
    located crossings of the problem's Poincaré section instead of samples; ``dt_out=D`` samples
    at t = k D (:mod:`gnibench.suite.cell.timegrid`). ``budget``: steps per call of the compiled
    driver (:func:`gnibench.suite.cell.driver.integrate`).
    """
    problem, method = prepare(problem_text, method_text)
    if section is not None:
        ref = None
    else:
        ref = (default_reference(problem.record) if reference is None
               else parse_reference(reference, problem.record))
    return integrate(problem, method, steps=steps, t_end=t_end, every=every, dt_out=dt_out,
                     section=section, locator=locator, reference=ref, progress=progress,
                     budget=budget)
