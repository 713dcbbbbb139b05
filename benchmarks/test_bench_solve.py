"""pytest-benchmark timings of ``gnibench.solve`` on warm cells of about 0.1-0.2 ms of
integration (issue 42, item 5: at most 1 ms plus 1.5 times the kernel), on shipped problems and
on a user problem defined in TOML.

Run with ``pytest benchmarks/test_bench_solve.py --benchmark-only``. Each round is one call of
``gnibench.solve`` (parsing and checking the specs, integrating, the reference solution, the
metrics, the table as a DataFrame, the metadata); ``extra_info`` has the kernel's own wall time
(the fastest round's ``meta['wall_seconds']``), the overhead beyond 1.5 times it, and the target.
"""
from __future__ import annotations

from pathlib import Path

import pytest

DEFINITIONS = Path(__file__).resolve().parents[1] / "examples" / "definitions.toml"

#: (problem, method, t_end, every): cells of about 0.2 ms of integration, sampled as usual
CASES = [
    ("kepler-2d", "dop853:rtol=1e-10,atol=1e-10", 120.0, 1),     # exact solution: Kepler's eq.
    ("pendulum", "rk4:h=0.005", 20.0, 10),                        # exact: Jacobi functions
    ("oscillator:omega=3", "dop853:rtol=1e-10,atol=1e-10", 200.0, 1),  # a user problem (TOML)
]


@pytest.fixture
def defined():
    """The user problem of examples/definitions.toml, loaded for the test and unloaded after it
    (the registries as they were for the other tests of the process)."""
    import gnibench
    from gnibench.suite.cell.user import loader

    before = set(loader.loaded())
    gnibench.load(DEFINITIONS)
    yield
    for name in set(loader.loaded()) - before:
        loader.unload(name)


@pytest.mark.parametrize("problem,method,t_end,every", CASES, ids=[c[0] for c in CASES])
def test_solve_overhead(benchmark, timed, defined, problem, method, t_end, every):
    import gnibench

    gnibench.solve(problem, method, t_end=t_end, every=every)       # warm: the kernels loaded
    kernel = []

    def call():
        traj = gnibench.solve(problem, method, t_end=t_end, every=every)
        kernel.append(traj.meta["wall_seconds"])
        return traj

    benchmark.group = "gnibench.solve on a warm cell"
    traj = benchmark.pedantic(call, rounds=50, iterations=1, warmup_rounds=2)
    assert traj.status == "ok"
    if not timed:                        # run once by the test command: nothing timed
        return
    fastest, k = benchmark.stats.stats.min, min(kernel)
    benchmark.extra_info.update(problem=problem, method=method, rows=len(traj.samples),
                                kernel_ms=k * 1e3, overhead_ms=(fastest - 1.5 * k) * 1e3,
                                target="solve <= 1 ms + 1.5 x kernel")
