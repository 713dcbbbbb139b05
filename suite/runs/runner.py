"""``gnibench run``: expand an experiment into cells, run them, store each, write the tables.

The runner only composes: :func:`gnibench.suite.runs.cellwork.run_cell` solves and measures a
cell, an executor (:mod:`gnibench.suite.runs.executors`: this process, a local process pool, Dask)
decides where, the store (:mod:`gnibench.suite.runs.store`) commits every finished cell as its own
part, and the tables (:mod:`gnibench.suite.runs.tables`) are consolidated from the parts in cell
order. An ensemble cell (:mod:`gnibench.suite.runs.ensemble_spec`) is run as units of a fixed
number of orbits (:func:`work_units`), each a part; its row and statistics are made from its units'
orbits (:mod:`gnibench.suite.runs.ensemble_tables`). A summary renderer can be passed in (the
command line passes the Markdown report's); the runner itself sits below the reports.

Outputs in ``out_dir`` (default ``results/<experiment name>``): ``parts/`` (the store),
``samples.parquet``, ``cells.parquet``, ``timings.parquet``, with ensemble cells
``ensemble.parquet`` and ``ensemble_stats.parquet``, and, with a renderer, ``summary.md``
(columns: ``suite/experiments/README.md``). Each Parquet file carries the provenance (experiment
name and full TOML text, package versions, canonical specs of every cell) in its schema metadata
under the key ``gnibench``; ``samples`` and ``cells`` carry nothing that depends on the run (no
time, no executor, no worker count), so they are byte-identical for the same inputs, also after
an interrupted run was resumed.

Metrics: each cell's chosen metrics (``Cell.metrics``) are applied to its trajectory in
:func:`~gnibench.suite.runs.cellwork.run_cell`; metrics across cells (``order``: families of cells
that differ only in h) are computed at each consolidation from the cells and samples tables alone
(:func:`gnibench.suite.metrics.families.family_columns`), so they do not depend on where or in
which order the cells ran.

Resuming: running the same command again reuses every stored cell whose key matches (spec, code
and versions; :func:`gnibench.suite.runs.store.cell_key`) and that did not end in ``error``, and
computes only the others; ``fresh`` ignores the store. An experiment's consolidated tables are
rewritten after one of its cells finishes whenever the time since their last write (or the
start) is at least ``FLUSH_SECONDS`` and ``FLUSH_RATIO`` times what the last writes of all the
run's experiments took together (so that a short run writes its tables once, a run over many
experiments, e.g. ``gnibench reproduce all``, does not rewrite the tables of the experiments whose
cells are not running, and the writing takes at most about a tenth of the run's time however many
experiments it holds), at the end, and on Ctrl-C; unfinished cells appear with status
``pending`` and ``complete: false``.

A cell that raises (anything but a KeyboardInterrupt) gets status ``error`` with the exception
type and message as reason, and the run goes on. A worker process that dies (killed, out of memory)
ends the run with one line naming its cell; the tables are written as on Ctrl-C (the cells whose
outcomes arrived, the others ``pending``), and the same command computes the rest. Bad input never
reaches this point: the whole experiment and the executor options are validated first and nothing
is written when that fails.
"""
from __future__ import annotations

import contextlib
import sys
import time
from dataclasses import replace
from pathlib import Path

from gnibench.suite.foundation.cache import atomic_write
from gnibench.suite.foundation.guard import stopped_by
from gnibench.suite.foundation.outputs import Fault, fault
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.foundation.status import Status
from gnibench.suite.runs import executors
from gnibench.suite.runs.cellwork import CellOutcome, kernel_plan
from gnibench.suite.runs.experiment import Experiment, load_experiment
from gnibench.suite.runs.progress import RunProgress
from gnibench.suite.runs.store import Part, Store, cell_key

FLUSH_RATIO = 10.0
FLUSH_SECONDS = 5.0


def run_experiment(name_or_path, out_dir=None, *, jobs: int | None = None,
                   executor: str = "local", scheduler: str | None = None, fresh: bool = False,
                   log=None, summarize=None, scale: str = "paper", started=None,
                   pool=None, repeat: int | None = None) -> Path:
    """Run an experiment (shipped name or TOML path); return the output directory.

    Parameters
    ----------
    name_or_path:
        Name of a shipped experiment (``quick``) or path to a TOML file.
    out_dir:
        Output directory; default ``results/<experiment name>`` in the working directory. It
        holds the store (``parts/``) too.
    jobs, executor, scheduler:
        Where the cells run (:mod:`gnibench.suite.runs.executors`): ``local`` with ``jobs``
        processes (default: the number of cores; 1: in this process), or ``dask`` (a
        LocalCluster of ``jobs`` workers, or the scheduler at ``scheduler``).
    fresh:
        Ignore the cells stored by earlier runs and compute all.
    log:
        Stream for the progress (default stderr).
    summarize:
        ``summarize(meta, cells, timings) -> str``: the Markdown written to ``summary.md`` with
        every consolidation (None: no summary).
    scale:
        ``paper`` (the file's values) or ``quick`` (its ``[scale.quick]`` overrides).
    repeat:
        Timed integrations per cell (replaces the file's ``repeat``; default: the file's, else
        1): :func:`gnibench.suite.runs.cellwork.timed_repeats`.
    started:
        Called once the experiment and the executor options are valid, before anything is
        written (the command line starts the report's drawing process there).
    pool:
        A local pool already started (:func:`gnibench.suite.runs.executors.start`; the command
        line starts it first thing, so that its workers get ready while the experiment is read),
        fitted to the cells to compute and used for them; the caller stops it. Default: one is
        started here when needed.
    """
    experiment = load_experiment(name_or_path, scale, repeat)
    executors.check(executor, jobs, scheduler)
    if started is not None:
        started()
    out = Path(out_dir) if out_dir is not None else Path("results") / experiment.name
    run_experiments([experiment], [out], out, jobs=jobs, executor=executor, scheduler=scheduler,
                    fresh=fresh, log=log, summarize=summarize, name=experiment.name,
                    pool=pool)
    return out


def run_experiments(experiments: list[Experiment], outs: list[Path], store_root: Path, *,
                    jobs: int | None = None, executor: str = "local",
                    scheduler: str | None = None, fresh: bool = False, log=None,
                    summarize=None, name: str = "run", pool=None) -> list[Path]:
    """Run several validated experiments over one store: a cell shared by several experiments
    (same key) is computed once; each experiment's tables are consolidated into its own
    directory (``outs``, in order). Executor options must have been checked."""
    log = sys.stderr if log is None else log
    outs = [Path(o) for o in outs]
    own = None
    if pool is None:            # the workers get ready while the store is read
        pool = own = executors.start(executor, jobs,
                                     len({id(c) for e in experiments for c in e.cells}))
    with own if own is not None else contextlib.nullcontext(), Store(store_root) as store:
        for out in outs:
            Store.make_output_dir(out)
        units = {id(c): work_units(c) for e in experiments for c in e.cells}
        keys = [{c.id: [cell_key(u) for u in units[id(c)]] for c in e.cells}
                for e in experiments]
        unique: dict[str, object] = {}
        for e, k in zip(experiments, keys):
            for c in e.cells:
                for u, key in zip(units[id(c)], k[c.id]):
                    unique.setdefault(key, u)
        stored = {} if fresh else {k: store.read(k) for k in unique}
        done = {k for k, part in stored.items() if _reusable(part)}
        retried = sum(1 for part in stored.values() if part is not None and not _reusable(part))
        todo = [c for k, c in unique.items() if k not in done]
        key_of = {id(c): k for k, c in unique.items()}
        if pool is not None:
            pool.fit(executors.workers(jobs, len(todo)))
        where = outs[0] if len(outs) == 1 else store_root
        again = f", {retried} of them ended in error before" if retried else ""
        ncells = len({k[c.id][0] for e, k in zip(experiments, keys) for c in e.cells})
        what = f"{ncells} cells" if ncells == len(unique) else \
            f"{ncells} cells in {len(unique)} units"
        print(f"gnibench: {name}: {what} -> {where} ({len(done)} reused from the "
              f"store, {len(todo)} to compute{again})", file=log, flush=True)
        progress = RunProgress(len(unique), len(done), log, name)
        # --fresh again would ignore what this run stores
        again = "run it again without --fresh" if fresh else "run the same command again"
        # the pool's workers get their first cells now; the tables' writers are made meanwhile
        groups, warm = _planned(todo)
        outcomes = executors.run(groups, executor, jobs, scheduler, progress.cell_progress,
                                 pool, warm)
        writers: list[Consolidator] = []
        try:
            with contextlib.closing(outcomes):      # an error stops the workers at once
                costs: dict = {}
                writers += [Consolidator(e, store, out, summarize, k, costs)
                            for e, out, k in zip(experiments, outs, keys)]
                _table_libraries()
                for outcome in outcomes:
                    key = key_of.get(id(outcome.cell)) or cell_key(outcome.cell)
                    store.write(key, _part(outcome))
                    done.add(key)         # stored: counted even if a signal comes right now
                    progress.cell_done(outcome)
                    for w in writers:      # only the experiments that hold the cell have news
                        if key in w.key_set:
                            w.dirty = True
                        if w.dirty and w.due():
                            w.flush(done)
            for w in writers:
                w.flush(done)
        except KeyboardInterrupt:
            progress.close()
            with contextlib.suppress(OSError):
                for w in writers:
                    w.flush(done)
            rest = "to compute the rest" if len(done) < len(unique) else "to finish"
            print(f"gnibench: {stopped_by()}: {len(done)} of {len(unique)} cells are stored in "
                  f"{store_root}; {again} {rest}", file=log, flush=True)
            raise
        except Fault:                 # a worker died: what is stored stays, the rest pending
            progress.close()
            with contextlib.suppress(OSError):
                for w in writers:
                    w.flush(done)
            raise
        except OSError as e:          # the disk filled up, say: what is stored stays
            raise fault(e, "the run", f"{len(done)} of {len(unique)} cells are stored in "
                        f"{store_root}; {again} once the cause is removed") from None
        finally:
            progress.close()
    return outs


def _table_libraries() -> None:
    """Import what the tables are written with (pandas, pyarrow: a third of a second), once the
    pool's workers have their first cells: this process waits for them meanwhile (their start-up
    takes longer than the experiment's reading), instead of after the last cell."""
    import pandas  # noqa: F401
    import pyarrow.parquet  # noqa: F401


def work_units(cell) -> list:
    """The units of work of a cell: itself, or an ensemble's chunks of orbits (one unit for an
    ensemble whose metric needs the whole set: the area of a carried curve)."""
    if cell.ensemble is None:
        return [cell]
    whole = any(c.metric.scope == "ensemble" for c in cell.spec.metrics)
    return [replace(cell, ensemble=u) for u in cell.ensemble.units(whole)]


def _reusable(part: Part | None) -> bool:
    """A stored cell is reused unless it ended in ``error``: an unexpected failure (a worker out
    of memory, a broken environment such as NUMBA_DISABLE_JIT=1) is not a result of its inputs,
    and the next run tries it again."""
    return part is not None and part.row.get("status") != str(Status.ERROR)


def _groups(cells) -> list[list]:
    """Cells grouped by compiled kernel, cells in cell order. The groups whose kernel must be
    compiled come first, the costliest first (by the length of its generated text: compiling
    takes a few tenths of a second to ten seconds, and a costly kernel left to the end of a run
    is compiled while the other workers have nothing left to do), then the others in cell
    order. Which worker runs a cell never changes its numbers."""
    return _planned(cells)[0]


def _planned(cells) -> tuple[list[list], list[bool]]:
    """:func:`_groups`, and whether each group's kernel is in the disk cache already (its cost
    0: its cells need not wait for a first one to compile it)."""
    groups: dict[str, list] = {}
    cost: dict[str, int] = {}
    for c in cells:
        key, cost[key] = kernel_plan(c)
        groups.setdefault(key, []).append(c)
    order = sorted(groups, key=lambda k: -cost[k])       # stable: ties stay in cell order
    return [groups[k] for k in order], [cost[k] == 0 for k in order]


def _part(o: CellOutcome) -> Part:
    return Part(o.samples, o.row, o.timing, tuple(o.state_names), o.orbits)


class Consolidator:
    """Writes the consolidated tables (and the summary) from the stored parts."""

    def __init__(self, experiment: Experiment, store: Store, out: Path, summarize=None,
                 keys: dict | None = None, costs: dict | None = None):
        self.experiment, self.store, self.out, self.summarize = experiment, store, out, summarize
        self.keys = keys if keys is not None else {c.id: [cell_key(u) for u in work_units(c)]
                                                   for c in experiment.cells}
        self.key_set = {k for ks in self.keys.values() for k in ks}
        self.dirty = False          # a cell of this experiment finished since the last write
        self.state_names = experiment_states(experiment)
        self.ensembles = any(c.ensemble is not None for c in experiment.cells)
        self.last_write = time.perf_counter()
        # what the last write of each experiment of the run took (shared by the run's writers)
        self.costs = {} if costs is None else costs
        figure = experiment.figure or {}
        self.fields_due = any(p.get("fields") for p in figure.get("panels", []))

    def due(self) -> bool:
        spent = sum(self.costs.values())
        return time.perf_counter() - self.last_write >= max(FLUSH_SECONDS, FLUSH_RATIO * spent)

    def flush(self, done: set) -> None:
        from gnibench.suite.metrics.families import family_columns
        from gnibench.suite.runs.storage import write_parquet
        from gnibench.suite.runs.tables import (
            cell_row,
            cells_table,
            samples_table,
            timing_row,
            timings_table,
        )

        t0 = time.perf_counter()
        out = self.out
        cells = self.experiment.cells
        parts = {c.id: self.part(c) for c in cells if all(k in done for k in self.keys[c.id])}
        parts = {k: p for k, p in parts.items() if p is not None}
        by_id = {c.id: c for c in cells}
        samples = samples_table([(by_id[i], p.samples, p.state_names) for i, p in parts.items()
                                 if p.samples is not None], self.state_names, self.ensembles)
        rows = [parts[c.id].row if c.id in parts else cell_row(c) for c in cells]
        timings = [parts[c.id].timing if c.id in parts else timing_row(c) for c in cells]
        if self.ensembles:
            from gnibench.suite.runs.ensemble_tables import ensemble_tables

            for row, c in zip(rows, cells):
                row.setdefault("orbits", None if c.ensemble is None else c.ensemble.total)
                row.setdefault("failed_orbits", None)
            orbits, stats = ensemble_tables([(by_id[i], p) for i, p in parts.items()],
                                            self.state_names)
        meta = provenance(self.experiment, len(parts))
        # metrics across cells (families equal but for h): a function of the two tables only
        cells_df = family_columns(cells_table(rows), samples)
        timings_df = timings_table(timings)
        if self.fields_due:           # a figure's functions on a grid: computed once, no cells
            from gnibench.suite.runs.figure_fields import field_table

            write_parquet(field_table(self.experiment.figure), out / "fields.parquet",
                          {**meta, "table": "fields"})
            self.fields_due = False
        write_parquet(samples, out / "samples.parquet", {**meta, "table": "samples"})
        write_parquet(cells_df, out / "cells.parquet", {**meta, "table": "cells"})
        if self.ensembles:
            write_parquet(orbits, out / "ensemble.parquet", {**meta, "table": "ensemble"})
            write_parquet(stats, out / "ensemble_stats.parquet",
                          {**meta, "table": "ensemble_stats"})
        write_parquet(timings_df, out / "timings.parquet",
                      {**meta, "table": "timings",
                       "written_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")})
        if self.summarize is not None:
            text = self.summarize(meta, cells_df, timings_df)
            atomic_write(out / "summary.md", lambda p: Path(p).write_text(text, encoding="utf-8"))
        self.last_write = time.perf_counter()
        self.costs[id(self)] = self.last_write - t0
        self.dirty = False


    def part(self, cell) -> Part | None:
        """The cell's stored part as a cell of this experiment (an ensemble's: its units'
        parts joined, :func:`gnibench.suite.runs.ensemble_tables.merge`)."""
        got = [self.store.read(k) for k in self.keys[cell.id]]
        if any(p is None for p in got):
            return None
        if cell.ensemble is None:
            return restamp(got[0], cell)
        from gnibench.suite.runs.ensemble_tables import merge

        return merge(cell, got)


def restamp(part: Part | None, cell) -> Part | None:
    """A stored part as a cell of this experiment: its id, group and label (a part is keyed by
    what determines its numbers, so one part may serve cells of several experiments; the samples
    get the cell's id when the table is made)."""
    if part is None:
        return None
    part.row.update(cell=cell.id, group=cell.group, label=cell.label,
                    swept="/".join(cell.sweep), setup_method=cell.setup_method)
    part.timing.update(cell=cell.id)
    return part


def experiment_states(experiment: Experiment) -> tuple[str, ...]:
    """The state names of all the experiment's problems, in order of first appearance (so the
    samples table has the same columns whichever cells are done)."""
    names: list[str] = []
    for c in experiment.cells:
        for s in c.spec.problem.record.state:
            if s not in names:
                names.append(s)
    return tuple(names)


def provenance(e: Experiment, ndone: int) -> dict:
    """The metadata of the consolidated tables: nothing that depends on the run itself."""
    return {"experiment": e.name, "title": e.title, "reference": e.reference,
            "description": e.description, "source": e.source, "experiment_toml": e.text,
            "scale": e.scale, "figure": e.figure, "repeat": e.repeat, "report": e.report,
            "versions": versions(), "complete": ndone == len(e.cells), "cells_done": ndone,
            "cells_total": len(e.cells),
            "cells": [c.described() for c in e.cells]}
