"""Writing results: csv, json and Parquet (with provenance in the Parquet schema metadata).

Every write goes to a temporary file first and is renamed into place, so a failure never leaves a
half-written file.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from gnibench.suite.foundation.cache import atomic_write


def trajectory_frame(result):
    """The public table of one cell: t, states, err_<integral>, global_error, steps, nfev."""
    import pandas as pd

    cols = {"t": result.t}
    for i, name in enumerate(result.state_names):
        cols[name] = result.y[:, i]
    for k, name in enumerate(result.integral_names):
        cols[f"err_{name}"] = result.invariant_errors[:, k]
    if result.global_error is not None:
        cols["global_error"] = result.global_error
    cols["steps"] = result.steps
    cols["nfev"] = result.nfev
    return pd.DataFrame(cols)


def provenance(result) -> dict:
    return {"problem": result.problem, "method": result.method, "status": result.status,
            "reason": result.reason, "wall_seconds": result.wall_seconds,
            "compile_seconds": result.compile_seconds, "numba_cache_misses": result.cache_misses,
            "h": result.h, "y0": list(result.y0), "njev": float(result.njev[-1]),
            **result.meta}


def _clean(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


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


def write_result(result, fmt: str, out: Path | None, stdout) -> None:
    """Write one cell's trajectory in csv, json or parquet, to a file or stdout."""
    write_frame(trajectory_frame(result), provenance(result), fmt, out, stdout)


def write_frame(df, meta: dict, fmt: str, out: Path | None, stdout) -> None:
    """Write a table with its provenance: csv, json ({"meta", "columns"}) or parquet (schema
    metadata), to a file (atomically) or stdout."""
    if fmt == "csv":
        if out is None:
            df.to_csv(stdout, index=False)
        else:
            atomic_write(out, lambda p: df.to_csv(p, index=False))
    elif fmt == "json":
        doc = {"meta": meta, "columns": {c: [_clean(float(v)) for v in df[c]] for c in df.columns}}
        text = json.dumps(doc, default=str)
        if out is None:
            stdout.write(text + "\n")
        else:
            atomic_write(out, lambda p: Path(p).write_text(text + "\n"))
    else:
        write_parquet(df, out, meta)


def write_sections(result, fmt: str, out, stdout=None) -> None:
    """Write the section points in csv, json or parquet (provenance as in gnibench.suite.runs.storage)."""
    meta = {"problem": result.problem, "method": result.method, "status": result.status,
            "reason": result.reason, **result.meta}
    write_frame(result.frame(), meta, fmt, out, stdout)
