"""The runner's local process pool: workers forked before the cells are prepared, that stay warm
and keep the kernels they loaded.

* **Ready early.** A fresh process pays about half a second before its first cell: numba and
  numba's CPU target (its typing and lowering registries); pandas it never needs (the samples
  travel as arrays, the parent makes the table). ``gnibench run`` starts the pool first thing
  (:func:`gnibench.suite.runs.executors.start`, before the experiment is read), and each worker
  pays that (:func:`preload`) while the parent reads the experiment, opens the store and groups
  the cells. Once the cells to compute are known the pool is fitted to them (:meth:`Pool.fit`:
  idle workers beyond their number end, more are forked when ``-j`` asks for more than the
  cores). The workers are children of the command, so a signal to it or its death ends them.
* **By kernel, longest first, one cell queued ahead.** Each worker has its own pipe and holds
  the cell it runs and the next one (while there are cells enough for all workers), so that it
  never waits for the parent (busy storing a result, or not scheduled on a loaded machine)
  between two cells. The first cell
  of a kernel group runs alone (it compiles the kernel into the disk cache); once it is done, the
  rest of the group goes preferably to the worker that ran it (the kernel is loaded there), a free
  worker takes a group not yet started (kernels compile in parallel), and only then helps with
  the largest group under way (it loads the kernel from the disk cache). Within a group the
  longest cells go first (:func:`longest_first`), so that short ones fill the end of the run.
* **Quiet workers** (:func:`gnibench.suite.foundation.processes.quiet_worker`): SIGINT ignored
  (Ctrl-C reaches the whole process group: the parent decides), SIGTERM ends them, they die with
  their parent. A worker reports the progress of a long cell through its pipe. When the run ends
  otherwise than by its last cell (Ctrl-C, SIGTERM, an error) the workers are terminated at once.
  A worker that dies (killed, out of memory) ends the run with one line naming the cell it was
  running (:class:`~gnibench.suite.foundation.outputs.Fault`); the cells stored so far stay.

Which worker runs a cell never changes its numbers: the tables are assembled in cell order.
"""
from __future__ import annotations

import contextlib
import os
import signal
from collections import deque

from gnibench.suite.foundation.outputs import Fault
from gnibench.suite.foundation.processes import quiet_worker

POLL_SECONDS = 0.2
AHEAD = 2                 # cells sent to a worker at a time: the one it runs and the next


def preload() -> None:
    """What the first cell of a fresh process would otherwise pay: the modules of a cell and the
    registries its records are looked up in, numba, and numba's CPU target (its typing and
    lowering registries, which import numpy's linear algebra support and scipy.linalg). Workers
    send their samples as arrays (``run_cell(frames=False)``): they never import pandas."""
    import gnibench.methods
    import gnibench.problems
    import gnibench.suite.cell.solve
    import gnibench.suite.metrics.compute
    import gnibench.suite.runs.cellwork
    import gnibench.suite.runs.tables  # noqa: F401
    from numba.core.registry import cpu_target

    cpu_target.typing_context.refresh()
    cpu_target.target_context.refresh()


def _serve(conn, others: list, parent: int) -> None:
    """A worker: cells in, ("o", outcome) and ("p", cell id, fraction done) out, until None."""
    quiet_worker(parent)
    for other in others:                  # the parent's ends of the workers forked before
        other.close()
    from gnibench.suite.runs.cellwork import install_reporter, run_cell

    def report(cell_id: int, fraction: float) -> None:
        with contextlib.suppress(Exception):          # progress is best effort
            conn.send(("p", cell_id, fraction))

    install_reporter(report)
    with contextlib.suppress(Exception):              # a failed preload: the first cell says why
        preload()
    while True:
        try:
            cell = conn.recv()
        except (EOFError, OSError):
            return
        if cell is None:
            return
        conn.send(("o", run_cell(cell, frames=False)))


def _fork(target, *args) -> int:
    """Fork a process that runs ``target(*args)`` and exits; its pid in the parent."""
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            target(*args)
            code = 0
        except BaseException:  # noqa: BLE001 - a bug: said, then the parent hears of the death
            import traceback

            with contextlib.suppress(Exception):
                traceback.print_exc()
        finally:
            os._exit(code)
    return pid


class Pool:
    """``workers`` worker processes forked from this one (see the module docstring)."""

    def __init__(self, workers: int):
        self.size = workers
        self.conns: list = []
        self.pids: list[int] = []
        self.plan, self.sent = None, {}

    def start(self) -> Pool:
        """Fork the workers missing to reach ``size`` (they preload at once)."""
        from multiprocessing import Pipe

        while len(self.conns) < self.size:
            conn, child = Pipe()
            self.pids.append(_fork(_serve, child, list(self.conns), os.getpid()))
            child.close()
            self.conns.append(conn)
        return self

    def fit(self, workers: int) -> Pool:
        """``workers`` workers from now on: the extra ones end (they are idle), missing ones are
        forked."""
        workers = max(0, workers)
        for conn, pid in zip(self.conns[workers:], self.pids[workers:]):
            _end(conn, pid)
        self.conns, self.pids = self.conns[:workers], self.pids[:workers]
        self.size = workers
        return self.start()

    def run(self, groups: list[list], progress=None):
        """Run the cells of ``groups`` (lists of cells sharing a kernel, in cell order): the first
        cells go to the workers now, and the iterator returned yields the outcomes as they
        finish; ``progress(cell_id, fraction)`` hears of long cells. If the caller stops early
        (an exception, Ctrl-C, ``close()``), the workers are terminated."""
        self.plan = Plan(groups)
        self.sent = {w: deque() for w in range(self.size)}     # worker -> its cells, in order
        try:
            self._top_up(0)
        except BaseException:
            self.stop(now=True)
            raise
        return self._outcomes(progress)

    def _outcomes(self, progress):
        from multiprocessing.connection import wait

        from gnibench.suite.runs.cellwork import with_frame

        try:
            while busy := [w for w, cells in self.sent.items() if cells]:
                for conn in wait([self.conns[w] for w in busy], timeout=POLL_SECONDS):
                    w = self.conns.index(conn)
                    try:
                        message = conn.recv()
                    except (EOFError, OSError):
                        raise self._died(w, self.sent[w][0]) from None
                    if message[0] == "p":
                        if progress is not None:
                            progress(message[1], message[2])
                        continue
                    self.plan.done(self.sent[w].popleft())
                    self._top_up(w)
                    yield with_frame(message[1])
        except BaseException:
            self.stop(now=True)
            raise

    def _top_up(self, first: int) -> None:
        """Give every worker (``first`` first) a cell to run and, while there are cells enough
        for all, one queued behind it (so that a worker never waits for this process between
        two cells; near the end the last cells go to whoever is free)."""
        for w in [first] + [v for v in range(self.size) if v != first]:
            cells = self.sent[w]
            while len(cells) < (AHEAD if self.plan.left >= self.size else 1):
                cell = self.plan.next_for(w)
                if cell is None:
                    break
                try:
                    self.conns[w].send(cell)
                except OSError:                       # it died while idle
                    raise self._died(w, cells[0] if cells else cell) from None
                cells.append(cell)

    def _died(self, w: int, cell) -> Fault:
        how = ""
        with contextlib.suppress(ChildProcessError, OSError):
            pid, status = os.waitpid(self.pids[w], 0)
            if pid and os.WIFSIGNALED(status):
                how = f" (signal {signal.Signals(os.WTERMSIG(status)).name})"
            elif pid and os.WIFEXITED(status):
                how = f" (exit code {os.WEXITSTATUS(status)})"
        return Fault(f"a worker of the pool died{how} while running cell {cell.id} "
                     f"({cell.problem} {cell.method}); the cells finished so far are stored: run "
                     f"the same command again to compute the rest")

    def stop(self, now: bool = False) -> None:
        """End the workers: ``now`` terminates them (Ctrl-C, an error), else they are told to end
        once idle."""
        for conn, pid in zip(self.conns, self.pids):
            if now:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGTERM)
            else:
                with contextlib.suppress(OSError, ValueError):
                    conn.send(None)
        for conn, pid in zip(self.conns, self.pids):
            with contextlib.suppress(ChildProcessError):
                os.waitpid(pid, 0)
            conn.close()
        self.conns, self.pids = [], []

    def __enter__(self):
        return self

    def __exit__(self, kind, *exc) -> None:
        self.stop(now=kind is not None)


def _end(conn, pid: int) -> None:
    """End an idle worker (it may still be preloading: terminated, not waited for)."""
    with contextlib.suppress(OSError):
        os.kill(pid, signal.SIGTERM)
    with contextlib.suppress(ChildProcessError):
        os.waitpid(pid, 0)
    conn.close()


def _planned_steps(cell) -> int:
    try:
        return int(cell.spec.nsteps)
    except Exception:  # noqa: BLE001 - an estimate only
        return 0


def longest_first(group: list) -> list:
    """A kernel group's cells, the longest first (so that short cells fill the end of the run):
    by planned steps (the cells of a group run one kernel: the same cost per step), ties (adaptive
    methods) in reverse cell order (a sweep lists its coarsest step or loosest tolerance first)."""
    backwards = list(reversed(group))               # sorted is stable: ties stay backwards
    return sorted(backwards, key=lambda c: -_planned_steps(c))


class Plan:
    """Which cell a free worker runs next (see the module docstring: kernel groups, affinity)."""

    def __init__(self, groups: list[list]):
        self.waiting = [deque(longest_first(g)) for g in groups if g]      # not started
        self.open: list[deque] = []                          # compiled, cells left
        self.compiling: dict[int, deque] = {}                # id(first cell) -> rest of its group
        self.home: dict[int, deque] = {}                     # worker -> the group it loaded
        self.left = sum(len(g) for g in groups)              # cells not handed out yet

    def next_for(self, w: int):
        cell = self._next_for(w)
        if cell is not None:
            self.left -= 1
        return cell

    def _next_for(self, w: int):
        group = self.home.get(w)
        if group:                                             # its kernel is loaded here
            return group.popleft()
        if self.waiting:                                      # compile another kernel
            group = self.waiting.pop(0)
            first = group.popleft()
            self.compiling[id(first)] = group
            self.home[w] = group
            return first
        self.open = [g for g in self.open if g]
        if self.open:                                         # help the largest group left
            group = max(self.open, key=len)
            self.home[w] = group
            return group.popleft()
        return None

    def done(self, cell) -> None:
        group = self.compiling.pop(id(cell), None)
        if group is not None and group:
            self.open.append(group)
