"""The on-disk cache: generated problem code, compiled kernels and reference solutions.

``GNIBENCH_CACHE_DIR`` overrides the location (default: ``~/.cache/gnibench``).
"""
from __future__ import annotations

import os
from pathlib import Path


def cache_dir(sub: str = "") -> Path:
    root = Path(os.environ.get("GNIBENCH_CACHE_DIR") or Path.home() / ".cache" / "gnibench")
    d = root / sub if sub else root
    d.mkdir(parents=True, exist_ok=True)
    return d


def write_atomic(path: Path, text: str) -> None:
    """Write text to path through a process-unique temporary file and an atomic rename, so that
    concurrent writers (pytest-xdist, Dask workers) never expose a partial file."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def atomic_write(path: Path, write) -> None:
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        write(tmp)
        tmp.replace(path)
    finally:
        if tmp.exists():
            tmp.unlink()
