"""The runner's local process pool: workers that get ready while the cells are prepared, stay
warm, and keep the kernels they loaded.

* **Ready early.** A fresh process pays about half a second before its first cell: numba and
  numba's CPU target (its typing and lowering registries); pandas it never needs (the samples
  travel as arrays, the parent makes the table). :meth:`Pool.start` forks the
  workers as soon as the experiment is valid, and each pays that (:func:`preload`) while the
  parent opens the store and groups the cells. ``gnibench run`` does better: its first act is to
  fork a :class:`Zygote`, a process that imports all that while the command imports the runner
  and reads the experiment, and then forks the workers from itself, ready at once (Linux).
* **One cell at a time per worker, by kernel, longest first.** Each worker has its own pipe and
  gets its next cell the moment it sends a result (before the parent stores it). The first cell
  of a kernel group runs alone (it compiles the kernel into the disk cache); once it is done, the
  rest of the group goes preferably to the worker that ran it (the kernel is loaded there), a free
  worker takes a group not yet started (kernels compile in parallel), and only then helps with
  the largest group under way (it loads the kernel from the disk cache). Within a group the
  longest cells go first (:func:`longest_first`), so that short ones fill the end of the run.
* **Quiet workers.** Workers ignore SIGINT (Ctrl-C reaches the whole process group: the parent
  decides), end on SIGTERM and die with their parent; a worker reports the progress of a long
  cell through its pipe. A worker that dies (killed, out of memory) fails the run with the cell it
  was running.

Which worker runs a cell never changes its numbers: the tables are assembled in cell order.
"""
from __future__ import annotations

import contextlib
import os
import signal
import socket
from collections import deque

POLL_SECONDS = 0.2


def _quiet(parent: int) -> None:
    """A worker's first act: SIGINT is the parent's business, SIGTERM ends it, and it dies with
    its parent (Linux: PR_SET_PDEATHSIG)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(os, "sched_getaffinity"):
        import ctypes

        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:
        os._exit(1)


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


def _serve(conn, parent: int) -> None:
    """A worker: cells in, ("o", outcome) and ("p", cell id, fraction done) out, until None."""
    from gnibench.suite.runs.cellwork import install_reporter, run_cell

    _quiet(parent)

    def report(cell_id: int, fraction: float) -> None:
        with contextlib.suppress(Exception):          # progress is best effort
            conn.send(("p", cell_id, fraction))

    install_reporter(report)
    with contextlib.suppress(Exception):
        preload()
    while True:
        try:
            cell = conn.recv()
        except (EOFError, OSError):
            return
        if cell is None:
            return
        conn.send(("o", run_cell(cell, frames=False)))


def _child(target, *args) -> int:
    """Fork a process that runs ``target(*args)`` and exits; its pid in the parent."""
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            target(*args)
            code = 0
        except Exception:  # noqa: BLE001 - a bug: said, then the parent hears of the death
            import traceback

            traceback.print_exc()
        finally:
            os._exit(code)
    return pid


class Zygote:
    """A process forked first thing that preloads (:func:`preload`) while its parent goes on, then
    forks ready workers from itself on request (:meth:`workers`); Linux only (it passes the
    workers' pipes by file descriptor)."""

    def __init__(self):
        self.pid, self.sock, self.forked = None, None, False

    @staticmethod
    def available() -> bool:
        return hasattr(os, "fork") and hasattr(socket, "send_fds") and \
            hasattr(os, "sched_getaffinity")

    def start(self) -> Zygote:
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.pid = _child(_zygote, theirs, ours, os.getpid())
        theirs.close()
        self.sock = ours
        return self

    def workers(self, n: int) -> list:
        """``n`` worker connections (the workers are forked once the zygote is ready)."""
        from multiprocessing import Pipe

        pairs = [Pipe() for _ in range(n)]
        socket.send_fds(self.sock, [b"fork"], [child.fileno() for _, child in pairs])
        self.forked = True
        for _, child in pairs:
            child.close()
        return [conn for conn, _ in pairs]

    def stop(self, now: bool = False) -> None:
        if self.pid is None:
            return
        with contextlib.suppress(OSError):
            if now or not self.forked:                  # it may be preloading: no need to wait
                os.kill(self.pid, signal.SIGTERM)       # its workers die with it (PDEATHSIG)
            else:
                self.sock.send(b"stop")
        with contextlib.suppress(ChildProcessError):
            os.waitpid(self.pid, 0)
        self.sock.close()
        self.pid = self.sock = None

    def __enter__(self):
        return self

    def __exit__(self, kind, *exc) -> None:
        self.stop(now=kind is not None)


def _zygote(sock, other, parent: int) -> None:
    from multiprocessing.connection import Connection

    other.close()
    _quiet(parent)
    with contextlib.suppress(Exception):
        preload()
    children = []
    while True:
        try:
            message, fds, _, _ = socket.recv_fds(sock, 16, 256)
        except OSError:
            break
        if message != b"fork":
            break
        children += [_child(_worker_of_fd, fd, fds, sock, Connection) for fd in fds]
        for fd in fds:
            os.close(fd)
    for pid in children:                # the workers end when their pipes close or say so
        with contextlib.suppress(ChildProcessError):
            os.waitpid(pid, 0)


def _worker_of_pipe(conn, others: list, parent: int) -> None:
    for other in others:                  # the parent's ends of the workers forked before
        other.close()
    _serve(conn, parent)


def _worker_of_fd(fd: int, fds, sock, connection) -> None:
    sock.close()
    for other in fds:
        if other != fd:
            with contextlib.suppress(OSError):
                os.close(other)
    _serve(connection(fd), os.getppid())


class Pool:
    """``workers`` worker processes (see the module docstring), forked by ``zygote`` if one is
    given, else from this process."""

    def __init__(self, workers: int, zygote: Zygote | None = None):
        self.size, self.zygote = workers, zygote
        self.conns: list = []
        self.pids: list[int] = []
        self.used: set[int] = set()

    def start(self) -> Pool:
        if self.zygote is not None:
            self.conns = self.zygote.workers(self.size)
            return self
        from multiprocessing import Pipe

        for _ in range(self.size):
            conn, child = Pipe()
            self.pids.append(_child(_worker_of_pipe, child, list(self.conns), os.getpid()))
            child.close()
            self.conns.append(conn)
        return self

    def run(self, groups: list[list], progress=None):
        """Run the cells of ``groups`` (lists of cells sharing a kernel, in cell order) and yield
        their outcomes as they finish; ``progress(cell_id, fraction)`` hears of long cells."""
        from multiprocessing.connection import wait

        from gnibench.suite.runs.cellwork import with_frame

        plan = Plan(groups)
        running: dict[int, object] = {}          # worker -> its cell
        for w in range(self.size):
            self._feed(w, plan, running)
        while running:
            for conn in wait([self.conns[w] for w in running], timeout=POLL_SECONDS):
                w = self.conns.index(conn)
                cell = running[w]
                try:
                    message = conn.recv()
                except (EOFError, OSError):
                    raise RuntimeError(f"a worker of the pool died while running cell {cell.id} "
                                       f"({cell.problem} {cell.method})") from None
                if message[0] == "p":
                    if progress is not None:
                        progress(message[1], message[2])
                    continue
                del running[w]
                plan.done(cell)
                for v in [w] + [v for v in range(self.size) if v != w]:
                    if v not in running:
                        self._feed(v, plan, running)
                yield with_frame(message[1])

    def _feed(self, w: int, plan: Plan, running: dict) -> None:
        cell = plan.next_for(w)
        if cell is not None:
            self.conns[w].send(cell)
            running[w] = cell
            self.used.add(w)

    def stop(self, now: bool = False) -> None:
        """Let the workers end (``now``: terminate them, e.g. on Ctrl-C or an error; a worker
        that never got a cell is terminated too: it may still be preloading)."""
        for w, conn in enumerate(self.conns):
            if not now and w in self.used:
                with contextlib.suppress(OSError, ValueError):
                    conn.send(None)
        for w, pid in enumerate(self.pids):
            if now or w not in self.used:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGTERM)
        for pid in self.pids:
            with contextlib.suppress(ChildProcessError):
                os.waitpid(pid, 0)
        for conn in self.conns:
            conn.close()                        # a zygote's idle workers end on this
        if now and self.zygote is not None:
            self.zygote.stop(now=True)
        self.conns, self.pids = [], []

    def __enter__(self):
        return self

    def __exit__(self, kind, *exc) -> None:
        self.stop(now=kind is not None)


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

    def next_for(self, w: int):
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
