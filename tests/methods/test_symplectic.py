"""Symplecticity of one step: M^T J M = J for M the Jacobian of the one-step map Φ_h.

[HLW] I.1.3 "Area Preservation": the exact flow of (1.10) has det φ'_t = 1 (d = 1) and more generally
φ'_t^T J φ'_t = J; symplectic Euler (1.9), Störmer–Verlet (1.17) and the implicit midpoint rule (1.7)
share this property, explicit Euler (1.5) does not (Fig 1.3). [HLW] (1.10) fixes the convention
p' = -H_q, q' = H_p, i.e. y' = J^{-1} ∇H with J[p_i, q_i] = 1, J[q_i, p_i] = -1, built here in each
problem's own state order from ``problem.canonical``.

M is computed through the public API only: Φ_h(y0) = ``solve(problem:<s>0=..., method, steps=1)``,
differentiated by central differences with step δ_j = δ max(1, |y0_j|), δ = 1e-5, at the default
initial point with h = 0.3/ρ (ρ the spectral radius of dF/dy there). Per symplectic method one
one-degree-of-freedom problem and one larger one are used, nonlinear and small first (all eligible
problems with GNIBENCH_TEST_FULL=1).

Tolerance. M(δ), the central difference, has truncation error (δ²/6)|Φ'''| and rounding error
ε|Φ|/δ (ε = 2.2e-16, plus the 4ε Newton tolerance of the implicit kernels). We use the
Richardson combination M = (4 M(δ/2) - M(δ))/3: truncation O(δ⁴) (negligible), rounding about
3 ε|Φ|/δ ≈ 1e-10 for the O(1) data used here. M^T J M - J is bilinear in M, so its error is at
most 2 |M| err(M) ≈ 2e-10 |M|; we require |M^T J M - J|_max <= 1e-8 max(1, |M|_max²), a 50x
margin (measured defects 1e-12 - 3e-11). As an empirical check, |M(δ/2) - M(δ)| (3/4 of the plain
truncation error) must itself be below the tolerance (measured <= 1.7e-9, Kepler pericentre). The
negative controls (explicit Euler, rk4 at h = 0.6) violate it by 3-7 orders of magnitude.
"""
from __future__ import annotations

import numpy as np
import pytest
from gnibench import methods
from gnibench.problems import REGISTRY
from gnibench.suite.cell.solve import solve
from support import FULL, rate_scale, takes

DELTA = 1e-5
TOL = 1e-8
COMPILED = getattr(methods, "COMPILED", methods.METHODS)   # external engines have their own tests


def step_size(pid: str) -> float:
    """A large but Newton-safe step: 0.3/ρ, ρ the spectral radius of dF/dy at y0."""
    return 0.3 / rate_scale(pid)


def _structure_ok(mid, pid) -> bool:
    """Hamiltonian, accepted by the method, and for partitioned methods the canonical (p, q) split."""
    method, problem = COMPILED[mid], REGISTRY[pid]
    if problem.canonical is None:
        return False
    if not takes(pid, mid):
        return False
    if "partition" in method.needs:
        blocks = {frozenset(b) for b in problem.partition}
        return blocks == {frozenset(b) for b in problem.canonical}
    return True


def _linear(pid) -> bool:
    """True when the field is linear (a weaker test of symplecticity)."""
    import sympy as sp
    from gnibench.problems.codegen import symbolic

    ys, _, rhs, _ = symbolic(REGISTRY[pid])
    try:
        return all(sp.Poly(f, *ys).total_degree() <= 1 for f in rhs)
    except sp.PolynomialError:
        return False


def _pick(pids):
    """Per method: one one-degree-of-freedom problem and one larger one, nonlinear and small first."""
    order = list(REGISTRY)
    ranked = sorted(pids, key=lambda pid: (_linear(pid), REGISTRY[pid].dim, order.index(pid)))
    if FULL:
        return ranked
    return [p for p in ranked if REGISTRY[p].dim == 2][:1] + [p for p in ranked if REGISTRY[p].dim > 2][:1]


CELLS = [pytest.param(pid, mid, id=f"{mid}-{pid}")
         for mid, m in COMPILED.items() if m.symplectic
         for pid in _pick([pid for pid in REGISTRY if _structure_ok(mid, pid)])]


def poisson_matrix(problem) -> np.ndarray:
    """J in the problem's state order: J[p_i, q_i] = 1, J[q_i, p_i] = -1 ([HLW] (1.10))."""
    n = problem.dim
    J = np.zeros((n, n))
    for p, q in zip(*problem.canonical):
        i, j = problem.state.index(p), problem.state.index(q)
        J[i, j], J[j, i] = 1.0, -1.0
    return J


def one_step(pid, y, method) -> np.ndarray:
    problem = REGISTRY[pid]
    opts = ",".join(f"{s}0={float(v)!r}" for s, v in zip(problem.state, y))
    r = solve(f"{pid}:{opts}", method, steps=1)
    assert r.status == "ok", r.reason
    return r.y[-1]


def central_jacobian(pid, method, delta) -> np.ndarray:
    """M(δ): central-difference Jacobian of the one-step map at the default initial point."""
    problem = REGISTRY[pid]
    y0 = np.array(solve(pid, method, steps=1).y0)
    M = np.empty((problem.dim, problem.dim))
    for j in range(problem.dim):
        d = delta * max(1.0, abs(y0[j]))
        e = np.zeros_like(y0)
        e[j] = d
        M[:, j] = (one_step(pid, y0 + e, method) - one_step(pid, y0 - e, method)) / (2 * d)
    return M


def step_jacobian(pid, method) -> tuple[np.ndarray, float]:
    """Richardson-extrapolated Jacobian M and the truncation estimate |M(δ/2) - M(δ)|_max."""
    M1 = central_jacobian(pid, method, DELTA)
    M2 = central_jacobian(pid, method, DELTA / 2)
    return (4 * M2 - M1) / 3, float(np.max(np.abs(M2 - M1)))


def symplecticity_defect(pid, method) -> tuple[float, float, np.ndarray, float]:
    """(|M^T J M - J|_max, tolerance scale max(1, |M|_max²), M, finite-difference estimate)."""
    J = poisson_matrix(REGISTRY[pid])
    M, trunc = step_jacobian(pid, method)
    scale = max(1.0, float(np.max(np.abs(M)))) ** 2
    return float(np.max(np.abs(M.T @ J @ M - J))), scale, M, trunc


def test_poisson_matrix_generates_the_field():
    """J^{-1} ∇H is the pendulum field (1.13): p' = -sin q, q' = p, in state order (p, q)."""
    J = poisson_matrix(REGISTRY["pendulum"])
    p, q = 0.3, 1.1
    grad = np.array([p, np.sin(q)])                 # ∇H of (1.12) in (p, q) order
    assert np.allclose(np.linalg.solve(J, grad), [-np.sin(q), p])


@pytest.mark.parametrize("pid,mid", CELLS)
def test_one_step_is_symplectic(pid, mid):
    """M^T J M = J for symplectic methods, [HLW] I.1.3 (area preservation, Fig 1.3)."""
    method = f"{mid}:h={step_size(pid)!r}"
    defect, scale, M, trunc = symplecticity_defect(pid, method)
    assert defect <= TOL * scale, f"|M^T J M - J| = {defect:.3e} > {TOL * scale:.1e}; M = {M}"
    assert trunc <= TOL * scale, f"finite differences too inaccurate here: {trunc:.2e}"


@pytest.mark.parametrize("mid,pid,h", [("euler", "harmonic-oscillator", 0.3),
                                       ("euler", "pendulum", 0.3), ("rk4", "pendulum", 0.6)])
def test_non_symplectic_methods_violate_it(mid, pid, h):
    """Negative control: explicit Euler (det M = 1 + h² on the oscillator) and rk4 are not symplectic."""
    defect, scale, _, _ = symplecticity_defect(pid, f"{mid}:h={h}")
    assert defect > 100 * TOL * scale, f"defect {defect:.3e} not distinguishable from round-off"


def _by_hand(method: str, p: float, q: float, h: float) -> tuple[float, float]:
    """One step on the pendulum H = p²/2 - cos q ([HLW] (1.12), state (p, q)) written out from the
    seed's formulas, independently of the kernel generators: symplectic Euler (1.9) implicit in p
    (explicit here, H being separable), its adjoint, and Störmer-Verlet (1.17), kick-drift-kick."""
    if method == "symplectic-euler":
        p = p - h * np.sin(q)
        return p, q + h * p
    if method == "symplectic-euler-adjoint":
        q = q + h * p
        return p - h * np.sin(q), q
    p = p - 0.5 * h * np.sin(q)                     # (1.17): p_n+1/2
    q = q + h * p                                   #         q_n+1
    return p - 0.5 * h * np.sin(q), q               #         p_n+1


@pytest.mark.parametrize("summation", ["plain", "compensated"])
@pytest.mark.parametrize("method", ["symplectic-euler", "symplectic-euler-adjoint", "stormer-verlet"])
def test_partitioned_steps_are_the_seeds_formulas(method, summation):
    """Ten steps of the compiled method (and of its compensated twin step_sum) follow [HLW] (1.9)
    and (1.17) evaluated by hand to round-off (the other order of Störmer-Verlet's halves,
    drift-kick-drift, is also symmetric, symplectic and of order 2, but is not (1.17): it differs
    by O(h³) per step, 1e-4 here)."""
    h, p, q = 0.1, 0.3, 1.2
    traj = solve(f"pendulum:p0={p},q0={q}", f"{method}:h={h},sum={summation}", steps=10)
    ours = np.asarray(traj.y)
    for n in range(1, 11):
        p, q = _by_hand(method, p, q, h)
        assert np.max(np.abs(ours[n] - (p, q))) <= 1e-14, (n, ours[n], (p, q))
