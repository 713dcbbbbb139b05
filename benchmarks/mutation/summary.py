"""Summarise a cosmic-ray session into benchmarks/mutation/cosmic-ray-<date>.json (README.md).

``python summary.py SESSION.sqlite[,MORE.sqlite] RUN_LOG.jsonl[,MORE.jsonl] OUT.json COMMIT``
(several sessions: samples drawn with other seeds from the same mutants; a mutant run twice is
counted once): per package, the mutants
cosmic-ray generated, how many of the sample were run (sampled), killed, survived, not settled,
or not run (an interrupted campaign) (the test command's
time limit reached without a failure; cosmic-ray counts a timeout as killed, we do not), and
every survivor with its diff.
"""
from __future__ import annotations

import json
import os
import sys
import time
from collections import defaultdict

from cosmic_ray.work_db import WorkDB, use_db
from cosmic_ray.work_item import TestOutcome, WorkerOutcome
from sample import package

#: tests that failed on the unmutated copy of the package during a campaign (a kill by one of
#: them is not a kill: counted as not settled), e.g. a lint test that read a file of the copy
FAILING_UNMUTATED = [t for t in os.environ.get("MUTATION_FAILING_UNMUTATED", "").split(",") if t]


def main(sessions: str, logs: str, out: str, commit: str) -> None:
    runs = [json.loads(line) for log in logs.split(",") for line in open(log, encoding="utf-8")
            if line.strip()]
    packages = defaultdict(lambda: {"mutants": 0, "sampled": 0, "killed": 0, "survived": 0,
                                    "unsettled": 0, "not run": 0, "equivalent": 0})
    survivors, seen = [], set()
    for k, session in enumerate(sessions.split(",")):
        with use_db(session, WorkDB.Mode.open) as db:
            items = {w.job_id: w for w in db.work_items}
            for w in items.values():
                if k == 0:
                    packages[package(str(w.mutations[0].module_path))]["mutants"] += 1
            for w in db.pending_work_items:  # sampled, not run yet (an interrupted campaign)
                packages[package(str(w.mutations[0].module_path))]["not run"] += 1
            for job_id, result in db.results:
                m = items[job_id].mutations[0]
                pkg = package(str(m.module_path))
                if result.worker_outcome == WorkerOutcome.SKIPPED:
                    if result.output == "equivalent: annotation" and k == 0:
                        packages[pkg]["equivalent"] += 1
                    continue
                ident = (str(m.module_path), m.operator_name, m.occurrence)
                if ident in seen:
                    continue
                seen.add(ident)
                s = packages[pkg]
                s["sampled"] += 1
                output = result.output or ""
                limit = '"outcome": "limit"' in output
                false = any(f in output for f in FAILING_UNMUTATED)
                if limit or false:
                    s["unsettled"] += 1
                elif result.test_outcome == TestOutcome.SURVIVED:
                    s["survived"] += 1
                    survivors.append({"file": str(m.module_path), "line": m.start_pos[0],
                                      "operator": m.operator_name, "diff": result.diff})
                elif result.test_outcome == TestOutcome.KILLED:
                    s["killed"] += 1
                else:
                    s["unsettled"] += 1
    doc = {"tool": "cosmic-ray", "date": time.strftime("%Y-%m-%d"), "commit": commit,
           "selection": ("test files whose imports reach the mutated file, import distance <= "
                         f"{os.environ.get('MUTATION_MAX_DISTANCE', '2')} (or the nearest), pytest -x, "
                         f"one process, {os.environ.get('MUTATION_LIMIT', '420')} s limit "
                         "(benchmarks/mutation/run_selected.py)"),
           "packages": dict(sorted(packages.items())), "survivors": survivors, "runs": runs}
    with open(out, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main(*sys.argv[1:5])
