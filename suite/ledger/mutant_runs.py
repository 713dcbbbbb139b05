"""The phases of a mutant's verification, each a subprocess on a copy of the package.

:mod:`.mutants` runs, for the unmutated baseline and for each mutant, the ledger
(``gnibench verify``, :func:`run_ledger`) and the tests that can see the mutated file
(:func:`run_tests`: pytest on the copy's own test suite, with ``-x``: the first failure is
enough). Every phase has a time limit derived from the baseline (:func:`limit`): a phase that
overruns it is counted as a kill (a hang, an endless Newton loop) only when the limit is a
generous multiple of what the baseline took; when the campaign's own cap cut the limit shorter,
the overrun is *inconclusive* and kills nothing.
"""
from __future__ import annotations

import json
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

#: a phase may take this many times the baseline's time (plus SLACK seconds) before it is stopped
FACTOR, SLACK = 4.0, 120.0
#: pytest's fixed cost per call (start, collection), added to the tests' summed durations
PYTEST_START = 30.0


@dataclass
class Phase:
    """The outcome of one phase: its exit code (-1: stopped at its time limit), what failed."""

    exit: int
    seconds: float
    failed: list[str] = field(default_factory=list)
    rows: list[dict] = field(default_factory=list)
    stderr: str = ""
    timed_out: bool = False
    conclusive: bool = True          # a timeout with a limit a generous multiple of the baseline's
    durations: dict = field(default_factory=dict)     # test file -> seconds (junit), baseline only


def limit(baseline_seconds: float | None, cap: float) -> tuple[float, bool]:
    """(time limit of a phase, whether overrunning it kills): FACTOR times the baseline's time
    plus SLACK, within ``cap``; conclusive only when ``cap`` did not cut it."""
    if baseline_seconds is None:
        return cap, False
    wanted = FACTOR * baseline_seconds + SLACK
    return min(wanted, cap), wanted <= cap


def _run(cmd: list[str], env: dict, cwd: Path, timeout: float):
    import time

    start = time.perf_counter()
    try:
        out = subprocess.run(cmd, check=False, env=env, cwd=cwd, capture_output=True, text=True,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, time.perf_counter() - start
    return out, time.perf_counter() - start


def run_ledger(import_root: Path, env: dict, out: Path, scale: str, jobs: int, claims: list[str],
               timeout: float, conclusive: bool = True) -> Phase:
    """``gnibench verify`` on the copy: its JSON rows (unexpected verdicts kill)."""
    cmd = [sys.executable, "-m", "gnibench.suite.cli.main", "verify", *claims, "--scale", scale,
           "-j", str(jobs), "-o", str(out), "--format", "json", "--no-report"]
    run, seconds = _run(cmd, env, import_root, timeout)
    if run is None:
        return Phase(-1, seconds, stderr=f"timed out after {timeout:.0f} s", timed_out=True,
                     conclusive=conclusive)
    try:
        rows = json.loads(run.stdout) if run.stdout.strip() else []
    except ValueError:
        rows = []
    last = run.stderr.strip().splitlines()[-1] if run.stderr.strip() else ""
    return Phase(run.returncode, seconds, rows=rows, stderr=last)


def _junit(path: Path) -> tuple[list[str], dict[str, float]]:
    """(failed or erroring node ids, seconds per test file) from a junit XML report."""
    failed, per_file = [], {}
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return failed, per_file
    for case in root.iter("testcase"):
        classname, name = case.get("classname", ""), case.get("name", "")
        if not classname:                     # a module that failed to import: the whole file
            file = name.replace(".", "/") + ".py"
            if case.find("failure") is not None or case.find("error") is not None:
                failed.append(file)
            continue
        parts = classname.split(".")
        # classname "tests.runs.test_runner" (or "...test_runner.TestClass"): the file
        k = next((i for i, p in enumerate(parts) if p.startswith("test_")), len(parts) - 1)
        file = "/".join(parts[: k + 1]) + ".py"
        per_file[file] = per_file.get(file, 0.0) + float(case.get("time", 0) or 0)
        if case.find("failure") is not None or case.find("error") is not None:
            node = f"{file}::{'::'.join(parts[k + 1:] + [name])}"
            failed.append(node)
    return failed, per_file


def run_tests(copy: Path, env: dict, tests: list[str], jobs: int, timeout: float,
              deselect: list[str] = (), stop_first: bool = True, report: Path | None = None,
              conclusive: bool = True) -> Phase:
    """pytest on the copy over ``tests`` (files relative to it), the baseline's failures
    deselected, and the tests marked ``source_text`` (they read the package's text, e.g. that
    each catalog mutant's snippet occurs in it: a mutant changes that text by construction, so
    their failure is no kill); ``stop_first``: -x."""
    if not tests:
        return Phase(0, 0.0)
    report = report or copy / "junit.xml"
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rf",
           "-m", "not slow and not source_text", f"--junitxml={report}", *(["-x"] if stop_first else []),
           *(["-n", str(jobs)] if jobs > 1 else []), *tests,
           *(f"--deselect={d}" for d in deselect)]
    run, seconds = _run(cmd, env, copy, timeout)
    if run is None:
        return Phase(-1, seconds, [f"tests timed out after {timeout:.0f} s"], timed_out=True,
                     conclusive=conclusive)
    failed, per_file = _junit(report)
    if not failed:
        failed = re.findall(r"^(?:FAILED|ERROR) (\S+)", run.stdout, flags=re.MULTILINE)
    if run.returncode not in (0, 5) and not failed:
        tail = (run.stdout.strip().splitlines() or [""])[-1]
        failed = [f"pytest exited {run.returncode}" + (f": {tail}" if tail else "")]
    return Phase(run.returncode, seconds, failed, durations=per_file)


def tiers(tests: list[str], distance: dict[str, int], most: int = 5) -> list[list[str]]:
    """The selected test files in calls of pytest by import distance, nearest first: those that
    import the mutated module itself (distance 1), then through one module (2), and so on, the
    farthest merged into the last of at most ``most`` calls (each call stops at its first
    failure, and the next only runs when none failed)."""
    levels = sorted({distance.get(t, 99) for t in tests})
    groups = [[t for t in tests if distance.get(t, 99) == d] for d in levels[:most - 1]]
    rest = [t for t in tests if distance.get(t, 99) in levels[most - 1:]]
    return [g for g in groups + [rest] if g]


def estimate(files: list[str], durations: dict[str, float], jobs: int) -> float | None:
    """What the baseline took for these test files (summed durations over the workers, plus
    pytest's start); None without a baseline run of the tests."""
    if not durations:
        return None
    total = sum(durations.get(f, 0.0) for f in files)
    return total / max(1, jobs) + PYTEST_START
