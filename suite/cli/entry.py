"""The ``gnibench`` console script: signal handlers first, then the command.

This module is what the script imports (``[project.scripts]``), and its first statements install
handlers for SIGINT and SIGTERM, before the command line's own imports: a signal that arrives
while they load is honoured too, also when the parent ignored SIGINT (background jobs of a
shell). :func:`gnibench.suite.cli.main.main` then installs the full handling
(:mod:`gnibench.suite.cli.process`). Every command ends with ``os._exit`` once it has returned
(its results written, its files closed, its pools and clusters stopped by their context managers)
and its streams are flushed: the interpreter's teardown costs 0.2-0.4 s after a warm run (pandas,
pyarrow, numba objects) and seconds after a cold compile, a wait not worth a user's time nor a
Ctrl-C (measured on a warm 16-cell ``gnibench run``: 6.3 s -> 6.0 s with ``-j 1``).
"""
import os
import signal
import sys

from gnibench.suite.foundation.guard import from_interrupt, signal_received

_received: list[int] = []


def _early(signum, frame):
    _received.append(signum)
    signal_received(signum)
    signals = sys.modules.get("gnibench.suite.cli.signals")   # loaded: the command's handling
    if signals is not None:                                   # ended, and its end reports this
        signals.note(signum)
    raise KeyboardInterrupt


for _s in (signal.SIGINT, signal.SIGTERM):
    signal.signal(_s, _early)

# A standard stream closed by the caller (``>&-``, ``2>&-``) is /dev/null at its descriptor: else
# the next file opened would get descriptor 1 or 2 and whatever writes there (numba, a worker)
# would write into a result file. Python has set sys.stdout or sys.stderr to None already, so a
# command still knows: stdout closed is refused (streams.py), stderr closed is silence.
for _fd, _mode in ((0, os.O_RDONLY), (1, os.O_WRONLY), (2, os.O_WRONLY)):
    try:
        os.fstat(_fd)
    except OSError:
        _null = os.open(os.devnull, _mode)
        if _null != _fd:
            os.dup2(_null, _fd)
            os.close(_null)
        os.set_inheritable(_fd, True)


def _end(code: int) -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):     # AttributeError: closed (None)
            pass
    os._exit(code)


def _last_signal() -> int:
    """The signal that ended the command: the one the command's own handlers saw last
    (:mod:`gnibench.suite.cli.signals`), else the one these early handlers saw, else SIGINT."""
    signals = sys.modules.get("gnibench.suite.cli.signals")
    seen = getattr(getattr(signals, "_state", None), "received", None)
    return seen or (_received[-1] if _received else signal.SIGINT)


def main() -> int:
    try:
        try:
            from gnibench.suite.cli.main import main as command
        except Exception as e:           # a C extension's init made the interrupt another error
            if _received and from_interrupt(e):     # (signals.py, "Turned into other errors")
                raise KeyboardInterrupt from None
            raise
    except KeyboardInterrupt:
        signum = _received[-1] if _received else signal.SIGINT
        print("gnibench: " + ("terminated" if signum == signal.SIGTERM else "interrupted"),
              file=sys.stderr)
        _end(128 + signum)
    try:
        if _received:                       # a signal in the last instructions of the imports
            _end(128 + _received[-1])
        code = command()
    except KeyboardInterrupt:               # a signal between the command's end and here
        code = 128 + _last_signal()
    _end(code)
    return code                             # not reached


if __name__ == "__main__":
    sys.exit(main())
