"""Print issue 19's accuracy tables of a work-precision experiment from one or more runs.

    python benchmarks/wp_goals.py results/wp-kepler-2d-1 results/wp-kepler-2d-2 ...

Each directory is one ``gnibench run`` of the same experiment (``--fresh``); each cell's wall time
is the median over them (reports/goals.py). Prints the per-family table (ms and nfev of the fastest
cell within each accuracy, best final error) and the fastest compiled method against heyoka
(double) and IAS15.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from gnibench.reports.goals import GOAL_ACCURACIES, family_table, goal_table, median_walls
from gnibench.reports.results import load_results


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", type=Path)
    ap.add_argument("--accuracy", default=",".join(f"{a:g}" for a in GOAL_ACCURACIES))
    ap.add_argument("--families", default="", help="comma-separated family labels (default: all)")
    a = ap.parse_args(argv)
    runs = [load_results(d) for d in a.dirs]
    accuracies = tuple(float(x) for x in a.accuracy.split(","))
    cells, walls = runs[0].cells, median_walls(runs)
    fams = [f for f in a.families.split(",") if f] or None
    print(f"{runs[0].name}: {len(runs)} run(s), wall time = median over the runs\n")
    print("\n".join(family_table(cells, walls, accuracies, fams)) + "\n")
    print("\n".join(goal_table(cells, walls, accuracies)))


if __name__ == "__main__":
    main()
