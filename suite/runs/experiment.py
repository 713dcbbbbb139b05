"""Experiment files: a TOML description of a matrix of cells, validated before anything runs.

An experiment is a TOML file, given by path or by the name of one shipped in
``suite/experiments/``
(``gnibench run quick``). Its keys, types, bounds and defaults are typed records in
:mod:`gnibench.suite.runs.experiment_schema` (tables in ``suite/experiments/README.md``, rendered
from them); the whole file, every scale included, is validated against them first (one line naming
the key's path on a bad value or an unknown key), then the chosen scale is applied
(:mod:`gnibench.suite.runs.scales`) and each group expands into cells here.

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
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from gnibench.suite.cell.spec import parse_item, split_method
from gnibench.suite.foundation.budgets import check_count
from gnibench.suite.foundation.errors import UserError, unknown
from gnibench.suite.foundation.params import format_float
from gnibench.suite.foundation.tomlfile import MAX_CHARS, load_toml

if TYPE_CHECKING:          # the schema (pydantic) is imported when a file is parsed, not by workers
    from gnibench.suite.runs.experiment_schema import ExperimentFile, Group


@dataclass(frozen=True)
class Cell:
    """One problem x method x horizon: the unit of work of the runner.

    ``problem_spec``/``method_spec`` are the texts given to :func:`gnibench.suite.cell.solve.solve`;
    ``problem``/``method`` are their canonical texts (what the tables show); ``metrics`` the
    canonical texts of the chosen metrics (beside the default ones); ``reference`` the canonical
    text of the chosen reference solution (:func:`gnibench.suite.cell.reference.parse_reference`:
    ``exact``, ``heyoka:precision=...,tol=...``, ``rebound:tol=...`` or ``none``), None for the
    default (the exact solution where the problem has one).
    """

    id: int
    group: int
    label: str
    problem_spec: str
    method_spec: str
    problem: str
    method: str
    h: float
    steps: int | None
    t_end: float | None
    every: int
    nsteps: int
    t_final: float
    metrics: tuple[str, ...] = ()
    dt_out: float | None = None     # time grid (suite/cell/timegrid.py); the specs stay as given
    reference: str | None = None
    section: int | None = None      # crossings of the problem's Poincaré section (suite/cell/sections.py)

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
        if path.stat().st_size > 4 * MAX_CHARS:            # before reading it into memory
            raise UserError(f"experiment file {arg!r} is {path.stat().st_size} bytes; allowed: "
                            f"a TOML file of at most {MAX_CHARS} characters")
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
    from gnibench.suite.foundation.records import validate
    from gnibench.suite.runs.experiment_schema import ExperimentFile
    from gnibench.suite.runs.scales import at_scale, check_scale, scales_stated

    check_scale(scale)
    doc = load_toml(text, source)
    validate(ExperimentFile, doc, source)        # every key, of every scale, before any applies
    stated = scales_stated(doc)
    top = validate(ExperimentFile, at_scale(doc, scale), source)
    groups = top.cells
    planned = sum(_planned_cells(g) for g in groups)
    check_count(planned, f"{source}", "GNIBENCH_MAX_CELLS", "cells")
    cells: list[Cell] = []
    for gi, group in enumerate(groups):
        cells.extend(_expand(group, gi, top, f"{source}: cells[{gi}]", len(cells)))
    seen: dict[tuple, int] = {}
    for c in cells:
        key = (c.problem, c.method, c.steps, c.t_end, c.every, c.dt_out, c.reference, c.section)
        if key in seen:
            raise UserError(f"{source}: cell {c.id} ({c.problem} {c.method}) duplicates cell "
                            f"{seen[key]}; allowed: each cell once")
        seen[key] = c.id
    figure = None
    if top.figure is not None:
        from gnibench.suite.runs.figure_spec import parse_figure

        figure = parse_figure(top.figure, cells, name=top.name, reference=top.reference,
                              scale=scale, where=f"{source}: figure")
    return Experiment(top.name, top.title, top.reference, top.description, source, text,
                      tuple(cells), scale, figure, stated)


def _horizon(group: Group, top: ExperimentFile, where: str
             ) -> tuple[int | None, float | None, int]:
    """steps or t_end (a group's horizon replaces the default one) and every."""
    src = group if (group.steps is not None or group.t_end is not None) else top
    if src.steps is None and src.t_end is None:
        raise UserError(f"{where}: no horizon; give t_end or steps (in the group or at the top)")
    every = group.every if group.every is not None else (top.every or 1)
    return src.steps, src.t_end, every


def _planned_cells(group: Group) -> int:
    """The number of cells a group expands to, counted before expanding it."""
    from gnibench.suite.runs.scales import planned_points

    n = planned_points(group.points) * len(group.problems) * len(group.methods)
    for options in group.vary.values():
        for values in options.values():
            n *= len(values)
    return n


def _reference(text: str | None, problem) -> str | None:
    """The canonical text of a cell's reference solution (None: the problem's default)."""
    from gnibench.suite.cell.reference import parse_reference

    if text is None:
        return None
    spec = parse_reference(text, problem.record)
    return "none" if spec is None else spec.text()


def _check_metrics(metrics: tuple[str, ...], problems: list, where: str) -> None:
    """Each chosen metric must be able to apply to at least one problem of the group."""
    from gnibench.suite.metrics.compute import not_applicable, parse_metrics

    choices = parse_metrics(list(metrics))
    reasons = [not_applicable(choices, p) for p in problems]
    for c in choices:
        if all(c.text() in r for r in reasons):
            why = "; ".join(dict.fromkeys(r[c.text()] for r in reasons))
            raise UserError(f"{where}: metric {c.text()} applies to no cell of the group: {why}")


def _vary(group: Group) -> tuple[list[tuple[str, str, list[str]]], ...]:
    """(target, option, [value texts]) triples: target is 'problem', 'method' or a modifier id."""
    out = [(target, opt, vals) for target, options in group.vary.items()
           for opt, vals in options.items()]
    problem_vary = [v for v in out if v[0] == "problem"]
    method_vary = [v for v in out if v[0] != "problem"]
    return problem_vary, method_vary


def with_options(spec: str, target: str, options: dict[str, str]) -> str:
    """The spec with the options of ``target`` ('problem', 'method' = the base, or a modifier id)
    set to the given texts; unchanged when ``target`` is a modifier the spec does not have."""
    parts = [spec] if target == "problem" else split_method(spec)
    out = []
    for i, part in enumerate(parts):
        name, given = parse_item(part, "problem" if target == "problem" else "method")
        if (i == 0 and target in ("problem", "method")) or (i > 0 and name == target):
            given = {**given, **options}
        out.append(name + (":" + ",".join(f"{k}={v}" for k, v in given.items()) if given else ""))
    return "+".join(out)


def _expand(group: Group, gi: int, defaults: ExperimentFile, where: str, first_id: int
            ) -> list[Cell]:
    from gnibench.suite.cell.driver import check_budgets
    from gnibench.suite.cell.grid import grid, grid_step
    from gnibench.suite.cell.spec import prepare
    from gnibench.suite.cell.timegrid import effective_dt_out, engine_method
    from gnibench.suite.metrics.compute import parse_metrics, period_grid

    label, problems, methods = group.label, group.problems, group.methods
    steps, t_end, every = _horizon(group, defaults, where)
    metrics = defaults.metrics or () if group.metrics is None else group.metrics
    dt_out = group.dt_out if group.dt_out is not None else defaults.dt_out
    section = group.section if group.section is not None else defaults.section
    if section is not None and dt_out is not None:
        raise UserError(f"{where}: section and dt_out both given; allowed: one of them (a section "
                        "cell writes its crossings, not samples)")
    reference = (defaults.reference_solution if group.reference_solution is None
                 else group.reference_solution)
    problem_vary, method_vary = _vary(group)
    metric_choices = parse_metrics(list(metrics))
    points = [{}]
    if group.points is not None:
        from gnibench.suite.runs.scales import point_options

        points = [{k: format_float(v) for k, v in p.items()}
                  for p in point_options(group.points, where)]
    for target, opt, _ in method_vary:
        modifiers = {part.partition(":")[0].strip() for m in methods for part in split_method(m)[1:]}
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
                problem, method = prepare(pspec, mspec)
                parsed_problems.append(problem)
                external = getattr(method.base.record, "run", None) is not None
                cell_dt_out = dt_out if section is not None else period_grid(
                    metric_choices, problem, method, every, dt_out)   # eta: samples at t = nT
                if cell_dt_out is not None and external:  # an engine's dt_out is its own grid
                    method = engine_method(method, cell_dt_out, problem)
                elif cell_dt_out is not None:
                    effective_dt_out(method, cell_dt_out)  # refuses a conflicting method option
                h = grid_step(method)
                nsteps, h_last = grid(h, steps, t_end)
                check_budgets(problem, method, steps, t_end, every, section, cell_dt_out)
                if section is not None and not problem.record.sections:
                    raise UserError(f"problem {problem.record.id!r} has no Poincaré section; "
                                    "allowed: a group without section")
                ref = None if section is not None else _reference(reference, problem)
            except UserError as e:
                raise UserError(f"{here}: {e}") from None
            cells.append(Cell(first_id + len(cells), gi, label, pspec, mspec, problem.text(),
                              method.text(), h, steps, t_end, every, nsteps,
                              (nsteps - 1) * h + h_last, metrics, dt_out=cell_dt_out, reference=ref,
                              section=section))
    _check_metrics(metrics, parsed_problems, where)
    return cells


def _apply(spec: str, vary: list, values: list[str]) -> str:
    by_target: dict[str, dict[str, str]] = {}
    for (target, opt, _), value in zip(vary, values):
        by_target.setdefault(target, {})[opt] = value
    for target, options in by_target.items():
        spec = with_options(spec, target, options)
    return spec
