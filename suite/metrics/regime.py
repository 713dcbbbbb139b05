"""Which errors measure a method: below saturation, above the reference's accuracy floor.

An error means something about a method only between two levels:

* **saturation**: an error of the order of the quantity itself says the trajectory is lost, not
  how accurate the method is. The level is :data:`SATURATION` times the scale: for the global
  error the size of the solution (``solution_size`` = max |y_ref| over the samples), for an
  integral's error |I(y0)| (``scale_<I>``). Ten periods of the unstable Arenstorf orbit give
  global errors of ~30 for every method: all saturated.
* **the reference's floor**: a global error at or below the reference's own accuracy estimate
  (``max_reference_error``, ``final_reference_error``,
  :func:`gnibench.suite.cell.reference.reference_accuracy`) measures the reference, not the
  method.

(choice) SATURATION = 0.5: an error of the order of the solution (or of the integral) is the
trajectory lost, and GeometricIntegrators.jl's convergence tests likewise fit only the
decreasing points. The regime where the error behaves like C h^p reaches further than a tenth of
the solution on the seeds' own protocol: on kepler-2d (e = 0.6) over 40π the implicit midpoint
rule's global errors at h = 0.005, 0.0025, 0.00125 are 0.270, 0.0679, 0.0170 (max |y| = 1.73),
ratios 3.98 and 4.00, i.e. order 2 from an error of a sixth of the solution on ([HLW] Table 2.1,
experiment hlw-table-2.1). The observed order (:mod:`.order`), the league tables and the
work-precision diagrams use the same levels (:func:`trusted`), so they agree on which cells count.
"""
from __future__ import annotations

import numpy as np

SATURATION = 0.5

#: words for each verdict of :func:`trusted`
SATURATED = "saturated"
BELOW_FLOOR = "below the reference's accuracy"
FAILED = "failed"


def scale_column(column: str) -> str:
    """The cells' column holding the scale of an error column: ``solution_size`` for the global
    errors, ``scale_<I>`` for ``max_abs_err_<I>`` or ``err_<I>``, "" otherwise."""
    if "global_error" in column or column == "global":
        return "solution_size"
    for head in ("max_abs_err_", "err_"):
        if column.startswith(head):
            return "scale_" + column[len(head):]
    return "scale_" + column


def floor_column(column: str) -> str:
    """The cells' column holding the reference's accuracy for an error column ("" for none):
    the final one for the final global error, the maximum for every other global error."""
    if column == "final_global_error":
        return "final_reference_error"
    if "global_error" in column or column == "global":
        return "max_reference_error"
    return ""


def levels(cells, column: str) -> tuple[np.ndarray, np.ndarray]:
    """(saturation level, reference floor) of each cell for the error ``column`` (NaN where
    unknown: no such scale or no estimate)."""
    n = len(cells)
    scale_col, floor_col = scale_column(column), floor_column(column)
    scale = cells[scale_col].to_numpy(dtype=float) if scale_col in cells else np.full(n, np.nan)
    floor = cells[floor_col].to_numpy(dtype=float) if floor_col and floor_col in cells \
        else np.full(n, np.nan)
    with np.errstate(invalid="ignore"):
        ceiling = np.where(scale > 0, SATURATION * scale, np.nan)
    return ceiling, floor


def verdicts(errors, ceiling, floor) -> list[str]:
    """For each error: "" (it measures the method), :data:`SATURATED`, :data:`BELOW_FLOOR` or
    :data:`FAILED` (not finite)."""
    out = []
    for e, c, f in zip(np.asarray(errors, float), np.asarray(ceiling, float),
                       np.asarray(floor, float)):
        if not np.isfinite(e):
            out.append(FAILED)
        elif np.isfinite(c) and e >= c:
            out.append(SATURATED)
        elif np.isfinite(f) and e <= f:
            out.append(BELOW_FLOOR)
        else:
            out.append("")
    return out


def trusted(cells, column: str) -> list[str]:
    """:func:`verdicts` of the cells' error ``column`` (a column of cells.parquet) against their
    own levels; a cell that did not end ``ok`` is :data:`FAILED`."""
    ceiling, floor = levels(cells, column)
    errors = cells[column].to_numpy(dtype=float) if column in cells else np.full(len(cells),
                                                                               np.nan)
    status = cells["status"].astype(str).to_numpy() if "status" in cells else ["ok"] * len(errors)
    return [FAILED if s != "ok" else v
            for s, v in zip(status, verdicts(errors, ceiling, floor))]


def saturation_words(column: str) -> str:
    """The saturation level of an error column in words."""
    if "global_error" in column:
        return f"{SATURATION:g} × max |y_ref|"
    name = scale_column(column)[len("scale_"):]
    return f"{SATURATION:g} × |{name}(y0)|"
