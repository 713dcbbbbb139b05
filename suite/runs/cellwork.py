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
    samples: dict | None = None     # column name -> array; None for a cell in error
    row: dict = field(default_factory=dict)
    timing: dict = field(default_factory=dict)
    state_names: tuple[str, ...] = ()
    orbits: dict | None = None      # an ensemble cell's per-orbit rows (column name -> array)


def _throttled(cell_id: int, report) -> Callable[[float], None]:
    """``report`` at most once every ``REPORT_SECONDS``, the first time that long after the cell
    started (a short cell sends none: no message nor wakeup of the parent per cell)."""
    last = [time.monotonic()]

    def progress(fraction: float) -> None:
        now = time.monotonic()
        if now - last[0] >= REPORT_SECONDS:
            last[0] = now
            report(cell_id, float(fraction))

    return progress


def run_cell(cell, report: Callable[[int, float], None] | None = None) -> CellOutcome:
    """Solve one cell (its typed cell, ``cell.spec``, as it is), apply its metrics, and build its
    rows. The samples are columns (a dict of arrays: no DataFrame is made per cell, and a pool
    worker never imports pandas); the tables are made from them (:func:`~gnibench.suite.runs.
    tables.samples_table`). An ensemble cell runs its orbits (:mod:`.ensembles`)."""
    from gnibench.suite.runs.tables import cell_row, timing_row

    report = report or _reporter
    progress = _throttled(cell.id, report) if report is not None else None
    try:
        with np.errstate(all="ignore"):     # overflow in a diverging cell is a status, not noise
            if getattr(cell, "ensemble", None) is not None:
                from gnibench.suite.runs.ensembles import run_ensemble

                samples, row, timing, names, orbits = run_ensemble(cell, progress)
                return CellOutcome(cell, row["status"], row["reason"], samples, row, timing,
                                   names, orbits)
            return _single(cell, progress)
    except Exception as e:  # noqa: BLE001 - any failure of one cell is recorded, the run goes on
        reason = f"{type(e).__name__}: {e}".replace("\n", " ")
        return CellOutcome(cell, str(Status.ERROR), reason, None,
                           cell_row(cell, None, None, str(Status.ERROR), reason),
                           timing_row(cell, None, str(Status.ERROR)))


def _single(cell, progress) -> CellOutcome:
    from gnibench.suite.cell.driver import integrate
    from gnibench.suite.metrics.compute import apply
    from gnibench.suite.runs.tables import cell_row, cell_sample_columns, timing_row

    traj = integrate(cell.spec, progress=progress)
    walls = timed_repeats(cell, traj)
    metrics, skipped = apply(traj, cell.spec.metrics, problem=cell.spec.problem, families=False)
    samples = cell_sample_columns(traj, metrics)
    row = cell_row(cell, traj, metrics, skipped=skipped)
    return CellOutcome(cell, str(traj.status), traj.reason, samples, row,
                       timing_row(cell, traj, walls=walls), traj.state_names)


class NotRepeatable(RuntimeError):
    """A repeated integration of a cell gave other results than its first run."""


def timed_repeats(cell, traj) -> list[float]:
    """The wall times of the cell's ``repeat`` timed integrations: the first run's (``traj``)
    and those of ``repeat - 1`` more runs of the same cell, each after the first run's warm-up
    (kernels compiled and loaded), without the reference solution (attached once). Every run
    must give the same samples, counters and status bit for bit; a difference raises
    :class:`NotRepeatable` (the cell's status is then ``error``, with this line as its reason).
    A cell that did not end ``ok`` is not repeated (the time of a failed run measures
    nothing)."""
    from dataclasses import replace

    from gnibench.suite.cell.driver import integrate

    walls = [traj.wall_seconds]
    if getattr(cell, "repeat", 1) <= 1 or str(traj.status) != "ok":
        return walls
    bare = replace(cell.spec, reference=None, reference_given=False)
    for k in range(2, cell.repeat + 1):
        again = integrate(bare)
        why = difference(traj, again)
        if why:
            raise NotRepeatable(f"run {k} of {cell.repeat} differs from the first: {why}; the "
                                f"integration is not deterministic")
        walls.append(again.wall_seconds)
    return walls


def difference(a, b) -> str:
    """What differs between two trajectories of one cell ("" when nothing does): status, sample
    times, states, counters, section charts."""
    if str(a.status) != str(b.status):
        return f"status {a.status} then {b.status}"
    for name in ("t", "y", "steps", "nfev", "njev", "rejected", "chart"):
        x, y = getattr(a, name, None), getattr(b, name, None)
        if x is None and y is None:
            continue
        if x is None or y is None or np.shape(x) != np.shape(y):
            return f"{name} has {np.shape(x)} then {np.shape(y)} values"
        if not np.array_equal(x, y, equal_nan=True):
            i = int(np.flatnonzero(~((x == y) | (np.isnan(x) & np.isnan(y))).reshape(
                len(x), -1).all(axis=1))[0])
            return f"{name} at sample {i}: {np.ravel(x[i])[:3]} then {np.ravel(y[i])[:3]}"
    return ""


def kernel_plan(cell) -> tuple[str, int]:
    """The cell's kernel group and a guess of the cost of compiling its kernel (0: in the disk
    cache already; :func:`gnibench.suite.cell.compiled.kernel_plan`). Cells with the same key run
    the same compiled kernel (the text of the generated module, or the external engine):
    executors run the first cell of a group before the others, so a kernel is compiled once and
    then loaded from the disk cache."""
    from gnibench.suite.cell.compiled import kernel_plan as plan

    return plan(cell.spec.problem, cell.spec.method)
