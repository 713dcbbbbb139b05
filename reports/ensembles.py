"""Statistical work-precision of ensemble cells: error against cost over the orbits, and league
tables ranked by the cost to reach ε for a share of the orbits.

Read from the tables only (``cells.parquet``, ``ensemble.parquet``, ``ensemble_stats.parquet``,
``timings.parquet``; :mod:`gnibench.suite.runs.ensemble_tables`):

* **Diagram** (:func:`work_precision`): per method family (column ``family``; its sweep of h or
  tolerance), the median over the orbits of an error measure against the median cost (nfev per
  orbit), a band from the 10 % to the 90 % quantile of the error (a failed orbit counts as +inf:
  the band then reaches the top of the axes), and beside it the failure rate of that measure
  against the same cost.
* **League** (:func:`league`): the cost per orbit (mean nfev; mean wall time, ``timings``) at
  which a family's sweep first has error <= ε for ``share`` of its orbits (default 0.9), i.e.
  whose ``share``-quantile of the error (failed orbits as +inf) is <= ε, interpolated in log-log
  between the two cells of the sweep around ε as :func:`gnibench.reports.league.cost_to_reach`
  does for single cells; ranked by nfev, then wall time.
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.reports.league import Cost, LeagueRow, cost_to_reach, ranked

SHARE = 0.9
MEASURES = ("max_global_error", "final_global_error")


def measure_of(orbits, measure: str | None = None) -> str:
    """The error measure of a league or diagram: the given one, else the max global error, the
    final one, or the first integral's max error, whichever the orbits have."""
    if measure is not None:
        if measure not in orbits.columns:
            from gnibench.suite.foundation.errors import UserError

            raise UserError(f"bad measure {measure!r}; allowed: a column of ensemble.parquet, "
                            f"e.g. {', '.join(c for c in orbits.columns if 'err' in c)}")
        return measure
    for c in MEASURES:
        if c in orbits.columns and orbits[c].notna().any():
            return c
    return next((c for c in orbits.columns if c.startswith("max_abs_err_")), "")


def per_cell(orbits, measure: str, share: float = SHARE):
    """One row per ensemble cell: ``orbits``, ``failure_rate`` (of the measure), ``error`` (its
    ``share``-quantile, failed orbits as +inf), ``nfev`` (mean per orbit)."""
    import pandas as pd
    from gnibench.suite.runs.ensemble_tables import quantile

    rows = []
    for cell, g in orbits.groupby("cell", sort=True):
        v = g[measure].to_numpy(dtype=float)
        failed = (g["status"] != "ok").to_numpy() | ~np.isfinite(v)
        rows.append({"cell": int(cell), "orbits": len(g), "failure_rate": float(failed.mean()),
                     "error": quantile(np.where(failed, np.inf, v), share),
                     "nfev": float(np.nanmean(g["nfev"].to_numpy(dtype=float)))})
    return pd.DataFrame(rows, columns=["cell", "orbits", "failure_rate", "error", "nfev"])


def _families(cells):
    """The cells with the report's family columns (:func:`gnibench.reports.setups.add_setups`:
    a family is the cells of one setup, never a mix of horizons, references or options) and
    the name of each family by setup id."""
    from gnibench.reports.setups import add_setups, family_names

    if "setup" not in cells:
        cells = add_setups(cells)
    return cells, (family_names(cells) if len(cells) else {})


def league(cells, orbits, eps: float, share: float = SHARE, measure: str | None = None,
           wall_by_cell: dict | None = None) -> list[LeagueRow]:
    """The league of the ensemble cells of one problem (see the module docstring): one
    :class:`~gnibench.reports.league.LeagueRow` per family, ranked."""
    measure = measure_of(orbits, measure)
    stats = per_cell(orbits, measure, share).set_index("cell")
    ens, names = _families(cells[cells["cell"].isin(stats.index)])
    rows = []
    for setup, part in ens.groupby("setup", sort=False):
        ids = part["cell"].to_numpy(dtype=int)
        err = stats.loc[ids, "error"].to_numpy(dtype=float)
        nfev = stats.loc[ids, "nfev"].to_numpy(dtype=float)
        n = stats.loc[ids, "orbits"].to_numpy(dtype=float)
        wall = np.array([(wall_by_cell or {}).get(int(c), math.nan) for c in ids]) / n
        finite = err[np.isfinite(err)]
        rows.append(LeagueRow(names[int(setup)], cost_to_reach(nfev, err, ids, eps),
                              cost_to_reach(wall, err, ids, eps),
                              float(finite.min()) if len(finite) else math.nan, len(part)))
    return ranked(rows)


def league_frame(rows: list[LeagueRow]):
    """A league as a DataFrame: family, rank, nfev per orbit and how it was found, wall seconds
    per orbit, best error."""
    import pandas as pd

    return pd.DataFrame([{"family": r.family, "rank": r.rank_nfev, "nfev": r.nfev.value,
                          "nfev_how": r.nfev.how, "wall_seconds": r.wall.value,
                          "rank_wall": r.rank_wall, "best_error": r.best_error, "cells": r.cells}
                         for r in rows])


def work_precision(cells, stats, measure: str, problem: str | None = None, palette=None):
    """The statistical work-precision diagram of the ensemble cells (of ``problem``, default
    all) as a description (:class:`gnibench.reports.render.Plot`): error (median line, q10-q90
    band) and failure rate, each against the median nfev per orbit (see the module
    docstring)."""
    from gnibench.reports.palette import styles
    from gnibench.reports.render import Panel, Plot, Series

    ens = cells[cells["orbits"].notna()] if "orbits" in cells else cells.iloc[:0]
    if problem is not None:
        ens = ens[ens["problem"] == problem]
    s = stats[stats["metric"] == measure].set_index("cell")
    cost = stats[stats["metric"] == "nfev"].set_index("cell")["median"]
    finite = s.loc[s.index.isin(ens["cell"]), ["q90", "median"]].replace(np.inf, np.nan)
    top = float(np.nanmax(finite.to_numpy())) * 10 if finite.notna().any().any() else 1.0
    left = Panel(xscale="log", yscale="log", grid=True, xlabel="f-evaluations per orbit (median)",
                 ylabel=f"{measure} (median, 10–90 %)", legend={"fontsize": 7.5, "loc": "best"})
    right = Panel(xscale="log", grid=True, xlabel="f-evaluations per orbit (median)",
                  ylabel=f"failure rate of {measure}", title="failed orbits")
    ens, names = _families(ens)
    style = styles(ens, palette) if len(ens) else {}
    for setup, part in ens.groupby("setup", sort=False):
        ids = [c for c in part["cell"] if c in s.index and c in cost.index]
        x = cost.loc[ids].to_numpy(dtype=float)
        order = np.argsort(x, kind="stable")
        x = x[order]
        med, lo, hi = (s.loc[ids, k].to_numpy(dtype=float)[order] for k in ("median", "q10",
                                                                             "q90"))
        st = style.get(int(setup), {})
        line = {"color": st.get("color"), "linestyle": st.get("linestyle", "-"),
                "marker": st.get("marker", "o"), "markersize": 4, "linewidth": 1.2}
        left.series.append(Series(x, np.where(np.isfinite(hi), hi, top), {
            "color": st.get("color"), "alpha": 0.18, "linewidth": 0},
            band=np.where(np.isfinite(lo), lo, top)))
        left.series.append(Series(x, np.where(np.isfinite(med), med, np.nan),
                                  {**line, "label": names[int(setup)][:60]}))
        right.series.append(Series(x, s.loc[ids, "failure_rate"].to_numpy(dtype=float)[order],
                                   line))
    n = int(s.loc[s.index.isin(ens["cell"]), "orbits"].max()) if len(ens) else 0
    left.title = f"{problem or 'ensembles'}: {n} orbits per cell"
    rates = s.loc[s.index.isin(ens["cell"]), "failure_rate"].to_numpy(dtype=float)
    right.ylim = (0.0, min(1.0, max(0.05, 1.15 * float(rates.max())) if len(rates) else 1.0))
    return Plot((10.5, 4.4), 1, 2, [left, right],
                {"left": 0.08, "right": 0.98, "bottom": 0.13, "top": 0.9, "wspace": 0.28})


def section(res, part, img_dir, prefix: str, slug: str, thresholds, jobs,
            share: float = SHARE, palette=None):
    """The ensembles of one problem on an experiment page: the diagram (its drawing appended
    to ``jobs``, into ``img_dir``) and the league tables at each threshold; {} when the problem
    has no ensemble cell (or the run no ``ensemble.parquet``)."""
    import pandas as pd

    path = res.dir / "ensemble.parquet"
    if "orbits" not in part or not part["orbits"].notna().any() or not path.is_file():
        return {}
    from gnibench.reports.results import read_table

    orbits = read_table(path)
    orbits = orbits[orbits["cell"].isin(part["cell"])]
    stats = read_table(res.dir / "ensemble_stats.parquet")
    measure = measure_of(orbits)
    if not measure or not len(orbits):
        return {}
    from gnibench.reports.drawing import Job

    file = f"{prefix}-ensemble-work-precision.png"
    problem = str(part["problem"].iloc[0]) if part["problem"].nunique() == 1 else None
    jobs.append(Job(work_precision(part, stats, measure, problem, palette), img_dir / file))
    wall = res.wall_by_cell()
    tables = []
    for eps in thresholds:
        rows = league(part, orbits, eps, share, measure, wall)
        tables.append({"threshold": f"{eps:.0e}", "rows": [
            [str(r.rank_nfev or "–"), r.family, _cost(r.nfev), _cost(r.wall, 1e3),
             str(r.rank_wall or "–"), f"{r.best_error:.3g}", str(r.cells)] for r in rows]})
    counts = part[part["orbits"].notna()]
    return {"figure": {"file": f"{slug}/{file}", "title": "statistical work-precision",
                       "caption": (f"{measure} over the orbits of each ensemble cell against "
                                   "the median f-evaluations per orbit: median (line), 10-90 % "
                                   "band (a failed orbit counts as +inf), and the failure rate "
                                   "(right).")},
            "measure": measure, "share": f"{share:.0%}",
            "orbits": int(pd.to_numeric(counts["orbits"]).max()),
            "header": ["rank (nfev)", "method family", "nfev per orbit to reach ε",
                       "wall ms per orbit to reach ε", "rank (wall)", f"best {measure}",
                       "cells"],
            "tables": tables}


def _cost(c: Cost, scale: float = 1.0) -> str:
    if c.how in ("not reached", "–", ""):
        return c.how or "–"
    value = f"{c.value * scale:.3g}"
    if c.how == "bound":
        return f"≤ {value} (cell {c.cells[0]})"
    if c.how == "interpolated":
        return f"{value} (cells {c.cells[0]}–{c.cells[1]})"
    return f"{value} (cell {c.cells[0]})"
