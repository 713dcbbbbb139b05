"""The runner's local process pool: workers forked before the cells are prepared, that stay warm
and keep the kernels they loaded.

* **Ready early.** A fresh process pays about half a second before its first cell: numba and
  numba's CPU target (its typing and lowering registries); pandas it never needs (the samples
  travel as arrays, the parent makes the table). ``gnibench run`` starts the pool first thing
  (:func:`start`, before the experiment is read): its first worker pays that once
  (:func:`preload`) while the parent reads the experiment, opens the store and groups the cells,
  then forks the others from itself, ready at once. Once the cells to compute are known the pool is fitted to them (:meth:`Pool.fit`:
  idle workers beyond their number end, more are forked when ``-j`` asks for more than the
  cores). The workers are children of the command, so a signal to it or its death ends them.
* **By kernel, in batches, one batch queued ahead.** Which cells a free worker runs next is the
  plan's (:mod:`gnibench.suite.runs.plan`: kernel groups, affinity, longest first, batches sized
  from the measured cost of a group's cells). Each worker has its own pipe and holds the batch it
  runs and the next one (while there are cells enough for all workers), so that it never waits
  for the parent (busy storing a result, or not scheduled on a loaded machine) between two
  batches. A worker sends the outcomes of its finished cells together, at the end of a batch or
  after ``SEND_SECONDS`` (so that neither side pays a message, nor the parent a wakeup, per
  cell), without their cells (the parent has them: it matches the outcomes to the cells it sent,
  in order).
* **Quiet workers** (:func:`gnibench.suite.foundation.processes.quiet_worker`): SIGINT ignored
  (Ctrl-C reaches the whole process group: the parent decides), SIGTERM ends them, they die with
  their parent. A worker reports the progress of a long cell through its pipe. When the run ends
  otherwise than by its last cell (Ctrl-C, SIGTERM, an error) the workers are terminated at once.
  A worker that dies (killed, out of memory) ends the run with one line naming the cell it was
  running (:class:`~gnibench.suite.foundation.outputs.Fault`; each worker counts the cells it
  started in a word of memory shared with the parent); the cells whose outcomes arrived are
  stored and stay (those it finished in the last ``SEND_SECONDS`` before it died are computed
  again by the next run).

Which worker runs a cell never changes its numbers: the tables are assembled in cell order.
"""
from __future__ import annotations

import contextlib
import mmap
import os
import signal
import sys
import time
from collections import deque

from gnibench.suite.foundation.outputs import Fault
from gnibench.suite.foundation.processes import children, quiet_worker, reap_strays
from gnibench.suite.runs.plan import Plan, longest_first  # noqa: F401 - part of this interface

POLL_SECONDS = 0.2
PR_SET_CHILD_SUBREAPER = 36
SAFETY_SECONDS = 600.0    # a forked worker says its pid within this (a hang only reaches it)
GONE = 0                  # the pid of a worker already reaped
BLOCKED = {signal.SIGINT, signal.SIGTERM}
AHEAD = 2                 # batches sent to a worker at a time: the one it runs and the next
SEND_SECONDS = 0.05       # a worker sends its finished outcomes at least this often


def default_jobs() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                       # not on Linux
        return os.cpu_count() or 1


def workers(jobs: int | None, cells: int) -> int:
    """How many workers ``-j jobs`` gives ``cells`` cells (-j 1000 for 6 cells: 6 processes)."""
    return max(0, min(jobs or default_jobs(), cells))


def start(jobs: int | None, cells: int | None = None) -> Pool | None:
    """A pool started now (its workers get ready while the caller prepares the cells), or None
    where none is needed (one worker: serial; no fork). ``cells`` unknown: at most one worker per
    core for now (see :meth:`Pool.fit`). This module imports little (not numpy), so the command
    forks the first worker early."""
    n = workers(jobs, default_jobs() if cells is None else cells)
    if n < 2 or not hasattr(os, "fork"):
        return None
    return Pool(n).start()


def preload() -> None:
    """What the first cell of a fresh process would otherwise pay: the modules of a cell and the
    registries its records are looked up in, numba, and numba's CPU target (its typing and
    lowering registries, which import numpy's linear algebra support and scipy.linalg). Workers
    send their samples as arrays (:func:`~gnibench.suite.runs.cellwork.run_cell`): they never
    import pandas."""
    import gnibench.methods
    import gnibench.problems
    import gnibench.suite.cell.solve
    import gnibench.suite.metrics.compute
    import gnibench.suite.runs.cellwork
    import gnibench.suite.runs.tables  # noqa: F401
    import numba
    import scipy.special  # noqa: F401 - exact solutions (elliptic functions): 0.15 s a process

    # numba sets up its CPU target (typing and lowering registries) at its first compilation:
    # a tiny function compiled here, through numba's public API, pays that before the fork
    numba.njit(lambda x: x + 1.0)(1.0)


def _serve(end, others: list, parent: int, ready: bool = False) -> None:
    """A worker: batches of cells in, ("o", outcomes, seconds) and ("p", cell id, fraction done)
    out, until None (``end``: its pipe and its shared counter of cells started; ``ready``: forked
    from a worker that preloaded)."""
    conn, slot = end
    _quiet(parent)
    for other in others:                  # the other ends of the pipes it does not serve
        other.close()
    from gnibench.suite.runs.cellwork import install_reporter, run_cell

    def report(cell_id: int, fraction: float) -> None:
        with contextlib.suppress(Exception):          # progress is best effort
            conn.send(("p", cell_id, fraction))

    install_reporter(report)
    if not ready:
        with contextlib.suppress(Exception):          # a failed preload: the first cell says why
            preload()
    started = 0
    while True:
        try:
            batch = conn.recv()
        except (EOFError, OSError):
            return
        if batch is None:
            return
        finished, since = [], time.perf_counter()
        for k, cell in enumerate(batch):
            started += 1
            slot[:8] = started.to_bytes(8, "little")     # which cell it runs, if it dies
            outcome = run_cell(cell)
            outcome.cell = None                          # the parent has it
            finished.append(outcome)
            now = time.perf_counter()
            if k == len(batch) - 1 or now - since >= SEND_SECONDS:
                conn.send(("o", finished, now - since))
                finished, since = [], now


def _first(mine, rest: list, others: list, parent: int) -> None:
    """The first worker of a batch: it preloads, forks the rest of the batch from itself (ready at
    once; each through a short-lived middle process, so that the command adopts it), then serves.
    ``mine`` and each of ``rest``: a pipe and its shared counter."""
    _quiet(parent)
    for other in others:
        other.close()
    with contextlib.suppress(Exception):
        preload()
    for child in rest:
        middle = _fork(_adopted, child, [mine[0]] + [c[0] for c in rest if c is not child],
                       parent)
        with contextlib.suppress(ChildProcessError):
            os.waitpid(middle, 0)
        child[0].close()
    _serve(mine, [], parent, ready=True)


def _adopted(end, others: list, parent: int) -> None:
    """In the middle process: fork the worker and end, so that the worker is adopted by the
    command (its child subreaper); the worker says its pid first."""
    if os.fork():
        os._exit(0)
    middle = os.getppid()
    while middle != parent and os.getppid() == middle:    # the middle process is ending
        time.sleep(0.001)
    _quiet(parent)                                        # adopted by another: it ends here
    end[0].send(("pid", os.getpid()))
    _serve(end, others, parent, ready=True)


def _subreaper(on: bool) -> bool:
    """Make this process the adopter of its orphaned descendants (Linux); whether it is."""
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    try:
        return ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, int(on), 0, 0,
                                                       0) == 0
    except (OSError, AttributeError):
        return False


def _quiet(parent: int) -> None:
    """The shared worker policy, then the signals blocked across the fork are let in."""
    quiet_worker(parent)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, BLOCKED)


def _fork(target, *args) -> int:
    """Fork a process that runs ``target(*args)`` and exits; its pid in the parent. SIGINT and
    SIGTERM are blocked across the fork until the child has its own dispositions (:func:`_quiet`):
    a signal in its first instant would otherwise run the parent's handler there, which writes to
    the parent's wakeup fd (gnibench.suite.cli.signals) and ends the parent."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, BLOCKED)
    pid = -1
    try:
        pid = os.fork()
    finally:
        if pid != 0:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)
    if pid == 0:
        code = 1
        try:
            target(*args)
            code = 0
        except Exception:  # noqa: BLE001 - a bug: said, then the parent hears of the death
            import traceback

            with contextlib.suppress(Exception):
                traceback.print_exc()
        finally:                          # never back into the caller's code (a signal: quietly)
            os._exit(code)
    return pid


class Pool:
    """``workers`` worker processes forked from this one (see the module docstring)."""

    def __init__(self, workers: int):
        self.size = workers
        self.conns: list = []
        self.slots: list = []                     # per worker: the cells it started (shared)
        self.received: list[int] = []             # per worker: the outcomes it sent
        self.pids: list[int | None] = []         # None: adopted, its pid not heard yet; GONE
        self.leaving: list = []                   # (conn, pid) of workers told to end
        self.plan, self.sent = None, {}
        self.reaping = False
        self.before: set[int] = set()             # children before this pool adopted any

    def start(self) -> Pool:
        """Fork the workers missing to reach ``size``: one that preloads and then forks the
        others from itself (Linux: this process adopts them), else each one preloading."""
        from multiprocessing import Pipe

        missing = self.size - len(self.conns)
        if missing <= 0:
            return self
        pairs = [Pipe() for _ in range(missing)]
        slots = [mmap.mmap(-1, 8) for _ in range(missing)]     # shared with the forked worker
        theirs = [(child, slot) for (_, child), slot in zip(pairs, slots)]
        ours = [conn for conn, _ in pairs]
        if not self.reaping:
            self.before = children()
        if missing >= 2 and (self.reaping or _subreaper(True)):
            self.reaping = True
            pid = _fork(_first, theirs[0], theirs[1:], self.conns + ours, os.getpid())
            self.pids += [pid] + [None] * (missing - 1)
        else:
            for k, child in enumerate(theirs):
                others = self.conns + ours + [c for c, _ in theirs[:k] + theirs[k + 1:]]
                self.pids.append(_fork(_serve, child, others, os.getpid()))
        for child, _ in theirs:
            child.close()
        self.conns += ours
        self.slots += slots
        self.received += [0] * missing
        return self

    def started(self) -> list[int]:
        """The workers' pids (waiting for the adopted ones to say theirs)."""
        for w in range(len(self.conns)):
            self._pid(w, SAFETY_SECONDS)
        return [p for p in self.pids if p]

    def _pid(self, w: int, wait: float) -> int | None:
        if self.pids[w] is None:
            self.pids[w] = _read_pid(self.conns[w], wait)
        return self.pids[w]

    def fit(self, workers: int) -> Pool:
        """``workers`` workers from now on: the extra ones end (they are idle), missing ones are
        forked."""
        workers = max(0, workers)
        for conn, pid in zip(self.conns[workers:], self.pids[workers:]):
            if pid:                               # it may be preloading: no need to wait
                _kill(pid)
            else:                                 # adopted: it ends once it reads this
                with contextlib.suppress(OSError, ValueError):
                    conn.send(None)
            self.leaving.append((conn, pid))
        self.conns, self.pids = self.conns[:workers], self.pids[:workers]
        self.slots, self.received = self.slots[:workers], self.received[:workers]
        self.size = workers
        return self.start()

    def run(self, groups: list[list], progress=None, warm: list[bool] | None = None):
        """Run the cells of ``groups`` (lists of cells sharing a kernel, in cell order; ``warm``:
        which groups' kernels are in the disk cache, :class:`~gnibench.suite.runs.plan.Plan`): the
        first cells go to the workers now, and the iterator returned yields the outcomes as they
        finish; ``progress(cell_id, fraction)`` hears of long cells. If the caller stops early
        (an exception, Ctrl-C, ``close()``), the workers are terminated."""
        self.plan = Plan(groups, warm)
        self.sent = {w: deque() for w in range(self.size)}     # worker -> its cells, in order
        self.batches = {w: deque() for w in range(self.size)}  # worker -> its batches' sizes
        try:
            self._top_up(0)
        except BaseException:
            self.stop(now=True)
            raise
        return self._outcomes(progress)

    def _outcomes(self, progress):
        from multiprocessing.connection import wait

        try:
            while busy := [w for w, cells in self.sent.items() if cells]:
                for conn in wait([self.conns[w] for w in busy], timeout=POLL_SECONDS):
                    w = self.conns.index(conn)
                    try:
                        message = conn.recv()
                    except (EOFError, OSError):
                        raise self._died(w) from None
                    if message[0] == "pid":
                        self.pids[w] = message[1]
                        continue
                    if message[0] == "p":
                        if progress is not None:
                            progress(message[1], message[2])
                        continue
                    outcomes, seconds = message[1], message[2]
                    cells = [self.sent[w].popleft() for _ in outcomes]
                    self.received[w] += len(cells)
                    self._finished(w, len(cells))
                    self.plan.measured(cells, seconds)
                    for cell in cells:
                        self.plan.done(cell)
                    self._top_up(w)
                    for outcome, cell in zip(outcomes, cells):
                        outcome.cell = cell   # the caller's own cell (the worker sends none)
                        yield outcome
        except BaseException:
            self.stop(now=True)
            raise

    def _finished(self, w: int, n: int) -> None:
        """``n`` more cells of worker ``w`` are done: its batches done are off its queue."""
        batches = self.batches[w]
        while n and batches:
            k = min(n, batches[0])
            n -= k
            batches[0] -= k
            if not batches[0]:
                batches.popleft()

    def _top_up(self, first: int) -> None:
        """Give every worker (``first`` first) a batch to run and, while there are cells enough
        for all, one queued behind it (so that a worker never waits for this process between
        two batches; near the end the last cells go to whoever is free)."""
        for w in [first] + [v for v in range(self.size) if v != first]:
            batches = self.batches[w]
            while len(batches) < (AHEAD if self.plan.left >= self.size else 1):
                cells = self.plan.batch(w, self.size)
                if not cells:
                    break
                try:
                    self.conns[w].send(cells)
                except OSError:                       # it died while idle
                    self.sent[w].extend(cells)
                    raise self._died(w) from None
                self.sent[w].extend(cells)
                batches.append(len(cells))

    def _died(self, w: int) -> Fault:
        """The fault of worker ``w``'s death, naming the cell it was running: the one after the
        cells whose outcomes arrived and those it finished since (by its count of the cells it
        started; the next cell it was sent if it died between two)."""
        how = ""
        with contextlib.suppress(ChildProcessError, OSError, TypeError):
            pid, status = os.waitpid(self._pid(w, 0.0), 0)
            self.pids[w] = GONE                   # reaped: its pid may be reused, never signal it
            if pid and os.WIFSIGNALED(status):
                how = f" (signal {signal.Signals(os.WTERMSIG(status)).name})"
            elif pid and os.WIFEXITED(status):
                how = f" (exit code {os.WEXITSTATUS(status)})"
        sent = self.sent[w]
        running = int.from_bytes(self.slots[w][:8], "little") - self.received[w] - 1
        cell = sent[min(max(running, 0), len(sent) - 1)] if sent else None
        what = f"cell {cell.id} ({cell.problem} {cell.method})" if cell is not None else "a cell"
        return Fault(f"a worker of the pool died{how} while running {what}; the cells whose "
                     f"outcomes arrived are stored: run the same command again to compute the "
                     f"rest")

    def stop(self, now: bool = False) -> None:
        """End the workers: ``now`` terminates them (Ctrl-C, an error), else they are told to end
        once idle. Adopted workers not heard of yet are waited for (they were forked or will
        never be: their pipe then closes)."""
        every = list(zip(self.conns, self.pids)) + self.leaving
        if now:
            for _, pid in every:                  # the first of a batch first: it forks no more
                if pid:
                    _kill(pid)
        else:
            for conn in self.conns:
                with contextlib.suppress(OSError, ValueError):
                    conn.send(None)
        for conn, pid in every:
            if pid is None:
                pid = _read_pid(conn, SAFETY_SECONDS)
                if pid is not None and now:
                    _kill(pid)
            if pid:
                with contextlib.suppress(ChildProcessError):
                    os.waitpid(pid, 0)
            conn.close()
        self.conns, self.pids, self.leaving = [], [], []
        self.slots, self.received = [], []
        if self.reaping:             # middle processes adopted after their parent was killed
            reap_strays(self.before)
            _subreaper(False)
            self.reaping = False

    def __enter__(self):
        return self

    def __exit__(self, kind, *exc) -> None:
        self.stop(now=kind is not None)


def _kill(pid: int) -> None:
    with contextlib.suppress(OSError):
        os.kill(pid, signal.SIGTERM)


def _read_pid(conn, wait: float) -> int | None:
    """The pid an adopted worker sends first, or None if its pipe closed (never forked)."""
    try:
        if conn.poll(wait):
            message = conn.recv()
            if message[0] == "pid":
                return message[1]
    except (EOFError, OSError):
        pass
    return None
