"""The benchmark suite saves every run (``pytest benchmarks --benchmark-only``) in
pytest-benchmark's storage, ``.benchmarks/<machine>/NNNN_<commit>.json`` (git-ignored), as if
``--benchmark-autosave`` were given; ``gnibench report --benchmarks .benchmarks`` draws the history
and ``pytest benchmarks --benchmark-only --benchmark-compare --benchmark-compare-fail=median:30%``
fails on a slowdown (documentation: how-to, "Track timing regressions")."""
from __future__ import annotations

import pytest


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config):
    if config.getoption("benchmark_only", False) and not config.getoption("benchmark_autosave",
                                                                           False):
        from pytest_benchmark.utils import get_tag

        config.option.benchmark_autosave = get_tag()      # <commit>_<time>[_uncommitted-changes]
