"""An ensemble cell's rows and statistics, made from its orbits when the tables are made.

The units of an ensemble cell (:mod:`gnibench.suite.runs.ensemble_spec`) are stored one part each;
:func:`merge` joins them, in orbit order, into the cell's part: its orbits (``ensemble.parquet``),
the samples of its kept orbits, and its row of ``cells.parquet``, whose per-cell values are
statistics of the orbits (:func:`statistics`). Everything here is a function of the orbits'
rows alone, so it does not depend on which worker ran which unit.

**Statistics** (``ensemble_stats.parquet``, one row per cell and metric; :func:`statistics`):
for every numeric column of the orbits' rows that measures an orbit (errors, counters, the time
reached; not its initial or final state), over the N orbits of the cell:

* ``failed``: orbits whose value is missing or not finite, or whose status is not ``ok``;
  ``failure_rate`` = failed / N;
* ``q10``, ``median``, ``q90``: quantiles of the values with every failed orbit counted as
  +inf (an orbit that failed never reached an accuracy; with more than 10 % failed, q90 is inf),
  by :func:`quantile` (numpy's default, Hyndman and Fan's definition 7: linear between the order
  statistics at (N - 1) q);
* ``min``, ``max`` of the same values.

The cell's row in ``cells.parquet`` has, beside the cell's own columns, ``orbits`` and
``failed_orbits`` (orbits whose status is not ``ok``), and in each metric column (``nfev``,
``steps``, ``final_global_error``, ``max_abs_err_<I>``, ...) the median of that statistic, so
that a table or diagram of cells shows an ensemble by its median orbit; its status is ``ok`` (the
orbits ran; theirs are in ``ensemble.parquet``) unless a unit ended in ``error``.
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.suite.runs.partfile import Part

QUANTILES = (("q10", 0.1), ("median", 0.5), ("q90", 0.9))
#: orbit columns that are not measures of the orbit (no statistics)
NOT_MEASURES = ("orbit", "status", "reason", "t_failed")
STATS_COLUMNS = ("cell", "problem", "method", "metric", "orbits", "failed", "failure_rate",
                 "q10", "median", "q90", "min", "max")


def quantile(values: np.ndarray, q: float) -> float:
    """The q-quantile (Hyndman and Fan's definition 7, numpy's default ``linear``): with the
    values sorted, x_(j) + (x_(j+1) - x_(j)) g at (N - 1) q = j + g. +inf values (failed orbits)
    are order statistics like the others: the result is inf when the interpolation reaches one
    with g > 0, or lands on one."""
    x = np.sort(np.asarray(values, dtype=float))
    if not len(x):
        return math.nan
    pos = (len(x) - 1) * q
    j = int(math.floor(pos))
    g = pos - j
    if j + 1 >= len(x) or g == 0:
        return float(x[j])
    lo, hi = float(x[j]), float(x[j + 1])
    if math.isinf(hi) or math.isinf(lo):
        return math.inf if hi > 0 or lo > 0 else lo
    return lo + (hi - lo) * g


def measures(orbits: dict, state_names) -> list[str]:
    """The columns of the orbits' rows that get statistics (see the module docstring)."""
    skip = set(NOT_MEASURES) | {f"{s}0" for s in state_names} | {f"final_{s}" for s in
                                                                  state_names}
    return [c for c, v in orbits.items() if c not in skip and np.asarray(v).dtype.kind == "f"]


def statistics(orbits: dict, state_names) -> list[dict]:
    """One row per measured column: orbits, failed, failure_rate, q10, median, q90, min, max."""
    ok = np.asarray(orbits["status"], dtype=object) == "ok"
    n = len(ok)
    out = []
    for name in measures(orbits, state_names):
        v = np.asarray(orbits[name], dtype=float)
        failed = ~ok | ~np.isfinite(v)
        counted = np.where(failed, np.inf, v)
        row = {"metric": name, "orbits": n, "failed": int(failed.sum()),
               "failure_rate": float(failed.sum()) / n if n else math.nan}
        row.update({label: quantile(counted, q) for label, q in QUANTILES})
        row.update(min=float(counted.min()) if n else math.nan,
                   max=float(counted.max()) if n else math.nan)
        out.append(row)
    return out


def merge(cell, parts: list[Part]) -> Part:
    """The part of an ensemble cell from the parts of its units, in order (see the module
    docstring)."""
    from gnibench.suite.foundation.status import Status
    from gnibench.suite.runs.tables import cell_row

    errors = [p for p in parts if p.row.get("status") == str(Status.ERROR)]
    if errors:
        row = dict(errors[0].row)
        row.update(cell=cell.id, group=cell.group, label=cell.label, orbits=cell.ensemble.total,
                   failed_orbits=None)
        return Part(None, row, dict(errors[0].timing, cell=cell.id), parts[0].state_names)
    orbits = _join([p.orbits for p in parts])
    samples = _join([p.samples for p in parts if p.samples is not None]) or None
    names = parts[0].state_names
    row = cell_row(cell, None, None, str(Status.OK))
    stats = {s["metric"]: s for s in statistics(orbits, names)}
    status = np.asarray(orbits["status"], dtype=object)
    failed = int((status != "ok").sum())
    reasons = {}
    for s in status[status != "ok"]:
        reasons[s] = reasons.get(s, 0) + 1
    row.update(reason=(f"{failed} of {len(status)} orbits failed: " + ", ".join(
        f"{k} ({v})" for k, v in reasons.items())) if failed else "",
        samples=None if samples is None else len(samples["orbit"]),
        integrals=parts[0].row.get("integrals", ""), reference=parts[0].row.get("reference", ""),
        orbits=len(status), failed_orbits=failed)
    if len(parts) == 1:              # a metric of the whole set (the area): the unit's values
        row.update({k: v for k, v in parts[0].row.items() if k not in row or k == "metric_notes"})
    for name, s in stats.items():
        if name == "steps":
            row["steps"] = None if not math.isfinite(s["median"]) else int(round(s["median"]))
        elif name == "t_final":
            row["t_final"] = s["median"]
        else:
            row[name] = s["median"]
    timing = dict(parts[0].timing, cell=cell.id,
                  wall_seconds=float(sum(p.timing.get("wall_seconds") or 0.0 for p in parts)),
                  compile_seconds=float(sum(p.timing.get("compile_seconds") or 0.0
                                            for p in parts)))
    return Part(samples, row, timing, names, orbits)


def _join(tables: list[dict]) -> dict:
    """Column tables joined row-wise (a column a table lacks is NaN there)."""
    tables = [t for t in tables if t]
    if not tables:
        return {}
    names: dict[str, None] = {}
    for t in tables:
        names.update(dict.fromkeys(t))
    sizes = [len(next(iter(t.values()))) for t in tables]
    return {c: np.concatenate([t[c] if c in t else np.full(n, np.nan) for t, n in
                               zip(tables, sizes)]) for c in names}


def ensemble_tables(parts: list[tuple[object, Part]], state_names=()):
    """``ensemble.parquet`` (one row per orbit of every finished ensemble cell, in cell and orbit
    order: ``cell``, ``problem``, ``method``, then the orbit's columns, :mod:`.ensembles`) and
    ``ensemble_stats.parquet`` (one row per cell and measured column, :func:`statistics`)."""
    import pandas as pd

    parts = sorted(((c, p) for c, p in parts if p.orbits), key=lambda cp: cp[0].id)
    sizes = [len(p.orbits["orbit"]) for _, p in parts]
    front = {"cell": np.repeat(np.array([c.id for c, _ in parts], dtype=np.int64), sizes),
             "problem": np.repeat(np.array([c.problem for c, _ in parts], dtype=object), sizes),
             "method": np.repeat(np.array([c.method for c, _ in parts], dtype=object), sizes)}
    joined = _join([p.orbits for _, p in parts])
    if not joined:
        joined = {"orbit": np.zeros(0, np.int64), "status": np.zeros(0, object)}
    orbits = pd.DataFrame({**front, **joined})
    rows = [{"cell": c.id, "problem": c.problem, "method": c.method, **s}
            for c, p in parts for s in statistics(p.orbits, p.state_names or state_names)]
    stats = pd.DataFrame(rows, columns=list(STATS_COLUMNS))
    stats = stats.astype({"cell": "int64", "orbits": "int64", "failed": "int64"})
    return orbits, stats
