"""scipy's ``solve_ivp`` solvers (RK45, RK23, DOP853, Radau, BDF, LSODA) as an external engine.

The solver object of ``scipy.integrate`` is stepped exactly as ``solve_ivp`` steps it
(``scipy/integrate/_ivp/ivp.py``: ``solver.step()`` until it finishes or fails; the points of
``t_eval`` passed by a step are read from that step's ``solver.dense_output()``), so the samples,
steps and counts are those of ``solve_ivp(fun, (0, T), y0, method, t_eval=grid, rtol, atol,
max_step, first_step[, jac])`` — ``tests/methods/test_scipy_engine.py`` checks it bit for bit. Stepping it
ourselves gives what ``solve_ivp`` keeps to itself: the counters after each accepted step, so that
every sample carries the cumulative ``steps`` (accepted steps: one per ``solver.step()``, which
retries rejected attempts inside; for LSODA one internal step of the Fortran code, ``itask=5``),
``nfev`` and ``njev`` (scipy's own ``solver.nfev``, ``solver.njev``) of the step that holds it. A
sample at t = 0 carries no step and the evaluations the solver made before its first step (f(y0);
for the explicit pairs also the initial step heuristic's, Hairer's HINIT, [HNW] II.4).

The right-hand side is the problem's compiled field ``base_f`` (the same numba function every
compiled method integrates), called from Python for each evaluation as ``solve_ivp`` requires;
Radau, BDF and LSODA get the compiled Jacobian ``base_jac`` (analytic, from the sympy model). The
per-call Python overhead is the engine's own cost, the cost any user of ``solve_ivp`` pays.

**Statuses.** scipy's failure messages map onto ours: "Required step size is less than spacing
between numbers" (all but LSODA) and LSODA's istate -2 (excess accuracy), -4 (repeated error test
failures), -5 (repeated convergence failures) and a step that no longer advances t (where
solve_ivp would loop) -> ``step_too_small``; LSODA's -1 (excess work) and
our own step budget ``max_steps`` (solve_ivp has none; an integration that needs more steps would
run for hours in Python) -> ``max_steps``; a non-finite state, sample or field value ->
``nonfinite``; Ctrl-C between two steps -> ``interrupted`` with the samples so far (the driver
then raises its ``Interrupted``). The reason quotes scipy's message.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
from gnibench.methods.engines.base import EngineRun
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.status import Status

#: gnibench method id suffix -> scipy solver name
SOLVERS = {"rk45": "RK45", "rk23": "RK23", "dop853": "DOP853", "radau": "Radau", "bdf": "BDF",
           "lsoda": "LSODA"}
#: the solvers that take a Jacobian (implicit, or switching to BDF as LSODA does)
WITH_JACOBIAN = ("Radau", "BDF", "LSODA")
#: LSODA's istate on failure (scipy/integrate/_ode.py, class lsoda) -> our status
LSODA_STATUS = {-1: Status.MAX_STEPS, -2: Status.STEP_TOO_SMALL, -4: Status.STEP_TOO_SMALL,
                -5: Status.STEP_TOO_SMALL}


def field_functions(kernel, n: int):
    """``fun(t, y)`` and ``jac(t, y)`` for solve_ivp from a problem's compiled module ``kernel``
    (:func:`gnibench.suite.cell.compiled.problem_kernel`: ``kernel.kernel``, ``kernel.par``)."""
    base_f, base_jac, par = kernel.kernel.base_f, kernel.kernel.base_jac, kernel.par

    def fun(t, y):
        return np.array(base_f(tuple(y.tolist()), par))

    def jac(t, y):
        J = np.empty((n, n))
        base_jac(tuple(y.tolist()), par, J)
        return J

    return fun, jac


_controller = None


def one_blas_thread():
    """BLAS and LAPACK on one thread while the solver runs (threadpoolctl). Radau's complex LU
    (LAPACK zgetrf/zgetrs through OpenBLAS) rounds differently with 1 and 2 threads, and a Dask
    worker runs with one while this process and a local pool run with one per core: fixed at one,
    a cell gives the same bits whatever the executor (the matrices are N x N, N <= 36)."""
    global _controller
    if _controller is None:
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController()
    return _controller.limit(limits=1, user_api="blas")


def solver_options(solver: str, rtol: float, atol: float, max_step: float, first_step: float,
                   jac) -> dict:
    """The keyword arguments solve_ivp receives (``max_step`` 0: unbounded, ``first_step`` 0: the
    solver's own choice)."""
    opts = {"rtol": rtol, "atol": atol, "max_step": max_step if max_step > 0 else np.inf}
    if first_step > 0:
        opts["first_step"] = first_step
    if solver in WITH_JACOBIAN:
        opts["jac"] = jac
    return opts


def scipy_propagate(problem_bound, t: np.ndarray, solver: str, kernel, rtol: float, atol: float,
                    max_step: float = 0.0, first_step: float = 0.0,
                    max_steps: int = 100000) -> EngineRun:
    """Integrate a problem with scipy's ``solver`` from t = 0 onto the sample times ``t`` (t[0] = 0,
    increasing), as ``solve_ivp`` with ``t_eval = t`` does."""
    import scipy
    import scipy.integrate

    rec = problem_bound.record
    n = rec.dim
    t = np.asarray(t, dtype=np.float64)
    if first_step > t[-1] - t[0]:               # solve_ivp's ValueError, as a UserError
        raise UserError(f"bad first_step={first_step:g}: larger than the horizon "
                        f"{t[-1] - t[0]:g}; allowed: 0 (the solver's choice) or a smaller step")
    y0 = np.array(rec.y0(problem_bound.values), dtype=np.float64)
    t0 = time.perf_counter()
    fun, jac = field_functions(kernel, n)
    fun(0.0, y0)                      # loads (or compiles) the field and its Jacobian: setup time
    if solver in WITH_JACOBIAN:
        jac(0.0, y0)
    setup = time.perf_counter() - t0

    rows = len(t)
    y = np.empty((rows, n))
    steps = np.zeros(rows, dtype=np.int64)
    nfev = np.zeros(rows)
    njev = np.zeros(rows)
    status, reason, message, done, accepted = Status.OK, "", None, 0, 0
    t1 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught, one_blas_thread():
        warnings.simplefilter("always")
        ode = getattr(scipy.integrate, solver)(fun, float(t[0]), y0, float(t[-1]), **solver_options(
            solver, rtol, atol, max_step, first_step, jac))
        start = (0, ode.nfev, ode.njev)   # the counters of a sample at t0: before any step
        try:
            while done < rows:
                message = ode.step()
                if ode.status == "failed":
                    break
                accepted += 1
                new = int(np.searchsorted(t, ode.t, side="right"))
                if new > done:
                    y[done:new] = ode.dense_output()(t[done:new]).T
                    steps[done:new], nfev[done:new], njev[done:new] = accepted, ode.nfev, ode.njev
                    if done == 0:             # t[0] = t0, read (as solve_ivp does) from the first
                        steps[0], nfev[0], njev[0] = start    # step's dense output
                    done = new
                if ode.status == "finished":
                    break
                if accepted >= max_steps:
                    status = Status.MAX_STEPS
                    reason = (f"more than max_steps={max_steps} steps before t = {float(t[-1]):g} "
                              f"(reached t = {float(ode.t):.17g})")
                    break
                if ode.t == ode.t_old:    # a step that no longer moves t (LSODA does not stop)
                    status = Status.STEP_TOO_SMALL
                    reason = f"scipy {solver}: the step no longer advances t = {float(ode.t):.17g}"
                    break
        except KeyboardInterrupt:         # Ctrl-C: a status; the samples so far are kept
            status, reason = Status.INTERRUPTED, f"interrupted at t = {float(ode.t):.17g}"
    seconds = time.perf_counter() - t1

    finite = np.all(np.isfinite(y[:done]), axis=1)
    if ode.status == "failed" and status is not Status.INTERRUPTED:
        status, reason = _failure(ode, solver, message, caught)
    if not finite.all():
        done = int(np.argmin(finite))
        status = Status.NONFINITE
        reason = f"state became non-finite near t = {float(t[done]):.17g}"
    info = {"engine": f"scipy {scipy.__version__}", "solver": solver,
            "call": "solve_ivp(fun, (0, t_end), y0, method, t_eval=grid, rtol, atol, max_step, "
                    "first_step" + (", jac)" if solver in WITH_JACOBIAN else ")"),
            "rtol": rtol, "atol": atol, "max_step": max_step if max_step > 0 else None,
            "first_step": first_step if first_step > 0 else None,
            "steps": "accepted steps (solver.step() calls)", "nfev": "scipy's solver.nfev",
            "njev": "scipy's solver.njev", "nlu": int(ode.nlu), "blas_threads": 1,
            **({"message": message} if message else {}),
            **({"warnings": said} if (said := sorted({str(w.message) for w in caught})) else {})}
    return EngineRun(y=y[:done], y_full=None, steps=steps[:done], nfev=nfev[:done],
                     status=status.value, reason=reason, setup_seconds=setup, seconds=seconds,
                     info=info, njev=njev[:done])


def _failure(ode, solver: str, message, caught) -> tuple[Status, str]:
    """Our status and reason for a solver that failed (``solver.status == 'failed'``)."""
    where = f"at t = {float(ode.t):.17g}"
    y = np.asarray(ode.y)
    if not np.all(np.isfinite(y)) or not np.all(np.isfinite(ode.fun(ode.t, y))):
        return Status.NONFINITE, f"state or field became non-finite {where} (scipy: {message})"
    if solver == "LSODA":
        istate = int(ode._lsoda_solver._integrator.istate)      # scipy's own LSODA wrapper
        said = next((str(w.message) for w in reversed(caught) if "lsoda" in str(w.message)), "")
        return (LSODA_STATUS.get(istate, Status.STEP_TOO_SMALL),
                f"LSODA failed {where}: istate={istate} {said}".rstrip())
    return Status.STEP_TOO_SMALL, f"scipy {solver} failed {where}: {message}"
