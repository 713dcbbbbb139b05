"""What every stored result carries so that it can be re-run: the versions of what computed it."""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import platform
import sys
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from gnibench.suite.foundation.version import VERSION as __version__

PACKAGES = ("numpy", "scipy", "numba", "sympy", "heyoka", "rebound", "pandas", "pyarrow")


def package_version(name: str) -> str | None:
    try:
        return version(name)
    except PackageNotFoundError:
        return None


@functools.cache
def _versions() -> dict:
    out = {"gnibench": __version__, "python": sys.version.split()[0]}
    out.update({name: package_version(name) for name in PACKAGES})
    out["platform"] = platform.platform()
    return out


def versions() -> dict:
    """gnibench, Python, the numerical packages and the platform (read once per process)."""
    return dict(_versions())


@functools.cache
def code_digest(*modules: str) -> str:
    """SHA-256 (16 hex digits) of the source of the named modules of the package (read once per
    process): the key of a cached result computed by that code, so that a change of the code (a
    fix of an engine) computes the result again instead of serving the one cached before it."""
    h = hashlib.sha256()
    for name in modules:
        spec = importlib.util.find_spec(name)
        if spec is None or not spec.origin:
            raise ModuleNotFoundError(name)
        h.update(name.encode() + b"\0" + Path(spec.origin).read_bytes() + b"\0")
    return h.hexdigest()[:16]
