"""``gnibench reproduce ID... | all``: run the seeds' figures and draw them.

Composes :mod:`gnibench.suite.runs.reproduce` (validate every figure, run all their cells over one
store in DIR, each figure's tables into ``DIR/<id>/``) and :mod:`gnibench.reports.figures` (the
images and ``figure.json`` into ``DIR/<id>/figure/``). ``--redraw`` draws from the tables already
in DIR without integrating (with the figure section of the file as it is now, provided its cells
are still those of the tables); ``--list`` prints the figures, their scales and their cost.
"""
from __future__ import annotations

import sys
from pathlib import Path

from gnibench.suite.foundation.errors import UserError


def add_parser(sub, path_type, jobs_type) -> None:
    r = sub.add_parser("reproduce", help="run and draw figures and tables of the seeds")
    r.add_argument("ids", nargs="*", metavar="ID",
                   help="figure ids (gnibench reproduce --list), or all")
    r.add_argument("--scale", default="paper", metavar="paper|quick",
                   help="paper: the seed's horizons and step sizes (default); quick: shortened")
    r.add_argument("-o", "--output", type=path_type, default=None, metavar="DIR",
                   help="results directory (default: results/seeds, shared with gnibench verify)")
    r.add_argument("-j", "--jobs", type=jobs_type, default=None, metavar="N",
                   help="worker processes (default: the number of cores; 1: in this process)")
    r.add_argument("--executor", default="local", metavar="local|dask",
                   help="local: a process pool (default); dask: a Dask cluster")
    r.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (dask)")
    r.add_argument("--fresh", action="store_true", help="ignore the cells stored in DIR")
    r.add_argument("--redraw", action="store_true",
                   help="draw again from the tables in DIR, without integrating")
    r.add_argument("--no-report", action="store_true",
                   help="do not write the report site (DIR/report/index.html)")
    r.add_argument("--list", action="store_true",
                   help="list the figures, their scales and cost (cells and steps per scale)")


def run(a) -> int:
    from gnibench.suite.runs import reproduce as rep
    from gnibench.suite.runs.scales import check_scale

    check_scale(a.scale)
    if a.list:
        if a.ids or a.redraw:
            raise UserError("--list takes no ids and no --redraw")
        print(list_text(rep.listing()))
        return 0
    out = a.output if a.output is not None else rep.DEFAULT_DIR
    from gnibench.reports.drawing import Drawers, cores

    ids = rep.choose(a.ids)             # an unknown id is refused before anything starts
    if a.redraw:
        for option in ("jobs", "scheduler"):
            if getattr(a, option) is not None:
                raise UserError(f"--{option} does not apply with --redraw (nothing is run)")
        if a.fresh:
            raise UserError("--fresh does not apply with --redraw (nothing is run)")
        missing = [fid for fid in ids if not (out / fid / "cells.parquet").is_file()]
        if missing:
            raise UserError(f"no results for {', '.join(missing)} in {out}; run gnibench "
                            f"reproduce {' '.join(missing)} first (without --redraw)")
    with Drawers() as drawers:
        # the figures and the report's plots are drawn by one pool, forked from a process that
        # imports what they need while the cells are prepared and run (-j 1: in this process)
        if a.jobs != 1:
            drawers.start(min(a.jobs or cores(), cores()), preload=FIGURE_MODULES)
        return _reproduce(a, out, ids, drawers)


#: what drawing a figure imports (the drawing process imports them once, before its forks)
FIGURE_MODULES = ("pandas", "pyarrow.parquet", "matplotlib.pyplot", "gnibench.reports.figures",
                  "gnibench.reports.figures.plot", "gnibench.reports.figures.table")


def _reproduce(a, out: Path, ids: list[str], drawers) -> int:
    from gnibench.suite.runs import reproduce as rep

    if a.redraw:
        dirs = [out / fid for fid in ids]
        figures = [rep.current_figure(fid, d) for fid, d in zip(ids, dirs)]
    else:
        from gnibench.reports.markdown import render_summary

        experiments = rep.load_figures(a.ids, a.scale)
        dirs = rep.run_figures(experiments, out, jobs=a.jobs, executor=a.executor,
                               scheduler=a.scheduler, fresh=a.fresh, summarize=render_summary)
        figures = [e.figure for e in experiments]
    draw_all(dirs, figures, drawers=drawers)
    if not a.no_report:                 # everything in DIR (figures, a ledger of verify), as a site
        from gnibench.reports.site import build_site

        index = build_site([out], out / "report", drawers=drawers)
        print(f"gnibench: reproduce: report {index}", file=sys.stderr)
    return 0


def _draw(d: Path, figure: dict | None):
    from gnibench.reports.figures import FigureDataError, draw_figure

    try:
        return draw_figure(d, figure=figure)
    except FigureDataError as e:
        return UserError(str(e))


def draw_all(dirs: list[Path], figures: list[dict] | None = None, log=None,
             drawers=None) -> list[dict]:
    """Draw the figure of each results directory (``figures``: the figure to draw from each, by
    default the one stored with its tables), by the workers of ``drawers`` (a started
    :class:`~gnibench.reports.drawing.Drawers`; drawing is independent per figure and reads
    tables only), the largest tables first, or in this process; one line per figure on ``log``,
    in order."""
    from gnibench.reports.drawing import Drawers

    log = sys.stderr if log is None else log
    figures = figures or [None] * len(dirs)
    results = (drawers or Drawers()).map(_draw, list(zip(dirs, figures)), cost=_size)
    manifests = []
    for d, manifest in zip(dirs, results):
        if isinstance(manifest, UserError):
            raise manifest
        manifests.append(manifest)
        empty = [c["label"] for p in manifest["panels"] for c in p["curves"] if not c["points"]]
        warn = f"; NO DATA for: {', '.join(empty)}" if empty else ""
        print(f"gnibench: {manifest['number']} ({manifest['id']}, {manifest['scale']} scale) -> "
              f"{d / 'figure' / manifest['files'][0]}{warn}", file=log, flush=True)
    return manifests


def _size(args) -> int:
    """What drawing a figure costs, roughly: the size of its samples table."""
    try:
        return (Path(args[0]) / "samples.parquet").stat().st_size
    except OSError:
        return 0


def list_text(rows: list[dict]) -> str:
    """The figure listing as aligned text: id, number, title; cost per scale."""
    lines = []
    for row in rows:
        lines.append(f"{row['id']:<16} {row['number']:<10} {row['title']}  ({row['reference']})")
        for scale, c in row["scales"].items():
            stated = "" if c["stated"] else " (same as paper)"
            lines.append(f"{'':16} {scale:<6} {c['cells']:>6} cells {c['steps']:>13,} steps "
                         f"{c['samples']:>11,} samples{stated}")
    return "\n".join(lines)
