"""The goals tables of the work-precision pages (reports/goals.py) are well-formed Markdown: every
row has as many cells as the header and the separator row (a cosmic-ray survivor's class, issue
41: a separator one column short renders no table at all), and they pick the fastest ok cell
within each accuracy."""
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
