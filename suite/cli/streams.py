"""Standard streams that may close under a command.

Writes to a closed stdout (``gnibench list methods | head -1``) or stderr are dropped silently and
never stop the command: progress goes to stderr, results to stdout, and a reader that stopped
reading does not end a run. A stdout that fails otherwise (``> /dev/full``: ENOSPC) is a
:class:`~gnibench.suite.foundation.outputs.Fault` (one line, exit 1).
"""
from __future__ import annotations

import contextlib
import errno
import os
import sys

from gnibench.suite.foundation.outputs import Fault

CLOSED = (errno.EPIPE, errno.EIO, errno.ECONNRESET)


class _Stream:
    """A text stream whose writes never end the command when the reader has gone."""

    def __init__(self, stream, name: str):
        self._stream, self._name, self.closed_by_reader = stream, name, False

    def __getattr__(self, attr):
        return getattr(self._stream, attr)

    def _failed(self, e: Exception) -> None:
        if self._name == "stdout" and not isinstance(e, ValueError) \
                and getattr(e, "errno", None) not in CLOSED:
            raise Fault(f"writing to stdout failed: {getattr(e, 'strerror', None) or e}") from None
        self.closed_by_reader = True           # stderr: nowhere left to report a failure to
        _silence(self._stream)

    def write(self, text):
        if self._stream is None:            # closed before the command started (``>&-``)
            return self._none(text)
        if self.closed_by_reader:
            return len(text)
        try:
            return self._stream.write(text)
        except UnicodeEncodeError:         # an ASCII terminal: µ, §, θ as escapes, not a crash
            encoding = getattr(self._stream, "encoding", None) or "ascii"
            return self.write(text.encode(encoding, "backslashreplace").decode(encoding))
        except (OSError, ValueError) as e:
            self._failed(e)
            return len(text)

    def writelines(self, lines):
        for line in lines:
            self.write(line)

    def _none(self, text):
        if self._name == "stdout" and text:
            raise Fault("writing to stdout failed: it is closed; allowed: an open stdout, or -o "
                        "FILE where the command has one")
        return len(text)

    def flush(self):
        if self.closed_by_reader or self._stream is None:
            return
        try:
            self._stream.flush()
        except (OSError, ValueError) as e:
            self._failed(e)


def _silence(stream) -> None:
    """Point the stream's file descriptor at /dev/null, so that what is still buffered (flushed at
    exit) goes nowhere instead of failing again."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        fd = stream.fileno()
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, fd)
        os.close(null)


def stdout_closed() -> bool:
    """Was stdout closed before the command started (``gnibench ... >&-``)?"""
    return isinstance(sys.stdout, _Stream) and sys.stdout._stream is None


@contextlib.contextmanager
def tolerant():
    """stdout and stderr wrapped for the duration of a command (see the module docstring)."""
    saved = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _Stream(sys.stdout, "stdout"), _Stream(sys.stderr, "stderr")
    try:
        yield
    finally:
        sys.stdout, sys.stderr = saved
