"""The resumable store of a results directory: one record per finished cell, appended.

Layout of ``<out>/``::

    .lock                      held (flock) by the run using the directory
    parts/NNNNNN.seg           segments: the records of finished cells, appended by the run that
                               computed them (one segment per run; :mod:`.partfile`)
    samples.parquet, cells.parquet, timings.parquet
                               consolidated from the parts, in cell order (rewritten as cells
                               finish and at the end)

The key of a part is a content hash of everything that determines its numbers: the canonical cell
(problem and method specs, horizon, sampling, metrics, reference solution, an ensemble's initial
conditions; the text of a user definition, :mod:`gnibench.suite.cell.user`), the source code that
computes it (problems, methods and their kernels, the cell layer, the metrics and the tables: a
fingerprint of those files) and the package versions. Running the same experiment again reuses
every part whose key matches and computes only the missing cells; a cell whose spec or code
changed gets a new key and is recomputed, never reused stale.

**Committed as it finishes.** A finished cell is appended to the run's segment as one record and
flushed to the operating system before the next cell is counted: after ``kill -9`` every record
written whole is there; a record cut short ends its segment and its cell is computed again. A
later record of a key replaces an earlier one (a cell in ``error`` recomputed).

**Verified when read.** A record carries the sha256 of its part, checked when a later run reads
it: a part whose bytes do not match (one flipped bit), or that cannot be read, is recomputed with
one warning line, and its new record replaces it. A segment whose records cannot be followed (a
damaged head) warns once; the cells after that point are recomputed. Segments are opened as
regular files only (:mod:`gnibench.suite.foundation.files`): a FIFO or a directory in place of one
is said in one warning line and removed, and its cells are recomputed (opening a FIFO would wait
for a writer forever).

**Cheap.** What a finished cell costs this process (the parent of the workers): one encoding of
its columns and rows, one digest, one append to an open file (a file created per cell cost more
than the rest together); the run keeps the part in memory and makes its tables from it, never
reading back what it wrote. A later run reads the heads of the records once (a walk over the
segments) and each part it needs once. When more than half of the stored bytes are replaced or
damaged records (``--fresh`` runs, say), the live records are copied into one new segment and the
old segments removed (:meth:`Store.compact`).
"""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Self

from gnibench.suite.foundation.cache import discard, warn
from gnibench.suite.foundation.errors import UserError, named
from gnibench.suite.foundation.files import NotRegularFile, open_regular_file
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.runs.partfile import FORMAT as PART_FORMAT
from gnibench.suite.runs.partfile import HEAD, KEY, MAGIC, Damaged, Entry, Part, encode, load, scan

SUFFIX = ".seg"

#: what the numbers of a cell depend on (folders and files of the package, relative to its root)
CODE = ("problems", "methods", "suite/foundation", "suite/cell", "suite/metrics",
        "suite/runs/tables.py", "suite/runs/ensembles.py")


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
    if getattr(cell, "ensemble", None) is not None:      # the orbits of an ensemble's unit
        doc["ensemble"] = cell.ensemble.digest()
    if getattr(cell, "repeat", 1) > 1:                   # timed N times: another timings row
        doc["repeat"] = cell.repeat
    spec = getattr(cell, "spec", None)
    defs = [] if spec is None else [r.definition for r in (spec.problem.record,
                                                            spec.method.base.record) if r.definition]
    if defs:                               # user definitions: their text (and Python code's hash)
        doc["definitions"] = hashlib.sha256("\n".join(defs).encode()).hexdigest()
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()).hexdigest()[:32]


class Store:
    """A results directory opened by one run (see the module docstring)."""

    def __init__(self, out: Path):
        self.out = Path(out)
        self.parts = self.out / "parts"
        self._lock = None
        self._memo: dict[str, Part] = {}      # parts this run has read or written
        self._index: dict[str, Entry] = {}    # key -> where its latest record lies
        self._files: dict[str, object] = {}   # segment name -> open file (reading)
        self._segment = None                  # this run's segment (appending), made on demand
        self._sizes: dict[str, int] = {}      # segment name -> bytes

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
            raise UserError(f"bad {named('-o', str(self.out))}: cannot create {self.parts} "
                            f"({e.strerror})") from None
        lock = DirectoryLock(self.out)
        lock.acquire()
        self._lock = lock
        self.clean_temporary()
        self._scan()
        self.compact()
        return self

    @staticmethod
    def make_output_dir(out: Path) -> None:
        """Create an output directory (a one-line UserError if it cannot be one)."""
        from gnibench.suite.foundation.outputs import probe

        out = Path(out)
        try:
            if out.exists() and not out.is_dir():
                raise UserError(f"bad {named('-o', str(out))}: it exists and is not a directory")
            if out.is_symlink() and not out.exists():
                raise UserError(f"bad {named('-o', str(out))}: it is a broken symlink (to {os.readlink(out)}); "
                                f"allowed: a directory, or a place to make one")
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise UserError(f"bad {named('-o', str(out))}: cannot create the directory ({e.strerror})") from None
        probe(out, f"-o {out}")

    def close(self) -> None:
        for f in [*self._files.values(), self._segment]:
            if f is not None:
                f.close()
        self._files, self._segment = {}, None
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
        for f in self.parts.glob("*.parquet"):      # parts of format 2: never read again
            f.unlink(missing_ok=True)
        return removed

    # -- segments ---------------------------------------------------------------------------------

    def _segments(self) -> list[Path]:
        return sorted(p for p in self.parts.glob(f"*{SUFFIX}") if p.stem.isdigit())

    def _scan(self) -> None:
        """Index the records of every segment, oldest first (a later record of a key wins)."""
        for path in self._segments():
            try:
                f = open_regular_file(path)   # never blocks on a FIFO (foundation/files.py)
            except NotRegularFile as e:       # a FIFO or a directory in its place
                warn(f"stored cells {path.relative_to(self.out)} {e.what}; discarded, their "
                     f"cells are recomputed")
                discard(path)
                continue
            except OSError as e:
                warn(f"stored cells {path.relative_to(self.out)} cannot be read ({e.strerror}); "
                     f"their cells are recomputed")
                continue
            entries, stop = scan(f, path.name)
            if stop == "damaged":
                warn(f"stored cells {path.relative_to(self.out)} are damaged after "
                     f"{len(entries)} records; the cells after them are recomputed")
            elif stop == "format":
                warn(f"stored cells {path.relative_to(self.out)} cannot be read: after "
                     f"{len(entries)} records they were written in another format of the store "
                     f"(not {MAGIC.decode().strip()!r}); their cells are recomputed")
            self._files[path.name] = f
            self._sizes[path.name] = f.seek(0, 2)
            self._index.update(entries)

    def compact(self, threshold: float = 0.5, least: int = 1 << 20) -> bool:
        """Copy the live records into one new segment and remove the others when replaced,
        damaged or cut-short bytes are more than ``threshold`` of the segments' bytes (and at
        least ``least`` bytes). A kill meanwhile leaves records twice, the same bytes: harmless."""
        total = sum(self._sizes.values())
        live = sum(e.length + HEAD for e in self._index.values())
        if total - live <= max(threshold * total, least):
            return False
        old = list(self._files)
        moved: dict[str, Entry] = {}
        for key, e in self._index.items():
            f = self._files[e.segment]
            f.seek(e.offset - HEAD)
            moved[key] = self._append(f.read(HEAD + e.length), key)
        self._segment.flush()
        for name in old:
            self._files.pop(name).close()
            (self.parts / name).unlink(missing_ok=True)
            self._sizes.pop(name, None)
        self._index = moved
        return True

    def _append(self, data: bytes, key: str) -> Entry:
        """Append a record to this run's segment (a new one, after the last): where its part is."""
        if self._segment is None:
            last = max((int(p.stem) for p in self._segments()), default=0)
            path = self.parts / f"{last + 1:06d}{SUFFIX}"
            self._segment = open(path, "xb")  # noqa: SIM115 - appended to until close
            self._files[path.name] = open(path, "rb")  # noqa: SIM115
            self._sizes[path.name] = 0
        name = Path(self._segment.name).name
        at = self._sizes[name]
        self._segment.write(data)
        self._sizes[name] = at + len(data)
        return Entry(name, at + HEAD, len(data) - HEAD, data[len(MAGIC) + KEY:HEAD - 8])

    # -- parts ------------------------------------------------------------------------------------

    def has(self, key: str) -> bool:
        return key in self._index

    def write(self, key: str, part: Part) -> Part:
        """Commit one finished cell: its record appended to this run's segment and flushed to the
        operating system. Returns the part as a later run reads it back, which this run's tables
        are made of too (so a resumed run's tables are the same bytes)."""
        data, back = encode(key, part)
        entry = self._append(data, key)
        self._segment.flush()
        self._index[key] = entry
        self._memo[key] = back
        return back.copy()

    def read(self, key: str) -> Part | None:
        """A stored part, or None when it is missing or damaged (then one warning line: it cannot
        be read, or its content does not match its digest; the cell is recomputed and its new
        record replaces this one).

        A part read or written before by this run is returned from memory, as a copy (its rows
        are re-stamped with each experiment's cell ids): a run over several experiments, or one
        that consolidates its tables many times, reads each part from the disk once."""
        if key in self._memo:
            return self._memo[key].copy()
        entry = self._index.get(key)
        if entry is None:
            return None
        where = f"{(self.parts / entry.segment).relative_to(self.out)} (cell {key})"
        try:
            part = load(self._files[entry.segment], entry, key)
        except Damaged:
            warn(f"stored cell in {where} does not match its checksum (damaged or modified); "
                 f"recomputed")
            part = None
        except Exception as e:  # noqa: BLE001 - a damaged part is recomputed, whatever the damage
            why = " ".join(str(e).split())[:120] or type(e).__name__
            warn(f"stored cell in {where} cannot be read ({why}); recomputed")
            part = None
        if part is None:
            del self._index[key]
            return None
        self._memo[key] = part
        return part.copy()

