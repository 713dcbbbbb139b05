"""Metrics across cells: families of cells that differ only in the step size h.

A family metric (``Metric.scope == "family"``, e.g. ``order``) is chosen like any metric, in an
experiment's ``metrics`` list; the cells that chose it carry its text in the ``metrics`` column of
``cells.parquet``. Once the cells are run, :func:`family_columns` groups them into families and
writes the metric's columns into every cell of each family, with the family id
(``<metric id>_family``: the smallest cell id of the family).

A family is the cells that chose the same metric with the same options and are equal in
everything but h: the same canonical problem, the same method apart from its base option ``h``
(modifiers included), and the same final time (``t_end``, or steps x h for a horizon in steps; to
12 significant digits). Sampling (``every``) may differ.

:func:`family_columns` is a pure function of the cells and samples tables (as the runner writes
them), so it does not care where or in which order the cells ran. A family with a cell still
``pending`` gets no values yet (they appear once the family is complete); a cell in ``error``
counts as a failed run.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from gnibench.suite.cell.spec import structure

if TYPE_CHECKING:
    import pandas as pd

SEPARATOR = ";"          # between the metric texts of a cell (the texts contain commas)


def join_metrics(texts) -> str:
    """The ``metrics`` column of a cell: its chosen metric texts."""
    return SEPARATOR.join(texts)


def split_metrics(text) -> list[str]:
    return [t for t in str(text or "").split(SEPARATOR) if t]


def method_without_step(method: str) -> str:
    """The canonical method text without the base option h (modifiers kept)."""
    return structure(method).without("h").text()


def final_time(row: pd.Series) -> str:
    """The planned final time, to 12 significant digits (t_end, or steps x h)."""
    import pandas as pd

    t = row["t_end"] if pd.notna(row["t_end"]) else row["steps_planned"] * row["h"]
    return f"{float(t):.12g}"


def family_key(row: pd.Series) -> tuple[str, str, str]:
    """What the cells of a family share: problem, method without h, final time."""
    return row["problem"], method_without_step(row["method"]), final_time(row)


def family_columns(cells: pd.DataFrame, samples: pd.DataFrame) -> pd.DataFrame:
    """``cells`` with the columns of every family metric its cells chose (see the module
    docstring); unchanged when no cell chose one."""
    import pandas as pd
    from gnibench.suite.metrics.compute import parse_metric

    if "metrics" not in cells.columns:
        return cells
    groups: dict[tuple, list[int]] = {}
    choices = {}
    chose = cells["metrics"].fillna("").astype(str) != ""      # no row of the others is read
    for i, row in cells[chose].iterrows():
        for text in split_metrics(row["metrics"]):
            choice = parse_metric(text)
            if choice.metric.scope != "family":
                continue
            choices[choice.text()] = choice
            groups.setdefault((choice.text(), family_key(row)), []).append(i)
    if not groups:
        return cells
    parts = []
    for (text, _), index in groups.items():
        family = cells.loc[index]
        if (family["status"] == "pending").any():
            continue
        choice = choices[text]
        ids = family["cell"].to_numpy()
        result = choice.metric.compute(family, samples[samples["cell"].isin(ids)], choice.values)
        result.insert(0, f"{choice.metric.id}_family", np.int64(ids.min()))
        parts.append(result)
    if not parts:
        return cells
    # one row per cell; a cell in two families (two family metrics) has its columns in both
    extra = pd.concat(parts).groupby(level=0).first()
    out = cells.merge(extra, how="left", left_on="cell", right_index=True)
    for col in extra.columns:          # integers and flags stay so beside the missing values
        if pd.api.types.is_bool_dtype(extra[col]):
            out[col] = out[col].astype("boolean")
        elif pd.api.types.is_integer_dtype(extra[col]):
            out[col] = out[col].astype("Int64")
    return out
