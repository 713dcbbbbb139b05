"""Time reversibility of the symmetric methods: Φ_{-h} ∘ Φ_h = id ([HLW] II.3, Definition 3.1:
a method is symmetric if Φ_h^* = Φ_h, i.e. Φ_{-h} = Φ_h^{-1}).

Test: integrate N = 1000 steps of h from y0, then N steps of -h from the final point, and require
the return to y0 to round-off. Negative steps are not allowed by the method specs (h > 0 is
validated); the driver facade integrates backward with ``reverse=True`` (steps of -h), from the
point reached given as the problem's initial values (``<state>0`` options, exact by repr).
(Reversing the momenta, p -> -p, would test ρ-reversibility instead, which needs a
ρ-reversible problem *and* a symmetric method; stepping with -h tests the symmetry of the method
alone, on every problem it accepts, Hamiltonian or not.)

Problems: per symmetric method, the two smallest eligible problems (support.cap) plus kepler-2d
(e = 0.6, the worst conditioned of the default set), all eligible ones with GNIBENCH_TEST_FULL=1 —
except the chaotic geodesic flow (Anosov) and the modified Gavrilov-Shil'nikov orbit (started
1e-10 from a saddle, on its homoclinic loop): there the backward flow amplifies round-off like
e^{λ t} and no fixed round-off bound holds for 1000 steps (measured 1e-9 - 1 relative). Step h = 0.05/ρ (ρ the spectral radius of
dF/dy at y0).

Bound. Each of the 2N steps commits a rounding error of a few ε |y| (ε = 2.2e-16; the implicit
kernels iterate Newton to a few ε as well). The exact map Φ_{-h}^N carries these perturbations
back to t = 0 with a gain bounded by the linear (not exponential) growth of perturbations of an
integrable or near-integrable orbit, O(1) over ~1.5 Kepler periods. Summed over 2N = 2000 steps
that is at most 2000 · (a few ε) · gain ≈ 1e-12 relative, mostly much less since the errors are
not aligned. We require |y_back - y0|_∞ <= 1e-12 · m · max(|y0|_∞, |y_N|_∞), m the number of
basic steps in one step (1; a composition's number of Störmer–Verlet sub-steps, 3/7/15 for
yoshida4/6/8: each sub-step rounds as a whole step does). Measured: <= 2.7e-13 per basic step
(Störmer–Verlet on kepler-2d; gauss4 1.8e-13, lie-poisson on euler-so4 1.3e-13, yoshida8
1.3e-12 / 15), typically 1e-15 - 2e-14.

Negative control: rk4 is not symmetric; Φ_{-h} ∘ Φ_h - id = O(h^5) per step, so it misses the
bound by orders of magnitude (measured 2e-9 - 7e-7 on the same problems).
"""
from __future__ import annotations

import numpy as np
import pytest
from gnibench import methods
from gnibench.problems import REGISTRY
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare
from support import cap, rate_scale, takes

COMPILED = getattr(methods, "COMPILED", methods.METHODS)   # external engines have their own tests

STEPS = 1000
RTOL = 1e-12
PER_METHOD = 2
ALWAYS = "kepler-2d"
# round-off grows exponentially along these orbits, forwards and backwards: an Anosov flow, and an
# orbit started 1e-10 from a hyperbolic equilibrium on its homoclinic loop
CHAOTIC = {"geodesic-genus2", "gavrilov-shilnikov-modified"}
MAX_DIM = 12                           # default sweep: skip the 36-dimensional N-body problems


def _eligible(mid: str, pid: str) -> bool:
    return pid not in CHAOTIC and takes(pid, mid)


def _problems(mid: str) -> list[str]:
    pids = [p for p in REGISTRY if REGISTRY[p].dim <= MAX_DIM and _eligible(mid, p)]
    chosen = cap(pids, PER_METHOD, REGISTRY)
    if ALWAYS in pids and ALWAYS not in chosen:
        chosen.append(ALWAYS)
    return chosen


def basic_steps(mid: str) -> int:
    """Sub-steps rounded per step: a composition's stages, else 1."""
    m = COMPILED[mid]
    return len(m.data) if m.family == "composition" else 1


def forth_and_back(pid: str, mid: str, steps: int = STEPS) -> tuple[float, float]:
    """(|y_back - y0|_∞ / scale, |y_N - y0|_∞ / scale), scale = max(|y0|_∞, |y_N|_∞)."""
    h = 0.05 / rate_scale(pid)
    problem, cfg = prepare(pid, f"{mid}:h={h!r}")

    def run(bound, reverse):
        traj = solve(bound, cfg, steps=steps, every=steps, reverse=reverse, reference="none")
        assert traj.status == "ok" and traj.steps[-1] == steps, (pid, mid, reverse, traj.status)
        return traj.y[-1].copy()

    y0 = np.array(problem.record.y0(problem.values), dtype=np.float64)
    yn = run(problem, False)
    start = ",".join(f"{s}0={float(v)!r}" for s, v in zip(problem.record.state, yn))
    back = run(prepare(f"{pid}:{start}", f"{mid}:h={h!r}")[0], True)
    scale = max(np.max(np.abs(y0)), np.max(np.abs(yn)))
    return float(np.max(np.abs(back - y0)) / scale), float(np.max(np.abs(yn - y0)) / scale)


CASES = [(mid, pid) for mid, m in COMPILED.items() if m.symmetric for pid in _problems(mid)]


def test_every_symmetric_method_is_covered():
    symmetric = {mid for mid, m in COMPILED.items() if m.symmetric}
    assert symmetric <= {mid for mid, _ in CASES}
    assert {"implicit-midpoint", "gauss4", "stormer-verlet"} <= symmetric


@pytest.mark.parametrize("mid,pid", CASES)
def test_symmetric_method_is_reversible(mid, pid):
    err, moved = forth_and_back(pid, mid)
    assert moved > 1e-3, f"{pid}: the orbit barely moved ({moved:.1e}); the test would be empty"
    tol = RTOL * basic_steps(mid)
    assert err <= tol, f"{mid} on {pid}: back to y0 within {err:.2e} (relative) > {tol:g}"


@pytest.mark.parametrize("pid", ["kepler-2d", "pendulum"])
def test_rk4_is_not_reversible(pid):
    assert not COMPILED["rk4"].symmetric
    err, _ = forth_and_back(pid, "rk4")
    assert err > 100 * RTOL, f"rk4 on {pid} came back within {err:.2e}: the test cannot tell"
