"""The runner's local pool: the plan (kernel groups, affinity, longest first), workers that never
import pandas, the zygote, a dead worker, no process left behind; the tables of a pool run are
those of a serial run (tests/test_runner_store.py checks -j 1, -j 2 and Dask on the command line)."""
from __future__ import annotations

import os
import subprocess
import sys
from types import SimpleNamespace

import gnibench.suite.runs.pool as pool
import pandas as pd
import pytest
from gnibench.suite.runs.cellwork import run_cell, with_frame
from gnibench.suite.runs.experiment import parse_experiment
from gnibench.suite.runs.pool import Plan, Pool, Zygote, longest_first
from gnibench.suite.runs.runner import _groups

SMALL = """
name = "small"
title = "two kernels"
reference = "[HLW] I.2"
steps = 200
every = 50

[[cells]]
problems = ["kepler-2d"]
methods = ["euler", "stormer-verlet"]
vary.h = [0.02, 0.01, 0.005]
"""


def cells():
    return parse_experiment(SMALL, "small.toml").cells


def fake(id, steps):
    return SimpleNamespace(id=id, spec=SimpleNamespace(nsteps=steps))


def test_longest_first_by_planned_steps_else_backwards():
    group = [fake(0, 10), fake(1, 30), fake(2, 20)]
    assert [c.id for c in longest_first(group)] == [1, 2, 0]
    tied = [fake(0, 5), fake(1, 5), fake(2, 5)]                # adaptive: the last of a sweep first
    assert [c.id for c in longest_first(tied)] == [2, 1, 0]


def test_plan_compiles_once_keeps_kernels_home_and_helps_last():
    a = [fake(i, 100 - i) for i in range(4)]                   # group A: 0 is the longest
    b = [fake(10 + i, 100 - i) for i in range(2)]
    plan = Plan([a, b])
    assert plan.next_for(0).id == 0                            # A's kernel compiles on worker 0
    assert plan.next_for(1).id == 10                           # B's on worker 1, meanwhile
    plan.done(b[0])
    assert plan.next_for(1).id == 11                           # B stays on worker 1
    assert plan.next_for(1) is None                            # A still compiling: wait
    plan.done(a[0])
    assert plan.next_for(0).id == 1                            # A stays on worker 0
    assert plan.next_for(1).id == 2                            # worker 1 helps with A
    assert plan.next_for(0).id == 3
    assert plan.next_for(0) is None and plan.next_for(1) is None


def test_outcome_as_columns_gives_the_same_table():
    cell = cells()[0]
    framed = run_cell(cell)
    columns = run_cell(cell, frames=False)
    assert isinstance(columns.samples, dict)
    rebuilt = with_frame(columns).samples
    pd.testing.assert_frame_equal(rebuilt, framed.samples, check_exact=True)
    assert list(rebuilt.dtypes) == list(framed.samples.dtypes)


def test_a_worker_runs_cells_without_pandas():
    code = ("import sys; from gnibench.suite.runs.pool import preload; preload(); "
            "from gnibench.suite.runs.cellwork import run_cell; "
            "from gnibench.suite.runs.experiment import parse_experiment; "
            f"cell = parse_experiment({SMALL!r}, 's.toml').cells[0]; "
            "mods = set(sys.modules); o = run_cell(cell, frames=False); "
            "assert o.status == 'ok', o.reason; "
            "print(sorted(m for m in set(sys.modules) - mods if m.split('.')[0] in "
            "('pandas', 'pyarrow')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def _children() -> set[int]:
    with open(f"/proc/{os.getpid()}/task/{os.getpid()}/children") as f:
        return {int(p) for p in f.read().split()}


@pytest.mark.skipif(not Zygote.available(), reason="the zygote needs Linux")
@pytest.mark.parametrize("with_zygote", [False, True])
def test_pool_runs_every_cell_once_and_leaves_nothing(with_zygote):
    before = _children()
    todo = cells()
    zygote = Zygote().start() if with_zygote else None
    try:
        with Pool(2, zygote).start() as p:
            outcomes = list(p.run(_groups(todo)))
    finally:
        if zygote is not None:
            zygote.stop()
    assert sorted(o.cell.id for o in outcomes) == [c.id for c in todo]
    assert all(o.status == "ok" and isinstance(o.samples, pd.DataFrame) for o in outcomes)
    assert _children() == before


@pytest.mark.skipif(not Zygote.available(), reason="the zygote needs Linux")
def test_a_dead_worker_fails_the_run_with_its_cell(monkeypatch):
    real = pool.run_cell if hasattr(pool, "run_cell") else None
    import gnibench.suite.runs.cellwork as cellwork

    original = cellwork.run_cell

    def dying(cell, report=None, frames=True):
        if cell.id == 4:
            os._exit(3)                                        # killed, out of memory, ...
        return original(cell, report, frames=frames)

    monkeypatch.setattr(cellwork, "run_cell", dying)           # inherited by the fork
    before = _children()
    with pytest.raises(RuntimeError, match="died while running cell 4"):
        with Pool(2).start() as p:
            list(p.run(_groups(cells())))
    assert _children() == before
    assert real is None
