"""The on-disk cache: generated problem code, compiled kernels and reference solutions.

``GNIBENCH_CACHE_DIR`` overrides the location (default: ``~/.cache/gnibench``).

Nothing read from the cache is trusted blindly. Every entry gnibench writes carries a checksum
recorded when it was written (:func:`write_checked`: a ``<name>.sha256`` file beside it) and is
verified when read (:func:`read_checked`). numba writes its own cache files (``__pycache__`` beside
each generated module, or under ``NUMBA_CACHE_DIR``: :func:`numba_cache_path`); their checksums
are recorded in a manifest after they are written (:func:`record_numba_files`) and verified
before the module is imported (:func:`verify_numba_files`). A corrupt or tampered entry is
discarded with one warning line on stderr and rebuilt; it never gives a traceback or a wrong
number.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import sys
from pathlib import Path

from gnibench.suite.foundation.files import NotRegularFile, read_regular


def cache_root() -> Path:
    """The cache directory; a one-line UserError when it cannot be one (``GNIBENCH_CACHE_DIR``
    names a file, or a place where nothing can be created)."""
    given = os.environ.get("GNIBENCH_CACHE_DIR")
    root = Path(given or Path.home() / ".cache" / "gnibench")
    if root.exists() and not root.is_dir():
        raise _bad_root(root, "it is not a directory")
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _bad_root(root, f"cannot create it ({e.strerror})") from None
    return root


def _bad_root(root: Path, why: str):
    from gnibench.suite.foundation.errors import UserError

    given = os.environ.get("GNIBENCH_CACHE_DIR")
    if given:
        return UserError(f"bad GNIBENCH_CACHE_DIR={given}: {why}; allowed: a writable directory "
                         f"(or unset: ~/.cache/gnibench)")
    return UserError(f"bad cache directory {root}: {why}; allowed: a writable directory, given "
                     f"as GNIBENCH_CACHE_DIR=DIR")


def check_cache_root() -> None:
    """Refuse, before any work, a cache directory that cannot be one or cannot be written."""
    from gnibench.suite.foundation.errors import UserError
    from gnibench.suite.foundation.outputs import probe

    root = cache_root()
    try:
        probe(root, "cache")
    except UserError:
        raise _bad_root(root, "not writable") from None


def cache_dir(sub: str = "") -> Path:
    root = cache_root()
    d = root / sub if sub else root
    if sub and (d.is_symlink() or d.exists() and not d.is_dir()):
        warn(f"cache entry {d} is not a directory; removed")
        discard(d)
    d.mkdir(parents=True, exist_ok=True)
    return d


def write_atomic(path: Path, text: str) -> None:
    """Write text to path through a process-unique temporary file and an atomic rename, so that
    concurrent writers (pytest-xdist, Dask workers) never expose a partial file."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(text)
        _replace(tmp, path)
    except OSError as e:              # a full disk, say: the error names the file
        if not e.filename:
            e.filename = str(path)
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def _replace(tmp: Path, path: Path) -> None:
    """Rename ``tmp`` onto ``path``; a directory in the way (a damaged cache) is removed first."""
    try:
        tmp.replace(path)
    except OSError:
        if not path.is_dir() or path.is_symlink():
            raise
        shutil.rmtree(path, ignore_errors=True)
        tmp.replace(path)


def atomic_write(path: Path, write) -> None:
    """``write(tmp)`` to a process-unique temporary file, then rename it onto ``path``."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        write(tmp)
        _replace(tmp, path)
    except OSError as e:              # a full disk, say: the error names the file
        if not e.filename:
            e.filename = str(path)
        raise
    finally:
        if tmp.exists():
            tmp.unlink()


def cache_fault(e: OSError) -> str:
    """The line for an OSError met writing the cache (a full disk, a quota, a read-only mount):
    which cache, what happened and what to do; "" for an error elsewhere."""
    import errno

    name = getattr(e, "filename", None)
    root = Path(os.environ.get("GNIBENCH_CACHE_DIR") or Path.home() / ".cache" / "gnibench")
    try:
        inside = name is not None and Path(name).resolve().is_relative_to(root.resolve())
    except (OSError, ValueError):
        inside = False
    if not inside:
        return ""
    full = e.errno in (errno.ENOSPC, errno.EDQUOT)
    remedy = ("free room on its disk, or point GNIBENCH_CACHE_DIR at a disk with room" if full
              else "make it writable, or point GNIBENCH_CACHE_DIR at a directory that is")
    return (f"the kernel cache {root} cannot be written ({e.strerror or type(e).__name__}: "
            f"{name}); {remedy}; nothing finished was lost, run the command again")


def warn(message: str) -> None:
    """One warning line on stderr."""
    print(f"gnibench: warning: {message}", file=sys.stderr, flush=True)


def _sum_path(path: Path) -> Path:
    return path.with_name(path.name + ".sha256")


def digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def write_checked(path: Path, data: bytes | str) -> None:
    """Write a cache entry atomically, then its checksum beside it."""
    path = Path(path)
    raw = data.encode() if isinstance(data, str) else data
    atomic_write(path, lambda p: Path(p).write_bytes(raw))
    atomic_write(_sum_path(path), lambda p: Path(p).write_text(digest(raw) + "\n"))


def read_checked(path: Path, what: str, parse=None):
    """The bytes of a cache entry whose checksum matches (``parse(bytes)`` of them, if given), or
    None when it is absent.

    An entry that is unreadable (a directory, say), has no checksum, whose content does not match
    its checksum, or that ``parse`` rejects (any exception: valid bytes can still be the wrong
    content) is deleted with one warning line (``what`` names it), and None is returned: the
    caller rebuilds.
    """
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        return None
    try:
        raw = read_regular(path)
        expected = read_regular(_sum_path(path)).decode().strip()
    except NotRegularFile as e:              # a FIFO, socket or directory in its place
        warn(f"cached {what} {path.name} {e.what}; discarded and rebuilt")
        discard(path)
        return None
    except (OSError, UnicodeDecodeError):
        expected, raw = None, b""
    if expected != digest(raw):
        warn(f"cached {what} {path.name} is corrupt or was modified (checksum mismatch); "
             f"discarded and rebuilt")
        discard(path)
        return None
    if parse is None:
        return raw
    try:
        return parse(raw)
    except Exception as e:  # noqa: BLE001 - whatever is wrong with it, it is rebuilt
        warn(f"cached {what} {path.name} does not hold what it should ({type(e).__name__}); "
             f"discarded and rebuilt")
        discard(path)
        return None


def discard(path: Path) -> None:
    """Remove a cache entry (a file, or whatever took its place) and its checksum."""
    for p in (Path(path), _sum_path(Path(path))):
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)


# -- numba's cache files of a generated module --------------------------------------------------

def numba_cache_path(module_path: Path) -> Path:
    """Where numba writes the compiled files of a module: ``__pycache__`` beside it, or, with
    ``NUMBA_CACHE_DIR`` set (checked by :mod:`~gnibench.suite.foundation.numba_settings`),
    ``DIR/<name of the module's directory>_<sha1 of its path>`` as numba's
    ``UserProvidedCacheLocator`` computes it (``numba/core/caching.py``)."""
    given = os.environ.get("NUMBA_CACHE_DIR", "")
    if not given:
        return Path(module_path).parent / "__pycache__"
    parent = os.path.dirname(os.path.abspath(module_path))
    sub = f"{os.path.basename(parent)}_{hashlib.sha1(parent.encode()).hexdigest()}"
    return Path(given) / sub


def _numba_files(module_path: Path) -> list[Path]:
    d = numba_cache_path(module_path)
    if not d.is_dir():
        return []
    return sorted(p for p in d.glob(f"{module_path.stem}.*") if p.suffix in (".nbi", ".nbc"))


def _manifest(module_path: Path) -> Path:
    return module_path.parent / "__pycache__" / f"{module_path.stem}.manifest.json"


def verify_numba_files(module_path: Path) -> None:
    """Before importing a generated module: keep only numba cache files whose checksum is in the
    module's manifest. A listed file that does not match means corruption or tampering: all the
    module's cache files are discarded (one warning line) and numba recompiles. Files the manifest
    does not list (a compilation killed before it was recorded) are removed silently."""
    module_path = Path(module_path)
    for d in dict.fromkeys((module_path.parent / "__pycache__", numba_cache_path(module_path))):
        if d.is_symlink() or d.exists() and not d.is_dir():
            warn(f"cache entry {d} is not a directory; removed")
            discard(d)
    _drop_irregular(module_path)
    files = _numba_files(module_path)
    if not files:
        return
    try:
        listed = json.loads(read_regular(_manifest(module_path)))
        if not isinstance(listed, dict):
            raise TypeError("not a manifest")
    except (OSError, ValueError, TypeError):
        listed = {}
    bad = [f for f in files if f.name in listed and listed[f.name] != _file_digest(f)]
    if bad:
        warn(f"compiled kernel {bad[0].name} is corrupt or was modified (checksum mismatch); "
             f"discarded and recompiled")
        for f in files:
            discard(f)
        discard(_manifest(module_path))
        return
    for f in files:
        if f.name not in listed:
            discard(f)


def _drop_irregular(module_path: Path) -> None:
    """Remove, with one warning line, whatever is not a regular file among the module's files in
    its ``__pycache__`` (Python's ``.pyc`` too, which Python's import reads without our opener:
    a FIFO there blocked the import for ever) and numba's cache directory."""
    for d in dict.fromkeys((module_path.parent / "__pycache__", numba_cache_path(module_path))):
        if not d.is_dir():
            continue
        for f in d.glob(f"{module_path.stem}.*"):
            if not f.is_symlink() and f.is_file():
                continue
            warn(f"cache entry {f} is not a regular file; removed")
            discard(f)


def discard_numba_files(module_path: Path) -> bool:
    """Remove every numba cache file of a generated module and its manifest (numba recompiles on
    the next import); True if there was any."""
    module_path = Path(module_path)
    files = _numba_files(module_path)
    for f in files:
        discard(f)
    discard(_manifest(module_path))
    return bool(files)


def _file_digest(path: Path) -> str | None:
    try:
        return digest(read_regular(path))
    except OSError:                       # a directory or FIFO in place of a file: not listed
        return None


def record_numba_files(module_path: Path) -> None:
    """After this process imported (and possibly compiled) a module: record the checksums of its
    numba cache files as they are now (they were verified before the import, and numba alone
    wrote any change since)."""
    module_path = Path(module_path)
    files = _numba_files(module_path)
    if not files:
        return
    listed = {f.name: _file_digest(f) for f in files}
    if None in listed.values():           # not files: verify_numba_files removes them next time
        return
    path = _manifest(module_path)
    try:
        if json.loads(read_regular(path)) == listed:
            return
    except (OSError, ValueError):
        pass
    path.parent.mkdir(exist_ok=True)      # numba's files may be under NUMBA_CACHE_DIR
    write_atomic(path, json.dumps(listed, sort_keys=True))
