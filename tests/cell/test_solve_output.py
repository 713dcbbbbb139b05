"""``gnibench solve`` writes csv and json from the cell's columns (suite/runs/writers.py,
``write_columns``), block by block: the same text as pandas writes from the whole DataFrame,
without importing pandas, whatever the block size.

Compared byte for byte with pandas' ``to_csv`` and ``json.dumps`` of the whole table (the oracle
below) on cells of every kind of table and on columns of edge values, in blocks of 7 rows and in
one block."""
from __future__ import annotations

import io
import subprocess
import sys

import numpy as np
import pytest
from gnibench.suite.runs.solving import solve_cell_spec, solve_output
import json
import math

from gnibench.suite.runs.writers import _plain, write_columns
from gnibench.suite.runs.tables import frame_of

CELLS = [
    ("kepler-2d", "rk4:h=0.01", {"steps": 300, "every": 7}),
    ("kepler-2d", "dopri5:rtol=1e-8,atol=1e-8", {"t_end": 6.0, "metrics": ["global_error", "relative_invariant_error"]}),
    ("kepler-2d", "dop853", {"t_end": 3.0, "dt_out": 0.25}),
    ("henon-heiles", "rk4:h=0.05", {"t_end": 200.0, "section": 4}),
    ("euler-so4", "lie-poisson:h=0.01", {"t_end": 30.0, "section": 3}),
    ("harmonic-oscillator", "scipy-dop853:rtol=1e-9,atol=1e-9", {"t_end": 2.0}),
]


def _oracle(columns, meta, fmt) -> str:
    """What pandas and json write for the whole table at once."""
    df = frame_of(dict(columns))
    if fmt == "csv":
        return df.to_csv(index=False)
    numbers = {c: [x if math.isfinite(x) else None
                   for x in df[c].to_numpy(dtype=float, na_value=math.nan).tolist()]
               for c in df.columns}
    return json.dumps({"meta": meta, "columns": numbers}, default=str) + "\n"


def _both(columns, meta, fmt):
    fast, blocks = io.StringIO(), io.StringIO()
    write_columns(columns, meta, fmt, None, fast)
    write_columns(columns, meta, fmt, None, blocks, block=7)
    assert blocks.getvalue() == fast.getvalue(), fmt
    return fast.getvalue(), _oracle(columns, meta, fmt)


@pytest.mark.parametrize("problem, method, options", CELLS)
def test_solve_tables_are_written_as_pandas_writes_them(problem, method, options):
    out = solve_output(solve_cell_spec(problem, method, **options))
    assert _plain(out.columns), list(out.columns)        # the fast path is the one taken
    for fmt in ("csv", "json"):
        fast, slow = _both(out.columns, out.meta, fmt)
        assert fast == slow, (problem, method, fmt)
    assert len(fast) > 100


def test_edge_values_are_written_as_pandas_writes_them():
    rng = np.random.default_rng(7)
    x = rng.normal(size=3000) * 10.0 ** rng.integers(-300, 300, 3000)
    edges = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 1e16, 9999999999999998.0, 1e-4, 1e-5,
                      5e-324, 1.7976931348623157e308, 0.1, 1 / 3, 100.0, 1e22, -2.5e-7])
    x = np.concatenate([x, edges])
    n = len(x)
    steps = np.arange(n, dtype=float)
    steps[::5] = np.nan                                  # a solver that reports no count
    columns = {"t": np.linspace(0, 1, n), "q": x, "steps": steps,
               "nfev": np.arange(n, dtype=np.int64) * 3, "chart": np.ones(n, dtype=np.int64)}
    for fmt in ("csv", "json"):
        fast, slow = _both(columns, {"problem": "p", "x": float("nan")}, fmt)
        assert fast == slow, fmt
    for name, bad in (("steps", np.full(n, 0.5)), ("q", np.array(["a"] * n, dtype=object)),
                      ("a,b", x), ("flag", x > 0)):
        cols = {**columns, name: bad}
        assert not _plain(cols), name                # left to pandas, same text as before
    assert not _plain({"t": x})                      # one column: csv quotes a lone ""


def test_solve_command_does_not_import_pandas():
    code = ("import sys\nfrom gnibench.suite.cli.main import main\n"
            "code = main(['solve', 'kepler-2d', 'rk4:h=0.01', '--steps', '20', '--every', '5'])\n"
            "print(code, 'pandas' in sys.modules, file=sys.stderr)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert proc.stderr.strip().splitlines()[-1] == "0 False"
    assert proc.stdout.splitlines()[0].startswith("t,p1,p2,q1,q2,err_H")
    assert len(proc.stdout.splitlines()) == 6


def test_parquet_in_row_groups_reads_back_as_the_table(tmp_path):
    import pandas as pd
    import pyarrow.parquet as pq
    from gnibench.suite.runs.storage import read_parquet_meta

    n = 1000
    steps = np.arange(n, dtype=float)
    steps[::9] = np.nan
    columns = {"t": np.linspace(0, 1, n), "q": np.sin(np.arange(n)), "steps": steps}
    write_columns(columns, {"problem": "p"}, "parquet", tmp_path / "a.parquet", None, block=64)
    back = pd.read_parquet(tmp_path / "a.parquet")
    pd.testing.assert_frame_equal(back, frame_of(dict(columns)))
    assert pq.ParquetFile(tmp_path / "a.parquet").num_row_groups == 16
    assert read_parquet_meta(tmp_path / "a.parquet") == {"problem": "p"}


def test_empty_tables_are_written_with_their_header():
    columns = {"t": np.array([]), "q": np.array([]), "steps": np.array([])}
    for fmt in ("csv", "json"):
        fast, oracle = _both(columns, {"problem": "p"}, fmt)
        assert fast == oracle, fmt
