"""The ``gnibench`` command line: solve, list, run, report, reproduce, verify, bench.

Bad input gives one line on stderr and exit code 2 (no traceback, nothing written).
"""
from __future__ import annotations

import argparse
import contextlib
import json
import sys
from pathlib import Path

from gnibench.suite.foundation.budgets import MAX_REPEAT, check_limits
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.numbers import option, parse_float
from gnibench.suite.foundation.outputs import check_output_dir, check_output_file, fault
from gnibench.suite.foundation.status import Status


class _Once(argparse.Action):
    """An option given twice is an error, not a silent override (``--steps 10 --steps 20``)."""

    def __call__(self, parser, namespace, values, option_string=None):
        given = namespace.__dict__.setdefault("_given", set())
        if self.dest in given:
            raise UserError(f"{option_string} given twice; allowed: once")
        given.add(self.dest)
        setattr(namespace, self.dest, values if self.nargs != 0 else self.const)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.register("action", None, _Once)
        self.register("action", "store", _Once)
        self.register("action", "store_true", _flag)

    def error(self, message):  # one line, exit 2 (argparse would print the usage too)
        raise UserError(message)


def _flag(option_strings, dest, default=False, required=False, help=None):
    return _Once(option_strings, dest, nargs=0, const=True, default=default, required=required,
                 help=help)


def _path(text: str) -> Path:
    if not text.strip():
        raise UserError(f"bad -o {text!r}: an empty path; allowed: a file or directory name")
    return Path(text)


JOBS = option("int", "-j", low=1, high=1024)


def _load_option(parser) -> None:
    parser.add_argument("--load", action="append", default=[], metavar="FILE",
                        help="a TOML file of user definitions ([[problem]], [[method]]); "
                             "repeatable (also GNIBENCH_LOAD=FILE:FILE)")


def _definitions(a) -> None:
    """User definitions: GNIBENCH_LOAD and the entry points, then each --load FILE."""
    from gnibench.suite.cell.user.loader import discover, load

    discover()
    for path in a.load:
        load(path)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="gnibench", description="Benchmark integrators of ODEs with first integrals.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    s = sub.add_parser("solve", help="integrate one cell and write its trajectory")
    s.add_argument("problem", help="PROBLEM spec, e.g. kepler-2d:e=0.6")
    s.add_argument("method", help="METHOD spec, e.g. rk4:h=0.01+observer:theta=10")
    g = s.add_mutually_exclusive_group(required=True)
    g.add_argument("--steps", type=option("int", "--steps"), help="number of steps N")
    g.add_argument("--t-end", type=option("float", "--t-end", low=0.0, low_open=True),
                   help="final time T (last step shortened to land on T)")
    s.add_argument("--every", type=option("int", "--every"), default=1,
                   help="sample every K steps (plus the final point)")
    s.add_argument("--dt-out", type=option("float", "--dt-out", low=0.0, low_open=True),
                   metavar="D",
                   help="sample at t = k*D (every K-th point with --every K) plus the final point, "
                        "located exactly for every compiled method: dense output (dopri5, dop853) "
                        "or a partial step of the method from the last step; the steps are those "
                        "taken without it (suite/cell/timegrid.py)")
    s.add_argument("--format", choices=("csv", "json", "parquet"), default="csv")
    s.add_argument("-o", "--output", type=_path, help="output file (default: stdout)")
    s.add_argument("--reference", metavar="REF",
                   help="what global_error is measured against: exact | heyoka[:precision=double|"
                        "long double|real128,tol=T] | rebound[:tol=T] (IAS15) | none "
                        "(default: exact when the problem has one, else none)")
    s.add_argument("--metrics", metavar="M,...",
                   help="metrics beside the defaults (err_<I>, global_error), e.g. "
                        "eta,precession,growth:of=H (see `gnibench list metrics`)")
    s.add_argument("--section", type=option("int", "--section"), metavar="K",
                   help="integrate until K crossings of the problem's Poincaré section (within "
                        "--t-end / --steps) and write the section points (suite/cell/sections.py)")
    _load_option(s)

    ls = sub.add_parser("list", help="list problems, methods or metrics")
    ls.add_argument("what", choices=("problems", "methods", "metrics"))
    ls.add_argument("--format", choices=("table", "json"), default="table")
    _load_option(ls)

    r = sub.add_parser("run", help="run an experiment (TOML file or shipped name)")
    r.add_argument("experiment", help="path to a TOML file, or the name of a shipped experiment")
    r.add_argument("-o", "--output", type=_path, default=None,
                   help="output directory (default: results/<experiment name>)")
    r.add_argument("-j", "--jobs", type=JOBS, default=None, metavar="N",
                   help="worker processes (default: the number of cores; 1: serial, in this "
                        "process)")
    r.add_argument("--executor", default="local", metavar="local|dask",
                   help="local: a process pool (default); dask: a Dask LocalCluster of N "
                        "workers, or the cluster at --scheduler")
    r.add_argument("--scheduler", metavar="ADDRESS",
                   help="address of a running Dask scheduler (with --executor dask)")
    r.add_argument("--fresh", action="store_true",
                   help="ignore the cells stored by earlier runs in the output directory")
    r.add_argument("--scale", default="paper", metavar="paper|quick",
                   help="the experiment's paper scale (default) or its shortened quick scale")
    r.add_argument("--repeat", type=option("int", "--repeat", high=MAX_REPEAT), default=None,
                   metavar="N",
                   help="run each cell's timed integration N times after the warm-up (min, "
                        "median and spread in timings.parquet; default: the file's repeat, else 1)")
    _load_option(r)

    from gnibench.suite.cli.reproduce import add_parser

    add_parser(sub, _path, JOBS)

    v = sub.add_parser("verify", help="check the claims of [B] and [HLW] against our measurements")
    v.add_argument("claims", nargs="*", metavar="ID", help="claim ids (default: all)")
    v.add_argument("--list", action="store_true", help="list the claims without running them")
    v.add_argument("--scale", default="quick", metavar="quick|paper",
                   help="quick (short horizons) or paper (the seeds' own)")
    v.add_argument("--format", default="text", metavar="text|json")
    v.add_argument("-o", "--output", type=_path, default=None,
                   help="output directory (default: results/seeds, shared with gnibench reproduce: "
                        "cells run by either are reused by the other)")
    v.add_argument("-j", "--jobs", type=JOBS, default=None, metavar="N")
    v.add_argument("--executor", default="local", metavar="local|dask")
    v.add_argument("--scheduler", metavar="ADDRESS")
    v.add_argument("--no-report", action="store_true",
                   help="do not write the report site (DIR/report/index.html)")
    v.add_argument("--mutants", nargs="?", const="all", default=None, metavar="ID,...|FILE.toml",
                   help="mutation testing: run the ledger and the tests on copies of the "
                        "package with each mutant (or those named, or those of a TOML file of held-out "
                        "[[mutant]] entries) applied; writes DIR/mutants.json")
    v.add_argument("--mutant-tests", default="auto", metavar="auto|all|none",
                   help="the tests run against each mutant: auto (those whose imports reach the "
                        "mutated file), all (the complete test suite), none (the ledger only)")
    v.add_argument("--mutant-timeout", type=float, default=3600.0, metavar="SECONDS",
                   help="the longest a phase of a mutant's verification may run (an overrun of "
                        "4x the baseline's time plus 120 s within it kills the mutant)")
    r.add_argument("--no-report", action="store_true",
                   help="do not write the report (DIR/report/index.html); summary.md is written")

    rp = sub.add_parser("report", help="a static site (HTML and Markdown) from results directories")
    rp.add_argument("dirs", nargs="+", metavar="DIR",
                    help="results directories of gnibench run (or directories holding several)")
    rp.add_argument("-o", "--output", type=_path, default=None, metavar="SITE",
                    help="site directory (default: DIR/report for one DIR, ./report for several)")
    rp.add_argument("--accuracy", metavar="EPS,...",
                    help="accuracies of the league tables (default: 1e-4,1e-8)")
    rp.add_argument("--benchmarks", type=_path, default=None, metavar="DIR",
                    help="benchmark storage for the timing page (default: ./.benchmarks if it "
                         "exists)")

    b = sub.add_parser("bench", help="time kernels in ns/step against a C loop")
    b.add_argument("--steps", type=option("int", "--steps"), default=2_000_000,
                   help="steps per timed run (default 2000000; within GNIBENCH_MAX_STEPS)")
    b.add_argument("--no-c", action="store_true", help="skip the gcc -O3 reference loop")
    b.add_argument("--storage", type=_path, default=Path(".benchmarks"), metavar="DIR",
                   help="benchmark history, pytest-benchmark's layout DIR/<machine>/NNNN_<commit>"
                        ".json (default: .benchmarks)")
    b.add_argument("--no-save", action="store_true", help="do not save this run in the history")
    b.add_argument("--compare", action="store_true",
                   help="compare the medians with the last saved run of this machine; exit 1 "
                        "when one is more than --threshold times slower")
    b.add_argument("--threshold", type=option("float", "--threshold", low=1.0, low_open=True,
                                              allowed="a finite number > 1 (e.g. 1.3)"),
                   default=1.3, metavar="X",
                   help="slowdown that fails --compare (default 1.3: 30%% slower)")
    return p


def _solve(a) -> int:
    from gnibench.suite.cli import streams
    from gnibench.suite.runs.progress import SolveProgress
    from gnibench.suite.runs.solving import solve_cell_spec, solve_output
    from gnibench.suite.runs.streaming import spool_directory
    from gnibench.suite.runs.writers import write_columns

    if a.output is not None and str(a.output) in ("-", "/dev/stdout"):
        a.output = None                   # stdout named as a file: written to stdout
    if a.format == "parquet" and a.output is None:
        raise UserError("--format parquet needs -o FILE (binary output is not written to stdout)")
    if a.output is not None:
        check_output_file(a.output)
    elif streams.stdout_closed():
        raise UserError("stdout is closed; allowed: -o FILE, or an open stdout")
    check_limits()
    cell = solve_cell_spec(a.problem, a.method, steps=a.steps, t_end=a.t_end, every=a.every,
                           dt_out=a.dt_out, section=a.section, reference=a.reference,
                           metrics=() if a.metrics is None else a.metrics)
    progress = SolveProgress(f"{a.problem} {a.method}")
    with spool_directory(cell) as spool:     # the table made and written block by block
        try:
            out = solve_output(cell, progress=progress, spool=spool)
        finally:
            progress.close()
        try:
            write_columns(out.columns, out.meta, a.format, a.output, sys.stdout)
        except OSError as e:              # e.g. the disk filled up: nothing is left half-written
            raise fault(e, f"writing {a.output or 'stdout'}", "run the same command again once "
                        "there is room") from None
    if out.interrupted is not None:       # the samples so far are written, then exit 130
        raise out.interrupted
    for name, why in out.skipped.items():
        print(f"gnibench: metric {name} does not apply: {why}", file=sys.stderr)
    status = out.traj.status
    if out.traj.reason or status.kind == "failure":
        print(f"gnibench: {status}: {out.traj.reason or status.doc}", file=sys.stderr)
    # a budget stopped the run: the output is not what was asked for (the rows so far are kept)
    return 1 if status is Status.MAX_ROWS else 0


def _list(a) -> int:
    from gnibench.suite.api.listing import listing

    rows = listing(a.what)
    if a.format == "json":
        print(json.dumps(rows, indent=1, default=str))
    else:
        from gnibench.suite.cli.listing import as_table

        print(as_table(a.what, rows))
    return 0


def _run(a) -> int:
    from gnibench.suite.runs.pool import start

    # first: the pool's workers get ready (numba) while the experiment is read (-j 1, Dask: none)
    early = start(a.jobs) if a.executor == "local" else None
    with early or contextlib.nullcontext() as pool:
        return _run_with(a, pool)


def _run_with(a, pool) -> int:
    from gnibench.reports.drawing import Drawers
    from gnibench.reports.markdown import render_summary
    from gnibench.suite.runs.runner import run_experiment

    with Drawers() as drawers:      # the report's drawing process imports matplotlib meanwhile
        out = run_experiment(a.experiment, a.output, jobs=a.jobs, executor=a.executor,
                             scheduler=a.scheduler, fresh=a.fresh, summarize=render_summary,
                             scale=a.scale, started=None if a.no_report else drawers.start,
                             pool=pool, repeat=a.repeat)
        if not a.no_report:
            from gnibench.reports.site import build_site

            index = build_site([out], out / "report", drawers=drawers)
            print(f"gnibench: report: {index}", file=sys.stderr)
    return 0


def _accuracies(text: str | None) -> tuple[float, ...] | None:
    if text is None:
        return None
    allowed = "finite numbers > 0 separated by commas, e.g. 1e-4,1e-8"
    return tuple(parse_float(v, "--accuracy", low=0.0, low_open=True, allowed=allowed)
                 for v in text.split(","))


def _report(a) -> int:
    from gnibench.suite.api.reporting import build_report

    index = build_report([Path(d) for d in a.dirs], a.output, accuracy=_accuracies(a.accuracy),
                         benchmarks=a.benchmarks, log=sys.stderr)
    print(f"gnibench: report: {index}", file=sys.stderr)
    return 0


def _bench(a) -> int:
    from gnibench.suite.foundation.budgets import check_count
    from gnibench.suite.runs.bench import bench
    from gnibench.suite.runs.benchsave import save_and_compare

    check_limits()
    check_count(a.steps, "gnibench bench --steps", "GNIBENCH_MAX_STEPS", "steps")
    if not a.no_save:                     # refused now, not after the timed runs
        from gnibench.suite.foundation.benchmarks import machine_id

        check_output_dir(a.storage, "--storage")
        check_output_dir(a.storage / machine_id(), "--storage")
    elif a.compare and a.storage.exists() and not a.storage.is_dir():
        raise UserError(f"bad --storage {a.storage}: it exists and is not a directory")
    rows = bench(steps=a.steps, with_c=not a.no_c)
    return save_and_compare(rows, a.storage, save=not a.no_save, against=a.compare,
                            threshold=a.threshold)


def main(argv=None) -> int:
    """The command line; returns the exit code: 0, 1 (a verdict or comparison that failed, or a
    fault during work such as a full disk), 2 (bad input), 130/143 (SIGINT/SIGTERM)."""
    from gnibench.suite.cli import signals, streams
    from gnibench.suite.foundation.errors import EDGE

    edge = EDGE.set("cli")          # errors name options as flags (--steps 0), not keywords
    try:
        with signals.handling(), streams.tolerant():
            return _main(argv)
    except KeyboardInterrupt:       # a signal between the handlers' start and _main's own try
        signals.quiet()
        print(f"gnibench: {signals.message()}", file=sys.stderr)
        return signals.exit_code()
    finally:
        EDGE.reset(edge)


def _main(argv) -> int:
    from gnibench.suite.cli import signals
    from gnibench.suite.foundation.outputs import Fault

    try:
        a = _parser().parse_args(argv)
        from gnibench.suite.cli.reproduce import run as _reproduce

        commands = {"solve": _solve, "list": _list, "run": _run, "reproduce": _reproduce,
                    "bench": _bench, "report": _report}
        if a.command in ("solve", "run", "reproduce", "verify", "bench"):
            from gnibench.suite.foundation.cache import check_cache_root

            check_limits()
            check_cache_root()
        if a.command in ("solve", "list", "run"):
            _definitions(a)
        if a.command == "verify":
            from gnibench.suite.cli.verify import verify_command

            return verify_command(a)
        code = commands[a.command](a)
        sys.stdout.flush()                 # a failing stdout (ENOSPC) is reported here, once
        return code
    except UserError as e:
        print(f"gnibench: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except Fault as e:
        print(f"gnibench: error: {_one_line(e)}", file=sys.stderr)
        return 1
    except OSError as e:                   # a fault of the environment no check could foresee
        from gnibench.suite.foundation.cache import cache_fault

        where = f" ({e.filename})" if getattr(e, "filename", None) else ""
        line = cache_fault(e) or f"{e.strerror or type(e).__name__}{where}"
        print(f"gnibench: error: {line}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        signals.quiet()
        print(f"gnibench: {signals.message()}", file=sys.stderr)
        return signals.exit_code()


def _one_line(e: Exception) -> str:
    return " ".join(str(e).split("\n"))


if __name__ == "__main__":
    sys.exit(main())
