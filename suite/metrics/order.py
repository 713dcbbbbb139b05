"""Exponent in h: the observed order of an error across cells that differ only in the step size.

[HLW] Table 2.1 gives how the errors of the Kepler problem scale with h (O(h), O(h^2), O(th),
O(t h^2)); the global error of a method of order p is O(t h^p) ([HLW] (1.5)-(1.7), (1.9),
(1.17)). The observed order is the least-squares slope of log(error) against log(h)
(GeometricIntegrators.jl style, as in tests/methods/test_orders.py):

* points below a round-off plateau (1e-13), points after the error stops decreasing, and failed
  runs (infinite or NaN errors) are dropped: the longest run of decreasing errors is kept;
* of that run, end points whose local rate log(e_k/e_k+1)/log(h_k/h_k+1) differs from the run's
  median rate by more than 20% are trimmed, one at a time (the pre-asymptotic coarse end; the fine
  end where rounding, which grows with the number of steps, slows the decrease);
* the finest (at most) five remaining points are fitted.

The trimming uses only the data, never a declared order.

As a metric (``order``, a family metric), the error of each cell is taken from the samples
table: its maximum over the samples (``at=max``, the claims inventory "exponent in h": slope of log max|err|
against log h at fixed t) or its value at the last sample (``at=final``); a cell that did not end
``ok`` counts as infinite. The family is the cells equal in everything but h
(:mod:`gnibench.suite.metrics.families`).
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
GLOBAL = "global"


def _local_rates(hs, errs, idx) -> list[float]:
    return [np.log(errs[a] / errs[b]) / np.log(hs[a] / hs[b]) for a, b in itertools.pairwise(idx)]


def order_points(hs, errs, plateau: float = PLATEAU, trim: float = TRIM,
                 fit: int = FIT) -> tuple[float, list[int]]:
    """The observed order and the indices of the points fitted (see the module docstring).

    ``hs`` and ``errs`` in the order of the runs, coarse to fine (h decreasing). NaN when fewer
    than two points remain.
    """
    hs, errs = np.asarray(hs, dtype=float), np.asarray(errs, dtype=float)
    best: list[int] = []
    run: list[int] = []
    for k, e in enumerate(errs):
        ok = bool(np.isfinite(e) and e >= plateau)
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
    if len(keep) < 2:
        return float("nan"), keep
    return float(np.polyfit(np.log(hs[keep]), np.log(errs[keep]), 1)[0]), keep


def observed_order(hs, errs, plateau: float = PLATEAU, trim: float = TRIM,
                   fit: int = FIT) -> tuple[float, int]:
    """Least-squares log-log slope over the usable points, and their number."""
    slope, keep = order_points(hs, errs, plateau, trim, fit)
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

    cells = cells.sort_values(["h", "cell"], ascending=[False, True], kind="stable")
    out = pd.DataFrame(index=pd.Index(cells["cell"].to_numpy(), name="cell"))
    hs = cells["h"].to_numpy(dtype=float)
    for name in values["of"]:
        errs = np.array([cell_error(row, samples, name, values["at"]) for _, row in cells.iterrows()])
        slope, keep = order_points(hs, errs, values["plateau"])
        used = np.zeros(len(errs), dtype=bool)
        used[keep] = True
        out[f"order_{name}"] = slope
        out[f"order_points_{name}"] = len(keep)
        out[f"order_used_{name}"] = used
        out[f"order_error_{name}"] = errs
    return out


order = Metric(
    id="order", title="exponent in h: observed order of an error across the cells of a family",
    reference="[HLW] Table 2.1, (1.5)-(1.17); the claims inventory Conventions ('exponent in h')",
    doc=("for the cells of an experiment equal in everything but h: the least-squares slope of "
         "log(error) against log(h) after dropping round-off plateaus, non-decreasing tails and "
         "failed cells and trimming end points off the median local rate (GeometricIntegrators.jl "
         "style); written to every cell of the family"),
    compute=_compute, scope="family",
    params=(Param("of", (GLOBAL,), "the errors: global and/or integral names", kind="names"),
            Param("at", "max", "max: max |err| over the samples; final: |err| at the last sample",
                  kind="str", choices=("max", "final")),
            Param("plateau", PLATEAU, "errors below this round-off plateau are dropped",
                  low=0.0)),
    problem_check=lambda problem, values: unknown_errors(problem, values["of"]),
    columns=(),
    scalars=(("order_family", "the family: the smallest cell id among its cells"),
             ("order_<X>", "observed order of error X (global or an integral) in the family"),
             ("order_points_<X>", "number of cells fitted"),
             ("order_used_<X>", "whether this cell's error was fitted"),
             ("order_error_<X>", ("this cell's error X (max or final; inf: the cell did not end "
                                 "ok)"))),
)
