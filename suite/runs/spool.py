"""Rows and columns kept on disk while ``gnibench solve`` streams a cell's table.

:class:`RawSpool` is the sink of a compiled driver's output blocks (:class:`gnibench.suite.cell.
calls.Buffers`): each block of t, y and the counters is appended to one file of float64 rows and
read back block by block. :class:`ColumnSpool` keeps the table's columns as they are made, one
file of float64 per column, and gives them back as :class:`SpooledColumn` objects that the writers
(:mod:`gnibench.suite.runs.writers`) slice block by block like arrays. Memory holds one block at a
time whatever the number of rows; the files live in a temporary directory
(:func:`gnibench.suite.runs.streaming.spool_directory`) removed when the output is written.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from gnibench.suite.cell.calls import COUNTERS
from gnibench.suite.foundation.outputs import fault

_ITEM = np.dtype(np.float64).itemsize


class RawSpool:
    """The sink of a driver's output blocks: ``spool(t, y, c)`` appends them to ``path``;
    ``rows``: the rows of one block (the driver's buffer is no larger)."""

    def __init__(self, path: Path, rows: int):
        self.path, self.rows = Path(path), int(rows)
        self.width = 0
        self._file = open(self.path, "wb")    # noqa: SIM115 - closed by close()

    def __call__(self, t, y, c) -> None:
        block = np.column_stack([t, y, c])
        if not self.width:
            self.width = block.shape[1]
        _write(self._file, block)

    def close(self) -> None:
        self._file.close()

    def read(self, rows: int):
        """The rows written, in blocks of ``rows``: (t, y, c), c the counters
        (:data:`~gnibench.suite.cell.calls.COUNTERS` columns)."""
        if not self.width:
            return
        dim = self.width - 1 - COUNTERS
        size = os.path.getsize(self.path) // (_ITEM * self.width)     # whole rows only
        with open(self.path, "rb") as f:
            for start in range(0, size, rows):
                n = min(rows, size - start)
                block = np.fromfile(f, dtype=np.float64, count=n * self.width)
                block = block.reshape(n, self.width)
                yield block[:, 0], block[:, 1:1 + dim], block[:, 1 + dim:]


class SpooledColumn:
    """One column of a spooled table: ``len``, ``dtype`` and slices read from its file."""

    ndim = 1

    def __init__(self, path: Path, integer: bool, length: int):
        self.path, self.length = Path(path), int(length)
        self.dtype = np.dtype(np.int64 if integer else np.float64)

    def __len__(self) -> int:
        return self.length

    def __getitem__(self, key):
        if not isinstance(key, slice) or key.step not in (None, 1):
            raise TypeError("a spooled column is read by contiguous slices")
        start, stop, _ = key.indices(self.length)
        n = max(stop - start, 0)
        with open(self.path, "rb") as f:
            f.seek(start * _ITEM)
            values = np.fromfile(f, dtype=np.float64, count=n)
        return values.astype(self.dtype) if self.dtype.kind == "i" else values

    def __array__(self, dtype=None, copy=None):
        values = self[:]
        return values if dtype is None else values.astype(dtype)


class ColumnSpool:
    """A table made block by block: :meth:`append` a block's columns (name -> 1-D numeric array,
    the same names every time), :meth:`columns` gives them back as :class:`SpooledColumn`.

    Every value is kept as float64; a column whose blocks were all integers is read back as int64
    (exact: the counters are integers below 2^53)."""

    def __init__(self, directory: Path):
        self.directory = Path(directory)
        self.names: list[str] | None = None
        self.integer: dict[str, bool] = {}
        self.rows = 0
        self._files: dict = {}

    def append(self, columns: dict) -> None:
        if self.names is None:
            self.names = list(columns)
            for k, name in enumerate(self.names):
                self._files[name] = open(self.directory / f"column-{k}.f8", "wb")  # noqa: SIM115
                self.integer[name] = True
        if list(columns) != self.names:
            raise ValueError(f"a block's columns {list(columns)} differ from {self.names}")
        for name, values in columns.items():
            values = np.asarray(values)
            if values.dtype.kind not in "fiu" or values.ndim != 1:
                raise ValueError(f"column {name} is not a 1-D numeric array")
            self.integer[name] &= values.dtype.kind in "iu"
            _write(self._files[name], np.ascontiguousarray(values, dtype=np.float64))
        self.rows += len(next(iter(columns.values()))) if columns else 0

    def columns(self) -> dict[str, SpooledColumn]:
        for f in self._files.values():
            f.close()
        return {name: SpooledColumn(self._files[name].name, self.integer[name], self.rows)
                for name in self.names or ()}


def _write(f, values: np.ndarray) -> None:
    """Append to a spool file; a full disk is one line naming the directory and the remedy."""
    try:
        f.write(values.tobytes())
    except OSError as e:
        raise fault(e, f"spooling the table under {Path(f.name).parent}",
                    "set TMPDIR to a directory with room (about 8 bytes per number of the "
                    "table), or sample less often") from None
