"""pytest-benchmark timings of Poincaré sections against plain integration of the same horizon.

The case of [B] §7: euler-so4 (its default chaotic orbit), rkf45 at rtol = atol = 5e-8 with the
observer theta = 10 on H1, H2, H3, crossings of x2 = 0 with x2' < 0 located by Hénon's trick
inside the compiled driver (suite/cell/sections.py). Before the crossings were found and located
in the compiled driver (each crossing returned to Python), t_end = 4000 took 11-26 s for 3646
crossings against 0.09-0.12 s of plain integration; [B] §7's horizon t = 4e5 about 45 min.

Measured (2 shared cores, load ~1.5, minimum of 5 rounds): plain 95.6 ms, section 157.3 ms
(1.64x) for 3649 crossings; to t = 4e5: 15.7 s (plain 9.9 s) for 379361 crossings.

Targets (here, never in the unit tests): the section run at most twice the plain integration at
t_end = 4000, and the run to t = 4e5 under a minute. Run with
``pytest benchmarks/test_bench_sections.py --benchmark-only``; each round is one whole
integration, the cell loaded and warmed up before timing (budget=None: one driver call).
"""
from __future__ import annotations

import time

import numpy as np
import pytest
from gnibench.suite.cell.calls import UNLIMITED
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare

PROBLEM = "euler-so4"
METHOD = "rkf45:rtol=5e-8,atol=5e-8,max_steps=1000000000+observer:theta=10"
T_END = 4000.0
T_LONG = 4.0e5                # [B] §7, Fig 26
ALL = 10**6                   # crossings asked for: every one up to t_end (379361 to T_LONG),
                              # within the row budget (GNIBENCH_MAX_ROWS); 10**9 was refused by it


def _plain(p, m, t_end):
    return solve(p, m, t_end=t_end, every=UNLIMITED, budget=None, reference="none")


def _section(p, m, t_end):
    return solve(p, m, t_end=t_end, section=ALL, budget=None)


def _best(fn, rounds=3):
    best = float("inf")
    for _ in range(rounds):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


@pytest.fixture(scope="module")
def cell():
    p, m = prepare(PROBLEM, METHOD)
    _plain(p, m, 1.0)
    _section(p, m, 1.0)          # loads (or compiles) both drivers
    return p, m


def test_so4_plain(benchmark, cell):
    p, m = cell
    benchmark.group = "euler-so4 rkf45 5e-8 + observer, t_end = 4000"
    traj = benchmark.pedantic(_plain, args=(p, m, T_END), rounds=5, iterations=1)
    benchmark.extra_info.update(steps=int(traj.steps[-1]), nfev=float(traj.nfev[-1]))


def test_so4_section(benchmark, timed, cell):
    p, m = cell
    benchmark.group = "euler-so4 rkf45 5e-8 + observer, t_end = 4000"
    traj = benchmark.pedantic(_section, args=(p, m, T_END), rounds=5, iterations=1)
    assert len(traj.t) == 3649 and traj.provenance["locator"] == "henon"
    if not timed:
        return
    plain = _best(lambda: _plain(p, m, T_END))
    ratio = benchmark.stats.stats.min / plain
    benchmark.extra_info.update(crossings=len(traj.t), steps=int(traj.steps[-1]),
                                locator_nfev=traj.provenance["henon"]["nfev"],
                                max_substeps=traj.provenance["henon"]["max_substeps"],
                                plain_seconds=plain, ratio_to_plain=ratio)
    assert ratio <= 2.0


def test_so4_section_b7_horizon(benchmark, timed, cell):
    """[B] §7's horizon: every crossing up to t = 4e5 (chart Γ1 holds most of them, Fig 26); run
    once to t = 4000 when untimed (the test command)."""
    p, m = cell
    benchmark.group = "euler-so4 rkf45 5e-8 + observer, t_end = 4e5"
    t_end = T_LONG if timed else T_END
    traj = benchmark.pedantic(_section, args=(p, m, t_end), rounds=1, iterations=1)
    charts = np.bincount(traj.chart, minlength=9)
    benchmark.extra_info.update(crossings=len(traj.t), charts=charts[1:].tolist(),
                                steps=int(traj.steps[-1]), wall=traj.wall_seconds,
                                locator_nfev=traj.provenance["henon"]["nfev"])
    assert traj.status == "ok" and charts.sum() == len(traj.t) < ALL    # all to t_end
    if timed:
        # measured: 379361 crossings, 145012 in Γ1 (Fig 26 of [B]: 140858), the most of any chart
        # (to t = 4000 chart Γ6 holds the most)
        assert int(np.argmax(charts)) == 1
        assert benchmark.stats.stats.min < 60.0
