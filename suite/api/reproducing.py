"""``gnibench.reproduce``: run and draw figures and tables of the seeds, as ``gnibench reproduce``
(which calls :func:`reproduce_figures` and prints where each figure went).

Composes :mod:`gnibench.suite.runs.reproduce` (validate every figure, run all their cells over one
store in DIR, each figure's tables into ``DIR/<id>/``) and :mod:`gnibench.reports.figures` (the
images and ``figure.json`` into ``DIR/<id>/figure/``). ``redraw`` draws from the tables already in
DIR without integrating (with the figure section of the file as it is now, provided its cells are
still those of the tables).
"""
from __future__ import annotations

import sys
from pathlib import Path

from gnibench.suite.api.arguments import api_function
from gnibench.suite.foundation.errors import UserError, spelled

#: what drawing a figure imports (the drawing process imports them once, before its forks)
FIGURE_MODULES = ("pandas", "pyarrow.parquet", "matplotlib.pyplot", "gnibench.reports.figures",
                  "gnibench.reports.figures.plot", "gnibench.reports.figures.table")


def reproduce_figures(ids: list[str], *, scale: str = "paper", output: Path | None = None,
                      jobs: int | None = None, executor: str = "local",
                      scheduler: str | None = None, fresh: bool = False, redraw: bool = False,
                      report: bool = False, log=None) -> dict[str, Path]:
    """Run (unless ``redraw``) and draw the figures ``ids`` (``["all"]``: every one) into
    ``output/<id>/``; with ``report``, the report site of ``output`` too. One line per figure
    on ``log`` (default: stderr). Returns {figure id: its results directory}."""
    from gnibench.reports.drawing import Drawers, cores
    from gnibench.suite.runs import reproduce as rep
    from gnibench.suite.runs.scales import check_scale

    check_scale(scale)
    out = Path(output) if output is not None else rep.DEFAULT_DIR
    chosen = rep.choose(list(ids))          # an unknown id is refused before anything starts
    if redraw:
        _check_redraw(out, chosen, jobs, scheduler, fresh)
    with Drawers() as drawers:
        # the figures and the report's plots are drawn by one pool, forked from a process that
        # imports what they need while the cells are prepared and run (jobs=1: in this process)
        if jobs != 1:
            drawers.start(min(jobs or cores(), cores()), preload=FIGURE_MODULES)
        if redraw:
            dirs = [out / fid for fid in chosen]
            figures = [rep.current_figure(fid, d) for fid, d in zip(chosen, dirs)]
        else:
            from gnibench.reports.markdown import render_summary

            experiments = rep.load_figures(chosen, scale)
            dirs = rep.run_figures(experiments, out, jobs=jobs, executor=executor,
                                   scheduler=scheduler, fresh=fresh, summarize=render_summary)
            figures = [e.figure for e in experiments]
        draw_all(dirs, figures, log=log, drawers=drawers)
        if report:               # everything in DIR (figures, a ledger of verify), as a site
            from gnibench.reports.site import build_site

            index = build_site([out], out / "report", drawers=drawers)
            print(f"gnibench: reproduce: report {index}", file=log or sys.stderr)
    return {fid: out / fid for fid in chosen}


def _check_redraw(out: Path, ids: list[str], jobs, scheduler, fresh: bool) -> None:
    for option, value in (("jobs", jobs), ("scheduler", scheduler)):
        if value is not None:
            raise UserError(f"{spelled('--' + option)} does not apply with {spelled('--redraw')} "
                            f"(nothing is run)")
    if fresh:
        raise UserError(f"{spelled('--fresh')} does not apply with {spelled('--redraw')} (nothing "
                        f"is run)")
    missing = [fid for fid in ids if not (out / fid / "cells.parquet").is_file()]
    if missing:
        raise UserError(f"no results for {', '.join(missing)} in {out}; reproduce "
                        f"{' '.join(missing)} first (without {spelled('--redraw')})")


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


@api_function
def reproduce(ids: str | list[str] = "all", *, scale: str = "paper", output: Path | None = None,
              jobs: int | None = None, executor: str = "local", scheduler: str | None = None,
              fresh: bool = False, redraw: bool = False) -> dict[str, Path]:
    """Run and draw figures and tables of the seeds, as ``gnibench reproduce``.

    Every chosen figure is validated at the scale first; then all their cells run over one
    store in ``output`` (a cell shared by several figures is computed once, a second call reuses
    everything), each figure's tables go to ``output/<id>/`` and its images and
    ``figure.json`` to ``output/<id>/figure/``. No report site is written (see
    :func:`gnibench.report`).

    Parameters
    ----------
    ids : str or list of str, default "all"
        A figure id (``"hlw-fig-1.4"``), a list of them, or ``"all"``
        (``gnibench reproduce --list`` lists them with their cost).
    scale : {"paper", "quick"}, default "paper"
        ``paper``: the seed's horizons and step sizes; ``quick``: shortened.
    output : path, optional
        The results directory; default ``results/seeds`` (shared with :func:`gnibench.verify`).
    jobs : int, optional
        Worker processes (default: the number of cores; 1: in this process).
    executor : {"local", "dask"}, default "local"
        A local process pool, or a Dask cluster.
    scheduler : str, optional
        The address of a running Dask scheduler (with ``executor="dask"``).
    fresh : bool, default False
        Ignore the cells stored in ``output`` and compute them again.
    redraw : bool, default False
        Draw again from the tables in ``output``, without integrating.

    Returns
    -------
    dict of str to pathlib.Path
        {figure id: its results directory}, in listing order.

    Raises
    ------
    gnibench.UserError
        An unknown figure id, a bad scale or option, before any work.

    Examples
    --------
    >>> import gnibench, tempfile
    >>> out = tempfile.mkdtemp()
    >>> dirs = gnibench.reproduce("hlw-fig-1.4", scale="quick", output=out, jobs=1)
    >>> sorted(p.name for p in (dirs["hlw-fig-1.4"] / "figure").iterdir())
    ['figure.json', 'hlw-fig-1.4.png', 'hlw-fig-1.4.svg']
    """
    from gnibench.suite.api.arguments import id_list

    chosen = id_list(ids, "gnibench.reproduce")
    return reproduce_figures(chosen, scale=scale, output=output,
                             jobs=None if redraw else jobs, executor=executor,
                             scheduler=scheduler, fresh=fresh, redraw=redraw)
