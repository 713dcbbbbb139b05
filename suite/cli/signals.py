"""SIGINT and SIGTERM, honoured from the start of a command to its end.

Handlers. :func:`handling` installs handlers for SIGINT and SIGTERM (the console script installs
simpler ones even earlier, :mod:`gnibench.suite.cli.entry`), also when the parent ignored SIGINT:
a shell starts background jobs (``gnibench ... &``) with SIGINT ignored and Python keeps an
inherited SIG_IGN, so ``kill -INT`` was lost. Both signals raise KeyboardInterrupt in the main
thread, so every ``except KeyboardInterrupt`` path (a solve writes its samples so far, a run
stores its tables) serves both; the exit code is 128 + the signal (130, 143).

Where an interrupt is not raised. Python runs a handler between bytecodes of the main thread,
wherever that is, and an exception raised in a ctypes callback, a ``__del__`` or a weakref
callback is printed and dropped ("Exception ignored ..."). numba's compiler runs llvmlite's
ctypes callbacks: a Ctrl-C during a cold compile was swallowed there, the compile went on (or
failed later with numba's state half-updated) and the integration ran for hours. So the handler
does not raise while the main thread is inside numba or llvmlite (it marks the signal pending),
a KeyboardInterrupt dropped anywhere else marks it pending too (``sys.unraisablehook``), and a
watchdog thread delivers a pending signal again every ``POLL`` seconds: the handler, which
Python gives the main thread's frame, raises it once that frame is back in our own code (no
other thread's frames are inspected).

Late. The watchdog also sleeps on the signal wakeup fd, which the C-level handler writes at
once: when a signal has not been raised in the main thread ``GRACE`` seconds after it came (a
long compile, or a long C call holding the main thread), it ends the process with one line and
the same exit code. Nothing finished is lost: every result file and stored cell is committed by
an atomic rename (a temporary file may remain, removed by the next run), pool workers die
with their parent (:mod:`gnibench.suite.runs.executors`), and a results directory's lock is
emptied as on a clean end (the next run took the hard exit for a killed run and said so).

Turned into other errors. A C extension's module init that a KeyboardInterrupt interrupts
returns an error the interpreter reports as ``SystemError: ... returned a result with an
exception set`` (seen when a signal came while pandas was first imported, to write a run's
tables: a traceback and exit code 1). An exception that ends the command with a KeyboardInterrupt
in its chain after a signal came is that signal (:func:`handling`; the console script does the
same during its imports).

Forks. A forked child inherits the C-level handler and the wakeup fd: a signal that reaches it
before its after-fork hook has reset them is written into the parent's pipe, and the parent's
watchdog, seeing a signal its own main thread never raises, ends the parent after GRACE (seen:
a report drawing process forked by multiprocessing and terminated at once, because the run
failed on a locked directory, ended the parent with exit code 143). So, while a command runs,
SIGINT and SIGTERM are blocked in the forking thread across every ``os.fork`` (the parent's mask
is restored after it) and in the child until its hook has reset the wakeup fd and the
dispositions; a signal sent meanwhile stays pending and then acts on the child alone.
"""
from __future__ import annotations

import contextlib
import os
import select
import signal
import sys
import threading
import time

from gnibench.suite.foundation.guard import from_interrupt, signal_received, watch_signals

GRACE = 1.0                 # seconds the main thread has to raise a signal before a hard exit
POLL = 0.02                 # how often the watchdog looks while a signal is pending
SIGNALS = (signal.SIGINT, signal.SIGTERM)
NAMES = {signal.SIGINT: "interrupted", signal.SIGTERM: "terminated"}
UNSAFE = ("numba", "llvmlite")     # packages in which an exception may be dropped


class _State:
    def __init__(self):
        self.received: int | None = None        # the last signal (its number)
        self.raised_at = -1e300                 # when the handler last raised (monotonic)
        self.pending: int | None = None         # a signal to raise again in our own code
        self.origin: float | None = None        # since when a signal waits to be raised
        self.lock = threading.Lock()
        self.active = False
        self.stop = threading.Event()
        self.previous_unraisable = None
        self.fds: tuple[int, int] | None = None  # the wakeup pipe (read end, write end)


_state = _State()


def note(signum: int) -> None:
    """Record a signal received by another handler of ours: the console script's early ones
    (:mod:`gnibench.suite.cli.entry`), back in place when a command's handling has ended, so that
    a signal then is still named rightly (a SIGTERM there gave "interrupted", exit code 130)."""
    _state.received = signum


def exit_code(default: int = 130) -> int:
    return 128 + _state.received if _state.received else default


def message() -> str:
    return NAMES.get(_state.received, "interrupted")


def _unsafe(frame) -> bool:
    """Is this frame, or a caller of it, in numba or llvmlite?"""
    depth = 0
    while frame is not None and depth < 400:
        name = frame.f_globals.get("__name__", "")
        if name.partition(".")[0] in UNSAFE:
            return True
        frame, depth = frame.f_back, depth + 1
    return False


def _handler(signum, frame):
    signal_received(signum)             # a real interrupt, not one the user's code raised
    now = time.monotonic()
    with _state.lock:
        _state.received = signum
        if _unsafe(frame):
            _state.pending = signum
            _state.origin = _state.origin or now
            return
        _state.pending, _state.origin = None, None
        _state.raised_at = now
    raise KeyboardInterrupt


def _unraisable(unraisable) -> None:
    if issubclass(unraisable.exc_type, KeyboardInterrupt) and _state.received:
        with _state.lock:                       # dropped: raise it again where it can propagate
            _state.pending = _state.received
            _state.origin = _state.origin or _state.raised_at
        return
    previous = _state.previous_unraisable or sys.__unraisablehook__
    previous(unraisable)


def quiet() -> None:
    """After an interrupt: no 'Exception ignored in ...' tracebacks from objects half-built when
    it came (restored when the command ends)."""
    sys.unraisablehook = lambda unraisable: None


def _hard_exit(signum: int) -> None:
    lock = sys.modules.get("gnibench.suite.runs.lock")      # loaded when a run holds one
    if lock is not None:
        lock.clear_held()
    with contextlib.suppress(OSError):
        os.write(2, f"gnibench: {NAMES.get(signum, 'interrupted')} (while compiling or in compiled "
                    f"code; what was finished is kept)\n".encode())
    os._exit(128 + signum)


def _watch(read_fd: int) -> None:
    """Deliver pending signals again; hard exit when one is not raised within GRACE seconds.
    The thread owns ``read_fd`` and closes it when it ends: closed by another thread while this
    one waits on it, its number could be given to a new file that this thread would then read."""
    try:
        _watch_fd(read_fd)
    finally:
        with contextlib.suppress(OSError):
            os.close(read_fd)


def _watch_fd(read_fd: int) -> None:
    came: tuple[int, float] | None = None       # a signal the handler has not raised yet
    while not _state.stop.is_set():
        waiting = came is not None or _state.pending is not None
        ready, _, _ = select.select([read_fd], [], [], POLL if waiting else None)
        now = time.monotonic()
        if ready:
            data = os.read(read_fd, 64)
            if not data:
                return
            got = [b for b in data if b in SIGNALS]
            if got and came is None:
                came = (got[-1], now)
        with _state.lock:
            if not _state.active:
                return
            if came is not None and _state.raised_at >= came[1] - GRACE:
                came = None                      # raised (just before this thread woke, maybe)
            signum, origin = _state.pending, _state.origin
        if signum is not None:
            if now - origin > GRACE:
                _hard_exit(signum)
            # delivered again; the handler, given the main thread's frame, raises only outside
            # numba and llvmlite and marks it pending again inside them (origin kept)
            with _state.lock:
                _state.pending = None
            came = (signum, now)
            signal.pthread_kill(threading.main_thread().ident, signum)
            continue
        if came is not None and now - came[1] > GRACE:
            _hard_exit(came[0])


_fork_masks = threading.local()       # the forking thread's signal mask before the fork


def _before_fork() -> None:
    _fork_masks.mask = (signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS) if _state.active
                        else None)


def _after_fork_in_parent() -> None:
    mask, _fork_masks.mask = getattr(_fork_masks, "mask", None), None
    if mask is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def _after_fork_in_child() -> None:
    """A forked child (a pool worker) must not write into its parent's wakeup pipe, nor act on
    the parent's handlers: the default dispositions until the worker sets its own; then the mask
    it had before the fork (see "Forks" in the module docstring)."""
    mask, _fork_masks.mask = getattr(_fork_masks, "mask", None), None
    try:
        _reset_in_child()
    finally:
        if mask is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def _reset_in_child() -> None:
    if not _state.active:
        return
    _state.active = False
    with contextlib.suppress(ValueError, OSError):
        signal.set_wakeup_fd(-1)
    for fd in _state.fds or ():                # the parent's pipe: its watchdog sees EOF at once
        with contextlib.suppress(OSError):
            os.close(fd)
    _state.fds = None
    for s in SIGNALS:
        with contextlib.suppress(ValueError, OSError):
            signal.signal(s, signal.SIG_DFL)


if hasattr(os, "register_at_fork"):
    os.register_at_fork(before=_before_fork, after_in_parent=_after_fork_in_parent,
                        after_in_child=_after_fork_in_child)


@contextlib.contextmanager
def handling():
    """The handlers and the watchdog for the duration of a command (only in the main thread; the
    previous handlers are restored afterwards)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _state.received, _state.raised_at, _state.pending, _state.origin = None, -1e300, None, None
    _state.stop.clear()
    previous = {s: signal.signal(s, _handler) for s in SIGNALS}
    watch_signals(True)
    _state.previous_unraisable, sys.unraisablehook = sys.unraisablehook, _unraisable
    read_fd, write_fd = os.pipe()
    os.set_blocking(write_fd, False)
    old_wakeup = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
    _state.fds = (read_fd, write_fd)
    _state.active = True
    watcher = threading.Thread(target=_watch, args=(read_fd,), name="gnibench-signals",
                               daemon=True)
    watcher.start()
    try:
        yield
    except Exception as e:
        if _state.received and from_interrupt(e):     # see "Turned into other errors"
            raise KeyboardInterrupt from None
        raise
    finally:
        with _state.lock:
            _state.active = False
            late, _state.pending = _state.pending, None
        _state.stop.set()
        sys.unraisablehook = _state.previous_unraisable
        signal.set_wakeup_fd(old_wakeup)
        for s, h in previous.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)
        watch_signals(False)
        _state.fds = None
        os.close(write_fd)                     # the watchdog reads EOF, ends, closes read_fd
        watcher.join(timeout=5)
    if late is not None:
        # a signal marked pending (it came inside numba, or its KeyboardInterrupt was dropped in
        # a __del__) and the command's work ended before the watchdog raised it again: it is
        # honoured now, not lost (seen under load: a SIGTERM to a pool run gave exit code 0)
        raise KeyboardInterrupt
