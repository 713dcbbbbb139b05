"""One cell solved and tabled: what ``gnibench solve`` writes and ``gnibench.solve`` returns.

:func:`solve_cell_spec` checks the options and makes the typed cell (before any work: the command
line starts its progress display after it), :func:`solve_output` solves the cell, applies its
metrics and builds the table
(:func:`gnibench.suite.runs.tables.sample_columns`) and its metadata
(:func:`gnibench.suite.runs.storage.provenance`). The command line writes both
(:func:`gnibench.suite.runs.writers.write_columns`); the Python API returns them as a DataFrame and
the JSON metadata as a dict (:func:`json_meta`), so the two cannot drift apart.
"""
from __future__ import annotations

import json
from dataclasses import dataclass

from gnibench.suite.foundation.errors import UserError, spelled


@dataclass
class SolveOutput:
    """A solved cell: its trajectory (:class:`gnibench.suite.cell.trajectory.Trajectory`),
    metric outputs, chosen metrics that did not apply (id -> why), table as columns (name ->
    array, :func:`gnibench.suite.runs.tables.sample_columns`), metadata, the Ctrl-C that
    stopped it (None if it ran to its end) and the typed cell
    (:class:`gnibench.suite.cell.cellspec.CellSpec`). ``frame`` is the table as a DataFrame,
    made when asked: ``gnibench solve`` writes csv and json from the columns without importing
    pandas (:func:`gnibench.suite.runs.writers.write_columns`)."""

    traj: object
    metrics: object
    skipped: dict
    columns: dict
    meta: dict
    interrupted: BaseException | None = None
    cell: object = None

    @property
    def frame(self):
        from gnibench.suite.runs.tables import frame_of

        return frame_of(self.columns)


def check_options(every: int, section, reference, dt_out) -> None:
    """Options that exclude each other (the command line's flag names in the messages)."""
    if section is not None:
        if every != 1:
            raise UserError(f"{spelled('--every')} does not apply with {spelled('--section')} (the "
                            f"section points are written)")
        if reference is not None:
            raise UserError(f"{spelled('--reference')} does not apply with {spelled('--section')} "
                            f"(no global error is written)")
        if dt_out is not None:
            raise UserError(f"{spelled('--dt-out')} does not apply with {spelled('--section')} (the "
                            f"section points are written)")


def solve_cell_spec(problem, method, *, steps: int | None = None, t_end: float | None = None,
                    every: int = 1, dt_out: float | None = None, section: int | None = None,
                    reference=None, metrics=()):
    """The typed cell of a solve (:func:`gnibench.suite.metrics.cells.make_cell`), after the
    checks of options that exclude each other. ``problem``, ``method``: spec strings or typed
    values; ``metrics``: metric specs (a list, or one comma-separated string) or parsed choices.
    Bad input raises UserError before any work."""
    from gnibench.suite.metrics.cells import make_cell

    check_options(every, section, reference, dt_out)
    return make_cell(problem, method, steps=steps, t_end=t_end, every=every, dt_out=dt_out,
                     section=section, reference=reference, metrics=metrics)


def solve_output(cell, progress=None, spool=None) -> SolveOutput:
    """Solve a typed cell (:func:`solve_cell_spec`) and build its table and metadata; Ctrl-C is
    kept in ``interrupted`` with the samples computed so far.

    ``spool``: a directory (:func:`gnibench.suite.runs.streaming.spool_directory`) where the table
    of a :func:`~gnibench.suite.runs.streaming.streamable` cell is made block by block, in memory
    bounded independently of the rows (``gnibench solve``); its columns are then read from the
    directory's files while it exists. Without it, the table is held in memory (the Python API)."""
    from gnibench.suite.cell.driver import Interrupted, integrate
    from gnibench.suite.runs.streaming import stream_output, streamable

    if spool is not None and streamable(cell):
        traj, interrupted, table = stream_output(cell, spool, progress)
        if table is None:                     # no row: the empty table
            return whole_output(cell, traj, interrupted)
        return SolveOutput(traj, *table, interrupted, cell)
    interrupted = None
    try:
        traj = integrate(cell, progress=progress)
    except Interrupted as e:                  # keep what was computed
        traj, interrupted = e.partial, e
    return whole_output(cell, traj, interrupted)


def whole_output(cell, traj, interrupted=None) -> SolveOutput:
    """The table, metric outputs and metadata of a whole trajectory."""
    from gnibench.suite.metrics.compute import apply
    from gnibench.suite.runs.storage import provenance
    from gnibench.suite.runs.tables import sample_columns

    out, skipped = apply(traj, cell.metrics, problem=cell.problem)
    return SolveOutput(traj, out, skipped, sample_columns(traj, out), provenance(traj, out),
                       interrupted, cell)


def json_meta(meta: dict) -> dict:
    """The metadata as the JSON output carries it (``gnibench solve --format json``'s ``meta``):
    the same serialization, read back."""
    return json.loads(json.dumps(meta, default=str))
