"""The resumable store of a results directory: one committed part per finished cell.

Layout of ``<out>/``::

    .lock                      held (flock) by the run using the directory
    parts/<key>.parquet        one finished cell: its samples, with its cells row and timings row
                               in the schema metadata; written to a temporary file and renamed,
                               so a part exists whole or not at all
    samples.parquet, cells.parquet, timings.parquet
                               consolidated from the parts, in cell order (rewritten as cells
                               finish and at the end)

The key of a part is a content hash of everything that determines its numbers: the canonical cell
(problem and method specs, horizon, sampling, metrics, reference solution; the text of a user
definition, :mod:`gnibench.suite.cell.user`), the source code that computes it
(problems, methods and their kernels, the cell layer, the metrics and the tables: a fingerprint of
those files) and the package versions. Running the same experiment again reuses every part whose
key matches and computes only the missing cells; a cell whose spec or code changed gets a new key
and is recomputed, never reused stale. Parts are verified when read: a part that cannot be read, or
whose content does not match the checksum it carries (:func:`content_checksum`, in its metadata),
is discarded with one warning line and recomputed.
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Self

from gnibench.suite.foundation.cache import discard, warn
from gnibench.suite.foundation.errors import UserError, named
from gnibench.suite.foundation.provenance import versions

#: what the numbers of a cell depend on (folders and files of the package, relative to its root)
CODE = ("problems", "methods", "suite/foundation", "suite/cell", "suite/metrics",
        "suite/runs/tables.py")
PART_FORMAT = 2             # 2: a checksum of the content in the metadata


def package_root() -> Path:
    """The folder of the package ``gnibench`` (this file is ``suite/runs/store.py`` in it)."""
    return Path(__file__).resolve().parents[2]


_fingerprint: str | None = None


def code_fingerprint() -> str:
    """sha256 over the source files that compute a cell's numbers (see :data:`CODE`)."""
    global _fingerprint
    if _fingerprint is None:
        root = package_root()
        h = hashlib.sha256()
        for entry in CODE:
            path = root / entry
            files = sorted(path.rglob("*.py")) if path.is_dir() else [path]
            for f in files:
                h.update(str(f.relative_to(root)).encode())
                h.update(f.read_bytes())
        _fingerprint = h.hexdigest()
    return _fingerprint


def cell_key(cell) -> str:
    """The content hash of one cell (see the module docstring)."""
    v = versions()
    v.pop("platform", None)
    doc = {"format": PART_FORMAT, "problem": cell.problem, "method": cell.method,
           "steps": cell.steps, "t_end": cell.t_end, "every": cell.every,
           "dt_out": getattr(cell, "dt_out", None), "metrics": list(cell.metrics),
           "code": code_fingerprint(), "versions": v}
    if getattr(cell, "reference", None) is not None:     # what global_error is measured against
        doc["reference"] = cell.reference
    if getattr(cell, "section", None) is not None:       # crossings instead of samples
        doc["section"] = cell.section
    if getattr(cell, "repeat", 1) > 1:                   # timed N times: another timings row
        doc["repeat"] = cell.repeat
    spec = getattr(cell, "spec", None)
    defs = [] if spec is None else [r.definition for r in (spec.problem.record,
                                                            spec.method.base.record) if r.definition]
    if defs:                               # user definitions: their text (and Python code's hash)
        doc["definitions"] = hashlib.sha256("\n".join(defs).encode()).hexdigest()
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()).hexdigest()[:32]


@dataclass
class Part:
    """A finished cell as stored: its samples (or None), its cells row and timings row."""

    samples: object
    row: dict
    timing: dict
    state_names: tuple[str, ...]


class Store:
    """A results directory opened by one run (see the module docstring)."""

    def __init__(self, out: Path):
        self.out = Path(out)
        self.parts = self.out / "parts"
        self._lock = None
        self._memo: dict[str, Part] = {}      # parts this run has read (each read once)

    # -- the lock ---------------------------------------------------------------------------------

    def open(self) -> Self:
        """Create the directory, take the lock (a one-line UserError if another run holds it; a
        lock whose owner is gone is taken over, :mod:`gnibench.suite.runs.lock`) and remove the
        temporary files of killed runs."""
        from gnibench.suite.runs.lock import DirectoryLock

        self.make_output_dir(self.out)
        try:
            self.parts.mkdir(exist_ok=True)
        except FileExistsError:                # parts is a file: not ours to keep
            warn(f"{self.parts} is not a directory; removed")
            discard(self.parts)
            self.parts.mkdir()
        except OSError as e:
            raise UserError(f"bad {named('-o', str(self.out))}: cannot create {self.parts} ({e.strerror})") \
                from None
        lock = DirectoryLock(self.out)
        lock.acquire()
        self._lock = lock
        self.clean_temporary()
        return self

    @staticmethod
    def make_output_dir(out: Path) -> None:
        """Create an output directory (a one-line UserError if it cannot be one)."""
        from gnibench.suite.foundation.outputs import probe

        out = Path(out)
        try:
            if out.exists() and not out.is_dir():
                raise UserError(f"bad -o {out}: it exists and is not a directory")
            if out.is_symlink() and not out.exists():
                raise UserError(f"bad -o {out}: it is a broken symlink (to {os.readlink(out)}); "
                                f"allowed: a directory, or a place to make one")
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise UserError(f"bad -o {out}: cannot create the directory ({e.strerror})") from None
        probe(out, f"-o {out}")

    def close(self) -> None:
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def __enter__(self) -> Self:
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    def clean_temporary(self) -> int:
        """Remove the temporary files a killed run left (``.<name>.tmp<pid>``): only one run holds
        the directory, so none of them is being written."""
        removed = 0
        for d in (self.out, self.parts):
            for f in d.glob(".*.tmp*"):
                f.unlink(missing_ok=True)
                removed += 1
        return removed

    # -- parts ------------------------------------------------------------------------------------

    def path(self, key: str) -> Path:
        return self.parts / f"{key}.parquet"

    def has(self, key: str) -> bool:
        return self.path(key).is_file()

    def write(self, key: str, part: Part, empty_samples) -> None:
        """Commit one finished cell atomically, with the checksum of its content."""
        from gnibench.suite.runs.storage import write_parquet

        samples = part.samples if part.samples is not None else empty_samples
        meta = {"part_format": PART_FORMAT, "key": key, "row": part.row, "timing": part.timing,
                "state_names": list(part.state_names), "has_samples": part.samples is not None}
        meta = json.loads(json.dumps(meta, default=str))       # as it will be read back
        meta["checksum"] = content_checksum(meta, part.samples)
        self._memo.pop(key, None)          # a part read before (in error, say) is replaced
        write_parquet(samples, self.path(key), meta)

    def read(self, key: str) -> Part | None:
        """A stored part, or None when it is missing or damaged (then it is discarded, with one
        warning line: it cannot be read, or its content does not match its checksum).

        A part read before by this run is returned from memory, as a copy (its rows are
        re-stamped with each experiment's cell ids): a run over several experiments, or one that
        consolidates its tables many times, reads each part from the disk once (and the tables
        are built from what the disk holds, whether the part was computed now or before)."""
        path = self.path(key)
        if key in self._memo and path.is_file():
            p = self._memo[key]
            return Part(None if p.samples is None else p.samples.copy(deep=False), dict(p.row),
                        dict(p.timing), p.state_names)
        if not path.exists():
            return None
        part = self._load(key, path)
        if part is None:
            return None
        self._memo[key] = part
        return Part(None if part.samples is None else part.samples.copy(deep=False),
                    dict(part.row), dict(part.timing), part.state_names)

    def _load(self, key: str, path: Path) -> Part | None:
        import pandas as pd
        import pyarrow as pa
        from gnibench.suite.foundation.files import NotRegularFile, read_regular
        from gnibench.suite.runs.storage import read_parquet_meta

        try:
            raw = read_regular(path)          # never blocks on a FIFO (foundation/files.py)
            meta = read_parquet_meta(pa.BufferReader(raw))
            if meta.get("key") != key or meta.get("part_format") != PART_FORMAT:
                raise ValueError("it is not the part of this cell")
            samples = pd.read_parquet(pa.BufferReader(raw)) if meta["has_samples"] else None
            stored = meta.pop("checksum", None)
            if stored != content_checksum(meta, samples):
                warn(f"stored cell {path.relative_to(self.out)} does not match its checksum "
                     f"(damaged or modified); discarded and recomputed")
                discard(path)
                return None
            return Part(samples, _restore(meta["row"]), _restore(meta["timing"]),
                        tuple(meta["state_names"]))
        except NotRegularFile as e:       # a FIFO or a directory in its place
            warn(f"stored cell {path.relative_to(self.out)} {e.what}; discarded and recomputed")
            discard(path)
            return None
        except Exception as e:  # noqa: BLE001 - a damaged part is recomputed, whatever the damage
            why = " ".join(str(e).split())[:120] or type(e).__name__
            warn(f"stored cell {path.relative_to(self.out)} cannot be read ({why}); discarded "
                 f"and recomputed")
            discard(path)
            return None


def content_checksum(meta: dict, samples) -> str:
    """sha256 of a part's content: its metadata (canonical JSON, without the checksum) and its
    samples, column by column (name, then the values: numbers as little-endian 8-byte words,
    anything else as text), so that one flipped bit in a value, a name or a row is seen."""
    import numpy as np

    h = hashlib.sha256(json.dumps(meta, sort_keys=True, default=str).encode())
    if samples is None:
        return h.hexdigest()
    h.update(f"rows {len(samples)}\n".encode())
    for name in samples.columns:
        column = samples[name]
        h.update(f"column {name}\n".encode())
        kind = column.dtype.kind if isinstance(column.dtype, np.dtype) else "O"
        if kind in "iub":
            h.update(np.ascontiguousarray(column.to_numpy(), dtype="<i8").tobytes())
        elif kind == "f":
            h.update(np.ascontiguousarray(column.to_numpy(), dtype="<f8").tobytes())
        else:
            h.update(_text_bytes(column.astype(object).tolist()))
    return h.hexdigest()


def _text_bytes(values: list) -> bytes:
    """The bytes :func:`content_checksum` hashes for a column of text (or other objects):
    ``str(v)`` in UTF-8 then ``\\x01`` for each value, ``\\x00`` for a missing one. A column
    without a missing value (every stored part: its problem and method, one per row) is joined at
    once (a part of 2001 rows: 0.36 ms for its checksum, 0.99 ms value by value)."""
    import pandas as pd

    def missing(v) -> bool:
        return v is None or (not isinstance(v, str) and bool(pd.isna(v)))

    if not values:
        return b""
    if all(isinstance(v, str) for v in values):
        return ("\x01".join(values) + "\x01").encode()
    return b"".join(b"\x00" if missing(v) else str(v).encode() + b"\x01" for v in values)


def _restore(d: dict) -> dict:
    """JSON null -> NaN for the float columns of a row (JSON has no NaN)."""
    return {k: (float("nan") if v is None and k not in ("steps", "samples", "cache_misses")
                else v) for k, v in d.items()}
