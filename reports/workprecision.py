"""Work-precision diagrams (as DiffEqDevTools' WorkPrecisionSet draws them): error against cost,
log–log, one curve per method family, the points of a curve being its step-size or tolerance
sweep.

Per problem, one figure per error measure — final global error, maximum global error (with a
reference), maximum |I(y) − I(y0)| of the problem's first integral — each with two panels: against
``nfev`` (reproducible) and against the integration wall time from ``timings.parquet`` (not
reproducible; compilation excluded). Engines that do not count evaluations (heyoka, IAS15: nfev
NaN) appear on the wall-time panels only. Only ``ok`` cells with a finite, positive error are
drawn; the page lists the others.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from gnibench.reports.drawing import Job
from gnibench.reports.palette import styles
from gnibench.reports.plots import Figure, brief, clip, layout, legend_width, problem_id_of
from gnibench.reports.render import Panel, Plot, Series


def has_sweeps(cells) -> bool:
    """True when some family of the cells has two or more cells (a curve to draw)."""
    return bool((cells.groupby("family")["cell"].count() >= 2).any())


def measures(cells) -> list[tuple[str, str]]:
    """(column, axis label) of the error measures present in a problem's cells."""
    out = []
    for col, label in (("final_global_error", "final global error"),
                       ("max_global_error", "max global error over the samples")):
        if col in cells and cells[col].notna().any():
            out.append((col, label))
    first = [i for i in str(cells["integrals"].iloc[0] or "").split("/") if i]
    if first and f"max_abs_err_{first[0]}" in cells:
        out.append((f"max_abs_err_{first[0]}", f"max |{first[0]}(y) − {first[0]}(y0)|"))
    return out


def no_nfev(cells) -> list[str]:
    """The families whose cells do not count f-evaluations (drawn against wall time only)."""
    fams = cells.groupby("family", sort=False)["nfev"].apply(lambda s: s.isna().all())
    return [str(f) for f, missing in fams.items() if missing]


def wp_figures(problem: str, cells, wall_by_cell: dict[int, float], out_dir: Path, prefix: str,
               slug: str, jobs) -> list[Figure]:
    """The work-precision figures of one problem's cells (with family columns); their drawing is
    appended to ``jobs``."""
    fams = list(dict.fromkeys(cells["family"]))
    style = styles(cells)
    ok = cells[cells["status"] == "ok"].copy()
    ok["wall_ms"] = [wall_by_cell.get(int(c), math.nan) * 1e3 for c in ok["cell"]]
    rows = measures(cells)
    if not rows:
        return []
    panels = []
    for col, label in rows:
        for xcol, xlabel in (("nfev", "f-evaluations (nfev)"),
                             ("wall_ms", "wall time (ms, integration only)")):
            panel = Panel(xscale="log", yscale="log", xlabel=xlabel, ylabel=label, grid=True)
            for fam in fams:
                part = ok[ok["family"] == fam]
                x, y = part[xcol].to_numpy(float), part[col].to_numpy(float)
                good = np.isfinite(x) & (x > 0) & np.isfinite(y) & (y > 0)
                if not good.any():
                    continue
                # in sweep order (coarse to fine): noisy wall times then show as they are
                order = np.argsort(-part["sweep_value"].to_numpy(float)[good], kind="stable")
                st = style[fam]
                panel.series.append(Series(x[good][order], y[good][order], {
                    "color": st["color"], "linestyle": st["linestyle"], "marker": st["marker"],
                    "markersize": 4, "linewidth": 1.2,
                    "label": clip(fam, 40)}))
            panels.append(panel)
    panels[0].title, panels[1].title = "against f-evaluations", "against wall time"
    plot = _plot(panels, len(rows), f"{brief(problem, problem_id_of(problem, cells))}: "
                                    f"work-precision")
    file = f"{prefix}-work-precision.png"
    jobs.append(Job(plot, out_dir / file))
    words = ", ".join(label for _, label in rows)
    cap = (f"Work-precision: {words} against cost (left: f-evaluations, right: wall time), one "
           "curve per method family (its sweep of h or tolerance); squares: fixed step, circles: "
           "adaptive, triangles: external engines. Wall times are single runs on the machine of "
           "the run (not reproducible).")
    missing = no_nfev(cells)
    if missing:
        cap += (" " + ", ".join(missing) + " do not count f-evaluations: they appear on the "
                "wall-time panels only.")
    return [Figure(f"{slug}/{file}", f"{problem}: error against cost", cap)]


#: the panels' left and right edges (inches): two columns of axes of a fixed size
AXES_LEFT, AXES_RIGHT = 1.12, 9.18
LEGEND_PT = 7.5


def _plot(panels: list[Panel], rows: int, title: str) -> Plot:
    """Two columns of panels of a fixed size, the families' legend just right of them, the figure
    as wide as the legend's longest label needs (labels are clipped to 40 characters)."""
    labelled = any(s.style.get("label") for p in panels for s in p.series)
    width = AXES_RIGHT + 0.1 + legend_width(panels, LEGEND_PT) if labelled else AXES_RIGHT + 0.25
    size = (width, 3.9 * rows + 0.6)
    adjust = layout(size, rows, right=AXES_RIGHT / width, left=AXES_LEFT / width)
    adjust["top"] = 1 - 0.75 / size[1]
    return Plot(size, rows, 2, panels, adjust, suptitle=title,
                suptitle_style={"fontsize": 11, "x": (AXES_LEFT + AXES_RIGHT) / 2 / width,
                                "y": 0.995},
                legend={"loc": "upper left", "bbox_to_anchor": ((AXES_RIGHT + 0.1) / width, 0.955),
                        "fontsize": LEGEND_PT, "framealpha": 0.9})
