"""Cache integrity: a corrupt or tampered cache entry is discarded and rebuilt with one warning line,
never a traceback, never a silently wrong number (kernel modules, numba's compiled files,
generated problem code, reference solutions).

Each test runs ``gnibench solve`` in a fresh process on its own cache directory (a copy of one
warmed once per module, so that no test compiles from scratch; a damaged entry is then rebuilt by
the test's own run), damages the entry, runs again and compares the output with the first run's.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

GNIBENCH = [str(Path(sys.executable).with_name("gnibench"))]
SOLVE = ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "300", "--every", "100"]
HEYOKA = ["solve", "lotka-volterra", "rk4:h=0.05", "--steps", "40", "--every", "10",
          "--reference", "heyoka"]


def _solve(cache: Path, args=SOLVE, **env) -> subprocess.CompletedProcess:
    env = {**os.environ, "GNIBENCH_CACHE_DIR": str(cache), **env}
    return subprocess.run(GNIBENCH + list(args), capture_output=True, text=True, check=False,
                          env=env)


@pytest.fixture(scope="module")
def warmed(tmp_path_factory):
    """Cache directories warmed once per module, each by one run (of SOLVE, of HEYOKA with its
    reference solution); the runs' outputs."""
    root = tmp_path_factory.mktemp("warmed")
    runs = {}
    for name, args in (("plain", SOLVE), ("heyoka", HEYOKA)):
        first = _solve(root / name, args)
        assert first.returncode == 0 and first.stderr == "", first.stderr
        runs[name] = (root / name, first.stdout)
    return runs


def _copy(warmed, name: str, tmp_path: Path) -> tuple[Path, str]:
    source, output = warmed[name]
    copy = tmp_path / "cache"
    shutil.copytree(source, copy, symlinks=True)      # copy2: numba's index checks the mtimes
    return copy, output


@pytest.fixture
def warm(warmed, tmp_path):
    """A cache directory warmed by one run (a copy); the run's output."""
    return _copy(warmed, "plain", tmp_path)


def _check_rebuilt(cache: Path, expected: str, what: str, args=SOLVE, **env) -> None:
    again = _solve(cache, args, **env)
    assert again.returncode == 0, again.stderr
    assert "Traceback" not in again.stderr
    warnings = [ln for ln in again.stderr.splitlines() if ln.startswith("gnibench: warning:")]
    assert len(warnings) == 1 and what in warnings[0], again.stderr
    assert again.stdout == expected
    third = _solve(cache, args, **env)               # rebuilt: clean from now on
    assert third.stderr == "" and third.stdout == expected


def _cell_module(cache: Path) -> Path:
    return next(p for p in (cache / "kernels").glob("cell_*.py") if "rk4" in p.read_text()
                or "0.16666666666666666" in p.read_text())


def test_tampered_kernel_module_is_rebuilt(warm):
    """One RK4 weight changed, still valid Python: the module no longer matches the text it is
    named after."""
    cache, expected = warm
    module = _cell_module(cache)
    text = module.read_text()
    assert "0.3333333333333333" in text
    module.write_text(text.replace("0.3333333333333333", "0.3333333333333", 1))
    _check_rebuilt(cache, expected, "kernel module")


@pytest.mark.parametrize("suffix", [".nbi", ".nbc"])
def test_truncated_numba_file_is_recompiled(warm, suffix):
    cache, expected = warm
    stem = _cell_module(cache).stem
    files = sorted((cache / "kernels" / "__pycache__").glob(f"{stem}.integrate-*{suffix}"))
    assert files
    files[0].write_bytes(files[0].read_bytes()[:20])
    _check_rebuilt(cache, expected, "compiled kernel")


def test_tampered_numba_machine_code_is_recompiled(warm):
    cache, expected = warm
    stem = _cell_module(cache).stem
    nbc = min((cache / "kernels" / "__pycache__").glob(f"{stem}.integrate-*.nbc"))
    raw = bytearray(nbc.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    nbc.write_bytes(bytes(raw))
    _check_rebuilt(cache, expected, "compiled kernel")


def test_truncated_problem_code_is_regenerated(warm):
    cache, expected = warm
    entry = next((cache / "problems").glob("kepler-2d-*.code.json"))
    entry.write_text(entry.read_text()[:50])
    _check_rebuilt(cache, expected, "problem code")


def test_rewritten_reference_is_recomputed(warmed, tmp_path):
    """A reference .npz rewritten with y * 1.001 (a valid file) must not give a wrong
    global_error: its checksum no longer matches."""
    cache, expected = _copy(warmed, "heyoka", tmp_path)
    path = next((cache / "references").glob("lotka-volterra-heyoka-*.npz"))
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["y"] = arrays["y"] * 1.001
    with open(path, "wb") as f:
        np.savez(f, **arrays)
    _check_rebuilt(cache, expected, "reference solution", HEYOKA)


def test_truncated_reference_is_recomputed(warmed, tmp_path):
    cache, expected = _copy(warmed, "heyoka", tmp_path)
    path = next((cache / "references").glob("lotka-volterra-heyoka-*.npz"))
    path.write_bytes(path.read_bytes()[:64])
    _check_rebuilt(cache, expected, "reference solution", HEYOKA)


def test_manifest_lists_every_compiled_file(warm):
    cache, _ = warm
    stem = _cell_module(cache).stem
    pycache = cache / "kernels" / "__pycache__"
    listed = json.loads((pycache / f"{stem}.manifest.json").read_text())
    files = {p.name for p in pycache.glob(f"{stem}.*") if re.search(r"\.nb[ic]$", p.name)}
    assert files and set(listed) == files


def test_numba_cache_dir_is_where_numba_puts_the_files(tmp_path):
    """numba_cache_path is where numba writes a cached function's files, with and without
    NUMBA_CACHE_DIR (observed: a module with a ``cache=True`` function is compiled in a fresh
    process, through numba's public API only)."""
    from gnibench.suite.foundation.cache import numba_cache_path

    module = tmp_path / "kernels" / "cell_x.py"
    module.parent.mkdir()
    module.write_text("from numba import njit\n\n@njit(cache=True)\ndef g(x):\n    return x + 1.0\n")
    load = ("import importlib.util, sys\n"
            f"spec = importlib.util.spec_from_file_location('cell_x', {str(module)!r})\n"
            "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); m.g(1.0)\n")
    for numba_dir in (None, tmp_path / "numba"):
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        if numba_dir is not None:
            env["NUMBA_CACHE_DIR"] = str(numba_dir)
        subprocess.run([sys.executable, "-c", load], env=env, check=True, timeout=300)
        with pytest.MonkeyPatch.context() as mp:
            if numba_dir is None:
                mp.delenv("NUMBA_CACHE_DIR", raising=False)
            else:
                mp.setenv("NUMBA_CACHE_DIR", str(numba_dir))
            where = numba_cache_path(module)
        assert list(where.glob("cell_x.g-*.nbi")), (numba_dir, sorted(tmp_path.rglob("*.nbi")))


def test_files_under_numba_cache_dir_are_checked_too(tmp_path):
    """With NUMBA_CACHE_DIR set numba writes the compiled files there, not beside the kernel
    modules: they are recorded and checked there (before, a flipped byte went unseen)."""
    cache, numba_dir = tmp_path / "cache", tmp_path / "numba"
    first = _solve(cache, NUMBA_CACHE_DIR=str(numba_dir))
    assert first.returncode == 0 and first.stderr == "", first.stderr
    stem = _cell_module(cache).stem
    nbc = min(numba_dir.glob(f"*/{stem}.integrate-*.nbc"))
    raw = bytearray(nbc.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    nbc.write_bytes(bytes(raw))
    _check_rebuilt(cache, first.stdout, "compiled kernel", NUMBA_CACHE_DIR=str(numba_dir))
