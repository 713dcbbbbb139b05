"""The ``gnibench`` console script: signal handlers first, then the command.

This module is what the script imports (``[project.scripts]``), and its first statements install
handlers for SIGINT and SIGTERM, before the command line's own imports: a signal that arrives
while they load is honoured too, also when the parent ignored SIGINT (background jobs of a
shell). :func:`gnibench.suite.cli.main.main` then installs the full handling
(:mod:`gnibench.suite.cli.process`). An interrupted command ends with ``os._exit`` once its
results are written and its streams flushed: the interpreter's teardown after a cold compile
takes seconds (numba and llvmlite objects), and that wait is not worth a user's Ctrl-C.
"""
import os
import signal
import sys

_received: list[int] = []


def _early(signum, frame):
    _received.append(signum)
    raise KeyboardInterrupt


for _s in (signal.SIGINT, signal.SIGTERM):
    signal.signal(_s, _early)


def _end(code: int) -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code)


def main() -> int:
    try:
        from gnibench.suite.cli.main import main as command
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
        code = 128 + (_received[-1] if _received else signal.SIGINT)
    if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        _end(code)
    return code


if __name__ == "__main__":
    sys.exit(main())
