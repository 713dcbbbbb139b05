"""Metrics across cells, and the families of cells they and the reports share.

A family metric (``Metric.scope == "family"``, e.g. ``order``) is chosen like any metric, in an
experiment's ``metrics`` list; the cells that chose it carry its text in the ``metrics`` column of
``cells.parquet``. Once the cells are run, :func:`family_columns` groups them into families and
writes the metric's columns into every cell of each family, with the family id
(``<metric id>_family``: the smallest cell id of the family).

A **family** is the cells of one setup (:func:`setup_key`): the same canonical problem (with its
options), the same method but for the options its group sweeps (column ``setup_method``:
modifiers and every option not swept included, e.g. ``atol`` when only ``rtol`` is swept), the
same final time (``t_end``, or steps x h for a horizon in steps; to 12 significant digits), the
same output grid (``every``, ``dt_out``, ``section``) and the same reference. A curve of a
work-precision diagram, a row of a league table and an order fit hold the cells of one family
only: the reports group by :func:`setups` too, so the ``order`` metric and the report agree. A
family metric's family is also limited to the cells that chose it with the same options.

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


def method_options(method: str) -> dict[str, str]:
    """The options of a canonical method spec, ``name=value`` of the base and
    ``modifier.name=value`` of each modifier, with the base and modifier ids as keys of value ""
    (the spec module's parser: the names a family's cells differ by, for the reports)."""
    parsed = structure(str(method))
    out: dict[str, str] = {parsed.base.id: ""}
    out.update(parsed.base.given)
    for mod in parsed.modifiers:
        out["+" + mod.id] = ""
        out.update({f"{mod.id}.{k}": v for k, v in mod.given.items()})
    return out


def final_time(row: pd.Series) -> str:
    """The planned final time, to 12 significant digits (t_end, or steps x h)."""
    import pandas as pd

    t = row["t_end"] if pd.notna(row["t_end"]) else row["steps_planned"] * row["h"]
    return f"{float(t):.12g}"


def _text(value) -> str:
    """A number of the setup as text (12 significant digits; "" for none)."""
    import pandas as pd

    if value is None or (not isinstance(value, str) and pd.isna(value)):
        return ""
    return f"{float(value):.12g}" if not isinstance(value, str) else value


#: the parts of a setup, in the order of :func:`setup_key`
SETUP = ("problem", "method", "horizon", "every", "dt_out", "section", "reference")


def setup_key(row) -> tuple[str, ...]:
    """What the cells of a family share (see the module docstring), as texts in the order of
    :data:`SETUP`; ``row`` is a row of cells.parquet (a mapping). Tables without
    ``setup_method`` (written before it) fall back to the method without ``h``."""
    method = row.get("setup_method")
    if method is None or not isinstance(method, str) or not method:
        method = method_without_step(row["method"])
    return (str(row["problem"]), method, final_time(row), _text(row.get("every")),
            _text(row.get("dt_out")), _text(row.get("section") or None),
            str(row.get("reference") or ""))


def family_key(row) -> tuple[str, ...]:
    """The family of a cell: its setup (:func:`setup_key`)."""
    return setup_key(row)


def setups(cells) -> pd.Series:
    """The family of each cell: the smallest cell id of its setup (index: the cells' index)."""
    import pandas as pd

    keys = [setup_key(r) for r in cells.to_dict("records")]
    first: dict[tuple, int] = {}
    for k, c in zip(keys, cells["cell"]):
        first[k] = min(first.get(k, int(c)), int(c))
    return pd.Series([first[k] for k in keys], index=cells.index, dtype="int64")


def family_columns(cells: pd.DataFrame, samples: pd.DataFrame) -> pd.DataFrame:
    """``cells`` with the columns of every family metric its cells chose (see the module
    docstring); unchanged when no cell chose one."""
    import pandas as pd
    from gnibench.suite.metrics.compute import parse_metric

    if "metrics" not in cells.columns:
        return cells
    groups: dict[tuple, list[int]] = {}
    choices = {}
    chose = cells[cells["metrics"].fillna("").astype(str) != ""]   # no row of the others is read
    for i, row in zip(chose.index, chose.to_dict("records")):
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
