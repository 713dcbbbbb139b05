"""The benchmark suite, timed or run once.

Timed: ``pytest benchmarks --benchmark-only`` saves every run in pytest-benchmark's storage,
``.benchmarks/<machine>/NNNN_<commit>.json`` (git-ignored), as if ``--benchmark-autosave`` were
given; ``gnibench report --benchmarks .benchmarks`` draws the history and ``pytest benchmarks
--benchmark-only --benchmark-compare --benchmark-compare-fail=median:30%`` fails on a slowdown
(docs/how-to/timing-regressions.md).

Run once: the test command (``python -m pytest -q -n auto``; pyproject's ``testpaths`` holds
``benchmarks`` and its ``addopts`` ``--benchmark-disable``) runs every benchmark once, untimed, at
its smoke size (:func:`timed` is False), so that a benchmark that no longer runs fails the tests
instead of rotting unseen (issue 43: five of fourteen had)."""
from __future__ import annotations

import pytest


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config):
    if not config.getoption("benchmark_only", False):
        return
    # the timed run: the --benchmark-disable of pyproject's addopts is for the test command,
    # and its --dist loadscope, without -n, would make pytest-benchmark believe xdist is on
    # (it disables the timing under xdist, and --benchmark-only then refuses to start)
    config.option.benchmark_disable = False
    if not getattr(config.option, "numprocesses", None):
        config.option.dist = "no"
    if not config.getoption("benchmark_autosave", False):
        from pytest_benchmark.utils import get_tag

        config.option.benchmark_autosave = get_tag()      # <commit>_<time>[_uncommitted-changes]


@pytest.fixture
def timed(benchmark) -> bool:
    """True when this run times the benchmarks (``--benchmark-only``); False when each runs once,
    untimed (``--benchmark-disable``, or under pytest-xdist): then a benchmark runs at its smoke
    size and skips the checks of its timings."""
    return not benchmark.disabled
