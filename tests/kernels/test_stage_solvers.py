"""The stage equations of the implicit Runge-Kutta methods are solved to round-off, by Newton's
method (the default) and by fixed-point iteration (``fixed_point=N``): both stop on the rule of
``methods/assembly/templates/newton.py`` (an increment at a few ε of the state's size).

* Linear test: for y' = L y the s-stage Gauss method is y_{n+1} = R(hL) y_n with R the (s, s) Padé
  approximant of exp (Hairer-Wanner, *Solving ODEs II*, Thm IV.3.10 and IV.5.2): (1 + z/2)/(1 - z/2)
  for the implicit midpoint rule ([HLW] (1.7), the one-stage Gauss method) and
  (1 + z/2 + z²/12)/(1 - z/2 + z²/12) for gauss4. The harmonic oscillator q' = p, p' = -q has
  L² = -I, so R(hL) = D⁻¹N with N, D = (1 ∓ h²/12) I ± (h/2) L: a closed form to compare with.
  With h = 0.5 the fixed-point iteration contracts by about h ρ(A) ≈ 0.3 per sweep: a solver
  stopping at a loose tolerance (1e-6) leaves ~1e-7 per step, far above the 1e-14 bound here.
* Nonlinear test: Kepler (e = 0.6), gauss4, Newton against converged fixed-point iteration:
  the same map to round-off (the mutant ``newton-tolerance-loosened`` of suite/mutants/catalog.toml
  leaves the quadratically convergent Newton almost exact, but not the linearly convergent
  fixed-point iteration).
"""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve

H, STEPS = 0.5, 20
EPS = np.finfo(float).eps


def pade_map(method: str, h: float) -> np.ndarray:
    L = np.array([[0.0, 1.0], [-1.0, 0.0]])
    c = 1.0 - h * h / 12 if method == "gauss4" else 1.0
    N = c * np.eye(2) + h / 2 * L
    D = c * np.eye(2) - h / 2 * L
    return np.linalg.solve(D, N)


@pytest.mark.parametrize("solver", ["", ",fixed_point=200"])
@pytest.mark.parametrize("method", ["implicit-midpoint", "gauss4"])
def test_linear_steps_are_the_pade_map(method, solver):
    traj = solve("harmonic-oscillator", f"{method}:h={H}{solver}", steps=STEPS, every=1)
    R = pade_map(method, H)
    y = traj.y[0].copy()
    worst = 0.0
    for n in range(1, STEPS + 1):
        y = R @ y
        worst = max(worst, float(np.max(np.abs(traj.y[n] - y))))
    scale = float(np.max(np.abs(traj.y)))
    assert worst <= 64 * EPS * scale, f"{method}{solver}: {worst:.3e}"
    if solver:
        assert traj.njev[-1] == 0                  # every step converged


def test_newton_and_fixed_point_agree_on_kepler():
    newton = solve("kepler-2d", "gauss4:h=0.02", steps=400, every=400)
    fixed = solve("kepler-2d", "gauss4:h=0.02,fixed_point=500", steps=400, every=400)
    assert fixed.njev[-1] == 0
    diff = float(np.max(np.abs(newton.y - fixed.y)))
    assert diff <= 1e-12 * float(np.max(np.abs(newton.y))), f"{diff:.3e}"


def test_the_iteration_count_is_read_at_run_time():
    """``fixed_point=N`` is a runtime option (Method.runtime, passed in par): a sweep over N is one
    kernel, and each cell still runs its own N (nfev = stages x sweeps while not converged)."""
    from gnibench.suite.cell.compiled import kernel_key
    from gnibench.suite.cell.spec import prepare

    keys = {n: kernel_key(*prepare("harmonic-oscillator", f"implicit-euler:h=0.5{n}"))
            for n in (",fixed_point=2", ",fixed_point=3", "")}
    assert keys[",fixed_point=2"] == keys[",fixed_point=3"] != keys[""]
    for n in (2, 3):
        traj = solve("harmonic-oscillator", f"implicit-euler:h=0.5,fixed_point={n}", steps=5,
                     every=5)
        assert traj.nfev[-1] == 5 * n and traj.njev[-1] == 5     # never converged in n sweeps
