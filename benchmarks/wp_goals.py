"""Print issue 19's accuracy tables of a work-precision experiment from one or more runs.

    python benchmarks/wp_goals.py results/wp-kepler-2d-1 results/wp-kepler-2d-2 ...

Each directory is one ``gnibench run`` of the same experiment (``--fresh``); each cell's wall time
is the median over them (reports/goals.py). Prints the per-family table (ms and nfev of the fastest
cell within each accuracy, best final error) and the fastest compiled method against heyoka
(double) and IAS15.

``--retime N``: also time the cells again in this one process, serially, N rounds over all cells
(round robin, so a burst of load from other processes hits every method alike), keeping each
cell's minimum: the ratios between methods of one process, less scattered on a loaded machine than
single runs (scipy's cells and cells whose error misses every accuracy are skipped).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from gnibench.reports.goals import GOAL_ACCURACIES, family_table, goal_table, median_walls
from gnibench.reports.results import load_results


def retime(experiment: str, cells, rounds: int, worst: float) -> dict[tuple[str, str], float]:
    """(problem, method) -> the minimum integration wall time of ``rounds`` serial solves."""
    from gnibench.suite.cell.driver import integrate
    from gnibench.suite.runs.experiment import load_experiment

    ok = {(str(r.problem), str(r.method)) for r in cells.itertuples(index=False)
          if r.status == "ok" and float(r.final_global_error) <= worst
          and not str(r.family).startswith("scipy-")}
    todo = [c for c in load_experiment(experiment).cells if (c.problem, c.method) in ok]
    best = {(c.problem, c.method): math.inf for c in todo}
    for _ in range(rounds):
        for c in todo:
            wall = integrate(c.spec).wall_seconds
            best[(c.problem, c.method)] = min(best[(c.problem, c.method)], wall)
    return best


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", type=Path)
    ap.add_argument("--accuracy", default=",".join(f"{a:g}" for a in GOAL_ACCURACIES))
    ap.add_argument("--families", default="", help="comma-separated family labels (default: all)")
    ap.add_argument("--retime", type=int, default=0, metavar="N",
                    help="also time the cells N times serially in this process (minimum)")
    a = ap.parse_args(argv)
    runs = [load_results(d) for d in a.dirs]
    accuracies = tuple(float(x) for x in a.accuracy.split(","))
    cells, walls = runs[0].cells, median_walls(runs)
    fams = [f for f in a.families.split(",") if f] or None
    print(f"{runs[0].name}: {len(runs)} run(s), wall time = median over the runs\n")
    print("\n".join(family_table(cells, walls, accuracies, fams)) + "\n")
    print("\n".join(goal_table(cells, walls, accuracies)))
    if a.retime:
        walls = retime(runs[0].name, cells, a.retime, max(accuracies))
        print(f"\nthe same cells timed again in one process: minimum of {a.retime} serial rounds\n")
        print("\n".join(family_table(cells, walls, accuracies, fams)) + "\n")
        print("\n".join(goal_table(cells, walls, accuracies)))


if __name__ == "__main__":
    main()
