"""The table of one cell written as csv, json or Parquet, streamed in blocks of rows.

``gnibench solve`` writes its table (:func:`gnibench.suite.runs.tables.sample_columns`: name -> 1-D
array, or a column spooled on disk and read by slices, :class:`gnibench.suite.runs.spool.
SpooledColumn`) through :func:`write_columns`. The text of a block of :data:`BLOCK` rows is made, written
and dropped before the next, so the writer's own memory does not grow with the number of rows (a
table of 5·10^6 rows took 10.5 GB when its whole csv text was made at once); Parquet is written by
row groups of :data:`BLOCK` rows (``pyarrow.parquet.ParquetWriter``). The text is the one pandas
writes (``DataFrame.to_csv(index=False)``; json: ``{"meta": ..., "columns": {name: [...]}}`` as
``json.dumps`` writes it) whatever the block size (tests/cell/test_solve_output.py).

A file named with ``-o`` is written to a temporary file and renamed into place
(:func:`gnibench.suite.foundation.cache.atomic_write`): a failure leaves nothing half-written.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from gnibench.suite.foundation.cache import atomic_write

#: rows per block of text or Parquet row group
BLOCK = 1 << 16


def write_columns(columns: dict, meta: dict, fmt: str, out: Path | None, stdout,
                  block: int = BLOCK) -> None:
    """Write one cell's table (``columns``) with its provenance ``meta`` in ``fmt`` (csv, json,
    parquet) to the file ``out`` (atomically) or, for csv and json, to ``stdout``."""
    if fmt == "parquet":
        atomic_write(out, lambda p: _parquet(columns, meta, p, block))
        return
    write = _csv if fmt == "csv" else _json
    if out is None:
        write(columns, meta, stdout, block)
    else:
        def to_file(p):
            with open(p, "w", encoding="utf-8", newline="") as f:
                write(columns, meta, f, block)

        atomic_write(out, to_file)


def _length(columns: dict) -> int:
    return len(next(iter(columns.values()))) if columns else 0


def _blocks(columns: dict, block: int):
    n = _length(columns)
    for start in range(0, max(n, 1), block):
        yield {c: v[start:start + block] for c, v in columns.items()}, start == 0


def _csv(columns: dict, meta: dict, f, block: int) -> None:
    for part, first in _blocks(columns, block):
        if _plain(part):                # the same text either way, the plain one faster
            f.write(_csv_text(part, header=first))
        else:
            from gnibench.suite.runs.tables import frame_of

            frame_of(part).to_csv(f, index=False, header=first)


def _json(columns: dict, meta: dict, f, block: int) -> None:
    """``json.dumps({"meta": meta, "columns": {name: values}})`` written column by column and
    block by block (numbers as floats, None for NaN, inf and missing values)."""
    f.write('{"meta": ' + json.dumps(meta, default=str) + ', "columns": {')
    for k, (name, values) in enumerate(columns.items()):
        f.write((", " if k else "") + json.dumps(name) + ": [")
        n = len(values)
        for start in range(0, n, block):
            numbers = _numbers(values[start:start + block])
            f.write((", " if start else "") + json.dumps(numbers)[1:-1])
        f.write("]")
    f.write("}}\n")


def _numbers(values) -> list:
    """Floats for JSON, None where a value is missing (NaN, inf, pandas' NA of a nullable
    integer such as the ``steps`` a Python solver did not report)."""
    import pandas as pd

    if isinstance(values, np.ndarray) and values.dtype.kind in "fiub":
        floats = values.astype(float).tolist()
    else:
        floats = pd.Series(values).to_numpy(dtype=float, na_value=math.nan).tolist()
    return [x if math.isfinite(x) else None for x in floats]


def _parquet(columns: dict, meta: dict, path, block: int) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq
    from gnibench.suite.runs.tables import frame_of

    writer = None
    try:
        for part, first in _blocks(columns, block):
            table = pa.Table.from_pandas(frame_of(part), preserve_index=False)
            if first:
                md = dict(table.schema.metadata or {})
                md[b"gnibench"] = json.dumps(meta, default=str).encode()
                schema = table.schema.with_metadata(md)
                writer = pq.ParquetWriter(path, schema)
            writer.write_table(table.cast(schema), row_group_size=block)
    finally:
        if writer is not None:
            writer.close()


def _plain(columns: dict) -> bool:
    """Columns that :func:`_csv_text` writes as pandas does: at least two (a lone empty field is
    quoted by csv), names without a separator, quote or line break, numeric 1-D arrays of one
    length, ``steps`` (a nullable integer in the DataFrame, :func:`~gnibench.suite.runs.tables.
    missing_steps`) whole numbers where not NaN."""
    arrays = list(columns.values())
    if len(arrays) < 2 or any(not isinstance(a, np.ndarray) or a.ndim != 1
                              or a.dtype.kind not in "fiu" or len(a) != len(arrays[0])
                              for a in arrays):
        return False
    if any(not isinstance(c, str) or set(c) & set(',"\r\n') or c.strip() != c for c in columns):
        return False
    steps = columns.get("steps")
    if steps is not None and steps.dtype.kind == "f":
        finite = steps[~np.isnan(steps)]
        return bool(np.all(np.isfinite(finite)) and np.all(finite == np.round(finite)))
    return True


def _csv_text(columns: dict, header: bool = True) -> str:
    """The csv ``DataFrame.to_csv(index=False)`` writes for :func:`_plain` columns: floats as
    their shortest repr (numpy's ``astype(str)``, which pandas uses too), NaN empty, integers
    and the whole-number ``steps`` as integers."""
    fields = []
    for name, a in columns.items():
        if a.dtype.kind == "f" and name == "steps":
            text = np.where(np.isnan(a), "", np.nan_to_num(a).astype(np.int64).astype(str))
        elif a.dtype.kind == "f":
            text = np.where(np.isnan(a), "", a.astype(str))
        else:
            text = a.astype(str)
        fields.append(text.tolist())
    lines = ([",".join(columns)] if header else []) + [",".join(row) for row in zip(*fields)]
    return "\n".join(lines) + "\n" if lines else ""
