"""One guard around the user's code: whatever it raises becomes a cell's ``error``, except a real
interrupt of the process.

A Python step, a Python solver or an entry point may raise anything, ``BaseException``\\ s
included: ``sys.exit(3)`` (SystemExit) ended ``gnibench solve`` with exit code 3 and nothing
written, ended a ``run -j 1`` without its tables, and killed a pool worker so that the cell never
got a status and every rerun died the same way. :func:`user_code` turns SystemExit,
GeneratorExit, a KeyboardInterrupt the code raised itself and any Exception into
:class:`UserCodeError`, which the callers make an ``error`` status with the reason; the other
cells are unharmed.

A KeyboardInterrupt is a real interrupt (Ctrl-C, or SIGTERM, which gnibench's commands raise as
KeyboardInterrupt) when a signal came while the code ran: the command line's handlers count the
signals they receive (:func:`signal_received`). Where no gnibench handler watches the signals
(the Python API, a notebook) and Python's own SIGINT handler is in place, :func:`user_code`
installs for its duration one that counts and then does what Python's does, so that there too
a step's own KeyboardInterrupt is its error and Ctrl-C stops. Where SIGINT is ignored or not
delivered (any thread but the main one: a Dask worker's task, a thread of the user's) no
KeyboardInterrupt is a signal's; under a handler of someone else's, every one is taken for
Ctrl-C (it cannot be told apart).
"""
from __future__ import annotations

import contextlib
import signal
import threading


class UserCodeError(Exception):
    """The user's code failed (any exception or exit it raised); the message says how."""


_signals = [0]                  # real SIGINT/SIGTERM received by gnibench's handlers so far
_watched = [False]              # are gnibench's handlers installed in this process?
_last: list[int | None] = [None]   # the last of them (its number)


def signal_received(signum: int | None = None) -> None:
    """Called by gnibench's signal handlers for each SIGINT or SIGTERM they receive."""
    _signals[0] += 1
    if signum is not None:
        _last[0] = signum


def stopped_by() -> str:
    """How the last signal gnibench's handlers received stopped the work, in the words of the
    command's last line: "terminated" (SIGTERM) or "interrupted" (SIGINT, or none counted)."""
    return "terminated" if _last[0] == signal.SIGTERM else "interrupted"


def watch_signals(on: bool = True) -> None:
    """Say that gnibench's handlers count the signals of this process (:func:`signal_received`),
    or that they no longer do."""
    _watched[0] = on


def from_interrupt(e: BaseException) -> bool:
    """Was ``e`` raised while a KeyboardInterrupt propagated (one in its causes or contexts)?"""
    todo, seen = [e], set()
    while todo:
        x = todo.pop()
        if x is None or id(x) in seen:
            continue
        if isinstance(x, KeyboardInterrupt):
            return True
        seen.add(id(x))
        todo += [x.__cause__, x.__context__]
    return False


def _describe(e: BaseException) -> str:
    if isinstance(e, SystemExit):
        return f"SystemExit({e.code!r}) (the code called sys.exit)"
    text = " ".join(str(e).split())
    return f"{type(e).__name__}: {text}" if text else type(e).__name__


@contextlib.contextmanager
def user_code(what):
    """Run the body as the user's code ``what`` (a text, e.g. ``"mymod:step"``, or a function
    returning it, called only on failure, e.g. to name the step reached): any exception or exit
    it raises becomes :class:`UserCodeError` naming ``what``; a real interrupt of the process is
    raised as it came."""
    before = _signals[0]
    with _counted() as counted:
        try:
            yield
        except KeyboardInterrupt as e:
            if not counted or _signals[0] != before:
                raise                           # Ctrl-C or SIGTERM: the command stops
            raise UserCodeError(f"{_name(what)}: {_describe(e)} raised by the code itself"
                                ) from None
        except (Exception, SystemExit, GeneratorExit) as e:  # noqa: BLE001 - the user's code
            raise UserCodeError(f"{_name(what)}: {_describe(e)}") from None


def _interrupt(signum, frame):
    """Python's SIGINT handler, counting the signal first (:func:`user_code` in the API)."""
    signal_received(signum)
    signal.default_int_handler(signum, frame)


@contextlib.contextmanager
def _counted():
    """Whether the signals that could raise KeyboardInterrupt here are counted (see the module
    docstring); installs :func:`_interrupt` for the block in place of Python's own handler."""
    if _watched[0] or threading.current_thread() is not threading.main_thread():
        yield True
        return
    handler = signal.getsignal(signal.SIGINT)
    if handler is not signal.default_int_handler:
        yield handler in (_interrupt, signal.SIG_IGN, signal.SIG_DFL)
        return
    signal.signal(signal.SIGINT, _interrupt)
    try:
        yield True
    finally:
        signal.signal(signal.SIGINT, handler)


def _name(what) -> str:
    return what() if callable(what) else str(what)
