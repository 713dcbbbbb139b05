"""``gnibench.run``, ``gnibench.verify``, ``gnibench.reproduce``, ``gnibench.report``: the
command line's ``run``, ``verify``, ``reproduce`` and ``report`` from Python, through the same code
(the runner, the CLI's own argument parser and commands), returning tables as DataFrames."""
from __future__ import annotations

import contextlib
import io
import json
import math
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from gnibench.suite.foundation.errors import UserError


@dataclass
class RunResult:
    """The tables of a run: ``samples`` (one row per cell and sample), ``cells`` (one row per
    cell), ``timings`` (wall and compile times) as DataFrames, ``meta`` (the tables' provenance:
    experiment, TOML text, versions, cells), and ``output``, the results directory (None when the
    run went to a temporary directory)."""

    samples: object
    cells: object
    timings: object
    meta: dict = field(default_factory=dict)
    output: Path | None = None

    def __repr__(self) -> str:
        where = self.output if self.output is not None else "in memory"
        return (f"RunResult({self.meta.get('experiment')!r}: {len(self.cells)} cells, "
                f"{len(self.samples)} samples, {where})")


def read_tables(out: Path, output: Path | None) -> RunResult:
    """A results directory's tables (``samples``, ``cells``, ``timings``.parquet) in memory."""
    import pandas as pd
    from gnibench.suite.runs.storage import read_parquet_meta

    tables = {name: pd.read_parquet(out / f"{name}.parquet")
              for name in ("samples", "cells", "timings")}
    meta = read_parquet_meta(out / "cells.parquet")
    meta.pop("table", None)
    return RunResult(**tables, meta=meta, output=output)


def run(experiment, *, output=None, jobs: int | None = None, executor: str = "local",
        fresh: bool = False, scheduler: str | None = None, scale: str = "paper",
        repeat: int | None = None) -> RunResult:
    """Run an experiment, as ``gnibench run``: a shipped id (``"quick"``), a path to a TOML file,
    or a dict with the TOML schema (``suite/experiments/README.md``; its ``load`` paths are
    relative to the working directory). ``output``: the results
    directory (resumable, as the command line's ``-o``; no report is written, see
    :func:`report`); None runs in a temporary directory and keeps the tables in memory only.
    ``jobs``, ``executor`` (``local`` or ``dask``), ``scheduler``, ``fresh``, ``scale``,
    ``repeat`` (timed integrations per cell): as on the command line."""
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
    elif isinstance(experiment, (str, Path)):
        exp = load_experiment(experiment, scale, repeat)
    else:
        raise UserError(f"bad experiment {type(experiment).__name__}; allowed: a shipped "
                        f"experiment id, a path to a TOML file, or a dict with the TOML schema")
    executors.check(executor, jobs, scheduler)
    with contextlib.ExitStack() as stack:
        if output is None:
            out = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="gnibench-run-")))
        else:
            out = Path(output)
        run_experiments([exp], [out], out, jobs=jobs, executor=executor, scheduler=scheduler,
                        fresh=fresh, summarize=render_summary if output is not None else None,
                        name=exp.name)
        return read_tables(out, None if output is None else out)


def _cli(argv: list[str]) -> int:
    """Run a command of the command line (parsed by its own parser: the same defaults and
    checks); its standard output, meant for a terminal, is dropped."""
    from gnibench.suite.cli.main import _parser
    from gnibench.suite.cli.reproduce import run as reproduce_command
    from gnibench.suite.cli.verify import verify_command

    a = _parser().parse_args(argv)
    command = {"verify": verify_command, "reproduce": reproduce_command}[a.command]
    with contextlib.redirect_stdout(io.StringIO()):
        return command(a)


def _common(output, jobs, executor, scheduler) -> list[str]:
    argv = ["--executor", str(executor)]
    if output is not None:
        argv += ["-o", str(output)]
    if jobs is not None:
        argv += ["-j", str(int(jobs))]
    if scheduler is not None:
        argv += ["--scheduler", str(scheduler)]
    return argv


def _ids(ids) -> list[str]:
    if isinstance(ids, str):
        return [ids]
    if not all(isinstance(i, str) for i in ids):
        raise UserError(f"bad ids {ids!r}; allowed: an id, 'all', or a list of ids")
    return list(ids)


def verify(ids="all", *, scale: str = "quick", output=None, jobs: int | None = None,
           executor: str = "local", scheduler: str | None = None):
    """Check claims of the ledger, as ``gnibench verify``; returns the ledger as a DataFrame (one
    row per claim: ``id``, ``citation``, ``claim``, ``verdict``, ``expected``, ``unexpected``,
    ``measured``, ``seed_value``, ``threshold``, ``figure``, ...). ``output``: the results
    directory (the runs' tables, ``ledger.parquet``, ``ledger.md``; resumable and shared with
    :func:`reproduce`); None works in a temporary directory."""
    import pandas as pd

    with contextlib.ExitStack() as stack:
        out = Path(output) if output is not None else Path(
            stack.enter_context(tempfile.TemporaryDirectory(prefix="gnibench-verify-")))
        _cli(["verify", *_ids(ids), "--scale", str(scale), "--no-report",
              *_common(out, jobs, executor, scheduler)])
        return pd.read_parquet(out / "ledger.parquet")


def reproduce(ids="all", *, scale: str = "paper", output=None, jobs: int | None = None,
              executor: str = "local", scheduler: str | None = None, fresh: bool = False,
              redraw: bool = False) -> dict[str, Path]:
    """Run and draw figures of the seeds, as ``gnibench reproduce`` (images, ``figure.json``
    and tables under ``output/<id>/``; default ``results/seeds``, as the command line); returns
    {figure id: its results directory}."""
    from gnibench.suite.runs import reproduce as rep

    out = Path(output) if output is not None else rep.DEFAULT_DIR
    chosen = rep.choose(_ids(ids))
    argv = ["reproduce", *chosen, "--scale", str(scale), "--no-report",
            *_common(out, None if redraw else jobs, executor, scheduler)]
    _cli(argv + (["--fresh"] if fresh else []) + (["--redraw"] if redraw else []))
    return {fid: out / fid for fid in chosen}


def report(dirs, output, *, accuracy=None, benchmarks=None) -> Path:
    """Render the report site of results directories (of :func:`run`, :func:`verify`,
    :func:`reproduce`) into ``output``, as ``gnibench report DIR... -o SITE``; returns the
    path of its ``index.html``."""
    from gnibench.reports.league import DEFAULT_THRESHOLDS
    from gnibench.reports.site import build_site

    dirs = [Path(dirs)] if isinstance(dirs, (str, Path)) else [Path(d) for d in dirs]
    try:
        thresholds = DEFAULT_THRESHOLDS if accuracy is None else tuple(float(a) for a in accuracy)
    except (TypeError, ValueError):
        thresholds = ()
    if not thresholds or not all(0 < a < math.inf for a in thresholds):
        raise UserError(f"bad accuracy {accuracy!r}; allowed: numbers > 0, e.g. (1e-4, 1e-8)")
    with contextlib.redirect_stdout(io.StringIO()):
        return Path(build_site(dirs, Path(output), thresholds,
                               None if benchmarks is None else Path(benchmarks)))


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
