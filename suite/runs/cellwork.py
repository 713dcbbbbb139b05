"""The unit of work of every executor: one cell of an experiment, solved, measured, made rows.

:func:`run_cell` runs wherever the executor puts it (this process, a worker of the local pool, a
Dask worker). It returns a small picklable :class:`CellOutcome`. An unexpected exception inside a
cell becomes status ``error`` with its type and message (the matrix goes on); Ctrl-C is not
caught. Progress inside a long cell goes to ``report(cell_id, fraction)`` when one is installed
(the local pool installs one per worker, see :mod:`gnibench.suite.runs.executors`).
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from gnibench.suite.foundation.status import Status

REPORT_SECONDS = 0.5          # at most two progress reports a second per cell

#: installed in a worker process by the executor: report(cell_id, fraction)
_reporter: Callable[[int, float], None] | None = None


def install_reporter(report: Callable[[int, float], None] | None) -> None:
    global _reporter
    _reporter = report


@dataclass
class CellOutcome:
    """What one cell gives back: its rows, ready for the tables (small and picklable)."""

    cell: object
    status: str
    reason: str
    samples: object = None          # pandas DataFrame, None for a cell in error
    row: dict = field(default_factory=dict)
    timing: dict = field(default_factory=dict)
    state_names: tuple[str, ...] = ()


def _throttled(cell_id: int, report) -> Callable[[float], None]:
    last = [0.0]

    def progress(fraction: float) -> None:
        now = time.monotonic()
        if now - last[0] >= REPORT_SECONDS:
            last[0] = now
            report(cell_id, float(fraction))

    return progress


def run_cell(cell, report: Callable[[int, float], None] | None = None,
             frames: bool = True) -> CellOutcome:
    """Solve one cell (its typed cell, ``cell.spec``, as it is), apply its metrics, and build its
    rows. ``frames=False``: the samples are left as columns (a dict of arrays; a pool worker
    builds no DataFrame and never imports pandas), made a table by :func:`with_frame`."""
    from gnibench.suite.cell.driver import integrate
    from gnibench.suite.metrics.compute import apply
    from gnibench.suite.runs.tables import cell_row, cell_sample_columns, cell_samples, timing_row

    report = report or _reporter
    progress = _throttled(cell.id, report) if report is not None else None
    try:
        with np.errstate(all="ignore"):     # overflow in a diverging cell is a status, not noise
            traj = integrate(cell.spec, progress=progress)
            metrics, skipped = apply(traj, cell.spec.metrics, problem=cell.spec.problem,
                                     families=False)
            samples = cell_samples(cell, traj, metrics) if frames else \
                cell_sample_columns(traj, metrics)
            row = cell_row(cell, traj, metrics, skipped=skipped)
    except Exception as e:  # noqa: BLE001 - any failure of one cell is recorded, the run goes on
        reason = f"{type(e).__name__}: {e}".replace("\n", " ")
        return CellOutcome(cell, str(Status.ERROR), reason, None,
                           cell_row(cell, None, None, str(Status.ERROR), reason),
                           timing_row(cell, None, str(Status.ERROR)))
    return CellOutcome(cell, str(traj.status), traj.reason, samples, row, timing_row(cell, traj),
                       traj.state_names)


def with_frame(outcome: CellOutcome) -> CellOutcome:
    """An outcome of ``run_cell(..., frames=False)`` with its samples as the table (as
    ``run_cell`` makes it; a failure there is the cell's error)."""
    if not isinstance(outcome.samples, dict):
        return outcome
    from gnibench.suite.runs.tables import cell_frame, cell_row, timing_row

    try:
        outcome.samples = cell_frame(outcome.cell, outcome.samples)
    except Exception as e:  # noqa: BLE001 - as run_cell records it
        reason = f"{type(e).__name__}: {e}".replace("\n", " ")
        cell = outcome.cell
        return CellOutcome(cell, str(Status.ERROR), reason, None,
                           cell_row(cell, None, None, str(Status.ERROR), reason),
                           timing_row(cell, None, str(Status.ERROR)))
    return outcome


def kernel_plan(cell) -> tuple[str, int]:
    """The cell's kernel group and a guess of the cost of compiling its kernel (0: in the disk
    cache already; :func:`gnibench.suite.cell.compiled.kernel_plan`). Cells with the same key run
    the same compiled kernel (the text of the generated module, or the external engine):
    executors run the first cell of a group before the others, so a kernel is compiled once and
    then loaded from the disk cache."""
    from gnibench.suite.cell.compiled import kernel_plan as plan

    return plan(cell.spec.problem, cell.spec.method)
