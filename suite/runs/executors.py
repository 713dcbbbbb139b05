"""Where the cells of a matrix run: this process, a local process pool, or a Dask cluster.

Every executor takes the cells to compute, grouped by compiled kernel
(:func:`gnibench.suite.runs.cellwork.kernel_plan`), and yields their
:class:`~gnibench.suite.runs.cellwork.CellOutcome` as they finish, in any order (the tables are
assembled in cell order afterwards, so they do not depend on the executor or the number of
workers). The first cell of each group whose kernel is not in the disk cache yet runs before the
rest of its group: it compiles the kernel once, into the disk cache, and the other cells, wherever
they run, load it (a group whose kernel is there already runs at once). Compiles of different
kernels run in parallel, in the order of the groups: the runner puts the kernels not compiled yet
first, the costliest first (:func:`gnibench.suite.runs.runner._groups`).

* ``serial`` (``-j 1``): in this process, in cell order.
* ``local`` (default, ``-j N``, N = the number of cores): a pool of forked workers
  (:mod:`gnibench.suite.runs.pool`), started while the cells are prepared, that keep the kernels
  they loaded. Workers ignore SIGINT (the parent handles Ctrl-C and stops them) and report the
  progress of long cells through a queue.
* ``dask`` (``--executor dask``): a ``distributed.LocalCluster`` of N single-threaded worker
  processes, or the scheduler at ``--scheduler ADDRESS``; the workers must have gnibench installed.
  A worker that dies mid-cell is Dask's to replace: the cell runs again elsewhere. A cell whose
  workers all died (Dask's ``KilledWorker``: out of memory, say), a lost scheduler, or a cluster
  without any worker for ``NO_WORKERS`` seconds (one line when it is first seen empty) ends the
  run with one line; the cells finished so far are stored, and the same command resumes.
"""
from __future__ import annotations

import contextlib
import os
import signal
import time
from collections.abc import Callable, Iterator

from gnibench.suite.foundation.errors import UserError, named, spelled
from gnibench.suite.foundation.outputs import Fault
from gnibench.suite.runs.cellwork import CellOutcome, run_cell
from gnibench.suite.runs.pool import default_jobs, workers  # noqa: F401 - part of this interface

EXECUTORS = ("local", "dask")

Progress = Callable[[int, float], None]
NO_WORKERS = 60.0       # seconds a Dask cluster may have no worker before the run stops
POLL = 5.0              # how often a waiting Dask run looks at the cluster's workers


def check(executor: str, jobs: int | None, scheduler: str | None) -> None:
    """Refuse bad executor options before anything runs or is written."""
    if executor not in EXECUTORS:
        raise UserError(f"bad {named('--executor', repr(executor))}; allowed: {', '.join(EXECUTORS)}")
    if jobs is not None and not 1 <= jobs <= 1024:
        raise UserError(f"bad {named('-j', str(jobs))}; allowed: an integer from 1 to 1024")
    if scheduler is not None:
        if executor != "dask":
            raise UserError(f"{spelled('--scheduler')} needs {named('--executor', 'dask')}")
        if not scheduler.strip() or any(c.isspace() for c in scheduler):
            raise UserError(f"bad {named('--scheduler', repr(scheduler))}; allowed: an address such as "
                            f"tcp://127.0.0.1:8786")
    if executor == "dask":
        try:
            import distributed  # noqa: F401
        except ImportError:
            raise UserError(f"{named('--executor', 'dask')} needs dask[distributed]: pip install "
                            "'gnibench[dask]'") from None
    if scheduler is not None:      # before the output directory exists: is a scheduler there?
        from gnibench.suite.runs.scheduler import probe

        probe(scheduler)


def start(executor: str, jobs: int | None, cells: int | None = None):
    """The local pool, started now, or None where none is needed (serial, Dask, a single cell,
    no fork): :func:`gnibench.suite.runs.pool.start`."""
    if executor != "local":
        return None
    from gnibench.suite.runs.pool import start as start_pool

    return start_pool(jobs, cells)


def run(groups: list[list], executor: str = "local", jobs: int | None = None,
        scheduler: str | None = None, progress: Progress | None = None,
        pool=None, warm: list[bool] | None = None) -> Iterator[CellOutcome]:
    """Run the cells of ``groups``: an iterator of their outcomes as they finish (``pool``: the
    local pool of :func:`start`, whose workers get their first cells at once; else one is started
    here when needed; ``warm[i]``: the kernel of ``groups[i]`` is in the disk cache already, so
    its cells need not wait for its first one)."""
    total = sum(len(g) for g in groups)
    jobs = max(1, workers(jobs, total))
    if executor == "dask":
        return _dask(groups, jobs, scheduler, warm)
    if pool is not None and total:
        return pool.run(groups, progress, warm)
    if jobs == 1 or total <= 1:
        return _serial(groups, progress)
    return _own_pool(groups, executor, jobs, total, progress, warm)


def _own_pool(groups, executor, jobs, total, progress, warm) -> Iterator[CellOutcome]:
    own = start(executor, jobs, total)
    if own is None:
        yield from _serial(groups, progress)
        return
    with own:
        yield from own.run(groups, progress, warm)


def _serial(groups, progress) -> Iterator[CellOutcome]:
    cells = sorted((c for g in groups for c in g), key=lambda c: c.id)
    for cell in cells:
        yield run_cell(cell, progress)


# -- Dask -----------------------------------------------------------------------------------

@contextlib.contextmanager
def _environ(name: str, value: str):
    """``name`` set to ``value`` (unless the user set it) for the block, as it was after."""
    if name in os.environ:
        yield
        return
    os.environ[name] = value
    try:
        yield
    finally:
        os.environ.pop(name, None)


@contextlib.contextmanager
def _quiet_logger(name: str):
    """The logger ``name`` says nothing below CRITICAL for the block: while our cluster starts,
    a worker that fails (its fork server killed, say) is Dask's ERROR log with a traceback from
    every nanny, 158 lines for two workers; the one line is ours."""
    import logging

    logger = logging.getLogger(name)
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logger.setLevel(level)


def _dask(groups, jobs, scheduler, warm=None) -> Iterator[CellOutcome]:
    from distributed import Client, LocalCluster

    cluster = None
    if scheduler is None:
        # SIGINT blocked while the cluster starts: its threads and worker processes inherit the
        # mask, so a Ctrl-C at the terminal reaches this process only (which closes the cluster)
        # instead of printing a traceback from every worker; a Ctrl-C meanwhile waits, not lost
        blocked = {signal.SIGINT}
        signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
        try:
            # no dashboard, and the scheduler's HTTP server on a free local port (on its default
            # 8787, taken by another cluster, it warned on stderr); the workers log critical
            # errors only (a Ctrl-C cancels their cells: Dask's warnings about that are no news;
            # the setting is read by the worker processes as they start, and then taken back, so
            # the caller's own clusters, in a notebook say, keep their logging)
            with _environ("DASK_LOGGING__DISTRIBUTED", "critical"), _forked_workers(), \
                    _quiet_logger("distributed"):
                try:
                    cluster = LocalCluster(n_workers=jobs, threads_per_worker=1,
                                           processes=True, dashboard_address=None,
                                           scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
                except Exception as e:  # noqa: BLE001 - its workers died as it started, say
                    cause = " ".join(str(e).split())[:160] or type(e).__name__
                    raise Fault(f"the local Dask cluster could not start ({cause}); nothing was "
                                f"lost: run the command again (or use {named('--executor', 'local')})") from None
            client = Client(cluster)
        finally:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, blocked)
    else:
        try:
            client = Client(scheduler, timeout="10s")
        except Exception as e:  # noqa: BLE001 - it answered the probe, then went away
            raise UserError(f"bad {named('--scheduler', repr(scheduler))}: cannot connect "
                            f"({type(e).__name__}: {e})") from None
    # a lost scheduler is our one line, not the client's ERROR log with two tracebacks
    with _quiet_logger("distributed.client"):
        try:
            yield from _outcomes(client, groups, scheduler, warm)
        except BaseException:
            import logging

            # Ctrl-C: the workers are stopped mid-cell; Dask's warnings about that are no news
            logging.getLogger("distributed").setLevel(logging.ERROR)
            if cluster is not None:
                _kill_workers(cluster)
            raise
        finally:
            client.close()
            if cluster is not None:
                cluster.close(timeout=5)


def _outcomes(client, groups, scheduler, warm=None) -> Iterator[CellOutcome]:
    """Submit the first cell of each group, the rest of a group once its first has finished (all
    at once for a group whose kernel is in the disk cache, ``warm``)."""
    waiting, cells = {}, {}        # pure=False: fresh keys, never a result of another run
    for g, ready in zip(groups, warm or [False] * len(groups)):
        for cell in g if ready else g[:1]:         # a kernel to compile: its first cell alone
            fut = client.submit(run_cell, cell, pure=False)
            waiting[fut], cells[fut.key] = [] if ready else g[1:], cell
    pending = set(waiting)
    for fut in _finished(client, pending, scheduler or "of the local cluster"):
        for cell in waiting.pop(fut, []):
            new = client.submit(run_cell, cell, pure=False)
            cells[new.key] = cell
            pending.add(new)
        cell = cells.pop(fut.key)            # the caller's own cell, not the worker's copy
        outcome = _result(fut, cell, scheduler)
        outcome.cell = cell
        yield outcome


def _finished(client, pending: set, where: str) -> Iterator:
    """The futures of ``pending`` as they finish (the caller may add to it meanwhile). Every
    ``POLL`` seconds without news the cluster's workers are counted: none for ``NO_WORKERS``
    seconds is a :class:`Fault` (a scheduler without workers waited for ever, silently)."""
    from distributed import CancelledError, TimeoutError, wait

    from gnibench.suite.foundation.cache import warn

    empty_since = None
    while pending:
        try:
            done, _ = wait(list(pending), timeout=POLL, return_when="FIRST_COMPLETED")
        except TimeoutError:
            if _workers(client, where):
                empty_since = None
                continue
            if empty_since is None:
                empty_since = time.monotonic()
                hint = f" (start some: dask worker {where})" if "://" in where else ""
                warn(f"the Dask scheduler {where} has no workers; waiting up to {NO_WORKERS:g} s "
                     f"for one{hint}")
            elif time.monotonic() - empty_since > NO_WORKERS:
                raise Fault(f"the Dask scheduler {where} has had no workers for {NO_WORKERS:g} s;"
                            f" the cells finished so far are stored: run the same command again "
                            f"once it has workers (or use {named('--executor', 'local')})") from None
            continue
        except CancelledError:          # the scheduler went away: every future is cancelled
            raise _lost(where) from None
        for fut in done:
            pending.discard(fut)
            yield fut


def _workers(client, where: str) -> int:
    try:
        return len(client.nthreads())
    except OSError:                     # CommClosedError included: the scheduler is gone
        raise _lost(where) from None


def _lost(where: str) -> Fault:
    return Fault(f"the connection to the Dask scheduler {where} was lost; the cells finished so "
                 f"far are stored: run the same command again once it is back")


def _result(fut, cell, scheduler):
    """The outcome of a cell's future; Dask's failures as one line naming the cell."""
    from distributed import CancelledError, KilledWorker

    try:
        return fut.result()
    except KilledWorker:
        raise Fault(f"Dask workers died while running cell {cell.id} ({cell.problem} "
                    f"{cell.method}), one after another (out of memory? see the workers' logs); "
                    f"the cells finished so far are stored: run the same command again to "
                    f"compute the rest") from None
    except CancelledError:
        raise _lost(scheduler or "of the local cluster") from None


#: What the fork server of our LocalCluster's workers imports once, instead of each worker: Dask,
#: and what a cell needs (gnibench.suite.runs.pool.preload: numba, its CPU target, the registries)
FORKSERVER_PRELOAD = ("distributed", "gnibench.suite.runs.forkserver")


@contextlib.contextmanager
def _forked_workers():
    """Our LocalCluster's workers are forked by a fork server that imported Dask and the cell
    runner once (``multiprocessing``'s "forkserver" start method, which Dask supports and uses
    for its own test suite), instead of each being a fresh interpreter that imports them
    ("spawn", Dask's default). Measured on ``gnibench run quick --executor dask -j 2``, the CPU of
    the command and all its processes (three runs each): spawn 4.7-5.6 s (2.7-3.4 s wall), Dask's
    fork server with its own preload list 3.5-4.1 s, with ours 3.4-3.7 s (2.3-2.4 s wall); each
    spawned worker spent 1.4 s, each forked one 0.9 s. The fork server lives as long as this
    process, so a second cluster (a notebook, the tests) starts its workers at the cost of a
    fork. Where the start method does not exist (Windows) Dask's default stays."""
    import multiprocessing

    if "forkserver" not in multiprocessing.get_all_start_methods():
        yield
        return
    import dask
    from distributed.utils import get_mp_context

    with dask.config.set({"distributed.worker.multiprocessing-method": "forkserver"}):
        get_mp_context()     # Dask sets its own preload list once per process; ours replaces it
        multiprocessing.get_context("forkserver").set_forkserver_preload(list(FORKSERVER_PRELOAD))
        yield


def _kill_workers(cluster) -> None:
    """A run that ends early (Ctrl-C, SIGTERM, an error): the worker processes of our own
    LocalCluster are killed at once, their cells abandoned (a cell is stored by this process when
    its outcome arrives, so a worker holds nothing to keep). ``cluster.close`` alone asks each busy
    worker to finish and then waits: measured 3.9-4.1 s with two cells running, 0.01 s once the
    workers are killed. Each nanny is told first that its worker is going away for good, else it
    would start another one."""
    for nanny in list(cluster.workers.values()):
        try:
            nanny.close_gracefully()          # the nanny no longer restarts its worker
            process = nanny.process.process
            if process.is_alive():
                os.kill(process.pid, signal.SIGKILL)
        except (AttributeError, OSError):   # not started, or gone already
            pass
