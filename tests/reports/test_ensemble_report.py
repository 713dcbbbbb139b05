"""Statistical work-precision of ensembles: the league by the cost to reach ε for a share of the
orbits (recomputed here from the orbits), through the API and on the report page."""
from __future__ import annotations

import numpy as np
import pytest

EXPERIMENT = {
    "name": "ens-league", "title": "ensemble league", "reference": "tests", "t_end": 5.0,
    "cells": [{"problems": ["pendulum"],
               "methods": ["dopri5", "dop853"],
               "vary": {"rtol": [1e-5, 1e-7, 1e-9], "atol": [1e-5, 1e-7, 1e-9]},
               "zip": ["rtol", "atol"],                 # a paired sweep: one family per method
               "ensemble": {"options": ["q0", "p0"], "sample": "box", "n": 24, "seed": 2,
                            "low": [-2.5, -1.0], "high": [2.5, 1.0]}}],
}


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    import gnibench

    return gnibench.run(EXPERIMENT, output=tmp_path_factory.mktemp("ens") / "out", jobs=1)


def test_run_result_has_the_orbits_and_their_statistics(result):
    assert len(result.ensemble) == 6 * 24
    assert set(result.ensemble_stats["metric"]) >= {"max_global_error", "nfev", "steps"}
    assert "orbits" in repr(result)


@pytest.mark.parametrize("share", [0.5, 0.9, 1.0])
def test_league_by_the_cost_for_a_share_of_the_orbits(result, share):
    """Recomputed from the orbits: each cell's share-quantile error and mean nfev per orbit;
    the family's cost is the cheapest cell reaching eps, or the log-log interpolation with the
    one before it."""
    eps = 1e-6
    league = result.ensemble_league(eps, share=share)
    assert list(league["rank"]) == sorted(league["rank"])
    orbits, cells = result.ensemble, result.cells
    for fam, part in cells.groupby("family"):
        pts = []
        for c in part["cell"]:
            g = orbits[orbits["cell"] == c]
            err = np.where(g["status"] == "ok", g["max_global_error"], np.inf)
            with np.errstate(invalid="ignore"):
                q = np.quantile(err, share)
            pts.append((g["nfev"].mean(), np.inf if np.isnan(q) else q))
        pts.sort()
        hit = next(i for i, (_, e) in enumerate(pts) if e <= eps)
        (c0, e0), (c1, e1) = pts[max(hit - 1, 0)], pts[hit]
        expect = c1 if hit == 0 else float(np.exp(np.log(c0) + (np.log(eps) - np.log(e0)) / (
            np.log(e1) - np.log(e0)) * (np.log(c1) - np.log(c0))))
        got = league.loc[league["family"] == fam, "nfev"].iloc[0]
        assert got == pytest.approx(expect, rel=1e-12), fam


def test_bad_league_arguments_are_one_line(result):
    import gnibench

    with pytest.raises(gnibench.UserError, match="0 < share <= 1"):
        result.ensemble_league(1e-6, share=1.5)
    with pytest.raises(gnibench.UserError, match="bad measure"):
        result.ensemble_league(1e-6, measure="nope")


def test_the_report_page_shows_the_ensembles(result, tmp_path):
    import gnibench

    index = gnibench.report([result.output], tmp_path / "site")
    page = (index.parent / "ens-league.html").read_text()
    assert "<h3>Ensembles</h3>" in page and "24 initial conditions" in page
    images = list((index.parent / "img").rglob("*ensemble-work-precision.png"))
    assert len(images) == 1 and images[0].stat().st_size > 10_000


def test_the_plot_helper_draws_the_median_band_and_failure_rate(result):
    import gnibench

    fig = gnibench.plot.ensemble_work_precision(result)
    left, right = fig.axes
    assert left.get_xscale() == right.get_xscale() == "log" and left.get_yscale() == "log"
    assert [t.get_text() for t in left.get_legend().get_texts()] == ["dopri5", "dop853"]
    assert len(left.collections) == 2                        # one q10-q90 band per family
    medians = result.ensemble_stats.query("metric == 'max_global_error'")["median"].to_numpy()
    drawn = np.concatenate([line.get_ydata() for line in left.get_lines()])
    assert sorted(drawn) == sorted(medians)
    again = gnibench.plot.ensemble_work_precision(result.output)     # from the directory
    assert [t.get_text() for t in again.axes[0].get_legend().get_texts()] == ["dopri5", "dop853"]
