"""The default figures of an experiment page, described from its tables (drawn by
:mod:`gnibench.reports.render`, matplotlib's Agg canvas).

Per problem: the invariant errors |I(y(t)) − I(y0)| against t (one panel per integral, log y,
log x when the samples span two decades or more), with each curve's growth exponent in t in the
legend (the ``growth`` metric's ``growth_exponent_<I>`` from cells.parquet when present, else the
same fit, :func:`gnibench.suite.metrics.growth.growth_exponent` over the metric's default window
[0.01 T, T]); the global error against t where a reference exists; η(nT) where the ``eta`` metric
wrote it; and the Poincaré section points of section cells in the section's coordinates.

A panel shows at most :data:`MAX_CURVES` cells: beyond that, one cell per method family (the
middle of its sweep by cost), and the caption says so. Exact zeros cannot be drawn on a log axis
and are left out (the caption says how many).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from gnibench.reports.drawing import Job
from gnibench.reports.palette import styles
from gnibench.reports.render import Panel, Plot, Series

MAX_CURVES = 12


@dataclass
class Figure:
    """A written figure: file name (relative to the site), title, caption."""

    file: str
    title: str
    caption: str


BRIEF = 40


def clip(text: str, width: int) -> str:
    """``text`` cut to ``width`` characters, an ellipsis marking the cut."""
    return text if len(text) <= width else text[:width - 1] + "…"


def brief(problem: str, problem_id: str | None) -> str:
    """A problem spec as a title or an index card names it: as it is up to ``BRIEF`` characters,
    else by its id (``problem_id``, the cells' column; the page's section heading shows the whole
    spec); a longer name that is not a spec (``problem_id`` None: a section label such as
    "id (n initial values)") is clipped."""
    if len(problem) <= BRIEF:
        return problem
    return problem_id if problem_id is not None else clip(problem, BRIEF)


def problem_id_of(name: str, cells) -> str | None:
    """The problem id of a page section named ``name`` when it is one of the cells' problem
    specs, else None (a section label)."""
    hit = cells.loc[cells["problem"].astype(str) == name, "problem_id"]
    return str(hit.iloc[0]) if len(hit) else None


def pick_cells(cells) -> tuple[list[int], str]:
    """The cells to draw (ids) and a note when not all of them are drawn."""
    ids = [int(c) for c in cells["cell"]]
    if len(ids) <= MAX_CURVES:
        return ids, ""
    picked = []
    for _, part in cells.groupby("family", sort=False):
        part = part.sort_values("nfev", na_position="last", kind="stable")
        picked.append(int(part["cell"].iloc[(len(part) - 1) // 2]))
    note = (f"{len(ids)} cells: one per method family is drawn (the middle of its sweep by "
            f"nfev); the work-precision diagrams and the table show them all.")
    return sorted(picked[:MAX_CURVES]), note


def _rows(cells, ids) -> dict[int, dict]:
    """The rows of the cells ``ids`` as dicts, by cell id (only those: a sweep has hundreds)."""
    return {int(r["cell"]): r for r in cells[cells["cell"].isin(ids)].to_dict("records")}


def curve_labels(cells, ids) -> dict[int, str]:
    """The name of each drawn cell in a legend or a title: its method spec when it fits in 48
    characters; else its group's label when no other drawn cell has that label (the specs of
    [B] Fig 10's observer and penalty cells differ only after 48 characters); else the spec cut
    to 48 characters."""
    rows = _rows(cells, ids)
    names = {cid: rows[cid].get("label") for cid in ids}
    names = {cid: g.strip() if isinstance(g, str) else "" for cid, g in names.items()}
    out = {}
    for cid in ids:
        spec, group = str(rows[cid]["method"]), names[cid]
        unique = group and list(names.values()).count(group) == 1
        out[cid] = clip(group if len(spec) > 48 and unique else spec, 48)
    return out


def _log_x(ts: list[np.ndarray]) -> bool:
    pos = np.concatenate([t[t > 0] for t in ts]) if ts else np.array([])
    return len(pos) > 1 and pos.max() / pos.min() >= 100


def exponent(row, samples_cell, name: str, memo: dict | None = None) -> float:
    """The growth exponent in t of err_<name> (or ``global``) of one cell (``samples_cell``: its
    samples, or None); ``memo`` keeps fitted values by (cell, name)."""
    from gnibench.suite.metrics.growth import envelope, growth_exponent

    col = f"growth_exponent_{name}"
    if col in row and row[col] is not None and not (isinstance(row[col], float)
                                                   and math.isnan(row[col])):
        return float(row[col])
    err_col = "global_error" if name == "global" else f"err_{name}"
    if samples_cell is None or err_col not in samples_cell or len(samples_cell) < 3:
        return math.nan
    key = (int(row["cell"]), name)
    if memo is not None and key in memo:
        return memo[key]
    t = samples_cell["t"].to_numpy(float)
    p = growth_exponent(t, envelope(samples_cell[err_col].to_numpy(float)), 0.01 * t[-1], t[-1])
    if memo is not None:
        memo[key] = p
    return p


def trajectories(samples) -> dict[int, object]:
    """The samples of each cell, section crossings left out, by cell id (in one pass)."""
    traj = samples[samples["crossing"].isna()] if "crossing" in samples else samples
    return {int(c): part for c, part in traj.groupby("cell", sort=False)}


def shades(cells) -> dict[int, float]:
    """Opacity per cell: the cells of one family from 0.45 (coarsest h or loosest tolerance) to 1."""
    out = {}
    for _, part in cells.groupby("family", sort=False):
        part = part.sort_values("sweep_value", ascending=False, kind="stable")
        n = len(part)
        for k, cid in enumerate(part["cell"]):
            out[int(cid)] = 1.0 if n == 1 else 0.45 + 0.55 * k / (n - 1)
    return out


def _panel(cells, by_cell, ids, column, style, name, with_exponent=True, memo=None,
           shade=None) -> tuple[Panel, int]:
    """|column| against t for the cells (``by_cell``: their samples by id), with a legend on the
    right of the panel (cell, method, growth exponent in t); and how many exact zeros were left
    out."""
    zeros = 0
    shade = shades(cells) if shade is None else shade
    rows = _rows(cells, ids)
    names = curve_labels(cells, ids)
    ts = []
    panel = Panel(yscale="log", xlabel="t", grid=True,
                  legend={"fontsize": 7, "loc": "upper left", "bbox_to_anchor": (1.01, 1.0),
                          "frameon": False})
    for cid in ids:
        row, s = rows[cid], by_cell.get(cid)
        if s is None or column not in s or s[column].isna().all():
            continue
        t, e = s["t"].to_numpy(float), np.abs(s[column].to_numpy(float))
        ok = np.isfinite(e) & (e > 0) & (t > 0)
        zeros += int(np.sum(e == 0))
        if not ok.any():
            continue
        ts.append(t[ok])
        label = f"c{cid} {names[cid]}"
        if with_exponent:
            p = exponent(row, s, name, memo)
            label += f"  t^{p:.2f}" if math.isfinite(p) else ""
        st = style[row["family"]]
        panel.series.append(Series(t[ok], e[ok], {
            "color": st["color"], "linestyle": st["linestyle"], "linewidth": 1.1,
            "alpha": shade.get(cid, 1.0), "label": label}))
    if _log_x(ts):
        panel.xscale = "log"
    return panel, zeros


def layout(size: tuple[float, float], rows: int, right: float = 0.98,
           left: float = 0.09) -> dict:
    """Fixed margins (tight_layout measures every tick label: seconds per page on log axes)."""
    height = size[1]
    return {"left": left, "right": right, "bottom": 0.55 / height + 0.02,
            "top": 1 - 0.45 / height, "hspace": 0.42, "wspace": 0.28}


#: a one-column figure's axes: left edge and width (inches); its legend column follows
AXES_LEFT, AXES_WIDTH = 1.17, 6.11
#: the legend's text size (points, as in :func:`_panel`), and its line handle and pads (inches)
LEGEND_PT, HANDLE_IN = 7.0, 0.75
#: advance widths of DejaVu Sans (matplotlib's default font), hundredths of an em, for the
#: characters 32-126 (tests/reports/test_report_drawing.py checks them against the font); others: 1 em
ADVANCE = (32, 40, 47, 84, 64, 96, 78, 28, 39, 39, 50, 85, 32, 36, 32, 34, 64, 64, 64, 64, 64,
           64, 64, 64, 64, 64, 34, 34, 84, 85, 84, 53, 100, 68, 69, 70, 77, 63, 58, 78, 75, 29,
           29, 65, 56, 86, 75, 79, 60, 79, 70, 64, 62, 73, 68, 99, 69, 61, 68, 39, 34, 39, 84,
           50, 50, 62, 63, 56, 64, 62, 35, 64, 63, 28, 28, 58, 28, 97, 63, 61, 63, 64, 42, 52,
           39, 63, 59, 82, 59, 59, 52, 63, 34, 64, 84)


def text_width(text: str, points: float) -> float:
    """The width (inches) of ``text`` in DejaVu Sans at ``points`` (no kerning: a bound)."""
    ems = sum(ADVANCE[ord(c) - 32] if 32 <= ord(c) < 127 else 100 for c in text) / 100
    return ems * points / 72


def legend_width(panels: list[Panel], points: float = LEGEND_PT) -> float:
    """The width (inches) of the widest legend of the panels: its longest label and the handle."""
    labels = [str(s.style.get("label", "")) for p in panels for s in p.series]
    return max((text_width(label, points) for label in labels), default=0.0) + HANDLE_IN


def _grid(panels: list[Panel], cols: int = 1, right: float | None = None) -> Plot:
    """The panels, one per row by default. ``right`` None: one column, legends to the right of
    axes of a fixed size, the figure as wide as its longest legend label needs (8 to 20 in);
    else the axes end at ``right`` (a fraction of 13 in, or of 6.2 in per column)."""
    rows = math.ceil(len(panels) / cols)
    height = 3.3 * rows + 0.8
    if right is None:
        width = min(20.0, max(8.0, AXES_LEFT + AXES_WIDTH + legend_width(panels)))
        size = (width, height)
        return Plot(size, rows, cols, panels,
                    layout(size, rows, right=(AXES_LEFT + AXES_WIDTH) / width,
                           left=AXES_LEFT / width))
    size = (13.0 if cols == 1 else 6.2 * cols, height)
    return Plot(size, rows, cols, panels, layout(size, rows, right=right))


def time_figures(problem: str, cells, samples, out_dir: Path, prefix: str, slug: str,
                 jobs, by_cell: dict | None = None, memo: dict | None = None) -> list[Figure]:
    """The time-series figures of one problem (see the module docstring); their drawing is
    appended to ``jobs``. ``by_cell``: :func:`trajectories` of the samples (if already split);
    ``memo``: fitted growth exponents, shared with the table of cells."""
    out: list[Figure] = []

    def add(name: str, plot: Plot, title: str, caption: str) -> None:
        jobs.append(Job(plot, out_dir / name))
        out.append(Figure(f"{slug}/{name}", title, caption))

    traj = samples[samples["crossing"].isna()] if "crossing" in samples else samples
    by_cell = trajectories(samples) if by_cell is None else by_cell
    shade = shades(cells)
    ids, note = pick_cells(cells[cells["cell"].isin(traj["cell"].unique())])
    style = styles(cells)
    pid = problem_id_of(problem, cells)
    integrals = [i for i in dict.fromkeys("/".join(cells["integrals"].fillna("")).split("/")) if i]
    integrals = [i for i in integrals if f"err_{i}" in traj and traj[f"err_{i}"].notna().any()]
    if ids and integrals:
        panels, zeros = [], 0
        for name in integrals:
            panel, z = _panel(cells, by_cell, ids, f"err_{name}", style, name, memo=memo,
                              shade=shade)
            panel.ylabel = f"|{name}(y(t)) − {name}(y0)|"
            panel.title = f"{brief(problem, pid)}: error of {name}"
            panels.append(panel)
            zeros += z
        cap = ("Invariant errors against time (log scale; legend: growth exponent in t of the "
               "error envelope, fitted over [0.01 T, T]).")
        cap += f" {zeros} exact zeros are not drawn." if zeros else ""
        add(f"{prefix}-invariants.png", _grid(panels), f"{problem}: invariant errors",
            f"{cap} {note}".strip())
    if ids and "global_error" in traj and traj.loc[traj["cell"].isin(ids), "global_error"].notna().any():
        panel, _ = _panel(cells, by_cell, ids, "global_error", style, "global", memo=memo,
                          shade=shade)
        panel.ylabel = "global error |y − y_ref|"
        refs = sorted({r for r in cells["reference"].fillna("") if r}) if "reference" in cells else []
        panel.title = f"{brief(problem, pid)}: global error" + (f" (against {', '.join(refs)})" if refs else "")
        add(f"{prefix}-global-error.png", _grid([panel]), f"{problem}: global error",
            f"Global error against time (legend: its growth exponent in t). {note}".strip())
    if ids and "eta" in traj and traj["eta"].notna().any():
        panel, _ = _panel(cells, by_cell, ids, "eta", style, "eta", with_exponent=False,
                          shade=shade)
        panel.ylabel = "η(nT) (rad)"
        panel.title = f"{brief(problem, pid)}: η(nT), angle between q(0) and q(nT)"
        add(f"{prefix}-eta.png", _grid([panel]), f"{problem}: η(nT)",
            "η(nT) at whole periods ([B] §5.2, Fig 12), log scale.")
    if "crossing" in samples and samples["crossing"].notna().any():
        plot = section_plot(problem, cells, samples[samples["crossing"].notna()], style)
        if plot is not None:
            coords = section_coords(str(cells["problem_id"].iloc[0]))
            add(f"{prefix}-sections.png", plot, f"{problem}: Poincaré section",
                f"Section crossings in the section's coordinates ({coords[0]}, {coords[1]}), "
                "one panel per section cell.")
    return out


def _section(problem_id: str):
    """The (first) Poincaré section of a problem (by its id), or None."""
    from gnibench.problems import REGISTRY

    record = REGISTRY.get(problem_id)
    return record.sections[0] if record is not None and record.sections else None


def section_charts(problem_id: str) -> int:
    """How many charts a problem's section points are labelled with (0: none or unknown)."""
    section = _section(problem_id)
    return int(section.charts) if section is not None else 0


def section_coords(problem_id: str) -> tuple[str, ...]:
    """The recorded coordinates of a problem's (first) Poincaré section (by its id)."""
    section = _section(problem_id)
    return tuple(section.coords) if section is not None else ()


def section_plot(problem: str, cells, points, style) -> Plot | None:
    """One panel per section cell: its crossings in the section's coordinates."""
    coords = section_coords(str(cells["problem_id"].iloc[0]))
    if len(coords) < 2:
        return None
    ids = [int(c) for c in cells["cell"] if c in set(points["cell"])][:MAX_CURVES]
    panels, names = [], curve_labels(cells, ids)
    for cid in ids:
        row = cells.loc[cells["cell"] == cid].iloc[0]
        s = points[points["cell"] == cid]
        x, y = s[coords[0]].to_numpy(float), s[coords[1]].to_numpy(float)
        panel = Panel(xlabel=coords[0], ylabel=coords[1], title_size=9,
                      title=f"cell {cid}: {names[cid]}  ({len(s)} points)")
        if "chart" in s and s["chart"].notna().any():
            panel.series.append(Series(x, y, {
                "s": 1.5, "c": s["chart"].to_numpy(float), "cmap": "tab10", "vmin": 0.5,
                "vmax": 10.5, "linewidths": 0}, scatter=True))
            # the colour bar shows the problem's charts only, not tab10's unused colours above
            n = section_charts(str(cells["problem_id"].iloc[0])) or int(np.nanmax(s["chart"]))
            panel.colorbar = {"label": "chart", "ticks": list(range(1, n + 1)),
                              "boundaries": [k + 0.5 for k in range(n + 1)],
                              "values": list(range(1, n + 1))}
        else:
            panel.series.append(Series(x, y, {"s": 1.5, "color": style[row["family"]]["color"],
                                              "linewidths": 0}, scatter=True))
        panels.append(panel)
    return _grid(panels, cols=2 if len(ids) > 1 else 1, right=0.95)
