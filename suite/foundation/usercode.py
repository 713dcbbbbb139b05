"""The one guard around the user's code: Python steps and solvers, the modules that define them,
entry points.

User code may end the process on its own: ``sys.exit(3)`` raises ``SystemExit``, a bare
``raise KeyboardInterrupt`` looks like Ctrl-C, ``GeneratorExit`` escapes ``except Exception``.
None of them is an ``Exception``, so a cell's ``except Exception`` let them through: ``gnibench
solve`` exited 3 with nothing written, ``gnibench run -j 1`` lost its tables, a pool worker died
and the cell never got a status, so every rerun died the same way. Under the guard every
``BaseException`` raised by user code is a failure of that code (status ``error``, with the
reason), except a real interrupt of the process: a ``KeyboardInterrupt`` raised by a signal
handler while the guard was open.

How a real interrupt is told apart: gnibench's command-line handlers (SIGINT, SIGTERM) count the
signals they receive (:func:`note_signal`); where Python's default SIGINT handler is installed
(the Python API, a notebook), :func:`guarded` installs for its duration one that counts and then
does the same. A ``KeyboardInterrupt`` is real when the count grew since the guard opened. Where
SIGINT is ignored (a pool worker) or not delivered (any thread but the main one, a Dask worker's
task), no ``KeyboardInterrupt`` is real; under a handler of someone else's, every one is taken as
real (it cannot be told apart).
"""
from __future__ import annotations

import contextlib
import signal
import threading

_count = [0]


def note_signal() -> None:
    """Called by a signal handler that raises KeyboardInterrupt: one more real interrupt."""
    _count[0] += 1


def _counting(signum, frame):
    note_signal()
    signal.default_int_handler(signum, frame)


_counting.counts_signals = True


class Guard:
    """An open guard: :meth:`real` tells a real interrupt from user code's, :meth:`reason` says
    what user code raised in one line."""

    def __init__(self, counted: bool):
        self.counted, self.start = counted, _count[0]

    def real(self, error: BaseException) -> bool:
        """Whether ``error`` is a real interrupt of the process (to be raised on, not recorded)."""
        if not isinstance(error, KeyboardInterrupt):
            return False
        if threading.current_thread() is not threading.main_thread():
            return False                   # signals are handled in the main thread only
        return not self.counted or _count[0] > self.start

    @staticmethod
    def reason(error: BaseException) -> str:
        """``Type: message`` on one line (``SystemExit: sys.exit(3)`` for an exit)."""
        if isinstance(error, SystemExit):
            text = f"sys.exit({error.code!r}) (user code may not end the process)"
        else:
            text = str(error)
        line = f"{type(error).__name__}: {text}" if text else type(error).__name__
        line = line.replace("\r", " ").replace("\n", " ")
        return line if len(line) <= 1000 else line[:997] + "..."


@contextlib.contextmanager
def guarded():
    """A :class:`Guard` for the user code run inside (see the module docstring)."""
    if threading.current_thread() is not threading.main_thread():
        yield Guard(True)
        return
    handler = signal.getsignal(signal.SIGINT)
    if handler is signal.default_int_handler:
        signal.signal(signal.SIGINT, _counting)
        try:
            yield Guard(True)
        finally:
            with contextlib.suppress(ValueError):
                signal.signal(signal.SIGINT, handler)
        return
    counted = handler in (signal.SIG_IGN, signal.SIG_DFL, None) or \
        getattr(handler, "counts_signals", False)
    yield Guard(counted)


def run_user_code(call, *args, **kwargs):
    """``call(*args, **kwargs)`` under a guard: any BaseException it raises but a real interrupt
    is raised again as a :class:`UserCodeFailed` (an ``Exception``) whose message is the
    reason."""
    with guarded() as guard:
        try:
            return call(*args, **kwargs)
        except BaseException as e:
            if guard.real(e) or isinstance(e, UserCodeFailed):
                raise
            raise UserCodeFailed(guard.reason(e)) from None


class UserCodeFailed(Exception):
    """User code raised (anything, ``SystemExit`` included); the message is the reason."""
