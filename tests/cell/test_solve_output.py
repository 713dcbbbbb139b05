"""``gnibench solve`` writes csv and json from the cell's columns (suite/runs/storage.py,
``write_columns``): the same text as pandas writes from the DataFrame, without importing pandas.

Compared byte for byte with ``write_frame`` (pandas' ``to_csv``) on cells of every kind of table
and on columns of edge values."""
from __future__ import annotations

import io
import subprocess
import sys

import numpy as np
import pytest
from gnibench.suite.runs.solving import solve_cell_spec, solve_output
from gnibench.suite.runs.storage import _plain, write_columns, write_frame
from gnibench.suite.runs.tables import frame_of

CELLS = [
    ("kepler-2d", "rk4:h=0.01", {"steps": 300, "every": 7}),
    ("kepler-2d", "dopri5:rtol=1e-8,atol=1e-8", {"t_end": 6.0, "metrics": ["global_error", "relative_invariant_error"]}),
    ("kepler-2d", "dop853", {"t_end": 3.0, "dt_out": 0.25}),
    ("henon-heiles", "rk4:h=0.05", {"t_end": 200.0, "section": 4}),
    ("euler-so4", "lie-poisson:h=0.01", {"t_end": 30.0, "section": 3}),
    ("harmonic-oscillator", "scipy-dop853:rtol=1e-9,atol=1e-9", {"t_end": 2.0}),
]


def _both(columns, meta, fmt):
    fast, slow = io.StringIO(), io.StringIO()
    write_columns(columns, meta, fmt, None, fast)
    write_frame(frame_of(columns), meta, fmt, None, slow)
    return fast.getvalue(), slow.getvalue()


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
