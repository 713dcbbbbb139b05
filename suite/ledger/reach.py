"""What a run reached, and the values read from it: the ledger judges only what ran.

Every value a claim reads comes from cells of an experiment's tables. Each of those cells is a
:class:`Run` (its status and reach: final t, steps, section points found of those asked), and a
value is *measured* only when the part of the run it reads was computed:

* a cell that did not end ``ok`` (``nonfinite``, ``newton_failed``, ``max_steps``,
  ``step_too_small``, ``interrupted``, ``error``, ``pending``) gives no value, whatever the value
  reads: the claim is about a run of the seed's length, and ours is shorter;
* a section cell that found fewer points than asked (it reached its horizon first) is truncated
  too, unless the claim declares ``reach = "horizon"`` (its experiment records all crossings up
  to the horizon, the count being only a cap, as for so(4) in [B] §7.2);
* a value read at ``t = T`` or ``steps = N`` needs a run that got there (a complete run with a
  shorter horizon, e.g. at the quick scale, does not) and a sample there (t within 1e-9 of T
  relative, steps exactly N): never the last sample before it.

Otherwise :class:`NotMeasured` is raised with the reason (which cell, its status, where it
stopped); the claim's verdict is then "not reproduced" with that reason. A value may name the
failure statuses that are the claimed behaviour itself (``accept = ["step_too_small"]``: the
method breaking down is what the claim says); the verdict still shows the run's status and reach.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd


class NotMeasured(Exception):
    """A value the runs cannot give (a failed or truncated cell, a time the run did not reach)."""


def _num(x) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return math.nan
    return v


@dataclass(frozen=True)
class Run:
    """One cell a claim read: where it comes from, its status and its reach."""

    experiment: str
    cell: int
    label: str
    status: str
    reason: str
    t_final: float
    t_end: float            # NaN when the horizon is given in steps
    steps: float
    steps_planned: float
    section: int            # points asked (0: not a section run)
    points: float           # samples written (section runs: points found)

    @classmethod
    def of(cls, experiment: str, row) -> Run:
        get = row.get if isinstance(row, dict) else (lambda k, d=None: getattr(row, k, d))
        return cls(experiment=experiment, cell=int(get("cell")), label=str(get("label", "") or ""),
                   status=str(get("status", "") or ""), reason=str(get("reason", "") or ""),
                   t_final=_num(get("t_final")), t_end=_num(get("t_end")),
                   steps=_num(get("steps")), steps_planned=_num(get("steps_planned")),
                   section=int(_num(get("section")) or 0) if not math.isnan(_num(get("section")))
                   else 0, points=_num(get("samples")))

    @property
    def short(self) -> bool:
        """A section run that found fewer points than it asked for."""
        return self.section > 0 and not (self.points >= self.section)

    def complete(self, horizon_only: bool = False) -> bool:
        return self.status == "ok" and (horizon_only or not self.short)

    def reach(self) -> str:
        """``t = 7940 of 2e+05, 794 steps`` (section runs: ``, 395 of 500 points``)."""
        parts = []
        if not math.isnan(self.t_final):
            of = f" of {self.t_end:.6g}" if not math.isnan(self.t_end) else ""
            parts.append(f"t = {self.t_final:.6g}{of}")
        if not math.isnan(self.steps):
            of = (f" of {self.steps_planned:.6g}" if math.isnan(self.t_end)
                  and not math.isnan(self.steps_planned) else "")
            parts.append(f"{self.steps:.0f}{of} steps")
        if self.section:
            parts.append(f"{self.points:.0f} of {self.section} points")
        return ", ".join(parts) or "nothing computed"

    def describe(self) -> str:
        return f"{self.experiment} cell {self.cell} ({self.label}): {self.status}, {self.reach()}"

    def why_incomplete(self) -> str:
        """The sentence of a verdict on a run that did not complete."""
        where = f"{self.experiment} cell {self.cell} ({self.label})"
        if self.status == "ok" and self.short:
            return (f"the run {where} found {self.points:.0f} of the {self.section} section points "
                    f"it asked for before its horizon t = {self.t_end:.6g}")
        if self.status in ("pending", "error", "interrupted"):
            return f"the run {where} did not finish ({self.status}{': ' + self.reason if self.reason else ''})"
        return (f"the run {where} stopped at {self.reach()} ({self.status}"
                f"{': ' + self.reason if self.reason else ''})")


def runs_of(experiment: str, cells: pd.DataFrame) -> list[Run]:
    return [Run.of(experiment, r) for r in cells.to_dict("records")]


def require_complete(runs: list[Run], accept=(), horizon_only: bool = False) -> None:
    """NotMeasured naming the first run that did not complete (``accept``: failure statuses
    that are the claimed behaviour)."""
    for r in runs:
        if r.complete(horizon_only) or r.status in accept:
            continue
        raise NotMeasured(r.why_incomplete())


def at_sample(column: np.ndarray, rows: pd.DataFrame, at: str, run: Run) -> float:
    """The value of a sample column at ``last``, ``t=T``, ``steps=N``, or reduced over the
    samples (``max_abs``, ``min``, ``max``); NotMeasured when the run did not reach T or N."""
    if len(column) == 0:
        raise NotMeasured(f"{run.experiment} cell {run.cell} ({run.label}) has no samples")
    if at == "last":
        return float(column[-1])
    if at in ("max_abs", "min", "max"):
        a = np.abs(column) if at == "max_abs" else column
        a = np.where(np.isnan(a), np.inf, a) if at != "min" else a
        return float(np.max(a) if at != "min" else np.min(a))
    key, _, number = at.partition("=")
    target = float(number)
    if key not in rows.columns:
        raise KeyError(f"no sample column {key!r} to read at {at!r}")
    where = rows[key].to_numpy(dtype=float)
    reached = np.nanmax(where) if len(where) else -math.inf
    if not reached >= target * (1 - 1e-12):
        raise NotMeasured(f"{at} was not reached: {run.describe()}")
    idx = np.nonzero(where <= target * (1 + 1e-12))[0]
    if not len(idx):
        raise NotMeasured(f"no sample at or before {at}: {run.describe()}")
    got = float(where[idx[-1]])
    if abs(got - target) > 1e-9 * max(abs(target), 1.0):
        raise NotMeasured(f"no sample at {at} (the nearest before is at {key}={got:.10g}): "
                          f"{run.describe()}")
    return float(column[idx[-1]])
