"""The order in which the test modules are handed to the workers: measured durations
(tests/durations.json, written by ``pytest --store-durations``), longest first. Kept out of
conftest.py so that it is importable by name beside benchmarks/conftest.py."""
from __future__ import annotations

import json
import statistics
from pathlib import Path

TESTS = Path(__file__).resolve().parent
#: measured seconds per test module (path relative to tests/), written by --store-durations
DURATIONS = TESTS / "durations.json"


def read_durations() -> dict[str, float]:
    """The measured duration of each test module (tests/durations.json), or {} without one."""
    try:
        return {str(k): float(v) for k, v in json.loads(DURATIONS.read_text()).items()}
    except (OSError, ValueError, AttributeError):
        return {}


def longest_first(modules: list[str], durations: dict[str, float]) -> list[str]:
    """The modules (paths relative to tests/) by measured duration, longest first (a stable
    sort); a module without a measurement at the median of the others."""
    default = statistics.median(durations.values()) if durations else 0.0
    return sorted(modules, key=lambda m: -durations.get(m, default))
