"""Worker processes that never outlive their command, and pools that stop at once.

A worker of any gnibench pool (the runner's local pool, the report's and the figures' drawing
pools) ignores SIGINT (Ctrl-C at a terminal reaches the whole process group: the parent decides
and stops the workers), ends on SIGTERM, and asks the kernel to kill it when its parent dies
(Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)``), so ``kill -9`` of a command leaves no orphan
behind. :func:`pool` is a process pool that, when the block it serves ends with an exception
(a KeyboardInterrupt: Ctrl-C or SIGTERM), terminates its workers instead of waiting for them.
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
from concurrent.futures import ProcessPoolExecutor

PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int) -> None:
    """Ask the kernel to kill this process when its parent dies; end at once if the parent died
    before the request (the worker was adopted by another process)."""
    if sys.platform.startswith("linux"):
        import ctypes

        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:
        os._exit(1)


def quiet_worker(parent: int) -> None:
    """A pool worker's first act: SIGINT is the parent's business, SIGTERM ends it, and it dies
    with its parent."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    die_with_parent(parent)


def stop_now(pool: ProcessPoolExecutor) -> None:
    """Shut a pool down now: cancel what has not started, terminate what runs."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        if p.is_alive():
            p.terminate()
    for p in processes:
        p.join(timeout=5)
    pool.shutdown(wait=True)         # the pool's manager thread releases its queues and locks


@contextlib.contextmanager
def pool(workers: int, method: str = "spawn"):
    """A process pool of quiet workers (see the module docstring)."""
    import multiprocessing

    executor = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method),
                                   initializer=quiet_worker, initargs=(os.getpid(),))
    try:
        yield executor
    except BaseException:
        stop_now(executor)
        raise
    executor.shutdown(wait=True)
