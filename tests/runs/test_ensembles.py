"""Ensemble cells: N initial conditions in one cell, run by one batched kernel.

Each orbit's row is the row of a single cell of that initial condition, bit for bit; the tables
are the same bytes under -j 1, -j 2 and Dask, on a problem the suite does not ship (a TOML user
problem); the statistics are recomputed here from the per-orbit rows alone; the initial sets are
reproducible and a shell lies on its level set; a run killed mid-record resumes to the same
tables; bad ensembles are refused in one line."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cell.cellspec import build
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.params import Bound
from gnibench.suite.runs.cellwork import run_cell
from gnibench.suite.runs.experiment import parse_experiment
from support import three_executors

TABLES = ("samples.parquet", "cells.parquet", "ensemble.parquet", "ensemble_stats.parquet")

DEFINITIONS = """
[[problem]]
id = "quartic-coupled"
title = "two oscillators coupled by q1^2 q2^2 (no exact solution)"
reference = "a test of ensembles on a problem the suite does not ship"
states = ["q1", "q2", "p1", "p2"]
hamiltonian = "(p1^2 + p2^2)/2 + (q1^2 + q2^2)/2 + q1^2*q2^2"
initial = {q1 = 0.5, q2 = 0.0, p1 = 0.0, p2 = 0.5}
"""

USER = """
name = "user-ensemble"
title = "an ensemble on a user problem"
reference = "tests"
load = ["defs.toml"]
t_end = 20.0
reference_solution = "heyoka"

[[cells]]
problems = ["quartic-coupled"]
methods = ["dop853:rtol=1e-9,atol=1e-9,dt_out=2.0", "rk4:h=0.05", "euler:h=0.4"]
every = 40
[cells.ensemble]
options = ["q10", "q20", "p10", "p20"]
sample = "shell"
level = { H = 0.6 }
low = [-0.8, -0.8, -0.8, -0.8]
high = [0.8, 0.8, 0.8, 0.8]
n = 40
seed = 7
chunk = 16
keep = [0, 17, 39]
"""

PENDULUM = """
name = "pendulum-ensemble"
title = "orbits against single cells"
reference = "tests"
t_end = 6.0
every = 50

[[cells]]
problems = ["pendulum"]
methods = ["rk4:h=0.02", "dop853:rtol=1e-9,atol=1e-9", "dopri5:rtol=1e-8,atol=1e-8,dt_out=0.5",
           "rk4:h=0.02+observer:theta=5", "implicit-midpoint:h=0.05", "scipy-rk45:rtol=1e-7,atol=1e-7"]
metrics = ["growth:of=H"]
[cells.ensemble]
options = ["q0", "p0"]
sample = "box"
low = [-1.0, -1.0]
high = [1.0, 1.0]
n = 5
seed = 3
chunk = 2
keep = 2
"""


def _tables(out: Path) -> dict[str, bytes]:
    return {name: (out / name).read_bytes() for name in TABLES}


@pytest.fixture(scope="module")
def user(tmp_path_factory) -> Path:
    """The user experiment and its definitions (one file: a problem id is defined once per
    process)."""
    root = tmp_path_factory.mktemp("user")
    (root / "defs.toml").write_text(DEFINITIONS)
    path = root / "user.toml"
    path.write_text(USER)
    return path


def test_each_orbit_is_the_single_cell_of_its_initial_condition():
    """Fixed step, adaptive (final point only), a time grid, a modifier whose H0 is the orbit's,
    an implicit method, scipy (orbit by one, not batched), a chosen metric: the orbit's row and
    kept samples are those of a cell of that initial condition."""
    exp = parse_experiment(PENDULUM, "pendulum.toml")
    from gnibench.suite.runs.ensemble_tables import merge
    from gnibench.suite.runs.runner import work_units
    from gnibench.suite.runs.store import Part

    for cell in exp.cells:
        units = work_units(cell)
        assert len(units) == 3                                   # 5 orbits, chunks of 2
        outcomes = [run_cell(u) for u in units]
        part = merge(cell, [Part(o.samples, o.row, o.timing, o.state_names, o.orbits)
                            for o in outcomes])
        orbits = pd.DataFrame(part.orbits)
        assert list(orbits["orbit"]) == [0, 1, 2, 3, 4]
        adaptive = cell.spec.method.base.values.get("adaptive") and cell.spec.dt_out is None
        for i in range(5):
            r = orbits.iloc[i]
            values = {**cell.spec.problem.values, "q0": float(r.q0), "p0": float(r.p0)}
            every = 10 ** 9 if adaptive else cell.spec.every     # t = 0 and the end only
            spec = build(Bound(cell.spec.problem.record, values), cell.spec.method,
                         t_end=cell.spec.t_end, every=every, dt_out=cell.spec.dt_out,
                         metrics=cell.spec.metrics, prepared=True)
            single = run_cell(replace(cell, spec=spec, ensemble=None))
            assert single.status == r.status
            growth = ("growth_exponent_H", "drift_H") if len(single.samples["t"]) >= 3 else ()
            for name in ("max_abs_err_H", "final_global_error", "max_global_error", "nfev",
                         "steps", "t_final") + growth:
                a, b = float(single.row[name]), float(r[name])
                assert a == b or (math.isnan(a) and math.isnan(b)), (cell.method, i, name)
            if i < 2:                                         # keep = 2: orbits 0 and 1
                mine = {k: v[part.samples["orbit"] == i] for k, v in part.samples.items()}
                for name, values in single.samples.items():
                    assert np.array_equal(mine[name], values, equal_nan=True), (cell.method, name)


def test_user_problem_tables_are_identical_whatever_runs_them(tmp_path, user):
    """-j 1, -j 2 and a 2-worker Dask LocalCluster: the same bytes."""
    pytest.importorskip("distributed")
    outs = three_executors(user, tmp_path)
    assert _tables(outs["pool"]) == _tables(outs["serial"])
    assert _tables(outs["dask"]) == _tables(outs["serial"])
    _check_statistics(outs["serial"])


def _check_statistics(out: Path) -> None:
    """The statistics and the cells' medians, recomputed from ensemble.parquet alone."""
    orbits = pd.read_parquet(out / "ensemble.parquet")
    stats = pd.read_parquet(out / "ensemble_stats.parquet")
    cells = pd.read_parquet(out / "cells.parquet")
    assert (orbits.groupby("cell").size() == 40).all()
    assert orbits["euler" == orbits["method"].str[:5]]["status"].ne("ok").any()  # some fail
    states = ["q1", "q2", "p1", "p2"]
    skip = {"cell", "problem", "method", "orbit", "status", "reason", "t_failed"}
    skip |= {f"{s}0" for s in states} | {f"final_{s}" for s in states}
    measured = [c for c in orbits.columns if c not in skip]
    assert {"max_abs_err_H", "final_global_error", "max_global_error", "nfev"} <= set(measured)
    for cell, group in orbits.groupby("cell"):
        for name in measured:
            v = group[name].to_numpy(dtype=float)
            failed = (group["status"] != "ok").to_numpy() | ~np.isfinite(v)
            counted = np.where(failed, np.inf, v)
            row = stats[(stats["cell"] == cell) & (stats["metric"] == name)].iloc[0]
            assert row["failed"] == failed.sum() and row["failure_rate"] == failed.mean()
            for label, q in (("q10", 0.1), ("median", 0.5), ("q90", 0.9)):
                with np.errstate(invalid="ignore"):
                    expect = np.quantile(counted, q)        # inf - inf -> nan: both are inf
                expect = np.inf if np.isnan(expect) else expect
                assert row[label] == expect, (cell, name, label)
            assert row["min"] == counted.min() and row["max"] == counted.max()
            if name not in ("steps", "samples"):
                assert cells.loc[cells["cell"] == cell, name].iloc[0] == row["median"]
        c = cells[cells["cell"] == cell].iloc[0]
        assert c["orbits"] == 40 and c["failed_orbits"] == (group["status"] != "ok").sum()
    kept = pd.read_parquet(out / "samples.parquet")
    assert sorted(kept.groupby(["cell", "orbit"]).size().index.get_level_values(1).unique()) == \
        [0, 17, 39]


def test_shell_points_lie_on_their_level_set_and_come_from_the_seed(user):
    from gnibench.problems.codegen import python_functions

    text = USER
    first = parse_experiment(text, "u.toml", base=user.parent).cells[0].ensemble
    again = parse_experiment(text, "u.toml", base=user.parent).cells[0].ensemble
    other = parse_experiment(text.replace("seed = 7", "seed = 8"), "u.toml",
                             base=user.parent).cells[0].ensemble
    assert first.points.tobytes() == again.points.tobytes()
    assert not np.array_equal(first.points, other.points)
    cell = parse_experiment(text, "u.toml", base=user.parent).cells[0]
    fns = python_functions(cell.spec.problem.record)
    for y in first.points:
        assert abs(fns["integral_0"](tuple(y), ()) - 0.6) <= 8 * 2.2e-16
    box = parse_experiment(text.replace('"shell"', '"box"').replace("level = { H = 0.6 }\n", ""),
                           "u.toml", base=user.parent).cells[0].ensemble
    rng = np.random.Generator(np.random.PCG64(7))
    assert np.array_equal(box.points, -0.8 + 1.6 * rng.random((40, 4)))


def test_a_run_killed_mid_record_resumes_to_the_same_tables(tmp_path, capsys):
    exp = tmp_path / "p.toml"
    exp.write_text(PENDULUM)
    whole, killed = tmp_path / "whole", tmp_path / "killed"
    assert main(["run", str(exp), "-o", str(whole), "-j", "1", "--no-report"]) == 0
    assert main(["run", str(exp), "-o", str(killed), "-j", "1", "--no-report"]) == 0
    segment = max((killed / "parts").glob("*.seg"))
    raw = segment.read_bytes()
    segment.write_bytes(raw[:len(raw) - 200])                  # the last record cut short
    for name in TABLES:
        (killed / name).unlink()
    capsys.readouterr()
    assert main(["run", str(exp), "-o", str(killed), "-j", "1", "--no-report"]) == 0
    assert "6 cells in 18 units -> " in capsys.readouterr().err
    assert _tables(killed) == _tables(whole)


def test_points_sets_are_ensemble_cells_with_every_orbit_kept():
    from gnibench.suite.runs.experiment import load_experiment

    exp = load_experiment("hlw-fig-1.3")
    assert len(exp.cells) == 6
    assert all(c.ensemble.total == 56 and len(c.ensemble.keep) == 56 for c in exp.cells)
    assert exp.cells[0].problem == "pendulum"


@pytest.mark.parametrize("patch,message", [
    (("options = [\"q0\", \"p0\"]", "options = [\"x0\", \"p0\"]"), "'x0' is not an initial value"),
    (("low = [-1.0, -1.0]", "low = [1.0, -1.0]"), "allowed: low < high"),
    (("high = [1.0, 1.0]\n", ""), 'sample = "box" needs high'),
    (("sample = \"box\"", "sample = \"shell\"\nlevel = { E = 1.0 }"), "pendulum has no integral 'E'"),
    (("keep = 2", "keep = [9]"), "orbit 9 does not exist"),
    (("n = 5", "n = 0"), "bad n = 0"),
])
def test_bad_ensembles_are_one_line(tmp_path, capsys, patch, message):
    exp = tmp_path / "bad.toml"
    exp.write_text(PENDULUM.replace(*patch))
    assert main(["run", str(exp), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "out").exists()


def test_quantiles_count_failures_as_infinite():
    from gnibench.suite.runs.ensemble_tables import quantile

    rng = np.random.default_rng(1)
    for n in (1, 2, 7, 10, 101):
        v = rng.random(n)
        for q in (0.1, 0.5, 0.9):
            assert quantile(v, q) == np.quantile(v, q)
    assert quantile([1.0, 2.0, np.inf], 0.5) == 2.0
    assert quantile([1.0, 2.0, np.inf], 0.9) == np.inf
    assert quantile([1.0, np.inf, np.inf], 0.9) == np.inf
