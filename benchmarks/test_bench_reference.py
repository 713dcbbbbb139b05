"""pytest-benchmark timings of a real128 heyoka reference: kepler-2d (e = 0.6), 10 periods, 101 samples.

Run with ``pytest benchmarks --benchmark-only``. *cold*: the reference file is deleted before each
round (in the untimed setup), so every round integrates (about 440 Taylor steps of order 40 in
real128) and writes the file. heyoka's in-process JIT cache is warm after the warm-up round, so
JIT compilation is not timed. *warm*: the file exists, and a round is a key computation plus the
file read.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.reference import cache_path, parse_reference, reference_solution
from gnibench.suite.cell.spec import parse_problem

T_GRID = np.linspace(0.0, 10 * 2 * math.pi, 101)
SPEC = "heyoka:precision=real128"


@pytest.fixture
def cell(tmp_path, monkeypatch):
    monkeypatch.setenv("GNIBENCH_CACHE_DIR", str(tmp_path))
    problem = parse_problem("kepler-2d")
    spec = parse_reference(SPEC, problem.record)
    return problem, spec, cache_path(problem, T_GRID, spec)


def test_reference_real128_cold(benchmark, cell):
    problem, spec, path = cell

    def setup():
        path.unlink(missing_ok=True)
        return (problem, T_GRID, spec), {}

    benchmark.group = "reference kepler-2d real128 10 periods"
    sol = benchmark.pedantic(reference_solution, setup=setup, rounds=5, warmup_rounds=1)
    assert not sol.cached and path.exists()
    benchmark.extra_info.update(steps=sol.info["steps"], samples=len(T_GRID))


def test_reference_real128_warm(benchmark, cell):
    problem, spec, _ = cell
    reference_solution(problem, T_GRID, spec)
    benchmark.group = "reference kepler-2d real128 10 periods"
    sol = benchmark.pedantic(reference_solution, args=(problem, T_GRID, spec), rounds=20,
                             warmup_rounds=1)
    assert sol.cached
