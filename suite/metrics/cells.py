"""The edge where a typed cell is made: specs (or typed values) and metric choices in, a validated
:class:`~gnibench.suite.cell.cellspec.CellSpec` out.

``gnibench solve``, experiment files (:mod:`gnibench.suite.runs.experiment`) and the Python API
call :func:`make_cell` once per cell; everything after it works on the typed cell. It sits on the
metrics floor because metric choices decide the sampling: a metric that needs samples at whole
periods (η(nT), [B] §5.2) puts the cell on the grid t = nT unless its own samples fall there
(:func:`gnibench.suite.metrics.compute.period_grid`).
"""
from __future__ import annotations

from gnibench.suite.cell.cellspec import CellSpec, build
from gnibench.suite.cell.spec import prepare
from gnibench.suite.metrics.compute import parse_metrics, period_grid


def make_cell(problem, method, *, steps: int | None = None, t_end: float | None = None,
              every: int = 1, dt_out: float | None = None, section: int | None = None,
              reference=None, metrics=()) -> CellSpec:
    """A validated typed cell (raises UserError before any work).

    ``problem``, ``method``: spec strings or typed values
    (:func:`gnibench.suite.cell.spec.prepare`); ``metrics``: metric spec strings, one
    comma-separated string (as ``--metrics``) or parsed choices; ``reference``: a reference spec
    text, a :class:`~gnibench.suite.cell.reference.ReferenceSpec` or None (the problem's
    default). A section cell is not put on a time grid."""
    choices = parse_metrics(metrics)
    problem, method = prepare(problem, method)
    if section is None:
        dt_out = period_grid(choices, problem, method, every, dt_out)   # eta: samples at t = nT
    return build(problem, method, steps=steps, t_end=t_end, every=every, dt_out=dt_out,
                 section=section, reference=reference, metrics=choices, prepared=True)
