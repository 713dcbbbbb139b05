"""The runner's own cost (issue 42, item 5), measured on a matrix of small warm cells:

1. **parent CPU per cell**: ``run_experiment`` of N cells with ``-j 2`` in this process, the CPU
   time of this process only (its workers excluded), beyond a run of one cell (the imports and
   fixed costs), divided by N - 1; and the share of reading the experiment; target <= 1 ms;
2. **speed-up of -j 2 over -j 1**: ``gnibench run`` (the command, start-up included) of N warm
   cells of about 2 ms each, wall time, the minimum of ``repeats`` alternating runs; and the
   same of the run phase alone (``run_experiment`` in this process, the pool started before,
   as the command starts it first thing); target >= 1.8 (needs an idle 2-core machine);
   Extra, for what the runner's parallel part gives: ``ready_run_phase_speedup_j2``, the run
   phase with a pool whose workers are ready (started and preloaded before the clock starts),
   so that their start-up (numba, about 0.6 s of CPU, which the command hides behind its own
   start-up) is not counted; no target;
3. **a stored cell reused**: the same command again on the stored matrix, CPU per cell beyond a
   run of one stored cell; target <= 0.5 ms;
4. **the report of N cells**: ``gnibench report`` of the matrix's results twice (the second finds
   every figure drawn: what remains is the report's own cost), wall time; target <= 2 s.

    python benchmarks/bench_runner_cost.py                  # N = 1000 cells of ~2 ms
    python benchmarks/bench_runner_cost.py --cells 100 --repeats 1      # quicker (CI: --quick)

Prints one line per measure with its target; ``--json FILE`` writes them.
"""
from __future__ import annotations

import argparse
import io
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GNIBENCH = [str(Path(sys.executable).with_name("gnibench"))]


def matrix(n: int, steps: int = 40000, every: int = 4000) -> str:
    """n pendulum cells of ``steps`` RK4 steps (about 2 ms each), one per initial momentum."""
    values = ", ".join(f"{0.5 + k * 1e-4:.6f}" for k in range(n))
    return (f'name = "runner-cost"\ntitle = "{n} small cells"\nreference = "[HLW] I.1"\n'
            f"steps = {steps}\nevery = {every}\n\n[[cells]]\nproblems = [\"pendulum\"]\n"
            f"methods = [\"rk4:h=0.001\"]\nvary.problem.p0 = [{values}]\n")


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def parent_cpu(toml: Path, out: Path, jobs: int, ready: bool = False) -> dict:
    """CPU seconds of this process (not its workers) for one run, and for reading the
    experiment alone (``ready``: the pool's workers preloaded before the clock starts)."""
    from gnibench.suite.runs import executors
    from gnibench.suite.runs.experiment import load_experiment
    from gnibench.suite.runs.runner import run_experiment

    shutil.rmtree(out, ignore_errors=True)
    c0 = cpu()
    load_experiment(toml)
    parse = cpu() - c0
    pool = executors.start("local", jobs)
    if ready and pool is not None:
        pool.started()      # the adopted workers say their pids once the first has preloaded
    c0, t0 = cpu(), time.perf_counter()
    run_experiment(toml, out, jobs=jobs, log=io.StringIO(), pool=pool)
    total, wall = cpu() - c0, time.perf_counter() - t0
    if pool is not None:
        pool.stop()
    return {"parse": parse, "total": total, "wall": wall}


def command(args: list[str]) -> tuple[float, float]:
    """(wall, CPU of the command and its children) of one gnibench command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(GNIBENCH + args, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def main(argv=None) -> int:
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--cells", type=int, default=1000)
    a.add_argument("--repeats", type=int, default=3)
    a.add_argument("--quick", action="store_true", help="40 cells, once (CI)")
    a.add_argument("--json", type=Path)
    args = a.parse_args(argv)
    load = os.getloadavg()[0]
    if args.quick:
        args.cells, args.repeats = 40, 1
    n = args.cells
    out: dict = {"cells": n}
    with tempfile.TemporaryDirectory(prefix="gnibench-runner-cost-") as d:
        root = Path(d)
        toml, one = root / "matrix.toml", root / "one.toml"
        toml.write_text(matrix(n))
        one.write_text(matrix(1))
        command(["run", str(toml), "-o", str(root / "warm"), "-j", "1", "--no-report"])
        import pandas  # noqa: F401 - imported before the measures (the tables need it)
        import pyarrow.parquet  # noqa: F401

        parent_cpu(one, root / "first", 2)                     # this process's first run
        alone = min(parent_cpu(one, root / "alone", 2)["total"] for _ in range(args.repeats))
        costs = [parent_cpu(toml, root / "parent", 2) for _ in range(args.repeats)]
        best = min(costs, key=lambda c: c["total"])
        out["parent_ms_per_cell"] = 1e3 * (best["total"] - alone) / (n - 1)
        out["parent_parse_ms_per_cell"] = 1e3 * best["parse"] / n
        out["run_phase_j2_s"] = min(c["wall"] for c in costs)
        serial = min(parent_cpu(toml, root / "serial", 1)["wall"] for _ in range(args.repeats))
        out["run_phase_j1_s"] = serial
        out["run_phase_speedup_j2"] = serial / out["run_phase_j2_s"]
        ready = min(parent_cpu(toml, root / "ready", 2, ready=True)["wall"]
                    for _ in range(args.repeats))
        out["ready_run_phase_j2_s"] = ready
        out["ready_run_phase_speedup_j2"] = serial / ready
        walls: dict[int, list[float]] = {1: [], 2: []}
        cpus: dict[int, list[float]] = {1: [], 2: []}
        for _ in range(args.repeats):
            for jobs in (1, 2):
                o = root / f"j{jobs}"
                shutil.rmtree(o, ignore_errors=True)
                w, c = command(["run", str(toml), "-o", str(o), "-j", str(jobs), "--no-report"])
                walls[jobs].append(w)
                cpus[jobs].append(c)
        out["j1_s"], out["j2_s"] = min(walls[1]), min(walls[2])
        out["j1_cpu_s"], out["j2_cpu_s"] = min(cpus[1]), min(cpus[2])     # all processes
        out["speedup_j2"] = out["j1_s"] / out["j2_s"]
        command(["run", str(one), "-o", str(root / "one"), "-j", "1", "--no-report"])
        again = min(command(["run", str(toml), "-o", str(root / "j1"), "-j", "1",
                             "--no-report"])[1] for _ in range(args.repeats))
        alone = min(command(["run", str(one), "-o", str(root / "one"), "-j", "1",
                             "--no-report"])[1] for _ in range(args.repeats))
        out["reuse_ms_per_cell"] = 1e3 * (again - alone) / max(n - 1, 1)
        report = root / "site"
        command(["report", str(root / "j1"), "-o", str(report)])       # draws the plots
        out["report_s"] = min(command(["report", str(root / "j1"), "-o", str(report)])[0]
                              for _ in range(args.repeats))
    targets = {"parent_ms_per_cell": ("<=", 1.0), "speedup_j2": (">=", 1.8),
               "run_phase_speedup_j2": (">=", 1.8),
               "reuse_ms_per_cell": ("<=", 0.5), "report_s": ("<=", 2.0)}
    for k, v in out.items():
        goal = targets.get(k)
        mark = "" if goal is None else f"   (target {goal[0]} {goal[1]})"
        print(f"{k}: {v:.3f}{mark}" if isinstance(v, float) else f"{k}: {v}")
    print(f"machine load (1 min) at the end: {os.getloadavg()[0]:.2f}")
    if args.json:
        from gnibench.suite.foundation.benchmarks import script_result

        goals = {k: [op, v, k.replace("_", " ")] for k, (op, v) in targets.items()}
        args.json.write_text(json.dumps(script_result("bench_runner_cost.py", [out], goals, load),
                                        indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
