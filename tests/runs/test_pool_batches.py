"""The local pool's batches (issue 42): how the plan sizes them, a kernel already in the disk cache
not waiting for its first cell, batch boundaries that never change a table, and a worker that dies
in the middle of a batch (its cell named, the tables written with the rest pending, the store
resumable).

No test depends on timing: batch sizes are forced through the plan's constants, and a worker
sends its outcomes at the end of each batch (``SEND_SECONDS`` made infinite) where a test needs
that."""
from __future__ import annotations

import os
from types import SimpleNamespace

import pandas as pd
import pytest
from gnibench.suite.foundation.outputs import Fault
from gnibench.suite.runs import plan as plan_module
from gnibench.suite.runs import pool as pool_module
from gnibench.suite.runs.plan import Plan
from gnibench.suite.runs.pool import Pool
from gnibench.suite.runs.runner import _groups, run_experiment

LINUX = pytest.mark.skipif(not os.path.exists(f"/proc/{os.getpid()}/task"), reason="/proc")

MATRIX = """
name = "batches"
title = "one kernel, twelve cells"
reference = "[HLW] I.1"
steps = 400
every = 100

[[cells]]
problems = ["pendulum"]
methods = ["rk4:h=0.01"]
vary.problem.p0 = [0.50, 0.51, 0.52, 0.53, 0.54, 0.55, 0.56, 0.57, 0.58, 0.59, 0.60, 0.61]
"""


def fake(id, steps=10):
    return SimpleNamespace(id=id, spec=SimpleNamespace(nsteps=steps))


def test_a_batch_is_sized_from_the_measured_cost_and_shrinks_towards_the_end(monkeypatch):
    monkeypatch.setattr(plan_module, "BATCH_SECONDS", 0.05)
    monkeypatch.setattr(plan_module, "MAX_BATCH", 64)
    group = [fake(i) for i in range(1000)]
    plan = Plan([group], [True])
    first = plan.batch(0, 2)
    assert [c.id for c in first] == [999]                    # the cost is not known yet: alone
    plan.measured(first, 0.01)                               # 10 ms a cell: 5 in 50 ms
    assert len(plan.batch(0, 2)) == 5
    plan.measured(first, 0.0001)                             # 0.1 ms: 500, at most MAX_BATCH
    assert len(plan.batch(0, 2)) == 64
    while plan.left > 100:
        assert plan.batch(1, 2)
    left = plan.left                                         # a quarter of the rest at most
    assert len(plan.batch(1, 2)) == -(-(left - 1) // 4) < 64
    sizes = []
    while batch := plan.batch(0, 2):
        sizes.append(len(batch))
    assert sizes == sorted(sizes, reverse=True) and sizes[-1] == 1
    assert plan.left == 0 and sum(sizes) == left - -(-(left - 1) // 4)


@pytest.mark.parametrize("cached", [False, True])
def test_a_kernel_in_the_disk_cache_does_not_wait_for_its_first_cell(cached):
    """Three workers, two groups: worker 0 compiles A's kernel (alone), worker 1 starts B; worker 2
    helps B at once if B's kernel is in the disk cache, else waits for B's first cell."""
    a = [fake(i) for i in range(4)]
    b = [fake(10 + i) for i in range(4)]
    plan = Plan([a, b], [False, cached])
    assert [c.id for c in plan.batch(0, 3)] == [3]           # A compiles here
    assert [c.id for c in plan.batch(1, 3)] == [13]          # B's first cell
    helped = [c.id for c in plan.batch(2, 3)]
    assert helped == ([12] if cached else [])
    plan.done(b[3])                                          # B's first cell finished
    assert plan.batch(2, 3)                                  # now open in any case


def _write(tmp_path):
    toml = tmp_path / "batches.toml"
    toml.write_text(MATRIX)
    return toml


def _tables(out):
    return {name: pd.read_parquet(out / f"{name}.parquet") for name in ("cells", "samples")}


def _same(a, b):
    for name in a:
        pd.testing.assert_frame_equal(a[name], b[name], check_exact=True)


@LINUX
def test_batch_boundaries_do_not_change_the_tables(tmp_path, monkeypatch):
    """The same cells in batches of one and in batches as large as the plan allows: the same
    tables (bytes of the Parquet files: their metadata holds no run-dependent value) as a serial
    run."""
    toml = _write(tmp_path)
    run_experiment(toml, tmp_path / "serial", jobs=1, log=open(os.devnull, "w"))
    monkeypatch.setattr(plan_module, "MAX_BATCH", 1)
    run_experiment(toml, tmp_path / "ones", jobs=2, log=open(os.devnull, "w"))
    monkeypatch.setattr(plan_module, "MAX_BATCH", 64)
    monkeypatch.setattr(plan_module, "BATCH_SECONDS", 1e9)
    monkeypatch.setattr(pool_module, "SEND_SECONDS", 1e9)   # outcomes per batch
    run_experiment(toml, tmp_path / "large", jobs=2, log=open(os.devnull, "w"))
    for name in ("cells", "samples"):
        serial = (tmp_path / "serial" / f"{name}.parquet").read_bytes()
        assert (tmp_path / "ones" / f"{name}.parquet").read_bytes() == serial, name
        assert (tmp_path / "large" / f"{name}.parquet").read_bytes() == serial, name


def _dying(monkeypatch, cell_id):
    from gnibench.suite.runs import cellwork

    original = cellwork.run_cell

    def dying(cell, report=None):
        if cell.id == cell_id:
            os._exit(3)                                      # killed, out of memory, ...
        return original(cell, report)

    monkeypatch.setattr(cellwork, "run_cell", dying)         # inherited by the fork


@LINUX
def test_a_worker_dying_in_the_middle_of_a_batch_names_its_cell(monkeypatch):
    """One worker: batches [11], [10], then [9, 8, 7, 6, 5] (longest first: ties backwards); it
    dies on cell 7, after finishing 9 and 8 without sending them (outcomes per batch). The fault
    names cell 7, not the first cell of the batch."""
    from gnibench.suite.runs.experiment import parse_experiment

    monkeypatch.setattr(plan_module, "BATCH_SECONDS", 1e9)
    monkeypatch.setattr(pool_module, "SEND_SECONDS", 1e9)
    _dying(monkeypatch, 7)
    todo = parse_experiment(MATRIX, "batches.toml").cells
    got = []
    with pytest.raises(Fault, match=r"died \(exit code 3\) while running cell 7 "), \
            Pool(1).start() as p:
        got.extend(o.cell.id for o in p.run(_groups(todo), warm=[True]))
    assert got == [11, 10]


@LINUX
def test_a_run_whose_worker_dies_mid_batch_writes_its_tables_and_resumes(tmp_path, monkeypatch):
    toml = _write(tmp_path)
    out = tmp_path / "run"
    run_experiment(toml, tmp_path / "serial", jobs=1, log=open(os.devnull, "w"))
    monkeypatch.setattr(plan_module, "BATCH_SECONDS", 1e9)
    monkeypatch.setattr(pool_module, "SEND_SECONDS", 1e9)
    with monkeypatch.context() as m:
        _dying(m, 5)
        with pytest.raises(Fault, match="while running cell 5 "):
            run_experiment(toml, out, jobs=2, log=open(os.devnull, "w"))
    cells = pd.read_parquet(out / "cells.parquet")          # written: every cell has a status
    assert len(cells) == 12 and set(cells["status"]) <= {"ok", "pending"}
    assert cells.loc[cells["cell"] == 5, "status"].item() == "pending"
    stored = (cells["status"] == "ok").sum()
    log = tmp_path / "log.txt"
    with open(log, "w") as f:
        run_experiment(toml, out, jobs=2, log=f)
    assert f"{stored} reused from the store, {12 - stored} to compute" in log.read_text()
    _same(_tables(out), _tables(tmp_path / "serial"))
