"""Tables from trajectories and their metric outputs: the one-cell table of ``gnibench solve`` and
the three tables of an experiment run.

``samples`` (one row per cell and sample), ``cells`` (one row per cell) and ``timings`` (one row per
cell). Only ``timings`` holds wall-clock numbers, so ``samples`` and ``cells`` are bit-identical
between two runs of the same experiment on the same machine. The column contract is in
``suite/experiments/README.md`` and the README ("``gnibench solve`` output").
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from gnibench.suite.foundation.status import TABLE_STATUSES

if TYPE_CHECKING:
    import pandas as pd

SAMPLE_FRONT = ("cell", "problem", "method", "t", "steps", "nfev")
#: between the ids of the column ``modifiers`` of cells.parquet (``observer+projection``)
MODIFIER_SEPARATOR = "+"


def modifier_ids(column_value) -> list[str]:
    """The modifier ids of a cell, from its column ``modifiers``."""
    return [m for m in str(column_value or "").split(MODIFIER_SEPARATOR) if m]
STATUSES = TABLE_STATUSES


def sample_frame(traj, metrics) -> pd.DataFrame:
    """The table of one cell (see :func:`sample_columns`)."""
    return frame_of(sample_columns(traj, metrics))


def frame_of(columns: dict[str, np.ndarray]) -> pd.DataFrame:
    """The DataFrame of a cell's columns (:func:`sample_columns`)."""
    import pandas as pd

    steps = columns.get("steps")
    if steps is not None and np.asarray(steps).dtype.kind == "f":     # see missing_steps
        columns = {**columns, "steps": pd.array(steps, dtype="Int64")}
    return pd.DataFrame(columns, copy=False)          # the arrays are the cell's own


def missing_steps(df: pd.DataFrame) -> pd.DataFrame:
    """``steps`` as nullable integers (pandas Int64: empty in csv, null in Parquet) where some
    are missing (NaN: a Python solver that reports no count, or section rows), else int64."""
    if "steps" in df.columns and df["steps"].dtype.kind == "f":
        df["steps"] = df["steps"].astype("Int64")
    return df


def sample_columns(traj, metrics) -> dict[str, np.ndarray]:
    """The table of one cell: its samples and the per-sample metric columns.

    Samples: ``t``, the states, ``err_<I>``, ``global_error``, ``steps``, ``nfev``, then the
    columns of the chosen metrics (``steps`` NaN where the method reports none:
    :func:`missing_steps` makes it a nullable integer in a DataFrame). Section crossings:
    ``crossing``, ``t``, ``chart`` (multi-chart sections), the section's coordinates, the other
    states, ``err_<I>``, then the chosen metrics.
    """
    cols = dict(metrics.columns)
    errors = {k: cols.pop(k) for k in list(cols) if k.startswith("err_")}
    out: dict[str, np.ndarray] = {}
    if traj.kind == "section":
        out["crossing"] = np.arange(1, len(traj.t) + 1)
        out["t"] = traj.t
        if traj.chart is not None:
            out["chart"] = traj.chart
        coords = list(traj.provenance.get("section_coords", ()))
        order = coords + [s for s in traj.state_names if s not in coords]
        for s in order:
            out[s] = traj.y[:, traj.state_names.index(s)]
        out.update(errors)
    else:
        out["t"] = traj.t
        for i, name in enumerate(traj.state_names):
            out[name] = traj.y[:, i]
        out.update(errors)
        if "global_error" in cols:
            out["global_error"] = cols.pop("global_error")
        out["steps"] = traj.steps
        out["nfev"] = traj.nfev
    clash = set(out) & set(cols)
    if clash:
        raise ValueError(f"metric columns {sorted(clash)} clash with the sample columns")
    out.update(cols)
    return out


def cell_sample_columns(traj, metrics) -> dict[str, np.ndarray]:
    """The samples of one cell of an experiment as columns (its ``gnibench solve`` table; the
    cell id and specs are added when the tables are made, :func:`samples_table`): what a worker
    sends and the store keeps, so a worker never builds a DataFrame or imports pandas."""
    clash = set(traj.state_names) & set(SAMPLE_FRONT + ("global_error", "orbit"))
    if clash:
        raise ValueError(f"state names {sorted(clash)} clash with the fixed sample columns")
    return sample_columns(traj, metrics)


def cell_row(cell, traj=None, metrics=None, status: str = "pending", reason: str = "",
             skipped: dict | None = None) -> dict:
    """The summary row of one cell; without a trajectory, the row of a cell that did not finish.

    ``skipped`` maps each chosen metric that did not apply to why (``metric_notes``)."""
    from gnibench.suite.metrics.families import join_metrics

    notes = "; ".join(f"{k}: {v}" for k, v in (skipped or {}).items())
    spec = cell.spec
    family = spec.method.family()
    row = {"cell": cell.id, "group": cell.group, "label": cell.label, "problem": cell.problem,
           "method": cell.method, "problem_id": spec.problem.id, "base_method": spec.method.id,
           "modifiers": MODIFIER_SEPARATOR.join(m.id for m in spec.method.modifiers),
           "method_kind": cell.method_kind,
           "family": family.label, "sweep": family.sweep, "sweep_value": family.value,
           "adaptive": family.adaptive, "h": cell.h,
           "t_end": np.nan if cell.t_end is None else cell.t_end,
           "steps_planned": cell.nsteps, "every": cell.every,
           "dt_out": np.nan if cell.dt_out is None else cell.dt_out,
           "section": getattr(cell, "section", None) or 0, "status": status, "reason": reason,
           "steps": None, "t_final": np.nan, "nfev": np.nan, "njev": np.nan, "samples": None,
           "integrals": "", "reference": _reference_text(cell),
           "metrics": join_metrics(cell.metrics), "metric_notes": notes,
           "swept": "/".join(getattr(cell, "sweep", ())),
           "setup_method": getattr(cell, "setup_method", cell.method),
           "final_global_error": np.nan, "max_global_error": np.nan}
    if traj is None:
        return row
    last = len(traj.t) - 1
    step = traj.steps[last] if last >= 0 else 0
    row.update(status=str(traj.status), reason=traj.reason,
               steps=int(step) if np.isfinite(step) else None,     # None: not reported
               t_final=float(traj.t[last]) if last >= 0 else np.nan,
               nfev=float(traj.nfev[last]) if last >= 0 else np.nan,
               njev=float(traj.njev[last]) if last >= 0 else np.nan, samples=len(traj.t),
               integrals="/".join(traj.integral_names),
               reference=traj.reference.describe["spec"] if traj.reference is not None else "")
    if metrics is not None:
        row.update(metrics.scalars)
    return row


def _reference_text(cell) -> str:
    """What a cell's global error is measured against, as its trajectory states it (the
    resolved reference's spec, ``exact`` for the default exact solution): the same text for a
    cell that has not run or failed as for one that ran, so that both are of one setup."""
    spec = getattr(cell, "spec", None)
    ref = getattr(spec, "reference", None) if spec is not None else None
    if ref is not None and hasattr(ref, "text"):
        return ref.text()
    return getattr(cell, "reference", None) or ""


def timing_row(cell, traj=None, status: str = "pending", walls: list[float] | None = None
               ) -> dict:
    """The timings row of one cell: ``wall_seconds`` the fastest of its ``repeats`` timed
    integrations, ``wall_median_seconds`` their median, ``wall_spread`` (max - min) / median
    (0 for one run)."""
    row = {"cell": cell.id, "problem": cell.problem, "method": cell.method, "status": status,
           "wall_seconds": np.nan, "compile_seconds": np.nan, "cache_misses": None,
           "repeats": 0, "wall_median_seconds": np.nan, "wall_spread": np.nan}
    if traj is not None:
        walls = np.asarray(walls if walls else [traj.wall_seconds], dtype=float)
        median = float(np.median(walls))
        row.update(status=str(traj.status), wall_seconds=float(walls.min()),
                   compile_seconds=traj.compile_seconds,
                   cache_misses=traj.provenance.get("numba_cache_misses"), repeats=len(walls),
                   wall_median_seconds=median,
                   wall_spread=float(np.ptp(walls) / median) if median > 0 else 0.0)
    return row


def samples_table(parts: list[tuple[object, dict, tuple[str, ...]]],
                  all_states: tuple[str, ...] = (), orbits: bool = False) -> pd.DataFrame:
    """The samples of an experiment, in cell order: fixed columns, states, err_*, global_error,
    then the other metric columns. ``parts`` are (cell, its sample columns, its problem's state
    names); ``all_states`` the states of every problem of the experiment, so that a partial table
    has the columns of problems not run yet; ``orbits``: the experiment has ensemble cells, whose
    kept orbits' samples carry their ``orbit`` (a nullable integer, empty for the other cells).

    States and integrals are the union over the cells, in order of first appearance; a column a
    cell's problem lacks is NaN in that cell's rows. The table is made once from the columns
    (one array per column, concatenated), never a DataFrame per cell.
    """
    import pandas as pd

    parts = sorted(parts, key=lambda p: p[0].id)
    sizes = [len(next(iter(cols.values()))) if cols else 0 for _, cols, _ in parts]
    states: list[str] = list(all_states)
    seen: dict[str, None] = {}
    for _, cols, names in parts:
        states += [s for s in names if s not in states]
        seen.update(dict.fromkeys(cols))
    front = list(SAMPLE_FRONT)
    if orbits:
        front.insert(1, "orbit")
    names = [c for c in seen if c not in front and c not in states]
    errors = [c for c in names if c.startswith("err_")]
    tail = ["global_error"] if "global_error" in names else []
    rest = [c for c in names if c not in errors and c not in tail]
    out: dict[str, object] = {
        "cell": np.repeat(np.array([c.id for c, _, _ in parts], dtype=np.int64), sizes),
        "problem": np.repeat(np.array([c.problem for c, _, _ in parts], dtype=object), sizes),
        "method": np.repeat(np.array([c.method for c, _, _ in parts], dtype=object), sizes)}
    if orbits:
        orbit = [cols.get("orbit") for _, cols, _ in parts]
        values = np.concatenate([np.full(n, -1, np.int64) if o is None else o.astype(np.int64)
                                 for o, n in zip(orbit, sizes)]) if parts else np.zeros(0, np.int64)
        out["orbit"] = pd.arrays.IntegerArray(values, values < 0)
    kinds = {"t": np.float64, "steps": np.int64, "nfev": np.float64}
    for c in front[1 + orbits + 2:] + states + errors + tail + rest:
        arrays = [cols[c] if c in cols else np.full(n, np.nan) for (_, cols, _), n
                  in zip(parts, sizes)]
        out[c] = np.concatenate(arrays) if arrays else np.zeros(0, kinds.get(c, np.float64))
    return missing_steps(pd.DataFrame(out, columns=front + states + errors + tail + rest))


#: the columns of cells.parquet before the per-cell metric values (suite/experiments/README.md)
CELL_COLUMNS = ("cell", "group", "label", "problem", "method", "problem_id", "base_method",
                "modifiers", "method_kind", "family", "sweep", "sweep_value", "adaptive", "h",
                "t_end", "steps_planned", "every", "dt_out", "section", "status", "reason", "steps",
                "t_final", "nfev", "njev", "samples", "integrals", "reference", "metrics",
                "metric_notes", "swept", "setup_method")


def cells_table(rows: list[dict]) -> pd.DataFrame:
    """One row per cell: the fixed columns, max_abs_err_<I>, the global errors, then the other
    per-cell metric values."""
    import pandas as pd

    if not rows:                         # a figure of fields only has no cells
        return pd.DataFrame({c: pd.Series(dtype="object") for c in CELL_COLUMNS})
    df = pd.DataFrame(sorted(rows, key=lambda r: r["cell"]))
    for col in ("steps", "samples", "orbits", "failed_orbits"):     # the last two: ensembles
        if col in df.columns:
            df[col] = df[col].astype("Int64")
    errs = [c for c in df.columns if c.startswith("max_abs_err_")]
    glob = ["final_global_error", "max_global_error"]
    extra = [c for c in df.columns if c not in CELL_COLUMNS and c not in errs and c not in glob]
    return df[list(CELL_COLUMNS) + errs + glob + extra]


def timings_table(rows: list[dict]) -> pd.DataFrame:
    import pandas as pd

    columns = ("cell", "problem", "method", "status", "wall_seconds", "compile_seconds",
               "cache_misses", "repeats", "wall_median_seconds", "wall_spread")
    df = pd.DataFrame(sorted(rows, key=lambda r: r["cell"]), columns=list(columns))
    df["cache_misses"] = df["cache_misses"].astype("Int64")
    df["repeats"] = df["repeats"].fillna(0).astype("int64")
    return df
