"""Exact conservation of quadratic first integrals, [HLW] §I.2, Table 2.1 and the text after it.

[HLW] I.2.3: "the angular momentum L(p, q) is exactly conserved by the symplectic Euler, the
Störmer–Verlet, and the implicit midpoint rule" (Table 2.1, column "error in L": 0). The general
statement behind it (proved in [HLW] IV.2, beyond the seed chapter): symplectic Runge–Kutta methods
conserve every quadratic first integral, and symplectic partitioned methods conserve every integral
of the bilinear form u^T C v (plus linear terms) in their blocks (u, v) — L = q1 p2 - q2 p1 is one.

Which integrals are quadratic or bilinear is decided symbolically from each problem's sympy model,
so new problems and methods are picked up from the registries (by default, per method, the three
smallest eligible problems for quadratic, the smallest for bilinear integrals, of dimension <= 8
and with integrals not 0 at y0; all eligible problems with GNIBENCH_TEST_FULL=1). "Exactly" means to round-off: over 10^4 steps
of h = 0.05/ρ (ρ the spectral radius of dF/dy at y0) the drift must stay below 1e-13 times
max_n Σ_k |c_k m_k(y_n)|, the size of the terms of I = Σ c_k m_k along the orbit (the scale of
its rounding error; measured drifts ~1e-14). Negative control: explicit Euler, which [HLW]
Table 2.1 lists with an O(t h) error in L, drifts far above that.
"""
from __future__ import annotations

import numpy as np
import pytest
from gnibench import methods
from gnibench.problems import REGISTRY
from gnibench.problems.codegen import symbolic
from gnibench.suite.metrics.invariants import invariant_errors
from support import FULL, rate_scale, takes

COMPILED = getattr(methods, "COMPILED", methods.METHODS)   # external engines have their own tests

STEPS = 10_000
RTOL = 1e-13
PER_METHOD = {"quadratic": 3, "bilinear": 1}    # problems per method by default
MAX_DIM = 8                                     # default sweep: skip the large N-body problems


def _kinds(problem) -> dict[str, tuple[set[str], object, int, float]]:
    """Integral name -> (kinds, Σ|terms| as a numpy function of the state, degree, value at y0)."""
    import sympy as sp

    ys, ps, _, integrals = symbolic(problem)
    pvals = dict(zip(ps, problem.par({p.name: p.default for p in problem.params})))
    out = {}
    for name, expr in integrals.items():
        expr = sp.expand(expr.subs(pvals))
        try:
            poly = sp.Poly(expr, *ys)
        except sp.PolynomialError:
            continue
        if poly.total_degree() > 2:
            continue
        kinds = {"quadratic"}
        if problem.partition is not None:
            u, v = ([ys[problem.state.index(s)] for s in block] for block in problem.partition)
            if all(sp.diff(expr, a, b) == 0 for blk in (u, v) for a in blk for b in blk):
                kinds.add("bilinear")
        size = sp.lambdify([ys], sum(abs(t) for t in poly.as_expr().as_ordered_terms()), "numpy")
        y0 = problem.y0({p.name: p.default for p in problem.params})
        at_start = float(sp.lambdify([ys], poly.as_expr(), "math")(y0))
        out[name] = (kinds, size, poly.total_degree(), at_start)
    return out


_KINDS = {pid: _kinds(p) for pid, p in REGISTRY.items()}


def _names(pid, kind):
    return tuple(n for n, (k, _, _, _) in _KINDS[pid].items() if kind in k)


def _cells(kind, want_method):
    cells = []
    for mid, m in COMPILED.items():
        if not want_method(m):
            continue
        pids = [pid for pid in REGISTRY if _names(pid, kind) and _applies(pid, mid)]
        for pid in _rank(pids, kind):
            names = _names(pid, kind)
            cells.append(pytest.param(pid, mid, names, id=f"{mid}-{pid}-{'/'.join(names)}"))
    return cells


def _rank(pids, kind):
    """Default: problems whose integrals are nonzero at y0 first (an integral that starts at 0 on a
    symmetry set, like K on the Gavrilov-Shil'nikov loop, is a weak test), then by dimension."""
    def zero_at_start(pid):
        return any(_KINDS[pid][n][3] == 0 for n in _names(pid, kind))

    order = list(REGISTRY)
    if FULL:
        return pids
    small = [pid for pid in pids if REGISTRY[pid].dim <= MAX_DIM]
    ranked = sorted(small, key=lambda pid: (zero_at_start(pid), REGISTRY[pid].dim, order.index(pid)))
    return ranked[:PER_METHOD[kind]]


def _applies(pid, mid) -> bool:
    return takes(pid, mid)


def _symplectic_rk(m):
    # Runge-Kutta only: other symplectic one-step maps (generating-function4) need not conserve
    # quadratic integrals, e.g. the oscillator's H
    return m.symplectic and m.family == "implicit-rk"


def _symplectic_partitioned(m):
    return m.symplectic and "partition" in m.needs


def relative_drift(pid, mid, names, steps=STEPS):
    """max_n |I(y_n) - I(y_0)| / max_n Σ|terms of I(y_n)| for each integral."""
    from gnibench.suite.cell.solve import solve

    h = 0.05 / rate_scale(pid)
    r = solve(pid, f"{mid}:h={h!r}", steps=steps, every=steps // 100)
    assert r.status == "ok", r.reason
    out = {}
    for name in names:
        k = r.integral_names.index(name)
        size = _KINDS[pid][name][1]
        scale = max(float(np.max(np.abs(size(y)))) for y in r.y)
        out[name] = float(np.max(np.abs(invariant_errors(r)[:, k]))) / scale
    return out


def test_symbolic_classification():
    """kepler-2d's L = q1 p2 - q2 p1 ([HLW] (2.4)) is bilinear in (p, q); H (2.3) is not quadratic."""
    assert "bilinear" in _KINDS["kepler-2d"]["L"][0]
    assert "H" not in _KINDS["kepler-2d"]
    assert _KINDS["harmonic-oscillator"]["H"][0] == {"quadratic"}
    size = _KINDS["kepler-2d"]["L"][1]
    assert size([1.0, -2.0, 3.0, 4.0]) == pytest.approx(3 * 2 + 4 * 1)   # |q1 p2| + |q2 p1|


@pytest.mark.parametrize("pid,mid,names", _cells("quadratic", _symplectic_rk))
def test_symplectic_rk_conserves_quadratic_integrals(pid, mid, names):
    """Implicit midpoint ([HLW] (1.7)) conserves L ([HLW] Table 2.1) and every quadratic integral."""
    drift = relative_drift(pid, mid, names)
    assert all(d <= RTOL for d in drift.values()), drift


@pytest.mark.parametrize("pid,mid,names", _cells("bilinear", _symplectic_partitioned))
def test_symplectic_partitioned_conserves_bilinear_integrals(pid, mid, names):
    """Symplectic Euler (1.9), its adjoint and Störmer–Verlet (1.17) conserve L, [HLW] Table 2.1."""
    drift = relative_drift(pid, mid, names)
    assert all(d <= RTOL for d in drift.values()), drift


def _control_cells():
    """The three smallest problems of the positive tests with a degree-2 integral not 0 at y0.

    Linear integrals are conserved by every RK method, and a start on a symmetry set can make
    Euler conserve an integral too (the Gavrilov-Shil'nikov loop has K = 0 and stays radial), so
    the control uses the plainest problems.
    """
    used = {p.values[0] for p in _cells("quadratic", _symplectic_rk)
            + _cells("bilinear", _symplectic_partitioned)}

    def names(pid):
        return tuple(n for n, (_, _, deg, v0) in _KINDS[pid].items() if deg == 2 and v0 != 0)

    pids = [pid for pid in used if names(pid)]
    order = list(REGISTRY)
    pids = sorted(pids, key=lambda pid: (REGISTRY[pid].dim, order.index(pid)))[:3]
    return [pytest.param(pid, names(pid), id=f"{pid}-{'/'.join(names(pid))}") for pid in pids]


@pytest.mark.parametrize("pid,names", _control_cells())
def test_explicit_euler_does_not_conserve_them(pid, names):
    """Negative control: explicit Euler ([HLW] (1.5)) has an O(t h) error in L, [HLW] Table 2.1.

    10^3 steps only, so that Euler's growth stays far from overflow.
    """
    drift = relative_drift(pid, "euler", names, steps=STEPS // 10)
    assert all(d > 1e4 * RTOL for d in drift.values()), drift
