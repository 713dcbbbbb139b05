"""The tables of a report page as plain data: the table of a problem's cells (status, cost,
metrics, why an order or exponent is missing) and the league tables of a context; ``num``, the
one number format of the pages."""
from __future__ import annotations

import math

from gnibench.reports import league, plots, workprecision

FIXED = {"cell", "group", "label", "problem", "method", "problem_id", "base_method", "modifiers",
         "method_kind", "h", "t_end",
         "steps_planned", "every", "status", "reason", "steps", "t_final", "nfev", "njev",
         "samples", "integrals", "reference", "metrics", "metric_notes", "final_global_error",
         "max_global_error", "family", "sweep", "sweep_value", "adaptive", "problem_id",
         "base_method", "modifiers", "swept", "setup_method", "setup", "context", "swept_text",
         "_key", "solution_size", "max_reference_error", "final_reference_error"}
#: columns of the metrics shown in the table's notes rather than as columns
QUIET = ("growth_exponent_", "growth_reason_", "order_reason_", "scale_", "order_used_",
         "order_error_")


def num(x, fmt: str = ".3g") -> str:
    """A number for a table; ``–`` for missing values."""
    if x is None:
        return "–"
    try:
        v = float(x)
    except (TypeError, ValueError):
        import pandas as pd

        return "–" if x is pd.NA else str(x)          # NA: a count the method did not report
    if math.isnan(v):
        return "–"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if v.is_integer() and abs(v) < 1e15 and fmt == ".3g":
        return f"{v:.0f}"
    return format(v, fmt)


def _horizon(row) -> str:
    if row.get("t_end") is not None and not (isinstance(row["t_end"], float)
                                             and math.isnan(row["t_end"])):
        return f"t_end = {num(row['t_end'], '.6g')}"
    return f"steps = {num(row.get('steps_planned'))}"


def cells_table(part, samples, wall: dict[int, tuple], compile_s: dict[int, float],
                by_cell: dict | None = None, memo: dict | None = None,
                names: dict | None = None) -> dict:
    """The table of one problem's cells: header, rows of strings, which columns are specs.
    ``wall``: each cell's (fastest, median, spread, runs) wall times; ``by_cell``:
    :func:`~gnibench.reports.plots.trajectories` of ``samples`` (if already split); ``memo``:
    fitted growth exponents, shared with the figures; ``names``: family names by setup id.
    The last column, notes, says why an order or a growth exponent is missing and which errors
    do not measure the method (saturated, below the reference's accuracy)."""
    from gnibench.suite.metrics.regime import trusted

    integrals = [i for i in dict.fromkeys("/".join(part["integrals"].fillna("")).split("/")) if i]
    errs = [i for i in integrals if f"max_abs_err_{i}" in part and part[f"max_abs_err_{i}"].notna().any()]
    has_global = part["final_global_error"].notna().any()
    extra = [c for c in part.columns if c not in FIXED and not c.startswith("max_abs_err_")
             and not c.startswith(QUIET) and part[c].notna().any()
             and not (part[c].astype(str) == "").all()
             and not (c == "section" and (part[c].fillna(0) == 0).all())]    # no section cells
    header = ["cell", "method", "family", "swept", "status", "horizon", "every", "t reached",
              "steps", "nfev", "run ms (fastest)", "median ms, spread", "compile s"]
    header += [f"max |err {i}|" for i in errs] + [f"growth exp. {i}" for i in errs]
    if has_global:
        header += ["final global error", "max global error", "reference's accuracy",
                   "growth exp. global", "reference"]
    header += extra + ["notes"]
    if samples is not None and by_cell is None:
        by_cell = plots.trajectories(samples)
    verdicts = {"max_global_error": trusted(part, "max_global_error")} if has_global else {}
    for i in errs:
        verdicts[f"max_abs_err_{i}"] = trusted(part, f"max_abs_err_{i}")
    rows = []
    for k, r in enumerate(part.to_dict("records")):
        cid = int(r["cell"])
        s = by_cell.get(cid) if samples is not None else None
        kind = " (runs in Python)" if r.get("method_kind") == "python" else ""
        fastest, median, spread, runs = wall.get(cid, (math.nan, math.nan, math.nan, 0))
        notes = []
        row = [str(cid), str(r["method"]) + kind, (names or {}).get(int(r["setup"]), r["family"]),
               str(r.get("swept_text") or "–"), str(r["status"]), _horizon(r), num(r["every"]),
               num(r["t_final"], ".6g"), num(r["steps"]), num(r["nfev"]),
               num(fastest * 1e3),
               f"{num(median * 1e3)}, {num(spread * 100, '.0f')} % ({runs} runs)" if runs > 1
               else "–", num(compile_s.get(cid), ".2f")]
        row += [num(r[f"max_abs_err_{i}"]) for i in errs]
        for i in errs:
            p, why = plots.exponent(r, s, i, memo) if samples is not None else (math.nan, "")
            row.append(num(p, ".2f"))
            notes += [f"growth {i}: {why}"] if why else []
        if has_global:
            p, why = plots.exponent(r, s, "global", memo) if samples is not None else \
                (math.nan, "")
            notes += [f"growth global: {why}"] if why else []
            row += [num(r["final_global_error"]), num(r["max_global_error"]),
                    num(r.get("max_reference_error")), num(p, ".2f"),
                    str(r.get("reference") or "–")]
        row += [num(r[c]) if isinstance(r[c], (int, float)) else str(r[c]) for c in extra]
        notes += [f"{c.removeprefix('max_')}: {v[k]}" for c, v in verdicts.items()
                  if v[k] and v[k] != "failed"]
        notes += [f"{c.removeprefix('order_reason_')} order: {r[c]}" for c in r
                  if c.startswith("order_reason_") and isinstance(r[c], str) and r[c]]
        row.append("; ".join(notes) or "–")
        rows.append(row)
    return {"header": header, "rows": rows, "code": [1], "status_col": 4,
            "wrap": [len(header) - 1]}


def league_tables(part, wall: dict[int, float], thresholds, names: dict | None = None) -> dict:
    """The league tables of one context, one per threshold, with the words stating them."""
    column, words = league.accuracy_column(part)
    if not column or not workprecision.has_sweeps(part):
        return {}
    tables = []
    for eps in thresholds:
        why = league.unrankable(part, column, eps)
        if why:
            tables.append({"threshold": f"{eps:.0e}", "rows": [], "note": why})
            continue
        rows = league.league(part, wall, eps, column, names)
        body = []
        for r in rows:
            failed = "; ".join(f"cell {c} {s}: {why}" if why else f"cell {c} {s}"
                               for c, s, why in r.failed)
            left = "; ".join(f"cell {c}: {why}" for c, why in r.excluded)
            order = num(r.order, ".2f") if math.isfinite(r.order) else \
                (f"NA: {r.order_reason}" if r.order_reason else "–")
            body.append([num(r.rank_nfev) if r.rank_nfev else "–", r.family,
                         _cost(r.nfev, ".3g"), _cost(r.wall, ".3g", 1e3),
                         num(r.rank_wall) if r.rank_wall else "–", num(r.best_error), order,
                         f"{r.cells}", "; ".join(x for x in (failed, left) if x) or "–"])
        tables.append({"threshold": f"{eps:.0e}", "rows": body, "note": ""})
    return {"measure": column, "words": words, "tables": tables,
            "header": ["rank (nfev)", "family", "nfev to reach ε", "wall ms to reach ε",
                       "rank (wall)", "best error", "order in h", "cells",
                       "failed or left-out cells"],
            "code": [1]}


def _cost(c: league.Cost, fmt: str, scale: float = 1.0) -> str:
    if c.how in ("not reached", "–"):
        return c.how
    value = num(c.value * scale, fmt)
    if c.how == "bound":
        return f"≤ {value} (cell {c.cells[0]})"
    if c.how == "interpolated":
        return f"{value} (cells {c.cells[0]}–{c.cells[1]})"
    return f"{value} (cell {c.cells[0]})"
