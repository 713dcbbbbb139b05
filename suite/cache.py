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
