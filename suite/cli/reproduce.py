"""``gnibench reproduce ID... | all``: run the seeds' figures and draw them.

A shell on the library (:func:`gnibench.suite.api.reproducing.reproduce_figures`: validate every
figure, run all their cells over one store in DIR, draw each into ``DIR/<id>/figure/``).
``--redraw`` draws from the tables already in DIR without integrating; ``--list`` prints the
figures, their scales and their cost.
"""
from __future__ import annotations

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
    """``gnibench reproduce``: the arguments to
    :func:`gnibench.suite.api.reproducing.reproduce_figures`, or ``--list``."""
    from gnibench.suite.api.reproducing import reproduce_figures
    from gnibench.suite.runs import reproduce as rep
    from gnibench.suite.runs.scales import check_scale

    check_scale(a.scale)
    if a.list:
        if a.ids or a.redraw:
            raise UserError("--list takes no ids and no --redraw")
        print(list_text(rep.listing()))
        return 0
    reproduce_figures(a.ids, scale=a.scale, output=a.output, jobs=a.jobs, executor=a.executor,
                      scheduler=a.scheduler, fresh=a.fresh, redraw=a.redraw,
                      report=not a.no_report)
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
