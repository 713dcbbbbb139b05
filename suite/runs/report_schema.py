"""The schema of an experiment's ``[report]`` section: what the report (and the plot helpers of
``gnibench.plot``) draws of the experiment's tables. Nothing here changes a cell or its numbers::

    [report]
    cells = "auto"            # time plots: "auto", "all", or a list of cell ids [3, 7, 12]
    family = "dop853"         # time plots: only this family's sweep (its label or method id)
    time_axis = "auto"        # t axis of the time plots: "auto", "linear" or "log"
    error_axis = "log"        # error axis of the time plots: "log" or "linear"
    figures = ["invariants", "global-error", "work-precision", "league"]   # which figures
    measures = ["max_global_error"]     # the errors of the work-precision diagrams
    costs = ["nfev", "wall"]            # their cost axes
    target = 1e-8             # the target accuracy of the index card's headline

``cells = "auto"`` draws every cell when there are at most 12, else one cell per family (the
middle of its sweep by nfev); ``time_axis = "auto"`` is logarithmic when the samples span two
decades or more. The cell ids and the family are checked against the experiment's cells when it
is read (:func:`gnibench.suite.runs.experiment.parse_experiment`).
"""
from __future__ import annotations

import re
from typing import Annotated, Literal

from gnibench.suite.foundation.budgets import MAX_REPEAT  # noqa: F401 - re-exported
from gnibench.suite.foundation.records import Allowed, Line, Positive, Record, key, refuse
from pydantic import AfterValidator, Field

FIGURES = ("invariants", "global-error", "eta", "sections", "work-precision", "league")
COSTS = ("nfev", "wall")
#: an error measure of cells.parquet a work-precision diagram can draw
MEASURE = re.compile(r"^(final_global_error|max_global_error|max_abs_err_[A-Za-z_][A-Za-z0-9_]*)$")


def _distinct(value: list) -> list:
    if len(set(value)) != len(value):
        raise refuse()
    return value


def _measures(value: list[str]) -> list[str]:
    for m in value:
        if not MEASURE.match(m):
            raise ValueError(f"bad measure {m!r}; allowed: final_global_error, max_global_error "
                             f"or max_abs_err_<I> (an integral's name)")
    return _distinct(value)


CellIds = Annotated[list[Annotated[int, Field(ge=0, le=10 ** 7)]],
                    Allowed("a non-empty list of cell ids"), Field(min_length=1, max_length=200),
                    AfterValidator(_distinct)]
Figures = Annotated[list[Literal[FIGURES]], Allowed(f"a list of {', '.join(FIGURES)}"),
                    Field(max_length=len(FIGURES)), AfterValidator(_distinct)]
Measures = Annotated[list[Line], Allowed("a list of final_global_error, max_global_error, "
                                         "max_abs_err_<I>"), Field(min_length=1, max_length=16),
                     AfterValidator(_measures)]
Costs = Annotated[list[Literal[COSTS]], Allowed("a non-empty list of nfev, wall"),
                  Field(min_length=1, max_length=2), AfterValidator(_distinct)]


class ReportOptions(Record):
    """``[report]``: what the report draws (see the module docstring)."""

    cells: Literal["auto", "all"] | CellIds = key(
        "auto", "the cells of the time plots: auto (all up to 12, else one per family), all, "
                "or a list of cell ids", "\"auto\", \"all\" or a list of cell ids")
    family: Line | None = key(None, "the time plots show only this family's cells (its label, "
                                    "e.g. \"dop853\", or its method id)")
    time_axis: Literal["auto", "linear", "log"] = key(
        "auto", "the t axis of the time plots (auto: log when the samples span two decades)",
        "auto, linear or log")
    error_axis: Literal["log", "linear"] = key("log", "the error axis of the time plots",
                                               "log or linear")
    figures: Figures = key(list(FIGURES), "the figures drawn, in the page's order")
    measures: Measures | None = key(None, "the errors of the work-precision diagrams (default: "
                                          "final and max global error, and the first integral's)")
    costs: Costs = key(list(COSTS), "the cost axes of the work-precision diagrams")
    target: Positive | None = key(None, "the target accuracy of the headline on the index card "
                                        "(default: the smallest --accuracy threshold)")


def report_options(doc: dict | None, where: str = "report") -> ReportOptions:
    """The options of a ``[report]`` table (or of the API's ``plots=`` dict), validated; the
    defaults for None."""
    from gnibench.suite.foundation.records import validate

    return validate(ReportOptions, doc or {}, where)
