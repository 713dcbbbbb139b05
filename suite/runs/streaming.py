"""``gnibench solve`` writing a file or stdout in memory bounded independently of the row count.

The table of a solved cell (:func:`gnibench.suite.runs.tables.sample_columns`) is made block by
block instead of from the whole trajectory:

1. the compiled driver hands each full output buffer to a :class:`~gnibench.suite.runs.spool.
   RawSpool` and reuses it (:class:`gnibench.suite.cell.calls.Buffers`), so the integration holds
   one block of :data:`BLOCK` rows (the row budget counts every row, with the same reason text);
2. the rows are read back block by block: each block becomes a trajectory of its own
   (:func:`gnibench.suite.cell.drivers.build_trajectory`: integrals; K-S rows mapped back), its
   reference solution (:mod:`gnibench.problems.blockwise`: iterations sweep as in one array), its
   metric columns (:func:`gnibench.suite.metrics.compute.apply`), appended to a
   :class:`~gnibench.suite.runs.spool.ColumnSpool`; the per-cell metric values are folded as the
   blocks pass (:data:`FOLDS`: maximum, first, last);
3. the writers (:func:`gnibench.suite.runs.writers.write_columns`) read the spooled columns block
   by block: csv row by row, json column by column, Parquet by row groups, with the metadata
   known before the first byte.

Every row-wise quantity is computed row by row, so the bytes written are those of the whole-table
path (tests/runs/test_streaming.py). Cells whose table needs the whole series take the whole-table
path (:func:`streamable`): section crossings, external engines and Python integrators (they return
the whole run), integrated references (heyoka, rebound: one propagation over the whole grid) and
the chosen metrics not in :data:`FOLDS`. The Python API keeps the whole table (it returns it).
"""
from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

#: rows of one block: the driver's output buffer, and a block of the table made from it (at
#: least the driver facade's ``ADAPTIVE_CHUNK``, so that adaptive and K-S grid cells keep their
#: buffers, and the grid steps redone at their ends, ``time_grid.steps_redone``)
BLOCK = 1 << 16

#: the start of the name of a spool directory, followed by the process id
SPOOL_PREFIX = "gnibench-solve-"

#: how each per-cell value of a streamed metric follows from its values on the blocks, by the
#: start of its name: the largest (NaN propagates, as np.max over the whole series), the first
#: block's (a constant), the last block's (the final sample)
FOLDS = {"invariant_error": {"max_abs_err_": "max", "scale_": "first"},
         "relative_invariant_error": {"max_rel_err_": "max"},
         "global_error": {"final_": "last", "max_": "max", "solution_size": "max"}}


@contextlib.contextmanager
def spool_directory(cell=None):
    """A temporary directory for the spooled rows and columns (``TMPDIR``), removed on exit;
    None for a ``cell`` that is not :func:`streamable` (its table is made in memory)."""
    if cell is not None and not streamable(cell):
        yield None
        return
    _remove_orphans()
    with tempfile.TemporaryDirectory(prefix=f"{SPOOL_PREFIX}{os.getpid()}-") as d:
        yield Path(d)


def _remove_orphans() -> None:
    """Remove the spool directories of solves that were killed (SIGKILL leaves them): those whose
    process (the number in the name) no longer exists."""
    for d in Path(tempfile.gettempdir()).glob(f"{SPOOL_PREFIX}*-*"):
        try:
            os.kill(int(d.name[len(SPOOL_PREFIX):].split("-")[0]), 0)
        except ProcessLookupError:
            shutil.rmtree(d, ignore_errors=True)
        except (ValueError, OSError):       # not ours, or a process of another user
            continue


def streamable(cell) -> bool:
    """Can the cell's table be made block by block (see the module docstring)?"""
    from gnibench.suite.cell.driver import STREAMED
    from gnibench.suite.metrics.compute import selected

    if cell.kind not in STREAMED:
        return False
    if cell.reference is not None and cell.reference.backend != "exact":
        return False
    return all(c.metric.id in FOLDS or c.metric.scope != "cell" for c in selected(cell.metrics))


def stream_output(cell, directory: Path, progress=None):
    """What :func:`gnibench.suite.runs.solving.solve_output` makes of a :func:`streamable` cell,
    with the table's columns spooled under ``directory`` (:class:`~gnibench.suite.runs.spool.
    SpooledColumn`): ``(trajectory, Ctrl-C or None, table)``, the trajectory holding the last
    row and the table ``(metric outputs, skipped, columns, metadata)``, or None when there is no
    row (the whole, empty, table is made from the trajectory)."""
    from gnibench.suite.cell.driver import Interrupted, integrate
    from gnibench.suite.runs.spool import ColumnSpool, RawSpool
    from gnibench.suite.runs.storage import provenance

    raw = RawSpool(Path(directory) / "rows.f8", BLOCK)
    interrupted = None
    try:
        summary = integrate(cell, progress=progress, sink=raw)
    except Interrupted as e:                  # keep what was computed
        summary, interrupted = e.partial, e
    finally:
        raw.close()
    if not raw.width:                         # no row at all: the whole (empty) table
        return summary, interrupted, None
    reference = cell.reference if interrupted is None else None   # as integrate() attaches it
    plan = _sweeps(cell, raw) if reference is not None else None
    table, folded, skipped, described = ColumnSpool(directory), {}, {}, None
    for t, y, c in raw.read(BLOCK):
        traj = _block(cell, summary, t, y, c)
        if reference is not None:
            _attach(traj, cell, plan)
            described = _described(described, traj.reference.describe)
            last = traj.reference.y[-1:]
        out, skipped = _apply(traj, cell)
        table.append(_columns(traj, out))
        _fold(folded, out.scalars)
    raw.path.unlink()                         # the rows are in the columns now
    if described is not None:
        from gnibench.suite.cell.trajectory import ReferenceSamples

        summary.reference = ReferenceSamples(last, described)
    from gnibench.suite.metrics.base import MetricOutput

    metrics = MetricOutput(scalars={k: float(v) for k, v in folded.items()})
    return summary, interrupted, (metrics, skipped, table.columns(), provenance(summary, metrics))


def _block(cell, summary, t, y, c):
    """The trajectory of one block of raw rows (K-S rows mapped back to (t, y), [B] (5.4))."""
    from gnibench.suite.cell.drivers import build_trajectory

    problem = cell.problem
    if cell.transformed is not None:
        t, y = problem.record.transform.back(y, problem.values)
        c = c[:, :4]
    return build_trajectory(problem, cell.method, t, y, c, summary.status, summary.reason,
                            summary.provenance)


def _times(cell, t, y):
    if cell.transformed is not None:
        return cell.problem.record.transform.back(y, cell.problem.values)[0]
    return t


def _sweeps(cell, raw):
    """The sweep counts of the reference's iterations over all the rows, as in one array
    (:class:`gnibench.problems.blockwise.Plan`): a first pass over the times."""
    from gnibench.problems.blockwise import Plan
    from gnibench.suite.cell.reference import reference_solution

    for margin in (None, 1 << 30):           # a record too short to tell: all sweeps recorded
        plan = Plan() if margin is None else Plan(margin)
        for t, y, _ in raw.read(BLOCK):
            with plan.evaluating():
                reference_solution(cell.problem, _times(cell, t, y), cell.reference)
        if plan.fix():
            return plan
    raise RuntimeError("the reference's sweep counts could not be fixed")


def _attach(traj, cell, plan) -> None:
    from gnibench.suite.cell.driver import attach_reference

    with plan.evaluating():
        attach_reference(traj, cell.problem, cell.reference)


def _described(before: dict | None, now: dict) -> dict:
    """The reference's description over the blocks: the first block's, its seconds summed."""
    if before is None:
        return dict(now)
    return {**before, "seconds": before.get("seconds", 0.0) + now.get("seconds", 0.0)}


def _apply(traj, cell):
    from gnibench.suite.metrics.compute import apply

    return apply(traj, cell.metrics, problem=cell.problem)


def _columns(traj, out) -> dict:
    from gnibench.suite.runs.tables import sample_columns

    return sample_columns(traj, out)


def _fold(folded: dict, scalars: dict) -> None:
    """Fold one block's per-cell values into ``folded`` (:data:`FOLDS`)."""
    rules = {}
    for metric_rules in FOLDS.values():
        rules.update(metric_rules)
    for name, value in scalars.items():
        rule = next((r for prefix, r in rules.items() if name.startswith(prefix)), None)
        if rule is None:
            raise ValueError(f"no fold for the per-cell value {name}")
        if name not in folded or rule == "last":
            folded[name] = value
        elif rule == "max":
            folded[name] = np.maximum(folded[name], value)
