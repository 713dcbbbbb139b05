"""The table of one cell written as it is produced: csv, json and Parquet in chunks of rows.

``gnibench solve`` used to build the whole text of its output in memory: 5·10^6 rows peaked at
10.5 GB for 480 MB of values (csv ~2.2 KB of Python strings per row, json ~1.5 KB, Parquet a
second copy of the table). The writers here take the columns (name -> 1-D array, as
:func:`gnibench.suite.runs.tables.sample_columns` gives them: views of the trajectory, no copy)
and write :data:`CHUNK` rows at a time, so that what they add to the values is bounded whatever
the number of rows: csv and json as text chunks (the same text as before, byte for byte:
tests/cell/test_solve_output.py), Parquet through pyarrow's ``ParquetWriter``, one row group per
chunk. A file is written to a temporary file and renamed into place
(:func:`gnibench.suite.foundation.cache.atomic_write`); a reader of stdout that stops reading
(``| head``) stops the writing.
"""
from __future__ import annotations

import json
from pathlib import Path

from gnibench.suite.foundation.cache import atomic_write

CHUNK = 1 << 15             # rows formatted at a time (~10 MB of text for 15 columns)


def write_table(columns: dict, meta: dict, fmt: str, out: Path | None, stdout) -> None:
    """Write one cell's table (``columns``) with its metadata: csv (header, then rows), json
    (``{"meta": ..., "columns": {name: [values]}}``, missing values null) or parquet (metadata in
    the schema under ``gnibench``), to the file ``out`` (atomically) or ``stdout``."""
    if fmt == "parquet":
        atomic_write(out, lambda p: _parquet(columns, meta, p))
        return
    writer = _csv if fmt == "csv" else _json
    if out is None:
        writer(columns, meta, stdout.write, lambda: getattr(stdout, "closed_by_reader", False))
        return

    def to_file(path):
        with open(path, "w", encoding="utf-8") as f:
            writer(columns, meta, f.write, lambda: False)

    atomic_write(out, to_file)


def _rows(columns: dict) -> int:
    return len(next(iter(columns.values()))) if columns else 0


def _chunks(columns: dict):
    """(start, stop) of the chunks of rows; one empty chunk for an empty table."""
    n = _rows(columns)
    return [(i, min(i + CHUNK, n)) for i in range(0, n, CHUNK)] or [(0, 0)]


def _slice(columns: dict, start: int, stop: int) -> dict:
    return {name: values[start:stop] for name, values in columns.items()}


def _csv(columns: dict, meta: dict, write, gone) -> None:
    from gnibench.suite.runs.storage import _csv_text, _plain

    plain = _plain(columns)
    for k, (start, stop) in enumerate(_chunks(columns)):
        if gone():
            return
        part = _slice(columns, start, stop)
        if plain:
            text = _csv_text(part)
            write(text if k == 0 else text.partition("\n")[2])     # the header once
        else:                               # text columns, booleans, odd names: pandas' csv
            from gnibench.suite.runs.tables import frame_of

            write(frame_of(part).to_csv(index=False, header=k == 0))


def _json(columns: dict, meta: dict, write, gone) -> None:
    write('{"meta": ' + json.dumps(meta, default=str) + ', "columns": {')
    for j, (name, values) in enumerate(columns.items()):
        write((", " if j else "") + json.dumps(name) + ": [")
        first = True
        for start, stop in _chunks(columns):
            if gone():
                return
            numbers = _numbers(values[start:stop])
            if numbers:
                write(("" if first else ", ") + json.dumps(numbers)[1:-1])
                first = False
        write("]")
    write("}}\n")


def _numbers(values) -> list:
    """Values as JSON numbers: floats, None for a missing one (NaN, inf, a missing count)."""
    import math

    import numpy as np

    a = np.asarray(values)
    if a.dtype.kind in "fiub":
        floats = a.astype(float).tolist()
    else:                                   # objects: as pandas converts them
        import pandas as pd

        floats = pd.Series(values).to_numpy(dtype=float, na_value=math.nan).tolist()
    return [x if math.isfinite(x) else None for x in floats]


def _parquet(columns: dict, meta: dict, path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq
    from gnibench.suite.runs.tables import frame_of

    writer, schema = None, None
    try:
        for start, stop in _chunks(columns):
            frame = frame_of(_slice(columns, start, stop))
            if writer is None:
                table = pa.Table.from_pandas(frame, preserve_index=False)
                md = {**(table.schema.metadata or {}),
                      b"gnibench": json.dumps(meta, default=str).encode()}
                schema = table.schema.with_metadata(md)
                writer = pq.ParquetWriter(path, schema)
            else:
                table = pa.Table.from_pandas(frame, preserve_index=False, schema=schema)
            writer.write_table(table.replace_schema_metadata(schema.metadata))
    finally:
        if writer is not None:
            writer.close()
