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
and is recomputed, never reused stale. Parts are verified when read (a part that cannot be read
is discarded and recomputed).
"""
from __future__ import annotations

import fcntl
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Self

from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.provenance import versions

#: what the numbers of a cell depend on (folders and files of the package, relative to its root)
CODE = ("problems", "methods", "suite/foundation", "suite/cell", "suite/metrics",
        "suite/runs/tables.py")
PART_FORMAT = 1


def package_root() -> Path:
    import gnibench

    return Path(gnibench.__file__).resolve().parent


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
        self._lock_file = None
        self._memo: dict[str, Part] = {}      # parts this run has read (each read once)

    # -- the lock ---------------------------------------------------------------------------------

    def open(self) -> Self:
        """Create the directory, take the lock (a one-line UserError if another run holds it) and
        remove the temporary files of killed runs."""
        if self.out.exists() and not self.out.is_dir():
            raise UserError(f"bad -o {self.out}: it exists and is not a directory")
        try:
            self.parts.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise UserError(f"bad -o {self.out}: cannot create the directory ({e.strerror})") \
                from None
        if not os.access(self.out, os.W_OK):
            raise UserError(f"bad -o {self.out}: the directory is not writable")
        lock = open(self.out / ".lock", "a+")          # noqa: SIM115 - held until close()
        try:
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.seek(0)
            holder = lock.read().strip() or "another process"
            lock.close()
            raise UserError(f"results directory {self.out} is in use by another gnibench run "
                            f"({holder}); wait for it to finish or use another -o") from None
        lock.seek(0)
        lock.truncate()
        lock.write(f"pid {os.getpid()}\n")
        lock.flush()
        self._lock_file = lock
        self.clean_temporary()
        return self

    @staticmethod
    def make_output_dir(out: Path) -> None:
        """Create an output directory (a one-line UserError if it cannot be one)."""
        out = Path(out)
        if out.exists() and not out.is_dir():
            raise UserError(f"bad -o {out}: it exists and is not a directory")
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise UserError(f"bad -o {out}: cannot create the directory ({e.strerror})") from None
        if not os.access(out, os.W_OK):
            raise UserError(f"bad -o {out}: the directory is not writable")

    def close(self) -> None:
        if self._lock_file is not None:
            fcntl.flock(self._lock_file.fileno(), fcntl.LOCK_UN)
            self._lock_file.close()
            self._lock_file = None

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
        """Commit one finished cell atomically."""
        from gnibench.suite.runs.storage import write_parquet

        samples = part.samples if part.samples is not None else empty_samples
        meta = {"part_format": PART_FORMAT, "key": key, "row": part.row, "timing": part.timing,
                "state_names": list(part.state_names), "has_samples": part.samples is not None}
        write_parquet(samples, self.path(key), meta)

    def read(self, key: str) -> Part | None:
        """A stored part, or None when it is missing or cannot be read (then it is discarded).

        A part read before by this run is returned from memory, as a copy (its rows are
        re-stamped with each experiment's cell ids): a run over several experiments, or one that
        consolidates its tables many times, reads each part from the disk once (and the tables
        are built from what the disk holds, whether the part was computed now or before)."""
        import pandas as pd
        from gnibench.suite.runs.storage import read_parquet_meta

        path = self.path(key)
        if key in self._memo and path.is_file():
            p = self._memo[key]
            return Part(None if p.samples is None else p.samples.copy(deep=False), dict(p.row),
                        dict(p.timing), p.state_names)
        if not path.is_file():
            return None
        try:
            meta = read_parquet_meta(path)
            if meta.get("key") != key or meta.get("part_format") != PART_FORMAT:
                raise ValueError("not the part of this cell")
            samples = pd.read_parquet(path) if meta["has_samples"] else None
        except Exception:  # noqa: BLE001 - a damaged part is recomputed, whatever the damage
            path.unlink(missing_ok=True)
            return None
        part = Part(samples, _restore(meta["row"]), _restore(meta["timing"]),
                    tuple(meta["state_names"]))
        self._memo[key] = part
        return Part(None if samples is None else samples.copy(deep=False), dict(part.row),
                    dict(part.timing), part.state_names)


def _restore(d: dict) -> dict:
    """JSON null -> NaN for the float columns of a row (JSON has no NaN)."""
    return {k: (float("nan") if v is None and k not in ("steps", "samples", "cache_misses")
                else v) for k, v in d.items()}
