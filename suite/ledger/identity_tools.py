"""Helpers shared by the identity checks (:mod:`.identities_b`, :mod:`.identities_hlw`)."""
from __future__ import annotations

import numpy as np


def problem(spec: str):
    from gnibench.suite.cell.spec import parse_problem

    return parse_problem(spec)


def functions(bound):
    """(plain-Python generated functions, par, integral names) of a parsed problem."""
    from gnibench.problems.codegen import problem_meta, python_functions

    rec = bound.record
    return python_functions(rec), rec.par(bound.values), problem_meta(rec)["integrals"]


def random_states(bound, count: int = 20, spread: float = 0.3, seed: int = 1994) -> np.ndarray:
    """Points around the problem's initial point (a fixed seed: the checks are reproducible)."""
    y0 = np.array(bound.record.y0(bound.values), dtype=float)
    rng = np.random.default_rng(seed)
    return y0 + spread * (1 + np.abs(y0)) * rng.standard_normal((count, len(y0)))


def conservation_residual(spec: str, names=None, count: int = 20) -> float:
    """max over random states of |∇I·F| / (|∇I| |F|): zero for a first integral ([B] §2)."""
    bound = problem(spec)
    fns, par, integrals = functions(bound)
    worst = 0.0
    for y in random_states(bound, count):
        F = np.array(fns["base_f"](tuple(y), par))
        for k, name in enumerate(integrals):
            if names is not None and name not in names:
                continue
            g = np.array(fns[f"grad_{k}"](tuple(y), par))
            scale = np.linalg.norm(g) * np.linalg.norm(F)
            if scale > 0:
                worst = max(worst, abs(g @ F) / scale)
    return float(worst)


def jacobian(fns, y, par) -> np.ndarray:
    n = len(y)
    J = np.zeros((n, n))
    fns["base_jac"](tuple(y), par, J)
    return J
