"""Gauss collocation conserves every quadratic first integral ([HLW] IV.2.1, Theorem 2.2: Gauss
methods conserve quadratic invariants; the implicit midpoint rule is the one-stage Gauss method).

Cells: gauss4, gauss6 and implicit-midpoint on
  * euler-so4 ([B] (7.1)-(7.2)), whose three integrals are all quadratic:
    H1 = x1 x4 + x2 x5 + x3 x6, H2 = Σ x_i², H3 = Σ λ_i x_i², at the chaotic default orbit;
  * kepler-2d (e = 0.6), angular momentum L = q1 p2 - q2 p1 (H and the Runge-Lenz vector are not
    polynomial/quadratic, and are not checked).
10^4 steps of h = 0.2/ρ (ρ the spectral radius of dF/dy at y0; t = 282 for so(4), 358 = 57
Kepler periods), through the public ``solve``.

Bound. "To round-off": each step evaluates I with rounding error ~ε Σ_k |c_k m_k(y)| (the size of
its terms) and the Newton iteration stops at a few ε, so the drift after N steps is a random walk of
~sqrt(N) ε per term, at worst N ε = 2e-12 per unit term size if every rounding were aligned. We
require max_n |I(y_n) - I(y0)| <= 1e-13 · S, S = max_n Σ_k |c_k m_k(y_n)| (for H2, H3 that is the
integral itself; for H1 and L the sum of the absolute values of its products). Measured: <= 1.2e-14
(gauss4, L), typically 2e-15 - 1e-14.

Negative control: rk4 (not a Gauss method; no RK method conserves all quadratic invariants unless
it is symplectic, [HLW] IV.2.1) drifts by 6e-5 (L) - 4e-3 (H3) relative on the same cells.
"""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.problems import REGISTRY
from gnibench.suite.cell.solve import solve
from gnibench.suite.metrics.invariants import invariant_errors
from support import rate_scale

STEPS = 10_000
RTOL = 1e-13
FAC = 0.2


def _so4_sizes(y: np.ndarray, lam: np.ndarray) -> dict[str, np.ndarray]:
    x = y.T
    return {"H1": np.abs(x[0] * x[3]) + np.abs(x[1] * x[4]) + np.abs(x[2] * x[5]),
            "H2": np.sum(x ** 2, axis=0), "H3": np.sum(lam[:, None] * x ** 2, axis=0)}


def _kepler_sizes(y: np.ndarray) -> dict[str, np.ndarray]:
    p1, p2, q1, q2 = y.T            # kepler-2d state order (p1, p2, q1, q2)
    return {"L": np.abs(q1 * p2) + np.abs(q2 * p1)}


CASES = {
    "euler-so4": ("H1", "H2", "H3"),
    "kepler-2d": ("L",),
}


def drift(pid: str, mid: str) -> dict[str, float]:
    """max_n |I(y_n) - I(y0)| / max_n (size of I's terms), per checked integral."""
    h = FAC / rate_scale(pid)
    r = solve(pid, f"{mid}:h={h!r}", steps=STEPS, every=10)
    assert r.status == "ok", (pid, mid, r.status, r.reason)
    assert r.steps[-1] == STEPS
    if pid == "euler-so4":
        rec = REGISTRY[pid]
        assert rec.state == ("x1", "x2", "x3", "x4", "x5", "x6")
        defaults = {p.name: p.default for p in rec.params}
        lam = np.array([defaults[f"lam{i}"] for i in range(1, 7)], dtype=float)
        sizes = _so4_sizes(r.y, lam)
        # the term sizes of H3 must reproduce H3 itself (all λ > 0): checks λ was read right
        k = r.integral_names.index("H3")
        assert np.allclose(sizes["H3"][0], r.provenance["H0"][k], rtol=1e-14)
    else:
        assert tuple(r.state_names) == ("p1", "p2", "q1", "q2")
        sizes = _kepler_sizes(r.y)
    out = {}
    for name in CASES[pid]:
        k = r.integral_names.index(name)
        out[name] = float(np.max(np.abs(invariant_errors(r)[:, k])) / np.max(sizes[name]))
    return out


@pytest.mark.parametrize("pid", list(CASES))
@pytest.mark.parametrize("mid", ["gauss4", "gauss6", "implicit-midpoint"])
def test_gauss_keeps_quadratic_integrals(mid, pid):
    for name, d in drift(pid, mid).items():
        assert d <= RTOL, f"{mid} on {pid}: {name} drifted {d:.2e} (relative to its terms) > {RTOL:g}"


@pytest.mark.parametrize("pid", list(CASES))
def test_rk4_does_not(pid):
    d = drift(pid, "rk4")
    assert max(d.values()) > 1e4 * RTOL, f"rk4 on {pid} kept {d}: the test cannot tell"
