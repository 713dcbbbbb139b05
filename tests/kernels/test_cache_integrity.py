"""Cache integrity: a corrupt or tampered cache entry is discarded and rebuilt with one warning line,
never a traceback, never a silently wrong number (kernel modules, numba's compiled files,
generated problem code, reference solutions).

Each test runs ``gnibench solve`` in a fresh process on its own cache directory (a copy of one
warmed once per module, so that no test compiles from scratch; a damaged entry is then rebuilt by
the test's own run), damages the entry, runs again and compares the output with the first run's.
"""
from __future__ import annotations

import importlib.util
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


def test_numba_file_rewritten_with_its_manifest_is_recompiled(warm):
    """A flipped byte in the machine code whose manifest checksum was computed again (the
    manifest agrees): numba fails to load it; one warning line and a recompilation, never
    numba's traceback."""
    import hashlib

    cache, expected = warm
    stem = _cell_module(cache).stem
    pycache = cache / "kernels" / "__pycache__"
    nbc = min(pycache.glob(f"{stem}.integrate-*.nbc"))
    raw = bytearray(nbc.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    nbc.write_bytes(bytes(raw))
    manifest = pycache / f"{stem}.manifest.json"
    listed = json.loads(manifest.read_text())
    listed[nbc.name] = hashlib.sha256(bytes(raw)).hexdigest()
    manifest.write_text(json.dumps(listed, sort_keys=True))
    _check_rebuilt(cache, expected, "could not be loaded from the kernel cache")


def _entries(cache: Path) -> dict[str, Path]:
    stem = _cell_module(cache).stem
    pycache = cache / "kernels" / "__pycache__"
    return {"kernel module": _cell_module(cache),
            "numba file": min(pycache.glob(f"{stem}.integrate-*.nbc")),
            "numba index": min(pycache.glob(f"{stem}.integrate-*.nbi")),
            "kernel manifest": pycache / f"{stem}.manifest.json",
            "problem code": next((cache / "problems").glob("kepler-2d-*.code.json")),
            "problem code checksum": next((cache / "problems").glob("kepler-2d-*.code.json.sha256")),
            # Python reads the module's bytecode itself (written or not: PYTHONDONTWRITEBYTECODE)
            "kernel bytecode": Path(importlib.util.cache_from_source(str(_cell_module(cache))))}


@pytest.mark.parametrize("entry", ["kernel module", "numba file", "numba index", "kernel manifest",
                                   "problem code", "problem code checksum", "kernel bytecode"])
def test_a_fifo_in_place_of_a_cache_entry_is_replaced_not_waited_on(warm, entry):
    """A FIFO where a cache file should be: opening it would wait for a writer forever. The run
    finishes (a timeout fails the test), with the same output, the entry rebuilt."""
    cache, expected = warm
    path = _entries(cache)[entry]
    path.unlink(missing_ok=True)
    os.mkfifo(path)
    env = {**os.environ, "GNIBENCH_CACHE_DIR": str(cache)}
    again = subprocess.run(GNIBENCH + SOLVE, capture_output=True, text=True, check=False,
                           env=env, timeout=240)
    assert again.returncode == 0 and "Traceback" not in again.stderr, again.stderr
    assert again.stdout == expected
    third = _solve(cache)
    assert third.stderr == "" and third.stdout == expected
    assert not any(p.is_fifo() for p in cache.rglob("*"))


def test_a_fifo_in_place_of_a_reference_is_replaced(warmed, tmp_path):
    cache, expected = _copy(warmed, "heyoka", tmp_path)
    path = next((cache / "references").glob("lotka-volterra-heyoka-*.npz"))
    path.unlink()
    os.mkfifo(path)
    env = {**os.environ, "GNIBENCH_CACHE_DIR": str(cache)}
    again = subprocess.run(GNIBENCH + HEYOKA, capture_output=True, text=True, check=False, env=env,
                           timeout=240)
    assert again.returncode == 0 and "is a FIFO, not a regular file" in again.stderr, again.stderr
    assert again.stdout == expected


def test_open_regular_refuses_what_is_not_a_file_at_once(tmp_path):
    from gnibench.suite.foundation.files import NotRegularFile, read_regular

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(NotRegularFile, match="is a FIFO, not a regular file"):
        read_regular(fifo)
    with pytest.raises(NotRegularFile, match="is a directory"):
        read_regular(tmp_path)
    with pytest.raises(FileNotFoundError):
        read_regular(tmp_path / "absent")
    (tmp_path / "f").write_bytes(b"abc")
    assert read_regular(tmp_path / "f") == b"abc"


def test_a_full_disk_under_the_kernel_cache_names_the_cache_and_the_remedy(tmp_path):
    """Writing a kernel module fails with ENOSPC: one line naming the cache, the file and what to
    do, exit code 1 (before: "No space left on device" alone)."""
    code = ("import errno, sys\n"
            "from gnibench.methods.assembly import loading\n"
            "def full(path, text):\n"
            "    raise OSError(errno.ENOSPC, 'No space left on device', str(path))\n"
            "loading.write_atomic = full\n"
            "from gnibench.suite.cli.main import main\n"
            "sys.exit(main(['solve', 'kepler-2d', 'rk4:h=0.1', '--steps', '3']))\n")
    env = {**os.environ, "GNIBENCH_CACHE_DIR": str(tmp_path / "cache")}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          check=False)
    assert done.returncode == 1 and done.stdout == "", done.stderr
    (line,) = done.stderr.splitlines()
    assert line.startswith(f"gnibench: error: the kernel cache {tmp_path / 'cache'} cannot be "
                           f"written (No space left on device: ")
    assert "point GNIBENCH_CACHE_DIR at a disk with room" in line


def test_an_error_outside_the_cache_is_not_blamed_on_it(tmp_path, monkeypatch):
    import errno

    from gnibench.suite.foundation.cache import cache_fault

    monkeypatch.setenv("GNIBENCH_CACHE_DIR", str(tmp_path / "cache"))
    assert cache_fault(OSError(errno.ENOSPC, "full", str(tmp_path / "out.csv"))) == ""
    assert "cannot be written" in cache_fault(OSError(errno.ENOSPC, "full",
                                                      str(tmp_path / "cache" / "x")))
