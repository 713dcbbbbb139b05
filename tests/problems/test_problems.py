"""Every registered problem: its compiled field, Jacobian, integrals and exact solution.

(a) first integrals: D_H F = 0 ([B] (2.1) and the proof of the Main Lemma, "D_H F is equal to zero
    because H is a first integral"; [HLW] (1.11)), at random points;
(b) ``base_jac`` is dF/dy (central differences of ``base_f``);
(c) ``grad_k`` is ∇H_k (central differences of ``integral_k``);
(d) ``problem.exact`` solves the base field: it agrees with scipy's DOP853 at rtol = atol = 1e-13
    over a few periods to 1e-9 times the size of the solution (DOP853's own error there is
    1e-11-5e-10), and returns y0 at t = 0.

Central differences with step δ = 1e-6 max(1, |y_j|) have error <= δ²/6 |f'''| + ε |f| / δ,
about 1e-10 for the O(1)-O(10) data below; the tolerance is 1e-7 relative to the size of the
derivative.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.problems import REGISTRY
from gnibench.methods.assembly import assemble
from gnibench.problems.codegen import problem_meta
from gnibench.suite.cell.spec import parse_method, parse_problem
from scipy.integrate import solve_ivp
from support import FULL

FD = 1e-6
PIDS = list(REGISTRY)

# extra initial points for the exact-solution check (problem spec, final time)
EXACT_CASES = {
    "pendulum": [("pendulum:p0=0,q0=0.5", 20.0),        # libration, [HLW] Fig 1.4 explicit Euler start
                 ("pendulum:p0=2.1,q0=0", 20.0),        # rotation, [HLW] Fig 1.4 symplectic Euler start
                 ("pendulum:p0=-1.3,q0=2.0", 20.0)],    # rotation backwards, mid-cycle start
    # e = 0.9: DOP853's own error grows ~4e-10 per pericentre passage: 1.5 periods
    "kepler-2d": [("kepler-2d:e=0.9", 3 * math.pi),                               # high eccentricity
                  ("kepler-2d:p10=-0.4,p20=0.9,q10=0.6,q20=0.5", 12.0),          # non-pericentre, e = 0.36
                  ("kepler-2d:p10=0.5,p20=0.4,q10=-0.8,q20=0.6", 12.0)],         # clockwise (L < 0)
    "kepler-3d": [("kepler-3d:M0=2", 3.0)],                                      # non-pericentre start
}


# default horizon 15 time units; problems whose period is much shorter get "a few periods"
EXACT_T = {"kepler-3d": 3.0}                            # period 1, e = 0.8


def _exact_cases():
    out = []
    for pid, rec in REGISTRY.items():
        if rec.exact is None:
            continue
        for spec, T in [(pid, EXACT_T.get(pid, 15.0))] + EXACT_CASES.get(pid, []):
            out.append(pytest.param(spec, T, id=spec))
    return out


def compiled(spec: str):
    """(module, problem Bound, par array) of the problem's generated code."""
    prob = parse_problem(spec)
    mod, meta = assemble(prob, parse_method("euler", prob)), problem_meta(prob.record)
    return mod, prob, np.array(prob.record.par(prob.values), dtype=np.float64), meta


def random_points(prob, k=8, seed=0):
    """Points near the default initial point, multiplicatively perturbed (stays in the domain)."""
    rng = np.random.default_rng(seed)
    y0 = np.array(prob.record.y0(prob.values))
    return [y0 * (1 + 0.2 * rng.uniform(-1, 1, y0.size)) + 0.1 * rng.uniform(-1, 1, y0.size)
            for _ in range(k)]


def central(fun, y, j):
    d = FD * max(1.0, abs(y[j]))
    e = np.zeros_like(y)
    e[j] = d
    return (np.asarray(fun(y + e)) - np.asarray(fun(y - e))) / (2 * d)


@pytest.mark.parametrize("pid", PIDS)
def test_integrals_are_first_integrals(pid):
    """D_H F = 0 to round-off for every integral, [B] (2.1), [HLW] (1.11)."""
    mod, prob, par, meta = compiled(pid)
    for y in random_points(prob):
        F = np.array(mod.base_f(tuple(y), par))
        for k in range(len(meta["integrals"])):
            g = np.array(getattr(mod, f"grad_{k}")(tuple(y), par))
            scale = np.sum(np.abs(g * F))
            assert scale > 0
            assert abs(g @ F) <= 1e-13 * scale, (meta["integrals"][k], y, g @ F, scale)


@pytest.mark.parametrize("pid", PIDS)
def test_jacobian_matches_finite_differences(pid):
    """base_jac = dF/dy (the Newton matrix of the implicit methods, [HLW] (1.6)-(1.7)).

    Compiling the Jacobian of the 36-dimensional outer solar system alone takes ~30 s, so
    problems of dimension > 12 are checked only with GNIBENCH_TEST_FULL=1.
    """
    if REGISTRY[pid].dim > 12 and not FULL:
        pytest.skip("large Jacobian: compiled only with GNIBENCH_TEST_FULL=1")
    mod, prob, par, _ = compiled(pid)
    n = prob.record.dim
    for y in random_points(prob, seed=1):
        J = np.empty((n, n))
        mod.base_jac(tuple(y), par, J)
        fd = np.column_stack([central(lambda z: mod.base_f(tuple(z), par), y, j) for j in range(n)])
        assert np.allclose(J, fd, rtol=1e-7, atol=1e-7 * max(1.0, np.max(np.abs(J)))), (y, J, fd)


@pytest.mark.parametrize("pid", PIDS)
def test_gradients_match_finite_differences(pid):
    """grad_k = ∇H_k, the rows of D_H in the observer (2.5) and penalty (2.10) terms of [B]."""
    mod, prob, par, meta = compiled(pid)
    n = prob.record.dim
    for y in random_points(prob, seed=2):
        for k in range(len(meta["integrals"])):
            g = np.array(getattr(mod, f"grad_{k}")(tuple(y), par))
            Hk = getattr(mod, f"integral_{k}")
            fd = np.array([central(lambda z, Hk=Hk: Hk(tuple(z), par), y, j) for j in range(n)])
            assert np.allclose(g, fd, rtol=1e-7, atol=1e-7 * max(1.0, np.max(np.abs(g)))), (k, y, g, fd)


@pytest.mark.parametrize("spec,T", _exact_cases())
def test_exact_solution_matches_dop853(spec, T):
    """problem.exact solves y' = F(y): [HLW] (1.13) via Jacobi functions, Kepler via (2.1)."""
    mod, prob, par, _ = compiled(spec)
    rec = prob.record
    y0 = rec.y0(prob.values)
    ts = np.linspace(0.0, T, 41)

    def rhs(t, y):
        return np.array(mod.base_f((*y,), par))

    ref = solve_ivp(rhs, (0.0, T), np.array(y0), method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=ts)
    assert ref.success
    ex = rec.exact(ts, y0, prob.values)
    assert ex.shape == (ts.size, rec.dim)
    err = np.max(np.abs(ex - ref.y.T))
    scale = max(1.0, float(np.max(np.abs(ref.y))))
    assert err <= 1e-9 * scale, f"max |exact - DOP853| = {err:.2e}, solution size {scale:.3g}"


@pytest.mark.parametrize("spec,T", _exact_cases())
def test_exact_solution_starts_at_y0(spec, T):
    """exact(0) = y0 to round-off."""
    prob = parse_problem(spec)
    y0 = np.array(prob.record.y0(prob.values))
    ex = prob.record.exact(np.array([0.0]), tuple(y0), prob.values)[0]
    assert np.max(np.abs(ex - y0)) <= 2e-15 * max(1.0, np.max(np.abs(y0))), (ex - y0)
