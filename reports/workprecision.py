"""Work-precision diagrams (as DiffEqDevTools' WorkPrecisionSet draws them): error against cost,
log–log, one curve per family (the cells of one setup, :mod:`gnibench.reports.setups`), the points
of a curve being its step-size or tolerance sweep.

One figure per context (one problem, horizon and reference): a row per error measure — final
global error, maximum global error (with a reference), maximum |I(y) − I(y0)| of the problem's
first integral, or those the ``[report]`` section chooses — and a column per cost: ``nfev``
(reproducible) and the integration wall time from ``timings.parquet`` (the fastest of the cell's
repeated runs; not reproducible; compilation excluded). Engines that do not count evaluations
(heyoka, IAS15: nfev NaN) appear on the wall-time panels only. Only ``ok`` cells with a finite,
positive error are drawn; the page lists the others.

What the errors can say is drawn with them (:mod:`gnibench.suite.metrics.regime`): points at or
below the reference's accuracy estimate are hollow (they measure the reference, and are left out
of the Pareto front, the league tables and the order fits), the reference's accuracy and the
saturation level (an error of half the solution: the trajectory lost) are grey lines, and
a panel whose every error is saturated says so in the caption. The Pareto front (the least cost
at which some family reaches each accuracy) is a black dashed step line.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from gnibench.reports.drawing import Job
from gnibench.reports.layout import Figure, page_plot
from gnibench.reports.render import Panel, Plot, Series

COSTS = {"nfev": ("nfev", "f-evaluations (nfev)"),
         "wall": ("wall_ms", "wall time (ms, integration only)")}


def has_sweeps(cells) -> bool:
    """True when some family of the cells has two or more cells (a curve to draw)."""
    return bool((cells.groupby("setup")["cell"].count() >= 2).any())


def measures(cells, chosen=None) -> list[tuple[str, str]]:
    """(column, axis label) of the error measures present in a problem's cells (``chosen``: the
    ``[report]`` section's ``measures``, in its order)."""
    out = []
    for col, label in (("final_global_error", "final global error"),
                       ("max_global_error", "max global error over the samples")):
        if col in cells and cells[col].notna().any():
            out.append((col, label))
    first = [i for i in str(cells["integrals"].iloc[0] or "").split("/") if i]
    names = first if chosen else first[:1]
    for name in names:
        if f"max_abs_err_{name}" in cells:
            out.append((f"max_abs_err_{name}", f"max |{name}(y) − {name}(y0)|"))
    if chosen:
        by = dict(out)
        out = [(c, by[c]) for c in chosen if c in by]
    return out


def no_nfev(cells, names: dict[int, str]) -> list[str]:
    """The families whose cells do not count f-evaluations (drawn against wall time only)."""
    fams = cells.groupby("setup", sort=False)["nfev"].apply(lambda s: s.isna().all())
    return [names[int(f)] for f, missing in fams.items() if missing]


def pareto(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Pareto front of points (cost x, error y): the points no cheaper point beats in error,
    by increasing cost."""
    order = np.lexsort((y, x))
    xs, ys, best = [], [], math.inf
    for i in order:
        if y[i] < best:
            xs.append(x[i])
            ys.append(y[i])
            best = y[i]
    return np.array(xs), np.array(ys)


def panel_points(cells, column: str, xcol: str):
    """Per family (setup id): (x, y, cell ids, verdicts) of its drawable points in sweep order
    (coarse to fine), verdicts from :func:`gnibench.suite.metrics.regime.trusted`."""
    from gnibench.suite.metrics.regime import trusted

    ok = cells.assign(_verdict=trusted(cells, column))
    ok = ok[ok["status"] == "ok"]
    out = {}
    for setup, part in ok.groupby("setup", sort=False):
        x, y = part[xcol].to_numpy(float), part[column].to_numpy(float)
        good = np.isfinite(x) & (x > 0) & np.isfinite(y) & (y > 0)
        if not good.any():
            continue
        sweep = part["sweep_value"].to_numpy(float)[good]
        order = np.argsort(-np.where(np.isnan(sweep), -x[good], sweep), kind="stable")
        out[int(setup)] = (x[good][order], y[good][order],
                           part["cell"].to_numpy(int)[good][order],
                           part["_verdict"].to_numpy(object)[good][order])
    return out


def levels_line(cells, column: str) -> tuple[float, float]:
    """(saturation level, reference accuracy) drawn on a panel: the smallest saturation level
    and the largest accuracy estimate of the context's ok cells (NaN: none)."""
    from gnibench.suite.metrics.regime import levels

    ok = (cells["status"] == "ok").to_numpy()
    ceiling, floor = levels(cells, column)
    ceiling, floor = ceiling[ok], floor[ok]
    sat = float(np.nanmin(ceiling)) if np.isfinite(ceiling).any() else math.nan
    acc = float(np.nanmax(floor)) if np.isfinite(floor).any() else math.nan
    return sat, acc


def wp_plot(title: str, cells, wall_ms: dict[int, float], style: dict, names: dict,
            options: dict | None = None) -> tuple[Plot | None, str]:
    """The work-precision figure of one context (see the module docstring) and the words its
    caption adds (saturated panels)."""
    from gnibench.suite.metrics.regime import BELOW_FLOOR, SATURATED, saturation_words

    options = options or {}
    rows = measures(cells, options.get("measures"))
    costs = [COSTS[c] for c in options.get("costs") or ("nfev", "wall")]
    if not rows:
        return None, ""
    cells = cells.assign(wall_ms=[wall_ms.get(int(c), math.nan) for c in cells["cell"]])
    panels, notes = [], []
    for col, label in rows:
        sat, acc = levels_line(cells, col)
        for xcol, xlabel in costs:
            panel = Panel(xscale="log", yscale="log", xlabel=xlabel, ylabel=label, grid=True)
            points = panel_points(cells, col, xcol)
            front_x, front_y = [], []
            for setup, (x, y, _, verdict) in points.items():
                st = style[setup]
                below = verdict == BELOW_FLOOR
                line = {"color": st["color"], "linestyle": st["linestyle"], "marker": st["marker"],
                        "markersize": 5.5, "linewidth": 1.3, "label": names[setup]}
                if (~below).any():
                    panel.series.append(Series(x[~below], y[~below], line))
                if below.any():
                    hollow = {"color": st["color"], "marker": st["marker"], "linestyle": "none",
                              "markersize": 5.5, "markerfacecolor": "white"}
                    if below.all():
                        hollow["label"] = names[setup]
                    panel.series.append(Series(x[below], y[below], hollow))
                trusted = verdict == ""
                front_x += list(x[trusted])
                front_y += list(y[trusted])
            if front_x:
                fx, fy = pareto(np.array(front_x), np.array(front_y))
                panel.series.append(Series(fx, fy, {
                    "color": "black", "linestyle": (0, (4, 2)), "linewidth": 0.9,
                    "drawstyle": "steps-post", "label": "Pareto front (least cost per accuracy)",
                    "zorder": 1}))
            ymax = max((float(np.max(p[1])) for p in points.values()), default=math.nan)
            xs = [v for p in points.values() for v in p[0]]
            if xs and math.isfinite(sat) and ymax >= 0.01 * sat:
                panel.series.append(Series(np.array([min(xs), max(xs)]), np.array([sat, sat]), {
                    "color": "0.45", "linestyle": "--", "linewidth": 0.9,
                    "label": f"saturation ({saturation_words(col)})"}))
            if xs and math.isfinite(acc) and acc > 0:
                panel.series.append(Series(np.array([min(xs), max(xs)]), np.array([acc, acc]), {
                    "color": "0.45", "linestyle": ":", "linewidth": 1.1,
                    "label": "reference's own accuracy (hollow: below it)"}))
            panels.append(panel)
        verdicts = [v for p in panel_points(cells, col, costs[0][0]).values() for v in p[3]]
        if verdicts and all(v == SATURATED for v in verdicts):
            notes.append(f"Every {label} is above the saturation level "
                         f"({saturation_words(col)}): the trajectory is lost for every method, "
                         f"these errors do not rank the methods.")
    for panel, (_, xlabel) in zip(panels[:len(costs)], costs):
        panel.title = f"against {xlabel.split(' (')[0]}"
    return page_plot(panels, cols=len(costs), panel_height=3.6, title=title), " ".join(notes)


def wp_figures(problem: str, cells, wall_ms: dict[int, float], out_dir: Path, prefix: str,
               slug: str, jobs, style: dict, names: dict, options: dict | None = None,
               context: str = "", repeats: str = "") -> list[Figure]:
    """The work-precision figure of one context's cells (with the columns of
    :func:`gnibench.reports.setups.add_setups`); its drawing is appended to ``jobs``.
    ``wall_ms``: each cell's wall time (ms); ``style``, ``names``: each family's style and name
    by setup id; ``context``: what sets the context apart (its title); ``repeats``: how the wall
    times were measured, in words."""
    from gnibench.reports.plots import brief, problem_id_of

    title = f"{brief(problem, problem_id_of(problem, cells))}: work-precision" + (f" ({context})" if context else "")
    plot, notes = wp_plot(title, cells, wall_ms, style, names, options)
    if plot is None:
        return []
    file = f"{prefix}-work-precision.png"
    jobs.append(Job(plot, out_dir / file))
    words = ", ".join(label for _, label in measures(cells, (options or {}).get("measures")))
    cap = (f"Work-precision: {words} against cost, one curve per family (its sweep of h or "
           f"tolerance); black dashed: the Pareto front. Wall times: {repeats or 'one run per cell'}"
           f" on the machine of the run (not reproducible).")
    missing = no_nfev(cells, names)
    if missing:
        cap += (" " + ", ".join(missing) + " do not count f-evaluations: they appear on the "
                "wall-time panels only.")
    if notes:
        cap = notes + " " + cap
    return [Figure(f"{slug}/{file}", f"{problem}: error against cost"
                   + (f" ({context})" if context else ""), cap)]
