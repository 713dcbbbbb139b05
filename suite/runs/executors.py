"""Where the cells of a matrix run: this process, a local process pool, or a Dask cluster.

Every executor takes the cells to compute, grouped by compiled kernel
(:func:`gnibench.suite.runs.cellwork.kernel_group`), and yields their
:class:`~gnibench.suite.runs.cellwork.CellOutcome` as they finish, in any order (the tables are
assembled in cell order afterwards, so they do not depend on the executor or the number of
workers). The first cell of each group runs before the rest of its group: it compiles the kernel
once, into the disk cache, and the other cells, wherever they run, load it. Compiles of different
kernels run in parallel.

* ``serial`` (``-j 1``): in this process, in cell order.
* ``local`` (default, ``-j N``, N = the number of cores): a process pool. Workers ignore SIGINT
  (the parent handles Ctrl-C and stops them) and report the progress of long cells through a
  queue.
* ``dask`` (``--executor dask``): a ``distributed.LocalCluster`` of N single-threaded worker
  processes, or the scheduler at ``--scheduler ADDRESS``; the workers must have gnibench installed.
"""
from __future__ import annotations

import contextlib
import os
import queue
import signal
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.processes import quiet_worker, stop_now
from gnibench.suite.runs.cellwork import CellOutcome, install_reporter, run_cell

EXECUTORS = ("local", "dask")
POLL_SECONDS = 0.2

Progress = Callable[[int, float], None]


def default_jobs() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                       # not on Linux
        return os.cpu_count() or 1


def check(executor: str, jobs: int | None, scheduler: str | None) -> None:
    """Refuse bad executor options before anything runs or is written."""
    if executor not in EXECUTORS:
        raise UserError(f"bad --executor {executor!r}; allowed: {', '.join(EXECUTORS)}")
    if jobs is not None and not 1 <= jobs <= 1024:
        raise UserError(f"bad -j {jobs}; allowed: an integer from 1 to 1024")
    if scheduler is not None:
        if executor != "dask":
            raise UserError("--scheduler needs --executor dask")
        if not scheduler.strip() or any(c.isspace() for c in scheduler):
            raise UserError(f"bad --scheduler {scheduler!r}; allowed: an address such as "
                            f"tcp://127.0.0.1:8786")
    if executor == "dask":
        try:
            import distributed  # noqa: F401
        except ImportError:
            raise UserError("--executor dask needs dask[distributed]: pip install "
                            "'gnibench[dask]'") from None
    if scheduler is not None:      # before the output directory exists: is a scheduler there?
        from gnibench.suite.runs.scheduler import probe

        probe(scheduler)


def run(groups: list[list], executor: str = "local", jobs: int | None = None,
        scheduler: str | None = None, progress: Progress | None = None) -> Iterator[CellOutcome]:
    """Run the cells of ``groups`` and yield their outcomes as they finish."""
    total = sum(len(g) for g in groups)
    jobs = max(1, min(jobs or default_jobs(), total))     # -j 1000 for 6 cells: 6 processes
    if executor == "dask":
        yield from _dask(groups, jobs, scheduler)
    elif jobs == 1 or sum(len(g) for g in groups) <= 1:
        yield from _serial(groups, progress)
    else:
        yield from _local(groups, jobs, progress)


def _serial(groups, progress) -> Iterator[CellOutcome]:
    cells = sorted((c for g in groups for c in g), key=lambda c: c.id)
    for cell in cells:
        yield run_cell(cell, progress)


# -- the local process pool ------------------------------------------------------------------

_queue = None


def _worker_init(q, parent: int) -> None:
    """In each worker: Ctrl-C is the parent's business (SIGINT ignored, SIGTERM ends the worker),
    the worker dies with its parent, and progress goes through the queue."""
    global _queue
    quiet_worker(parent)
    _queue = q
    install_reporter(_report)


def _report(cell_id: int, fraction: float) -> None:
    with contextlib.suppress(Exception):          # progress is best effort
        _queue.put_nowait((cell_id, fraction))


def _drain(q, progress) -> None:
    while True:
        try:
            cell_id, fraction = q.get_nowait()
        except (queue.Empty, OSError, ValueError):
            return
        if progress is not None:
            progress(cell_id, fraction)


def _local(groups, jobs, progress) -> Iterator[CellOutcome]:
    import multiprocessing as mp

    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    ctx = mp.get_context(method)
    q = ctx.Queue()
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_worker_init,
                               initargs=(q, os.getpid()))
    waiting = {i: list(g[1:]) for i, g in enumerate(groups)}
    running = {pool.submit(run_cell, g[0]): i for i, g in enumerate(groups) if g}
    try:
        while running:
            done, _ = wait(running, timeout=POLL_SECONDS, return_when=FIRST_COMPLETED)
            _drain(q, progress)
            for fut in done:
                group = running.pop(fut)
                for cell in waiting.pop(group, []):      # the kernel is compiled: the rest may go
                    running[pool.submit(run_cell, cell)] = -1
                yield fut.result()
    finally:
        _stop(pool)
        q.close()


def _stop(pool: ProcessPoolExecutor) -> None:
    """Shut the pool down now: cancel what has not started, stop what runs (Ctrl-C)."""
    stop_now(pool)


# -- Dask -----------------------------------------------------------------------------------

def _dask(groups, jobs, scheduler) -> Iterator[CellOutcome]:
    from distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler is None:
        # SIGINT blocked while the cluster starts: its threads and worker processes inherit the
        # mask, so a Ctrl-C at the terminal reaches this process only (which closes the cluster)
        # instead of printing a traceback from every worker; a Ctrl-C meanwhile waits, not lost
        blocked = {signal.SIGINT}
        signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
        try:
            cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        finally:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, blocked)
    else:
        try:
            client = Client(scheduler, timeout="10s")
        except Exception as e:  # noqa: BLE001 - it answered the probe, then went away
            raise UserError(f"bad --scheduler {scheduler!r}: cannot connect "
                            f"({type(e).__name__}: {e})") from None
    try:
        waiting = {}                   # pure=False: fresh keys, never a result of another run
        for g in groups:
            if g:
                waiting[client.submit(run_cell, g[0], pure=False)] = g[1:]
        pending = as_completed(list(waiting))
        for fut in pending:
            for cell in waiting.pop(fut, []):
                pending.add(client.submit(run_cell, cell, pure=False))
            yield fut.result()
    except BaseException:
        import logging

        # Ctrl-C: the workers are stopped mid-cell; Dask's warnings about that are no news
        logging.getLogger("distributed").setLevel(logging.ERROR)
        raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close(timeout=5)
