"""``gnibench bench``: kernel speed in ns/step against a straight C loop, and warm startup cost.

asv style: the cell is loaded and warmed up (compiled or read from the numba disk cache) before
timing; each repeat integrates ``steps`` steps with ``every = steps`` (sampling cost negligible);
ns/step = wall / steps, reported as min and median over the repeats. The C reference
(``bench_c/kepler.c``, ``gcc -O3 -ffp-contract=off``) performs the same floating-point operations
in the same order, so the final states must agree to round-off. Target: numba/C <= 1.5.
"""
from __future__ import annotations

import json
import math
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from importlib import resources
from pathlib import Path

import numpy as np

PROBLEM = "kepler-2d"
H = 2 * math.pi / 1000
REPEATS = 5
TARGET = 1.5
CELLS = (("rk4", "rk4", "rk4"), ("stormer-verlet", "stormer-verlet", "sv"))  # (label, method, C)
C_REFERENCE_NS = {"rk4": 29.0, "sv": 14.0}  # the C numbers on the reference machine


def compiled_cell(method: str, problem: str = PROBLEM, h: float = H):
    """(integrate, y0, par) of a warmed-up cell without modifiers; compile time excluded."""
    from suite.codegen import load
    from suite.solve import prepare

    bound, cfg = prepare(problem, f"{method}:h={h!r}")
    if cfg.modifiers:
        raise ValueError("bench cells take no modifiers")
    mod, _, _ = load(bound, cfg)
    rec = bound.record
    y0 = np.array(rec.y0(bound.values), dtype=np.float64)
    par = np.array(rec.par(bound.values), dtype=np.float64)
    scratch = (np.empty(3), np.empty((3, rec.dim)), np.empty((3, 3)))
    mod.integrate(y0, par, h, 1, h, 1, *scratch)  # warm-up: loads or compiles every function
    return mod.integrate, y0, par


def run_steps(integrate, y0, par, steps: int, h: float = H):
    """One timed call of ``steps`` steps, sampled only at the end: (seconds, final state)."""
    out_t, out_y, out_c = np.empty(3), np.empty((3, y0.size)), np.empty((3, 3))
    t0 = time.perf_counter()
    status, done, rows = integrate(y0, par, h, steps, h, steps, out_t, out_y, out_c)
    dt = time.perf_counter() - t0
    if status != 0 or done != steps:
        raise RuntimeError(f"bench run stopped early: status {status} after {done} steps")
    return dt, out_y[rows - 1].copy()


def time_numba(method: str, steps: int, repeats: int = REPEATS):
    """(min ns/step, median ns/step, final state) of the compiled kernel."""
    integrate, y0, par = compiled_cell(method)
    ts, y = [], None
    for _ in range(repeats):
        dt, y = run_steps(integrate, y0, par, steps)
        ts.append(dt * 1e9 / steps)
    return min(ts), statistics.median(ts), y, y0


def build_c(tmp: Path) -> Path | None:
    """Compile bench_c/kepler.c into ``tmp``; None if gcc is missing."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    src = resources.files("suite") / "bench_c" / "kepler.c"
    exe = tmp / "kepler"
    with resources.as_file(src) as path:
        subprocess.run([gcc, "-O3", "-ffp-contract=off", "-o", str(exe), str(path), "-lm"],
                       check=True, capture_output=True, text=True)
    return exe


def time_c(exe: Path, method: str, steps: int, y0, repeats: int = REPEATS):
    """(min ns/step, median ns/step, final state) of the C loop."""
    args = [str(exe), method, str(steps), repr(H), *(repr(float(v)) for v in y0), str(repeats)]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1]), np.array([float(v) for v in out[2:6]])


def _solve_cmd() -> list[str]:
    exe = Path(sys.executable).with_name("gnibench")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "suite.cli"]


def startup(runs: int = 2) -> list[dict]:
    """Run a small ``gnibench solve`` in fresh processes; per run: process wall time, meta."""
    cmd = _solve_cmd() + ["solve", PROBLEM, "rk4:h=0.01", "--steps", "10", "--format", "json"]
    rows = []
    for _ in range(runs):
        t0 = time.perf_counter()
        p = subprocess.run(cmd, check=True, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        meta = json.loads(p.stdout)["meta"]
        rows.append({"process_seconds": wall, "compile_seconds": meta["compile_seconds"],
                     "numba_cache_misses": meta["numba_cache_misses"]})
    return rows


def bench(steps: int = 2_000_000, with_c: bool = True) -> list[dict]:
    """Print the table (and return its rows): numba vs C ns/step, ratio, agreement, startup."""
    if steps < 1:
        from suite.errors import UserError

        raise UserError(f"bad --steps {steps}; allowed: an integer >= 1")
    print(f"{PROBLEM} e=0.6, h = 2pi/1000, {steps} steps, min/median of {REPEATS} repeats "
          "(compile excluded)")
    rows = []
    with tempfile.TemporaryDirectory(prefix="gnibench-c-") as tmp:
        exe = build_c(Path(tmp)) if with_c else None
        if with_c and exe is None:
            print("gcc not found: C reference skipped")
        head = f"{'method':<22}{'min ns':>9}{'median':>9}"
        if exe:
            head += f"{'C min':>9}{'C med':>9}{'ratio':>7}  {'<=1.5':<6}{'|dy| vs C':>10}"
        print(head)
        for label, method, cname in CELLS:
            lo, med, y, y0 = time_numba(method, steps)
            row = {"method": label, "ns_min": lo, "ns_median": med}
            line = f"{label:<22}{lo:9.2f}{med:9.2f}"
            if exe:
                clo, cmed, cy = time_c(exe, cname, steps, y0)
                dy = float(np.max(np.abs(cy - y)))
                row.update(c_ns_min=clo, c_ns_median=cmed, ratio=lo / clo, max_abs_diff=dy)
                line += (f"{clo:9.2f}{cmed:9.2f}{lo / clo:7.2f}  {'yes' if lo / clo <= TARGET else 'NO':<6}"
                         f"{dy:10.1e}")
            rows.append(row)
            print(line)
        if exe:
            clo, cmed, cy = time_c(exe, "sv-fsal", steps, y0)
            print(f"{'C sv-fsal (info)':<22}{'':18}{clo:9.2f}{cmed:9.2f}")
            rows.append({"method": "c-sv-fsal", "c_ns_min": clo, "c_ns_median": cmed})
            print(f"issue's C reference machine: rk4 {C_REFERENCE_NS['rk4']:g} ns/step, "
                  f"sv {C_REFERENCE_NS['sv']:g} ns/step; agreement expected ~1e-12 (same operations)")
    runs = startup()
    second = runs[-1]
    ok = second["compile_seconds"] < 1.0
    print(f"startup (gnibench solve {PROBLEM} rk4:h=0.01 --steps 10, fresh processes): "
          + ", ".join(f"run {i + 1}: process {r['process_seconds']:.2f} s, load+warm-up "
                      f"{r['compile_seconds']:.3f} s, cache misses {r['numba_cache_misses']}"
                      for i, r in enumerate(runs))
          + f"; second run under 1 s before integrating: {'yes' if ok else 'NO'}")
    rows.append({"startup": runs})
    return rows
