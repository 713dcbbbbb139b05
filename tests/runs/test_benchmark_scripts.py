"""The benchmark scripts of the runner and of ensembles run (at their quick size), so that none
can rot: each ends with exit code 0 and prints its table; no timing is checked here. They are
benchmarks: marked ``slow``, so CI runs them once (``pytest -m slow``) and the test command
does not."""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


def _run(script: str, tmp_path: Path) -> list[dict]:
    """The rows of the script's ``--json`` document, checked to say what the documentation's
    performance page reads (script, date, commit, machine, load, goals)."""
    out = tmp_path / "out.json"
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), "--quick",
                           "--json", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    doc = json.loads(out.read_text())
    assert doc["script"] == script and doc["date"] and doc["machine"]["cpus"] >= 1
    assert {"id", "dirty"} <= set(doc["commit"]) and doc["load"]["after"] >= 0
    for key, goal in doc["goals"].items():
        assert goal[0] in ("<=", ">=") and all(key in r for r in doc["rows"]), key
    return doc["rows"]


def test_ensemble_benchmark_runs_and_its_orbits_are_the_separate_cells(tmp_path):
    rows = _run("bench_ensembles.py", tmp_path)
    assert [r["method"].split(":")[0] for r in rows] == ["dop853", "vern9"]
    for r in rows:
        assert r["same_bits"] and r["orbits"] == 40
        assert r["heyoka_tol"] is not None                  # heyoka reached the same accuracy
        assert r["median_error_ensemble"] == r["median_error_cells"]


def test_runner_cost_benchmark_runs(tmp_path):
    [out] = _run("bench_runner_cost.py", tmp_path)
    assert out["cells"] == 40
    for key in ("parent_ms_per_cell", "speedup_j2", "report_s"):
        assert out[key] > 0
    assert math.isfinite(out["reuse_ms_per_cell"])          # a difference of noisy times
