"""pytest-benchmark timing of one warm runner cell: ``run_cell`` (solve, metrics, rows) of a quick
cell whose kernel is already loaded, i.e. what the runner adds around an integration.

Run with ``pytest benchmarks --benchmark-only``.
"""
from __future__ import annotations

from gnibench.suite.runs.cellwork import run_cell
from gnibench.suite.runs.experiment import parse_experiment

TEXT = """
name = "bench-cell"
title = "one warm cell"
reference = "[HLW] I.2"
t_end = 62.83185307179586
every = 10
metrics = ["growth:of=H"]
[[cells]]
problems = ["kepler-2d"]
methods = ["stormer-verlet:h=0.01"]
"""


def test_warm_runner_cell(benchmark):
    cell = parse_experiment(TEXT, "bench-cell.toml").cells[0]
    run_cell(cell)                                                       # warm-up: load the kernel
    benchmark.group = "runner"
    outcome = benchmark.pedantic(run_cell, args=(cell,), rounds=10, iterations=1, warmup_rounds=1)
    assert outcome.status == "ok"
    benchmark.extra_info.update(cell=cell.method, samples=len(outcome.samples))
