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


def write_result(traj, metrics, fmt: str, out: Path | None, stdout) -> None:
    """Write one cell's table (samples or section crossings) in csv, json or parquet, to a file
    or stdout; ``metrics`` is its MetricOutput (per-sample columns, per-cell values in meta)."""
    from gnibench.suite.runs.tables import sample_frame

    write_frame(sample_frame(traj, metrics), provenance(traj, metrics), fmt, out, stdout)


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
