"""Kernel modules on disk and in the process: written once, verified, imported, compiled once.

numba's ``cache=True`` cannot cache a jitted function that receives another jitted function as an
argument, so every cell gets its own module in which the problem's functions, the modifiers'
terms, the method's step and the driver are plain ``@njit`` globals calling each other by name,
and the functions Python calls are cached by numba (``@entry``, methods/assembly/source.py). A
module's file is named by the hash of its text (``<cache>/kernels/<prefix>_<hash>.py``) and holds
that text under a first line with its checksum; numba's cache files lie beside it (or under
``NUMBA_CACHE_DIR``), their checksums recorded after each compilation and checked before each
import (:mod:`gnibench.suite.foundation.cache`): a second run in a new process loads machine code
instead of compiling, and a damaged file is discarded and rebuilt.
"""
from __future__ import annotations

import contextlib
import functools
import gc
import hashlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

from gnibench.suite.foundation.cache import (
    cache_dir,
    discard,
    discard_numba_files,
    numba_cache_path,
    record_numba_files,
    verify_numba_files,
    warn,
    write_atomic,
)
from gnibench.suite.foundation.files import NotRegularFile, read_regular

_loaded: dict[str, ModuleType] = {}


def key(text: str) -> str:
    """The hash of a module's text: its file's name and the key of its cache files."""
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def module_name(text: str, prefix: str) -> str:
    """The name under which the module of this text is imported (``sys.modules``)."""
    return f"gnibench_{prefix}_{key(text)}"


def _path(k: str, prefix: str) -> Path:
    return cache_dir("kernels") / f"{prefix}_{k}.py"


def load(text: str, prefix: str) -> ModuleType:
    """Import the module of ``text`` from the kernel cache, writing it there first if needed (a
    file whose checksum does not match is discarded with its numba files, with one warning)."""
    k = key(text)
    if k in _loaded:
        return _loaded[k]
    path = _path(k, prefix)
    if path.exists():
        damaged = "is corrupt or was modified (its checksum does not match)"
        try:
            if read_regular(path).decode() == _sealed(text):
                damaged = ""
        except NotRegularFile as e:                    # a FIFO in its place, say
            damaged = e.what
        except (OSError, UnicodeDecodeError):
            pass
        if damaged:
            warn(f"cached kernel module {path.name} {damaged}; discarded and rebuilt")
            discard(path)
            for f in path.parent.glob(f"__pycache__/{path.stem}.*"):
                discard(f)
    if not path.exists():
        write_atomic(path, _sealed(text))
    verify_numba_files(path)
    name = module_name(text, prefix)
    spec = importlib.util.spec_from_file_location(name, path)
    kernel = importlib.util.module_from_spec(spec)
    sys.modules[name] = kernel
    spec.loader.exec_module(kernel)
    _loaded[k] = kernel
    return kernel


def forget(*kernels: ModuleType) -> bool:
    """Drop generated modules whose numba cache files failed to load (a ``.nbc`` damaged in a
    way its manifest does not show, e.g. rewritten together with the manifest): their numba cache
    files are removed and the next :func:`load` of the same text imports and compiles them
    afresh. True if any of them had cache files."""
    had = False
    for kernel in kernels:
        for k, loaded in list(_loaded.items()):
            if loaded is kernel:
                del _loaded[k]
        sys.modules.pop(kernel.__name__, None)
        _recorded.pop(kernel.__file__, None)
        had |= discard_numba_files(Path(kernel.__file__))
    return had


def _sealed(text: str) -> str:
    return f"# sha256 {hashlib.sha256(text.encode()).hexdigest()}\n{text}"


_found: set[str] = set()          # the modules compiled_before found in the kernel cache


def compiled_before(text: str, prefix: str = "cell") -> bool:
    """Whether the module of this text is in the kernel cache with numba's files beside it (a
    guess for scheduling, not a check: :func:`load` verifies what it loads). A module found once
    is not looked for again in this process: the look is a listing of numba's cache directory,
    and a runner asks it for every cell it plans."""
    k = key(text)
    if k in _loaded or k in _found:
        return True
    path = _path(k, prefix)
    if path.exists() and any(numba_cache_path(path).glob(f"{path.stem}.*.nbi")):
        _found.add(k)
        return True
    return False


@functools.cache
def _frozen_by_owner() -> bool:
    """Whether the process was frozen when gnibench first compiled in it (asked once:
    ``gc.get_freeze_count`` walks the frozen objects)."""
    return gc.get_freeze_count() > 0


@contextlib.contextmanager
def compiling():
    """While numba compiles (or loads) a cell, the objects alive before are frozen for Python's
    cyclic garbage collector (``gc.freeze``; unfrozen after, nothing is lost): numba allocates
    millions of objects, and each full collection it triggers walked the ~250 000 objects of a
    loaded gnibench (measured: 0.1 s each, 0.24 s of the 1.4 s of a cold kepler-2d dopri5 cell,
    0.5 s of a section cell's 4.4 s). The compiler's own garbage is still collected. A process
    whose collector is disabled, or frozen by its owner when gnibench first compiles in it, is
    left as it is (``gc.get_freeze_count`` walks the frozen objects: asked once per process, as
    the test processes freeze millions, tests/conftest.py)."""
    if not gc.isenabled() or _frozen_by_owner():
        yield
        return
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


#: module file -> numba cache misses of its functions when this process last recorded it
_recorded: dict[str, int] = {}


def cache_misses(kernel: ModuleType) -> int:
    """Functions of the module compiled in this process instead of loaded from numba's disk cache
    (the dispatchers' ``stats``)."""
    return sum(sum(f.stats.cache_misses.values()) for f in vars(kernel).values()
               if hasattr(f, "stats") and hasattr(f.stats, "cache_misses"))


def record_compiled(*kernels: ModuleType) -> None:
    """Record the checksums of the numba cache files of kernel modules (after they compiled or
    loaded what a cell runs; see :func:`gnibench.suite.foundation.cache.record_numba_files`).

    numba writes cache files only when it compiles (a cache miss), so a module recorded before
    in this process with no miss since is skipped: listing the shared ``__pycache__`` costs more
    than a small cell."""
    for kernel in kernels:
        misses = cache_misses(kernel)
        if _recorded.get(kernel.__file__) == misses:
            continue
        record_numba_files(Path(kernel.__file__))
        _recorded[kernel.__file__] = misses
