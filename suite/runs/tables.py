"""The three tables of an experiment run, built from cells and their results.

``samples`` (one row per cell and sample), ``cells`` (one row per cell) and ``timings`` (one row per
cell). Only ``timings`` holds wall-clock numbers, so ``samples`` and ``cells`` are bit-identical
between two runs of the same experiment on the same machine. The column contract is in
``suite/experiments/README.md``.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from gnibench.suite.runs.storage import trajectory_frame

SAMPLE_FRONT = ("cell", "problem", "method", "t", "steps", "nfev")
STATUSES = ("ok", "nonfinite", "newton_failed", "error", "pending")


def cell_samples(cell, result) -> pd.DataFrame:
    """The samples of one cell: its ``gnibench solve`` table plus the cell id and specs."""
    df = trajectory_frame(result)
    clash = set(result.state_names) & set(SAMPLE_FRONT + ("global_error",))
    if clash:
        raise ValueError(f"state names {sorted(clash)} clash with the fixed sample columns")
    df.insert(0, "cell", np.int64(cell.id))
    df.insert(1, "problem", cell.problem)
    df.insert(2, "method", cell.method)
    return df


def _max_abs(values: np.ndarray) -> float:
    """max |x|, where NaN counts as infinite (a diverged cell must not look accurate)."""
    a = np.abs(values)
    return float(np.max(np.where(np.isnan(a), np.inf, a))) if a.size else float("nan")


def cell_row(cell, result=None, status: str = "pending", reason: str = "") -> dict:
    """The summary row of one cell; without a result, the row of a cell that did not finish."""
    row = {"cell": cell.id, "group": cell.group, "label": cell.label, "problem": cell.problem,
           "method": cell.method, "h": cell.h,
           "t_end": np.nan if cell.t_end is None else cell.t_end,
           "steps_planned": cell.nsteps, "every": cell.every, "status": status, "reason": reason,
           "steps": None, "t_final": np.nan, "nfev": np.nan, "njev": np.nan, "samples": None,
           "integrals": "", "final_global_error": np.nan, "max_global_error": np.nan}
    if result is None:
        return row
    row.update(status=result.status, reason=result.reason, steps=int(result.steps[-1]),
               t_final=float(result.t[-1]), nfev=float(result.nfev[-1]),
               njev=float(result.njev[-1]), samples=len(result.t),
               integrals="/".join(result.integral_names))
    for k, name in enumerate(result.integral_names):
        row[f"max_abs_err_{name}"] = _max_abs(result.invariant_errors[:, k])
    if result.global_error is not None:
        g = result.global_error
        row["final_global_error"] = float(g[-1])
        row["max_global_error"] = _max_abs(g)
    return row


def timing_row(cell, result=None, status: str = "pending") -> dict:
    row = {"cell": cell.id, "problem": cell.problem, "method": cell.method, "status": status,
           "wall_seconds": np.nan, "compile_seconds": np.nan, "cache_misses": None}
    if result is not None:
        row.update(status=result.status, wall_seconds=result.wall_seconds,
                   compile_seconds=result.compile_seconds, cache_misses=result.cache_misses)
    return row


def samples_table(frames: list[pd.DataFrame]) -> pd.DataFrame:
    """Concatenate cell samples in cell order: fixed columns, states, err_*, global_error.

    States and integrals are the union over the cells, in order of first appearance; a column a
    cell's problem lacks is NaN in that cell's rows.
    """
    frames = sorted(frames, key=lambda f: int(f["cell"].iloc[0]) if len(f) else -1)
    if not frames:
        return pd.DataFrame({c: pd.Series(dtype=t) for c, t in zip(
            SAMPLE_FRONT, ("int64", "object", "object", "float64", "int64", "float64"))})
    df = pd.concat(frames, ignore_index=True)
    rest = [c for c in df.columns if c not in SAMPLE_FRONT and c != "global_error"]
    states = [c for c in rest if not c.startswith("err_")]
    errors = [c for c in rest if c.startswith("err_")]
    tail = ["global_error"] if "global_error" in df.columns else []
    return df[list(SAMPLE_FRONT) + states + errors + tail]


def cells_table(rows: list[dict]) -> pd.DataFrame:
    df = pd.DataFrame(sorted(rows, key=lambda r: r["cell"]))
    for col in ("steps", "samples"):
        df[col] = df[col].astype("Int64")
    errs = [c for c in df.columns if c.startswith("max_abs_err_")]
    front = [c for c in df.columns if not c.startswith("max_abs_err_")
             and c not in ("final_global_error", "max_global_error")]
    return df[front + errs + ["final_global_error", "max_global_error"]]


def timings_table(rows: list[dict]) -> pd.DataFrame:
    df = pd.DataFrame(sorted(rows, key=lambda r: r["cell"]))
    df["cache_misses"] = df["cache_misses"].astype("Int64")
    return df
