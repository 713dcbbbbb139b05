"""Contestants' options reach their engine as the user wrote them, bit for bit.

Each external contestant is compared with a direct call of its library, written here as a user of
that library would write it, with options that cannot be confused: rtol and atol unequal (and
each other's swap checked to give other bits, so the comparison can tell them apart), heyoka's
tolerance and precision, IAS15's epsilon. Same samples, bit for bit, and the options recorded in
the result's provenance as given. And heyoka's step counts at the samples (a cosmic-ray
survivor's class, issue 41).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare
from test_scipy_engine import SOLVERS, direct

PERIOD = 2 * math.pi                               # kepler-2d from its default start: a = 1
RTOL, ATOL = 1e-5, 1e-9


def solve_ivp_directly(solver: str, t_eval, rtol: float, atol: float):
    """solve_ivp on kepler-2d's compiled field (and Jacobian for the implicit solvers)."""
    return direct("kepler-2d", solver, t_eval, rtol, solver in ("Radau", "BDF", "LSODA"),
                  atol=atol)


@pytest.mark.parametrize("name", list(SOLVERS))
def test_scipy_contestants_pass_rtol_and_atol_as_given(name):
    traj = solve("kepler-2d", f"scipy-{name}:rtol={RTOL},atol={ATOL},dt_out=0.5", t_end=PERIOD)
    assert traj.status.value == "ok"
    sol = solve_ivp_directly(SOLVERS[name], traj.t, RTOL, ATOL)
    swapped = solve_ivp_directly(SOLVERS[name], traj.t, ATOL, RTOL)
    assert not np.array_equal(sol.y, swapped.y)      # the comparison tells rtol from atol
    assert np.array_equal(traj.y, sol.y.T)
    assert (traj.nfev[-1], traj.njev[-1]) == (sol.nfev, sol.njev)
    engine = traj.provenance["engine"]
    assert (engine["rtol"], engine["atol"]) == (RTOL, ATOL)


def heyoka_directly(t, tol: float, precision: str):
    """heyoka's Taylor integrator on kepler-2d's equations, with the options as given."""
    import heyoka as hy
    from gnibench.methods.engines.heyoka import fp_type, heyoka_system

    bound, _ = prepare("kepler-2d", "rk4")
    rec = bound.record
    fp = fp_type(precision)
    system = heyoka_system(rec)
    pars = ([fp(float(x)) for x in rec.par(bound.values)] + [fp(c) for c in system.constants])
    ta = hy.taylor_adaptive(system.equations, [fp(float(x)) for x in rec.y0(bound.values)],
                            fp_type=fp, tol=fp(tol), pars=pars[:system.n_pars], high_accuracy=True)
    _, _, _, _, _, out = ta.propagate_grid(np.asarray(t, fp))
    return np.asarray(out.astype(np.float64)), ta


@pytest.mark.parametrize("tol,precision", [(1e-9, "double"), (1e-12, "long double")])
def test_heyoka_contestant_passes_its_tolerance_and_precision(tol, precision):
    traj = solve("kepler-2d", f"heyoka-taylor:tol={tol},precision={precision},dt_out=0.5",
                 t_end=PERIOD)
    y, ta = heyoka_directly(traj.t, tol, precision)
    assert np.array_equal(traj.y, y)
    engine = traj.provenance["engine"]
    assert (engine["tol"], engine["precision"], engine["taylor_order"]) == (tol, precision,
                                                                            ta.order)
    other, _ = heyoka_directly(traj.t, tol * 1e3, precision)
    assert not np.array_equal(other, y)               # the tolerance shows in the bits


def ias15_directly(t, epsilon: float):
    """IAS15 on kepler-2d (μ = 1: G = 1, a unit central mass, a test particle), landing exactly
    on every sample."""
    import rebound

    bound, _ = prepare("kepler-2d", "rk4")
    p1, p2, q1, q2 = bound.record.y0(bound.values)
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    sim.add(m=1.0)
    sim.add(m=0.0, x=q1, y=q2, vx=p1, vy=p2)
    sim.N_active = 1
    out = []
    for tk in t:
        sim.integrate(float(tk), exact_finish_time=1)
        star, planet = sim.particles[0], sim.particles[1]
        out.append([planet.vx - star.vx, planet.vy - star.vy, planet.x - star.x,
                    planet.y - star.y])
    return np.array(out)


def test_ias15_contestant_passes_its_epsilon():
    eps = 1e-6
    traj = solve("kepler-2d", f"rebound-ias15:epsilon={eps},dt_out=0.5", t_end=PERIOD)
    assert np.array_equal(traj.y, ias15_directly(traj.t, eps))
    assert traj.provenance["engine"]["epsilon"] == eps
    assert not np.array_equal(ias15_directly(traj.t, 1e-3), traj.y)


def test_heyoka_step_counts_count_the_steps_before_each_sample():
    """``steps`` at a sample is the number of Taylor steps taken to reach it: 0 at t = 0, at least
    1 at every later sample (several samples inside the first step all say 1), non-decreasing."""
    traj = solve("kepler-2d", "heyoka-taylor:dt_out=0.01", t_end=1.0)
    steps = np.asarray(traj.steps)
    assert steps[0] == 0 and np.all(steps[1:] >= 1) and np.all(np.diff(steps) >= 0)
    assert np.sum(steps == 1) > 1                      # samples inside the first step
