"""The bytes of the store: one finished cell (a part) as a record, records appended to segments.

A **part** is what a finished cell leaves: its cells row and timings row, its samples as columns
and, for an ensemble cell, its orbits (one row per initial condition) as columns. Its bytes
(:func:`encode`) are the length of a JSON header (8 bytes, little-endian), the header (the rows,
the state names and, per column, its table, name, type, length and size in bytes), then each
column's values: numbers and booleans as their little-endian bytes, anything else as a JSON list.

A **record** frames one part in a segment file (:func:`record`)::

    b"gnibench part 3\\n"    16 bytes: the format
    key                      32 bytes: the cell's key (ASCII hex)
    sha256                   64 bytes: the hex digest of the part's bytes
    length                    8 bytes: the part's size, little-endian
    part                     ``length`` bytes

so a reader walks a segment from record to record reading only their 120-byte heads
(:func:`scan`), and verifies a part's digest when it reads it (:func:`load`). One flipped bit in a
part changes its digest; a record cut short (a run killed while appending it) ends the segment.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

FORMAT = 3
MAGIC = b"gnibench part %d\n" % FORMAT
KEY = 32
HEAD = len(MAGIC) + KEY + 64 + 8


@dataclass
class Part:
    """A finished cell as stored: its samples (column name -> 1-D array, or None for a cell in
    error), its cells row and timings row, and for an ensemble cell its orbits (one row per initial
    condition, column name -> 1-D array; :mod:`gnibench.suite.runs.ensembles`)."""

    samples: dict | None
    row: dict
    timing: dict
    state_names: tuple[str, ...]
    orbits: dict | None = None

    def copy(self) -> Part:
        """A copy whose rows and column tables can be re-stamped (the arrays are shared: they are
        never written to)."""
        return Part(None if self.samples is None else dict(self.samples), dict(self.row),
                    dict(self.timing), self.state_names,
                    None if self.orbits is None else dict(self.orbits))


class Damaged(ValueError):
    """A part whose bytes do not match their digest."""


@dataclass(frozen=True)
class Entry:
    """Where a record's part lies: its segment, the offset of the part and its size."""

    segment: str
    offset: int
    length: int
    digest: bytes


def encode(key: str, part: Part) -> tuple[bytes, Part]:
    """The record of a part (:func:`record`), and the part as a reader gets it back (its rows
    through JSON: numpy scalars as Python numbers, JSON null as NaN in the float columns), which
    the writer's tables are made of too, so a resumed run's tables are the same bytes."""
    import numpy as np

    text = json.dumps({"key": key, "row": part.row, "timing": part.timing,
                       "state_names": list(part.state_names)}, default=_plain)
    meta = json.loads(text)                 # as a reader gets it back
    columns, blobs = [], []
    for table, cols in (("samples", part.samples), ("orbits", part.orbits)):
        for name, values in (cols or {}).items():
            a = np.asarray(values)
            if a.dtype.kind in "fiub":
                a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))
                kind, data = a.dtype.str, a.tobytes()
            else:
                kind = "json"
                data = json.dumps([_plain(v) for v in a.tolist()]).encode()
            columns.append([table, str(name), kind, int(a.shape[0]), len(data)])
            blobs.append(data)
    header = (text[:-1] + ', "columns": ' + json.dumps(columns) + "}").encode()
    payload = b"".join([len(header).to_bytes(8, "little"), header, *blobs])
    back = Part(part.samples, restore(meta["row"]), restore(meta["timing"]),
                tuple(meta["state_names"]), part.orbits)
    return record(key, payload), back


def record(key: str, payload: bytes) -> bytes:
    """A part's bytes framed as a record (see the module docstring)."""
    if len(key) != KEY:
        raise ValueError(f"bad key {key!r}")
    return b"".join([MAGIC, key.encode("ascii"), hashlib.sha256(payload).hexdigest().encode(),
                     len(payload).to_bytes(8, "little"), payload])


def scan(f, segment: str) -> tuple[dict[str, Entry], str]:
    """The records of an open segment file, in order (a later record of a key replaces an earlier
    one), and why the walk stopped before the end ("" when it did not): a record cut short (a
    run killed while appending it: nothing lost but that cell, ``"cut"``), a record written in
    another format of the store (an older or newer gnibench, ``"format"``) or a head that is not
    one (``"damaged"``; the records after it cannot be found)."""
    f.seek(0, 2)
    size = f.tell()
    f.seek(0)
    entries: dict[str, Entry] = {}
    at = 0
    while at < size:
        head = f.read(HEAD)
        if len(head) < HEAD:
            return entries, "cut"
        if not head.startswith(MAGIC):      # another format of the store, or no record head
            return entries, "format" if head.startswith(MAGIC[:14]) else "damaged"
        key = head[len(MAGIC):len(MAGIC) + KEY]
        digest = head[len(MAGIC) + KEY:len(MAGIC) + KEY + 64]
        length = int.from_bytes(head[-8:], "little")
        if not (key.isalnum() and key.isascii()):
            return entries, "damaged"
        if at + HEAD + length > size:
            return entries, "cut"
        entries[key.decode()] = Entry(segment, at + HEAD, length, digest)
        at += HEAD + length
        f.seek(at)
    return entries, ""


def load(f, entry: Entry, key: str) -> Part:
    """The part of a record (read from an open segment file, its digest verified):
    :class:`Damaged` when its bytes do not match their digest, ValueError when they are not a
    part."""
    import numpy as np

    f.seek(entry.offset)
    payload = f.read(entry.length)
    if hashlib.sha256(payload).hexdigest().encode() != entry.digest:
        raise Damaged("digest")
    size = int.from_bytes(payload[:8], "little")
    meta = json.loads(payload[8:8 + size])
    if meta.get("key") != key:
        raise ValueError("it is not the part of this cell")
    at = 8 + size
    tables: dict[str, dict] = {}
    for table, name, kind, length, nbytes in meta.pop("columns"):
        data = payload[at:at + nbytes]
        at += nbytes
        if kind == "json":
            values = np.array(json.loads(data), dtype=object)
        else:
            dtype = np.dtype(kind)
            values = np.frombuffer(data, dtype=dtype).astype(dtype.newbyteorder("="), copy=False)
        if len(values) != length:
            raise ValueError(f"column {name} has {len(values)} values, not {length}")
        tables.setdefault(table, {})[name] = values
    if at != len(payload):
        raise ValueError("trailing bytes")
    return Part(tables.get("samples"), restore(meta["row"]), restore(meta["timing"]),
                tuple(meta["state_names"]), tables.get("orbits"))


def _plain(v):
    """JSON of numpy scalars (their Python value), anything else unknown as text."""
    if hasattr(v, "item"):
        return v.item()
    if isinstance(v, (str, int, float, bool)) or v is None:
        return v
    return str(v)


def normal(meta: dict) -> dict:
    """``meta`` as JSON gives it back (numpy scalars as Python numbers, tuples as lists)."""
    return json.loads(json.dumps(meta, default=_plain))


def restore(d: dict) -> dict:
    """JSON null -> NaN for the float columns of a row (JSON has no NaN)."""
    return {k: (float("nan") if v is None and k not in ("steps", "samples", "cache_misses")
                else v) for k, v in d.items()}
