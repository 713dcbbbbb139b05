"""Identity checks of [HLW] Ch. I: structure and closed-form statements (kind [I] of the claims inventory)."""
from __future__ import annotations

import math

import numpy as np
from gnibench.suite.ledger.identity_tools import (
    conservation_residual,
    functions,
    problem,
    random_states,
)


def lv_invariant() -> dict:
    """[HLW] (1.4): I = ln u − u + 2 ln v − v is an invariant (∇I·f = 0), and an accurate trajectory
    (dop853, 1e-14, t = 20) keeps it."""
    from gnibench.suite.cell.solve import solve

    traj = solve("lotka-volterra", "dop853:rtol=1e-14,atol=1e-14", t_end=20.0)
    drift = float(np.max(np.abs(traj.integrals[:, 0] - traj.H0[0])))
    return {"residual": conservation_residual("lotka-volterra"), "trajectory": drift,
            "measured": drift}


def _forth_and_back(method: str, h: float, steps: int = 100) -> float:
    """|Φ_{−h}^n(Φ_h^n(y0)) − y0| / |y0| on the pendulum: n steps forward, then n steps backward
    from the point reached (the driver facade, ``reverse=True``)."""
    from gnibench.suite.cell.solve import solve
    from gnibench.suite.cell.spec import prepare

    bound, cfg = prepare("pendulum:p0=0.3,q0=1.0", f"{method}:h={h!r}")
    y_n = solve(bound, cfg, steps=steps, every=steps, reference="none").y[-1]
    start = ",".join(f"{s}0={float(v)!r}" for s, v in zip(bound.record.state, y_n))
    back, cfg = prepare(f"pendulum:{start}", f"{method}:h={h!r}")
    y_back = solve(back, cfg, steps=steps, every=steps, reference="none",
                   reverse=True).y[-1]
    y0 = np.array(bound.record.y0(bound.values))
    return float(np.linalg.norm(y_back - y0) / np.linalg.norm(y0))


def imr_symmetric() -> dict:
    """[HLW] (1.7): the implicit midpoint rule is symmetric, Φ_{−h}∘Φ_h = id (to round-off); the
    symplectic Euler method is not (an O(h²) defect per step)."""
    imr = _forth_and_back("implicit-midpoint", 0.01)
    se = _forth_and_back("symplectic-euler", 0.01)
    return {"imr": imr, "se": se, "measured": imr}


def implicit_euler_damping() -> dict:
    """[HLW] (1.6): implicit Euler damps y' = iωy for every h > 0: |1/(1 − ihω)| < 1 (the
    margin 1 − |R| over hω ∈ [1e-3, 1e3])."""
    hw = np.logspace(-3, 3, 61)          # below 1e-8, 1 - |R| is under the double's resolution
    return {"measured": float(np.min(1 - np.abs(1 / (1 - 1j * hw))))}      # the damping margin


def _det(flow, y, d=1e-3) -> float:
    """det of the Jacobian of ``flow`` at y by central differences, Richardson-extrapolated
    (error O(d⁴))."""
    def jac(step):
        n = len(y)
        J = np.zeros((n, n))
        for j in range(n):
            e = np.zeros(n)
            e[j] = step
            J[:, j] = (flow(y + e) - flow(y - e)) / (2 * step)
        return J

    return float(np.linalg.det((4 * jac(d / 2) - jac(d)) / 3))


def pendulum_area() -> dict:
    """[HLW] I.1.3: the exact flow of the pendulum preserves area, det φ'_t = 1 (the exact solution
    by Jacobi elliptic functions, Jacobian by differences, t = 1..10)."""
    bound = problem("pendulum:p0=0.5,q0=0.8")
    rec, values = bound.record, bound.values
    worst = 0.0
    for t in range(1, 11):
        def flow(y, t=t):
            return np.asarray(rec.exact(np.array([float(t)]), y, values))[0]
        worst = max(worst, abs(_det(flow, np.array(rec.y0(values))) - 1))
    return {"measured": worst}


def pendulum_one_step_area() -> dict:
    """[HLW] Fig 1.3 (h = 1): one explicit Euler step has det 1 + h² cos q ≠ 1 (not area
    preserving); one symplectic Euler step has det 1."""
    from gnibench.suite.cell.solve import solve

    def step(method):
        def flow(y):
            spec = f"pendulum:p0={float(y[0])!r},q0={float(y[1])!r}"
            return solve(spec, f"{method}:h=1.0", steps=1, reference="none").y[-1]
        return flow

    ee_error, se, ee = 0.0, 0.0, 0.0
    for p0, q0 in ((0.2, 0.4), (0.9, -1.1), (0.0, 2.0)):
        y = np.array([p0, q0])
        d_ee = _det(step("euler"), y)
        ee = max(ee, abs(d_ee - 1))
        ee_error = max(ee_error, abs(d_ee - (1 + math.cos(q0))))
        se = max(se, abs(_det(step("symplectic-euler"), y) - 1))
    return {"ee_closed_form": ee_error, "ee_area_change": ee, "se": se, "measured": se}


def stormer_verlet_forms() -> dict:
    """[HLW] (1.15)-(1.17): the one-step Störmer–Verlet solution satisfies the two-step form
    q_{n+1} − 2q_n + q_{n−1} = h² f(q_n) and p_n = (q_{n+1} − q_{n−1})/(2h) (pendulum, h = 0.1)."""
    from gnibench.suite.cell.solve import solve

    h = 0.1
    traj = solve("pendulum:p0=0.3,q0=1.0", f"stormer-verlet:h={h!r}", steps=1000)
    p, q = traj.y[:, 0], traj.y[:, 1]
    two_step = np.max(np.abs(q[2:] - 2 * q[1:-1] + q[:-2] + h * h * np.sin(q[1:-1])))
    momenta = np.max(np.abs(p[1:-1] - (q[2:] - q[:-2]) / (2 * h)))
    return {"two_step": float(two_step), "momenta": float(momenta),
            "measured": float(max(two_step, momenta))}


def kepler_conic() -> dict:
    """[HLW] (2.5)-(2.10): along an accurate trajectory r = d/(1 + e cos φ) (φ from the pericenter,
    d = L², e = |A|), and a spatial orbit stays in the plane ⊥ c."""
    from gnibench.suite.cell.solve import solve

    traj = solve("kepler-2d", "dop853:rtol=1e-13,atol=1e-13", t_end=20.0)
    p1, p2, q1, q2 = traj.y.T
    L = q1 * p2 - q2 * p1
    A = np.column_stack([p2 * L - q1 / np.hypot(q1, q2), -p1 * L - q2 / np.hypot(q1, q2)])
    e = np.linalg.norm(A[0])
    phi = np.arctan2(q2, q1) - math.atan2(A[0, 1], A[0, 0])
    conic = float(np.max(np.abs(np.hypot(q1, q2) - L[0] ** 2 / (1 + e * np.cos(phi)))))
    space = solve("kepler-3d", "dop853:rtol=1e-13,atol=1e-13", t_end=3.0)
    q, pm = space.y[:, :3], space.y[:, 3:]
    c0 = np.cross(q[0], pm[0])
    plane = float(np.max(np.abs(q @ c0)) / (np.linalg.norm(c0) * np.max(np.linalg.norm(q, axis=1))))
    return {"conic": conic, "plane": plane, "measured": max(conic, plane)}


def kepler_angular_momentum() -> dict:
    """[HLW] (2.4): L = q1 p2 − q2 p1 is a first integral (∇L·f = 0)."""
    return {"measured": conservation_residual("kepler-2d", ["L"])}


def kepler_eccentricity_relation() -> dict:
    """[HLW] (2.9): e² = 1 + 2 H0 L0² (e = |A|, the Runge–Lenz vector) at random states."""
    bound = problem("kepler-2d")
    fns, par, names = functions(bound)
    worst = 0.0
    for y in random_states(bound, 30, spread=0.1):
        I = dict(zip(names, fns["invariants"](tuple(y), par)))
        worst = max(worst, abs(I["A1"] ** 2 + I["A2"] ** 2 - 1 - 2 * I["H"] * I["L"] ** 2))
    return {"measured": worst}


def kepler_initial_values() -> dict:
    """[HLW] (2.11): H0 = −1/2, L0 = √(1 − e²), and the orbit returns at t = 2π (dop853, 1e-13)."""
    from gnibench.suite.cell.solve import solve

    bound = problem("kepler-2d")
    fns, par, names = functions(bound)
    y0 = np.array(bound.record.y0(bound.values))
    I = dict(zip(names, fns["invariants"](tuple(y0), par)))
    e = bound.values["e"]
    traj = solve("kepler-2d", "dop853:rtol=1e-13,atol=1e-13", t_end=2 * math.pi, every=10 ** 9)
    back = float(np.linalg.norm(traj.y[-1] - y0))
    values = max(abs(I["H"] + 0.5), abs(I["L"] - math.sqrt(1 - e * e)))
    return {"values": values, "back": back, "measured": max(values, back)}


def henon_heiles_saddles() -> dict:
    """[HLW] after (3.2): the saddles of U = (q1² + q2²)/2 + q1² q2 − q2³/3 are (0, 1) and
    (±√3/2, −1/2), all with U = 1/6 and an indefinite Hessian: an equilateral triangle of side √3."""
    def U(x, y):
        return (x * x + y * y) / 2 + x * x * y - y**3 / 3

    def grad(x, y):
        return np.array([x + 2 * x * y, y + x * x - y * y])

    def hess(x, y):
        return np.array([[1 + 2 * y, 2 * x], [2 * x, 1 - 2 * y]])

    pts = [(0.0, 1.0), (math.sqrt(3) / 2, -0.5), (-math.sqrt(3) / 2, -0.5)]
    level = max(abs(U(*p) - 1 / 6) for p in pts)
    critical = max(float(np.max(np.abs(grad(*p)))) for p in pts)
    saddle = float(all(np.linalg.det(hess(*p)) < 0 for p in pts))
    sides = [math.dist(a, b) for a, b in ((pts[0], pts[1]), (pts[1], pts[2]), (pts[0], pts[2]))]
    triangle = max(abs(s - math.sqrt(3)) for s in sides)
    return {"level": level, "critical": critical, "saddle": saddle, "triangle": triangle,
            "measured": max(level, critical, triangle)}


CHECKS = {f.__name__: f for f in (
    lv_invariant, imr_symmetric, implicit_euler_damping, pendulum_area, pendulum_one_step_area,
    stormer_verlet_forms, kepler_conic, kepler_angular_momentum, kepler_eccentricity_relation,
    kepler_initial_values, henon_heiles_saddles)}
