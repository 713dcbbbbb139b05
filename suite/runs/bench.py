"""``gnibench bench``: kernel speed in ns/step against a straight C loop, and warm startup cost.

asv style: the cell is loaded and warmed up (compiled or read from the numba disk cache) before
timing; each repeat integrates ``steps`` steps with ``every = steps`` (sampling cost negligible);
ns/step = wall / steps, reported as min and median over the repeats. The C reference
(``bench_c/kepler.c``, ``gcc -O3 -ffp-contract=off``) performs the same floating-point operations
in the same order, so the final states must agree to round-off. Target: numba/C <= 1.5.

Adaptive part (``bench_adaptive``): dopri5 and dop853 on kepler-2d, rtol = atol = 1e-10, 100
periods, Hairer's HINIT start, µs per attempted step (accepted + rejected). References: (a)
``bench_c/kepler_adaptive.c``, a C port of the same driver, its unrolled step written from the
same ``Pair`` record (``pair_header``): same operations, so the same step counts and final state
(checked in the table and by tests/runs/test_bench_adaptive.py);
(b) ``scipy.integrate.solve_ivp`` (RK45 / DOP853, same tolerances, a plain Python right-hand
side) over ``SCIPY_PERIODS`` periods, per step = wall / (nfev / evaluations per step).
Targets: numba <= 1.3x C, and >= 100x faster than solve_ivp per step.
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
from gnibench.suite.cell.calls import UNLIMITED
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare

PROBLEM = "kepler-2d"
H = 2 * math.pi / 1000
REPEATS = 5
TARGET = 1.5
CELLS = (("rk4", "rk4", "rk4"), ("stormer-verlet", "stormer-verlet", "sv"))  # (label, method, C)
C_REFERENCE_NS = {"rk4": 29.0, "sv": 14.0}  # the C numbers on the reference machine


def compiled_cell(method: str, problem: str = PROBLEM, h: float = H):
    """(problem, method) of a warmed-up cell without modifiers, parsed once; compile time excluded
    (the driver facade keeps the compiled cell of this process)."""
    bound, cfg = prepare(problem, f"{method}:h={h!r}")
    if cfg.modifiers:
        raise ValueError("bench cells take no modifiers")
    solve(bound, cfg, steps=1, budget=None, reference="none")     # warm-up: loads or compiles every function
    return bound, cfg


def run_steps(bound, cfg, steps: int):
    """One timed integration of ``steps`` steps through the driver facade in a single call of the
    compiled driver, sampled only at the end: (seconds inside the compiled call, final state)."""
    traj = solve(bound, cfg, steps=steps, every=steps, budget=None, reference="none")
    if traj.status != "ok" or traj.steps[-1] != steps:
        raise RuntimeError(f"bench run stopped early: {traj.status} after {traj.steps[-1]} steps")
    return traj.wall_seconds, traj.y[-1].copy()


def time_numba(method: str, steps: int, repeats: int = REPEATS):
    """(min ns/step, median ns/step, final state) of the compiled kernel."""
    bound, cfg = compiled_cell(method)
    ts, y = [], None
    for _ in range(repeats):
        dt, y = run_steps(bound, cfg, steps)
        ts.append(dt * 1e9 / steps)
    return min(ts), statistics.median(ts), y, np.array(bound.record.y0(bound.values))


def build_c(tmp: Path) -> Path | None:
    """Compile bench_c/kepler.c into ``tmp``; None if gcc is missing."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    src = resources.files("gnibench.suite.runs") / "bench_c" / "kepler.c"
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
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "gnibench.suite.cli.main"]


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


def bench(steps: int = 2_000_000, with_c: bool = True, adaptive: bool = True,
          with_scipy: bool = True) -> list[dict]:
    """Print the tables (and return their rows): fixed step numba vs C ns/step, ratio, agreement;
    adaptive dopri5/dop853 vs C and solve_ivp (``bench_adaptive``); startup."""
    if steps < 1:
        from gnibench.suite.foundation.errors import UserError, named

        raise UserError(f"bad {named('--steps', str(steps))}; allowed: an integer >= 1")
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
    if adaptive:
        rows.extend({"adaptive": True, **r} for r in bench_adaptive(with_c, with_scipy))
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


# ---------------------------------------------------------------- adaptive (dopri5 / dop853)

ADAPTIVE_TOL = 1e-10
ADAPTIVE_PERIODS = 100
SCIPY_PERIODS = 10
ADAPTIVE_TARGET_C = 1.3
ADAPTIVE_TARGET_SCIPY = 100.0
ADAPTIVE_REPEATS = 25      # one run is a few ms: many repeats make the min robust to load
ADAPTIVE_CELLS = (("dopri5", "RK45"), ("dop853", "DOP853"))  # (gnibench method, solve_ivp method)


def adaptive_cell(method: str, tol: float = ADAPTIVE_TOL, problem: str = PROBLEM):
    """(problem, method, Pair) of a warmed-up adaptive cell, parsed once; compile time excluded."""
    bound, cfg = prepare(problem, f"{method}:adaptive=true,rtol={tol!r},atol={tol!r}")
    run_adaptive(bound, cfg, 1.0)      # warm-up
    return bound, cfg, cfg.base.record.data


def run_adaptive(bound, cfg, t_end: float):
    """One timed adaptive integration to t_end through the driver facade (h0 = 0: HINIT,
    hmax = t_end), sampled only at the end: (seconds inside the compiled call, accepted,
    rejected, nfev, final state)."""
    traj = solve(bound, cfg, t_end=t_end, every=UNLIMITED, budget=None, reference="none")
    if traj.status != "ok":
        raise RuntimeError(f"adaptive bench run stopped: {traj.status}")
    return (traj.wall_seconds, int(traj.steps[-1]), int(traj.rejected[-1]), float(traj.nfev[-1]),
            traj.y[-1].copy())


def time_numba_adaptive(method: str, periods: int = ADAPTIVE_PERIODS,
                        repeats: int = ADAPTIVE_REPEATS,
                        tol: float = ADAPTIVE_TOL) -> dict:
    bound, cfg, pair = adaptive_cell(method, tol)
    y0 = np.array(bound.record.y0(bound.values))
    t_end = periods * 2 * math.pi
    ts = []
    for _ in range(repeats):
        dt, nacc, nrej, nfev, y = run_adaptive(bound, cfg, t_end)
        ts.append(dt * 1e6 / (nacc + nrej))
    return {"us_min": min(ts), "us_median": statistics.median(ts), "accepted": nacc,
            "rejected": nrej, "nfev": nfev, "y": y, "y0": y0, "pair": pair}


def pair_header(pair, n: int = 4) -> str:
    """The C header kepler_adaptive.c is compiled with: the pair's controller constants and its
    ``step_err``, unrolled with constant coefficients as methods/embedded_rk.py writes the numba
    ``attempt`` (same operations, same order: zero coefficients skipped, sums left to right)."""
    tab, s = pair.tab, pair.tab.stages
    if not pair.fsal:
        raise ValueError("kepler_adaptive.c takes FSAL pairs only")

    def lit(x):
        return repr(float(x))

    def comb(w, i):
        return " + ".join(f"{lit(c)} * k{j}[{i}]" for j, c in enumerate(w) if c != 0)

    lazy = int(pair.lazy_last)      # f(y1) only once accepted (DOP853), as the numba driver
    lines = [f"#define S {s}", f"#define LAZY_LAST {lazy}", f"#define IORD {pair.iord}",
             f"#define EXPO {pair.expo!r}",
             f"#define BETA {pair.beta!r}", f"#define SAFE {pair.safe!r}",
             f"#define FAC1 {pair.fac1!r}", f"#define FAC2 {pair.fac2!r}",
             "static double step_err(const double *y, double h, const double *k0, double rtol,",
             "                       double atol, double *y1, double *knew) {",
             "    double z[4];"]
    for st in range(1, s - 1):
        lines.append(f"    double k{st}[4];")
        for i in range(n):
            lines.append(f"    z[{i}] = y[{i}] + h * ({comb(tab.a[st][:st], i)});")
        lines.append(f"    field(z, k{st});")
    for i in range(n):
        lines.append(f"    y1[{i}] = y[{i}] + h * ({comb(tab.b, i)});")
    lines += [f"    const double *k{s - 1} = knew;", f"    (void)k{s - 1};",
              "    (void)knew;" if lazy else "    field(y1, knew);",
              "    double acc = 0.0, acc3 = 0.0, sk, q;"]
    for i in range(n):
        lines.append(f"    sk = atol + rtol * fmax(fabs(y[{i}]), fabs(y1[{i}]));")
        if pair.e3 is None:
            lines.append(f"    q = h * ({comb(pair.e, i)}) / sk; acc += q * q;")
        else:
            lines.append(f"    q = ({comb(pair.e, i)}) / sk; acc += q * q;")
            lines.append(f"    q = ({comb(pair.e3, i)}) / sk; acc3 += q * q;")
    if pair.e3 is None:
        lines.append(f"    (void)acc3; return sqrt(acc / {n});")
    else:
        lines += ["    double deno = acc + 0.01 * acc3;", "    if (deno <= 0.0) deno = 1.0;",
                  f"    return fabs(h) * acc / sqrt(deno * {n});"]
    lines.append("}")
    return "\n".join(lines) + "\n"


def build_c_adaptive(tmp: Path, method: str, pair) -> Path | None:
    """Compile bench_c/kepler_adaptive.c with the pair's header into ``tmp``; None without gcc."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    (tmp / method).mkdir(exist_ok=True)
    (tmp / method / "pair.h").write_text(pair_header(pair))
    src = resources.files("gnibench.suite.runs") / "bench_c" / "kepler_adaptive.c"
    exe = tmp / f"kepler_{method}"
    with resources.as_file(src) as path:
        # -march=native: numba compiles for the host CPU too (-ffp-contract=off still forbids FMA)
        subprocess.run([gcc, "-O3", "-march=native", "-ffp-contract=off", "-fno-math-errno",
                        "-I", str(tmp / method), "-o", str(exe), str(path), "-lm"],
                       check=True, capture_output=True, text=True)
    return exe


def time_c_adaptive(exe: Path, y0, periods: int = ADAPTIVE_PERIODS,
                    repeats: int = ADAPTIVE_REPEATS,
                    tol: float = ADAPTIVE_TOL) -> dict:
    args = [periods * 2 * math.pi, tol, tol, *map(float, y0)]
    out = subprocess.run([str(exe), *map(repr, args), str(repeats)], check=True,
                         capture_output=True, text=True).stdout.split()
    return {"us_min": float(out[0]), "us_median": float(out[1]), "accepted": int(out[2]),
            "rejected": int(out[3]), "nfev": float(out[4]),
            "y": np.array([float(v) for v in out[5:9]])}


def time_scipy(method: str, y0, periods: int = SCIPY_PERIODS, tol: float = ADAPTIVE_TOL,
               repeats: int = 3) -> dict:
    """solve_ivp on the Kepler field written as plain Python (numpy arrays in and out)."""
    from scipy.integrate import solve_ivp

    def kepler(t, y):
        r2 = y[2] * y[2] + y[3] * y[3]
        t0 = 1.0 / (r2 * math.sqrt(r2))
        return np.array([-t0 * y[2], -t0 * y[3], y[0], y[1]])

    per_step = {"RK45": 6, "DOP853": 12}[method]     # evaluations per attempted step (FSAL)
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = solve_ivp(kepler, (0.0, periods * 2 * math.pi), y0, method=method, rtol=tol,
                        atol=tol)
        dt = time.perf_counter() - t0
        steps = (sol.nfev - 2) / per_step            # 2: f(y0) and the initial-step probe
        ts.append(dt * 1e6 / steps)
    return {"us_min": min(ts), "us_median": statistics.median(ts), "accepted": len(sol.t) - 1,
            "attempted": steps}


def bench_adaptive(with_c: bool = True, with_scipy: bool = True,
                   periods: int = ADAPTIVE_PERIODS) -> list[dict]:
    """Print the adaptive table (and return its rows): µs/step of numba vs C vs solve_ivp."""
    print(f"{PROBLEM} e=0.6, adaptive rtol = atol = {ADAPTIVE_TOL:g}, {periods} periods "
          f"(solve_ivp: {SCIPY_PERIODS}), µs per attempted step, min/median of {ADAPTIVE_REPEATS} repeats")
    rows = []
    with tempfile.TemporaryDirectory(prefix="gnibench-c-") as tmp:
        have_gcc = with_c and shutil.which("gcc") is not None
        if with_c and not have_gcc:
            print("gcc not found: C reference skipped")
        head = f"{'method':<9}{'acc+rej':>14}{'min us':>9}{'median':>9}"
        if have_gcc:
            head += f"{'C min':>9}{'ratio':>7}  {'<=1.3':<6}{'same steps':<11}{'|dy| vs C':>10}"
        if with_scipy:
            head += f"{'scipy us':>10}{'speedup':>9}  {'>=100':<5}"
        print(head)
        for method, scipy_method in ADAPTIVE_CELLS:
            r = time_numba_adaptive(method, periods)
            row = {"method": method, "us_min": r["us_min"], "us_median": r["us_median"],
                   "accepted": r["accepted"], "rejected": r["rejected"]}
            line = (f"{method:<9}{r['accepted']:>9}+{r['rejected']:<4}{r['us_min']:9.4f}"
                    f"{r['us_median']:9.4f}")
            if have_gcc:
                exe = build_c_adaptive(Path(tmp), method, r["pair"])
                c = time_c_adaptive(exe, r["y0"], periods)
                same = (c["accepted"], c["rejected"]) == (r["accepted"], r["rejected"])
                dy = float(np.max(np.abs(c["y"] - r["y"])))
                ratio = r["us_min"] / c["us_min"]
                row.update(c_us_min=c["us_min"], c_us_median=c["us_median"], c_ratio=ratio,
                           same_steps=same, max_abs_diff=dy)
                line += (f"{c['us_min']:9.4f}{ratio:7.2f}  "
                         f"{'yes' if ratio <= ADAPTIVE_TARGET_C else 'NO':<6}"
                         f"{'yes' if same else 'NO':<11}{dy:10.1e}")
            if with_scipy:
                sp = time_scipy(scipy_method, r["y0"])
                speedup = sp["us_min"] / r["us_min"]
                row.update(scipy_method=scipy_method, scipy_us_min=sp["us_min"],
                           scipy_speedup=speedup)
                line += (f"{sp['us_min']:10.2f}{speedup:9.0f}  "
                         f"{'yes' if speedup >= ADAPTIVE_TARGET_SCIPY else 'NO':<5}")
            rows.append(row)
            print(line)
    return rows
