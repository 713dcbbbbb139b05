"""An ensemble of Hénon–Heiles orbits, side by side in one run (issue 42, item 6):

* one ensemble cell of N orbits at one energy (``[cells.ensemble]``, a shell of H = 1/12, [HLW]
  I.3), dop853 and vern9 at rtol = atol = 1e-10, ``gnibench.run`` with one worker (this
  process) and with ``jobs`` workers;
* the same N initial conditions as N separate cells, the same run otherwise, ``jobs`` workers;
* heyoka's ``ensemble_propagate_until`` on ``threads`` threads (the Taylor integrator of the same
  sympy model, JIT-compiled once beforehand, not timed), at the loosest tolerance of a sweep
  whose final error is at most gnibench's for the same orbit, orbit by orbit (the median of the
  ratio <= 1);

the final accuracy of every orbit measured against heyoka at the precision's epsilon. The runs
are ``gnibench.run`` calls in this process (the command's start-up is not counted), each into a
new output directory (nothing reused from a store), with kernels compiled (and the heyoka
integrator built) beforehand; each timing is the minimum over ``repeats`` runs, the
contestants alternating; CPU seconds count this process's threads and its workers.

    python benchmarks/bench_ensembles.py                 # N = 1000, t_end = 100, 3 repeats
    python benchmarks/bench_ensembles.py --quick         # N = 40, t_end = 10, 1 repeat (CI)
    python benchmarks/bench_ensembles.py --json out.json

Prints a Markdown table: wall and CPU seconds of each contestant and method, the ratios the issue
asks (separate cells / ensemble >= 20; ensemble / heyoka <= 1.5, both with the faster of the two
ensemble runs), the median final error of each, and whether each orbit of the ensemble ends on
the same bits as its separate cell.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

METHODS = ("dop853:rtol=1e-10,atol=1e-10", "vern9:rtol=1e-10,atol=1e-10")
ENERGY = 1.0 / 12.0
BOX = ([-0.35, -0.35, -0.35, -0.35], [0.35, 0.35, 0.35, 0.35])
HEYOKA_TOLS = (1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15)


def ensemble_experiment(method: str, n: int, t_end: float, chunk: int) -> dict:
    return {"name": "bench-ensemble", "title": "Hénon–Heiles ensemble", "reference": "[HLW] I.3",
            "t_end": t_end, "reference_solution": "none",
            "cells": [{"problems": ["henon-heiles"], "methods": [method],
                       "ensemble": {"options": ["p10", "p20", "q10", "q20"], "sample": "shell",
                                    "level": {"H": ENERGY}, "low": BOX[0], "high": BOX[1],
                                    "n": n, "seed": 1, "chunk": chunk}}]}


def cells_experiment(method: str, points: np.ndarray, t_end: float) -> dict:
    groups = [{"problems": [f"henon-heiles:p10={p1!r},p20={p2!r},q10={q1!r},q20={q2!r}"],
               "methods": [method], "every": 10 ** 9}
              for p1, p2, q1, q2 in points.tolist()]
    return {"name": "bench-cells", "title": "Hénon–Heiles cells", "reference": "[HLW] I.3",
            "t_end": t_end, "reference_solution": "none", "cells": groups}


def cpu() -> float:
    """CPU seconds of this process (all its threads) and of its children that ended."""
    me, kids = (resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def timed_run(experiment: dict, jobs: int):
    """(wall seconds, CPU seconds, RunResult) of a fresh run (a new output directory: nothing
    reused), its workers' CPU included."""
    import gnibench

    with tempfile.TemporaryDirectory(prefix="gnibench-bench-") as d:
        c0, t0 = cpu(), time.perf_counter()
        res = gnibench.run(experiment, output=Path(d) / "out", jobs=jobs)
        return time.perf_counter() - t0, cpu() - c0, res


def final_states(res, ensemble: bool) -> np.ndarray:
    """Each orbit's final state (p1, p2, q1, q2), in orbit order."""
    names = ["p1", "p2", "q1", "q2"]
    if ensemble:
        orbits = res.ensemble.sort_values("orbit")
        return orbits[[f"final_{s}" for s in names]].to_numpy(float)
    last = res.samples.groupby("cell").tail(1).sort_values("cell")
    return last[names].to_numpy(float)


def heyoka_run(problem, y0: np.ndarray, t_end: float, tol: float, threads: int, repeats: int):
    """(min wall seconds of ensemble_propagate_until, final states) at Taylor tolerance tol."""
    import heyoka as hy
    from gnibench.methods.engines.heyoka import heyoka_system

    system = heyoka_system(problem.record)
    pars = [float(x) for x in problem.record.par(problem.values)][:system.n_pars]
    ta = hy.taylor_adaptive(system.equations, list(y0[0]), tol=tol, pars=pars)
    starts = [list(row) for row in y0]

    def gen(copy, i):
        copy.state[:] = starts[i]
        copy.time = 0.0
        return copy

    best, best_cpu = float("inf"), float("inf")
    for _ in range(repeats):
        c0, t0 = cpu(), time.perf_counter()
        out = hy.ensemble_propagate_until(ta, t_end, len(y0), gen, algorithm="thread",
                                          max_workers=threads)
        best, best_cpu = min(best, time.perf_counter() - t0), min(best_cpu, cpu() - c0)
    return best, best_cpu, np.array([r[0].state for r in out])


def main(argv=None) -> int:
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--orbits", type=int, default=1000)
    a.add_argument("--t-end", type=float, default=100.0)
    a.add_argument("--jobs", type=int, default=2)
    a.add_argument("--threads", type=int, default=2)
    a.add_argument("--repeats", type=int, default=3)
    a.add_argument("--quick", action="store_true", help="40 orbits to t = 10, once (CI)")
    a.add_argument("--json", type=Path)
    args = a.parse_args(argv)
    load = os.getloadavg()[0]
    if args.quick:
        args.orbits, args.t_end, args.repeats = 40, 10.0, 1
    from gnibench.suite.api.running import toml_text
    from gnibench.suite.cell.ensemble_reference import propagate
    from gnibench.suite.runs.ensembles import initial_states
    from gnibench.suite.runs.experiment import parse_experiment

    n, t_end = args.orbits, args.t_end
    chunk = max(1, -(-n // (2 * args.jobs)))             # two units per worker
    cell = parse_experiment(toml_text(ensemble_experiment(METHODS[0], n, t_end, chunk)),
                            "bench").cells[0]
    points = cell.ensemble.points
    y0 = initial_states(cell)
    reference = propagate(cell.spec.problem, y0, np.array([0.0, t_end]))[:, -1]
    rows = []
    for method in METHODS:
        ens_exp = ensemble_experiment(method, n, t_end, chunk)
        cells_exp = cells_experiment(method, points, t_end)
        timed_run(ens_exp, args.jobs)                      # compile (or load) the kernels
        timed_run(cells_experiment(method, points[:2], t_end), args.jobs)
        walls = {"ensemble": [], "ensemble_j1": [], "cells": []}
        cpus = {k: [] for k in walls}
        for _ in range(args.repeats):
            for key, exp, jobs in (("ensemble_j1", ens_exp, 1), ("ensemble", ens_exp, args.jobs),
                                   ("cells", cells_exp, args.jobs)):
                w, c, res = timed_run(exp, jobs)
                walls[key].append(w)
                cpus[key].append(c)
                if key == "ensemble":
                    ens = res
                elif key == "cells":
                    sep = res
        err_ens = np.linalg.norm(final_states(ens, True) - reference, axis=1)
        err_cells = np.linalg.norm(final_states(sep, False) - reference, axis=1)
        tol, hy_wall, hy_cpu, hy_err = None, None, None, None
        for t in HEYOKA_TOLS:                      # the loosest at least as accurate per orbit
            w, c, states = heyoka_run(cell.spec.problem, y0, t_end, t, args.threads,
                                      args.repeats)
            e = np.linalg.norm(states - reference, axis=1)
            if np.median(e / err_ens) <= 1.0:
                tol, hy_wall, hy_cpu, hy_err = t, w, c, e
                break
        best = "ensemble" if min(walls["ensemble"]) <= min(walls["ensemble_j1"]) else \
            "ensemble_j1"
        rows.append({"method": method, "orbits": n, "t_end": t_end, "jobs": args.jobs,
                     **{f"{k}_s": min(v) for k, v in walls.items()},
                     **{f"{k}_cpu_s": min(v) for k, v in cpus.items()},
                     "best_ensemble": best,
                     "heyoka_s": hy_wall, "heyoka_cpu_s": hy_cpu, "heyoka_tol": tol,
                     "heyoka_threads": args.threads,
                     "median_error_ensemble": float(np.median(err_ens)),
                     "median_error_cells": float(np.median(err_cells)),
                     "median_error_heyoka": None if hy_err is None else float(np.median(hy_err)),
                     "same_bits": bool(np.array_equal(final_states(ens, True),
                                                      final_states(sep, False)))})
    print(f"| method | orbits | ensemble -j 1: wall, CPU (s) | ensemble -j {args.jobs}: wall, "
          f"CPU (s) | separate cells -j {args.jobs}: wall, CPU (s) | cells / ensemble (wall) | "
          f"heyoka, {args.threads} threads: wall, CPU (s) (tol) | ensemble / heyoka (wall) | "
          "median final error: ensemble, heyoka | same bits |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        ens = r[f"{r['best_ensemble']}_s"]
        hy, ratio = "–", "–"
        if r["heyoka_s"] is not None:
            hy = f"{r['heyoka_s']:.3f}, {r['heyoka_cpu_s']:.3f} ({r['heyoka_tol']:g})"
            ratio = f"{ens / r['heyoka_s']:.2f}"
        print(f"| {r['method']} | {r['orbits']} | {r['ensemble_j1_s']:.3f}, "
              f"{r['ensemble_j1_cpu_s']:.3f} | {r['ensemble_s']:.3f}, {r['ensemble_cpu_s']:.3f} | "
              f"{r['cells_s']:.3f}, {r['cells_cpu_s']:.3f} | {r['cells_s'] / ens:.1f} | {hy} | "
              f"{ratio} | {r['median_error_ensemble']:.2e}, "
              f"{r['median_error_heyoka'] or float('nan'):.2e} | {r['same_bits']} |")
    if args.json:
        from gnibench.suite.foundation.benchmarks import script_result

        for r in rows:
            ens = r[f"{r['best_ensemble']}_s"]
            r["cells_over_ensemble"] = r["cells_s"] / ens
            r["ensemble_over_heyoka"] = None if r["heyoka_s"] is None else ens / r["heyoka_s"]
        goals = {"cells_over_ensemble": [">=", 20, "1,000 separate cells / the ensemble (wall)"],
                 "ensemble_over_heyoka": ["<=", 1.5, "the ensemble / heyoka's "
                                          "ensemble_propagate_until at the same accuracy (wall)"]}
        args.json.write_text(json.dumps(script_result("bench_ensembles.py", rows, goals, load),
                                        indent=1) + "\n")
    return 0 if all(r["same_bits"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
