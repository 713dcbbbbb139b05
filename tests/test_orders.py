"""Observed order of convergence of every fixed-step method (GeometricIntegrators.jl style).

The global error at a fixed final time T is measured against the problem's exact solution for
h = T/(n0 2^k), k = 0..10; the order is the least-squares slope of log(error) against log(h).
Points below a 1e-13 round-off plateau, points after the error stops decreasing, and failed runs
are dropped. Of the longest remaining run of decreasing errors, end points whose local rate
log(e_k/e_{k+1})/log 2 differs from the run's median rate by more than 20% are trimmed (the
pre-asymptotic coarse end; the fine end where rounding, which grows with the number of steps, slows
the decrease, e.g. an 8th-order method near 1e-13 on Kepler), and the finest (at most) five points
are fitted. The trimming uses only the data, never the declared order. At least three points must
remain and the slope must agree with the method's declared classical order to ±0.35
([HLW] (1.5)-(1.7), (1.9), (1.17); global error O(t h^p), [HLW] Table 2.1).

T is deliberately not a multiple of the period: at a full Kepler period the O(h) error terms of
symplectic Euler cancel by symmetry and it shows a spurious order 2.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from gnibench import methods
from gnibench.problems import REGISTRY
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.global_error import global_errors

# (problem spec, T, n0): nonlinear problems with exact solutions
ORDER_CASES = {
    "pendulum": ("pendulum:p0=0,q0=1.2", 6.0, 12),      # large libration, exact via Jacobi sn/cn
    "kepler-2d": ("kepler-2d", 3.0, 24),                # e = 0.6, exact via Kepler's equation
}
LEVELS = 11
FIT = 5
PLATEAU = 1e-13
TRIM = 0.2
TOL = 0.35

COMPILED = getattr(methods, "COMPILED", methods.METHODS)   # external engines have their own tests


def method_spec(mid: str, h: float) -> str:
    """Fixed-step spec: embedded pairs get adaptive=false."""
    names = {p.name for p in COMPILED[mid].params}
    return f"{mid}:" + ("adaptive=false," if "adaptive" in names else "") + f"h={h!r}"


def _fixed_step(method) -> bool:
    names = {p.name for p in method.params}
    return "h" in names


def _applies(mid, pid) -> bool:
    try:
        prepare(ORDER_CASES[pid][0], method_spec(mid, 0.1))
    except UserError:
        return False
    return REGISTRY[pid].exact is not None


CELLS = [pytest.param(mid, pid, id=f"{mid}-{pid}")
         for mid, m in COMPILED.items() if _fixed_step(m) for pid in ORDER_CASES if _applies(mid, pid)]


def _local_rates(hs, errs, idx):
    return [np.log(errs[a] / errs[b]) / np.log(hs[a] / hs[b]) for a, b in itertools.pairwise(idx)]


def observed_order(hs: np.ndarray, errs: np.ndarray) -> tuple[float, int]:
    """Least-squares log-log slope over the usable points (see module docstring), and their number."""
    best: list[int] = []
    run: list[int] = []
    for k, e in enumerate(errs):
        ok = np.isfinite(e) and e >= PLATEAU
        if ok and run and e < errs[run[-1]]:
            run.append(k)
        else:
            run = [k] if ok else []
        if len(run) > len(best):
            best = list(run)
    # trim end points whose local rate is off the run's median rate by more than TRIM (the coarse
    # pre-asymptotic end, the fine end approaching the round-off floor)
    while len(best) >= 4:
        rates = _local_rates(hs, errs, best)
        med = float(np.median(rates))
        ends = {0: abs(rates[0] - med), -1: abs(rates[-1] - med)}
        end = max(ends, key=ends.get)
        if ends[end] <= TRIM * abs(med):
            break
        best.pop(end)
    keep = best[-FIT:]
    if len(keep) < 2:
        return float("nan"), len(keep)
    slope = np.polyfit(np.log(hs[keep]), np.log(errs[keep]), 1)[0]
    return float(slope), len(keep)


def test_observed_order_helper_on_synthetic_data():
    """The slope helper recovers p from C h^p with garbage, a plateau and a stagnating tail."""
    hs = 0.5 / 2.0 ** np.arange(12)
    errs = np.maximum(3.0 * hs**4, 5e-14)
    errs[:2] = [np.inf, 10.0]                          # diverged / pre-asymptotic
    errs[-1] = 1e-12                                   # stops decreasing
    p, n = observed_order(hs, errs)
    assert n == FIT and abs(p - 4.0) < 1e-9
    p, n = observed_order(hs, 3.0 * hs**1)
    assert n == FIT and abs(p - 1.0) < 1e-9
    # the yoshida8-on-Kepler shape: order 8 with a pre-asymptotic head and a rounding-bent tail
    errs = np.array([1.8e-4, 1.1e-5, 5.9e-8, 2.46e-10, 9.9e-13, 1.17e-13, 2.7e-14])
    p, n = observed_order(0.125 / 2.0 ** np.arange(7), errs)
    assert n == 4 and abs(p - 7.8) < 0.1
    # a method of order 3 posing as order 4 is not rescued by the trimming
    p, _ = observed_order(hs, np.maximum(3.0 * hs**3, 5e-14))
    assert abs(p - 3.0) < 1e-9


@pytest.mark.parametrize("mid,pid", CELLS)
def test_observed_order_matches_declared(mid, pid):
    """Global error at T decreases like h^order ([HLW] Table 2.1: O(t h^p) global error)."""
    spec, T, n0 = ORDER_CASES[pid]
    hs, errs = [], []
    for k in range(LEVELS):
        n = n0 * 2**k
        r = solve(spec, method_spec(mid, T / n), steps=n, every=n)
        ok = r.status == "ok" and r.steps[-1] == n
        assert not ok or abs(r.t[-1] - T) < 1e-12 * T
        hs.append(T / n)
        errs.append(global_errors(r)[-1] if ok else np.inf)
    hs, errs = np.array(hs), np.array(errs)
    p, used = observed_order(hs, errs)
    order = COMPILED[mid].order
    detail = f"errors {errs.tolist()} for h {hs.tolist()}"
    assert used >= 3, f"only {used} usable points; {detail}"
    assert abs(p - order) <= TOL, f"observed order {p:.3f}, declared {order}; {detail}"
