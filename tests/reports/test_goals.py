"""The accuracy-goal tables of the work-precision experiments (reports/goals.py)."""
from __future__ import annotations

import math
from types import SimpleNamespace

import pandas as pd
from gnibench.reports.goals import family_table, goal_rows, goal_table, median_walls, picks
from support_reports import with_method_columns

P = "kepler-2d:e=0.6"
CELLS = [  # method, status, final error, nfev
    ("vern9:rtol=1e-10,atol=1e-18", "ok", 3e-8, 1000.0),
    ("vern9:rtol=1e-14,atol=1e-18", "ok", 5e-11, 3000.0),
    ("vern9:rtol=1e-16,atol=1e-18", "ok", 8e-13, 9000.0),
    ("feagin10:rtol=1e-14,atol=1e-18", "ok", 4e-11, 2500.0),
    ("feagin10:rtol=1e-17,atol=1e-18", "max_steps", 1e-20, 1e9),     # failed: never counts
    ("heyoka-taylor:dt_out=0.6,tol=1e-12", "ok", 3e-9, math.nan),
    ("heyoka-taylor:dt_out=0.6,tol=1e-15", "ok", 2e-12, math.nan),
    ("rebound-ias15:dt_out=0.6,epsilon=1e-09", "ok", 1e-12, math.nan),
]
# wall seconds of three runs; the medians are 1, 3, 9, 2, 1, 1, 4, 50 ms
WALLS = [(1, 3, 9, 2, 1, 1, 4, 50), (1, 2, 9, 9, 1, 1, 5, 50), (7, 3, 1, 2, 1, 7, 4, 50)]


def _runs():
    cells = pd.DataFrame({"cell": range(len(CELLS)), "problem": P,
                          "method": [c[0] for c in CELLS], "status": [c[1] for c in CELLS],
                          "final_global_error": [c[2] for c in CELLS],
                          "nfev": [c[3] for c in CELLS]})
    cells = with_method_columns(cells)
    runs = [SimpleNamespace(timings=pd.DataFrame(
        {"cell": cells["cell"], "problem": P, "method": cells["method"], "status": cells["status"],
         "wall_seconds": [w / 1000 for w in ws]})) for ws in WALLS]
    return cells, runs


def test_the_fastest_cell_within_each_accuracy_by_median_wall_time():
    cells, runs = _runs()
    walls = median_walls(runs)
    assert walls[(P, CELLS[2][0])] == 9e-3 and walls[(P, CELLS[3][0])] == 2e-3
    p = picks(cells, walls, 1e-10)
    assert set(p) == {"vern9", "feagin10", "heyoka-taylor", "rebound-ias15"}
    assert p["feagin10"].setting == "rtol=1e-14" and p["feagin10"].compiled
    assert p["vern9"].wall == 3e-3 and p["vern9"].nfev == 3000.0
    assert not p["heyoka-taylor"].compiled and p["heyoka-taylor"].wall == 4e-3
    assert "feagin10" not in picks(cells, walls, 1e-12)             # its failed cell does not count


def test_the_goal_rows_compare_the_fastest_compiled_method_with_heyoka():
    cells, runs = _runs()
    walls = median_walls(runs)
    rows = {r[0]: r for r in goal_rows(cells, walls, (1e-7, 1e-10, 1e-12, 1e-14))}
    _, fast, hey, _, ratio, ld = rows[1e-7]
    assert fast.family == "vern9" and hey.setting == "tol=1e-12" and ratio == 1.0 and ld is None
    _, fast, hey, _, ratio, _ = rows[1e-10]
    assert fast.family == "feagin10" and math.isclose(ratio, 0.5)
    _, fast, hey, ias, ratio, _ = rows[1e-12]
    assert fast.family == "vern9" and hey is None and ias.family == "rebound-ias15"
    assert math.isnan(ratio)
    assert rows[1e-14][1] is None
    text = "\n".join(goal_table(cells, walls, (1e-10,)) + family_table(cells, walls, (1e-10,)))
    assert "`feagin10` rtol=1e-14: 2.00 ms, 2500 f-evals (error 4.0e-11)" in text
    assert "| `vern9` | 3.00 (3000) | 8.0e-13 |" in text
