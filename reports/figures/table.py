"""Drawing a ``kind = "table"`` figure: the seed's entries beside the fitted exponents.

One row per method, one column per error (an integral, or ``global``). Each entry shows the seed's
text (``O(th)``) and what the tables give: the growth exponent in t (``growth_exponent_<X>``, the
median over the row's cells: the claims inventory "growth exponent in t") and the exponent in h
(``order_<X>``, fitted across the row's cells, which differ only in h: the claims inventory "exponent in h"),
as ``t^a h^b``. When every cell's max |err| is below the figure's ``zero_below``, the entry reads
``0`` with that maximum (round-off: [HLW] Table 2.1's exact conservation of L).
"""
from __future__ import annotations

import math
import textwrap

import numpy as np


def _finite(values) -> list[float]:
    out = []
    for v in values:
        try:
            v = float(v)
        except (TypeError, ValueError):
            continue
        if math.isfinite(v):
            out.append(v)
    return out


def measured(results, row: dict, col: dict, zero_below: float) -> dict:
    """The measured entry of one row and column, from ``cells.parquet`` only."""
    x = col["of"]
    cells = results.cells[results.cells["cell"].isin(row["cells"])]
    err_col = "max_global_error" if x == "global" else f"max_abs_err_{x}"
    errors = cells[err_col].to_numpy(dtype=float) if err_col in cells else np.array([np.nan])
    growth = _finite(cells.get(f"growth_exponent_{x}", []))
    order = _finite(cells.get(f"order_{x}", []))
    entry = {"of": x, "max_abs_err": float(np.max(errors)) if len(errors) else math.nan,
             "growth_exponent": float(np.median(growth)) if growth else math.nan,
             "growth_exponent_range": [min(growth), max(growth)] if growth else None,
             "order": order[0] if order else math.nan,
             "statuses": sorted(set(cells["status"].astype(str)))}
    entry["zero"] = bool(np.all(errors <= zero_below)) if zero_below > 0 and len(errors) else False
    return entry


def entry_text(entry: dict, math_text: bool) -> str:
    """``t^1.00 h^1.01``, or ``0 (≤ 3e-15)`` for an error at round-off."""
    if entry["zero"]:
        return f"0 (max {entry['max_abs_err']:.0e})"
    a, b = entry["growth_exponent"], entry["order"]
    ta = "?" if not math.isfinite(a) else f"{a:.2f}"
    hb = "?" if not math.isfinite(b) else f"{b:.2f}"
    return rf"$t^{{{ta}}}\,h^{{{hb}}}$" if math_text else f"t^{ta} h^{hb}"


def book_math(text: str) -> str:
    """The seed's O(t²h) in mathtext, so both columns share one look."""
    return "$" + text.replace("O(", r"\mathcal{O}(").replace("²", "^2") + "$" if text.startswith(
        "O(") else text


def table_data(results, figure: dict) -> dict:
    table = figure["table"]
    rows = []
    for row in table["rows"]:
        entries = [measured(results, row, col, table["zero_below"]) for col in table["columns"]]
        rows.append({"label": row["label"], "cells": row["cells"], "book": row["book"],
                     "measured": entries})
    return {"columns": table["columns"], "zero_below": table["zero_below"], "rows": rows}


def draw_table(results, figure: dict):
    """The matplotlib figure of the table and its manifest entry."""
    import matplotlib.pyplot as plt
    from gnibench.reports.figures.plot import title_text
    from gnibench.reports.figures.style import color_of, method_key

    data = table_data(results, figure)
    ncols = len(data["columns"])
    labels = ["\n".join(textwrap.wrap(row["label"], 30)) for row in data["rows"]]
    units = 2 + 0.4 + sum(1 + 0.8 * lab.count("\n") + 0.4 for lab in labels)
    width = figure.get("size") or [3.2 + 3.0 * ncols, 0.9 + 0.3 * units]
    fig = plt.figure(figsize=tuple(width), layout="constrained")
    fig.suptitle(title_text(figure, width[0]), fontsize=10.5)
    ax = fig.add_subplot(1, 1, 1)
    ax.axis("off")
    header = ["method"]
    for col in data["columns"]:
        header += [f"{col['label']}\n[HLW]", f"{col['label']}\nmeasured"]
    body = []
    for label, row in zip(labels, data["rows"]):
        line = [label]
        for book, entry in zip(row["book"], row["measured"]):
            line += [book_math(book), entry_text(entry, math_text=True)]
        body.append(line)
    first = 3.2 / width[0]
    widths = [first] + [(1 - first) / (2 * ncols)] * (2 * ncols)
    tab = ax.table(cellText=body, colLabels=header, cellLoc="center", colWidths=widths,
                   bbox=[0, 0, 1, 1])
    tab.auto_set_font_size(False)
    tab.set_fontsize(9.5)
    for (r, c), cell in tab.get_celld().items():
        text_lines = 2 if r == 0 else max(1, labels[r - 1].count("\n") + 1)
        cell.set_height((1 + 0.8 * (text_lines - 1) + 0.4) / units)
        if r == 0:
            cell.set_text_props(fontweight="bold")
            cell.set_facecolor("#EEEEEE")
        elif c == 0:
            key = method_key(results.cell_row(figure["table"]["rows"][r - 1]["cells"][0]))
            cell.set_text_props(color=color_of(key), fontweight="bold")
    manifest = [{"title": "", "xlabel": "", "ylabel": "", "table": data,
                 "curves": [{"label": row["label"], "cells": row["cells"],
                             "points": sum(1 for e in row["measured"]
                                           if e["zero"] or math.isfinite(e["growth_exponent"]))}
                            for row in data["rows"]]}]
    return fig, manifest


def markdown(data: dict) -> str:
    """The table as Markdown: the seed's entry and the measured one, side by side."""
    header = ["method"] + [f"{c['label']} ([HLW] / measured)" for c in data["columns"]]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in data["rows"]:
        cells = [row["label"]] + [f"{b} / {entry_text(e, math_text=False)}"
                                  for b, e in zip(row["book"], row["measured"])]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
