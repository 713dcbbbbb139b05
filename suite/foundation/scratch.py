"""Scratch directories of the Python API: where ``gnibench.run`` and ``gnibench.verify`` write
when no ``output`` is given.

A scratch directory lies in the kernel cache's ``scratch/`` folder, named by its kind, host and
process (``verify-<host>-<pid>-<random>``), and is removed when the call ends, also by an
exception or Ctrl-C. A process that is killed (SIGTERM without a handler, SIGKILL, a power cut)
cannot remove it: the next scratch directory made on the same host removes those whose process
is gone, so none outlives the next call (a directory of a process that is alive is never
touched; one of another host is left to that host).
"""
from __future__ import annotations

import contextlib
import os
import shutil
import socket
import tempfile
from collections.abc import Iterator
from pathlib import Path

from gnibench.suite.foundation.cache import cache_dir


def _host() -> str:
    return "".join(c if c.isalnum() else "_" for c in socket.gethostname())[:40] or "host"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:            # another user's process
        return True
    return True


def sweep(root: Path) -> list[Path]:
    """Remove the scratch directories of this host whose process has ended; the removed ones."""
    host, gone = _host(), []
    for d in root.iterdir():
        parts = d.name.split("-")
        if len(parts) < 4 or parts[1] != host or not parts[2].isdigit():
            continue
        pid = int(parts[2])
        if pid != os.getpid() and not _alive(pid):
            shutil.rmtree(d, ignore_errors=True)
            gone.append(d)
    return gone


@contextlib.contextmanager
def scratch_dir(kind: str) -> Iterator[Path]:
    """A new scratch directory for ``kind`` (``run``, ``verify``), removed on exit; those left
    by ended processes of this host are removed first."""
    root = cache_dir("scratch")
    sweep(root)
    d = Path(tempfile.mkdtemp(prefix=f"{kind}-{_host()}-{os.getpid()}-", dir=root))
    try:
        yield d
    finally:
        shutil.rmtree(d, ignore_errors=True)
