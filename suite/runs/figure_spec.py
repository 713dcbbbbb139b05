"""The ``[figure]`` section of an experiment file: a figure or table of a seed, as data.

Validated with the experiment, before anything runs, against its expanded cells; the result is a
plain JSON-able dict (the *normalized figure*) that the runner stores in the tables' metadata, so
the drawing (:mod:`gnibench.reports.figures`) reads only the results directory. The keys, their
types, bounds and sizes are the records of :mod:`gnibench.suite.runs.figure_schema` (validated with
the whole experiment file; tables in ``suite/experiments/README.md``); what is checked here needs
the cells: selections, columns, label placeholders, sample times, zoom targets. In short::

    [figure]
    number  = "Fig 1.4"            # as in the seed ("Fig 2.3", "Table 2.1")
    caption = "..."                # the seed's caption, one line
    kind    = "plot"               # plot (default) | table
    layout  = [1, 3]               # rows, columns of panels (default: one row)
    size    = [12.0, 4.2]          # inches (default: from the layout)
    note    = "..."                # what the seed says, what we got, choices of the drawing

    [[figure.panels]]
    title = "symplectic Euler"     # panel title
    x = "q"                        # default columns of its curves (samples.parquet)
    y = "p"
    xlabel = "q"                   # axis labels with the seed's symbols (unicode or $mathtext$)
    ylabel = "p"
    xscale = "linear"              # linear | log (log plots |value|: say so in the label)
    yscale = "linear"
    xlim = [-3.2, 3.2]             # optional limits; aspect = "equal" for phase planes
    legend = "best"                # best | upper left | ... | outside | none
    zoom = { of = 0, mark = true } # a magnification of panel 0 (its curves; needs xlim, ylim)
    note = "..."

    [[figure.panels.curves]]
    cells = { group = 1 }          # group (int or list), index (within the groups), cell (ids)
    label = "p0 = 0.7, 1.4, 2.1 (h = {=h})"  # legend ("" or none: no entry); {=column:fmt} =
                                   # a cells.parquet value (median over the curve's cells)
    style = "line"                 # line | dots | points | markers | polygon | pixels (tiny
                                   # dots for dense clouds: 0.6 pt at 140 000 points, larger
                                   # for fewer, up to 2 pt); dots, points, pixels: not thinned
    at = [0, 1.3, 2.6]             # polygon / points: the sample times drawn (one shape each)
    color = "exact"                # a palette key (default: the cell's method)
    start = "J"                    # text at the first point of the curve
    xwrap = [-3.14159, 3.14159]    # x taken modulo the interval (an angle on the circle)
    linewidth = 0.5                # points (default 1.2)
    where = { chart = 1 }          # only the samples whose columns have these values (e.g. the
                                   # section points in chart Γ1 of euler-so4, [B] Fig 26)
    pieces = true                  # a line broken where it jumps (a map back into a fundamental
                                   # domain, [B] §8.1), the origin of each piece numbered 1, 2, ...

    [[figure.panels.fields]]       # a function of the problem record on a grid (no integration)
    problem = "henon-heiles"       # PROBLEM spec
    function = "H"                 # an integral, or "field" (the vector field, kind quiver)
    kind = "contour"               # contour | quiver
    x = "q1"                       # state on each axis; fixed = the other states (default y0)
    y = "q2"
    fixed = { p1 = 0.0, p2 = 0.0 } # or an expression of the axis states: { q1 = "0.1 / p2" }
    xrange = [-1, 1]
    yrange = [-1, 1]
    n = 200                        # grid points per axis
    levels = [0.02, 0.05]          # or through = [[x, y], ...]: the levels through points
    label = "level curves of U"

A ``kind = "table"`` figure has ``[figure.table]`` instead of panels: ``columns`` (``of`` an
error: an integral or ``global``, and a ``label``), ``zero_below`` (a round-off threshold) and
``[[figure.table.rows]]`` with ``label``, ``cells`` and the seed's entries ``book``; each entry
shows the fitted growth exponent in t and exponent in h (metrics ``growth`` and ``order``).
"""
from __future__ import annotations

import functools
import re

from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.runs.figure_fields import parse_field
from gnibench.suite.runs.figure_schema import PLACEHOLDER, Curve, Figure, Panel, Select, Table

FIXED_COLUMNS = ("t", "steps", "nfev")
#: columns of the samples of a section cell (``section = N``) besides the states
SECTION_COLUMNS = ("crossing", "chart")
#: columns that may be negative: a log axis plots their absolute value
_SIGNED = re.compile(r"^(err_|relerr_|eta_phase$|pericenter_angle$)")


def parse_figure(fig: Figure, cells, *, name: str, reference: str, scale: str, where: str) -> dict:
    """Check a validated ``[figure]`` record against the experiment's cells; the normalized
    figure (a plain JSON-able dict)."""
    out = {"id": name, "number": fig.number, "caption": fig.caption, "reference": reference,
           "kind": fig.kind, "scale": scale, "note": fig.note}
    size = list(fig.size) if fig.size is not None else None
    if fig.kind == "table":
        out["table"] = _table(fig.table, cells, f"{where}.table")
        out["layout"], out["size"] = [1, 1], size
        return out
    panels = fig.panels
    out["panels"] = [_panel(p, i, cells, len(panels), f"{where}.panels[{i}]")
                     for i, p in enumerate(panels)]
    out["layout"] = list(fig.layout) if fig.layout is not None else [1, len(panels)]
    if out["layout"][0] * out["layout"][1] < len(panels):
        raise UserError(f"{where}: bad layout = {out['layout']!r}; allowed: [rows, columns] with "
                        f"room for the {len(panels)} panels")
    out["size"] = size
    return out


def _panel(panel: Panel, index: int, cells, npanels: int, where: str) -> dict:
    out = {"title": panel.title, "note": panel.note, "xscale": panel.xscale,
           "yscale": panel.yscale, "xlim": _list(panel.xlim), "ylim": _list(panel.ylim),
           "aspect": panel.aspect, "legend": panel.legend, "zoom": None}
    x, y = panel.x, panel.y
    out["xlabel"] = panel.xlabel if panel.xlabel is not None else x
    out["ylabel"] = panel.ylabel if panel.ylabel is not None else y
    if panel.zoom is not None:
        of = panel.zoom.of
        if not of < npanels or of == index:
            raise UserError(f"{where}: bad zoom of = {of}; allowed: the index of another panel "
                            f"(0 to {npanels - 1})")
        out["zoom"] = {"of": of, "mark": panel.zoom.mark}
    out["curves"] = [_curve(c, cells, x, y, f"{where}.curves[{k}]")
                     for k, c in enumerate(panel.curves)]
    out["fields"] = [parse_field(f, f"{where}.fields[{k}]") for k, f in enumerate(panel.fields)]
    for axis in ("x", "y"):
        if out[f"{axis}scale"] == "log":
            signed = {c[axis] for c in out["curves"] if _SIGNED.match(c[axis])}
            if signed and "|" not in out[f"{axis}label"]:
                raise UserError(f"{where}: a log {axis}-axis plots |{min(signed)}|: say so "
                                f"in {axis}label (e.g. '|H − H₀|')")
    return out


def _list(value):
    return None if value is None else list(value)


def select(sel: Select, cells, where: str) -> list[int]:
    """Cell ids chosen by ``{group = g, index = i}`` or ``{cell = c}`` (ints or lists)."""
    def ints(key, values, bound):
        if not all(v < bound for v in values):
            raise UserError(f"{where}: bad {key} = {values!r}; allowed: integers from 0 to "
                            f"{bound - 1}")
        return values

    if sel.cell is not None:
        return ints("cell", sel.cell, len(cells))
    ngroups = 1 + max((c.group for c in cells), default=-1)
    chosen = [c.id for g in ints("group", sel.group, max(ngroups, 1)) for c in cells
              if c.group == g]
    if sel.index is not None:
        chosen = [chosen[i] for i in ints("index", sel.index, len(chosen) or 1)
                  if i < len(chosen)]
    if not chosen:
        raise UserError(f"{where}: the selection {sel.model_dump(exclude_none=True)!r} has no "
                        "cells")
    return chosen


def _curve(curve: Curve, cells, x: str, y: str, where: str) -> dict:
    ids = select(curve.cells, cells, f"{where}: cells")
    out = {"cells": ids, "label": curve.label, "x": curve.x if curve.x is not None else x,
           "y": curve.y if curve.y is not None else y, "style": curve.style, "at": None,
           "color": curve.color, "start": curve.start, "xwrap": _list(curve.xwrap),
           "ywrap": _list(curve.ywrap), "linewidth": curve.linewidth, "pieces": curve.pieces}
    if not out["y"]:
        raise UserError(f"{where}: no y column (give y in the curve or its panel)")
    chosen = [cells[i] for i in ids]
    out["method"] = chosen[0].method
    for axis in ("x", "y"):
        for c in chosen:
            why = column_problem(out[axis], c)
            if why:
                raise UserError(f"{where}: {axis} = {out[axis]!r}: {why}")
    out["where"] = _where(curve.where, chosen, where)
    _check_label(out["label"], chosen, where)
    if curve.at is not None:
        out["at"] = list(curve.at)
        for c in chosen:
            for t in out["at"]:
                if not _sampled(c, t):
                    raise UserError(f"{where}: cell {c.id} ({c.method}) has no sample at t = {t} "
                                    f"(samples every {c.every} steps of h = {c.h}, up to "
                                    f"t = {c.t_final:.6g})")
    return out


def _where(value: dict, chosen, where: str) -> dict:
    """``where = {column = number, ...}``: the samples kept (columns of every chosen cell)."""
    out = {}
    for column, v in value.items():
        why = ""
        for c in chosen:
            why = why or column_problem(column, c)
        if why:
            raise UserError(f"{where}: where {column!r}: {why}")
        out[column] = float(v)
    return out


def _sampled(cell, t: float) -> bool:
    """Whether a fixed-step cell has a sample at time t (every ``every`` steps, and the end)."""
    tol = 1e-9 * max(1.0, abs(cell.t_final))
    if abs(t - cell.t_final) <= tol:
        return True
    k = t / (cell.h * cell.every)
    return 0 <= t <= cell.t_final + tol and abs(k - round(k)) * cell.h * cell.every <= tol


@functools.lru_cache(maxsize=256)
def _problem_facts(problem_text: str) -> tuple[tuple[str, ...], tuple[str, ...], bool]:
    """(states, integrals, has an exact solution) of a canonical problem spec."""
    from gnibench.suite.cell.spec import parse_problem
    from gnibench.suite.metrics.base import integral_names

    problem = parse_problem(problem_text)
    return problem.record.state, integral_names(problem), problem.record.exact is not None


@functools.lru_cache(maxsize=256)
def _charts(problem_text: str) -> tuple[str, ...]:
    """'1', ..., 'k' for the charts Γ1..Γk of a multi-chart section (euler-so4); () otherwise."""
    from gnibench.suite.cell.spec import parse_problem

    record = parse_problem(problem_text).record
    k = next((s.charts for s in record.sections if s.chart is not None), 0)
    return tuple(str(i) for i in range(1, k + 1))


def _metric_columns(cell) -> tuple[set[str], set[str]]:
    """(sample columns, per-cell columns) the chosen metrics of a cell write."""
    from gnibench.suite.metrics.compute import parse_metrics, selected

    _, integrals, exact = _problem_facts(cell.problem)
    errors = list(integrals) + (["global"] if exact else [])
    columns, scalars = set(), set()
    for choice in selected(parse_metrics(list(cell.metrics))):
        of = choice.values.get("of") or errors
        for names, out in ((choice.metric.columns, columns), (choice.metric.scalars, scalars)):
            for template, _ in names:
                subs = {"<I>": integrals, "<X>": of, "<k>": _charts(cell.problem)}
                key = next((k for k in subs if k in template), None)
                out.update([template.replace(key, v) for v in subs[key]] if key else [template])
    if not exact:
        columns.discard("global_error")
    return columns, scalars


def column_problem(column: str, cell) -> str:
    """Why ``column`` is not in the samples of ``cell`` ("" when it is)."""
    states, _, exact = _problem_facts(cell.problem)
    if column in FIXED_COLUMNS or column in states:
        return ""
    if getattr(cell, "section", None) is not None and column in SECTION_COLUMNS:
        return ""
    columns, _ = _metric_columns(cell)
    if column in columns:
        return ""
    if column == "global_error" and not exact:
        return f"{cell.problem} has no exact solution"
    known = list(FIXED_COLUMNS) + list(states) + sorted(columns)
    near = unknown("column", column, known)
    return f"not a column of cell {cell.id} ({cell.problem} {cell.method}); {near}"


def _check_label(label: str, cells, where: str) -> None:
    """A label's {=placeholders} must be per-cell values of its cells (cells.parquet columns)."""
    fixed = {"h", "t_end", "t_final", "steps", "nfev", "cell", "final_global_error",
             "max_global_error"}
    for match in PLACEHOLDER.finditer(label):
        name = match.group(1)                    # its format is checked by the schema
        for c in cells:
            _, integrals, _ = _problem_facts(c.problem)
            scalars = _metric_columns(c)[1] | {f"max_abs_err_{i}" for i in integrals}
            if name not in fixed and name not in scalars:
                raise UserError(f"{where}: label placeholder {{={name}}} is not a value of cell "
                                f"{c.id}; allowed: {', '.join(sorted(fixed | scalars))}")


def _table(table: Table, cells, where: str) -> dict:
    cols = [{"of": col.of, "label": col.label} for col in table.columns]
    out = {"columns": cols, "zero_below": table.zero_below, "rows": []}
    for r, row in enumerate(table.rows):
        here = f"{where}.rows[{r}]"
        ids = select(row.cells, cells, f"{here}: cells")
        for col in cols:
            for c in (cells[i] for i in ids):
                _, scalars = _metric_columns(c)
                need = [m for m, key in (("growth", f"growth_exponent_{col['of']}"),
                                         ("order", f"order_{col['of']}")) if key not in scalars]
                if need:
                    wanted = " and ".join(f"{m}:of={col['of']}" for m in need)
                    raise UserError(f"{here}: column {col['label']!r} needs the metrics "
                                    f"{wanted} for cell {c.id} ({c.method})")
        out["rows"].append({"label": row.label, "cells": ids, "book": list(row.book),
                            "method": cells[ids[0]].method})
    return out
