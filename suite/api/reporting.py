"""``gnibench.report``: the report site (HTML and Markdown) of results directories, as
``gnibench report DIR... -o SITE`` (which calls :func:`build_report`)."""
from __future__ import annotations

import math
from pathlib import Path

from gnibench.suite.api.arguments import api_function
from gnibench.suite.foundation.errors import UserError, named


def default_site(dirs: list[Path]) -> Path:
    """Where the site goes when no output is given: ``DIR/report`` for one directory,
    ``./report`` for several."""
    return Path(dirs[0]) / "report" if len(dirs) == 1 else Path("report")


def build_report(dirs: list[Path], output: Path | None = None, *, accuracy=None,
                 benchmarks: Path | None = None, log=None, option: str = "-o",
                 plots: dict | None = None) -> Path:
    """Render the site of the results directories ``dirs`` into ``output`` (default:
    :func:`default_site`); returns its ``index.html``. ``accuracy``: the accuracies ε of the
    league tables (default 1e-4, 1e-8); ``benchmarks``: a benchmark storage for the timing page
    (default ``./.benchmarks`` when it exists). Bad input raises UserError before anything is
    written (``option``: how the caller names the site, in messages). ``plots``: ``[report]``
    keys that replace those of every experiment file."""
    from gnibench.reports.league import DEFAULT_THRESHOLDS
    from gnibench.reports.site import build_site
    from gnibench.suite.foundation.outputs import check_output_dir

    if not dirs:
        raise UserError("no results directory given; allowed: one or more directories written "
                        "by gnibench run, reproduce or verify")
    from gnibench.suite.runs.report_schema import report_options

    if plots is not None:
        report_options(plots, "plots")                # one line on a bad key, before any work
    thresholds = DEFAULT_THRESHOLDS if accuracy is None else tuple(accuracy)
    if not thresholds or not all(0 < a < math.inf for a in thresholds):
        raise UserError(f"bad accuracy {list(thresholds)!r}; allowed: numbers > 0, e.g. "
                        f"(1e-4, 1e-8)")
    site = Path(output) if output is not None else default_site(dirs)
    check_output_dir(site, option if output is not None else "report directory")
    if benchmarks is None and Path(".benchmarks").is_dir():
        benchmarks = Path(".benchmarks")
    if benchmarks is not None and not Path(benchmarks).is_dir():
        raise UserError(f"bad {named('--benchmarks', str(benchmarks))}: not a directory")
    return Path(build_site([Path(d) for d in dirs], site, thresholds,
                           None if benchmarks is None else Path(benchmarks), log=log,
                           plots=plots))


@api_function
def report(dirs: Path | list[Path], output: Path | None = None, *,
           accuracy: list[float] | None = None, benchmarks: Path | None = None,
           plots: dict | None = None) -> Path:
    """Render the report site of results directories, as ``gnibench report DIR... -o SITE``.

    The site (``index.html``, one page per experiment, the ledger and the figures, each page
    also as Markdown) reads the tables only: results of :func:`gnibench.run`,
    :func:`gnibench.verify` and :func:`gnibench.reproduce`, or of the command line.

    Parameters
    ----------
    dirs : path or list of paths
        Results directories, or directories holding several (one level down).
    output : path, optional
        The site directory; default ``DIR/report`` for one directory, ``./report`` for several.
    accuracy : list of float, optional
        The accuracies ε of the league tables (each > 0); default ``[1e-4, 1e-8]``.
    benchmarks : path, optional
        A benchmark storage (pytest-benchmark's layout) for the timing page; default
        ``./.benchmarks`` when it exists.
    plots : dict, optional
        What the figures show, as the experiment file's ``[report]`` section (its keys replace
        the file's for every experiment): ``cells`` (``"auto"``, ``"all"`` or a list of cell
        ids), ``family``, ``time_axis``, ``error_axis``, ``figures``, ``measures``, ``costs``,
        ``target``.

    Returns
    -------
    pathlib.Path
        The site's ``index.html``.

    Raises
    ------
    gnibench.UserError
        No directory, a directory without results, a bad accuracy or output, before anything
        is written.

    Examples
    --------
    >>> import gnibench, tempfile
    >>> from pathlib import Path
    >>> out = Path(tempfile.mkdtemp())
    >>> res = gnibench.run({"name": "tiny", "title": "Two cells", "reference": "none",
    ...                     "t_end": 0.5, "cells": [{"problems": ["pendulum"],
    ...                     "methods": ["rk4"], "vary": {"h": [0.1, 0.05]}}]},
    ...                    output=out / "tiny", jobs=1)
    >>> index = gnibench.report(out / "tiny", out / "site")
    >>> index.name, index.is_file()
    ('index.html', True)
    """
    import contextlib
    import io

    listed = [dirs] if isinstance(dirs, Path) else dirs
    with contextlib.redirect_stdout(io.StringIO()):
        return build_report(listed, output, accuracy=accuracy, benchmarks=benchmarks,
                            option="output", plots=plots)
