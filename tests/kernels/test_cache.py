"""The numba disk cache: a second ``gnibench solve`` of a cell in a new process compiles nothing.

Correctness, not timing: the json meta's ``numba_cache_misses`` counts functions compiled in the
process, so it is > 0 with an empty cache and 0 when the machine code is loaded from disk.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys


def _solve(cache, cwd):
    env = dict(os.environ, GNIBENCH_CACHE_DIR=str(cache))
    cmd = [sys.executable, "-m", "gnibench.suite.cli.main", "solve", "kepler-2d", "rk4:h=0.01", "--steps", "10",
           "--format", "json"]
    p = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, timeout=300,
                       check=False)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def test_second_run_loads_compiled_code_from_disk(tmp_path):
    cache = tmp_path / "cache"
    first = _solve(cache, tmp_path)
    second = _solve(cache, tmp_path)
    assert first["meta"]["numba_cache_misses"] > 0
    assert second["meta"]["numba_cache_misses"] == 0
    assert list((cache / "kernels").glob("cell_*.py"))
    assert first["columns"] == second["columns"]
