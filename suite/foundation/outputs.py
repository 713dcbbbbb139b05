"""Where results may be written: checked before any work, faults during work made one line.

Output goes to regular files only. A file named with ``-o`` is written to a temporary file beside
it and renamed into place (:func:`gnibench.suite.foundation.cache.atomic_write`), and a rename
replaces whatever the name points at: given ``/dev/null``, a FIFO or a symlink it would replace
the device, the FIFO or the link itself. So an existing ``-o`` that is not a regular file (a
device, a FIFO, a socket, a directory) or that is a symlink is refused before any work, and the
place is probed by creating (and removing) a file where the temporary file will be: a directory
that only looks writable (``/proc``, a read-only mount, a full quota) fails there, before the work
and not after it.

A fault during the work (the disk fills up, a directory vanishes) is a :class:`Fault`: one line
naming the file and the cause, exit code 1; what was finished stays (every result file is
committed by an atomic rename, so none is left half-written).
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

from gnibench.suite.foundation.errors import UserError, named


class Fault(Exception):
    """A fault of the environment during work (disk full, I/O error): one line, exit code 1."""


def kind(mode: int) -> str:
    """What a file of this mode is, in words ("a FIFO")."""
    for test, name in ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISDIR, "a directory")):
        if test(mode):
            return name
    return "not a regular file"


def probe(directory: Path, what: str, name: str = "gnibench-probe") -> None:
    """Create and remove a file in ``directory`` (named as the temporary file of an atomic write
    of ``name``): a one-line UserError when that fails."""
    path = Path(directory) / f".{name}.tmp{os.getpid()}"
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        os.close(fd)
        os.unlink(path)
    except OSError as e:
        raise UserError(f"bad {what}: cannot write in {directory} ({e.strerror})") from None


def check_output_file(path: Path, option: str = "-o") -> None:
    """Refuse, before any work, an output file that cannot be written as a regular file."""
    path = Path(path)
    try:
        _check_file(path, f"{option} {path}")
    except OSError as e:                 # a name too long, a loop of symlinks, ...
        raise UserError(f"bad {named(option, str(path))}: {e.strerror or e}") from None


def _check_file(path: Path, what: str) -> None:
    if path.is_symlink():
        target = path.resolve()
        hint = f"its target, {target}" if target.is_file() or not target.exists() else \
            "a regular file; to write to stdout, leave out -o"
        raise UserError(f"bad {what}: it is a symlink (it would be replaced, not written "
                        f"through); allowed: {hint}")
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        mode = None
    except OSError as e:
        raise UserError(f"bad {what}: {e.strerror}") from None
    if mode is not None and not stat.S_ISREG(mode):
        hint = "; to discard the output, write to stdout" if stat.S_ISCHR(mode) else ""
        raise UserError(f"bad {what}: it is {kind(mode)}; allowed: a regular file{hint}")
    parent = path.parent
    if not parent.exists():
        raise UserError(f"bad {what}: directory {parent} does not exist")
    if not parent.is_dir():
        raise UserError(f"bad {what}: {parent} is not a directory")
    if mode is not None and not os.access(path, os.W_OK):
        raise UserError(f"bad {what}: not writable")
    probe(parent, what, path.name)


def check_output_dir(path: Path, option: str = "-o") -> None:
    """Refuse, before any work, an output directory that cannot be one: an existing file, or a
    place where it cannot be created or written (nothing is created here)."""
    path = Path(path)
    try:
        _check_dir(path, f"{option} {path}")
    except OSError as e:
        raise UserError(f"bad {named(option, str(path))}: {e.strerror or e}") from None


def _check_dir(path: Path, what: str) -> None:
    if path.exists() and not path.is_dir():
        raise UserError(f"bad {what}: it exists and is not a directory")
    existing = path
    while not existing.exists():
        if existing.is_symlink():            # a dangling symlink on the way
            raise UserError(f"bad {what}: {existing} is a broken symlink")
        existing = existing.parent
    if not existing.is_dir():
        raise UserError(f"bad {what}: {existing} is not a directory")
    probe(existing, what)


def fault(e: OSError, doing: str, after: str = "") -> Fault:
    """A one-line Fault for an OSError while ``doing`` (e.g. "writing results/x/cells.parquet")."""
    cause = e.strerror or " ".join(str(e).split())[:200] or type(e).__name__
    name = f" {e.filename}" if getattr(e, "filename", None) and str(e.filename) not in doing \
        else ""
    return Fault(f"{doing} failed: {cause}{name}{'; ' + after if after else ''}")
