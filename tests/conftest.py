"""The order in which the test modules are run: the longest first, by their measured durations.

With ``--dist loadscope --no-loadscope-reorder`` (pyproject.toml) pytest-xdist hands whole modules
to the workers in collection order, each worker taking the next module when it runs dry. Handing
out the longest first (the "longest processing time first" rule) makes the workers end together;
by default pytest-xdist orders the modules by their number of tests, which put several of the
longest, with few tests, last (one worker ran alone at the end). Without pytest-xdist the order
only changes which module runs first.

The durations are measured, not ranked by hand: ``pytest --store-durations`` (best on an empty
kernel cache, as CI runs: ``GNIBENCH_CACHE_DIR`` set to a new directory) writes the summed
setup, call and teardown times of each test module to tests/durations.json, which is committed.
A module that is not in it yet (a new one) is ranked at the median of the measured ones.

Since the order of the modules on a worker is not fixed, a module leaves the registries as it
found them: the user definitions it loaded (``--load``, an experiment's ``load``, the API) are
unloaded after it.
"""
from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import pytest
from support_order import DURATIONS, TESTS, longest_first, read_durations  # noqa: F401


def pytest_addoption(parser):
    parser.addoption("--store-durations", action="store_true", default=False,
                     help="write the summed duration of each test module to tests/durations.json "
                          "(the order in which the modules are handed out: the longest first)")


def _module(path) -> str:
    return Path(path).resolve().relative_to(TESTS).as_posix()


def pytest_collection_modifyitems(session, config, items):
    """The modules in :func:`longest_first` order; each module's tests stay together and in
    order."""
    def name(item) -> str:
        try:
            return _module(item.path)
        except ValueError:                  # a test outside tests/ (e.g. benchmarks/)
            return str(item.path)

    rank = {m: k for k, m in enumerate(longest_first(list(dict.fromkeys(map(name, items))),
                                                     read_durations()))}
    items.sort(key=lambda item: rank[name(item)])


class _Durations:
    """Sums the reported durations per module (on the controller: pytest-xdist sends each
    worker's reports to it) and writes them when the session ends."""

    def __init__(self, root: Path):
        self.root = root
        self.seconds: dict[str, float] = defaultdict(float)

    @pytest.hookimpl
    def pytest_runtest_logreport(self, report):
        try:
            name = _module(self.root / report.nodeid.split("::")[0])
        except ValueError:                  # not under tests/
            return
        self.seconds[name] += report.duration

    @pytest.hookimpl
    def pytest_sessionfinish(self, session, exitstatus):
        if not self.seconds:
            return
        ordered = dict(sorted(((k, round(v, 2)) for k, v in self.seconds.items()),
                              key=lambda kv: (-kv[1], kv[0])))
        DURATIONS.write_text(json.dumps(ordered, indent=1) + "\n", encoding="utf-8")


def pytest_configure(config):
    """Where durations are stored (the controller only, not a pytest-xdist worker); then the
    garbage collector's settings (below)."""
    if config.getoption("--store-durations") and not hasattr(config, "workerinput"):
        config.pluginmanager.register(_Durations(Path(config.rootpath)), "gnibench-durations")
    _collector_settings()


@pytest.fixture(scope="module", autouse=True)
def _earlier_objects_frozen():
    """Before a module: the garbage of the modules before it is collected, then what is alive is
    frozen for the cyclic garbage collector (``gc.freeze``), so that the collections during this
    module walk only the objects it makes. Without it, every full collection walked again the
    millions of objects of the kernels compiled so far: 173 and 116 full collections took 26.9 s
    and 37.2 s of the two workers' CPU in a cold run (2026-11-27, gc.callbacks), with 0.6-4 s
    each late in the run. The collector still runs all along (a ``__del__`` that raises is
    reported); cyclic garbage among frozen objects is never collected: a test process only lives
    for the run."""
    _freeze_alive()


def _freeze_alive() -> None:
    import gc

    gc.collect()
    gc.freeze()


def _collector_settings() -> None:
    """The process is frozen before the test modules are imported: gnibench's own freezing while
    it compiles (``gnibench.methods.assembly.loading.compiling``) then leaves it as it is, also for a
    kernel compiled at collection. The oldest generation is collected before each module only
    (third threshold 10**9; the young generations keep their thresholds); a process forked from
    a test process (a pool worker, the drawing process) inherits both, for its short life."""
    import gc

    young, middle, _ = gc.get_threshold()
    gc.set_threshold(young, middle, 10**9)
    _freeze_alive()


@pytest.fixture(scope="module", autouse=True)
def _registries_as_found():
    """After a module: the definitions files and entry points it loaded are unloaded, and
    discovery (``GNIBENCH_LOAD``, entry points) is as it was before it."""
    from gnibench.suite.cell.user import loader

    before, discovered = set(loader.loaded()), loader._discovered
    yield
    for name in set(loader.loaded()) - before:
        loader.unload(name)
    loader._discovered = discovered


def pytest_unconfigure(config):
    """Before pytest's last cleanup: the young generations are collected, then what is alive is
    frozen for the cyclic garbage collector (``gc.freeze``), so that pytest's final
    ``gc.collect`` (its unraisable-exception check, run after this hook) does not walk again the
    millions of objects of the compiled kernels a worker holds (3.5 s and 4.9 s in the two
    workers of a cold run, 2026-11-27). The collector ran all along the run, so a ``__del__``
    that raises is still reported for the garbage it met; what the last check no longer sees is
    cyclic garbage old enough to have reached the oldest generation and not yet collected."""
    import gc

    gc.collect(1)
    gc.freeze()
