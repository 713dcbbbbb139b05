"""scipy's ``solve_ivp`` solvers as contestants: ``scipy-rk45``, ``scipy-rk23``, ``scipy-dop853``,
``scipy-radau``, ``scipy-bdf``, ``scipy-lsoda``.

External methods (:class:`gnibench.methods.external.ExternalMethod`) run by
:mod:`gnibench.methods.engines.scipy`: the solver steps exactly as ``solve_ivp`` steps it, on the
problem's compiled field (and, for Radau, BDF and LSODA, its compiled Jacobian), called from
Python once per evaluation. Their options are solve_ivp's: ``rtol`` and ``atol`` (solve_ivp's
defaults 1e-3 and 1e-6), ``max_step`` (0: unbounded, solve_ivp's inf) and ``first_step`` (0: the
solver's own choice, solve_ivp's None); ``dt_out`` spaces the output grid (``t_eval``) as for the
other external engines; ``max_steps`` is our step budget (solve_ivp has none). ``nfev`` and
``njev`` are scipy's own counts, ``steps`` the accepted steps. Modifiers are refused (they act on
gnibench's compiled field, which the solver receives unmodified), as are problems that map the
state after every step (``post_step``: solve_ivp has no such hook).
"""
from __future__ import annotations

from functools import partial

from gnibench.methods.external import DT_OUT, ExternalMethod, _not_compiled
import numpy as np
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Param

PARAMS = (
    DT_OUT,
    # solve_ivp raises a smaller rtol to 100 eps with a warning (scipy/integrate/_ivp/common.py,
    # validate_tol): the tables would record a tolerance never used, so it is refused
    Param("rtol", 1e-3, "relative tolerance (solve_ivp's default; solve_ivp uses no rtol below "
          "100 eps)", low=100 * float(np.finfo(float).eps)),
    Param("atol", 1e-6, "absolute tolerance (solve_ivp's default)", low=0.0, low_open=True),
    Param("max_step", 0.0, "maximal step (0: unbounded, solve_ivp's inf)", low=0.0,
          show_default=False),
    Param("first_step", 0.0, "initial step (0: the solver's own choice, solve_ivp's None)",
          low=0.0, show_default=False),
    Param("max_steps", 100000, "maximal number of accepted steps (gnibench's budget; solve_ivp "
          "has none)", kind="int", low=1, show_default=False),
)


def _run(solver: str, problem_bound, values, grid, kernel=None):
    from gnibench.methods.engines.scipy import scipy_propagate

    if kernel is None:
        raise RuntimeError("scipy methods integrate the problem's compiled field: the driver "
                           "passes the problem kernel")
    return scipy_propagate(problem_bound, grid.t, solver, kernel, values["rtol"], values["atol"],
                           values["max_step"], values["first_step"], values["max_steps"])


def _plain_state(problem) -> None:
    if getattr(problem, "post_step", None) is not None:
        raise UserError(f"problem {problem.id} maps the state after every step (post_step, e.g. "
                        f"back into a fundamental domain); scipy's solve_ivp cannot apply that map, "
                        f"so the scipy-* methods do not take this problem")


def _record(id: str, solver: str, order: int, doc: str, reference: str, implicit: bool = False):
    return ExternalMethod(
        id=id, family="external (scipy)", order=order,
        reference=reference + "; scipy.integrate.solve_ivp (Virtanen et al., Nat. Methods 17 "
                              "(2020) 261); beyond the seeds",
        doc=f"scipy.integrate.solve_ivp(method={solver!r}): {doc}", generate=_not_compiled,
        params=PARAMS, implicit=implicit, run=partial(_run, solver), grid_param="dt_out",
        adaptive=True, engine="scipy", requires=_plain_state)


scipy_rk45 = _record(
    "scipy-rk45", "RK45", 5, "Dormand-Prince 5(4) pair, local extrapolation, quartic dense output",
    "Dormand & Prince, J. Comput. Appl. Math. 6 (1980) 19; [HNW] II.5")
scipy_rk23 = _record(
    "scipy-rk23", "RK23", 3, "Bogacki-Shampine 3(2) pair, cubic Hermite dense output",
    "Bogacki & Shampine, Appl. Math. Lett. 2 (1989) 321")
scipy_dop853 = _record(
    "scipy-dop853", "DOP853", 8, "Dormand-Prince 8(5,3) (Hairer's DOP853 in Python), order-7 "
    "dense output", "[HNW] II.10 (DOP853)")
scipy_radau = _record(
    "scipy-radau", "Radau", 5, "Radau IIA, 3 stages, order 5, simplified Newton with the "
    "compiled Jacobian, cubic collocation dense output", "[HW] IV.8 (RADAU5)", implicit=True)
scipy_bdf = _record(
    "scipy-bdf", "BDF", 5, "variable-order (1-5) BDF / NDF in quasi-constant step form, Newton with "
    "the compiled Jacobian; 'order' lists the highest", "Shampine & Reichelt, SIAM J. Sci. Comput. "
    "18 (1997) 1 (ode15s)", implicit=True)
scipy_lsoda = _record(
    "scipy-lsoda", "LSODA", 12, "ODEPACK's LSODA: Adams (orders 1-12) switching to BDF (1-5) when "
    "stiff, with the compiled Jacobian; 'order' lists the highest", "Petzold, SIAM J. Sci. Stat. "
    "Comput. 4 (1983) 136; Hindmarsh, ODEPACK (1983)")
