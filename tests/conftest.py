"""The order in which the test modules are run: the costliest first.

With ``--dist loadscope --no-loadscope-reorder`` (pyproject.toml) pytest-xdist hands whole modules
to the workers in collection order, each worker taking the next module when it runs dry. Handing
out the longest first (the "longest processing time first" rule) makes the workers end together;
by default pytest-xdist orders the modules by their number of tests, which put several of the
longest, with few tests, last (one worker ran alone at the end). Without pytest-xdist the order
only changes which module runs first.

Since the order of the modules on a worker is not fixed, a module leaves the registries as it
found them: the user definitions it loaded (``--load``, an experiment's ``load``, the API) are
unloaded after it.
"""
from __future__ import annotations

import pytest

#: the costliest modules, longest first: their summed test durations (s) in a cold run (empty
#: kernel cache) on 2 cores, 2026-11-27; the modules not listed follow in collection order
COSTLIEST_FIRST = [
    "test_time_grid.py",          # 70
    "test_hlw_chapter_1.py",         # 55
    "test_b_sections_7_8.py",      # 50
    "test_orders.py",             # 38
    "test_dense_output.py",       # 32
    "test_sections.py",           # 27
    "test_runner_store.py",       # 27
    "test_signals.py",            # 27
    "test_b_section_5.py",       # 26
    "test_summation.py",          # 25
    "test_cache_healing.py",      # 23
    "test_generating_function.py",  # 21
    "test_seed_problems.py",      # 20
    "test_cache_integrity.py",    # 19
    "test_user_definitions_unseen.py",       # 15
    "test_locator_precision.py",  # 14
    "test_b_section_6.py",       # 13
    "test_user_runs.py",          # 12
    "test_reversibility.py",      # 11
    "test_hairer_counts.py",      # 10
    "test_user_definitions.py",   # 10
    "test_cli_refusals.py",         # 10
]


def pytest_collection_modifyitems(session, config, items):
    """A stable sort by the module's rank: each module's tests stay together and in order."""
    rank = {name: k for k, name in enumerate(COSTLIEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


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


def pytest_configure(config):
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
