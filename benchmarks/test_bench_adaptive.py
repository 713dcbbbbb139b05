"""pytest-benchmark timings of the adaptive embedded pairs (kepler-2d, e = 0.6, rtol = atol = 1e-10,
100 periods, Hairer's HINIT start), as ``gnibench bench`` times them (suite/runs/bench.py,
``bench_adaptive``).

Run with ``pytest benchmarks --benchmark-only``. The cell is loaded and warmed up before timing;
each round is one whole integration sampled only at the end. ``extra_info['us_per_step']`` is the
fastest round's wall time per attempted (accepted + rejected) step.
"""
from __future__ import annotations

import math

import pytest
from gnibench.suite.runs.bench import ADAPTIVE_PERIODS, ADAPTIVE_TOL, adaptive_cell, run_adaptive


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_kepler_adaptive(benchmark, timed, method):
    bound, cfg, _ = adaptive_cell(method)
    t_end = ADAPTIVE_PERIODS * 2 * math.pi
    benchmark.group = "kepler-2d adaptive rtol=atol=1e-10, 100 periods"
    _, nacc, nrej, _, y = benchmark.pedantic(run_adaptive,
                                             args=(bound, cfg, t_end),
                                             rounds=20, iterations=1, warmup_rounds=1)
    assert y.shape == (4,)
    assert nacc > 0 and nrej >= 0
    if timed:
        benchmark.extra_info.update(method=method, tol=ADAPTIVE_TOL, periods=ADAPTIVE_PERIODS,
                                    accepted=nacc, rejected=nrej,
                                    us_per_step=benchmark.stats.stats.min * 1e6 / (nacc + nrej))
