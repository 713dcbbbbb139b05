"""Keep a random sample of a cosmic-ray session's mutants, per package (README.md beside this file).

``python sample.py SESSION.sqlite N SEED``: of the pending work items, N per package (the first
two folders of the module path, e.g. suite/metrics, methods/engines, reports) are kept, drawn
with ``random.Random(SEED)``; the others are marked skipped (cosmic-ray then does not run them).
"""
from __future__ import annotations

import random
import sys
from collections import defaultdict

from cosmic_ray.work_db import WorkDB, use_db
from cosmic_ray.work_item import WorkerOutcome, WorkResult


def package(path: str) -> str:
    """suite/runs, suite/metrics, suite/api, methods/engines (with methods/external.py and
    methods/scipy_methods.py), reports."""
    parts = path.split("/")
    if parts[0] == "methods":
        return "methods/engines"
    return "/".join(parts[:2]) if parts[0] == "suite" else parts[0]


def main(session: str, n: int, seed: int) -> None:
    with use_db(session, WorkDB.Mode.open) as db:
        items = sorted(db.pending_work_items, key=lambda w: w.job_id)
        by_package = defaultdict(list)
        for item in items:
            by_package[package(str(item.mutations[0].module_path))].append(item)
        rng = random.Random(seed)
        skip = []
        for pkg, group in sorted(by_package.items()):
            keep = set(w.job_id for w in rng.sample(group, min(n, len(group))))
            skip += [w.job_id for w in group if w.job_id not in keep]
            print(f"{pkg}: {len(group)} mutants, {len(keep)} sampled")
        db.set_multiple_results(skip, WorkResult(worker_outcome=WorkerOutcome.SKIPPED))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))
