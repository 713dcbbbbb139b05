"""The ``[figure]`` section of an experiment file: a figure or table of a seed, as data.

Validated with the experiment, before anything runs, against its expanded cells; the result is a
plain JSON-able dict (the *normalized figure*) that the runner stores in the tables' metadata, so
the drawing (:mod:`gnibench.reports.figures`) reads only the results directory. Schema (also in
``suite/experiments/README.md``)::

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
                                   # dots for dense clouds); dots, points, pixels are not thinned
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
import math
import re

from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.runs.figure_fields import parse_field

FIGURE_KEYS = ("number", "caption", "kind", "layout", "size", "note", "panels", "table")
PANEL_KEYS = ("title", "x", "y", "xlabel", "ylabel", "xscale", "yscale", "xlim", "ylim", "aspect",
              "legend", "zoom", "note", "curves", "fields")
CURVE_KEYS = ("cells", "label", "x", "y", "style", "at", "color", "start", "pieces", "xwrap", "ywrap",
              "linewidth", "where")
SELECT_KEYS = ("group", "index", "cell")
TABLE_KEYS = ("columns", "rows", "zero_below")
ROW_KEYS = ("label", "cells", "book")
KINDS = ("plot", "table")
SCALES = ("linear", "log")
STYLES = ("line", "dots", "points", "markers", "polygon", "pixels")
LEGENDS = ("best", "upper left", "upper right", "lower left", "lower right", "center left",
           "center right", "upper center", "lower center", "outside", "none")
FIXED_COLUMNS = ("t", "steps", "nfev")
#: columns of the samples of a section cell (``section = N``) besides the states
SECTION_COLUMNS = ("crossing", "chart")
#: columns that may be negative: a log axis plots their absolute value
_SIGNED = re.compile(r"^(err_|relerr_|eta_phase$|pericenter_angle$)")


def parse_figure(fig, cells, *, name: str, reference: str, scale: str, where: str) -> dict:
    """Validate a ``[figure]`` table against the experiment's cells; the normalized figure."""
    if not isinstance(fig, dict):
        raise UserError(f"{where}: bad value; allowed: a [figure] table")
    _keys(fig, FIGURE_KEYS, where)
    kind = fig.get("kind", "plot")
    if kind not in KINDS:
        raise UserError(f"{where}: {unknown('kind', str(kind), KINDS)}")
    out = {"id": name, "number": _line(fig, "number", where, True),
           "caption": _line(fig, "caption", where, True), "reference": reference, "kind": kind,
           "scale": scale, "note": _text(fig.get("note", ""), f"{where}: note")}
    if kind == "table":
        if "panels" in fig or "table" not in fig:
            raise UserError(f"{where}: a table figure has [figure.table] and no panels")
        out["table"] = _table(fig["table"], cells, f"{where}.table")
        out["layout"], out["size"] = [1, 1], _pair(fig, "size", where, None, positive=True)
        return out
    panels = fig.get("panels")
    if "table" in fig or not isinstance(panels, list) or not panels:
        raise UserError(f"{where}: a plot figure needs [[figure.panels]] (and no table)")
    out["panels"] = [_panel(p, i, cells, len(panels), f"{where}.panels[{i}]")
                     for i, p in enumerate(panels)]
    layout = fig.get("layout", [1, len(panels)])
    if (not isinstance(layout, list) or len(layout) != 2
            or not all(isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in layout)
            or layout[0] * layout[1] < len(panels)):
        raise UserError(f"{where}: bad layout = {layout!r}; allowed: [rows, columns] with room "
                        f"for the {len(panels)} panels")
    out["layout"] = layout
    out["size"] = _pair(fig, "size", where, None, positive=True)
    return out


def _keys(table: dict, allowed: tuple[str, ...], where: str) -> None:
    if not isinstance(table, dict):
        raise UserError(f"{where}: bad value {table!r}; allowed: a table")
    for key in table:
        if key not in allowed:
            raise UserError(f"{where}: {unknown('key', key, allowed)}")


def _text(value, where: str) -> str:
    if not isinstance(value, str):
        raise UserError(f"{where}: bad value {value!r}; allowed: a string")
    return value


def _line(table: dict, key: str, where: str, required: bool = False, default: str = "") -> str:
    if key not in table:
        if required:
            raise UserError(f"{where}: missing key {key!r} (one line of text)")
        return default
    value = table[key]
    if not isinstance(value, str) or not value.isprintable() or (required and not value.strip()):
        raise UserError(f"{where}: bad {key} = {value!r}; allowed: one line of text")
    return value


def _number(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(f"{where}: bad value {value!r}; allowed: a finite number")
    return float(value)


def _pair(table: dict, key: str, where: str, default, positive: bool = False):
    if key not in table:
        return default
    value = table[key]
    if not isinstance(value, list) or len(value) != 2:
        raise UserError(f"{where}: bad {key} = {value!r}; allowed: two numbers [a, b]")
    a, b = (_number(v, f"{where}: {key}") for v in value)
    if (positive and min(a, b) <= 0) or (not positive and not a < b):
        raise UserError(f"{where}: bad {key} = {value!r}; allowed: "
                        f"{'two numbers > 0' if positive else 'two numbers a < b'}")
    return [a, b]


def _choice(table: dict, key: str, allowed: tuple[str, ...], default: str, where: str) -> str:
    value = table.get(key, default)
    if value not in allowed:
        raise UserError(f"{where}: {unknown(key, str(value), allowed)}")
    return value


def _panel(panel, index: int, cells, npanels: int, where: str) -> dict:
    _keys(panel, PANEL_KEYS, where)
    out = {"title": _line(panel, "title", where), "note": _text(panel.get("note", ""),
                                                                f"{where}: note"),
           "xscale": _choice(panel, "xscale", SCALES, "linear", where),
           "yscale": _choice(panel, "yscale", SCALES, "linear", where),
           "xlim": _pair(panel, "xlim", where, None), "ylim": _pair(panel, "ylim", where, None),
           "aspect": _choice(panel, "aspect", ("auto", "equal"), "auto", where),
           "legend": _choice(panel, "legend", LEGENDS, "best", where), "zoom": None}
    x, y = _line(panel, "x", where, default="t"), _line(panel, "y", where)
    out["xlabel"] = _line(panel, "xlabel", where, default=x)
    out["ylabel"] = _line(panel, "ylabel", where, default=y)
    if "zoom" in panel:
        zoom = panel["zoom"]
        _keys(zoom, ("of", "mark"), f"{where}: zoom")
        of, mark = zoom.get("of"), zoom.get("mark", True)
        if (isinstance(of, bool) or not isinstance(of, int) or not 0 <= of < npanels
                or of == index or not isinstance(mark, bool)):
            raise UserError(f"{where}: bad zoom = {zoom!r}; allowed: of = the index of another "
                            f"panel (0 to {npanels - 1}), mark = true|false")
        if out["xlim"] is None or out["ylim"] is None or "curves" in panel:
            raise UserError(f"{where}: a zoom panel shows the curves of panel {of} in xlim, ylim "
                            "(give both, and no curves)")
        out["zoom"] = {"of": of, "mark": mark}
    curves = panel.get("curves", [])
    fields = panel.get("fields", [])
    if not isinstance(curves, list) or not isinstance(fields, list) or (
            not curves and not fields and "zoom" not in panel):
        raise UserError(f"{where}: needs [[...curves]] or [[...fields]] (or a zoom)")
    out["curves"] = [_curve(c, cells, x, y, f"{where}.curves[{k}]") for k, c in enumerate(curves)]
    out["fields"] = [parse_field(f, f"{where}.fields[{k}]") for k, f in enumerate(fields)]
    for axis in ("x", "y"):
        if out[f"{axis}scale"] == "log":
            signed = {c[axis] for c in out["curves"] if _SIGNED.match(c[axis])}
            if signed and "|" not in out[f"{axis}label"]:
                raise UserError(f"{where}: a log {axis}-axis plots |{min(signed)}|: say so "
                                f"in {axis}label (e.g. '|H − H₀|')")
    return out


def select(sel, cells, where: str) -> list[int]:
    """Cell ids chosen by ``{group = g, index = i}`` or ``{cell = c}`` (ints or lists)."""
    _keys(sel, SELECT_KEYS, where)
    if not sel:
        raise UserError(f"{where}: empty cells selection; allowed: group, index, cell")

    def ints(key, bound):
        value = sel[key]
        values = value if isinstance(value, list) else [value]
        if not values or not all(isinstance(v, int) and not isinstance(v, bool) and 0 <= v < bound
                                 for v in values):
            raise UserError(f"{where}: bad {key} = {value!r}; allowed: integers from 0 to "
                            f"{bound - 1}")
        return values

    if "cell" in sel:
        if set(sel) != {"cell"}:
            raise UserError(f"{where}: cell selects by id alone (no group or index with it)")
        return ints("cell", len(cells))
    ngroups = 1 + max((c.group for c in cells), default=-1)
    if "group" not in sel:
        raise UserError(f"{where}: index needs group")
    chosen = [c.id for g in ints("group", max(ngroups, 1)) for c in cells if c.group == g]
    if "index" in sel:
        chosen = [chosen[i] for i in ints("index", len(chosen) or 1) if i < len(chosen)]
    if not chosen:
        raise UserError(f"{where}: the selection {sel!r} has no cells")
    return chosen


def _curve(curve, cells, x: str, y: str, where: str) -> dict:
    _keys(curve, CURVE_KEYS, where)
    ids = select(curve.get("cells"), cells, f"{where}: cells")
    out = {"cells": ids, "label": _line(curve, "label", where),
           "x": _line(curve, "x", where, default=x), "y": _line(curve, "y", where, default=y),
           "style": _choice(curve, "style", STYLES, "line", where), "at": None,
           "color": _line(curve, "color", where), "start": _line(curve, "start", where),
           "xwrap": _pair(curve, "xwrap", where, None), "ywrap": _pair(curve, "ywrap", where, None),
           "linewidth": _number(curve.get("linewidth", 1.2), f"{where}: linewidth")}
    out["pieces"] = curve.get("pieces", False)
    if not isinstance(out["pieces"], bool):
        raise UserError(f"{where}: bad pieces = {out['pieces']!r}; allowed: true or false")
    if out["pieces"] and out["style"] != "line":
        raise UserError(f"{where}: pieces needs style = \"line\" (a broken line)")
    if not 0 < out["linewidth"] <= 10:
        raise UserError(f"{where}: bad linewidth = {out['linewidth']}; allowed: 0 < width <= 10")
    if not out["y"]:
        raise UserError(f"{where}: no y column (give y in the curve or its panel)")
    chosen = [cells[i] for i in ids]
    out["method"] = chosen[0].method
    for axis in ("x", "y"):
        for c in chosen:
            why = column_problem(out[axis], c)
            if why:
                raise UserError(f"{where}: {axis} = {out[axis]!r}: {why}")
    out["where"] = _where(curve.get("where", {}), chosen, where)
    _check_label(out["label"], chosen, where)
    if "at" in curve:
        at = curve["at"]
        if not isinstance(at, list) or not at:
            raise UserError(f"{where}: bad at = {at!r}; allowed: a list of sample times")
        out["at"] = [_number(v, f"{where}: at") for v in at]
        for c in chosen:
            for t in out["at"]:
                if not _sampled(c, t):
                    raise UserError(f"{where}: cell {c.id} ({c.method}) has no sample at t = {t} "
                                    f"(samples every {c.every} steps of h = {c.h}, up to "
                                    f"t = {c.t_final:.6g})")
    elif out["style"] == "polygon":
        raise UserError(f"{where}: style polygon needs at = [times] (one polygon per time)")
    return out


def _where(value, chosen, where: str) -> dict:
    """``where = {column = number, ...}``: the samples kept (columns of every chosen cell)."""
    if not isinstance(value, dict):
        raise UserError(f"{where}: bad where = {value!r}; allowed: a table {{column = number}}")
    out = {}
    for column, v in value.items():
        why = column_problem(column, next(iter(chosen))) if chosen else ""
        for c in chosen:
            why = why or column_problem(column, c)
        if why:
            raise UserError(f"{where}: where {column!r}: {why}")
        out[column] = _number(v, f"{where}: where {column}")
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


#: a per-cell value in a label: {=name} or {=name:format} (braces alone stay mathtext)
PLACEHOLDER = re.compile(r"\{=([A-Za-z_][A-Za-z0-9_]*)(?::([^{}]*))?\}")


def _check_label(label: str, cells, where: str) -> None:
    """A label's {=placeholders} must be per-cell values of its cells (cells.parquet columns)."""
    fixed = {"h", "t_end", "t_final", "steps", "nfev", "cell", "final_global_error",
             "max_global_error"}
    for match in PLACEHOLDER.finditer(label):
        name, spec = match.group(1), match.group(2)
        try:
            format(1.0, spec or "")
        except ValueError:
            raise UserError(f"{where}: bad format {spec!r} of {{={name}}}; allowed: a float "
                            f"format such as .2f or .1e") from None
        for c in cells:
            _, integrals, _ = _problem_facts(c.problem)
            scalars = _metric_columns(c)[1] | {f"max_abs_err_{i}" for i in integrals}
            if name not in fixed and name not in scalars:
                raise UserError(f"{where}: label placeholder {{={name}}} is not a value of cell "
                                f"{c.id}; allowed: {', '.join(sorted(fixed | scalars))}")


def _table(table, cells, where: str) -> dict:
    _keys(table, TABLE_KEYS, where)
    columns, rows = table.get("columns"), table.get("rows")
    if not isinstance(columns, list) or not columns or not isinstance(rows, list) or not rows:
        raise UserError(f"{where}: needs columns = [{{of = ..., label = ...}}, ...] and "
                        f"[[figure.table.rows]]")
    cols = []
    for k, col in enumerate(columns):
        _keys(col, ("of", "label"), f"{where}.columns[{k}]")
        cols.append({"of": _line(col, "of", f"{where}.columns[{k}]", True),
                     "label": _line(col, "label", f"{where}.columns[{k}]", True)})
    zero = table.get("zero_below", 0.0)
    out = {"columns": cols, "zero_below": _number(zero, f"{where}: zero_below"), "rows": []}
    for r, row in enumerate(rows):
        here = f"{where}.rows[{r}]"
        _keys(row, ROW_KEYS, here)
        ids = select(row.get("cells"), cells, f"{here}: cells")
        book = row.get("book")
        if (not isinstance(book, list) or len(book) != len(cols)
                or not all(isinstance(b, str) and b.isprintable() for b in book)):
            raise UserError(f"{here}: bad book = {book!r}; allowed: {len(cols)} one-line texts, "
                            f"the seed's entries")
        for col in cols:
            for c in (cells[i] for i in ids):
                _, scalars = _metric_columns(c)
                need = [m for m, key in (("growth", f"growth_exponent_{col['of']}"),
                                         ("order", f"order_{col['of']}")) if key not in scalars]
                if need:
                    wanted = " and ".join(f"{m}:of={col['of']}" for m in need)
                    raise UserError(f"{here}: column {col['label']!r} needs the metrics "
                                    f"{wanted} for cell {c.id} ({c.method})")
        out["rows"].append({"label": _line(row, "label", here, True), "cells": ids,
                            "book": book, "method": cells[ids[0]].method})
    return out
