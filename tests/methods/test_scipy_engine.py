"""scipy's solve_ivp solvers as contestants (methods/scipy_methods.py, methods/engines/scipy.py).

* The engine is solve_ivp: the same samples (bit for bit), nfev and njev as ``solve_ivp`` called
  directly with the problem's compiled field, and ``steps`` = its number of accepted steps.
* Against Kepler's exact solution the global error follows the tolerance.
* Statuses, refusals (modifiers, post_step problems), the step budget.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.methods import METHODS
from gnibench.suite.cell.compiled import problem_kernel
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.status import Status
from scipy.integrate import solve_ivp
from threadpoolctl import threadpool_limits

PERIOD = 2 * math.pi                       # kepler-2d from its default start: a = 1
SOLVERS = {"rk45": "RK45", "rk23": "RK23", "dop853": "DOP853", "radau": "Radau", "bdf": "BDF",
           "lsoda": "LSODA"}


def direct(problem: str, solver: str, t_eval, tol: float, with_jac: bool, t_end=None,
           atol: float | None = None):
    """solve_ivp called as a user would, on the problem's compiled field (and Jacobian), with
    rtol = tol and atol = tol (or ``atol``)."""
    bound, _ = prepare(problem, "rk4")
    pk = problem_kernel(bound)
    f, J, par = pk.kernel.base_f, pk.kernel.base_jac, pk.par
    n = bound.record.dim

    def jac(t, y):
        out = np.zeros((n, n))
        J(tuple(y), par, out)
        return out

    y0 = np.array(bound.record.y0(bound.values), dtype=float)
    kw = {"jac": jac} if with_jac else {}
    t_end = t_eval[-1] if t_end is None else t_end
    with threadpool_limits(1, user_api="blas"):      # as the engine runs (Radau's LU rounds
        return solve_ivp(lambda t, y: f(tuple(y), par), (0.0, t_end), y0,    # by thread count)
                         method=solver, t_eval=t_eval, rtol=tol,
                         atol=tol if atol is None else atol, **kw)


def test_dop853_is_solve_ivp_on_kepler():
    """The acceptance check of issue 16: scipy-dop853 at rtol = atol = 1e-10 over one period."""
    traj = solve("kepler-2d", f"scipy-dop853:rtol=1e-10,atol=1e-10,dt_out={PERIOD / 10!r}",
                 t_end=PERIOD)
    assert traj.status is Status.OK
    sol = direct("kepler-2d", "DOP853", traj.t, 1e-10, with_jac=False)
    assert sol.success
    assert traj.nfev[-1] == sol.nfev
    assert np.array_equal(traj.t, sol.t)
    assert np.array_equal(traj.y, sol.y.T)
    free = direct("kepler-2d", "DOP853", None, 1e-10, with_jac=False, t_end=PERIOD)
    assert traj.steps[-1] == len(free.t) - 1          # accepted steps (solve_ivp keeps each end)


@pytest.mark.parametrize("name", list(SOLVERS))
def test_every_solver_is_solve_ivp(name):
    tol = 1e-7
    traj = solve("kepler-2d", f"scipy-{name}:rtol={tol},atol={tol},dt_out=0.5", t_end=PERIOD)
    assert traj.status is Status.OK
    sol = direct("kepler-2d", SOLVERS[name], traj.t, tol, with_jac=name in ("radau", "bdf", "lsoda"))
    assert (traj.nfev[-1], traj.njev[-1]) == (sol.nfev, sol.njev)
    assert np.array_equal(traj.y, sol.y.T)
    # cumulative counters: non-decreasing, 0 steps at t = 0
    assert traj.steps[0] == 0 and np.all(np.diff(traj.steps) >= 0) and np.all(np.diff(traj.nfev) >= 0)
    assert traj.provenance["engine"]["solver"] == SOLVERS[name]


@pytest.mark.parametrize("name", list(SOLVERS))
def test_global_error_follows_the_tolerance(name):
    """Against Kepler's exact solution (the default reference), one period at e = 0.6: the error is
    within 10^4 tolerances (the global amplification of the local error over the orbit) and falls
    by at least 100 when the tolerance falls by 10^4."""
    errs = {}
    for tol in (1e-6, 1e-10):
        traj = solve("kepler-2d", f"scipy-{name}:rtol={tol},atol={tol},dt_out=0.5", t_end=PERIOD)
        assert traj.status is Status.OK and traj.reference.describe["backend"] == "exact"
        errs[tol] = float(np.max(np.linalg.norm(traj.y - traj.reference.y, axis=1)))
        assert errs[tol] < 1e4 * tol, (name, tol, errs[tol])
    assert errs[1e-10] < errs[1e-6] / 100, errs


def test_step_budget_is_a_status():
    traj = solve("kepler-2d", "scipy-rk45:rtol=1e-10,atol=1e-10,max_steps=20", t_end=PERIOD)
    assert traj.status is Status.MAX_STEPS and "max_steps=20" in traj.reason
    assert traj.steps[-1] <= 20 and len(traj.t) >= 1 and traj.t[-1] < PERIOD


@pytest.mark.parametrize("name", ["rk45", "radau", "lsoda"])
def test_collision_is_a_failure_not_a_crash(name):
    """A radial Kepler orbit (p = 0) falls into the singularity at t = pi/(2 sqrt 2) from r = 1:
    the solvers stop there (LSODA keeps shrinking its step and stops at the step budget)."""
    traj = solve("kepler-2d:p10=0,p20=0,q10=1,q20=0",
                 f"scipy-{name}:rtol=1e-8,atol=1e-8,max_steps=3000", t_end=2.0)
    assert traj.status in (Status.STEP_TOO_SMALL, Status.NONFINITE, Status.MAX_STEPS), traj.status
    assert traj.reason and np.all(np.isfinite(traj.y))
    assert traj.t[-1] < math.pi / (2 * math.sqrt(2))


def test_modifiers_and_post_step_problems_are_refused():
    with pytest.raises(UserError, match="modifiers"):
        prepare("kepler-2d", "scipy-rk45+observer:on=H/L")
    with pytest.raises(UserError, match="post_step"):
        prepare("geodesic-genus2", "scipy-dop853")


def test_records_are_external_and_listed():
    for name in SOLVERS:
        rec = METHODS[f"scipy-{name}"]
        assert rec.run is not None and rec.grid_param == "dt_out"
        assert rec.kind == "external"
        assert {"rtol", "atol", "max_step", "first_step", "dt_out"} <= {p.name for p in rec.params}


def test_options_reach_the_solver():
    """max_step bounds every step; first_step is the first step (both as solve_ivp takes them)."""
    traj = solve("kepler-2d", "scipy-rk45:rtol=1e-6,atol=1e-6,max_step=0.05,dt_out=0.5",
                 t_end=PERIOD)
    assert traj.steps[-1] >= PERIOD / 0.05
    a = solve("kepler-2d", "scipy-rk45:rtol=1e-6,atol=1e-6,first_step=1e-4", t_end=PERIOD)
    b = solve("kepler-2d", "scipy-rk45:rtol=1e-6,atol=1e-6", t_end=PERIOD)
    assert not np.array_equal(a.y[-1], b.y[-1])


def test_every_work_precision_experiment_has_the_six_solvers():
    from gnibench.suite.runs.experiment import load_experiment, shipped

    wp = [name for name in shipped() if name.startswith("wp-")]
    assert len(wp) >= 5
    for name in wp:
        bases = {c.method.split(":")[0] for c in load_experiment(name).cells}
        assert {f"scipy-{s}" for s in SOLVERS} <= bases, name


def test_work_precision_report_shows_the_solvers(tmp_path):
    """A tiny work-precision run: scipy's DOP853 beside ours, ranked by nfev in the league table,
    a family of its own with its own colour and marker on the nfev and wall-time panels."""
    import re

    import pandas as pd
    from gnibench.reports.palette import styles
    from gnibench.reports.setups import add_setups
    from gnibench.reports.site import build_site
    from gnibench.suite.runs.runner import run_experiment

    path = tmp_path / "wp.toml"
    path.write_text('name = "wp-tiny-scipy"\ntitle = "tiny wp"\nreference = "r"\n'
                    't_end = 6.283185307179586\nevery = 1000\n'
                    '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["dop853:atol=1e-14"]\n'
                    'vary.rtol = [1e-6, 1e-9]\n'
                    '[[cells]]\nproblems = ["kepler-2d"]\n'
                    'methods = ["scipy-dop853:dt_out=3.14,atol=1e-14"]\nevery = 1\n'
                    'vary.rtol = [1e-6, 1e-9]\n')
    out = run_experiment(path, tmp_path / "out", jobs=1, log=open("/dev/null", "w"))  # noqa: SIM115
    cells = pd.read_parquet(out / "cells.parquet")
    ours = cells[cells["family"] == "scipy-dop853"]
    assert len(ours) == 2 and ours["adaptive"].all() and (ours["method_kind"] == "external").all()
    assert (ours["sweep"] == "rtol").all() and ours["nfev"].notna().all()
    families = add_setups(cells)
    style = styles(families)
    first = families.drop_duplicates("setup")
    assert list(first["family"]) == ["dop853", "scipy-dop853"]
    ours_style, scipy_style = (style[int(s)] for s in first["setup"])
    assert ours_style["color"] != scipy_style["color"]
    assert ours_style["marker"] != scipy_style["marker"]
    build_site([out], tmp_path / "site", thresholds=(1e-6,))
    html = (tmp_path / "site" / "wp-tiny-scipy.html").read_text()
    rows = re.findall(r"<tr>\s*<td>([^<]*)</td><td><code>([^<]*)</code></td>", html)
    ranks = {fam: rank for rank, fam in rows}
    assert ranks["scipy-dop853"] in ("1", "2") and ranks["dop853"] in ("1", "2")


def test_scipy_refusals_and_warnings_are_kept():
    """A first step beyond the horizon is a UserError (solve_ivp raises a ValueError); an rtol
    that solve_ivp would raise to 100 eps (with a warning) is refused before any work."""
    with pytest.raises(UserError, match="first_step=100"):
        solve("kepler-2d", "scipy-rk45:first_step=100", t_end=1.0)
    with pytest.raises(UserError, match="rtol='1e-16'; allowed: 2.22045e-14 <= rtol"):
        solve("kepler-2d", "scipy-rk45:rtol=1e-16", t_end=1.0)


def test_ctrl_c_keeps_the_samples_so_far(monkeypatch):
    """A KeyboardInterrupt inside the solver (here raised by the field's 300th call) ends the
    cell as the compiled drivers end one: the driver's Interrupted, with the samples computed."""
    import gnibench.methods.engines.scipy as engine
    from gnibench.suite.cell.driver import Interrupted

    real = engine.field_functions

    def counting(kernel, n):
        fun, jac = real(kernel, n)
        calls = [0]

        def interrupting(t, y):
            calls[0] += 1
            if calls[0] == 300:
                raise KeyboardInterrupt
            return fun(t, y)

        return interrupting, jac

    monkeypatch.setattr(engine, "field_functions", counting)
    with pytest.raises(Interrupted) as e:
        solve("kepler-2d", "scipy-rk45:rtol=1e-8,atol=1e-8,dt_out=0.1", t_end=10 * PERIOD)
    part = e.value.partial
    assert part.status is Status.INTERRUPTED and 10 < len(part.t) and part.t[-1] < 10 * PERIOD
    assert np.all(np.isfinite(part.y)) and part.nfev[-1] < 300


@pytest.mark.parametrize("name", SOLVERS)
def test_a_tolerance_scipy_would_raise_is_refused(name):
    """solve_ivp raises rtol below 100 eps to 100 eps with a warning: the table would record a
    tolerance never used (scipy-radau:rtol=1e-30 was ``ok`` with rtol=1e-30 in its spec)."""
    eps100 = float(100 * np.finfo(float).eps)
    with pytest.raises(UserError, match=rf"scipy-{name}: bad value rtol='1e-30'; allowed: "):
        prepare("harmonic-oscillator", f"scipy-{name}:rtol=1e-30")
    with pytest.raises(UserError):
        prepare("harmonic-oscillator", f"scipy-{name}:rtol={eps100 * 0.999!r}")
    traj = solve("harmonic-oscillator", f"scipy-{name}:rtol={eps100!r},atol=1e-12", t_end=0.01)
    assert traj.status is Status.OK and "warnings" not in traj.provenance["engine"], \
        traj.provenance["engine"].get("warnings")
