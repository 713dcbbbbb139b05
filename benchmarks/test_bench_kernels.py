"""pytest-benchmark timings of the compiled integrate call (kepler-2d, e=0.6, h = 2 pi/1000).

Run with ``pytest benchmarks --benchmark-only`` (the test command runs it once, untimed:
benchmarks/conftest.py).
The cell is loaded and warmed up (compiled, or read from the numba disk cache) before timing;
each round integrates STEPS steps sampled only at the end. ``extra_info['ns_per_step']`` is the
fastest round's wall time per step, as in ``gnibench bench``.
"""
from __future__ import annotations

import pytest
from gnibench.suite.runs.bench import H, compiled_cell, run_steps

STEPS = 200_000


@pytest.mark.parametrize("method", ["rk4", "stormer-verlet"])
def test_kepler_integrate(benchmark, timed, method):
    bound, cfg = compiled_cell(method)
    benchmark.group = "kepler-2d"
    benchmark.extra_info.update(method=method, steps=STEPS, h=H)
    _, y = benchmark.pedantic(run_steps, args=(bound, cfg, STEPS), rounds=10, iterations=1,
                              warmup_rounds=1)
    assert y.shape == (4,)
    if timed:
        benchmark.extra_info["ns_per_step"] = benchmark.stats.stats.min * 1e9 / STEPS
