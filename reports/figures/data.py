"""What a figure reads: the tables of one results directory and the figure stored with them.

``cells.parquet`` carries the normalized figure (``figure`` in its ``gnibench`` metadata, written
by the runner from the experiment's ``[figure]`` section), ``samples.parquet`` the sampled columns,
``fields.parquet`` the field layers. Nothing here integrates or imports the runner.
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

#: signed columns: a log axis plots their absolute value (as suite/runs/figure_spec.py says)
SIGNED_PREFIXES = ("err_", "relerr_")
SIGNED = ("eta_phase", "pericenter_angle")
#: most points drawn for one line (a longer one is thinned evenly, its last point kept)
MAX_DRAWN = 20_000


class FigureDataError(Exception):
    """The results directory lacks what the figure needs (not run, or not a figure's)."""


def read_meta(path: Path) -> dict:
    import pyarrow.parquet as pq

    md = pq.read_schema(path).metadata or {}
    return json.loads(md.get(b"gnibench", b"{}"))


@dataclass
class Results:
    """The tables of a results directory, read for one figure."""

    root: Path
    meta: dict
    figure: dict
    cells: pd.DataFrame
    samples: pd.DataFrame
    fields: pd.DataFrame | None

    @classmethod
    def read(cls, root: str | Path, figure: dict | None = None) -> Results:
        root = Path(root)
        path = root / "cells.parquet"
        if not path.is_file():
            raise FigureDataError(f"no results in {root} (cells.parquet is missing)")
        meta = read_meta(path)
        figure = figure or meta.get("figure")
        if not figure:
            raise FigureDataError(f"{root}: experiment {meta.get('experiment')!r} has no [figure]")
        cells = pd.read_parquet(path)
        if "base_method" not in cells.columns:
            raise FigureDataError(f"{root}: its tables were written by an earlier gnibench (no "
                                  f"column 'base_method'); run gnibench reproduce "
                                  f"{figure.get('id', '')} again")
        columns = _sample_columns(figure)
        samples_path = root / "samples.parquet"
        if columns and samples_path.is_file():
            import pyarrow.parquet as pq

            have = set(pq.read_schema(samples_path).names)
            samples = pd.read_parquet(samples_path, columns=[c for c in columns if c in have])
        else:
            samples = pd.DataFrame({"cell": pd.Series(dtype="int64")})
        fields_path = root / "fields.parquet"
        fields = pd.read_parquet(fields_path) if fields_path.is_file() else None
        return cls(root, meta, figure, cells, samples, fields)

    def cell_samples(self, cell: int) -> pd.DataFrame:
        return self.samples[self.samples["cell"] == cell]

    def cell_row(self, cell: int) -> dict:
        rows = self.cells[self.cells["cell"] == cell]
        return rows.iloc[0].to_dict() if len(rows) else {}

    def field(self, panel: int, index: int) -> pd.DataFrame:
        if self.fields is None:
            raise FigureDataError(f"{self.root}: fields.parquet is missing")
        f = self.fields
        return f[(f["panel"] == panel) & (f["field"] == index)]


def _sample_columns(figure: dict) -> list[str]:
    cols = {"cell", "t"}
    for panel in figure.get("panels", []):
        for curve in panel.get("curves", []):
            cols.update((curve["x"], curve["y"], *curve.get("where", {})))
    return sorted(cols) if figure.get("panels") else []


def where(df: pd.DataFrame, conditions: dict | None) -> pd.DataFrame:
    """The samples of a curve's ``where = {column = value}`` (all of them without one)."""
    for column, value in (conditions or {}).items():
        df = df[df[column].to_numpy(dtype=float) == value]
    return df


def is_signed(column: str) -> bool:
    return column.startswith(SIGNED_PREFIXES) or column in SIGNED


def values(df: pd.DataFrame, column: str, log: bool) -> np.ndarray:
    """A column as floats; on a log axis the absolute value of a signed column, and NaN where
    the value is not positive (matplotlib leaves those out)."""
    v = df[column].to_numpy(dtype=float)
    if log:
        v = np.abs(v) if is_signed(column) else v.copy()
        v[~(v > 0)] = np.nan
    return v


def thin(x: np.ndarray, y: np.ndarray, limit: int = MAX_DRAWN,
         logx: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """At most about ``limit`` points of a line: the samples are cut into ``limit / 2`` buckets
    and the smallest and largest y of each are kept, in order (the band of a fast oscillation
    keeps its edges; even thinning would alias it). A curve whose x increases (a time series) is
    cut into buckets of equal width in x as drawn (in log x on a log axis), others into buckets of
    equal numbers of samples. First and last points kept."""
    n = len(x)
    if n <= limit:
        return x, y
    nb = limit // 2
    pos = np.log(np.where(x > 0, x, np.nan)) if logx else x.astype(float)
    ok = np.isfinite(pos)
    if ok.sum() > 1 and np.all(np.diff(pos[ok]) >= 0):
        edges = np.linspace(pos[ok][0], pos[ok][-1], nb + 1)
        bucket = np.where(ok, np.clip(np.searchsorted(edges, pos, side="right") - 1, 0, nb - 1),
                          -1)
        run = np.cumsum(np.diff(np.concatenate([[-2], bucket])) != 0) - 1
    else:
        sizes = np.full(nb, n // nb)
        sizes[:n % nb] += 1                      # np.array_split's buckets
        run = np.repeat(np.arange(nb), sizes)
    # per run of samples, the first smallest and the first largest finite y (the first sample
    # when it has none): one sort by (run, y, index) each, NaN last within a run
    finite = np.where(np.isfinite(y), y, np.nan)
    index = np.arange(n)
    first = np.flatnonzero(np.diff(np.concatenate([[-1], run])) != 0)
    lowest = np.lexsort((index, finite, run))[first]
    highest = np.lexsort((index, -finite, run))[first]
    idx = np.unique(np.concatenate([[0, n - 1], lowest, highest]))
    return x[idx], y[idx]


def at_times(df: pd.DataFrame, times: list[float]) -> list[int | None]:
    """The row positions of the samples at the given times (None where there is none)."""
    t = df["t"].to_numpy(dtype=float)
    out = []
    for target in times:
        if not len(t):
            out.append(None)
            continue
        k = int(np.argmin(np.abs(t - target)))
        out.append(k if abs(t[k] - target) <= 1e-9 * max(1.0, abs(target)) else None)
    return out


def polygon_area(x: np.ndarray, y: np.ndarray) -> float:
    """Area enclosed by the closed polygon through the points (shoelace formula); NaN when a
    vertex is missing."""
    if len(x) < 3 or not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        return math.nan
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


#: a per-cell value in a label: {=name} or {=name:format} (as suite/runs/figure_spec.py says)
PLACEHOLDER = re.compile(r"\{=([A-Za-z_][A-Za-z0-9_]*)(?::([^{}]*))?\}")


def format_label(label: str, rows: list[dict]) -> str:
    """A legend label with its ``{=column:format}`` placeholders filled from the cells' rows (the
    median over the curve's cells of a numeric value; ``nan`` when missing)."""

    def fill(match) -> str:
        name, spec = match.group(1), match.group(2) or "g"
        vals = []
        for row in rows:
            try:
                vals.append(float(row.get(name)))
            except (TypeError, ValueError):
                continue
        finite = [v for v in vals if math.isfinite(v)]
        value = float(np.median(finite)) if finite else (vals[0] if vals else math.nan)
        try:
            return format(value, spec)
        except ValueError:
            return str(value)

    return PLACEHOLDER.sub(fill, label)


def wrap(x: np.ndarray, y: np.ndarray, xwrap, ywrap) -> tuple[np.ndarray, np.ndarray]:
    """x (and y) taken modulo their intervals, with a break (NaN) where the curve jumps across
    (a rotating pendulum's angle on the circle, [HLW] I.1.3)."""
    jumps = np.zeros(len(x), dtype=bool)
    out = []
    for v, interval in ((x, xwrap), (y, ywrap)):
        if interval:
            a, b = interval
            v = a + np.mod(v - a, b - a)
            jumps[1:] |= np.abs(np.diff(v)) > (b - a) / 2
        out.append(v.astype(float))
    if jumps.any():
        at = np.flatnonzero(jumps)
        out = [np.insert(v, at, np.nan) for v in out]
    return out[0], out[1]
