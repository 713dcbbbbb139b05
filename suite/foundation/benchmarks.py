"""Benchmark history on disk, in pytest-benchmark's storage layout.

``<storage>/<machine>/NNNN_<commit>_<time>[_uncommitted-changes].json``, one file per saved run, with
pytest-benchmark's JSON (``machine_info``, ``commit_info``, ``datetime``, ``benchmarks``: each
with ``name``, ``fullname``, ``group``, ``stats`` {min, median, mean, max, rounds, ...} in seconds,
``extra_info``). The pytest-benchmark suite (``pytest benchmarks --benchmark-only``, autosaving)
and ``gnibench bench`` write there; ``gnibench bench --compare`` and the report's timing page read
it. The default storage is ``.benchmarks`` in the working directory (git-ignored).
"""
from __future__ import annotations

import json
import math
import platform
import re
import subprocess
import time
from pathlib import Path

DEFAULT_STORAGE = Path(".benchmarks")
_RUN = re.compile(r"^(\d{4})_.*\.json$")


def machine_id() -> str:
    """pytest-benchmark's machine id: system, implementation, Python major.minor, bits."""
    return "-".join((platform.system(), platform.python_implementation(),
                     ".".join(platform.python_version_tuple()[:2]), platform.architecture()[0]))


def commit_info(cwd: Path | None = None) -> dict:
    """The git commit of ``cwd`` (id, dirty, branch, time); empty values outside a repository."""
    def git(*args: str) -> str:
        try:
            return subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True,
                                  check=True, timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""

    return {"id": git("rev-parse", "HEAD"), "dirty": bool(git("status", "--porcelain",
                                                                "--untracked-files=no")),
            "branch": git("rev-parse", "--abbrev-ref", "HEAD"), "time": git("log", "-1", "--format=%cI")}


def runs(storage: Path, machine: str | None = None) -> list[tuple[str, Path]]:
    """(machine, file) of the saved runs, oldest first per machine (by run number)."""
    storage = Path(storage)
    if not storage.is_dir():
        return []
    out = []
    for d in sorted(p for p in storage.iterdir() if p.is_dir()):
        if machine is not None and d.name != machine:
            continue
        files = sorted((f for f in d.iterdir() if _RUN.match(f.name)),
                       key=lambda f: int(_RUN.match(f.name).group(1)))
        out += [(d.name, f) for f in files]
    return out


def load_run(path: Path) -> dict:
    """One saved run (JSON); a file that is not a run raises TypeError (ValueError: not JSON)."""
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    if not isinstance(doc, dict) or not isinstance(doc.get("benchmarks"), list):
        raise TypeError(f"{path} is not a benchmark run (no 'benchmarks' list)")
    return doc


def save_run(storage: Path, benchmarks: list[dict], commit: dict | None = None,
             machine: str | None = None) -> Path:
    """Write a run as the next ``NNNN_<commit>.json`` of this machine; return its path."""
    machine = machine or machine_id()
    commit = commit_info() if commit is None else commit
    d = Path(storage) / machine
    d.mkdir(parents=True, exist_ok=True)
    numbers = [int(_RUN.match(f.name).group(1)) for f in d.iterdir() if _RUN.match(f.name)]
    tag = ((commit.get("id") or "unversioned") + time.strftime("_%Y%m%d_%H%M%S")
           + ("_uncommitted-changes" if commit.get("dirty") else ""))
    path = d / f"{max(numbers, default=0) + 1:04d}_{tag}.json"
    doc = {"machine_info": {"node": platform.node(), "machine": platform.machine(),
                            "system": platform.system(), "python_version": platform.python_version(),
                            "processor": platform.processor()},
           "commit_info": commit, "datetime": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
           "version": "gnibench", "benchmarks": benchmarks}
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(doc, indent=1, default=str), encoding="utf-8")
    tmp.replace(path)
    return path


def last_values(storage: Path, machine: str, stat: str = "median") -> dict[str, tuple[float, str]]:
    """For each benchmark name, its ``stat`` in the last saved run of ``machine`` that has it, and
    that run's file name."""
    out: dict[str, tuple[float, str]] = {}
    for _, f in runs(storage, machine):
        try:
            doc = load_run(f)
        except (ValueError, TypeError, OSError):
            continue
        for b in doc["benchmarks"]:
            try:                       # a hand-edited or damaged entry is skipped, not a crash
                value = float((b.get("stats") or {})[stat])
                name = str(b.get("fullname") or b["name"])
            except (AttributeError, KeyError, TypeError, ValueError):
                continue
            if math.isfinite(value):
                out[name] = (value, f.name)
    return out


def compare(current: dict[str, float], previous: dict[str, tuple[float, str]],
            threshold: float) -> list[dict]:
    """Rows of (name, previous, current, ratio, slower) for the names in both; ``slower`` when
    current / previous > threshold."""
    rows = []
    for name, value in current.items():
        if name not in previous or previous[name][0] <= 0:
            continue
        before, run = previous[name]
        ratio = value / before
        rows.append({"name": name, "previous": before, "current": value, "ratio": ratio,
                     "run": run, "slower": ratio > threshold})
    return rows


def script_result(script: str, rows: list[dict], goals: dict | None = None,
                  load_before: float | None = None) -> dict:
    """The JSON document a benchmark script of ``benchmarks/`` writes with ``--json``: its rows
    (one dict per measured case), the goals they are read against (``{key: [op, value, what]}``)
    and where, when and under which load it was measured (the documentation's performance page
    shows the newest saved one of each script from ``benchmarks/results/``)."""
    import os

    return {"script": script, "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "commit": commit_info(Path(__file__).resolve().parents[2]),
            "machine": {"id": machine_id(), "node": platform.node(), "cpus": os.cpu_count(),
                        "processor": platform.processor() or platform.machine()},
            "load": {"before": load_before, "after": os.getloadavg()[0]},
            "goals": goals or {}, "rows": rows}
