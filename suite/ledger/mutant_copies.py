"""Copies of the package for mutation testing (:mod:`.mutants`): each mutant gets its own copy,
kernel cache and environment.

A copy is the installed package (the repository root, tests included) at ``<home>/gnibench``,
imported first through ``PYTHONPATH`` (checked: :func:`imports_copy`). Its kernel cache is seeded
by hard links with the generated kernels and problem code of the unmutated baseline run: both are
keyed by the hash of their own full text, so a mutated template gets a new key and compiles, an
untouched one loads; every cache write is a rename, so nothing the mutant writes reaches the
seed. Reference solutions are not seeded, since their key does not cover the code that computes
them.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from gnibench.suite.foundation.errors import UserError

#: what is not part of the package when it is copied
IGNORE = shutil.ignore_patterns(".venv", ".git", "__pycache__", "results", ".benchmarks",
                                "*.egg-info", ".pytest_cache", "build", "dist")
#: cache subfolders keyed by the hash of their full content (safe to share with a mutant)
SEEDED = ("kernels", "problems")


def package_root() -> Path:
    """The package this module belongs to (suite/ledger/ two levels down): importing the
    package top would import the API, a floor above the ledger (tests/test_layout.py)."""
    return Path(__file__).resolve().parents[2]



def copy_package(dest: Path) -> Path:
    """A copy of the installed package at ``dest/gnibench`` (the import root is ``dest``)."""
    target = dest / "gnibench"
    shutil.copytree(package_root(), target, ignore=IGNORE)
    return target



def env_for(import_root: Path, cache: Path) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(import_root)
    env["GNIBENCH_CACHE_DIR"] = str(cache)
    env.pop("PYTEST_ADDOPTS", None)
    # tests/methods/test_hairer_counts.py compares with Hairer's Fortran in a venv it makes once in the
    # user's cache (not keyed by content, so not seeded): point the copy at it, else every mutant
    # would build its own
    if "GNIBENCH_FORTRAN_SCIPY_PYTHON" not in env:
        from gnibench.suite.foundation.cache import cache_dir

        fortran = cache_dir() / "scipy-fortran" / "bin" / "python"
        if fortran.is_file():
            env["GNIBENCH_FORTRAN_SCIPY_PYTHON"] = str(fortran)
    return env


def _link_or_copy(src: str, dst: str) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def seed_cache(source: Path | None, cache: Path) -> None:
    """Seed a mutant's own cache with hard links to ``source``'s kernels and problem code. Safe:
    gnibench and numba write every cache file by writing a new file and renaming it over the
    old one (never in place), so a write in the mutant's cache never reaches ``source``."""
    cache.mkdir(parents=True, exist_ok=True)
    if source is None:
        return
    for sub in SEEDED:
        if (source / sub).is_dir() and not (cache / sub).exists():
            try:       # a shared cache may change while it is linked: a partial seed is fine,
                shutil.copytree(source / sub, cache / sub, copy_function=_link_or_copy,
                                ignore=shutil.ignore_patterns("*.tmp*", ".*"))
            except shutil.Error:                 # every entry is verified when it is read
                pass


def imports_copy(import_root: Path, env: dict) -> None:
    """Refuse to go on unless a subprocess with ``env`` imports the copy (not the installed tree)."""
    out = subprocess.run([sys.executable, "-c", "import gnibench; print(gnibench.__file__)"],
                         check=False, env=env, cwd=import_root, capture_output=True, text=True, timeout=120)
    where = Path(out.stdout.strip() or "?").resolve()
    if import_root.resolve() not in where.parents:
        raise UserError(f"the subprocess imports gnibench from {where}, not from the copy in "
                        f"{import_root}: an editable install shadows PYTHONPATH")
