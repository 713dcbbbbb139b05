"""Cache entries that used to never heal, and consistent forgeries (issue 18, item 1, caches).

A checksummed entry whose content is wrong in kind (``code.json`` that is not JSON, with a
matching checksum), a cache file, checksum, numba file or ``__pycache__`` replaced by a
directory, the cache directory that is a file, a results directory's ``.lock`` replaced by a
directory: each heals with one warning line (or is refused with one error line), and the second
run after it is clean. A reference rewritten *with its checksum recomputed* (what a forger would
do) is caught by its content: it must start at y0, keep the first integrals, and follow the flow
(:mod:`gnibench.suite.cell.reference_checks`).

One cache is warmed per module and copied for each test, so that no test compiles from scratch.
"""
from __future__ import annotations

import hashlib
import io
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

GNIBENCH = [str(Path(sys.executable).with_name("gnibench"))]
SOLVE = ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "300", "--every", "100"]
HEYOKA = ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "300", "--every", "100",
          "--reference", "heyoka"]


def _solve(cache: Path, args=SOLVE) -> subprocess.CompletedProcess:
    return subprocess.run(GNIBENCH + list(args), capture_output=True, text=True, check=False,
                          timeout=600, env={**os.environ, "GNIBENCH_CACHE_DIR": str(cache)})


@pytest.fixture(scope="module")
def warmed(tmp_path_factory):
    pytest.importorskip("heyoka")
    cache = tmp_path_factory.mktemp("warm") / "cache"
    plain, heyoka = _solve(cache), _solve(cache, HEYOKA)
    assert plain.returncode == 0 and plain.stderr == "", plain.stderr
    assert heyoka.returncode == 0 and heyoka.stderr == "", heyoka.stderr
    return cache, {"plain": plain.stdout, "heyoka": heyoka.stdout}


@pytest.fixture
def cache(warmed, tmp_path):
    source, outputs = warmed
    copy = tmp_path / "cache"
    shutil.copytree(source, copy, symlinks=True)
    return copy, outputs


def _heals(cache: Path, expected: str, what: str, args=SOLVE) -> str:
    again = _solve(cache, args)
    assert again.returncode == 0, again.stderr
    assert "Traceback" not in again.stderr
    warnings = [ln for ln in again.stderr.splitlines() if ln.startswith("gnibench: warning:")]
    assert len(warnings) == 1 and what in warnings[0], again.stderr
    assert again.stdout == expected
    third = _solve(cache, args)
    assert third.returncode == 0 and third.stderr == "" and third.stdout == expected, third.stderr
    return warnings[0]


def _rewrite_with_checksum(path: Path, raw: bytes) -> None:
    """What a forger does: new content, and the checksum recomputed to match it."""
    path.write_bytes(raw)
    path.with_name(path.name + ".sha256").write_text(hashlib.sha256(raw).hexdigest() + "\n")


def test_problem_code_that_is_not_json_with_a_matching_checksum(cache):
    cache, out = cache
    entry = next((cache / "problems").glob("kepler-2d-*.code.json"))
    _rewrite_with_checksum(entry, b"{ this is not json")
    _heals(cache, out["plain"], "problem code")


def test_problem_code_that_is_json_of_the_wrong_shape(cache):
    cache, out = cache
    entry = next((cache / "problems").glob("kepler-2d-*.code.json"))
    _rewrite_with_checksum(entry, b'{"text": 42, "meta": []}')
    _heals(cache, out["plain"], "problem code")


@pytest.mark.parametrize("which", ["problem code", "its checksum", "kernel module",
                                   "numba file", "__pycache__"])
def test_an_entry_replaced_by_a_directory_is_removed_and_rebuilt(cache, which):
    cache, out = cache
    code = next((cache / "problems").glob("kepler-2d-*.code.json"))
    module = next(p for p in (cache / "kernels").glob("cell_*.py"))
    pycache = cache / "kernels" / "__pycache__"
    target = {"problem code": code, "its checksum": code.with_name(code.name + ".sha256"),
              "kernel module": module,
              "numba file": next(pycache.glob(f"{module.stem}.integrate-*.nbc")),
              "__pycache__": pycache}[which]
    shutil.rmtree(target) if target.is_dir() else target.unlink()
    (target / "inner").mkdir(parents=True)
    again = _solve(cache)
    assert again.returncode == 0 and again.stdout == out["plain"], again.stderr
    assert "Traceback" not in again.stderr
    assert len(again.stderr.splitlines()) <= 1           # at most one warning line
    third = _solve(cache)
    assert third.stderr == "" and third.stdout == out["plain"], third.stderr


def test_a_cache_directory_that_is_a_file_is_one_line(tmp_path):
    path = tmp_path / "cache"
    path.write_text("a file")
    p = _solve(path)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.startswith("gnibench: error: bad GNIBENCH_CACHE_DIR=") and \
        len(p.stderr.splitlines()) == 1


@pytest.mark.parametrize("what", ["directory", "fifo", "socket"])
def test_a_results_lock_replaced_by_a_special_file_heals(tmp_path, capsys, what):
    """A ``.lock`` that is a directory, a FIFO or a socket is removed with one warning line (a
    FIFO was 'gnibench: error: Invalid argument', exit 1, at every run)."""
    import socket

    from gnibench.suite.cli.main import main

    exp = tmp_path / "tiny.toml"
    exp.write_text('name = "tiny"\ntitle = "Tiny"\nreference = "[HLW] (2.2)"\nsteps = 10\n'
                   '[[cells]]\nproblems = ["harmonic-oscillator"]\nmethods = ["rk4"]\n')
    out = tmp_path / "out"
    if what == "directory":
        (out / ".lock" / "inner").mkdir(parents=True)
    else:
        out.mkdir()
        if what == "fifo":
            os.mkfifo(out / ".lock")
        else:
            with socket.socket(socket.AF_UNIX) as s:
                s.bind(str(out / ".lock"))
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    warnings = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(warnings) == 1 and ".lock" in warnings[0]
    assert (out / ".lock").is_file() and (out / "cells.parquet").is_file()


def _forge(cache: Path, change) -> None:
    path = next((cache / "references").glob("kepler-2d-heyoka-*.npz"))
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["y"] = change(arrays["t"], arrays["y"].copy())
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    _rewrite_with_checksum(path, buffer.getvalue())


def _warped(t, y):
    """The exact Kepler orbit at t (1 + 1e-6): on every integral's level set, starting at y0,
    but not the solution at t (a consistent forgery that only the flow check sees)."""
    from gnibench.suite.cell.spec import parse_problem

    pb = parse_problem("kepler-2d")
    rec = pb.record
    forged = np.asarray(rec.exact(t * (1 + 1e-6), rec.y0(pb.values), pb.values), float)
    forged[0] = y[0]
    return forged


@pytest.mark.parametrize("forgery,why", [
    (lambda t, y: y * (1 + 1e-6), "start at the initial point"),
    (lambda t, y: np.vstack([y[:1], y[1:] * (1 + 1e-6)]), "first integral"),
    (_warped, "flow"),
])
def test_a_reference_forged_with_its_checksum_is_caught_by_its_content(cache, forgery, why):
    cache, out = cache
    _forge(cache, forgery)
    warning = _heals(cache, out["heyoka"], "reference solution", HEYOKA)
    assert why.split()[0] in warning


def test_the_forgeries_would_change_global_error(cache):
    """The test above can fail: each forgery, if believed, changes global_error."""
    from gnibench.suite.cell import reference_checks

    cache, _out = cache
    _forge(cache, _warped)
    path = next((cache / "references").glob("kepler-2d-heyoka-*.npz"))
    with np.load(path, allow_pickle=False) as z:
        t, y = z["t"], z["y"]
    from gnibench.suite.cell.spec import parse_problem

    pb = parse_problem("kepler-2d")
    truth = np.asarray(pb.record.exact(t, pb.record.y0(pb.values), pb.values), float)
    truth[0] = pb.record.y0(pb.values)          # the formula at t = 0 is y0 up to round-off
    assert np.max(np.abs(y - truth)) > 1e-7               # far above rk4's 1e-9 error here
    assert "flow" in reference_checks.problem_ok(pb, t, y)
    assert reference_checks.problem_ok(pb, t, truth) == ""
