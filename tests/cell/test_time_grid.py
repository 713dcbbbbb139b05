"""Samples on a time grid for every compiled method (suite/cell/timegrid.py): ``dt_out``.

Checked against exact solutions (Kepler's equation), against one step of the method itself, and
against the run without the grid (the steps must be the same, bit for bit).
"""
from __future__ import annotations

import io
import math

import numpy as np
import pandas as pd
import pytest
from gnibench.methods import COMPILED
from gnibench.suite.cell import driver
from gnibench.suite.cell.solve import solve
from gnibench.suite.cli.main import main
from support import per_family
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.global_error import global_errors
from gnibench.suite.runs.experiment import parse_experiment

PERIOD = 2 * math.pi          # kepler-2d: a = 1, mu = 1


def _enclosing_errors(plain, grid):
    """Global errors of the two step ends around each grid sample (the run without grid)."""
    after = np.maximum(np.searchsorted(plain.t, grid.t, side="left"), 1)
    err = global_errors(plain)
    return np.maximum(err[after - 1], err[after])


@pytest.mark.parametrize("method", ["rk4:h=0.01", "rkf45:rtol=1e-9,atol=1e-9",
                                    "odex:rtol=1e-9,atol=1e-9", "gauss4:h=0.03"])
def test_samples_at_multiples_of_the_period(method):
    """t_k = 2 pi k (h = 0.01 does not divide it): the samples are where the exact solution is at
    t_k, up to the method's own error there (measured: the error of the two enclosing step ends
    times 0.997-1.09), not the 1e-2 of the nearest step end; the steps are those without a grid."""
    plain = solve("kepler-2d", method, t_end=10 * PERIOD)
    grid = solve("kepler-2d", method, t_end=10 * PERIOD, dt_out=PERIOD)
    assert grid.status == "ok" and grid.provenance["time_grid"]["locator"] == "partial step"
    assert np.array_equal(grid.t[:-1], PERIOD * np.arange(10)) and grid.t[-1] == 10 * PERIOD
    assert np.all(global_errors(grid) <= 1.25 * _enclosing_errors(plain, grid) + 1e-13)
    # the same steps: counts and the final state bit for bit; partial steps only add to nfev
    assert (grid.steps[-1], grid.rejected[-1]) == (plain.steps[-1], plain.rejected[-1])
    assert np.array_equal(grid.y[-1], plain.y[-1]) and grid.nfev[-1] > plain.nfev[-1]


@pytest.mark.parametrize("method,fixed", [("rk4:h=0.01", "rk4"),
                                          ("rkf45:rtol=1e-9,atol=1e-9", "rkf45:adaptive=false")])
def test_partial_step_is_one_step_of_the_method(method, fixed):
    """The sample at t_k is one step of size t_k - t_n from the accepted point y_n, bit for bit,
    and nfev counts it (rk4: 4, rkf45: 5 evaluations beside f(y_n))."""
    plain = solve("kepler-2d", method, t_end=3 * PERIOD)
    grid = solve("kepler-2d", method, t_end=3 * PERIOD, dt_out=PERIOD)
    for k in (1, 2):
        n = int(grid.steps[k]) - 1                     # the step (t_n, t_n+1] holding t_k
        assert plain.steps[n] == n and plain.t[n] < grid.t[k] < plain.t[n + 1]
        y = {s: float(v) for s, v in zip(plain.state_names, plain.y[n])}
        sigma = float(grid.t[k] - plain.t[n])
        one = solve("kepler-2d:" + ",".join(f"{s}0={v!r}" for s, v in y.items()),
                    f"{fixed}{',' if ':' in fixed else ':'}h={sigma!r}", steps=1)
        assert np.array_equal(one.y[-1], grid.y[k])
    per_step = 4.0 if method.startswith("rk4") else 5.0
    assert grid.nfev[-1] - plain.nfev[-1] == 2 * per_step


def _fixed_spec(mid: str, h: float) -> str:
    """Fixed steps of size h, with plain sums (under sum=compensated a step also adds the carried
    rounding error of y, which a restart from the rounded y_n does not have)."""
    names = {p.name for p in COMPILED[mid].params}
    return (f"{mid}:" + ("adaptive=false," if "adaptive" in names else "")
            + ("sum=plain," if "sum" in names else "") + f"h={h!r}")


@pytest.mark.parametrize("mid", per_family(sorted(COMPILED)))
def test_every_compiled_method_samples_by_its_own_step(mid):
    """Registry-wide: h = 0.03, dt_out = 0.1: the samples at t = 0.1, 0.2 are one step of the
    method itself (fixed-step mode) of size t_k - t_n from the accepted point y_n, bit for bit;
    t = 0.3 is the end of step 10 (no partial step)."""
    problem = "euler-so4" if mid == "lie-poisson" else "kepler-2d"
    plain = solve(problem, _fixed_spec(mid, 0.03), steps=12)
    grid = solve(problem, _fixed_spec(mid, 0.03), steps=12, dt_out=0.1)
    assert grid.status == "ok" and grid.steps.tolist() == [0, 4, 7, 10, 12]
    assert np.array_equal(grid.y[3], plain.y[10]) and np.array_equal(grid.y[-1], plain.y[-1])
    for k in (1, 2):
        n = int(grid.steps[k]) - 1
        y = ",".join(f"{s}0={float(v)!r}" for s, v in zip(plain.state_names, plain.y[n]))
        one = solve(f"{problem}:{y}", _fixed_spec(mid, float(grid.t[k] - plain.t[n])), steps=1)
        assert np.array_equal(one.y[-1], grid.y[k]), k


def test_grid_points_on_step_ends_are_the_step_ends():
    """h = 0.01 and dt_out = 0.1: every t_k is a step end to a few ulps; no partial step."""
    plain = solve("kepler-2d", "rk4:h=0.01", t_end=5.0, every=10)
    grid = solve("kepler-2d", "rk4:h=0.01", t_end=5.0, dt_out=0.1)
    assert np.array_equal(grid.y, plain.y) and np.array_equal(grid.nfev, plain.nfev)
    assert np.array_equal(grid.t[:-1], 0.1 * np.arange(50))


@pytest.mark.parametrize("method", ["rk4:h=0.001", "dop853:rtol=1e-11,atol=1e-11",
                                    "odex:rtol=1e-11,atol=1e-11", "gauss4:h=0.002"])
def test_ks_grid_is_in_physical_time(method):
    """K-S (fictitious time s): the grid is in the physical time t, the state component t of the
    transformed system, located by the secant method on the partial step size (dense output:
    Newton on θ) to round-off (measured: 0 ulps for rk4 and dop853, <= 1 for gauss4, <= 3 for
    odex, whose extrapolated t(sigma) is noisy at that level); the samples are on the exact
    Kepler orbit within the method's error (at most the largest error of the run's own steps)."""
    plain = solve("kepler-3d:ks=true", method, t_end=3.0)
    r = solve("kepler-3d:ks=true", method, t_end=3.0, dt_out=0.25)
    grid = r.provenance["time_grid"]
    assert r.status == "ok" and grid["time"] == "t"
    assert grid["locator"] == ("dense output" if "dop853" in method else "partial step")
    tk = 0.25 * np.arange(len(r.t) - 1)
    assert len(tk) == 12                                   # 3 revolutions, Δs = 1 each
    assert np.all(np.abs(r.t[:-1] - tk) <= 4 * np.spacing(tk))
    assert np.max(global_errors(r)) <= np.max(global_errors(plain))
    assert (r.steps[-1], r.rejected[-1]) == (plain.steps[-1], plain.rejected[-1])
    assert np.array_equal(r.y[-1], plain.y[-1])


@pytest.mark.parametrize("problem,method,kw", [
    ("kepler-2d", "rk4:h=0.2", {"t_end": 10.0}),
    ("kepler-2d", "rkf45:rtol=1e-8,atol=1e-8", {"t_end": 10.0}),
    ("kepler-2d", "dop853:rtol=1e-9,atol=1e-9", {"t_end": 10.0}),
    ("kepler-2d", "odex:rtol=1e-9,atol=1e-9", {"t_end": 10.0}),
    ("kepler-3d:ks=true", "rk4:h=0.05", {"steps": 40}),
    ("kepler-3d:ks=true", "dop853:rtol=1e-10,atol=1e-10", {"t_end": 2.0}),
])
def test_grid_resumable_whatever_the_buffer_and_budget(monkeypatch, problem, method, kw):
    """Three-row output buffers (a step whose samples do not fit is redone by the next call) and
    one step per call give the same samples, bit for bit."""
    dt_out = 0.07 if problem == "kepler-2d" else 0.02
    big = solve(problem, method, dt_out=dt_out, every=2, **kw)
    monkeypatch.setattr(driver, "GRID_ROWS", 3)
    monkeypatch.setattr(driver, "ADAPTIVE_CHUNK", 3)
    tiny = solve(problem, method, dt_out=dt_out, every=2, budget=1, **kw)
    assert tiny.provenance["time_grid"]["steps_redone"] > 0 and len(big.t) > 20
    for a, b in [(big.t, tiny.t), (big.y, tiny.y), (big.steps, tiny.steps), (big.nfev, tiny.nfev),
                 (big.rejected, tiny.rejected)]:
        assert np.array_equal(a, b)


def test_method_option_and_argument_agree_or_are_refused():
    a = solve("kepler-2d", "dop853:rtol=1e-10,atol=1e-10,dt_out=0.5", t_end=2.2)
    b = solve("kepler-2d", "dop853:rtol=1e-10,atol=1e-10", t_end=2.2, dt_out=0.5)
    c = solve("kepler-2d", "dop853:rtol=1e-10,atol=1e-10,dt_out=0.5", t_end=2.2, dt_out=0.5)
    assert a.t.tolist() == [0.0, 0.5, 1.0, 1.5, 2.0, 2.2]
    assert np.array_equal(a.y, b.y) and np.array_equal(a.y, c.y)
    assert a.provenance["time_grid"]["locator"] == "dense output"
    with pytest.raises(UserError, match="conflicting dt_out") as e:
        solve("kepler-2d", "dop853:dt_out=0.5", t_end=2.2, dt_out=0.25)
    assert "\n" not in str(e.value)
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(UserError, match="bad dt_out="):
            solve("kepler-2d", "rk4", t_end=1.0, dt_out=bad)
    with pytest.raises(UserError, match="does not apply with section "):
        solve("henon-heiles", "rk4", t_end=1.0, dt_out=0.1, section=2)


def test_external_engine_grid_is_its_dt_out():
    r = solve("kepler-2d", "heyoka-taylor", t_end=1.0, dt_out=0.25)
    assert r.t.tolist() == [0.0, 0.25, 0.5, 0.75, 1.0] and "dt_out=0.25" in r.method
    assert np.max(global_errors(r)) <= 1e-13
    with pytest.raises(UserError, match="conflicting dt_out"):
        solve("kepler-2d", "heyoka-taylor:dt_out=0.5", t_end=1.0, dt_out=0.25)
    with pytest.raises(UserError, match="fixed-step"):
        solve("outer-solar-system", "rebound-whfast", t_end=1.0, dt_out=0.25)


def test_cli_dt_out(capsys):
    code = main(["solve", "kepler-2d", "rk4:h=0.01", "--t-end", "1", "--dt-out", "0.3"])
    out, err = capsys.readouterr()
    assert code == 0, err
    d = pd.read_csv(io.StringIO(out))
    assert d.t.tolist() == [*(0.3 * np.arange(4)), 1.0] and d.global_error.max() <= 1e-6
    code = main(["solve", "henon-heiles", "rk4", "--t-end", "1", "--dt-out", "0.3",
                 "--section", "2"])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and len(err.splitlines()) == 1


EXPERIMENT = """
name = "grid"
title = "grid"
reference = "test"
t_end = 1.0
dt_out = 0.25
[[cells]]
methods = ["rk4:h=0.01", "dop853"]
problems = ["kepler-2d"]
[[cells]]
methods = ["rk4:h=0.01"]
problems = ["kepler-2d"]
dt_out = 0.5
"""


def test_experiment_key():
    e = parse_experiment(EXPERIMENT, "grid.toml")
    assert [c.dt_out for c in e.cells] == [0.25, 0.25, 0.5]
    assert [c.method for c in e.cells] == ["rk4:h=0.01", "dop853:adaptive=true,rtol=1e-06,atol=1e-06",
                                           "rk4:h=0.01"]          # the specs stay as written
    with pytest.raises(UserError, match=r"bad dt_out = -1"):
        parse_experiment(EXPERIMENT.replace("dt_out = 0.5", "dt_out = -1"), "grid.toml")
    with pytest.raises(UserError, match="conflicting dt_out"):
        parse_experiment(EXPERIMENT.replace('"dop853"', '"dop853:dt_out=0.1"'), "grid.toml")
