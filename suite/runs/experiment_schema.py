"""The schema of an experiment file: its top level, its ``[[cells]]`` groups, their scales and point
sets, as typed records (:mod:`gnibench.suite.foundation.records`: types, bounds, sizes, unknown
keys and what each key allows, in one place; the tables of ``suite/experiments/README.md`` are
rendered from these records).

A new key is one line in the record it belongs to (and its use where the file is expanded,
:mod:`gnibench.suite.runs.experiment`). The registry semantics stay with the registries: metric
choices are canonicalized by :func:`gnibench.suite.metrics.compute.parse_metrics` (a validator
here), specs and budgets are checked cell by cell when the groups expand, the figure against the
cells (:mod:`gnibench.suite.runs.figure_spec`).
"""
from __future__ import annotations

import math
import re
from typing import Annotated, Any, Literal

from gnibench.suite.foundation.params import format_float
from gnibench.suite.foundation.records import (
    MAX_ITEMS,
    Allowed,
    Count,
    Line,
    NonEmptyLine,
    Number,
    Positive,
    Record,
    Text,
    key,
    refuse,
    via,
)
from gnibench.suite.runs.figure_schema import Figure
from gnibench.suite.runs.report_schema import MAX_REPEAT, ReportOptions
from pydantic import AfterValidator, Field, model_validator

MAX_POINTS = 10_000
SPECS = "a non-empty list of spec strings"
METRICS = ('a list of metric spec strings, e.g. ["eta", "growth:of=H"] (gnibench list metrics), '
           'each metric at most once')
REFERENCES = ("exact | heyoka[:precision=double|long double|real128,tol=T] | rebound[:tol=T] | "
              "none")
VARY = "a table of option = [values] (numbers, booleans, words, lists of numbers)"
_WORD = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _metrics(value: list[str]) -> tuple[str, ...]:
    """The canonical texts of a metrics list (checked against the metric registry)."""
    from gnibench.suite.metrics.compute import parse_metrics

    return via(lambda v: tuple(c.text() for c in parse_metrics(list(v))))(value)


def _distinct(value: list) -> list:
    if len(set(value)) != len(value):
        raise refuse()
    return value


def value_text(value, where: str) -> str:
    """Spec text of one vary value: floats round-trip, lists become a/b/c."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int) and abs(value) <= 2 ** 63:
        return str(value)
    if isinstance(value, float) and math.isfinite(value):
        return format_float(value)
    if isinstance(value, str) and value and len(value) <= 200 and not re.search(r"[,:=+\s]",
                                                                                   value):
        return value
    if isinstance(value, list) and 0 < len(value) <= 64 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return "/".join(value_text(v, where) for v in value)
    from gnibench.suite.foundation.records import short
    raise ValueError(f"{where}: bad value {short(value)}; allowed: a finite number, a boolean, "
                     "a word, or a list of numbers")


def _vary(table: dict) -> dict[str, dict[str, list[str]]]:
    """``vary`` as {target: {option: [value texts]}}: target 'method' (the base method, also for
    ``vary.method.h``), 'problem' or a modifier id."""
    out: dict[str, dict[str, list[str]]] = {}
    for name, value in table.items():
        items = value.items() if isinstance(value, dict) else [(name, value)]
        target = name if isinstance(value, dict) else "method"
        for option, values in items:
            here = f"vary.{'' if target == 'method' and not isinstance(value, dict) else name + '.'}"
            here += str(option)
            if not _WORD.match(str(option)) or not _WORD.match(name.replace("-", "_")):
                raise ValueError(f"{here}: bad option name; allowed: letters, digits and _")
            if not isinstance(values, list) or not values or len(values) > MAX_ITEMS:
                raise ValueError(f"{here}: bad value {values!r}; allowed: a non-empty list of "
                                 f"at most {MAX_ITEMS} values")
            if option in out.get(target, {}):       # vary.h and vary.method.h: one option
                raise ValueError(f"{here}: the option {option!r} of the {target} is varied twice "
                                 f"(vary.{option} and vary.method.{option} name the same option); "
                                 f"allowed: one list per option")
            out.setdefault(target, {})[option] = [value_text(v, here) for v in values]
    return out


Specs = Annotated[list[Line], Allowed(SPECS), Field(min_length=1, max_length=MAX_ITEMS)]
Metrics = Annotated[list[Line], Allowed(METRICS), Field(max_length=64), AfterValidator(_metrics)]
Reference = Annotated[NonEmptyLine, Allowed(REFERENCES)]
def _dt_out(value: float) -> float:
    """The one rule of a time grid (:func:`gnibench.suite.cell.timegrid.check_dt_out`)."""
    from gnibench.suite.cell.timegrid import check_dt_out

    return via(lambda v: check_dt_out(v, "dt_out ="))(value)


DtOut = Annotated[float, Allowed("a finite number > 0"), AfterValidator(_dt_out)]
Vary = Annotated[dict[str, Any], Allowed(VARY), Field(max_length=64), AfterValidator(_vary)]
Zip = Annotated[list[Line], Allowed("a list of at least two distinct vary keys, e.g. [\"rtol\", "
                                   "\"atol\"] or [\"h\", \"observer.theta\"]"),
              Field(min_length=2, max_length=16), AfterValidator(_distinct)]
Repeat = Annotated[int, Allowed(f"an integer from 1 to {MAX_REPEAT}"), Field(ge=1, le=MAX_REPEAT)]
Pair = Annotated[list[Number], Allowed("two numbers [a, b]"), Field(min_length=2, max_length=2)]
PointList = Annotated[list[Annotated[list[Number], Field(min_length=1, max_length=16)]],
                      Allowed(f"a list of 1 to {MAX_POINTS} points (lists of numbers, one per "
                              "option)"), Field(min_length=1, max_length=MAX_POINTS)]
PointCount = Annotated[int, Allowed(f"an integer from 3 to {MAX_POINTS}"),
                       Field(ge=3, le=MAX_POINTS)]


class Horizon(Record):
    """The keys of a horizon and sampling (shared by the top level, the groups and the scales)."""

    t_end: Positive | None = key(None, "the horizon t_end = T (the last step lands on T); "
                                       "exclusive with steps")
    steps: Count | None = key(None, "the horizon as a number of steps; exclusive with t_end")
    every: Count | None = key(None, "one sample every K steps, plus the final point (default 1)")
    section: Count | None = key(None, "the first N crossings of the problem's Poincaré section "
                                      "(up to the horizon) instead of samples")

    @model_validator(mode="after")
    def _one_horizon(self):
        if self.t_end is not None and self.steps is not None:
            raise ValueError("both steps and t_end given; allowed: exactly one of them")
        return self


class Circle(Record):
    center: Pair = key(doc="the center (one number per option)")
    radius: Positive = key(doc="the radius")
    n: PointCount | None = key(None, "the number of points (counterclockwise from angle 0)")


class Polygon(Record):
    vertices: PointList = key(doc="the vertices (at least 3)")
    n: PointCount | None = key(None, "the number of points, evenly spaced along the outline")


class PointsPatch(Record):
    """A scale's change of a point set (its keys replace the group's)."""

    options: Annotated[list[Line], Field(min_length=1, max_length=16)] | None = key(
        None, "problem option names, one per coordinate", "a list of distinct problem option "
        "names, e.g. [\"q0\", \"p0\"]")
    circle: Circle | None = key(None, "center, radius, n")
    polygon: Polygon | None = key(None, "vertices, n")
    list_: PointList | None = key(None, "the points themselves", alias="list")
    n: PointCount | None = key(None, "the number of points of a circle or polygon")


class Points(PointsPatch):
    """``[cells.points]``: one cell per initial point, setting the problem ``options`` in order."""

    options: Annotated[list[Line], Field(min_length=1, max_length=16),
                       AfterValidator(_distinct)] = key(
        doc="problem option names, one per coordinate", allowed="a list of distinct problem "
        "option names, e.g. [\"q0\", \"p0\"]")

    @model_validator(mode="after")
    def _one_shape(self):
        shapes = [s for s in ("circle", "polygon", "list") if getattr(self, s.replace(
            "list", "list_")) is not None]
        if len(shapes) != 1:
            raise ValueError(f"give exactly one of circle, polygon, list (got "
                             f"{', '.join(shapes) or 'none'})")
        return self


MAX_ORBITS = 1_000_000
Orbits = Annotated[int, Allowed(f"an integer from 1 to {MAX_ORBITS}"),
                   Field(ge=1, le=MAX_ORBITS)]
Seed = Annotated[int, Allowed("an integer from 0 to 2^63 - 1"), Field(ge=0, le=2 ** 63 - 1)]
Bounds = Annotated[list[Number], Allowed("a list of numbers, one per option"),
                   Field(min_length=1, max_length=16)]
Levels = Annotated[dict[str, Number], Allowed("a table of integral = value, e.g. { H = 0.125 }"),
                   Field(min_length=1, max_length=16)]
Keep = Annotated[Literal["all"] | Annotated[int, Field(ge=0, le=MAX_ORBITS)]
                 | Annotated[list[Annotated[int, Field(ge=0)]], Field(max_length=MAX_POINTS)],
                 Allowed('"all", a number of orbits (the first ones), or a list of orbit '
                         'indices')]


class EnsemblePatch(Record):
    """A scale's change of an ensemble (its keys replace the group's)."""

    n: Orbits | None = key(None, "the number of initial conditions (box, shell, circle, "
                                 "polygon)")
    seed: Seed | None = key(None, "box, shell: the seed of numpy's Generator(PCG64(seed)) (default 0)")
    keep: Keep | None = key(None, "the orbits whose samples go to samples.parquet")
    chunk: Orbits | None = key(None, "orbits per unit of work (default 250)")


class Ensemble(EnsemblePatch):
    """``[cells.ensemble]``: one cell of N initial conditions, run by one batched kernel
    (:mod:`gnibench.suite.runs.ensembles`)."""

    options: Annotated[list[Line], Field(min_length=1, max_length=16),
                       AfterValidator(_distinct)] = key(
        doc="initial-value options of the problem, one per sampled coordinate",
        allowed="a list of distinct options <state>0, e.g. [\"q0\", \"p0\"]")
    sample: Literal["box", "shell", "list", "circle", "polygon"] = key(
        doc="how the initial conditions are made (suite/runs/sampling.py)",
        allowed="box | shell | list | circle | polygon")
    low: Bounds | None = key(None, "box, shell: the box's lower corner")
    high: Bounds | None = key(None, "box, shell: the box's upper corner")
    level: Levels | None = key(None, "shell: the level set, integral = value")
    points: PointList | None = key(None, "list: the initial conditions themselves")
    center: Pair | None = key(None, "circle: its center")
    radius: Positive | None = key(None, "circle: its radius")
    vertices: PointList | None = key(None, "polygon: its vertices (at least 3)")

    @model_validator(mode="after")
    def _keys_of_the_sample(self):
        needs = {"box": ("n", "low", "high"), "shell": ("n", "low", "high", "level"),
                 "list": ("points",), "circle": ("n", "center", "radius"),
                 "polygon": ("n", "vertices")}[self.sample]
        missing = [k for k in needs if getattr(self, k) is None]
        if missing:
            raise ValueError(f"sample = \"{self.sample}\" needs {', '.join(missing)}")
        shapes = ("low", "high", "level", "points", "center", "radius", "vertices")
        extra = [k for k in shapes if k not in needs and getattr(self, k) is not None]
        if extra:
            raise ValueError(f"{', '.join(extra)} do not apply to sample = \"{self.sample}\"")
        return self


class ScaleTop(Horizon):
    """``[scale.<name>]``: the top-level horizon, sampling or section at that scale."""


class ScaleGroup(Horizon):
    """``[cells.scale.<name>]``: a group's horizon, sampling, section, vary or points at that
    scale (vary and points are merged key by key)."""

    vary: Vary | None = key(None, "replaces these vary keys of the group")
    points: PointsPatch | None = key(None, "replaces these keys of the group's point set")
    ensemble: EnsemblePatch | None = key(None, "replaces these keys of the group's ensemble")


class TopScales(Record):
    paper: ScaleTop | None = key(None, "overrides at the paper scale (rare)")
    quick: ScaleTop | None = key(None, "overrides at the quick scale")


class GroupScales(Record):
    paper: ScaleGroup | None = key(None, "overrides at the paper scale (rare)")
    quick: ScaleGroup | None = key(None, "overrides at the quick scale")


class Common(Horizon):
    """Keys of both the top level (defaults of the groups) and a group (replacing them)."""

    dt_out: DtOut | None = key(None, "samples at t = k·dt_out (every K-th), plus the final point")
    metrics: Metrics | None = key(None, "metrics beside the defaults (a group's list replaces the "
                                        "top-level one)")
    reference_solution: Reference | None = key(None, "what global_error is measured against "
                                                     "(default: the exact solution, if any)")

    @model_validator(mode="after")
    def _section_or_grid(self):
        if self.section is not None and self.dt_out is not None:
            raise ValueError("section and dt_out both given; allowed: one of them (a section "
                             "cell writes its crossings, not samples)")
        return self


class Group(Common):
    """``[[cells]]``: problems x vary.problem x methods x the other vary keys."""

    label: Line = key("", "shown in the tables")
    problems: Specs = key(doc="PROBLEM spec strings")
    methods: Specs = key(doc="METHOD spec strings")
    vary: Vary = key({}, "vary.h = [...] (a base-method option), vary.problem.p0 = [...], "
                         "vary.observer.theta = [...] (a modifier's): one cell per value")
    zip: Zip | None = key(None, "vary keys that vary together, value by value (a paired sweep, "
                                "e.g. [\"rtol\", \"atol\"]: rtol = atol = each value), not as a "
                                "product; their lists must have the same length")
    points: Points | None = key(None, "a set of initial points: one ensemble cell, every "
                                      "orbit's samples kept ([cells.points])")
    ensemble: Ensemble | None = key(None, "N initial conditions in one cell ([cells.ensemble])")
    scale: GroupScales | None = key(None, "[cells.scale.quick]: this group at another scale")

    @model_validator(mode="after")
    def _one_set(self):
        if self.points is not None and self.ensemble is not None:
            raise ValueError("points and ensemble both given; allowed: one of them (points is "
                             "an ensemble whose orbits' samples are all kept)")
        return self


class ExperimentFile(Common):
    """The top level of an experiment file."""

    repeat: Repeat | None = key(None, "each cell's timed integration run N times after the "
                                      "warm-up (min, median and spread of the wall times in "
                                      "timings.parquet; results must be identical); default 1")
    report: ReportOptions | None = key(None, "what the report draws ([report]: time-plot cells, "
                                             "axes, figures, measures, target accuracy)")

    name: Annotated[str, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9._-]*$", max_length=120)] = key(
        doc="the experiment's name (default output: results/<name>)",
        allowed="letters, digits and . _ - (it names the output directory)")
    title: NonEmptyLine = key(doc="the title")
    reference: NonEmptyLine = key(doc="the place in the seeds")
    description: Text = key("", "what to expect, and every (choice) made where the seed is silent")
    cells: Annotated[list[Group], Field(max_length=MAX_ITEMS)] = key(
        [], "the groups of cells ([[cells]])", "[[cells]] tables")
    scale: TopScales | None = key(None, "[scale.quick]: the top level at another scale")
    figure: Figure | None = key(None, "a figure or table of a seed ([figure])")
    load: Annotated[list[NonEmptyLine], Field(max_length=64)] = key(
        [], "user definitions loaded before the cells are read (docs: reference, User definitions)",
        "a list of paths of definitions files, relative to the experiment file")

    @model_validator(mode="after")
    def _some_cells(self):
        if not self.cells and self.figure is None:
            raise ValueError("needs at least one [[cells]] group")
        return self


SCALES: tuple[Literal["paper", "quick"], ...] = ("paper", "quick")
