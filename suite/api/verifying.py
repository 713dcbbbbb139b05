"""``gnibench.verify``: check the claims of the ledger, as ``gnibench verify`` (which calls
:func:`check_claims` and prints its verdicts).

The runs go through the runner with one shared store in the output directory (parallel,
resumable, shared with :func:`gnibench.reproduce`); the verdicts are judged from the tables only
(:mod:`gnibench.suite.ledger.verdicts`) and written as ``ledger.parquet`` and ``ledger.md``.
"""
from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass
from pathlib import Path

from gnibench.suite.api.arguments import api_function, id_list
from gnibench.suite.foundation.errors import UserError, named
from gnibench.suite.foundation.scratch import scratch_dir

SCALES = ("quick", "paper")


@dataclass
class Ledger:
    """The verdicts of a verification: ``verdicts`` (:class:`gnibench.suite.ledger.verdicts.
    Verdict`, in ledger order), where the ledger was written (``output``) and its report site
    (``report``: its ``index.html``, None when none was written)."""

    verdicts: list
    output: Path
    scale: str
    report: Path | None = None

    @property
    def unexpected(self) -> list[str]:
        """The claims whose verdict differs from the expected one, or failed to measure."""
        return [v.id for v in self.verdicts if v.unexpected]


def check_scale(scale: str) -> str:
    if scale not in SCALES:
        raise UserError(f"bad {named('--scale', repr(scale))}; allowed: {', '.join(SCALES)}")
    return scale


def check_claims(ids: list[str], *, scale: str = "quick", output: Path | None = None,
                 jobs: int | None = None, executor: str = "local", scheduler: str | None = None,
                 report: bool = False) -> Ledger:
    """Run what the claims ``ids`` need (``[]`` or ``["all"]``: every claim), judge them, write
    ``output/ledger.parquet`` and ``output/ledger.md`` (and the report site of ``output`` with
    ``report``). Bad input raises UserError before any work."""
    from gnibench.suite.ledger.verify import needed_experiments, select_claims
    from gnibench.suite.runs import executors
    from gnibench.suite.runs.experiment import load_experiment
    from gnibench.suite.runs.reproduce import DEFAULT_DIR
    from gnibench.suite.runs.runner import run_experiments

    check_scale(scale)
    claims = select_claims(list(ids))
    executors.check(executor, jobs, scheduler)
    out = Path(output) if output is not None else DEFAULT_DIR
    experiments = [load_experiment(name, scale) for name in needed_experiments(claims, scale)]
    outs = [out / e.name for e in experiments]
    if experiments:
        run_experiments(experiments, outs, out, jobs=jobs, executor=executor,
                        scheduler=scheduler, name="verify")
    ledger = _judge(claims, {e.name: o for e, o in zip(experiments, outs)}, out, scale)
    if report:
        from gnibench.reports.site import build_site

        ledger.report = build_site([out], out / "report")
    return ledger


def _judge(claims, dirs: dict[str, Path], out: Path, scale: str) -> Ledger:
    from gnibench.reports.ledger import render_ledger
    from gnibench.suite.foundation.cache import atomic_write
    from gnibench.suite.foundation.provenance import versions
    from gnibench.suite.ledger.verdicts import Results
    from gnibench.suite.ledger.verify import judge, ledger_table, write_ledger

    verdicts = judge(claims, Results(dirs), scale)
    meta = {"scale": scale, "versions": versions(),
            # relative to the ledger: the same ledger bytes whatever directory it was written to
            "experiments": {k: os.path.relpath(v, out) for k, v in dirs.items()}}
    write_ledger(verdicts, out, meta)
    text = render_ledger(ledger_table(verdicts), meta)
    atomic_write(out / "ledger.md", lambda p: Path(p).write_text(text, encoding="utf-8"))
    return Ledger(verdicts, out, scale)


@api_function
def verify(ids: str | list[str] = "all", *, scale: str = "quick", output: Path | None = None,
           jobs: int | None = None, executor: str = "local", scheduler: str | None = None):
    """Check claims of the seeds' ledger against our measurements, as ``gnibench verify``.

    Runs what the chosen claims need (in parallel, resumable: one store in ``output``, shared
    with :func:`gnibench.reproduce`), judges each claim from the tables and writes
    ``output/ledger.parquet`` and ``output/ledger.md``.

    Parameters
    ----------
    ids : str or list of str, default "all"
        A claim id (``"B-2-b"``), a list of them, or ``"all"``; the parts of an aggregate claim
        are judged with it. ``gnibench verify --list`` lists the ids.
    scale : {"quick", "paper"}, default "quick"
        ``quick``: the shortened horizons of the experiments' quick scale; ``paper``: the seeds'
        own (claims stated at the paper scale only are then judged too).
    output : path, optional
        The results directory (the runs' tables, the ledger); None works in a scratch
        directory of the kernel cache, removed on return (one left by a killed process is
        removed by the next call, :mod:`gnibench.suite.foundation.scratch`).
    jobs : int, optional
        Worker processes (default: the number of cores; 1: in this process).
    executor : {"local", "dask"}, default "local"
        A local process pool, or a Dask cluster (a ``LocalCluster`` of ``jobs`` workers, or the
        one at ``scheduler``).
    scheduler : str, optional
        The address of a running Dask scheduler (with ``executor="dask"``).

    Returns
    -------
    pandas.DataFrame
        The ledger: one row per claim (``id``, ``citation``, ``claim``, ``verdict``,
        ``expected``, ``unexpected``, ``measured``, ``seed_value``, ``threshold``, ``figure``,
        ...), as ``ledger.parquet``.

    Raises
    ------
    gnibench.UserError
        An unknown claim id, a bad scale, executor or option, before any work.

    Examples
    --------
    An identity claim is checked without running any cell:

    >>> import gnibench
    >>> ledger = gnibench.verify("HLW-1.2-a")
    >>> ledger.loc[0, "id"], ledger.loc[0, "verdict"]
    ('HLW-1.2-a', 'reproduced')
    """
    import pandas as pd

    with contextlib.ExitStack() as stack:
        out = output if output is not None else stack.enter_context(scratch_dir("verify"))
        check_claims(id_list(ids), scale=scale, output=out, jobs=jobs, executor=executor,
                     scheduler=scheduler)
        return pd.read_parquet(out / "ledger.parquet")
