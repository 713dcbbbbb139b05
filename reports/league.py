"""League tables: the methods of one problem ranked by the cost to reach a stated accuracy.

For each method family (the cells' column ``family``) and a threshold ε on an error measure
(``max_global_error`` when the problem's cells have a reference, else ``max_abs_err_<I>`` of its
first integral), the cost is found along the family's sweep, cells ordered by cost:

* the cheapest ``ok`` cell whose error is ≤ ε is found; if the next cheaper ``ok`` cell of the
  sweep misses ε, the cost is **interpolated** linearly in log(cost) against log(error) between
  the two (the cost at which the sweep's error curve crosses ε);
* if the cheapest cell of the sweep already reaches ε, its cost is an upper bound (shown "≤");
* if no cell reaches ε, the family is "not reached" (with its best error).

Costs are ``nfev`` (reproducible) and wall time (``timings.parquet``; not reproducible). Ranks are
by nfev, then by wall time; equal costs (to 3 significant digits) share a rank. Families whose
engine does not count evaluations (heyoka, IAS15: nfev NaN) are ranked by wall time only. Failed
cells (status other than ``ok``) are listed per family with their reasons and never reach ε.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

DEFAULT_THRESHOLDS = (1e-4, 1e-8)


@dataclass
class Cost:
    """The cost of one family to reach ε in one currency (nfev or seconds)."""

    value: float = math.nan        # NaN: not reached or not measured
    how: str = ""                  # "interpolated", "bound" (≤ the cheapest cell), "not reached", "–"
    cells: tuple[int, ...] = ()    # the cell(s) it comes from


@dataclass
class LeagueRow:
    family: str
    nfev: Cost
    wall: Cost
    best_error: float
    cells: int
    failed: list[tuple[int, str, str]] = field(default_factory=list)   # (cell, status, reason)
    rank_nfev: int | None = None
    rank_wall: int | None = None


def accuracy_column(cells) -> tuple[str, str]:
    """(column, words) of the error a problem's league is judged on."""
    if "max_global_error" in cells and cells["max_global_error"].notna().any():
        return "max_global_error", "maximum global error over the samples"
    for c in cells.columns:
        if c.startswith("max_abs_err_") and cells[c].notna().any():
            name = c[len("max_abs_err_"):]
            return c, f"maximum |{name}(y) − {name}(y0)| over the samples"
    return "", ""


def cost_to_reach(costs: np.ndarray, errors: np.ndarray, ids: np.ndarray, eps: float) -> Cost:
    """The cost at which a sweep first reaches error ≤ eps (see the module docstring).

    ``costs``, ``errors``, ``ids``: the ok cells of one family; NaN costs are dropped first."""
    keep = np.isfinite(costs) & (costs > 0)
    costs, errors, ids = costs[keep], errors[keep], ids[keep]
    if not len(costs):
        return Cost(how="–")
    order = np.argsort(costs, kind="stable")
    costs, errors, ids = costs[order], errors[order], ids[order]
    errors = np.where(np.isnan(errors), np.inf, errors)
    hit = np.nonzero(errors <= eps)[0]
    if not len(hit):
        return Cost(how="not reached")
    i = int(hit[0])
    if i == 0:
        return Cost(float(costs[0]), "bound", (int(ids[0]),))
    c0, c1, e0, e1 = costs[i - 1], costs[i], errors[i - 1], errors[i]
    if not (np.isfinite(e0) and e1 > 0 and e0 > e1):
        return Cost(float(c1), "cheapest cell", (int(ids[i]),))
    frac = (math.log(eps) - math.log(e0)) / (math.log(e1) - math.log(e0))
    value = math.exp(math.log(c0) + frac * (math.log(c1) - math.log(c0)))
    return Cost(value, "interpolated", (int(ids[i - 1]), int(ids[i])))


def _ranks(values: list[float]) -> list[int | None]:
    """Competition ranks (1, 2, 2, 4) of finite values, ties at 3 significant digits."""
    keyed = [(float(f"{v:.3g}"), i) for i, v in enumerate(values) if math.isfinite(v)]
    keyed.sort()
    out: list[int | None] = [None] * len(values)
    for pos, (v, i) in enumerate(keyed):
        out[i] = pos + 1 if pos == 0 or v != keyed[pos - 1][0] else out[keyed[pos - 1][1]]
    return out


def league(cells, wall_by_cell: dict[int, float], eps: float,
           column: str | None = None) -> list[LeagueRow]:
    """The league rows of one problem's cells (with family columns) at threshold ``eps``,
    ranked by nfev and by wall time; unranked rows last."""
    column = column or accuracy_column(cells)[0]
    rows = []
    for fam, part in cells.groupby("family", sort=False):
        ok = part[part["status"] == "ok"]
        ids = ok["cell"].to_numpy(dtype=int)
        err = ok[column].to_numpy(dtype=float) if column else np.full(len(ok), np.nan)
        nfev = ok["nfev"].to_numpy(dtype=float)
        wall = np.array([wall_by_cell.get(int(c), math.nan) for c in ids], dtype=float)
        failed = [(int(r.cell), str(r.status), str(r.reason or ""))
                  for r in part.itertuples() if r.status != "ok"]
        finite = err[np.isfinite(err)]
        if not len(ok):                       # only failed cells: they never reach eps
            costs = (Cost(how="not reached"), Cost(how="not reached"))
        else:
            costs = (cost_to_reach(nfev, err, ids, eps), cost_to_reach(wall, err, ids, eps))
        rows.append(LeagueRow(str(fam), *costs,
                              float(finite.min()) if len(finite) else math.nan, len(part), failed))
    for attr, rank in (("nfev", "rank_nfev"), ("wall", "rank_wall")):
        for row, r in zip(rows, _ranks([getattr(x, attr).value for x in rows])):
            setattr(row, rank, r)
    big = 10 ** 9
    rows.sort(key=lambda r: (r.rank_nfev or big, r.rank_wall or big, r.family))
    return rows
