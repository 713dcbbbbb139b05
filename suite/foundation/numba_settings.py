"""numba's environment settings that gnibench depends on, checked before numba is imported.

numba reads its ``NUMBA_*`` variables once, when it is imported (``numba/core/config.py``). A
value it cannot parse gives a multi-line RuntimeWarning (a traceback inside) and its default,
and some parse but fail later (``NUMBA_NUM_THREADS=0``: a ValueError at the first compile). For
the settings below gnibench refuses a bad value first, with one line naming the variable and
what is allowed (exit 2, before any work); numba's other variables are left to numba.

=======================  ===========================================  ========================
variable                 allowed                                      why it matters
=======================  ===========================================  ========================
``NUMBA_DISABLE_JIT``    unset or 0                                   every kernel is compiled
``NUMBA_OPT``            unset, 0, 1, 2, 3 or max (numba's own list)  the kernels' speed
``NUMBA_NUM_THREADS``    unset or a whole number >= 1                 read when numba starts
``NUMBA_BOUNDSCHECK``    unset, 0 or 1                                the kernels' speed
``NUMBA_CACHE_DIR``      unset, empty or a writable directory         where compiled kernels go
=======================  ===========================================  ========================

Whitespace around a number is allowed (numba reads it with ``int``); ``1_0``, ``1e3``, ``١٠``
and the empty string are refused (numba would warn and fall back to its default). A
``NUMBA_CACHE_DIR`` that is set is where numba writes the compiled files of gnibench's kernels;
their checksums are checked there as under ``GNIBENCH_CACHE_DIR``
(:func:`gnibench.suite.foundation.cache.numba_cache_path`).
"""
from __future__ import annotations

import os
import re
from pathlib import Path

from gnibench.suite.foundation.errors import UserError

__all__ = ["check_numba_settings"]

_DIGITS = re.compile(r"[0-9]+")


def _shown(text: str) -> str:
    """The value as given; quoted when it is empty or has blanks around it."""
    return text if text and text.strip() == text else repr(text)


def _whole(text: str) -> int | None:
    text = text.strip(" \t")
    return int(text) if _DIGITS.fullmatch(text) else None


def _disable_jit(text: str) -> bool:
    return _whole(text) == 0


def _opt(text: str) -> bool:
    return text in ("0", "1", "2", "3", "max")     # numba compares the text itself


def _threads(text: str) -> bool:
    n = _whole(text)
    return n is not None and n >= 1


def _boundscheck(text: str) -> bool:
    return _whole(text) in (0, 1)


_SETTINGS = {
    "NUMBA_DISABLE_JIT": (_disable_jit, "unset or 0 (gnibench's kernels are compiled by numba)"),
    "NUMBA_OPT": (_opt, "unset, 0, 1, 2, 3 or max"),
    "NUMBA_NUM_THREADS": (_threads, "unset or a whole number >= 1 in ASCII digits"),
    "NUMBA_BOUNDSCHECK": (_boundscheck, "unset, 0 or 1"),
}


def check_numba_settings(environ=None) -> None:
    """Refuse a bad value of a numba setting gnibench depends on (the table above)."""
    environ = os.environ if environ is None else environ
    for name, (good, allowed) in _SETTINGS.items():
        text = environ.get(name)
        if text is not None and not good(text):
            raise UserError(f"bad {name}={_shown(text)}; allowed: {allowed}")
    _check_cache_dir(environ.get("NUMBA_CACHE_DIR", ""))


def _check_cache_dir(text: str) -> None:
    """A directory numba can write (or create): numba silently ignores one it cannot use. The
    same checks as an output directory's (:func:`gnibench.suite.foundation.outputs.check_output_dir`),
    a file created and removed in the nearest existing directory included."""
    from gnibench.suite.foundation.outputs import _check_dir

    if text == "":                       # numba: not set
        return
    what = f"NUMBA_CACHE_DIR={_shown(text)}"
    allowed = ("allowed: unset (numba's files then stay with the kernels under "
               "GNIBENCH_CACHE_DIR) or a writable directory, or one that can be created")
    if not text.strip():
        raise UserError(f"bad {what}: a blank name; {allowed}")
    try:
        _check_dir(Path(text), what)
    except OSError as e:                 # a name too long, a loop of symlinks
        raise UserError(f"bad {what}: {e.strerror or e}; {allowed}") from None
    except UserError as e:
        raise UserError(f"{e}; {allowed}") from None
