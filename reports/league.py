"""League tables: the methods of one problem ranked by the cost to reach a stated accuracy.

For each family (the cells of one setup, :mod:`gnibench.reports.setups`; a league table holds the
families of one context: one problem, horizon and reference) and a threshold ε on an error
measure (``max_global_error`` when the problem's cells have a reference, else ``max_abs_err_<I>``
of its first integral), the cost is found along the family's sweep, cells ordered by cost:

* the cheapest ``ok`` cell whose error is ≤ ε is found; if the next cheaper ``ok`` cell of the
  sweep misses ε, the cost is **interpolated** linearly in log(cost) against log(error) between
  the two (the cost at which the sweep's error curve crosses ε);
* if the cheapest cell of the sweep already reaches ε, its cost is an upper bound (shown "≤");
* if no cell reaches ε, the family is "not reached" (with its best error).

Only errors that measure the method count (:mod:`gnibench.suite.metrics.regime`): a saturated
error (the trajectory lost) is left out; an error at or below the reference's accuracy estimate
f counts as an error of 2f (its true value is at most that) where 2f <= ε, and is left out
otherwise. A threshold below twice the smallest floor of the context is not ranked, nor is a
context whose every error is saturated.

Costs are ``nfev`` (reproducible) and wall time (``timings.parquet``: the fastest of the cell's
repeated runs; not reproducible). Ranks are by nfev, then by wall time; equal costs (to 3
significant digits) share a rank. Families whose engine does not count evaluations (heyoka,
IAS15: nfev NaN) are ranked by wall time only. Failed cells (status other than ``ok``) are listed
per family with their reasons and never reach ε. A family that sweeps h also shows its observed
order in h of the measure (:func:`gnibench.suite.metrics.order.order_points`, the ``order``
metric's fit), or why there is none.
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
    excluded: list[tuple[int, str]] = field(default_factory=list)      # (cell, why)
    order: float = math.nan
    order_reason: str = ""                # why there is no order ("" when there is, or no h sweep)


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


def league(cells, wall_by_cell: dict[int, float], eps: float, column: str | None = None,
           names: dict[int, str] | None = None) -> list[LeagueRow]:
    """The league rows of one context's cells (with the columns of
    :func:`gnibench.reports.setups.add_setups`) at threshold ``eps``, ranked by nfev and by wall
    time; unranked rows last. ``names``: each family's name by setup id (default: its label)."""
    from gnibench.suite.metrics.regime import BELOW_FLOOR, FAILED, levels, trusted

    column = column or accuracy_column(cells)[0]
    verdict = dict(zip(cells["cell"].astype(int), trusted(cells, column) if column else
                       [""] * len(cells)))
    floors = dict(zip(cells["cell"].astype(int), levels(cells, column)[1] if column else
                      np.full(len(cells), np.nan)))
    rows = []
    for setup, part in cells.groupby("setup", sort=False):
        ok = part[part["status"] == "ok"]
        ids_all = ok["cell"].to_numpy(dtype=int)
        err_all = ok[column].to_numpy(dtype=float) if column else np.full(len(ok), np.nan)
        keep, errs, excluded = [], [], []
        for cid, e in zip(ids_all, err_all):
            why = verdict[int(cid)]
            if why == BELOW_FLOOR and 2 * floors[int(cid)] <= eps:
                keep.append(cid)
                errs.append(2 * floors[int(cid)])          # its true error is at most this
            elif why in ("", FAILED):
                keep.append(cid)
                errs.append(e)
            else:
                excluded.append((int(cid), why))
        ids = np.array(keep, dtype=int)
        err = np.array(errs, dtype=float)
        chosen = ok.set_index("cell").loc[ids] if len(ids) else ok.iloc[:0]
        nfev = chosen["nfev"].to_numpy(dtype=float)
        wall = np.array([wall_by_cell.get(int(c), math.nan) for c in ids], dtype=float)
        failed = [(int(r.cell), str(r.status), str(r.reason or ""))
                  for r in part.itertuples() if r.status != "ok"]
        finite = err[np.isfinite(err)]
        if not len(ids):                       # only failed or excluded cells: never reach eps
            costs = (Cost(how="not reached"), Cost(how="not reached"))
        else:
            costs = (cost_to_reach(nfev, err, ids, eps), cost_to_reach(wall, err, ids, eps))
        name = (names or {}).get(int(setup), str(part["family"].iloc[0]))
        row = LeagueRow(name, *costs, float(finite.min()) if len(finite) else math.nan,
                        len(part), failed, excluded=excluded)
        if column:
            row.order, row.order_reason = family_order(part, column)
        rows.append(row)
    return ranked(rows)


def ranked(rows: list[LeagueRow]) -> list[LeagueRow]:
    """League rows with their ranks by nfev and by wall time, in rank order (unranked last)."""
    for attr, rank in (("nfev", "rank_nfev"), ("wall", "rank_wall")):
        for row, r in zip(rows, _ranks([getattr(x, attr).value for x in rows])):
            setattr(row, rank, r)
    big = 10 ** 9
    rows.sort(key=lambda r: (r.rank_nfev or big, r.rank_wall or big, r.family))
    return rows


def family_order(part, column: str) -> tuple[float, str]:
    """The observed order in h of ``column`` over one family's cells, with the ``order``
    metric's rules (:func:`gnibench.suite.metrics.order.order_points`: the asymptotic regime,
    at least 3 points); (NaN, "") for a family that does not sweep h."""
    from gnibench.suite.metrics.order import order_points
    from gnibench.suite.metrics.regime import levels

    if str(part["swept"].iloc[0]).split("/")[0] != "h":
        return math.nan, ""
    part = part.sort_values(["h", "cell"], ascending=[False, True], kind="stable")
    errs = np.where(part["status"] == "ok", part[column].to_numpy(dtype=float), np.inf)
    ceiling, floor = levels(part, column)
    slope, _, why = order_points(part["h"].to_numpy(dtype=float), errs, ceiling=ceiling,
                                 floor=floor)
    return slope, why


def unrankable(cells, column: str, eps: float) -> str:
    """Why a context's cells cannot be ranked at ``eps`` ("" when they can): every ok error
    saturated, or ``eps`` below twice the reference's smallest accuracy estimate."""
    from gnibench.suite.metrics.regime import SATURATED, levels, saturation_words, trusted

    ok = cells["status"] == "ok"
    verdicts = [v for v, good in zip(trusted(cells, column), ok) if good]
    if verdicts and all(v == SATURATED for v in verdicts):
        return (f"every error is above the saturation level ({saturation_words(column)}): the "
                f"trajectory is lost for every method, nothing is ranked")
    floor = levels(cells, column)[1][ok.to_numpy()]
    floor = floor[np.isfinite(floor)]
    if len(floor) and eps < 2 * floor.min():
        return (f"ε is below twice the reference's own accuracy ({floor.min():.2g}): errors "
                f"this small are not measured, nothing is ranked")
    return ""
