"""The timing page: the history of every benchmark in a benchmark storage directory
(:mod:`gnibench.suite.foundation.benchmarks`, pytest-benchmark's layout), per machine.

One figure per benchmark group: the median of each benchmark against the saved run (oldest
first; x labels are run number and commit), one line per benchmark and machine, log y; the min as
a thin line below it. The table gives, per benchmark and machine, the last median, the one before
and their ratio (a ratio above :data:`SLOWDOWN` is flagged: ``gnibench bench --compare``'s default).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from gnibench.reports.drawing import Job
from gnibench.reports.tables import num
from gnibench.reports.layout import Figure, margins
from gnibench.reports.render import Panel, Plot, Series
from gnibench.suite.foundation.benchmarks import load_run, runs

SLOWDOWN = 1.3


def history(storage: Path) -> list[dict]:
    """One row per saved benchmark result: machine, run, commit, date, group, name, median, min,
    unit."""
    rows = []
    for machine, f in runs(storage):
        try:
            doc = load_run(f)
        except (ValueError, TypeError, OSError):
            continue
        try:
            commit = str((doc.get("commit_info") or {}).get("id") or "")
        except AttributeError:
            commit = ""
        for b in doc["benchmarks"]:
            try:                        # a hand-edited or damaged entry is skipped, not a crash
                stats = b.get("stats") or {}
                extra = b.get("extra_info") or {}
                rows.append({"machine": machine, "run": f.name[:4], "commit": commit[:8],
                             "date": str(doc.get("datetime", ""))[:16],
                             "group": str(b.get("group") or "other"),
                             "name": str(b.get("fullname") or b.get("name")),
                             "median": float(stats.get("median", math.nan)),
                             "min": float(stats.get("min", math.nan)),
                             "unit": str(extra.get("unit") or "s per round")})
            except (AttributeError, TypeError, ValueError):
                continue
    return rows


def timing_page(storage: Path, out_dir: Path, slug: str, jobs=None) -> dict:
    """The content of the timing page; its figures (to be drawn into ``out_dir``) are appended
    to ``jobs`` (a list or :class:`~gnibench.reports.drawing.Figures`; None: drawn now)."""
    if jobs is None:
        from gnibench.reports.drawing import draw

        jobs = []
        page = timing_page(storage, out_dir, slug, jobs)
        draw(jobs)
        return page
    import pandas as pd

    df = pd.DataFrame(history(storage))
    page = {"title": "Timing history", "figures": [], "rows": [], "code": [0],
            "header": ["benchmark", "machine", "unit", "last median", "previous median",
                       "ratio", f"slower than {SLOWDOWN}×", "runs"],
            "paragraphs": [(f"Benchmark storage: {storage}. Saved by pytest benchmarks "
                            "--benchmark-only (autosave) and gnibench bench; gnibench bench "
                            f"--compare fails above {SLOWDOWN}× the last saved median of the same "
                            "machine (--threshold).")]}
    if df.empty:
        page["paragraphs"].append("No saved benchmark runs were found.")
        return page
    for gi, (group, part) in enumerate(df.groupby("group", sort=True)):
        runs_order = list(dict.fromkeys(zip(part["machine"], part["run"], part["commit"])))
        xpos = {r: i for i, r in enumerate(runs_order)}
        panel = Panel(yscale="log", ylabel=", ".join(sorted(set(part["unit"]))),
                      xlabel="saved run (number, commit)", grid=True,
                      title=f"{group}: median (markers) and min (thin) per saved run",
                      legend={"fontsize": 7, "loc": "center left", "bbox_to_anchor": (1.01, 0.5)},
                      xticks=list(range(len(runs_order))),
                      xticklabels=[f"{r}\n{c}" for _, r, c in runs_order])
        for k, ((name, machine), series) in enumerate(part.groupby(["name", "machine"], sort=True)):
            x = np.array([xpos[r] for r in zip(series["machine"], series["run"], series["commit"])],
                         dtype=float)
            colour = f"C{k % 10}"                 # matplotlib's default colour cycle
            panel.series.append(Series(x, series["median"].to_numpy(float), {
                "color": colour, "marker": "o", "markersize": 4,
                "label": f"{name} [{machine}]"[-70:]}))
            panel.series.append(Series(x, series["min"].to_numpy(float), {
                "color": colour, "linewidth": 0.6, "alpha": 0.6}))
        size = (11, 4.6)
        file = f"group-{gi:02d}.png"
        jobs.append(Job(Plot(size, 1, 1, [panel], margins(size, 1, right=0.62)), out_dir / file))
        page["figures"].append(Figure(f"{slug}/{file}", str(group),
                                      "History of the median per benchmark (log scale).").__dict__)
    for (name, machine), series in df.groupby(["name", "machine"], sort=True):
        last = series["median"].iloc[-1]
        prev = series["median"].iloc[-2] if len(series) > 1 else math.nan
        ratio = last / prev if prev and math.isfinite(prev) else math.nan
        page["rows"].append([name, machine, series["unit"].iloc[-1], num(last), num(prev),
                             num(ratio, ".2f"), "yes" if ratio > SLOWDOWN else "no",
                             str(len(series))])
    return page
