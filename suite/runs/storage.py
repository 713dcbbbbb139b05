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


def write_parquet(df, path: Path, meta: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(df, preserve_index=False)
    md = dict(table.schema.metadata or {})
    md[b"gnibench"] = json.dumps(meta, default=str).encode()
    table = table.replace_schema_metadata(md)
    atomic_write(path, lambda p: pq.write_table(table, p))


def read_parquet(path, columns=None):
    """A Parquet table of a results directory as a DataFrame, read from a regular file only (a
    FIFO in its place raises at once instead of blocking: :mod:`~gnibench.suite.foundation.files`)."""
    import pandas as pd
    from gnibench.suite.foundation.files import open_regular_file

    with open_regular_file(path) as f:
        return pd.read_parquet(f, columns=columns)


def read_parquet_meta(path) -> dict:
    """gnibench's metadata of a Parquet file (a path, regular files only, or a pyarrow buffer)."""
    import pyarrow.parquet as pq
    from gnibench.suite.foundation.files import open_regular_file

    if isinstance(path, (str, Path)):
        with open_regular_file(path) as f:
            md = pq.read_schema(f).metadata or {}
    else:
        md = pq.read_schema(path).metadata or {}
    return json.loads(md.get(b"gnibench", b"{}"))
