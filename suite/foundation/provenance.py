"""What every stored result carries so that it can be re-run: the versions of what computed it."""
from __future__ import annotations

import functools
import platform
import sys
from importlib.metadata import PackageNotFoundError, version

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
