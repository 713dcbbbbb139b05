"""The schema of an experiment's ``[figure]`` section as typed records: figure, panels, curves,
cell selections, zoom, field layers and tables (types, bounds, sizes, unknown keys and what each
key allows, in one place; the README table of ``suite/experiments/README.md`` is rendered from
these records). What needs the cells (columns, selections, sample times) is checked against them
in :mod:`gnibench.suite.runs.figure_spec`; what needs the problem registry (states, integrals) in
:mod:`gnibench.suite.runs.figure_fields`.

Every size is bounded (the drawing allocates by them): layout at most 12 x 12 panels, size at most
50 inches a side, at most 64 panels, 200 curves a panel, 1000 grid points an axis, label formats
of width at most 100 and precision at most 30, expressions as :mod:`gnibench.suite.foundation.
expressions` bounds them.
"""
from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from gnibench.suite.foundation.records import Allowed, Line, NonEmptyLine, Number, Record, Text, key, refuse
from pydantic import AfterValidator, Field, model_validator

LEGENDS = Literal["best", "upper left", "upper right", "lower left", "lower right", "center left",
                  "center right", "upper center", "lower center", "outside", "none"]
MAX_SIDE = 12            # panels in a row or a column
MAX_INCHES = 50.0
MAX_GRID = 1000          # grid points of a field per axis
MAX_WIDTH, MAX_PRECISION = 100, 30
#: a per-cell value in a label: {=name} or {=name:format} (braces alone stay mathtext)
PLACEHOLDER = re.compile(r"\{=([A-Za-z_][A-Za-z0-9_]*)(?::([^{}]*))?\}")
#: a float format spec: [[fill]align][sign][z][#][0][width][grouping][.precision][type]
_FORMAT = re.compile(r"^(?:.?[<>=^])?[+\- ]?z?#?0?(?P<width>\d+)?[,_]?(?:\.(?P<precision>\d+))?"
                     r"[eEfFgGn%]?$")
FORMATS = (f"a float format such as .2f or .1e (width at most {MAX_WIDTH}, precision at most "
           f"{MAX_PRECISION})")


def check_format(spec: str) -> str:
    """A label placeholder's format: a bounded float format (a width of 5e9 would allocate GBs)."""
    m = _FORMAT.match(spec)
    if not m or int(m["width"] or 0) > MAX_WIDTH or int(m["precision"] or 0) > MAX_PRECISION:
        raise ValueError(f"bad format {spec[:40]!r}; allowed: {FORMATS}")
    try:
        format(1.0, spec)
    except ValueError:
        raise ValueError(f"bad format {spec[:40]!r}; allowed: {FORMATS}") from None
    return spec


def _label(text: str) -> str:
    for match in PLACEHOLDER.finditer(text):
        try:
            check_format(match.group(2) or "")
        except ValueError as e:
            raise ValueError(f"label: {{={match.group(1)}}}: {e}") from None
    return text


def _ints(value):
    values = value if isinstance(value, list) else [value]
    if not values or len(values) > 10_000 or not all(
            isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 10 ** 7 for v in values):
        raise refuse()
    return values


def _ordered(pair: list[float]) -> list[float]:
    if not pair[0] < pair[1]:
        raise refuse()
    return pair


Label = Annotated[Line, Allowed("one line of text; {=column:format} shows a cells.parquet value "
                                f"({FORMATS})"), AfterValidator(_label)]
Ints = Annotated[Any, Allowed("an integer from 0 or a list of them"), AfterValidator(_ints)]
Interval = Annotated[list[Number], Allowed("two numbers [a, b] with a < b"),
                     Field(min_length=2, max_length=2), AfterValidator(_ordered)]
Point = Annotated[list[Number], Field(min_length=2, max_length=2)]
Numbers = Annotated[list[Number], Allowed("a non-empty list of at most 1000 finite numbers"),
                    Field(min_length=1, max_length=1000)]


class Select(Record):
    """``cells = {...}``: the cells of a curve or a table row."""

    group: Ints | None = key(None, "[[cells]] groups (from 0)")
    index: Ints | None = key(None, "positions within the chosen groups (needs group)")
    cell: Ints | None = key(None, "cell ids (alone)")

    @model_validator(mode="after")
    def _how(self):
        given = [k for k in ("group", "index", "cell") if getattr(self, k) is not None]
        if not given:
            raise ValueError("empty cells selection; allowed: group, index, cell")
        if self.cell is not None and len(given) > 1:
            raise ValueError("cell selects by id alone (no group or index with it)")
        if self.index is not None and self.group is None:
            raise ValueError("index needs group")
        return self


class Zoom(Record):
    of: Annotated[int, Field(ge=0, le=63)] = key(doc="the index of the magnified panel",
                                                 allowed="the index of another panel (0 to 63)")
    mark: bool = key(True, "mark the window in that panel")


class Curve(Record):
    """``[[figure.panels.curves]]``: one curve (or set of points) over some cells."""

    cells: Select = key(doc="the cells drawn", allowed="{group = g, index = i} or {cell = c} "
                                                       "(integers or lists)")
    label: Label = key("", "the legend entry (\"\": none)")
    x: Line | None = key(None, "column of samples.parquet on x (default: the panel's)")
    y: Line | None = key(None, "column of samples.parquet on y (default: the panel's)")
    style: Literal["line", "dots", "points", "markers", "polygon", "pixels"] = key(
        "line", "dots, points, pixels are not thinned; polygon needs at")
    at: Numbers | None = key(None, "polygon / points: the sample times drawn")
    color: Line = key("", "a palette key (default: the cell's method)")
    start: Line = key("", "text at the first point of the curve")
    pieces: bool = key(False, "a line broken where it jumps, each piece's origin numbered")
    xwrap: Interval | None = key(None, "x taken modulo the interval")
    ywrap: Interval | None = key(None, "y taken modulo the interval")
    linewidth: Annotated[float, Field(gt=0, le=10)] = key(1.2, "points",
                                                          allowed="0 < width <= 10")
    where: Annotated[dict[Line, Number], Field(max_length=16)] = key(
        {}, "only the samples whose columns have these values",
        "a table {column = finite number}")

    @model_validator(mode="after")
    def _style(self):
        if self.pieces and self.style != "line":
            raise ValueError("pieces needs style = \"line\" (a broken line)")
        if self.style == "polygon" and self.at is None:
            raise ValueError("style polygon needs at = [times] (one polygon per time)")
        return self


class FieldLayer(Record):
    """``[[figure.panels.fields]]``: a function of the problem on a grid (no integration)."""

    problem: Line = key(doc="PROBLEM spec", allowed="a PROBLEM spec string")
    function: Line | None = key(None, "an integral, \"domain\", or \"field\" (quiver)")
    kind: Literal["contour", "quiver"] = key("contour", "level curves or arrows")
    x: Line = key(doc="the state on the x axis", allowed="a state of the problem")
    y: Line = key(doc="the state on the y axis", allowed="a state of the problem")
    fixed: Annotated[dict[Line, Any], Field(max_length=64)] = key(
        {}, "the other states (default y0): numbers or expressions of x and y",
        "a table state = number or expression of the axis states")
    xrange: Interval = key(doc="the grid's x range")
    yrange: Interval = key(doc="the grid's y range")
    n: Annotated[int, Field(ge=2, le=MAX_GRID)] | None = key(
        None, "grid points per axis (default 200 contour, 21 quiver)",
        f"an integer from 2 to {MAX_GRID}")
    levels: Numbers | None = key(None, "contour levels")
    through: Annotated[list[Point], Allowed("a list of at most 1000 [x, y] points"),
                       Field(min_length=1, max_length=1000)] | None = key(
        None, "the levels through these points")
    label: Line = key("", "legend entry")
    color: Line = key("", "a palette key")


class Panel(Record):
    """``[[figure.panels]]``: axes with curves, fields, or a zoom of another panel."""

    title: Line = key("", "the panel title")
    x: Line = key("t", "default column of its curves on x")
    y: Line = key("", "default column of its curves on y")
    xlabel: Line | None = key(None, "axis label with the seed's symbols (default: x)")
    ylabel: Line | None = key(None, "axis label (default: y)")
    xscale: Literal["linear", "log"] = key("linear", "log plots |value|: say so in the label")
    yscale: Literal["linear", "log"] = key("linear", "log plots |value|: say so in the label")
    xlim: Interval | None = key(None, "x limits")
    ylim: Interval | None = key(None, "y limits")
    aspect: Literal["auto", "equal"] = key("auto", "equal for phase planes")
    legend: LEGENDS = key("best", "where the legend goes")
    zoom: Zoom | None = key(None, "a magnification of another panel (needs xlim, ylim)")
    note: Text = key("", "shown with the figure")
    curves: Annotated[list[Curve], Field(max_length=200)] = key([], "[[...curves]]",
                                                                 "[[...curves]] tables")
    fields: Annotated[list[FieldLayer], Field(max_length=32)] = key([], "[[...fields]]",
                                                                     "[[...fields]] tables")

    @model_validator(mode="after")
    def _content(self):
        if self.zoom is not None and (self.xlim is None or self.ylim is None or self.curves):
            raise ValueError(f"a zoom panel shows the curves of panel {self.zoom.of} in xlim, "
                             "ylim (give both, and no curves)")
        if not self.curves and not self.fields and self.zoom is None:
            raise ValueError("needs [[...curves]] or [[...fields]] (or a zoom)")
        return self


class Column(Record):
    of: NonEmptyLine = key(doc="an error: an integral or global")
    label: NonEmptyLine = key(doc="the column header")


class Row(Record):
    label: NonEmptyLine = key(doc="the row label")
    cells: Select = key(doc="the cells of the row", allowed="{group = g, index = i} or "
                                                             "{cell = c}")
    book: Annotated[list[Line], Field(max_length=32)] = key(
        doc="the seed's entries, one per column", allowed="one-line texts, one per column")


class Table(Record):
    """``[figure.table]``: growth exponents in t and exponents in h, against the seed's."""

    columns: Annotated[list[Column], Field(min_length=1, max_length=32)] = key(
        doc="{of = ..., label = ...} per column", allowed="1 to 32 tables {of, label}")
    rows: Annotated[list[Row], Field(min_length=1, max_length=200)] = key(
        doc="[[figure.table.rows]]", allowed="[[figure.table.rows]] tables")
    zero_below: Number = key(0.0, "a round-off threshold")

    @model_validator(mode="after")
    def _books(self):
        for r, row in enumerate(self.rows):
            if len(row.book) != len(self.columns):
                raise ValueError(f"rows[{r}]: bad book; allowed: {len(self.columns)} one-line "
                                 "texts, the seed's entries")
        return self


Side = Annotated[int, Field(ge=1, le=MAX_SIDE)]
Inches = Annotated[float, Field(gt=0, le=MAX_INCHES)]


class Figure(Record):
    """``[figure]``: a figure or table of a seed."""

    number: NonEmptyLine = key(doc="as in the seed (\"Fig 2.3\", \"Table 2.1\")")
    caption: NonEmptyLine = key(doc="the seed's caption")
    kind: Literal["plot", "table"] = key("plot", "a plot (panels) or a table")
    layout: Annotated[list[Side], Field(min_length=2, max_length=2)] | None = key(
        None, "rows, columns of panels (default: one row)",
        f"[rows, columns], each 1 to {MAX_SIDE}, with room for the panels")
    size: Annotated[list[Inches], Field(min_length=2, max_length=2)] | None = key(
        None, "width, height in inches (default: from the layout)",
        f"two numbers > 0 and at most {MAX_INCHES:g} (inches)")
    note: Text = key("", "what the seed says, what we got, choices of the drawing")
    panels: Annotated[list[Panel], Field(max_length=64)] | None = key(
        None, "[[figure.panels]] (a plot)", "[[figure.panels]] tables")
    table: Table | None = key(None, "[figure.table] (a table)")

    @model_validator(mode="after")
    def _kind(self):
        if self.kind == "table" and (self.panels is not None or self.table is None):
            raise ValueError("a table figure has [figure.table] and no panels")
        if self.kind == "plot" and (self.table is not None or not self.panels):
            raise ValueError("a plot figure needs [[figure.panels]] (and no table)")
        if self.layout and self.panels and self.layout[0] * self.layout[1] < len(self.panels):
            raise ValueError(f"bad layout = {self.layout!r}; allowed: [rows, columns] with room "
                             f"for the {len(self.panels)} panels")
        return self
