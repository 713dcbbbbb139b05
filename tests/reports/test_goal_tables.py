"""The work-precision pages: the goals tables (reports/goals.py) are well-formed Markdown: every
row has as many cells as the header and the separator row (a cosmic-ray survivor's class, issue
41: a separator one column short renders no table at all) and pick the fastest ok cell within
each accuracy; the curves (reports/workprecision.py) hold exactly the measurable ok cells."""
from __future__ import annotations

import math

import pandas as pd
from gnibench.reports.goals import family_table, goal_table


def cells_and_walls():
    rows = [("kepler-2d", "dopri5:rtol=1e-6", "dopri5", 1e-5, 100.0, "rtol", 1e-6, "compiled"),
            ("kepler-2d", "dopri5:rtol=1e-9", "dopri5", 1e-9, 400.0, "rtol", 1e-9, "compiled"),
            ("kepler-2d", "rk4:h=0.01", "rk4", 1e-7, 2500.0, "h", 0.01, "compiled"),
            ("kepler-2d", "heyoka-taylor:tol=1e-10", "heyoka-taylor", 1e-10, math.nan, "tol",
             1e-10, "external")]
    cells = pd.DataFrame(rows, columns=["problem", "method", "family", "final_global_error", "nfev",
                                        "sweep", "sweep_value", "method_kind"]).assign(status="ok")
    walls = {("kepler-2d", m): w for m, w in zip(cells["method"], (1e-3, 4e-3, 9e-3, 2e-3))}
    return cells, walls


def columns(line: str) -> int:
    assert line.startswith("|") and line.endswith("|"), line
    return line.count("|") - 1


def test_goal_tables_are_well_formed_and_pick_the_fastest():
    cells, walls = cells_and_walls()
    for table in (family_table(cells, walls, (1e-4, 1e-8)), goal_table(cells, walls, (1e-4, 1e-8))):
        assert set(table[1].strip("|").split("|")) == {"---"}
        assert {columns(line) for line in table} == {columns(table[0])}, table
    fam = family_table(cells, walls, (1e-4, 1e-8))
    dopri = next(line for line in fam if line.startswith("| `dopri5`"))
    assert "1.00 (100)" in dopri and "4.00 (400)" in dopri         # fastest within each accuracy


def test_work_precision_curves_hold_every_measurable_ok_cell_in_sweep_order(tmp_path):
    """Each family's curve (reports/workprecision.py) holds exactly its ok cells whose cost and
    error are finite and > 0, from the coarsest to the finest setting; a failed cell, a zero or
    NaN cost, a zero error are left out (log axes)."""
    from gnibench.reports.workprecision import wp_figures

    cells, walls = cells_and_walls()
    extra = pd.DataFrame([("kepler-2d", "dopri5:rtol=1e-3", "dopri5", 0.0, 50.0, "rtol", 1e-3,
                           "compiled"),
                          ("kepler-2d", "dopri5:rtol=1e-4", "dopri5", 3e-3, 80.0, "rtol", 1e-4,
                           "compiled")], columns=cells.columns[:-1]).assign(status="ok")
    cells = pd.concat([cells, extra], ignore_index=True)
    cells.loc[5, "status"] = "max_steps"                           # a failed cell
    cells = cells.assign(cell=range(len(cells)), max_global_error=cells["final_global_error"],
                         integrals="H/L", base_method=cells["family"], adaptive=True,
                         problem_id="kepler-2d")
    from gnibench.reports.palette import styles
    from gnibench.reports.setups import add_setups, family_names

    cells = add_setups(cells.assign(t_end=6.283185307179586, swept=cells["sweep"],
                                    setup_method=cells["family"]))
    wall = {i: 1e-3 * (i + 1) for i in cells["cell"]}
    jobs = []
    wp_figures("kepler-2d", cells, wall, tmp_path, "k", "k", jobs, styles(cells),
               family_names(cells))
    (job,) = jobs
    nfev_panel = job.plot.panels[0]
    dopri = next(s for s in nfev_panel.series if s.style["label"] == "dopri5")
    assert list(dopri.x) == [100.0, 400.0] and list(dopri.y) == [1e-5, 1e-9]
    rk4 = next(s for s in nfev_panel.series if s.style["label"] == "rk4")
    assert list(rk4.x) == [2500.0]
    assert not any(s.style["label"] == "heyoka-taylor" for s in nfev_panel.series)  # no nfev
    wall_panel = job.plot.panels[1]
    assert any(s.style["label"] == "heyoka-taylor" for s in wall_panel.series)
