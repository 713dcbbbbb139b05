"""The lock of a results directory: one run at a time, and a lock whose owner is gone is taken over.

``<out>/.lock`` is held with ``flock`` by the run using the directory and holds ``pid N`` while it
does; a run that ends cleanly empties it. The kernel releases a flock when the last file
descriptor of its open file description is closed, so a run killed with ``kill -9`` leaves no
lock behind, provided no other process shares that descriptor: a forked child (a worker of the
local process pool) would inherit it and hold the lock for as long as it lives. So the
descriptor is pointed at /dev/null in every child forked while the lock is held
(``os.register_at_fork``), and a pool worker dies with its parent
(:mod:`gnibench.suite.runs.executors`).

A run that finds ``pid N`` in a lock it could take says so in one line: the run of pid N ended
without unlocking (it was killed), and its lock is taken over. A run that cannot take the lock
names who holds it: the running gnibench, or the processes that outlived it (found in /proc).
The lock file is opened without following a symlink, and a ``.lock`` that is a directory, a
FIFO, a socket or a device is removed with one warning line.
"""
from __future__ import annotations

import contextlib
import fcntl
import os
import re
import shutil
import stat
from pathlib import Path

from gnibench.suite.foundation.cache import warn
from gnibench.suite.foundation.errors import UserError, named

_held: set[int] = set()            # descriptors of the locks this process holds


def _forget_in_child() -> None:
    """In a forked child: drop the inherited lock descriptors (without unlocking the parent's)."""
    if not _held:
        return
    with contextlib.suppress(OSError):
        null = os.open(os.devnull, os.O_RDWR)
        for fd in _held:
            with contextlib.suppress(OSError):
                os.dup2(null, fd)
        os.close(null)
    _held.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_in_child)


def _special(path: Path) -> str | None:
    """What ``path`` is when it is neither absent, a regular file, a directory nor a symlink (a
    FIFO, a socket, a device: a flock on it cannot be kept, or opening it blocks or fails)."""
    from gnibench.suite.foundation.outputs import kind

    try:
        mode = os.lstat(path).st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode) or stat.S_ISLNK(mode):
        return None
    return kind(mode)


def _open(path: Path) -> int:
    flags = (os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
             | os.O_NONBLOCK)
    for _ in range(2):
        special = _special(path)
        if special:
            warn(f"{path} is {special}, not a lock file; removed")
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
        try:
            return os.open(path, flags, 0o644)
        except IsADirectoryError:
            warn(f"{path} is a directory, not a lock file; removed")
            shutil.rmtree(path, ignore_errors=True)
        except OSError as e:
            if not path.is_symlink():
                raise UserError(f"bad {named('-o', str(path.parent))}: cannot open {path.name} "
                                f"({e.strerror})") from None
            warn(f"{path} is a symlink, not a lock file; removed")
            path.unlink()
    raise UserError(f"bad {named('-o', str(path.parent))}: {path.name} cannot be made a lock file")


def _pid(text: str) -> int | None:
    m = re.fullmatch(r"pid (\d+)", text.strip())
    return int(m.group(1)) if m else None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def holders(path: Path) -> list[int]:
    """Processes with ``path`` open (Linux: /proc/*/fd), other than this one."""
    try:
        target = path.stat()
    except OSError:
        return []
    found = []
    for proc in Path("/proc").glob("[0-9]*"):
        if int(proc.name) == os.getpid():
            continue
        with contextlib.suppress(OSError):
            for fd in (proc / "fd").iterdir():
                with contextlib.suppress(OSError):
                    st = fd.stat()
                    if (st.st_dev, st.st_ino) == (target.st_dev, target.st_ino):
                        found.append(int(proc.name))
                        break
    return sorted(found)


class DirectoryLock:
    """The flock on ``<out>/.lock`` (see the module docstring)."""

    def __init__(self, out: Path):
        self.path = Path(out) / ".lock"
        self.fd: int | None = None

    def acquire(self) -> None:
        fd = _open(self.path)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            previous = _read(fd)
            os.close(fd)
            raise UserError(self._busy(_pid(previous))) from None
        previous = _pid(_read(fd))
        if previous is not None and previous != os.getpid():
            warn(f"results directory {self.path.parent} was left locked by pid {previous}, which "
                 f"is gone (killed?); lock taken over")
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()}\n".encode(), 0)
        self.fd = fd
        _held.add(fd)

    def _busy(self, pid: int | None) -> str:
        where = f"results directory {self.path.parent}"
        if pid is not None and not _alive(pid):
            others = holders(self.path)
            listed = " ".join(map(str, others)) or "unknown"
            return (f"{where} is locked by processes that outlived gnibench run pid {pid} "
                    f"(pids {listed}); stop them (kill {listed}) or use another -o")
        holder = f"pid {pid}" if pid is not None else "another process"
        return (f"{where} is in use by another gnibench run ({holder}); wait for it to finish "
                f"or use another -o")

    def release(self) -> None:
        if self.fd is None:
            return
        _held.discard(self.fd)
        with contextlib.suppress(OSError):
            os.ftruncate(self.fd, 0)            # a clean end: nothing to take over next time
        with contextlib.suppress(OSError):
            fcntl.flock(self.fd, fcntl.LOCK_UN)
        os.close(self.fd)
        self.fd = None


def clear_held() -> None:
    """Empty the locks this process holds, as it ends at once (``os._exit`` after a signal that
    could not be raised, :mod:`gnibench.suite.cli.signals`): an orderly end, which the next run
    must not take for a killed one. The flocks go with the process."""
    for fd in list(_held):
        with contextlib.suppress(OSError):
            os.ftruncate(fd, 0)


def _read(fd: int) -> str:
    try:
        return os.pread(fd, 200, 0).decode(errors="replace")
    except OSError:
        return ""
