"""Worker processes that never outlive their command.

A worker of any gnibench pool (the runner's local pool, the report's and the figures' drawing
pools) ignores SIGINT (Ctrl-C at a terminal reaches the whole process group: the parent decides
and stops the workers), ends on SIGTERM, and asks the kernel to kill it when its parent dies
(Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)``), so ``kill -9`` of a command leaves no orphan
behind.
"""
from __future__ import annotations

import contextlib
import os
import signal

from gnibench.suite.foundation.guard import watch_signals
import sys

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
    watch_signals()        # no real KeyboardInterrupt here: one raised is the user's code's
    die_with_parent(parent)


def children() -> set[int]:
    """This process's children (Linux: /proc; empty elsewhere), zombies included."""
    found: set[int] = set()
    with contextlib.suppress(OSError):
        for task in os.listdir(f"/proc/{os.getpid()}/task"):
            with contextlib.suppress(OSError), \
                    open(f"/proc/{os.getpid()}/task/{task}/children") as f:
                found.update(int(p) for p in f.read().split())
    return found


def _zombie(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rpartition(")")[2].split()[0] == "Z"
    except (OSError, IndexError):
        return False


def reap_strays(before: set[int], quiet_checks: int = 3, seconds: float = 1.0) -> None:
    """Wait for the children that ended since ``before`` was taken and that nobody waits for: the
    short-lived processes a child subreaper adopts when their parent was killed (a pool stopped
    while its first worker forked the others). Only zombies are reaped; a live child is left to
    its owner. Returns after ``quiet_checks`` checks 10 ms apart found none (at most ``seconds``)."""
    import time

    quiet, deadline = 0, time.monotonic() + seconds
    while quiet < quiet_checks and time.monotonic() < deadline:
        strays = [pid for pid in children() - before if _zombie(pid)]
        for pid in strays:
            with contextlib.suppress(ChildProcessError):
                os.waitpid(pid, os.WNOHANG)
        quiet = 0 if strays else quiet + 1
        time.sleep(0.01)
