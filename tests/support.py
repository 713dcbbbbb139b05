"""Small helpers shared by the test files (imported as ``support``; tests/ is on sys.path).

Registry-wide sweeps compile one kernel per (problem, method, modifier) cell, ~1-3 s each (tens of
seconds for the 36-dimensional outer solar system). By default a sweep therefore takes, per
method, the first few eligible problems in order of dimension; set ``GNIBENCH_TEST_FULL=1`` to run
every eligible combination.
"""
from __future__ import annotations

import functools
import os

import numpy as np

FULL = os.environ.get("GNIBENCH_TEST_FULL", "") not in ("", "0")


def cap(pids, n: int, registry) -> list[str]:
    """The first n problem ids by (dimension, registry order), or all of them with FULL."""
    order = list(registry)
    ranked = sorted(pids, key=lambda pid: (registry[pid].dim, order.index(pid)))
    return ranked if FULL else ranked[:n]


@functools.cache
def base_module(spec: str):
    """(module, problem Bound, par) of a problem's generated code (its own compiled module)."""
    from gnibench.suite.cell.codegen import load_problem
    from gnibench.suite.cell.spec import parse_problem

    prob = parse_problem(spec)
    mod, _ = load_problem(prob)
    return mod, prob, np.array(prob.record.par(prob.values), dtype=np.float64)


def rate_scale(spec: str) -> float:
    """Spectral radius of dF/dy at the initial point: the fastest local rate of the problem."""
    mod, prob, par = base_module(spec)
    n = prob.record.dim
    J = np.empty((n, n))
    mod.base_jac(tuple(prob.record.y0(prob.values)), par, J)
    return float(np.max(np.abs(np.linalg.eigvals(J))))


def integrals_at_start(spec: str) -> tuple[float, ...]:
    """H_k(y0) for every integral of the problem."""
    mod, prob, par = base_module(spec)
    return tuple(float(x) for x in mod.invariants(tuple(prob.record.y0(prob.values)), par))


def gradient_at_start(spec: str, k: int) -> np.ndarray:
    mod, prob, par = base_module(spec)
    return np.array(getattr(mod, f"grad_{k}")(tuple(prob.record.y0(prob.values)), par))


def gradients(spec: str, k: int, ys) -> np.ndarray:
    """∇H_k at each row of ys."""
    mod, _, par = base_module(spec)
    grad = getattr(mod, f"grad_{k}")
    return np.array([grad(tuple(y), par) for y in ys])
