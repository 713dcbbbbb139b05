"""Exponent in h: the observed order of an error across cells that differ only in the step size.

[HLW] Table 2.1 gives how the errors of the Kepler problem scale with h (O(h), O(h^2), O(th),
O(t h^2)); the global error of a method of order p is O(t h^p) ([HLW] (1.5)-(1.7), (1.9),
(1.17)). The observed order is the least-squares slope of log(error) against log(h)
(GeometricIntegrators.jl style, as in tests/methods/test_orders.py):

* points below a round-off plateau (1e-13), saturated points (an error of at least half
  the solution's size or of |I(y0)|: the trajectory is lost, :mod:`.regime`), points at or below
  the reference's own accuracy estimate, points after the error stops decreasing, and failed
  runs (infinite or NaN errors) are dropped: the longest run of decreasing errors is kept;
* of that run, end points whose local rate log(e_k/e_k+1)/log(h_k/h_k+1) differs from the run's
  median rate by more than 20% are trimmed, one at a time (the pre-asymptotic coarse end; the fine
  end where rounding, which grows with the number of steps, slows the decrease);
* the finest (at most) five remaining points are fitted, and only when at least three remain
  (:data:`MIN_POINTS`, as GeometricIntegrators.jl's convergence tests): with fewer, the order is
  NaN and ``order_reason_<X>`` says why (how many points each rule dropped).

The trimming uses only the data, never a declared order.

As a metric (``order``, a family metric), the error of each cell is taken from the samples
table: its maximum over the samples (``at=max``, the claims inventory "exponent in h": slope of log max|err|
against log h at fixed t) or its value at the last sample (``at=final``); a cell that did not end
``ok`` counts as infinite. The family is the cells of one setup
(:func:`gnibench.suite.metrics.families.setup_key`: problem, method options but the swept ones,
horizon, sampling, reference), the same families the reports draw; a family must sweep h.
"""
from __future__ import annotations

import itertools
from typing import TYPE_CHECKING

import numpy as np
from gnibench.suite.foundation.params import Param
from gnibench.suite.metrics.base import Metric, max_abs
from gnibench.suite.metrics.growth import unknown_errors

if TYPE_CHECKING:
    import pandas as pd

PLATEAU = 1e-13
TRIM = 0.2
FIT = 5
MIN_POINTS = 3
GLOBAL = "global"


def _local_rates(hs, errs, idx) -> list[float]:
    return [np.log(errs[a] / errs[b]) / np.log(hs[a] / hs[b]) for a, b in itertools.pairwise(idx)]


def order_points(hs, errs, plateau: float = PLATEAU, trim: float = TRIM, fit: int = FIT,
                 ceiling=None, floor=None) -> tuple[float, list[int], str]:
    """The observed order, the indices of the points fitted and, when there is no order (NaN),
    why (see the module docstring).

    ``hs`` and ``errs`` in the order of the runs, coarse to fine (h decreasing); ``ceiling`` and
    ``floor`` (None, or one level per point, NaN for none): errors at or above ``ceiling``
    (saturated) or at or below ``floor`` (the reference's accuracy) are dropped.
    """
    hs, errs = np.asarray(hs, dtype=float), np.asarray(errs, dtype=float)
    n = len(errs)
    ceiling = np.full(n, np.nan) if ceiling is None else np.asarray(ceiling, dtype=float)
    floor = np.full(n, np.nan) if floor is None else np.asarray(floor, dtype=float)
    drops = {"failed": ~np.isfinite(errs)}
    with np.errstate(invalid="ignore"):
        drops["saturated"] = ~drops["failed"] & (errs >= ceiling)
        drops["below the reference's accuracy"] = ~drops["failed"] & ~drops["saturated"] & \
            (errs <= floor)
        drops[f"below the round-off plateau {plateau:g}"] = ~drops["failed"] & (errs < plateau)
    usable = ~np.logical_or.reduce(list(drops.values())) if n else np.zeros(0, dtype=bool)
    best: list[int] = []
    run: list[int] = []
    for k, e in enumerate(errs):
        ok = bool(usable[k])
        if ok and run and e < errs[run[-1]]:
            run.append(k)
        else:
            run = [k] if ok else []
        if len(run) > len(best):
            best = list(run)
    while len(best) >= 4:
        rates = _local_rates(hs, errs, best)
        med = float(np.median(rates))
        ends = {0: abs(rates[0] - med), -1: abs(rates[-1] - med)}
        end = max(ends, key=ends.get)
        if ends[end] <= trim * abs(med):
            break
        best.pop(end)
    keep = best[-fit:]
    if len(keep) < MIN_POINTS:
        counts = [f"{int(m.sum())} {why}" for why, m in drops.items() if m.any()]
        rest = int(usable.sum()) - len(keep)
        if rest > 0:
            counts.append(f"{rest} not in the longest decreasing run")
        detail = f" ({', '.join(counts)})" if counts else ""
        return float("nan"), keep, (f"{len(keep)} of {n} points in the asymptotic regime, "
                                    f"{MIN_POINTS} needed{detail}")
    return float(np.polyfit(np.log(hs[keep]), np.log(errs[keep]), 1)[0]), keep, ""


def observed_order(hs, errs, plateau: float = PLATEAU, trim: float = TRIM,
                   fit: int = FIT) -> tuple[float, int]:
    """Least-squares log-log slope over the usable points, and their number."""
    slope, keep, _ = order_points(hs, errs, plateau, trim, fit)
    return slope, len(keep)


def cell_error(cell: pd.Series, samples: pd.DataFrame, name: str, at: str) -> float:
    """The error ``name`` of one cell from its samples: max |.| or |.| at the last sample; inf
    for a cell that did not end ``ok``; NaN when the cell has no such column."""
    if cell["status"] != "ok":
        return float("inf")
    col = "global_error" if name == GLOBAL else f"err_{name}"
    rows = samples[samples["cell"] == cell["cell"]]
    if col not in rows.columns or not len(rows) or rows[col].isna().all():
        return float("nan")
    values = rows.sort_values("t", kind="stable")[col].to_numpy(dtype=float)
    return max_abs(values) if at == "max" else float(abs(values[-1]))


def _compute(cells: pd.DataFrame, samples: pd.DataFrame, values) -> pd.DataFrame:
    import pandas as pd
    from gnibench.suite.metrics.regime import levels

    cells = cells.sort_values(["h", "cell"], ascending=[False, True], kind="stable")
    out = pd.DataFrame(index=pd.Index(cells["cell"].to_numpy(), name="cell"))
    hs = cells["h"].to_numpy(dtype=float)
    swept = str(cells["swept"].iloc[0]) if "swept" in cells else "h"
    for name in values["of"]:
        errs = np.array([cell_error(row, samples, name, values["at"]) for _, row in cells.iterrows()])
        column = ("final_global_error" if values["at"] == "final" else "max_global_error") \
            if name == GLOBAL else f"err_{name}"
        ceiling, floor = levels(cells, column)
        if swept.split("/")[0] not in ("h", ""):
            slope, keep = float("nan"), []
            reason = f"the family sweeps {swept}, not h: an order in h needs a step-size sweep"
        else:
            slope, keep, reason = order_points(hs, errs, values["plateau"], ceiling=ceiling,
                                               floor=floor)
        used = np.zeros(len(errs), dtype=bool)
        used[keep] = True
        out[f"order_{name}"] = slope
        out[f"order_reason_{name}"] = reason
        out[f"order_points_{name}"] = len(keep)
        out[f"order_used_{name}"] = used
        out[f"order_error_{name}"] = errs
    return out


order = Metric(
    id="order", title="exponent in h: observed order of an error across the cells of a family",
    reference="[HLW] Table 2.1, (1.5)-(1.17); the claims inventory Conventions ('exponent in h')",
    doc=("for the cells of one setup (equal in everything but h): the least-squares slope of "
         "log(error) against log(h) after dropping round-off plateaus, saturated errors, errors "
         "below the reference's accuracy, non-decreasing tails and failed cells and trimming end "
         "points off the median local rate (GeometricIntegrators.jl style), from at least 3 "
         "points (else NaN, with the reason in order_reason_<X>); written to every cell of the "
         "family"),
    compute=_compute, scope="family",
    params=(Param("of", (GLOBAL,), "the errors: global and/or integral names", kind="names"),
            Param("at", "max", "max: max |err| over the samples; final: |err| at the last sample",
                  kind="str", choices=("max", "final")),
            Param("plateau", PLATEAU, "errors below this round-off plateau are dropped",
                  low=0.0)),
    problem_check=lambda problem, values: unknown_errors(problem, values["of"]),
    columns=(),
    scalars=(("order_family", "the family: the smallest cell id among its cells"),
             ("order_<X>", ("observed order of error X (global or an integral) in the family; "
                            "NaN when fewer than 3 points are in the asymptotic regime")),
             ("order_reason_<X>", "why order_<X> is NaN (\"\" when it is not)"),
             ("order_points_<X>", "number of cells fitted"),
             ("order_used_<X>", "whether this cell's error was fitted"),
             ("order_error_<X>", ("this cell's error X (max or final; inf: the cell did not end "
                                 "ok)"))),
)
