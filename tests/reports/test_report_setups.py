"""Reports that cannot mislead (issue 40): families keyed by their setup, orders only from the
asymptotic regime, saturated panels said so, the reference's accuracy, plots a reader controls.

The fixture is the issue's case: the planar restricted three-body problem (Arenstorf orbit,
HNW I, II.0, defined in TOML here, not shipped) over one period and over ten, a paired tolerance
sweep of DOP853 and DOPRI5 at both horizons, an RK4 step sweep, one classic-test cell with another
atol, and a heyoka reference in double precision. Over ten periods the unstable orbit is lost:
every global error is of the order of the solution.
"""
from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest
from gnibench.reports.site import build_site

T = 17.0652165601579625588917206249
DEFS = f'''
[[problem]]
id = "arenstorf-test"
title = "planar restricted three-body problem, rotating frame (Arenstorf orbit)"
reference = "Arenstorf (1963); HNW I, II.0 (0.1)"
states = ["q1", "q2", "p1", "p2"]
hamiltonian = "(p1^2 + p2^2)/2 + q2*p1 - q1*p2 - (1 - mu)/sqrt((q1 + mu)^2 + q2^2) - mu/sqrt((q1 - 1 + mu)^2 + q2^2)"
parameters = {{mu = 0.012277471}}
initial = {{q1 = 0.994, q2 = 0.0, p1 = 0.0, p2 = -1.0075851063790825224}}
period = "{T}"
'''
EXPERIMENT = f'''
name = "arenstorf-mixed"
title = "Arenstorf orbit over one and ten periods"
reference = "HNW I, II.0"
load = ["defs.toml"]
reference_solution = "heyoka:precision=double"
repeat = 2

[report]
target = 1e-5

[[cells]]
label = "one period"
problems = ["arenstorf-test"]
methods = ["dop853:max_steps=1000000", "dopri5:max_steps=1000000"]
t_end = {T}
every = 20
vary.rtol = [1e-6, 1e-8, 1e-10]
vary.atol = [1e-6, 1e-8, 1e-10]
zip = ["rtol", "atol"]

[[cells]]
label = "ten periods"
problems = ["arenstorf-test"]
methods = ["dop853:max_steps=1000000", "dopri5:max_steps=1000000"]
t_end = {10 * T}
every = 100
vary.rtol = [1e-6, 1e-8, 1e-10]
vary.atol = [1e-6, 1e-8, 1e-10]
zip = ["rtol", "atol"]

[[cells]]
label = "fixed step"
problems = ["arenstorf-test"]
methods = ["rk4"]
t_end = {T}
every = 200
metrics = ["order"]
vary.h = [0.004, 0.002, 0.001, 0.0005]

[[cells]]
label = "a classic test"
problems = ["arenstorf-test"]
methods = ["dop853:rtol=1e-8,atol=1e-12,max_steps=1000000"]
t_end = {T}
every = 20
'''


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    from gnibench.suite.cli.main import main
    from gnibench.suite.cell.user.loader import loaded, unload

    root = tmp_path_factory.mktemp("arenstorf")
    (root / "defs.toml").write_text(DEFS)
    (root / "exp.toml").write_text(EXPERIMENT)
    before = set(loaded())
    assert main(["run", str(root / "exp.toml"), "-o", str(root / "out"), "-j", "2"]) == 0
    for path in set(loaded()) - before:
        unload(path)
    return root / "out"


@pytest.fixture(scope="module")
def cells(run):
    from gnibench.reports.results import load_results
    from gnibench.reports.setups import add_setups

    return add_setups(load_results(run).cells)


def test_a_family_holds_one_setup(cells):
    """One family per method and horizon, the classic-test cell a family of its own (its atol
    is not the sweep's), each named by what tells it apart; a curve, a league row and an order
    fit never mix them."""
    from gnibench.reports.setups import contexts, family_names

    sizes = cells.groupby("setup")["cell"].count().to_dict()
    assert sorted(sizes.values()) == [1, 3, 3, 3, 3, 4]
    for _, part in cells.groupby("setup"):
        assert part["t_end"].nunique() == 1 and part["setup_method"].nunique() == 1
        assert part["family"].nunique() == 1
    names = family_names(cells)
    classic = int(cells.loc[cells["label"] == "a classic test", "setup"].iloc[0])
    assert names[classic] == "dop853 (T = 17.0652; atol=1e-12)"
    assert sorted(set(names.values())) == sorted([
        "dop853 (T = 17.0652; atol swept)", "dop853 (T = 170.652)", "dopri5 (T = 17.0652)",
        "dopri5 (T = 170.652)", "rk4", "dop853 (T = 17.0652; atol=1e-12)"])
    ctx = contexts(cells)
    assert [name for name, _ in ctx] == ["T = 17.0652", "T = 170.652"]
    assert all(part["t_end"].nunique() == 1 for _, part in ctx)
    one, _ = ctx[0][1], ctx[1][1]
    assert sorted(family_names(one).values()) == [
        "dop853 (atol swept)", "dop853 (atol=1e-12)", "dopri5", "rk4"]


def test_paired_sweep_gives_the_pairs(cells):
    sweep = cells[cells["label"] == "one period"]
    assert len(sweep) == 6 and set(sweep["swept"]) == {"rtol/atol"}
    for method in sweep["method"]:
        rtol = re.search(r"rtol=([^,]+)", method).group(1)
        assert f"atol={rtol}" in method
    assert set(sweep["swept_text"]) == {"rtol=atol=1e-06", "rtol=atol=1e-08",
                                        "rtol=atol=1e-10"}


def test_the_reference_is_checked_and_the_lost_orbit_saturates(cells, run):
    """Every cell records its reference's accuracy (heyoka in double against heyoka at a 100
    times looser tolerance); over ten periods every error is saturated, and the league tables
    and the work-precision caption say so instead of ranking."""
    from gnibench.reports.league import unrankable
    from gnibench.suite.metrics.regime import SATURATED, trusted

    assert (cells["max_reference_error"] > 0).all() and cells["max_reference_error"].notna().all()
    samples = pd.read_parquet(run / "samples.parquet", columns=["cell", "reference_error"])
    assert samples["reference_error"].notna().all()
    ten = cells[cells["t_end"] > 100]
    assert set(trusted(ten, "max_global_error")) == {SATURATED}
    assert "trajectory is lost" in unrankable(ten, "max_global_error", 1e-4)
    one = cells[cells["t_end"] < 100]
    assert unrankable(one, "max_global_error", 1e-4) == ""
    page = (run / "report" / "arenstorf-mixed.html").read_text()
    assert page.count("the trajectory is lost for every method") >= 3     # caption, ε = 1e-4, 1e-8
    assert "<b>ε = 1e-04</b>: every error is above the saturation level" in page


def test_no_order_from_noise(cells, run):
    """RK4's errors over one period at h = 0.004 ... 0.0005 (about 2, 2, 0.9, 0.05): the three
    coarse ones saturated (the orbit lost near the moon), one left: no order, and the same
    reason from the ``order`` metric (cells.parquet, the API) and in the report's league table,
    which fit the same family."""
    from gnibench.reports.league import family_order

    rk4 = cells[cells["family"] == "rk4"]
    order, why = family_order(rk4, "max_global_error")
    assert math.isnan(order)
    assert why == "1 of 4 points in the asymptotic regime, 3 needed (3 saturated)"
    assert rk4["order_global"].isna().all() and (rk4["order_reason_global"] == why).all()
    assert (rk4["order_family"] == rk4["setup"]).all()
    page = (run / "report" / "arenstorf-mixed.html").read_text()
    assert f"NA: {why}" in page


def test_league_rows_hold_one_context(run):
    page = (run / "report" / "arenstorf-mixed.html").read_text()
    tables = page.split("<h3>League tables")[1:]
    assert len(tables) == 2 and tables[0].startswith(" (T = 17.0652)")
    first = tables[0].split("</table>")[0]
    families = re.findall(r"<td><code>([^<]*)</code></td>", first)
    assert "dop853 (atol=1e-12)" in families and "dopri5" in families
    assert not any("170" in f for f in families)


def test_repeated_timings(run):
    timings = pd.read_parquet(run / "timings.parquet")
    ok = timings[timings["status"] == "ok"]
    assert (ok["repeats"] == 2).all()
    assert (ok["wall_seconds"] <= ok["wall_median_seconds"]).all()
    assert (ok["wall_spread"] >= 0).all()


def test_index_card_headline_and_thumbnail(run):
    index = (run / "report" / "index.html").read_text()
    assert re.search(r'class="headline">cheapest to reach max_global_error ≤ 1e-05 \(T = 17.0652\)'
                     r': [^<]+ f-evaluations</p>', index), index
    assert 'img class="thumb" src="img/arenstorf-mixed/00-' in index
    assert "work-precision.png" in index.split('img class="thumb"')[1].split(">")[0]


def test_report_options_choose_the_cells_and_axes(cells, run, tmp_path):
    """[report] keys from the API: the time plots of one family's sweep with a linear t axis;
    the work-precision diagram against nfev only."""
    from gnibench.reports.plots import time_plots
    from gnibench.reports.results import load_results

    samples = load_results(run).samples()
    plots = time_plots("arenstorf-test:mu=0.012277471", cells, samples,
                       options={"family": "rk4", "time_axis": "linear",
                                "figures": ["global-error"]})
    (name, plot, _, caption), = plots
    assert name == "global-error" and plot.panels[0].xscale == "linear"
    labels = [s.style["label"] for s in plot.panels[0].series]
    assert len(labels) == 4 and all(label.startswith("rk4 h=") for label in labels)
    assert "The cells of family rk4 (4)." in caption
    index = build_site([run], tmp_path / "site", plots={"costs": ["nfev"], "cells": [0, 1]})
    page = index.with_name("arenstorf-mixed.html").read_text()
    assert "Cells 0, 1, as chosen." in page


def test_one_style_per_family_across_a_report():
    """The palette: the first 20 families all differ in (colour, marker); a family keeps its
    style wherever it is met again; a second setup of one family differs in line style only."""
    from gnibench.reports.palette import Palette

    palette = Palette()
    looks = [(s["color"], s["marker"]) for s in (palette.of(f"m{k}") for k in range(20))]
    assert len(set(looks)) == 20
    assert len({c for c, _ in looks[:9]}) == 9
    assert palette.of("m3") == palette.of("m3")
    variant = palette.of("m3", 1)
    assert variant["color"] == palette.of("m3")["color"]
    assert variant["linestyle"] != palette.of("m3")["linestyle"]


def test_a_nondeterministic_cell_is_an_error(tmp_path, monkeypatch):
    """A repeated run that gives other numbers than the first is an error with one line."""
    import gnibench.suite.cell.driver as driver
    from gnibench.suite.runs.runner import run_experiment

    real = driver.integrate
    calls = {"n": 0}

    def shaky(cell, **kw):
        traj = real(cell, **kw)
        calls["n"] += 1
        if calls["n"] == 2:
            traj.y = traj.y.copy()
            traj.y[-1, 0] += 1e-15
        return traj

    monkeypatch.setattr(driver, "integrate", shaky)
    path = tmp_path / "e.toml"
    path.write_text('name = "shaky"\ntitle = "t"\nreference = "r"\nt_end = 1.0\nrepeat = 3\n'
                    '[[cells]]\nproblems = ["pendulum"]\nmethods = ["rk4:h=0.1"]\n')
    out = run_experiment(path, tmp_path / "out", jobs=1, log=open("/dev/null", "w"))  # noqa: SIM115
    row = pd.read_parquet(out / "cells.parquet").iloc[0]
    assert row["status"] == "error"
    assert row["reason"].startswith("NotRepeatable: run 2 of 3 differs from the first: y at "
                                    "sample 10")
    assert "\n" not in row["reason"]
    assert np.isnan(pd.read_parquet(out / "timings.parquet")["wall_seconds"].iloc[0])


def test_the_api_gives_the_same_tables_and_figures(run):
    """The held-out experiment through the API (``gnibench.run`` on the same file and output,
    its cells reused): the same cells table as ``gnibench run`` wrote, the order's NA with its
    reason, and the plot helpers' figures with one legend entry per family of a horizon."""
    import gnibench
    from gnibench.suite.cell.user.loader import loaded, unload

    before = set(loaded())
    try:
        res = gnibench.run(run.parent / "exp.toml", output=run, jobs=1)
    finally:
        for path in set(loaded()) - before:
            unload(path)
    disk = pd.read_parquet(run / "cells.parquet")
    pd.testing.assert_frame_equal(res.cells.reset_index(drop=True), disk.reset_index(drop=True))
    rk4 = res.cells[res.cells["base_method"] == "rk4"]
    assert rk4["order_global"].isna().all()
    assert rk4["order_reason_global"].str.contains("3 needed").all()
    fig = gnibench.plot.work_precision(res, horizon=T)
    labels = {t.get_text() for legend in fig.legends for t in legend.get_texts()}
    assert {"dopri5", "rk4", "dop853 (atol swept)", "dop853 (atol=1e-12)"} <= labels, labels
    assert not any("170" in label for label in labels)
    fig = gnibench.plot.global_error(res, family="rk4", time_axis="linear")
    assert fig.axes[0].get_xscale() == "linear"


def test_gnibench_plot_is_an_importable_module():
    """``import gnibench.plot`` and ``from gnibench.plot import ...`` work as the attribute
    does (the docs build imports the module to document it), and ``import gnibench`` stays
    without matplotlib."""
    import subprocess
    import sys

    code = ("import sys, gnibench\n"
            "assert 'matplotlib' not in sys.modules\n"
            "import gnibench.plot\n"
            "from gnibench.plot import global_error, invariant_errors, work_precision\n"
            "assert gnibench.plot.work_precision is work_precision\n"
            "print(sorted(gnibench.plot.__all__))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "['ensemble_work_precision', 'global_error', 'invariant_errors', 'work_precision']"
