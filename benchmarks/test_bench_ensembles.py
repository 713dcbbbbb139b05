"""pytest-benchmark timings of an ensemble of Hénon–Heiles orbits (issue 42, item 6), saved like
every benchmark so that the documentation's performance page shows them: N orbits at H = 1/12
([HLW] I.3) to t = 100 by dop853 and vern9 at rtol = atol = 1e-10,

* as one ensemble cell (``gnibench.run``, one worker),
* as N separate cells (``gnibench.run``, two workers),
* by heyoka's ``ensemble_propagate_until`` on two threads, at the loosest Taylor tolerance whose
  final error is at most the ensemble's, orbit by orbit (the median of the ratio <= 1).

Run with ``pytest benchmarks/test_bench_ensembles.py --benchmark-only`` (``GNIBENCH_BENCH_ORBITS``
sets N, default 1000). ``extra_info`` holds the median final error of every contestant against
heyoka at the precision's epsilon, and heyoka's tolerance. ``benchmarks/bench_ensembles.py``
prints the same comparison as one table.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ensembles import (  # noqa: E402 - the script beside this file
    HEYOKA_TOLS,
    METHODS,
    cells_experiment,
    ensemble_experiment,
    final_states,
    heyoka_run,
    timed_run,
)

ORBITS = int(os.environ.get("GNIBENCH_BENCH_ORBITS", "1000"))
T_END = 100.0
GROUP = f"Hénon–Heiles ensemble: {ORBITS} orbits at H = 1/12 to t = 100, rtol = 1e-10"


@pytest.fixture(scope="module")
def orbits():
    """The initial conditions and the reference final states (heyoka at epsilon)."""
    from gnibench.suite.api.running import toml_text
    from gnibench.suite.cell.ensemble_reference import propagate
    from gnibench.suite.runs.ensembles import initial_states
    from gnibench.suite.runs.experiment import parse_experiment

    cell = parse_experiment(toml_text(ensemble_experiment(METHODS[0], ORBITS, T_END, 250)),
                            "bench").cells[0]
    y0 = initial_states(cell)
    return cell, y0, propagate(cell.spec.problem, y0, np.array([0.0, T_END]))[:, -1]


def _error(states, reference) -> float:
    return float(np.median(np.linalg.norm(states - reference, axis=1)))


@pytest.mark.parametrize("method", METHODS, ids=["dop853", "vern9"])
def test_ensemble_cell(benchmark, orbits, method):
    _, _, reference = orbits
    exp = ensemble_experiment(method, ORBITS, T_END, 250)
    timed_run(exp, 1)                                          # kernels compiled or loaded
    benchmark.group = GROUP
    _, _, res = benchmark.pedantic(timed_run, args=(exp, 1), rounds=3, iterations=1)
    benchmark.extra_info.update(contestant="ensemble cell, -j 1", method=method,
                                median_error=_error(final_states(res, True), reference))


@pytest.mark.parametrize("method", METHODS, ids=["dop853", "vern9"])
def test_separate_cells(benchmark, orbits, method):
    cell, _, reference = orbits
    exp = cells_experiment(method, cell.ensemble.points, T_END)
    timed_run(cells_experiment(method, cell.ensemble.points[:2], T_END), 2)
    benchmark.group = GROUP
    _, _, res = benchmark.pedantic(timed_run, args=(exp, 2), rounds=2, iterations=1)
    benchmark.extra_info.update(contestant="separate cells, -j 2", method=method,
                                median_error=_error(final_states(res, False), reference))


@pytest.mark.parametrize("method", METHODS, ids=["dop853", "vern9"])
def test_heyoka_ensemble(benchmark, orbits, method):
    cell, y0, reference = orbits
    _, _, ens = timed_run(ensemble_experiment(method, ORBITS, T_END, 250), 1)
    target = np.linalg.norm(final_states(ens, True) - reference, axis=1)
    for tol in HEYOKA_TOLS:
        _, _, states = heyoka_run(cell.spec.problem, y0, T_END, tol, 2, 1)
        if np.median(np.linalg.norm(states - reference, axis=1) / target) <= 1.0:
            break
    benchmark.group = GROUP
    _, _, states = benchmark.pedantic(heyoka_run, args=(cell.spec.problem, y0, T_END, tol, 2, 1),
                                      rounds=3, iterations=1)
    benchmark.extra_info.update(contestant="heyoka ensemble_propagate_until, 2 threads",
                                method=f"as accurate as {method}", tol=tol,
                                median_error=_error(states, reference))
