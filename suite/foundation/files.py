"""Opening the files gnibench reads back (store parts, cache entries, input files): regular files
only, and never a blocking open.

``open()`` of a FIFO waits for a writer, for ever; of ``/dev/zero`` it never ends a read; of a
directory it fails late. Every file of the store and of the caches, and every input file, is
opened here: :func:`open_regular` opens it with ``O_NONBLOCK`` (a FIFO opens at once instead of
waiting) and, for the files gnibench writes itself, ``O_NOFOLLOW`` (it never writes a symlink: one
in its place was put there by someone else), then checks with ``fstat`` on the open descriptor
(not on the name, which could change in between) that it is a regular file, and only then reads.
Anything else raises :class:`NotRegular` (an ``OSError``), which the callers already treat as a
damaged entry (one warning line, discarded and rebuilt) or as bad input (one line, exit 2).
"""
from __future__ import annotations

import contextlib
import errno
import os
import stat


class NotRegular(OSError):
    """The path is not a regular file (a FIFO, a device, a directory, a socket, a symlink where
    none is allowed): ``strerror`` says what it is."""


def kind(mode: int) -> str:
    """What a file of this mode is, in words ("a FIFO")."""
    for test, name in ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISDIR, "a directory"), (stat.S_ISLNK, "a symlink")):
        if test(mode):
            return name
    return "not a regular file"


def open_regular(path, follow: bool = False) -> int:
    """A file descriptor open for reading on the regular file ``path``, in blocking mode.

    ``follow=False`` (the store's and the caches' own files) refuses a symlink; ``follow=True``
    (a user's input file) follows it. Raises :class:`NotRegular` for anything but a regular file,
    and the ``OSError`` of the open otherwise (missing, no permission)."""
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)
    if not follow:
        flags |= getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except OSError as e:
        if e.errno == errno.ELOOP and not follow:
            raise NotRegular(errno.ELOOP, "it is a symlink", str(path)) from None
        raise
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise NotRegular(errno.EINVAL, f"it is {kind(mode)}", str(path))
        os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return fd


def read_regular(path, follow: bool = False, limit: int | None = None) -> bytes:
    """The bytes of the regular file ``path`` (:func:`open_regular`); ``limit``: refuse a file
    larger than that many bytes (:class:`NotRegular`, "too large") before reading it."""
    fd = open_regular(path, follow)
    with open(fd, "rb", closefd=True) as f:
        if limit is not None:
            size = os.fstat(f.fileno()).st_size
            if size > limit:
                raise NotRegular(errno.EFBIG, f"it is {size} bytes, more than {limit}", str(path))
        return f.read()


def read_text(path, follow: bool = False, encoding: str = "utf-8") -> str:
    """The text of the regular file ``path`` (:func:`read_regular`)."""
    return read_regular(path, follow).decode(encoding)


def open_binary(path, follow: bool = False):
    """A binary file object open for reading on the regular file ``path`` (for readers that take
    a file, such as pyarrow's)."""
    return open(open_regular(path, follow), "rb", closefd=True)


def is_regular(path) -> bool:
    """Whether ``path`` itself (not followed) is a regular file: a look that never opens it."""
    with contextlib.suppress(OSError):
        return stat.S_ISREG(os.lstat(path).st_mode)
    return False


def describe(e: OSError) -> str:
    """The cause of a failed read in a few words ("it is a FIFO", "Permission denied")."""
    return e.strerror or type(e).__name__


__all__ = ["NotRegular", "describe", "is_regular", "kind", "open_binary", "open_regular",
           "read_regular", "read_text"]
