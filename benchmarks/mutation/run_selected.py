"""The test command of the cosmic-ray campaign (README.md beside this file).

cosmic-ray mutates one file of the package copy in place and runs this command: it finds the
mutated file (the newest .py of the package), selects the test files whose imports reach it
(gnibench.suite.ledger.importers: the reverse import graph, the same selection as
``gnibench verify --mutants``), nearest first, at import distance <= MAX_DISTANCE (or the nearest
ones, when none is that near), and runs
pytest on them with -x, on one worker, under LIMIT seconds. Exit 0: every selected test passed
(the mutant survived); 1: a test failed (killed); 3: the limit was reached without a failure
(logged as "limit": neither killed nor shown to survive). One JSON line per mutant goes to
$MUTATION_LOG.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]          # the package copy (named gnibench)
MAX_DISTANCE = int(os.environ.get("MUTATION_MAX_DISTANCE", "2"))
LIMIT = float(os.environ.get("MUTATION_LIMIT", "420"))


def mutated_file() -> str:
    code = [p for folder in ("suite", "methods", "problems", "reports")
            for p in (ROOT / folder).rglob("*.py")]
    newest = max(code, key=lambda p: p.stat().st_mtime_ns)
    return newest.relative_to(ROOT).as_posix()


def main() -> int:
    sys.path.insert(0, str(ROOT.parent))
    from gnibench.suite.ledger import importers

    file = mutated_file()
    graph = importers.import_graph(str(ROOT))
    dist = importers.importers(graph, importers.module_of(file))
    seeing = importers.tests_seeing(ROOT, file)
    cut = max([MAX_DISTANCE] + [dist[t] for t in seeing[:1]])    # at least the nearest tests
    tests = [t for t in seeing if dist.get(t, 99) <= cut]
    env = {**os.environ, "PYTHONPATH": str(ROOT.parent)}
    start = time.perf_counter()
    cmd = [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "-m", "not slow",
           "-o", "addopts=", "-p", "no:randomly", *tests]
    outcome, failed = "survived", ""
    if tests:
        try:
            run = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True,
                                 timeout=LIMIT)
            if run.returncode not in (0, 5):
                outcome = "killed"
                failed = next((ln for ln in run.stdout.splitlines()
                               if ln.startswith(("FAILED", "ERROR"))), run.stdout[-300:])
        except subprocess.TimeoutExpired:
            outcome = "limit"
    else:
        outcome = "no tests"
    record = {"file": file, "tests": len(tests), "outcome": outcome, "failed": failed,
              "seconds": round(time.perf_counter() - start, 1)}
    log = os.environ.get("MUTATION_LOG")
    if log:
        with open(log, "a", encoding="utf-8") as f:
            f.write(json.dumps(record) + "\n")
    print(json.dumps(record))
    return {"survived": 0, "no tests": 0, "killed": 1, "limit": 3}[outcome]


if __name__ == "__main__":
    sys.exit(main())
