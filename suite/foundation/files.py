"""Reading the files gnibench keeps (store parts, cache entries, manifests): regular files only.

Every file of the results store and of the kernel and reference caches is read through
:func:`read_regular`. A path that names anything else — a FIFO, a socket, a device, a directory —
raises :class:`NotRegularFile` at once instead of blocking (``open()`` of a FIFO waits for a writer
forever) or reading a device without end. The callers treat it as any damaged entry: one warning
line, the entry discarded, rebuilt or recomputed.

The file is opened with ``O_NONBLOCK`` (so opening a FIFO returns at once) and checked with
``fstat`` on the descriptor that is read (no window between the check and the read).
"""
from __future__ import annotations

import os
import stat
from pathlib import Path


class NotRegularFile(OSError):
    """The path exists but is not a regular file (a FIFO, socket, device or directory);
    ``what`` says which, e.g. ``"is a FIFO, not a regular file"``."""

    def __init__(self, path, kind: str):
        self.what = f"is {kind}, not a regular file"
        super().__init__(f"{path} {self.what}")


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISLNK, "a symbolic link")):
        if test(mode):
            return name
    return "not a regular file"


def open_regular(path) -> int:
    """A read-only descriptor of ``path`` if it is a regular file (symbolic links followed), else
    :class:`NotRegularFile`; ``FileNotFoundError`` if it is absent. Never blocks."""
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except IsADirectoryError as e:
        raise NotRegularFile(path, "a directory") from e
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise NotRegularFile(path, _kind(mode))
        os.set_blocking(fd, True)          # a regular file reads whole either way
    except BaseException:
        os.close(fd)
        raise
    return fd


def open_regular_file(path):
    """A binary file object (seekable, to be closed) of the regular file ``path``
    (:func:`open_regular`): for readers such as pyarrow that take a file, not bytes."""
    return os.fdopen(open_regular(path), "rb")


def read_regular(path) -> bytes:
    """The bytes of the regular file ``path`` (:func:`open_regular`)."""
    with os.fdopen(open_regular(path), "rb") as f:
        return f.read()


def read_regular_text(path, encoding: str = "utf-8") -> str:
    """The text of the regular file ``path`` (:func:`open_regular`)."""
    return read_regular(path).decode(encoding)


def is_regular(path) -> bool:
    """True for an existing regular file (after symbolic links), without opening it."""
    try:
        return stat.S_ISREG(os.stat(Path(path)).st_mode)
    except OSError:
        return False
