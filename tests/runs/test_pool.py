"""The runner's local pool: the plan (kernel groups, affinity, longest first), workers that never
import pandas, quiet workers, a dead worker, a run stopped early, fitting the pool to the cells, no
process left behind; the tables of a pool run are those of a serial run (tests/runs/test_runner_store.py
checks -j 1, -j 2 and Dask on the command line).

No test depends on timing: each waits for an outcome or a process's end, never for a time."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from gnibench.suite.foundation.outputs import Fault
from gnibench.suite.runs.cellwork import run_cell
from gnibench.suite.runs.experiment import parse_experiment
from gnibench.suite.runs.pool import Plan, Pool, longest_first
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


def test_outcome_columns_make_the_table_of_the_cell():
    """A cell's samples travel as columns; the table made of them has the cell's id and specs in
    front and the columns' values as they are."""
    from gnibench.suite.runs.tables import samples_table

    cell = cells()[0]
    outcome = run_cell(cell)
    assert isinstance(outcome.samples, dict)
    table = samples_table([(cell, outcome.samples, outcome.state_names)])
    assert list(table.columns[:6]) == ["cell", "problem", "method", "t", "steps", "nfev"]
    assert (table["cell"] == cell.id).all() and (table["method"] == cell.method).all()
    for name, values in outcome.samples.items():
        assert np.array_equal(table[name].to_numpy(), values, equal_nan=True), name


def test_a_worker_runs_cells_without_pandas():
    code = ("import sys; from gnibench.suite.runs.pool import preload; preload(); "
            "from gnibench.suite.runs.cellwork import run_cell; "
            "from gnibench.suite.runs.experiment import parse_experiment; "
            f"cell = parse_experiment({SMALL!r}, 's.toml').cells[0]; "
            "mods = set(sys.modules); o = run_cell(cell); "
            "assert o.status == 'ok', o.reason; "
            "print(sorted(m for m in set(sys.modules) - mods if m.split('.')[0] in "
            "('pandas', 'pyarrow')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def _children() -> set[int]:
    with open(f"/proc/{os.getpid()}/task/{os.getpid()}/children") as f:
        return {int(p) for p in f.read().split()}


LINUX = pytest.mark.skipif(not os.path.exists(f"/proc/{os.getpid()}/task"), reason="/proc")


@LINUX
def test_pool_runs_every_cell_once_and_leaves_nothing():
    before = _children()
    todo = cells()
    with Pool(2).start() as p:
        assert set(p.started()) == _children() - before        # forked before the cells are known
        assert len(p.started()) == 2
        outcomes = list(p.run(_groups(todo)))
    assert sorted(o.cell.id for o in outcomes) == [c.id for c in todo]
    assert all(o.status == "ok" and isinstance(o.samples, dict) for o in outcomes)
    # the caller's own cells come back (the parent keys them by identity)
    assert {id(o.cell) for o in outcomes} == {id(c) for c in todo}
    assert _children() == before


@LINUX
def test_fit_ends_the_idle_workers_beyond_the_cells_and_forks_the_missing_ones():
    before = _children()
    with Pool(2).start() as p:
        first = p.started()
        p.fit(1)
        assert p.started() == first[:1]
        p.fit(3)
        assert len(p.started()) == 3 and p.started()[0] == first[0]
        assert set(p.started()) <= _children()
        outcomes = list(p.run(_groups(cells())))
        assert sorted(o.cell.id for o in outcomes) == list(range(6))
        p.fit(0)
        assert p.started() == []
    assert _children() == before


@LINUX
def test_a_worker_ignores_sigint_and_ends_on_sigterm():
    """Ctrl-C reaches the whole process group: the parent decides (quiet_worker)."""
    before = _children()
    todo = cells()
    with Pool(1).start() as p:
        (worker,) = p.started()
        assert [o.status for o in p.run(_groups(todo[:1]))] == ["ok"]   # its handlers are set
        os.kill(worker, signal.SIGINT)
        assert [o.status for o in p.run(_groups(todo[1:2]))] == ["ok"]  # still serving
        os.kill(worker, signal.SIGTERM)
        with pytest.raises(Fault, match=r"died \(signal SIGTERM\) while running cell 2"):
            list(p.run(_groups(todo[2:3])))
    assert _children() == before


@LINUX
def test_a_run_stopped_early_terminates_the_workers_at_once():
    """The caller stops after the first outcome (Ctrl-C in the runner closes the generator): the
    cells still running are not waited for."""
    before = _children()
    p = Pool(2).start()
    run = p.run(_groups(cells()))
    next(run)
    run.close()
    assert _children() == before and p.conns == []


@LINUX
def test_a_dead_worker_fails_the_run_with_its_cell(monkeypatch):
    from gnibench.suite.runs import cellwork

    original = cellwork.run_cell

    def dying(cell, report=None):
        if cell.id == 4:
            os._exit(3)                                        # killed, out of memory, ...
        return original(cell, report)

    monkeypatch.setattr(cellwork, "run_cell", dying)           # inherited by the fork
    before = _children()
    died = r"died \(exit code 3\) while running cell 4"
    with pytest.raises(Fault, match=died), Pool(2).start() as p:
        list(p.run(_groups(cells())))
    assert _children() == before


@LINUX
@pytest.mark.parametrize("now", [True, False])
def test_a_pool_stopped_at_once_leaves_nothing(now):
    """Stopped whatever its first worker is doing (preloading, forking the others)."""
    before = _children()
    Pool(3).start().stop(now=now)
    assert _children() == before


def test_our_dask_workers_are_forked_from_a_preloaded_fork_server():
    """gnibench's own LocalCluster forks its workers from a fork server that imported Dask and
    what a cell needs (numba, its CPU target, the registries) once: a worker starts with them, and
    its parent is that server, not this process; outside, Dask's default start method is back."""
    pytest.importorskip("distributed")
    import dask
    from distributed import Client, LocalCluster
    from gnibench.suite.runs.executors import FORKSERVER_PRELOAD, _forked_workers

    def worker_state():
        import multiprocessing
        import sys

        return ([m for m in FORKSERVER_PRELOAD if m in sys.modules],
                multiprocessing.get_start_method(allow_none=True), os.getppid())

    before = dask.config.get("distributed.worker.multiprocessing-method")
    with _forked_workers():
        with LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                          dashboard_address=None, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}
                          ) as cluster, Client(cluster) as client:
            ((loaded, method, parent),) = client.run(worker_state).values()
    assert dask.config.get("distributed.worker.multiprocessing-method") == before
    assert loaded == list(FORKSERVER_PRELOAD) and method == "forkserver"
    assert parent != os.getpid()                           # forked by the server
