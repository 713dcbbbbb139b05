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

from gnibench.suite.cell.spec import structure, with_options
from gnibench.suite.foundation.budgets import check_count
from gnibench.suite.foundation.errors import UserError, named, unknown
from gnibench.suite.foundation.tomlfile import load_toml, read_text_file
from gnibench.suite.runs.cell import Cell

if TYPE_CHECKING:          # the schema (pydantic) is imported when a file is parsed, not by workers
    from gnibench.suite.runs.experiment_schema import ExperimentFile, Group


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
    repeat: int = 1
    report: dict | None = None


def shipped() -> dict[str, str]:
    """Names of the shipped experiments and their TOML texts."""
    root = resources.files("gnibench.suite") / "experiments"
    return {f.name[:-5]: f.read_text(encoding="utf-8") for f in root.iterdir()
            if f.name.endswith(".toml")}


def load_experiment(name_or_path: str | Path, scale: str = "paper",
                    repeat: int | None = None) -> Experiment:
    """Read, validate and expand an experiment given by path or shipped name, at a scale
    (``paper`` or ``quick``, :mod:`gnibench.suite.runs.scales`); ``repeat`` replaces the file's
    ``repeat`` (``gnibench run --repeat N``)."""
    arg = str(name_or_path)
    path = Path(arg)
    if path.suffix == ".toml" or "/" in arg or path.is_file():
        text = read_text_file(path, "experiment file")
        source, base = path.name, path.parent
    else:
        known = shipped()
        if arg not in known:
            raise unknown("experiment", arg, known)
        text, source, base = known[arg], f"{arg}.toml", None
    return parse_experiment(text, source, scale, base, repeat)


def parse_experiment(text: str, source: str, scale: str = "paper",
                     base: Path | None = None, repeat: int | None = None) -> Experiment:
    """Validate an experiment's TOML text at a scale and expand its cells (``source`` names it
    in errors; ``base``: the directory its ``load`` paths are relative to, default the working
    directory; ``repeat``: replaces the file's ``repeat``); a ``[figure]`` section is validated
    against the cells (:mod:`gnibench.suite.runs.figure_spec`), a ``[report]`` section's cell ids
    and family against the cells."""
    from gnibench.suite.foundation.records import validate
    from gnibench.suite.runs.experiment_schema import ExperimentFile
    from gnibench.suite.runs.scales import at_scale, check_scale, scales_stated

    check_scale(scale)
    doc = load_toml(text, source)
    validate(ExperimentFile, doc, source)        # every key, of every scale, before any applies
    stated = scales_stated(doc)
    top = validate(ExperimentFile, at_scale(doc, scale), source)
    _load(top.load, base, source)                # user definitions, before the cells are read
    groups = top.cells
    repeat = check_repeat(repeat if repeat is not None else (top.repeat or 1), "--repeat")
    planned = sum(_planned_cells(g, f"{source}: cells[{gi}]") for gi, g in enumerate(groups))
    check_count(planned, f"{source}", "GNIBENCH_MAX_CELLS", "cells")
    cells: list[Cell] = []
    for gi, group in enumerate(groups):
        cells.extend(_expand(group, gi, top, f"{source}: cells[{gi}]", len(cells), repeat))
    seen: dict[tuple, int] = {}
    for c in cells:
        key = (c.problem, c.method, c.steps, c.t_end, c.every, c.dt_out, c.reference, c.section,
               None if c.ensemble is None else c.ensemble.digest())
        if key in seen:
            raise UserError(f"{source}: cell {c.id} ({c.problem} {c.method}) duplicates cell "
                            f"{seen[key]}; allowed: each cell once")
        seen[key] = c.id
    figure = None
    if top.figure is not None:
        from gnibench.suite.runs.figure_spec import parse_figure

        figure = parse_figure(top.figure, cells, name=top.name, reference=top.reference,
                              scale=scale, where=f"{source}: figure")
    report = None
    if top.report is not None:
        report = top.report.model_dump(exclude_unset=True)
        _check_report(report, cells, f"{source}: report")
    return Experiment(top.name, top.title, top.reference, top.description, source, text,
                      tuple(cells), scale, figure, stated, repeat, report)


def check_repeat(value, name: str = "repeat") -> int:
    """A number of timed runs per cell: an integer from 1 to MAX_REPEAT."""
    from gnibench.suite.foundation.budgets import MAX_REPEAT

    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_REPEAT:
        raise UserError(f"bad {named(name, repr(value))}; allowed: an integer from 1 to {MAX_REPEAT}")
    return value


def _check_report(report: dict, cells: list[Cell], where: str) -> None:
    """The cell ids and the family of ``[report]`` must name cells of the experiment."""
    ids = report.get("cells")
    if isinstance(ids, list):
        bad = [i for i in ids if i >= len(cells)]
        if bad:
            raise UserError(f"{where}: bad cells = {bad[0]}; allowed: cell ids from 0 to "
                            f"{len(cells) - 1}")
    family = report.get("family")
    if family is not None:
        known = {c.spec.method.base.id for c in cells} | {c.setup_method for c in cells}
        labels = [getattr(c.spec.method, "family", None) for c in cells]
        known |= {f().label for f in labels if f is not None}
        if family not in known:
            from gnibench.suite.foundation.errors import unknown

            raise UserError(f"{where}: family: {unknown('family', family, sorted(known))}")


def _horizon(group: Group, top: ExperimentFile, where: str
             ) -> tuple[int | None, float | None, int]:
    """steps or t_end (a group's horizon replaces the default one) and every."""
    src = group if (group.steps is not None or group.t_end is not None) else top
    if src.steps is None and src.t_end is None:
        raise UserError(f"{where}: no horizon; give t_end or steps (in the group or at the top)")
    every = group.every if group.every is not None else (top.every or 1)
    return src.steps, src.t_end, every


def _planned_cells(group: Group, where: str) -> int:
    """The number of cells a group expands to, counted before expanding it (a point set or an
    ensemble is one cell; a zip of unequal lists is refused here)."""
    n = len(group.problems) * len(group.methods)
    for axis in _axes(group, where):
        n *= len(axis[1])
    return n


def _load(paths: list[str], base: Path | None, source: str) -> None:
    """The experiment's user definitions (``load = ["defs.toml"]``, :mod:`gnibench.suite.cell.user`),
    relative to the experiment file; an error names the experiment and the key first."""
    from gnibench.suite.cell.user.loader import load

    for i, p in enumerate(paths):
        try:
            load(Path(base or ".") / p)
        except UserError as e:
            raise UserError(f"{source}: load[{i}]: {e}") from None


def _check_metrics(choices, problems: list, where: str) -> None:
    """Each chosen metric must be able to apply to at least one problem of the group."""
    from gnibench.suite.metrics.compute import not_applicable

    reasons = [not_applicable(choices, p) for p in problems]
    for c in choices:
        if all(c.text() in r for r in reasons):
            why = "; ".join(dict.fromkeys(r[c.text()] for r in reasons))
            raise UserError(f"{where}: metric {c.text()} applies to no cell of the group: {why}")


#: the options of a base method that set its step size or tolerance: a work-precision sweep
#: varies one of them (the first of these the group varies), with its zip partners
SWEEP_OPTIONS = ("h", "rtol", "tol", "epsilon", "atol")


def _vary_name(target: str, option: str) -> str:
    """How a vary key is written: ``rtol`` (the base method's), ``observer.theta``, ``problem.e``."""
    return option if target == "method" else f"{target}.{option}"


def _axes(group: Group, where: str) -> list[tuple[tuple[tuple[str, str], ...], list[tuple]]]:
    """The group's vary keys as axes of the product: ``((target, option), ...)`` and the value
    tuples. A key alone is an axis of 1-tuples; the keys of ``zip`` form one axis of their values
    taken together, in the place of the first of them (their lists must have one length)."""
    keys = [(target, opt, vals) for target, options in group.vary.items()
            for opt, vals in options.items()]
    names = {_vary_name(t, o): (t, o, v) for t, o, v in keys}
    zipped = list(group.zip or ())
    for name in zipped:
        if name.removeprefix("method.") not in names:
            raise UserError(f"{where}: zip: {name!r} is not a vary key of the group; allowed: "
                            f"its vary keys ({', '.join(names) or 'none'})")
    zipped = [names[n.removeprefix("method.")] for n in zipped]
    if zipped:
        if len({t == "problem" for t, _, _ in zipped}) > 1:
            raise UserError(f"{where}: zip mixes problem and method options; allowed: the options "
                            f"of the problem, or those of the method and its modifiers")
        lengths = [len(v) for _, _, v in zipped]
        if len(set(lengths)) > 1:
            detail = ", ".join(f"vary.{_vary_name(t, o)} has {len(v)}" for t, o, v in zipped)
            raise UserError(f"{where}: zip = [{', '.join(_vary_name(t, o) for t, o, _ in zipped)}]"
                            f": lists of unequal length ({detail}); allowed: lists of one length "
                            f"(the values are taken together, pair by pair)")
    axes, done = [], False
    for t, o, v in keys:
        if (t, o, v) not in zipped:
            axes.append((((t, o),), [(x,) for x in v]))
        elif not done:
            axes.append((tuple((zt, zo) for zt, zo, _ in zipped),
                         list(zip(*[zv for _, _, zv in zipped]))))
            done = True
    return axes


def swept_options(group: Group, where: str) -> tuple[str, ...] | None:
    """The base-method options along which the group's cells form work-precision curves: the
    first option of :data:`SWEEP_OPTIONS` the group varies, with the options zipped with it; None
    when the group varies none (each cell's own step or tolerance option is its sweep then)."""
    for axis, _ in _axes(group, where):
        methods = [o for t, o in axis if t == "method"]
        if any(o in SWEEP_OPTIONS for o in methods):
            break
    else:
        return None
    varied = [o for axis, _ in _axes(group, where) for t, o in axis if t == "method"]
    first = next(o for o in SWEEP_OPTIONS if o in varied)
    axis = next(a for a, _ in _axes(group, where) if ("method", first) in a)
    return tuple([first] + [o for t, o in axis if t == "method" and o != first])


def _expand(group: Group, gi: int, defaults: ExperimentFile, where: str, first_id: int,
            repeat: int = 1) -> list[Cell]:
    from gnibench.suite.metrics.cells import make_cell
    from gnibench.suite.metrics.compute import parse_metrics

    label, problems, methods = group.label, group.problems, group.methods
    steps, t_end, every = _horizon(group, defaults, where)
    metrics = defaults.metrics or () if group.metrics is None else group.metrics
    dt_out = group.dt_out if group.dt_out is not None else defaults.dt_out
    section = group.section if group.section is not None else defaults.section
    if section is not None and dt_out is not None:
        raise UserError(f"{where}: section and dt_out both given; allowed: one of them (a section "
                        "cell writes its crossings, not samples)")
    if section is not None:
        # every K-th sample does not apply to crossings: a group's every, or a top-level every
        # beside the top-level section, would be dropped without a word (solve refuses --every
        # with --section); a top-level every is left aside by a group with its own section
        beside = group.every if group.every is not None else (
            defaults.every if group.section is None else None)
        if beside is not None and beside != 1:
            raise UserError(f"{where}: section and every = {beside} both given; allowed: one of "
                            f"them (a section cell writes every crossing)")
    reference = (defaults.reference_solution if group.reference_solution is None
                 else group.reference_solution)
    axes = _axes(group, where)
    problem_vary = [a for a in axes if a[0][0][0] == "problem"]
    method_vary = [a for a in axes if a[0][0][0] != "problem"]
    swept = swept_options(group, where)
    metric_choices = parse_metrics(list(metrics))
    ensemble = None
    if group.points is not None:
        from gnibench.suite.runs.ensemble_spec import from_points

        ensemble = from_points(group.points, f"{where}: points")
    elif group.ensemble is not None:
        ensemble = group.ensemble.model_dump(exclude_none=True)
    for choice in metric_choices:
        if choice.metric.scope == "ensemble" and (ensemble is None or ensemble["sample"] not in (
                "circle", "polygon")):
            raise UserError(f"{where}: metric {choice.text()} applies to an ensemble of initial "
                            f"points on a closed curve (ensemble or points: circle or polygon)")
        if choice.metric.scope == "ensemble" and choice.values.get("of") is None and len(
                ensemble["options"]) != 2:
            raise UserError(f"{where}: metric {choice.text()} needs of=x/y (the ensemble samples "
                            f"{len(ensemble['options'])} options, not 2)")
    if ensemble is not None:
        sampled = {opt for axis, _ in problem_vary for _, opt in axis} & set(ensemble["options"])
        if sampled:
            raise UserError(f"{where}: vary.problem.{sorted(sampled)[0]} and the ensemble both "
                            f"set it; allowed: one of them")
    try:
        modifiers = {mod.id for m in methods for mod in structure(m).modifiers}
    except UserError as e:
        raise UserError(f"{where}: {e}") from None
    for axis, _ in method_vary:
        for target, opt in axis:
            if target != "method" and target not in modifiers:
                raise UserError(f"{where}: vary.{target}.{opt}: no method of the group has the "
                                f"modifier {target!r}")
    cells = []
    parsed_problems = []
    sets: dict[str, object] = {}        # problem spec -> its ensemble (drawn once)
    for pgiven, *pvals in itertools.product(problems, *[v for _, v in problem_vary]):
        for mgiven, *mvals in itertools.product(methods, *[v for _, v in method_vary]):
            here = f"{where}: {pgiven} {mgiven}"
            try:
                pspec = _apply(pgiven, problem_vary, pvals)
                mspec = _apply(mgiven, method_vary, mvals)
                here = f"{where}: {pspec} {mspec}"
                spec = make_cell(pspec, mspec, steps=steps, t_end=t_end, every=every,
                                 dt_out=dt_out, section=section, reference=reference,
                                 metrics=metric_choices)
                if ensemble is not None and pspec not in sets:
                    from gnibench.suite.runs.ensemble_spec import make

                    sets[pspec] = make(ensemble, spec.problem,      # under ``here``, below
                                       "points" if group.points is not None else "ensemble")
            except UserError as e:
                raise UserError(f"{here}: {e}") from None
            parsed_problems.append(spec.problem)
            cells.append(Cell(first_id + len(cells), gi, label, spec, swept, repeat,
                              sets.get(pspec)))
    _check_metrics(metric_choices, parsed_problems, where)
    return cells


def _apply(spec: str, axes: list, values: list[tuple]) -> str:
    by_target: dict[str, dict[str, str]] = {}
    for (axis, _), taken in zip(axes, values):
        for (target, opt), value in zip(axis, taken):
            by_target.setdefault(target, {})[opt] = value
    for target, options in by_target.items():
        spec = with_options(spec, target, options)
    return spec
