"""Dask faults beyond an unreachable scheduler (issue 43 item 4): a scheduler without workers, a
scheduler lost mid-run, a cell whose workers all die. Each is one line (a Fault: exit code 1)
and the cells finished before it stay stored; none is a hang or a traceback.

The clusters are real (an in-process LocalCluster without workers); nothing waits for a time:
``NO_WORKERS`` is set to 0 and ``POLL`` to a fraction of a second, so a cluster that never gets a
worker fails at the second look, however loaded the machine.
"""
from __future__ import annotations

from types import SimpleNamespace

import pytest

pytest.importorskip("distributed")

from gnibench.suite.foundation.outputs import Fault  # noqa: E402
from gnibench.suite.runs import executors  # noqa: E402
from gnibench.suite.runs.experiment import parse_experiment  # noqa: E402

ONE = """
name = "one"
title = "One cell"
reference = "[HLW] (2.2)"
steps = 10

[[cells]]
problems = ["kepler-2d"]
methods = ["rk4:h=0.1"]
"""


@pytest.fixture
def empty_cluster():
    """A scheduler that accepts clients and has no worker."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
        yield cluster


@pytest.fixture
def said(monkeypatch):
    from gnibench.suite.foundation import cache

    lines = []
    monkeypatch.setattr(cache, "warn", lines.append)
    monkeypatch.setattr(executors, "NO_WORKERS", 0.0)
    monkeypatch.setattr(executors, "POLL", 0.2)
    return lines


def test_a_scheduler_without_workers_is_one_line_not_a_hang(empty_cluster, said):
    """Seen: ``gnibench run E --executor dask --scheduler ADDRESS`` against a scheduler with no
    worker printed its first line and waited for ever, silently."""
    cells = parse_experiment(ONE, "one.toml").cells
    address = empty_cluster.scheduler_address
    with pytest.raises(Fault, match=f"the Dask scheduler {address} has had no workers"):
        list(executors._dask([cells], 1, address))
    assert len(said) == 1 and "has no workers; waiting up to" in said[0]
    assert f"dask worker {address}" in said[0]


def test_a_scheduler_lost_mid_run_is_one_line(said, monkeypatch):
    """Seen: a scheduler killed mid-run was a FutureCancelledError traceback (and the Dask
    client's ERROR log with two more)."""
    import contextlib

    from distributed import LocalCluster

    from gnibench.suite.foundation import cache

    cluster = LocalCluster(n_workers=0, processes=False, dashboard_address=None,
                           scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})

    def gone(line):                   # the run waits: the scheduler goes away now
        said.append(line)
        cluster.scheduler.stop()

    monkeypatch.setattr(cache, "warn", gone)
    monkeypatch.setattr(executors, "NO_WORKERS", 1e9)
    cells = parse_experiment(ONE, "one.toml").cells
    try:
        with pytest.raises(Fault, match="the connection to the Dask scheduler .* was lost"):
            list(executors._dask([cells], 1, cluster.scheduler_address))
    finally:
        with contextlib.suppress(Exception):
            cluster.close(timeout=1)


def test_a_cell_whose_workers_all_died_is_one_line_naming_it():
    """Seen: a worker with a small memory limit, restarted by its nanny and killed again, ended
    the run with distributed's KilledWorker traceback."""
    from distributed import KilledWorker

    class Dead:
        def result(self):
            raise KilledWorker("run_cell-1", None, 3)

    cell = SimpleNamespace(id=7, problem="kepler-2d:e=0.6", method="rk4:h=0.001")
    with pytest.raises(Fault, match=r"Dask workers died while running cell 7 \(kepler-2d:e=0.6 "
                                    r"rk4:h=0.001\).*stored: run the same command again"):
        executors._result(Dead(), cell, "tcp://127.0.0.1:8786")
