"""``gnibench.run``: an experiment, as ``gnibench run``, through the same runner, returning its
tables as DataFrames (:class:`RunResult`)."""
from __future__ import annotations

import contextlib
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from gnibench.suite.api.arguments import api_function
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.scratch import scratch_dir


@dataclass
class RunResult:
    """The tables of an experiment run (:func:`gnibench.run`).

    Attributes
    ----------
    samples : pandas.DataFrame
        One row per cell and sample: ``cell``, ``problem``, ``method``, ``t``, ``steps``,
        ``nfev``, the states, ``err_<I>``, ``global_error`` and the chosen metrics' columns.
    cells : pandas.DataFrame
        One row per cell: its specs (``problem``, ``method``, ``base_method``, ``modifiers``,
        ``method_kind``), horizon, ``status`` and ``reason``, counts, the per-cell metrics.
    timings : pandas.DataFrame
        Wall-clock and compile times per cell (the only table that is not reproducible).
    meta : dict
        The tables' provenance: experiment, its TOML text, versions, the cells.
    output : pathlib.Path or None
        The results directory; None when the run went to a temporary directory.
    ensemble : pandas.DataFrame or None
        With ensemble cells: one row per orbit (``cell``, ``orbit``, its initial state
        ``<state>0``, ``status``, ``t_failed``, counters, ``final_<state>``, per-orbit metrics;
        ``ensemble.parquet``); None without.
    ensemble_stats : pandas.DataFrame or None
        With ensemble cells: per cell and measure, ``failed``, ``failure_rate``, ``q10``,
        ``median``, ``q90``, ``min``, ``max`` over the orbits (``ensemble_stats.parquet``).

    Examples
    --------
    >>> import gnibench
    >>> res = gnibench.run({"name": "one-cell", "title": "One cell", "reference": "none",
    ...                     "t_end": 0.5, "cells": [{"problems": ["pendulum"],
    ...                                              "methods": ["rk4:h=0.1"]}]}, jobs=1)
    >>> res
    RunResult('one-cell': 1 cells, 6 samples, in memory)
    >>> res.cells.loc[0, "status"]
    'ok'
    """

    samples: object
    cells: object
    timings: object
    meta: dict = field(default_factory=dict)
    output: Path | None = None
    ensemble: object = None
    ensemble_stats: object = None

    def __repr__(self) -> str:
        where = self.output if self.output is not None else "in memory"
        orbits = "" if self.ensemble is None else f", {len(self.ensemble)} orbits"
        return (f"RunResult({self.meta.get('experiment')!r}: {len(self.cells)} cells, "
                f"{len(self.samples)} samples{orbits}, {where})")

    def ensemble_league(self, eps: float, share: float = 0.9, measure: str | None = None,
                        problem: str | None = None):
        """The league of the ensemble cells: per method family, the cost per orbit (mean
        nfev, mean wall seconds) at which ``share`` of its orbits reach error <= ``eps``
        (failed orbits never do), interpolated along the family's sweep, ranked
        (:func:`gnibench.reports.ensembles.league`).

        Parameters
        ----------
        eps : float
            The accuracy to reach.
        share : float
            The share of the orbits that must reach it (0 < share <= 1).
        measure : str or None
            The error (a column of ``RunResult.ensemble``); default ``max_global_error`` where there
            is a reference, else the first integral's ``max_abs_err_<I>``.
        problem : str or None
            The cells of this problem spec only (default: all).

        Returns
        -------
        pandas.DataFrame
            One row per family: ``family``, ``rank``, ``nfev``, ``nfev_how``, ``wall_seconds``,
            ``rank_wall``, ``best_error``, ``cells``.
        """
        from gnibench.reports.ensembles import league, league_frame

        if self.ensemble is None:
            raise UserError("this run has no ensemble cells ([cells.ensemble])")
        if not (isinstance(share, (int, float)) and 0 < share <= 1) or not (
                isinstance(eps, (int, float)) and eps > 0):
            raise UserError(f"bad eps={eps!r}, share={share!r}; allowed: eps > 0, "
                            f"0 < share <= 1")
        cells, orbits = self.cells, self.ensemble
        if problem is not None:
            cells = cells[cells["problem"] == problem]
            orbits = orbits[orbits["cell"].isin(cells["cell"])]
        wall = dict(zip(self.timings["cell"], self.timings["wall_seconds"]))
        return league_frame(league(cells, orbits, float(eps), float(share), measure, wall))


def read_tables(out: Path, output: Path | None) -> RunResult:
    """A results directory's tables (``samples``, ``cells``, ``timings``.parquet) in memory."""
    from gnibench.suite.runs.storage import check_table_set, read_parquet, read_parquet_meta

    check_table_set(out)
    tables = {name: read_parquet(out / f"{name}.parquet")
              for name in ("samples", "cells", "timings")}
    for name, file in (("ensemble", "ensemble"), ("ensemble_stats", "ensemble_stats")):
        path = out / f"{file}.parquet"
        tables[name] = read_parquet(path) if path.exists() else None
    meta = read_parquet_meta(out / "cells.parquet")
    meta.pop("table", None)
    return RunResult(**tables, meta=meta, output=output)


@api_function
def run(experiment: str | Path | dict, *, output: Path | None = None, jobs: int | None = None,
        executor: str = "local", fresh: bool = False, scheduler: str | None = None,
        scale: str = "paper", repeat: int | None = None) -> RunResult:
    """Run an experiment (a matrix of problems x methods x options), as ``gnibench run``.

    Its cells run in parallel and are stored as they finish: an output directory given again
    resumes the run, computing only the cells that are missing (or whose code changed).

    Parameters
    ----------
    experiment : str, path or dict
        A shipped experiment id (``"quick"``; ``gnibench run --help`` and the docs list them),
        a path to a TOML file, or a dict with the TOML schema (its ``load`` paths are relative
        to the working directory).
    output : path, optional
        The results directory (``samples.parquet``, ``cells.parquet``, ``timings.parquet``,
        ``summary.md``; no report site, see :func:`gnibench.report`). None runs in a scratch
        directory of the kernel cache, removed on return (one left by a killed process is
        removed by the next call, :mod:`gnibench.suite.foundation.scratch`), and keeps the
        tables in memory only.
    jobs : int, optional
        Worker processes (default: the number of cores; 1: serial, in this process).
    executor : {"local", "dask"}, default "local"
        A local process pool, or a Dask cluster (a ``LocalCluster`` of ``jobs`` workers, or the
        one at ``scheduler``).
    fresh : bool, default False
        Ignore the cells stored by earlier runs in ``output``.
    scheduler : str, optional
        The address of a running Dask scheduler (with ``executor="dask"``), e.g.
        ``"tcp://127.0.0.1:8786"``.
    scale : {"paper", "quick"}, default "paper"
        The experiment's paper scale, or its shortened quick scale.
    repeat : int, optional
        Run each cell's timed integration this many times after the warm-up (the fastest, the
        median and the spread go to ``timings``; a run that gives other numbers is an error);
        default: the experiment's ``repeat``, else 1.

    Returns
    -------
    RunResult
        The tables as DataFrames (``samples``, ``cells``, ``timings``), their provenance
        (``meta``) and the results directory (``output``).

    Raises
    ------
    gnibench.UserError
        An unknown experiment, a bad file or dict, a bad option, before any cell runs. A cell
        that diverges is a status in the tables, not an exception.

    Examples
    --------
    >>> import gnibench
    >>> res = gnibench.run({"name": "pendulum-steps", "title": "RK4 on the pendulum",
    ...                     "reference": "[HLW] I.1", "t_end": 1.0,
    ...                     "cells": [{"problems": ["pendulum"], "methods": ["rk4"],
    ...                                "vary": {"h": [0.1, 0.05]}}]}, jobs=1)
    >>> res.cells[["method", "status", "steps"]]
               method status  steps
    0   rk4:h=0.1     ok     10
    1  rk4:h=0.05     ok     20
    """
    from gnibench.reports.markdown import render_summary
    from gnibench.suite.cell.user.loader import discover, refresh
    from gnibench.suite.runs import executors
    from gnibench.suite.runs.experiment import load_experiment, parse_experiment
    from gnibench.suite.runs.runner import run_experiments

    discover()                      # GNIBENCH_LOAD and entry points, as `gnibench run`
    refresh()                       # definitions edited since they were loaded
    if isinstance(experiment, dict):        # its `load` paths are relative to the working dir
        exp = parse_experiment(toml_text(experiment), "experiment dict", scale, Path.cwd(),
                               repeat)
    else:
        exp = load_experiment(experiment, scale, repeat)
    executors.check(executor, jobs, scheduler)
    with contextlib.ExitStack() as stack:
        if output is None:
            out = stack.enter_context(scratch_dir("run"))
        else:
            out = output
        run_experiments([exp], [out], out, jobs=jobs, executor=executor, scheduler=scheduler,
                        fresh=fresh, summarize=render_summary if output is not None else None,
                        name=exp.name)
        return read_tables(out, output)


_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def toml_text(doc: dict) -> str:
    """TOML text of an experiment given as a dict (the TOML schema; tables, arrays of tables,
    strings, numbers, booleans, lists), which :func:`parse_experiment` then validates as a file."""
    if not isinstance(doc, dict):
        raise UserError(f"bad experiment {type(doc).__name__}; allowed: a dict")
    lines, later = [], []
    for k, v in doc.items():
        if isinstance(v, dict):
            later += ["", f"[{_key(k)}]"] + [f"{_key(k2)} = {_value(v2, k2)}" for k2, v2 in v.items()]
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for item in v:
                later += ["", f"[[{_key(k)}]]"] + [f"{_key(k2)} = {_value(v2, k2)}"
                                                   for k2, v2 in item.items()]
        else:
            lines.append(f"{_key(k)} = {_value(v, k)}")
    return "\n".join(lines + later) + "\n"


def _key(k) -> str:
    if not isinstance(k, str):
        raise UserError(f"bad key {k!r} in the experiment dict; allowed: strings")
    return k if _BARE.match(k) else json.dumps(k, ensure_ascii=False)


def _value(v, key) -> str:
    if hasattr(v, "item") and not isinstance(v, (list, tuple, dict)):     # numpy scalars
        v = v.item()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        return ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x, key) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x, k)}" for k, x in v.items()) + "}"
    raise UserError(f"bad value {v!r} of {key!r} in the experiment dict; allowed: strings, "
                    f"numbers, booleans, lists and tables")
