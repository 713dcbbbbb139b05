"""The metric record and how metrics are chosen and computed.

A metric is a small registered function of a :class:`~gnibench.suite.cell.trajectory.Trajectory`
plus the problem (a :class:`~gnibench.suite.foundation.params.Bound`): it returns per-sample
columns (they join the samples table, one value per row of the trajectory) and per-cell scalars
(they join ``cells.parquet``). Tables, figures, reports and the claims ledger read these outputs
only. Metrics are chosen with the spec syntax: ``--metrics eta,growth:of=H`` on the command line,
``metrics = ["eta", "growth:of=H"]`` in an experiment file.

Three scopes: a ``cell`` metric is a function of one trajectory; a ``family`` metric (the observed
order, :mod:`gnibench.suite.metrics.order`) is a function of the cells and samples tables of the
cells of an experiment that differ only in the step size h (:mod:`gnibench.suite.metrics.families`);
an ``ensemble`` metric (the area of a carried set, :mod:`gnibench.suite.metrics.area`) is a
function of the orbits of an ensemble cell (``compute(carried, values)``).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gnibench.suite.foundation.params import Param
from gnibench.suite.foundation.registries import Registered

#: what a metric may need from a cell (``Metric.needs``), and what that means
NEEDS = {
    "integrals": "the problem has first integrals",
    "reference": "reference samples (an exact solution or --reference)",
    "period": "the problem has a period (Problem.period); samples at whole periods t = nT",
    "section": "the cell's samples are section crossings (--section)",
    "samples": "the cell's samples are a trajectory (not section crossings)",
}

SCOPES = ("cell", "family", "ensemble")


@dataclass
class MetricOutput:
    """What a metric gives back: per-sample columns and per-cell scalars, by name."""

    columns: dict[str, np.ndarray] = field(default_factory=dict)
    scalars: dict[str, Any] = field(default_factory=dict)

    def update(self, other: MetricOutput) -> None:
        clash = (set(self.columns) & set(other.columns)) | (set(self.scalars) & set(other.scalars))
        if clash:
            raise ValueError(f"two metrics write the same names: {sorted(clash)}")
        self.columns.update(other.columns)
        self.scalars.update(other.scalars)


@dataclass(frozen=True)
class Metric(Registered):
    """A self-describing metric.

    ``compute(trajectory, problem, values) -> MetricOutput``; ``values`` are the metric's options,
    validated against ``params``. ``needs`` lists the keys of :data:`NEEDS` the cell must meet;
    ``problem_check(problem, values) -> str`` and ``check(trajectory, problem, values) -> str``, if
    given, say why else the metric does not apply (to the problem: known before integrating; to
    the trajectory); ``validate(values) -> str`` checks options against each other (a non-empty
    text is a bad choice). ``columns`` and ``scalars`` document the names it writes (``<I>`` stands for
    each integral, ``<X>`` for each error it is applied to). ``default`` metrics are computed for
    every cell they apply to.

    A ``family`` metric (``scope="family"``) has ``compute(cells, samples, values) -> DataFrame``:
    the cells and samples tables of one family (cells equal in everything but h), returning one
    row per cell (index: cell id) of columns for ``cells.parquet``.
    """

    registry = "metric"

    id: str
    title: str
    reference: str
    doc: str
    compute: Callable
    needs: tuple[str, ...] = ()
    params: tuple[Param, ...] = ()
    columns: tuple[tuple[str, str], ...] = ()
    scalars: tuple[tuple[str, str], ...] = ()
    default: bool = False
    scope: str = "cell"
    problem_check: Callable | None = None
    check: Callable | None = None
    validate: Callable | None = None

    def __post_init__(self):
        unknown_needs = set(self.needs) - set(NEEDS)
        if unknown_needs or self.scope not in SCOPES:
            raise ValueError(f"metric {self.id}: bad needs {sorted(unknown_needs)} or scope "
                             f"{self.scope!r}")

    def problem_why_not(self, problem, values=None) -> str:
        """Why the metric cannot apply to any cell of this problem ("" when it may)."""
        values = {} if values is None else values
        rec = problem.record
        if "integrals" in self.needs and not _integral_names(rec):
            return f"{problem.id} has no first integrals"
        if "period" in self.needs and getattr(rec, "period", None) is None:
            return f"{problem.id} has no period"
        if "section" in self.needs and not rec.sections:
            return f"{problem.id} has no Poincaré section"
        return self.problem_check(problem, values) if self.problem_check is not None else ""

    def why_not(self, traj, problem, values=None) -> str:
        """Why the metric does not apply to this cell ("" when it does)."""
        values = {} if values is None else values
        if self.scope == "family":
            return (f"{self.id} is computed across the cells of an experiment that differ only "
                    "in h (gnibench run), not from one cell")
        if self.scope == "ensemble":
            return f"{self.id} is " + self.check(traj, problem, values)
        for need in self.needs:
            if need == "integrals" and not traj.integral_names:
                return f"{problem.id} has no first integrals"
            if need == "reference" and traj.reference is None:
                return "no reference samples (no exact solution; use --reference)"
            if need == "period" and getattr(problem.record, "period", None) is None:
                return f"{problem.id} has no period"
            if need == "section" and traj.kind != "section":
                return "the samples are not section crossings (use --section)"
            if need == "samples" and traj.kind != "samples":
                return "the samples are section crossings, not a trajectory"
        if self.problem_check is not None:
            why = self.problem_check(problem, values)
            if why:
                return why
        return self.check(traj, problem, values) if self.check is not None else ""

    def describe(self) -> dict:
        return {"id": self.id, "title": self.title, "reference": self.reference, "doc": self.doc,
                "scope": self.scope, "needs": list(self.needs), "default": self.default,
                "params": [p.describe() for p in self.params],
                "columns": dict(self.columns), "scalars": dict(self.scalars)}


@dataclass(frozen=True)
class MetricChoice:
    """A metric with its option values (parsed from ``id[:key=value,...]``)."""

    metric: Metric
    values: dict

    def text(self) -> str:
        parts = [f"{p.name}={p.format(self.values[p.name])}" for p in self.metric.params
                 if self.values.get(p.name) is not None and self.values[p.name] != p.default]
        return self.metric.id + (":" + ",".join(parts) if parts else "")


def _integral_names(rec) -> tuple[str, ...]:
    """The names of a problem record's first integrals (from its sympy model)."""
    from gnibench.problems.codegen import problem_meta

    return tuple(problem_meta(rec)["integrals"])


def integral_names(problem) -> tuple[str, ...]:
    """The names of a parsed problem's first integrals, in the order of ``Trajectory.integrals``."""
    return _integral_names(problem.record)


def max_abs(values: np.ndarray) -> float:
    """max |x|, where NaN counts as infinite (a diverged cell must not look accurate)."""
    a = np.abs(np.asarray(values, dtype=float))
    return float(np.max(np.where(np.isnan(a), np.inf, a))) if a.size else float("nan")
