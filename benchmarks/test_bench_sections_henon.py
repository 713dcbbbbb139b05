"""pytest-benchmark timings of Poincaré sections against plain integration of the same horizon:
henon-heiles (H0 = 1/8), dop853 at rtol = atol = 1e-10 (crossings located on its continuous
extension), and RK4 at h = 0.01 (Hénon's trick).

Run with ``pytest benchmarks --benchmark-only``. The section cell is run first to learn the time of
its last crossing; the plain cell then integrates to that time, so both do the same steps and the
ratio is the cost of detecting and locating the crossings. Kernels are warmed up before timing.
"""
from __future__ import annotations

import pytest
from gnibench.suite.cell.solve import solve

CROSSINGS = 200
METHODS = ("dop853:rtol=1e-10,atol=1e-10", "rk4:h=0.01")


@pytest.mark.parametrize("method", METHODS)
def test_section(benchmark, method):
    solve("henon-heiles", method, t_end=1.0, section=1)                 # warm-up
    benchmark.group = f"henon-heiles sections vs plain, {CROSSINGS} crossings"
    traj = benchmark.pedantic(solve, args=("henon-heiles", method),
                              kwargs={"t_end": 1e6, "section": CROSSINGS}, rounds=5, iterations=1,
                              warmup_rounds=1)
    assert len(traj.t) == CROSSINGS
    benchmark.extra_info.update(method=method, t_last=float(traj.t[-1]), kind="section")


@pytest.mark.parametrize("method", METHODS)
def test_plain(benchmark, method):
    t_last = float(solve("henon-heiles", method, t_end=1e6, section=CROSSINGS).t[-1])
    solve("henon-heiles", method, t_end=1.0)                            # warm-up
    benchmark.group = f"henon-heiles sections vs plain, {CROSSINGS} crossings"
    traj = benchmark.pedantic(solve, args=("henon-heiles", method),
                              kwargs={"t_end": t_last, "every": 10 ** 9}, rounds=5, iterations=1,
                              warmup_rounds=1)
    assert traj.status == "ok"
    benchmark.extra_info.update(method=method, t_end=t_last, kind="plain")
