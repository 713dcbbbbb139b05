"""The metric record and how metrics are chosen and computed.

A metric is a small registered function of a :class:`~gnibench.suite.cell.trajectory.Trajectory`
plus the problem (a :class:`~gnibench.suite.foundation.params.Bound`): it returns per-sample
columns (they join the samples table, one value per row of the trajectory) and per-cell scalars
(they join ``cells.parquet``). Tables, figures, reports and the claims ledger read these outputs
only. Metrics are chosen with the spec syntax: ``--metrics eta,growth:of=H`` on the command line,
``metrics = ["eta", "growth:of=H"]`` in an experiment file.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gnibench.suite.foundation.params import Param

#: what a metric may need from a cell (``Metric.needs``), and what that means
NEEDS = {
    "integrals": "the problem has first integrals",
    "reference": "reference samples (an exact solution or --reference)",
    "period": "the problem has a period (Problem.period); samples at whole periods t = nT",
    "section": "the cell's samples are section crossings (--section)",
    "samples": "the cell's samples are a trajectory (not section crossings)",
}


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
class Metric:
    """A self-describing metric.

    ``compute(trajectory, problem, values) -> MetricOutput``; ``values`` are the metric's options,
    validated against ``params``. ``needs`` lists the keys of :data:`NEEDS` the cell must meet;
    ``columns`` and ``scalars`` document the names it writes (``<I>`` stands for each integral,
    ``<X>`` for each error it is applied to). ``default`` metrics are computed for every cell they
    apply to.
    """

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

    def why_not(self, traj, problem) -> str:
        """Why the metric does not apply to this cell ("" when it does)."""
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
        return ""

    def describe(self) -> dict:
        return {"id": self.id, "title": self.title, "reference": self.reference, "doc": self.doc,
                "needs": list(self.needs), "default": self.default,
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


def max_abs(values: np.ndarray) -> float:
    """max |x|, where NaN counts as infinite (a diverged cell must not look accurate)."""
    a = np.abs(np.asarray(values, dtype=float))
    return float(np.max(np.where(np.isnan(a), np.inf, a))) if a.size else float("nan")
