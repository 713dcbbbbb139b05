"""Every problem's vector field agrees with its integrals: along a heyoka Taylor trajectory (tol at
round-off), every first integral stays constant to <= 1e-12 relative (issue: reference machinery)."""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.methods.engines.heyoka import heyoka_propagate
from gnibench.problems import REGISTRY
from gnibench.problems.codegen import python_functions
from gnibench.suite.cell.spec import parse_problem

HORIZON = {"outer-solar-system": 2000.0, "geodesic-genus2": 0.3}   # geodesic: before leaving Ω


@pytest.mark.parametrize("pid", sorted(REGISTRY))
def test_integrals_constant_along_heyoka_trajectory(pid):
    problem = parse_problem(pid)
    t = np.linspace(0.0, HORIZON.get(pid, 10.0), 41)
    run = heyoka_propagate(problem, t, precision="double")
    fns = python_functions(problem.record)
    par = problem.record.par(problem.values)
    values = np.array([fns["invariants"](tuple(row), par) for row in run.y])
    # scale: the integral's size, or for an integral that is 0 on the orbit the size of its terms
    scale = np.maximum(np.abs(values[0]), 1.0)
    drift = np.abs(values - values[0]).max(axis=0) / scale
    assert drift.max() <= 1e-12, dict(zip(fns["invariants"].__code__.co_names, drift))
