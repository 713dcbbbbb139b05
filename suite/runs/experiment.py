"""Experiment files: a TOML description of a matrix of cells, validated before anything runs.

An experiment is a TOML file, given by path or by the name of one shipped in
``suite/experiments/`` (``gnibench run quick``). Schema (also in ``suite/experiments/README.md``)::

    name        = "hlw-fig-1.4"      # required; letters, digits, . _ -; output dir results/<name>
    title       = "..."              # required, one line
    reference   = "[HLW] Fig 1.4"    # required: the place in the seeds
    description = "..."              # optional; (choice) notes go here
    t_end = 10.0                     # default horizon of every group: t_end OR steps
    every = 1                        # default sampling: a sample every K steps (plus the last)
    metrics = ["growth:of=H"]        # optional: metrics beside the defaults (gnibench list metrics)
    dt_out = 0.5                     # optional: samples at t = k dt_out (every K-th) plus the last
    reference_solution = "heyoka:precision=long double"   # optional: what global_error is
                                     # measured against (exact | heyoka[:...] | rebound[:...] | none)
    section = 10000                  # optional: the first N crossings of the problem's Poincaré
                                     # section up to the horizon, instead of samples

    [[cells]]                        # a group; the cells are problems x methods x vary values
    label    = "symplectic Euler"    # optional, shown in the summary
    problems = ["pendulum:q0=0"]     # PROBLEM spec strings (README: spec strings)
    methods  = ["symplectic-euler:h=0.3"]
    steps = 100                      # optional: replaces the top-level horizon for this group
    every = 1                        # optional
    metrics = ["precession"]         # optional: replaces the top-level metrics for this group
    dt_out = 0.5                     # optional: replaces the top-level time grid for this group
    reference_solution = "exact"     # optional: replaces the top-level reference for this group
    section = 10000                  # optional: replaces the top-level section for this group
    vary.h = [0.3, 0.15]             # a base-method option, one cell per value
    vary.problem.p0 = [0.7, 1.4]     # a problem option
    vary.observer.theta = [1, 15]    # an option of a modifier (only methods that have it)

A ``vary`` value overrides the same option written in a spec. Values are numbers, strings,
booleans, or lists of numbers (written ``a/b`` in the spec). The cells of a group are the product
problems x vary.problem x methods x (method vary keys), in that order, numbered from 0 across
the groups. Every cell is checked before any runs (unknown keys, specs through
:func:`gnibench.suite.cell.solve.prepare`, horizons, sample counts, duplicates, metric specs, and
that each chosen metric may apply to at least one cell of its group); a bad one raises
:class:`~gnibench.suite.foundation.errors.UserError` naming the place and what is allowed. A metric
that applies to some cells of a group only is computed where it applies; the others say why in
``cells.parquet`` (``metric_notes``).
"""
from __future__ import annotations

import itertools
import math
import re
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from gnibench.suite.cell.cellspec import CellSpec
from gnibench.suite.cell.spec import structure, with_options
from gnibench.suite.foundation.budgets import INT_LIMIT, check_count
from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.foundation.params import format_float

TOP_KEYS = ("name", "title", "reference", "description", "t_end", "steps", "every", "dt_out",
            "metrics", "reference_solution", "section", "cells", "scale", "figure")
GROUP_KEYS = ("label", "problems", "methods", "t_end", "steps", "every", "dt_out", "metrics",
              "reference_solution", "section", "vary", "points", "scale")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


@dataclass(frozen=True)
class Cell:
    """One problem x method x horizon of an experiment: the unit of work of the runner.

    ``spec`` is the typed cell (:class:`~gnibench.suite.cell.cellspec.CellSpec`: the parsed
    problem and method, horizon, sampling, reference solution and chosen metrics), made once when
    the experiment is read; ``id``, ``group`` and ``label`` place it in the experiment. The other
    attributes are the canonical texts and numbers the tables show: ``problem``/``method`` the
    canonical specs, ``metrics`` the canonical texts of the chosen metrics (beside the default
    ones), ``reference`` the canonical text of the chosen reference solution (``exact``,
    ``heyoka:precision=...,tol=...``, ``rebound:tol=...`` or ``none``), None for the default (the
    exact solution where the problem has one).
    """

    id: int
    group: int
    label: str
    spec: CellSpec

    @property
    def problem(self) -> str:
        return self.spec.problem_text

    @property
    def method(self) -> str:
        return self.spec.method_text

    @property
    def method_kind(self) -> str:
        return self.spec.kind

    @property
    def h(self) -> float:
        return self.spec.h

    @property
    def steps(self) -> int | None:
        return self.spec.steps

    @property
    def t_end(self) -> float | None:
        return self.spec.t_end

    @property
    def every(self) -> int:
        return self.spec.every

    @property
    def nsteps(self) -> int:
        return self.spec.nsteps

    @property
    def t_final(self) -> float:
        return self.spec.t_final

    @property
    def metrics(self) -> tuple[str, ...]:
        return self.spec.metric_texts

    @property
    def dt_out(self) -> float | None:
        """The time grid (suite/cell/timegrid.py); the specs stay as given, but for an engine's."""
        return self.spec.dt_out

    @property
    def reference(self) -> str | None:
        return self.spec.reference_text

    @property
    def section(self) -> int | None:
        """Crossings of the problem's Poincaré section (suite/cell/sections.py)."""
        return self.spec.section

    def described(self) -> dict:
        """What the tables' metadata records of the cell (and a redraw compares)."""
        return {"cell": self.id, "problem": self.problem, "method": self.method,
                "steps": self.steps, "t_end": self.t_end, "every": self.every,
                "dt_out": self.dt_out, "reference": self.reference, "section": self.section}


@dataclass(frozen=True)
class Experiment:
    """A validated experiment: its texts and its expanded cells."""

    name: str
    title: str
    reference: str
    description: str
    source: str
    text: str
    cells: tuple[Cell, ...]
    scale: str = "paper"
    figure: dict | None = None
    scales: tuple[str, ...] = ("paper",)


def shipped() -> dict[str, str]:
    """Names of the shipped experiments and their TOML texts."""
    root = resources.files("gnibench.suite") / "experiments"
    return {f.name[:-5]: f.read_text(encoding="utf-8") for f in root.iterdir()
            if f.name.endswith(".toml")}


def load_experiment(name_or_path: str | Path, scale: str = "paper") -> Experiment:
    """Read, validate and expand an experiment given by path or shipped name, at a scale
    (``paper`` or ``quick``, :mod:`gnibench.suite.runs.scales`)."""
    arg = str(name_or_path)
    path = Path(arg)
    if path.suffix == ".toml" or "/" in arg or path.is_file():
        if not path.is_file():
            raise UserError(f"no experiment file {arg!r}")
        try:
            text, source = path.read_text(encoding="utf-8"), path.name
        except UnicodeDecodeError as e:
            raise UserError(f"experiment file {arg!r} is not UTF-8 text (byte {e.start}); allowed: "
                            f"a TOML file in UTF-8") from None
        except OSError as e:
            raise UserError(f"cannot read experiment file {arg!r} ({e.strerror})") from None
    else:
        known = shipped()
        if arg not in known:
            raise unknown("experiment", arg, known)
        text, source = known[arg], f"{arg}.toml"
    return parse_experiment(text, source, scale)


def parse_experiment(text: str, source: str, scale: str = "paper") -> Experiment:
    """Validate an experiment's TOML text at a scale and expand its cells (``source`` names it
    in errors); a ``[figure]`` section is validated against the cells
    (:mod:`gnibench.suite.runs.figure_spec`)."""
    from gnibench.suite.runs.scales import at_scale, check_scale, scales_stated

    check_scale(scale)
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UserError(f"{source}: not valid TOML: {e}") from None
    _keys(doc, TOP_KEYS, source)
    stated = scales_stated(doc)
    doc = at_scale(doc, scale, source)
    name = _text(doc, "name", source, required=True)
    if not _NAME.match(name):
        raise UserError(f"{source}: bad name {name!r}; allowed: letters, digits and . _ - "
                        "(it names the output directory)")
    title = _text(doc, "title", source, required=True, one_line=True)
    reference = _text(doc, "reference", source, required=True, one_line=True)
    description = _text(doc, "description", source)
    groups = doc.get("cells", [] if "figure" in doc else None)
    if not isinstance(groups, list) or not all(isinstance(g, dict) for g in groups) or (
            not groups and "figure" not in doc):
        raise UserError(f"{source}: needs at least one [[cells]] group")
    defaults = {k: doc[k] for k in ("t_end", "steps", "every", "dt_out", "section") if k in doc}
    planned = sum(_planned_cells(g, f"{source}: cells[{gi}]") for gi, g in enumerate(groups))
    check_count(planned, f"{source}", "GNIBENCH_MAX_CELLS", "cells")
    defaults["metrics"] = _metrics(doc, source)
    defaults["reference_solution"] = _reference_text(doc, source)
    cells: list[Cell] = []
    for gi, group in enumerate(groups):
        cells.extend(_expand(group, gi, defaults, f"{source}: cells[{gi}]", len(cells)))
    seen: dict[tuple, int] = {}
    for c in cells:
        key = (c.problem, c.method, c.steps, c.t_end, c.every, c.dt_out, c.reference, c.section)
        if key in seen:
            raise UserError(f"{source}: cell {c.id} ({c.problem} {c.method}) duplicates cell "
                            f"{seen[key]}; allowed: each cell once")
        seen[key] = c.id
    figure = None
    if "figure" in doc:
        from gnibench.suite.runs.figure_spec import parse_figure

        figure = parse_figure(doc["figure"], cells, name=name, reference=reference,
                              scale=scale, where=f"{source}: figure")
    return Experiment(name, title, reference, description, source, text, tuple(cells), scale,
                      figure, stated)


def _keys(table: dict, allowed: tuple[str, ...], where: str) -> None:
    for key in table:
        if key not in allowed:
            raise UserError(f"{where}: {unknown('key', key, allowed)}")


def _text(table: dict, key: str, where: str, required: bool = False,
          one_line: bool = False) -> str:
    if key not in table:
        if required:
            raise UserError(f"{where}: missing key {key!r} (a string)")
        return ""
    value = table[key]
    if not isinstance(value, str) or (required and not value.strip()):
        raise UserError(f"{where}: bad {key} = {value!r}; allowed: a non-empty string")
    if one_line and any(not c.isprintable() for c in value):
        raise UserError(f"{where}: bad {key} = {value!r}; allowed: one line of text (no line "
                        f"breaks or control characters)")
    return value


def _spec_list(group: dict, key: str, where: str) -> list[str]:
    value = group.get(key)
    if not isinstance(value, list) or not value or not all(isinstance(s, str) for s in value):
        raise UserError(f"{where}: bad or missing {key} = {value!r}; allowed: a non-empty list "
                        "of spec strings")
    return value


def _horizon(group: dict, defaults: dict, where: str) -> tuple[int | None, float | None, int]:
    """steps or t_end (a group's horizon replaces the default one) and every."""
    src = group if ("steps" in group or "t_end" in group) else defaults
    if "steps" in src and "t_end" in src:
        raise UserError(f"{where}: both steps and t_end given; allowed: exactly one of them")
    if "steps" not in src and "t_end" not in src:
        raise UserError(f"{where}: no horizon; give t_end or steps (in the group or at the top)")
    steps = t_end = None
    if "steps" in src:
        steps = _integer(src["steps"], "steps", where)
    else:
        t_end = src["t_end"]
        if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not (
                math.isfinite(t_end) and t_end > 0):
            raise UserError(f"{where}: bad t_end = {t_end!r}; allowed: a finite number > 0")
        t_end = float(t_end)
    every = _integer(group.get("every", defaults.get("every", 1)), "every", where)
    return steps, t_end, every


def _dt_out(group: dict, defaults: dict, where: str) -> float | None:
    """The time grid of a group (its own dt_out replaces the top-level one)."""
    from gnibench.suite.cell.timegrid import check_dt_out

    try:
        return check_dt_out(group.get("dt_out", defaults.get("dt_out")), "dt_out =")
    except UserError as e:
        raise UserError(f"{where}: {e}") from None


def _section(group: dict, defaults: dict, where: str) -> int | None:
    """The number of section crossings of a group (its own section replaces the top-level one)."""
    value = group.get("section", defaults.get("section"))
    return None if value is None else _integer(value, "section", where)


def _integer(value, key: str, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= INT_LIMIT:
        raise UserError(f"{where}: bad {key} = {value!r}; allowed: an integer from 1 to 2^62")
    return value


def _planned_cells(group, where: str) -> int:
    """The number of cells a group expands to, counted before expanding it."""
    if not isinstance(group, dict):
        return 0
    from gnibench.suite.runs.scales import planned_points

    n = planned_points(group.get("points"))
    for key in ("problems", "methods"):
        value = group.get(key)
        n *= len(value) if isinstance(value, list) else 1
    vary = group.get("vary", {})
    if isinstance(vary, dict):
        for value in vary.values():
            for vals in (value.values() if isinstance(value, dict) else [value]):
                n *= len(vals) if isinstance(vals, list) and vals else 1
    return n


def _value_text(value, where: str) -> str:
    """Spec text of one vary value: floats round-trip, lists become a/b/c."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float) and math.isfinite(value):
        return format_float(value)
    if isinstance(value, str) and value and not re.search(r"[,:=+\s]", value):
        return value
    if isinstance(value, list) and value and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return "/".join(_value_text(v, where) for v in value)
    raise UserError(f"{where}: bad value {value!r}; allowed: a finite number, a boolean, a word, "
                    "or a list of numbers")


def _metrics(table: dict, where: str) -> tuple[str, ...] | None:
    """The canonical texts of a ``metrics`` list (None when the key is absent)."""
    from gnibench.suite.metrics.compute import parse_metrics

    if "metrics" not in table:
        return None
    value = table["metrics"]
    if not isinstance(value, list) or not all(isinstance(m, str) for m in value):
        raise UserError(f"{where}: bad metrics = {value!r}; allowed: a list of metric spec "
                        "strings, e.g. [\"eta\", \"growth:of=H\"] (gnibench list metrics)")
    try:
        return tuple(c.text() for c in parse_metrics(value))
    except UserError as e:
        raise UserError(f"{where}: metrics: {e}") from None


def _reference_text(table: dict, where: str) -> str | None:
    """The ``reference_solution`` string of a table (None when absent); each cell checks it."""
    if "reference_solution" not in table:
        return None
    value = table["reference_solution"]
    if not isinstance(value, str) or not value.strip() or any(not c.isprintable() for c in value):
        raise UserError(f"{where}: bad reference_solution = {value!r}; allowed: exact | "
                        "heyoka[:precision=double|long double|real128,tol=T] | rebound[:tol=T] | none")
    return value


def _check_metrics(choices, problems: list, where: str) -> None:
    """Each chosen metric must be able to apply to at least one problem of the group."""
    from gnibench.suite.metrics.compute import not_applicable

    reasons = [not_applicable(choices, p) for p in problems]
    for c in choices:
        if all(c.text() in r for r in reasons):
            why = "; ".join(dict.fromkeys(r[c.text()] for r in reasons))
            raise UserError(f"{where}: metric {c.text()} applies to no cell of the group: {why}")


def _vary(group: dict, where: str) -> tuple[list[tuple[str, str, list[str]]], ...]:
    """(target, option, [value texts]) triples: target is 'problem', 'method' or a modifier id."""
    vary = group.get("vary", {})
    if not isinstance(vary, dict):
        raise UserError(f"{where}: bad vary = {vary!r}; allowed: a table of option = [values]")
    out = []
    for key, value in vary.items():
        if isinstance(value, dict):
            items = [(key, opt, vals) for opt, vals in value.items()]
        else:
            items = [("method", key, value)]
        for target, opt, vals in items:
            here = f"{where}: vary.{'' if target == 'method' else target + '.'}{opt}"
            if not isinstance(vals, list) or not vals:
                raise UserError(f"{here}: bad value {vals!r}; allowed: a non-empty list of values")
            out.append((target, opt, [_value_text(v, here) for v in vals]))
    problem_vary = [v for v in out if v[0] == "problem"]
    method_vary = [v for v in out if v[0] != "problem"]
    return problem_vary, method_vary


def _expand(group: dict, gi: int, defaults: dict, where: str, first_id: int) -> list[Cell]:
    from gnibench.suite.metrics.cells import make_cell
    from gnibench.suite.metrics.compute import parse_metrics

    _keys(group, GROUP_KEYS, where)
    label = _text(group, "label", where, one_line=True)
    problems = _spec_list(group, "problems", where)
    methods = _spec_list(group, "methods", where)
    steps, t_end, every = _horizon(group, defaults, where)
    metrics = _metrics(group, where)
    metrics = (defaults.get("metrics") or ()) if metrics is None else metrics
    dt_out = _dt_out(group, defaults, where)
    section = _section(group, defaults, where)
    if section is not None and dt_out is not None:
        raise UserError(f"{where}: section and dt_out both given; allowed: one of them (a section "
                        "cell writes its crossings, not samples)")
    reference = _reference_text(group, where)
    reference = defaults.get("reference_solution") if reference is None else reference
    problem_vary, method_vary = _vary(group, where)
    metric_choices = parse_metrics(list(metrics))
    points = [{}]
    if "points" in group:
        from gnibench.suite.runs.scales import point_options

        points = [{k: format_float(v) for k, v in p.items()}
                  for p in point_options(group["points"], where)]
    try:
        modifiers = {mod.id for m in methods for mod in structure(m).modifiers}
    except UserError as e:
        raise UserError(f"{where}: {e}") from None
    for target, opt, _ in method_vary:
        if target != "method" and target not in modifiers:
            raise UserError(f"{where}: vary.{target}.{opt}: no method of the group has the "
                            f"modifier {target!r}")
    cells = []
    parsed_problems = []
    for pgiven, point, *pvals in itertools.product(problems, points,
                                                   *[v[2] for v in problem_vary]):
        for mgiven, *mvals in itertools.product(methods, *[v[2] for v in method_vary]):
            here = f"{where}: {pgiven} {mgiven}"
            try:
                pspec = with_options(pgiven, "problem", point) if point else pgiven
                pspec = _apply(pspec, problem_vary, pvals)
                mspec = _apply(mgiven, method_vary, mvals)
                here = f"{where}: {pspec} {mspec}"
                spec = make_cell(pspec, mspec, steps=steps, t_end=t_end, every=every,
                                 dt_out=dt_out, section=section, reference=reference,
                                 metrics=metric_choices)
            except UserError as e:
                raise UserError(f"{here}: {e}") from None
            parsed_problems.append(spec.problem)
            cells.append(Cell(first_id + len(cells), gi, label, spec))
    _check_metrics(metric_choices, parsed_problems, where)
    return cells


def _apply(spec: str, vary: list, values: list[str]) -> str:
    by_target: dict[str, dict[str, str]] = {}
    for (target, opt, _), value in zip(vary, values):
        by_target.setdefault(target, {})[opt] = value
    for target, options in by_target.items():
        spec = with_options(spec, target, options)
    return spec
