"""Writing results: csv, json and Parquet (with provenance in the Parquet schema metadata).

Every write goes to a temporary file first and is renamed into place, so a failure never leaves a
half-written file.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from gnibench.suite.foundation.cache import atomic_write


def provenance(traj, metrics=None) -> dict:
    """The metadata written with one cell's table: specs, status, cost, provenance, and the
    per-cell metric values (``metrics``: a MetricOutput, or None)."""
    meta = {"problem": traj.problem, "method": traj.method, "kind": traj.kind,
            "status": str(traj.status), "reason": traj.reason,
            "njev": float(traj.njev[-1]) if len(traj.njev) else 0.0, **traj.provenance}
    if traj.reference is not None:
        meta["reference"] = traj.reference.describe
    else:
        meta.setdefault("reference", {"backend": None})
    if metrics is not None:
        meta["metrics"] = {k: _clean(v) for k, v in metrics.scalars.items()}
    return meta


def _clean(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if hasattr(x, "item"):                    # numpy scalars
        return _clean(x.item())
    return x


def _numbers(column) -> list:
    """A table column for JSON: floats, None for a missing value (NaN, inf, or pandas' NA of a
    nullable integer column such as the ``steps`` a Python solver did not report)."""
    values = column.to_numpy(dtype=float, na_value=math.nan).tolist()
    return [x if math.isfinite(x) else None for x in values]


def write_parquet(df, path: Path, meta: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(df, preserve_index=False)
    md = dict(table.schema.metadata or {})
    md[b"gnibench"] = json.dumps(meta, default=str).encode()
    table = table.replace_schema_metadata(md)
    atomic_write(path, lambda p: pq.write_table(table, p))


def read_parquet_meta(path: Path) -> dict:
    import pyarrow.parquet as pq

    md = pq.read_schema(path).metadata or {}
    return json.loads(md.get(b"gnibench", b"{}"))


def write_columns(columns: dict, meta: dict, fmt: str, out: Path | None, stdout) -> None:
    """:func:`write_frame` of the table of one cell given as its columns (name -> 1-D array,
    :func:`gnibench.suite.runs.tables.sample_columns`): csv and json are written from the arrays,
    the same text as pandas writes, without importing pandas (0.27 s of the 0.7 s of a small
    ``gnibench solve``); Parquet, and columns this does not cover (text, booleans, names that
    csv would quote), go through the DataFrame."""
    import numpy as np

    if fmt == "parquet" or not _plain(columns):
        from gnibench.suite.runs.tables import frame_of

        write_frame(frame_of(columns), meta, fmt, out, stdout)
        return
    if fmt == "csv":
        text = _csv_text(columns)
    else:
        numbers = {c: [x if math.isfinite(x) else None
                       for x in np.asarray(v, dtype=float).tolist()] for c, v in columns.items()}
        text = json.dumps({"meta": meta, "columns": numbers}, default=str) + "\n"
    if out is None:
        stdout.write(text)
    else:
        atomic_write(out, lambda p: Path(p).write_text(text))


def _plain(columns: dict) -> bool:
    """Columns that :func:`_csv_text` writes as pandas does: at least two (a lone empty field is
    quoted by csv), names without a separator, quote or line break, numeric 1-D arrays of one
    length, ``steps`` (a nullable integer in the DataFrame, :func:`~gnibench.suite.runs.tables.
    missing_steps`) whole numbers where not NaN."""
    import numpy as np

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


def _csv_text(columns: dict) -> str:
    """The csv ``DataFrame.to_csv(index=False)`` writes for :func:`_plain` columns: floats as
    their shortest repr (numpy's ``astype(str)``, which pandas uses too), NaN empty, integers
    and the whole-number ``steps`` as integers."""
    import numpy as np

    fields = []
    for name, a in columns.items():
        if a.dtype.kind == "f" and name == "steps":
            text = np.where(np.isnan(a), "", np.nan_to_num(a).astype(np.int64).astype(str))
        elif a.dtype.kind == "f":
            text = np.where(np.isnan(a), "", a.astype(str))
        else:
            text = a.astype(str)
        fields.append(text.tolist())
    lines = [",".join(columns)] + [",".join(row) for row in zip(*fields)]
    return "\n".join(lines) + "\n"


def write_frame(df, meta: dict, fmt: str, out: Path | None, stdout) -> None:
    """Write a table with its provenance: csv, json ({"meta", "columns"}) or parquet (schema
    metadata), to a file (atomically) or stdout."""
    if fmt == "csv":
        if out is None:
            df.to_csv(stdout, index=False)
        else:
            atomic_write(out, lambda p: df.to_csv(p, index=False))
    elif fmt == "json":
        doc = {"meta": meta, "columns": {c: _numbers(df[c]) for c in df.columns}}
        text = json.dumps(doc, default=str)
        if out is None:
            stdout.write(text + "\n")
        else:
            atomic_write(out, lambda p: Path(p).write_text(text + "\n"))
    else:
        write_parquet(df, out, meta)
