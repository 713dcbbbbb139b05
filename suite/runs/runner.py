"""``gnibench run``: expand an experiment into cells, solve each, write tables and a summary.

The runner only composes: :func:`gnibench.suite.cell.solve.solve` integrates a cell, :mod:`gnibench.suite.runs.tables` turns
results into rows, :mod:`gnibench.reports.markdown` renders the summary from the tables.

Outputs in ``out_dir`` (default ``results/<experiment name>``), each written atomically:
``samples.parquet``, ``cells.parquet``, ``timings.parquet`` and ``summary.md`` (columns: see
``suite/experiments/README.md``). Each Parquet file carries the provenance (experiment name and
full TOML text, package versions, canonical specs of every cell) in its schema metadata under the
key ``gnibench``.

Progressive writing: the four outputs are rewritten after a cell finishes whenever the time since
the last write is at least 10 times what that write took (so writing costs at most ~10% of the
run; for small experiments that is after every cell), always after the last cell, and when the run
is interrupted (Ctrl-C). Cells not finished yet appear in ``cells.parquet`` with status
``pending``; the metadata has ``complete: false`` until all cells are done. A hard kill loses at
most the cells finished since the last write.

A cell that raises (anything but a KeyboardInterrupt) gets status ``error`` with the exception
type and message as reason, and the run goes on. Bad input never reaches this point: the whole
experiment is validated first (:func:`gnibench.suite.runs.experiment.load_experiment`) and nothing is written
when that fails.

Execution is serial by default. ``executor(run_cell, cells)`` is the seam for parallel backends
(e.g. Dask, later): it must call ``run_cell`` on every cell, wherever it likes, and yield the
returned :class:`CellOutcome` objects in any order as they finish.
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.runs.experiment import Cell, Experiment, load_experiment

FLUSH_RATIO = 10.0


@dataclass
class CellOutcome:
    """What one cell gives back: its rows, ready for the tables (small and picklable)."""

    cell: Cell
    status: str
    reason: str
    samples: object = None          # pandas DataFrame, None for a cell in error
    row: dict = field(default_factory=dict)
    timing: dict = field(default_factory=dict)
    state_names: tuple[str, ...] = ()


def run_cell(cell: Cell) -> CellOutcome:
    """Solve one cell, measure it and build its rows; an unexpected exception becomes status
    ``error``."""
    from gnibench.suite.cell.solve import solve
    from gnibench.suite.metrics.compute import apply, parse_metrics
    from gnibench.suite.runs.tables import cell_row, cell_samples, timing_row

    try:
        with np.errstate(all="ignore"):     # overflow in a diverging cell is a status, not noise
            traj = solve(cell.problem_spec, cell.method_spec, steps=cell.steps,
                         t_end=cell.t_end, every=cell.every, dt_out=cell.dt_out)
            metrics, _ = apply(traj, parse_metrics(cell.metrics))
            samples = cell_samples(cell, traj, metrics)
            row = cell_row(cell, traj, metrics)
    except Exception as e:  # noqa: BLE001 - any failure of one cell is recorded, the run goes on
        reason = f"{type(e).__name__}: {e}".replace("\n", " ")
        return CellOutcome(cell, "error", reason, None, cell_row(cell, None, None, "error", reason),
                           timing_row(cell, None, "error"))
    return CellOutcome(cell, str(traj.status), traj.reason, samples, row, timing_row(cell, traj),
                       traj.state_names)


def serial(fn: Callable[[Cell], CellOutcome], cells: Iterable[Cell]) -> Iterator[CellOutcome]:
    """The default executor: one cell after the other, in this process."""
    for cell in cells:
        yield fn(cell)


def run_experiment(name_or_path, out_dir=None, executor=None, log=None, summarize=None) -> Path:
    """Run an experiment (shipped name or TOML path); return the output directory.

    Parameters
    ----------
    name_or_path:
        Name of a shipped experiment (``quick``) or path to a TOML file.
    out_dir:
        Output directory; default ``results/<experiment name>`` in the working directory.
    executor:
        ``executor(run_cell, cells)`` yielding :class:`CellOutcome` (default :func:`serial`).
    log:
        Stream for the progress lines (default stderr).
    summarize:
        ``summarize(meta, cells, timings) -> str``, the Markdown written to ``summary.md`` with
        every flush (the command line passes :func:`gnibench.reports.markdown.render_summary`;
        the runner sits below the reports and does not import them). None: no summary.
    """
    experiment = load_experiment(name_or_path)
    out = Path(out_dir) if out_dir is not None else Path("results") / experiment.name
    if out.exists() and not out.is_dir():
        raise UserError(f"bad -o {out}: it exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise UserError(f"bad -o {out}: cannot create the directory ({e.strerror})") from None
    log = sys.stderr if log is None else log
    writer = _Writer(experiment, out, summarize)
    n = len(experiment.cells)
    print(f"gnibench: {experiment.name}: {n} cells -> {out}", file=log)
    try:
        for k, outcome in enumerate((executor or serial)(run_cell, experiment.cells), 1):
            writer.add(outcome)
            print(_progress(k, n, outcome), file=log, flush=True)
            if k == n or writer.due():
                writer.flush()
    except BaseException:
        writer.flush()
        raise
    return out


def _progress(k: int, n: int, o: CellOutcome) -> str:
    c, timing = o.cell, o.timing
    line = f"[{k}/{n}] cell {c.id}: {c.problem} {c.method}: {o.status}"
    if o.status != "error":
        line += (f", {o.row['steps']} steps, compile/load {timing['compile_seconds']:.2f} s, "
                 f"run {timing['wall_seconds'] * 1e3:.3g} ms")
    return line + (f" ({o.reason})" if o.reason else "")


class _Writer:
    """Holds the finished cells and rewrites the four outputs atomically."""

    def __init__(self, experiment: Experiment, out: Path, summarize=None):
        self.experiment, self.out, self.summarize = experiment, out, summarize
        self.done: dict[int, CellOutcome] = {}
        self.last_write, self.write_cost = time.perf_counter(), 0.0

    def add(self, outcome: CellOutcome) -> None:
        self.done[outcome.cell.id] = outcome

    def due(self) -> bool:
        return time.perf_counter() - self.last_write >= FLUSH_RATIO * self.write_cost

    def flush(self) -> None:
        from gnibench.suite.runs.storage import atomic_write, write_parquet
        from gnibench.suite.runs.tables import cell_row, cells_table, samples_table, timing_row, timings_table

        t0 = time.perf_counter()
        cells = self.experiment.cells
        done = [self.done[c.id] for c in cells if c.id in self.done]
        samples = samples_table([(o.samples, o.state_names) for o in done if o.samples is not None])
        rows = [self.done[c.id].row if c.id in self.done else cell_row(c) for c in cells]
        timings = [self.done[c.id].timing if c.id in self.done else timing_row(c) for c in cells]
        meta = self.provenance(len(done))
        cells_df, timings_df = cells_table(rows), timings_table(timings)
        write_parquet(samples, self.out / "samples.parquet", {**meta, "table": "samples"})
        write_parquet(cells_df, self.out / "cells.parquet", {**meta, "table": "cells"})
        write_parquet(timings_df, self.out / "timings.parquet",
                      {**meta, "table": "timings", "written_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")})
        if self.summarize is not None:
            text = self.summarize(meta, cells_df, timings_df)
            atomic_write(self.out / "summary.md", lambda p: Path(p).write_text(text, encoding="utf-8"))
        self.last_write = time.perf_counter()
        self.write_cost = self.last_write - t0

    def provenance(self, ndone: int) -> dict:
        from gnibench.suite.foundation.provenance import versions

        e = self.experiment
        return {"experiment": e.name, "title": e.title, "reference": e.reference,
                "description": e.description, "source": e.source, "experiment_toml": e.text,
                "versions": versions(), "complete": ndone == len(e.cells), "cells_done": ndone,
                "cells_total": len(e.cells),
                "cells": [{"cell": c.id, "problem": c.problem, "method": c.method,
                           "steps": c.steps, "t_end": c.t_end, "every": c.every,
                           "dt_out": c.dt_out}
                          for c in e.cells]}
