"""``gnibench reproduce``: the cells of the seeds' figures, run over one shared store.

A figure is a shipped experiment with a ``[figure]`` section (``hlw-fig-1.2``, ``hlw-table-2.1``,
``b-fig-9``, …). :func:`run_figures` validates every chosen figure at the chosen scale first, then
runs all their cells through :func:`gnibench.suite.runs.runner.run_experiments` with one store in
``DIR`` (so a cell shared by several figures is computed once, and a second call reuses
everything), and writes each figure's tables into ``DIR/<id>/``. Drawing is the reports' job
(:mod:`gnibench.reports.figures`); the command line composes the two.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from gnibench.suite.foundation.errors import UserError, spelled, unknown
from gnibench.suite.runs.experiment import Experiment, load_experiment, shipped
from gnibench.suite.runs.scales import SCALES, check_scale

DEFAULT_DIR = Path("results") / "seeds"     # shared with gnibench verify: one store for both


@dataclass(frozen=True)
class FigureEntry:
    """A shipped figure as listed: id, number, title, reference and the scales it states."""

    id: str
    number: str
    title: str
    reference: str


def figures() -> dict[str, FigureEntry]:
    """The shipped experiments that have a ``[figure]`` section, by id (sorted)."""
    out = {}
    for name, text in sorted(shipped().items(), key=lambda kv: _sort_key(kv[0])):
        try:
            doc = tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            continue
        fig = doc.get("figure")
        if isinstance(fig, dict):
            out[name] = FigureEntry(name, str(fig.get("number", "")), str(doc.get("title", "")),
                                    str(doc.get("reference", "")))
    return out


def _sort_key(name: str) -> tuple:
    """hlw before b, then the figure numbers in numeric order (1.2 < 1.10, 9 < 10)."""
    source, _, rest = name.partition("-")
    kind, _, number = rest.partition("-")
    parts = tuple((0, int(p), "") if p.isdigit() else (1, 0, p)
                  for p in number.replace("-", ".").split("."))
    return ({"hlw": 0, "b": 1}.get(source, 2), kind != "fig", parts, name)


def choose(ids: list[str]) -> list[str]:
    """The figure ids asked for (``all``: every one), each once, in listing order."""
    known = figures()
    if not ids:
        raise UserError("no figure id given; allowed: one or more ids, or all "
                        "(gnibench reproduce --list)")
    chosen: list[str] = []
    for fid in ids:
        if fid == "all":
            chosen += list(known)
            continue
        if fid not in known:
            raise unknown("figure", fid, known)
        chosen.append(fid)
    order = list(known)
    return sorted(dict.fromkeys(chosen), key=order.index)


def load_figures(ids: list[str], scale: str) -> list[Experiment]:
    """Every chosen figure's experiment, validated at the scale before anything runs."""
    check_scale(scale)
    return [load_experiment(fid, scale) for fid in choose(ids)]


def cost(experiment: Experiment) -> dict:
    """Cells, steps and samples a figure's run needs (a cost estimate, before running)."""
    steps = sum(c.nsteps for c in experiment.cells)
    samples = sum(c.nsteps // c.every + 2 for c in experiment.cells)
    return {"cells": len(experiment.cells), "steps": steps, "samples": samples}


def listing() -> list[dict]:
    """One row per shipped figure: id, number, title, reference, and the cost at each scale
    (a scale the file does not state is the paper scale)."""
    rows = []
    for fid, entry in figures().items():
        row = {"id": fid, "number": entry.number, "title": entry.title,
               "reference": entry.reference, "scales": {}}
        for scale in SCALES:
            experiment = load_experiment(fid, scale)
            row["scales"][scale] = {**cost(experiment),
                                    "stated": scale in experiment.scales}
        rows.append(row)
    return rows


def check_output(out: Path) -> None:
    """Refuse, before any work, an output directory that cannot be one (or be written)."""
    from gnibench.suite.foundation.outputs import check_output_dir

    check_output_dir(out)


def run_figures(experiments: list[Experiment], out: Path, *, jobs: int | None = None,
                executor: str = "local", scheduler: str | None = None, fresh: bool = False,
                log=None, summarize=None) -> list[Path]:
    """Run the figures' cells over one store in ``out``; each figure's tables go to
    ``out/<id>/``. Returns those directories, in order."""
    from gnibench.suite.runs import executors
    from gnibench.suite.runs.runner import run_experiments

    executors.check(executor, jobs, scheduler)
    check_output(out)
    outs = [out / e.name for e in experiments]
    scale = experiments[0].scale if experiments else "paper"
    return run_experiments(experiments, outs, out, jobs=jobs, executor=executor,
                           scheduler=scheduler, fresh=fresh, log=log, summarize=summarize,
                           name=f"reproduce ({len(experiments)} figures, {scale} scale)")


def current_figure(fid: str, results: Path) -> dict:
    """The figure of the shipped file as it is now, for a redraw of the tables in ``results``:
    the file is read at the scale the tables were run at, and its cells must still be those of
    the tables (else the tables are stale and the figure must be run again)."""
    from gnibench.suite.runs.storage import read_parquet_meta

    meta = read_parquet_meta(results / "cells.parquet")
    experiment = load_experiment(fid, meta.get("scale", "paper"))
    if [c.described() for c in experiment.cells] != meta.get("cells"):
        raise UserError(f"{fid}: the cells of the file changed since the tables in {results} were "
                        f"computed; reproduce {fid} again (without {spelled('--redraw')})")
    return experiment.figure
