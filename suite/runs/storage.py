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


#: the tables one write of the runner makes together (runner.py ``flush``), and the keys of their
#: gnibench metadata that differ between them
TABLE_SET = ("samples", "cells", "timings")
PER_TABLE = ("table", "written_at")


def check_table_set(out: Path) -> None:
    """Refuse, in one line, the tables of a results directory that come from two writes of the
    runner (a run killed between writing two of them leaves, say, samples.parquet of its last
    write beside cells.parquet of the one before): their metadata, but for each table's name and
    time, is the same when they belong together (the cells done, the experiment's text, the
    versions)."""
    from gnibench.suite.foundation.errors import UserError

    metas = {}
    for name in TABLE_SET:
        path = Path(out) / f"{name}.parquet"
        try:
            meta = read_parquet_meta(path)
        except UserError:
            raise
        except Exception as e:  # noqa: BLE001 - pyarrow raises many kinds; all mean the same
            why = " ".join(str(e).split())[:160] or type(e).__name__
            raise UserError(f"cannot read {path} ({why}); it is damaged or not a gnibench "
                            f"table: run the command that wrote it again") from None
        metas[name] = {k: v for k, v in meta.items() if k not in PER_TABLE}
    first, ref = next(iter(metas.items()))
    for name, meta in metas.items():
        if meta != ref:
            what = ", ".join(f"{n}.parquet {m.get('cells_done', '?')} of {m.get('cells_total', '?')}"
                             for n, m in metas.items())
            raise UserError(f"the tables of {out} come from two writes of a run (cells done: "
                            f"{what}); it was stopped while writing them: run the command that "
                            f"wrote them again")
