"""``gnibench solve`` makes and writes its table block by block (suite/runs/streaming.py): the same
bytes as the whole-table path, one block in memory at a time.

The block size is lowered to 7 rows so that every cell crosses many block boundaries (of the
driver's buffer, of the table and of the writers). The metadata's timings (wall and compile
seconds, the reference's seconds) differ between any two runs and are set to 0 before writing;
everything else is compared byte for byte.
"""
from __future__ import annotations

import io

import numpy as np
import pytest
from gnibench.suite.runs import spool as spool_module
from gnibench.suite.runs import streaming
from gnibench.suite.runs.solving import solve_cell_spec, solve_output
from gnibench.suite.runs.spool import SpooledColumn
from gnibench.suite.runs.writers import write_columns

BLOCK = 7
TIMINGS = {"wall_seconds", "compile_seconds", "seconds", "numba_cache_misses"}

CELLS = [
    ("kepler-2d", "rk4:h=0.01", {"steps": 400, "every": 3}),                 # fixed step
    ("kepler-2d:e=0.9", "dopri5:rtol=1e-7,atol=1e-7", {"t_end": 30.0}),      # adaptive
    ("kepler-2d", "dop853", {"t_end": 4.0, "dt_out": 0.05}),                  # dense output grid
    ("kepler-2d", "rk4:h=0.01", {"t_end": 3.0, "dt_out": 0.07}),             # partial steps
    ("kepler-3d:ks=true", "rk4:h=0.01", {"steps": 600, "every": 2}),         # K-S, mapped back
    ("kepler-2d", "rk4:h=0.01+observer:on=H/L",
     {"steps": 200, "metrics": "relative_invariant_error"}),                   # a modifier
    ("pendulum", "stormer-verlet:h=0.1", {"steps": 90}),
    ("henon-heiles", "rk4:h=0.1", {"steps": 60}),                             # no reference
]


@pytest.fixture(autouse=True)
def small_blocks(monkeypatch):
    monkeypatch.setattr(streaming, "BLOCK", BLOCK)


def _timeless(meta):
    if isinstance(meta, dict):
        return {k: 0 if k in TIMINGS else _timeless(v) for k, v in meta.items()}
    return meta


def _written(out, fmt, tmp_path, name) -> bytes:
    meta = _timeless(out.meta)
    if fmt == "parquet":
        path = tmp_path / f"{name}.parquet"
        write_columns(out.columns, meta, fmt, path, None, block=5)
        return path.read_bytes()
    f = io.StringIO()
    write_columns(out.columns, meta, fmt, None, f, block=5)
    return f.getvalue().encode()


def _outputs(cell, tmp_path):
    whole = solve_output(cell)
    directory = tmp_path / "spool"
    directory.mkdir()
    streamed = solve_output(cell, spool=directory)
    return whole, streamed


@pytest.mark.parametrize("problem, method, options", CELLS)
def test_the_streamed_table_has_the_bytes_of_the_whole_table(problem, method, options, tmp_path):
    cell = solve_cell_spec(problem, method, **options)
    assert streaming.streamable(cell)
    whole, streamed = _outputs(cell, tmp_path)
    assert all(isinstance(c, SpooledColumn) for c in streamed.columns.values())
    assert len(whole.traj.t) > 3 * BLOCK
    for fmt in ("csv", "json", "parquet"):
        assert _written(streamed, fmt, tmp_path, "s") == _written(whole, fmt, tmp_path, "w"), fmt
    assert repr(streamed.metrics.scalars) == repr(whole.metrics.scalars)     # NaN as nan
    assert (streamed.traj.status, streamed.traj.reason) == (whole.traj.status, whole.traj.reason)
    assert streamed.skipped == whole.skipped


def test_the_row_budget_counts_the_rows_written_with_the_same_reason(tmp_path, monkeypatch):
    monkeypatch.setenv("GNIBENCH_MAX_ROWS", "50")
    cell = solve_cell_spec("kepler-2d", "dopri5:rtol=1e-9,atol=1e-9", t_end=50.0)
    whole, streamed = _outputs(cell, tmp_path)
    assert str(streamed.traj.status) == "max_rows" and "after 50 rows" in streamed.traj.reason
    assert streamed.traj.reason == whole.traj.reason
    assert len(next(iter(streamed.columns.values()))) == len(whole.traj.t) == 50
    assert _written(streamed, "csv", tmp_path, "s") == _written(whole, "csv", tmp_path, "w")


def test_the_driver_hands_over_blocks_of_at_most_the_block_size_in_one_reused_buffer(
        tmp_path, monkeypatch):
    seen = []
    hand_over = spool_module.RawSpool.__call__

    def watched(self, t, y, c):
        seen.append((len(t), t.__array_interface__["data"][0], y.__array_interface__["data"][0]))
        hand_over(self, t, y, c)

    monkeypatch.setattr(spool_module.RawSpool, "__call__", watched)
    for k, (problem, method, options) in enumerate(CELLS[:2] + CELLS[3:4]):   # a step's rows
        seen.clear()                                                            # fit a block
        cell = solve_cell_spec(problem, method, **options)
        directory = tmp_path / str(k)
        directory.mkdir()
        out = solve_output(cell, spool=directory)
        rows = len(next(iter(out.columns.values())))
        assert len(seen) >= rows // BLOCK > 3 and sum(n for n, _, _ in seen) == rows
        assert max(n for n, _, _ in seen) <= BLOCK
        assert len({(t, y) for _, t, y in seen}) == 1        # always the same buffer


def test_ctrl_c_keeps_the_rows_streamed_so_far(tmp_path, monkeypatch):
    calls = []
    hand_over = spool_module.RawSpool.__call__

    def interrupted(self, t, y, c):
        hand_over(self, t, y, c)
        calls.append(len(t))
        if len(calls) == 3:
            raise KeyboardInterrupt

    cell = solve_cell_spec("kepler-2d", "rk4:h=0.01", steps=300)
    whole = solve_output(cell)
    monkeypatch.setattr(spool_module.RawSpool, "__call__", interrupted)
    directory = tmp_path / "spool"
    directory.mkdir()
    out = solve_output(cell, spool=directory)
    rows = sum(calls)
    assert out.interrupted is not None and str(out.traj.status) == "interrupted"
    t = out.columns["t"][:]
    assert len(t) == rows > 0 and np.array_equal(t, whole.columns["t"][:rows])
    assert np.array_equal(out.columns["err_H"][:], whole.columns["err_H"][:rows])
    assert out.traj.reason == f"interrupted by the user at t = {t[-1]:.17g}"
    assert "global_error" not in out.columns     # no reference after Ctrl-C, as in memory


@pytest.mark.parametrize("problem, method, options", [
    ("henon-heiles", "rk4:h=0.05", {"t_end": 100.0, "section": 3}),          # crossings
    ("harmonic-oscillator", "scipy-dop853:rtol=1e-9,atol=1e-9", {"t_end": 2.0}),
    ("kepler-2d", "rk4:h=0.01", {"steps": 100, "metrics": "growth:of=H"}),
])
def test_cells_that_need_the_whole_series_keep_the_whole_table(problem, method, options,
                                                               tmp_path):
    cell = solve_cell_spec(problem, method, **options)
    assert not streaming.streamable(cell)
    out = solve_output(cell, spool=tmp_path)
    assert all(isinstance(c, np.ndarray) for c in out.columns.values())
    assert not list(tmp_path.iterdir())


def test_the_spool_of_a_killed_solve_is_removed_by_the_next(tmp_path, monkeypatch):
    import subprocess
    import sys

    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr(streaming.tempfile, "tempdir", None)     # TMPDIR read again
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    orphan = tmp_path / f"{streaming.SPOOL_PREFIX}{dead}-x"
    alive = tmp_path / f"{streaming.SPOOL_PREFIX}{__import__('os').getpid()}-y"
    orphan.mkdir()
    alive.mkdir()
    cell = solve_cell_spec("kepler-2d", "rk4:h=0.01", steps=20)
    with streaming.spool_directory(cell) as d:
        assert d.parent == tmp_path and d.name.startswith(streaming.SPOOL_PREFIX)
    assert not orphan.exists() and alive.exists() and not d.exists()
