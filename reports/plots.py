"""The time plots of an experiment page, described from its tables (drawn by
:mod:`gnibench.reports.render`, matplotlib's Agg canvas).

Per problem: the invariant errors |I(y(t)) − I(y0)| against t (one panel per integral), with each
curve's growth exponent in t in the legend (the ``growth`` metric's ``growth_exponent_<I>`` from
cells.parquet when present, else the same fit, :func:`gnibench.suite.metrics.growth.growth_fit`
over the metric's default window [0.01 T, T]; none over less than 0.8 decade); the global error
against t where a reference exists; η(nT) where the ``eta`` metric wrote it; and the Poincaré
section points of section cells in the section's coordinates.

Which cells, which figures and which axes follow the experiment's ``[report]`` section (or the
options of the plot helpers, :mod:`gnibench.reports.plot_api`;
:mod:`gnibench.suite.runs.report_schema`): ``cells = "auto"`` draws every cell up to
:data:`MAX_CURVES`, else one per family (the middle of its sweep by cost), and the caption says
so; ``"all"``, a list of cell ids, or one family's sweep (``family``) otherwise. Each curve has
its family's colour and marker (:mod:`gnibench.reports.palette`), lighter for the coarser cells of
a sweep, and is labelled by its family and swept value (the full spec is in the table of cells).
Exact zeros cannot be drawn on a log axis and are left out (the caption says how many).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from gnibench.reports.drawing import Job
from gnibench.reports.layout import Figure, clip, page_plot
from gnibench.reports.render import Panel, Plot, Series

MAX_CURVES = 12
BRIEF = 40
__all__ = ["Figure", "clip", "time_figures"]


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
    """The cells drawn by default (ids) and a note when not all of them are drawn."""
    ids = [int(c) for c in cells["cell"]]
    if len(ids) <= MAX_CURVES:
        return ids, ""
    from gnibench.reports.setups import positions

    picked = []
    for rows in positions(cells["setup"]).values():
        if len(rows) == 1:
            picked.append(ids[rows[0]])
            continue
        part = cells.iloc[rows].sort_values("nfev", na_position="last", kind="stable")
        picked.append(int(part["cell"].iloc[(len(part) - 1) // 2]))
    note = (f"{len(ids)} cells: one per family is drawn (the middle of its sweep by nfev; "
            f"[report] cells and family choose others); the work-precision diagrams and the table "
            f"show them all.")
    return sorted(picked[:MAX_CURVES]), note


def of_family(cells, family: str):
    """The cells of a family, named by its label, its method id or its setup's method spec."""
    hit = (cells["family"].astype(str) == family) | (cells["base_method"].astype(str) == family)
    if "setup_method" in cells:
        hit |= cells["setup_method"].astype(str) == family
    return cells[hit]


def choose_cells(cells, options: dict | None) -> tuple[list[int], str]:
    """The cells the time plots show (``options``: the ``[report]`` keys ``cells`` and
    ``family``) and a note saying which."""
    options = options or {}
    note = ""
    family = options.get("family")
    if family:
        cells = of_family(cells, family)
        note = f"The cells of family {family} ({len(cells)})."
    chosen = options.get("cells", "auto")
    if chosen == "all":
        return [int(c) for c in cells["cell"]], note
    if isinstance(chosen, (list, tuple)):
        ids = [int(c) for c in chosen if int(c) in set(cells["cell"].astype(int))]
        return ids, (note + f" Cells {', '.join(map(str, ids))}, as chosen.").strip()
    ids, more = pick_cells(cells)
    return ids, (note + " " + more).strip()


def _rows(cells, ids) -> dict[int, dict]:
    """The rows of the cells ``ids`` as dicts, by cell id (only those: a sweep has hundreds)."""
    return {int(r["cell"]): r for r in cells[cells["cell"].isin(ids)].to_dict("records")}


def _log_x(ts: list[np.ndarray]) -> bool:
    pos = np.concatenate([t[t > 0] for t in ts]) if ts else np.array([])
    return len(pos) > 1 and pos.max() / pos.min() >= 100


def exponent(row, samples_cell, name: str, memo: dict | None = None) -> tuple[float, str]:
    """The growth exponent in t of err_<name> (or ``global``) of one cell and why it is NaN
    (``samples_cell``: its samples, or None); ``memo`` keeps fitted values by (cell, name)."""
    from gnibench.suite.metrics.growth import envelope, growth_fit

    col = f"growth_exponent_{name}"
    if col in row and row[col] is not None and not (isinstance(row[col], float)
                                                   and math.isnan(row[col])):
        return float(row[col]), ""
    if col in row and isinstance(row.get(f"growth_reason_{name}"), str) and \
            row[f"growth_reason_{name}"]:
        return math.nan, row[f"growth_reason_{name}"]
    err_col = "global_error" if name == "global" else f"err_{name}"
    if samples_cell is None or err_col not in samples_cell or len(samples_cell) < 3:
        return math.nan, "fewer than 3 samples"
    key = (int(row["cell"]), name)
    if memo is not None and key in memo:
        return memo[key]
    t = samples_cell["t"].to_numpy(float)
    fit = growth_fit(t, envelope(samples_cell[err_col].to_numpy(float)), 0.01 * t[-1], t[-1])
    if memo is not None:
        memo[key] = fit
    return fit


def trajectories(samples) -> dict[int, object]:
    """The samples of each cell, section crossings left out, by cell id (in one pass)."""
    traj = samples[samples["crossing"].isna()] if "crossing" in samples else samples
    return {int(c): part for c, part in traj.groupby("cell", sort=False)}


def shades(cells) -> dict[int, float]:
    """Opacity per cell: the cells of one family from 0.45 (coarsest h or loosest tolerance) to 1."""
    from gnibench.reports.setups import positions

    ids = cells["cell"].to_numpy()
    out = {}
    for rows in positions(cells["setup"]).values():
        if len(rows) == 1:
            out[int(ids[rows[0]])] = 1.0
            continue
        part = cells.iloc[rows].sort_values("sweep_value", ascending=False, kind="stable")
        n = len(part)
        for k, cid in enumerate(part["cell"]):
            out[int(cid)] = 1.0 if n == 1 else 0.45 + 0.55 * k / (n - 1)
    return out


def cell_label(row, names: dict[int, str]) -> str:
    """A cell in a legend: its family's name and swept value, and its id."""
    from gnibench.reports.setups import point_label

    return f"{point_label(names[int(row['setup'])], row.get('swept_text', ''))} [{row['cell']}]"


def _panel(cells, by_cell, ids, column, style, name, names, with_exponent=True, memo=None,
           shade=None, yscale="log") -> tuple[Panel, int]:
    """|column| against t for the cells (``by_cell``: their samples by id), labelled by family
    and swept value (``with_exponent``: and the growth exponent in t); and how many exact zeros
    were left out."""
    zeros = 0
    shade = shades(cells) if shade is None else shade
    rows = _rows(cells, ids)
    ts = []
    panel = Panel(yscale=yscale, xlabel="t", grid=True)
    for cid in ids:
        row, s = rows[cid], by_cell.get(cid)
        if s is None or column not in s or s[column].isna().all():
            continue
        t, e = s["t"].to_numpy(float), np.abs(s[column].to_numpy(float))
        ok = np.isfinite(e) & (t > 0) & ((e > 0) if yscale == "log" else True)
        zeros += int(np.sum(e == 0)) if yscale == "log" else 0
        if not ok.any():
            continue
        ts.append(t[ok])
        label = cell_label(row, names)
        if with_exponent:
            p, _ = exponent(row, s, name, memo)
            label += f"  t^{p:.2f}" if math.isfinite(p) else ""
        st = style[int(row["setup"])]
        panel.series.append(Series(t[ok], e[ok], {
            "color": st["color"], "linestyle": st["linestyle"], "linewidth": 1.2,
            "marker": st["marker"], "markevery": max(1, int(ok.sum()) // 8), "markersize": 4.5,
            "alpha": shade.get(cid, 1.0), "label": label}))
    panel.xscale = "log" if _log_x(ts) else "linear"
    return panel, zeros


def time_figures(problem: str, cells, samples, out_dir: Path, prefix: str, slug: str,
                 jobs, by_cell: dict | None = None, memo: dict | None = None, style=None,
                 names: dict | None = None, options: dict | None = None) -> list[Figure]:
    """The time-series figures of one problem (see the module docstring); their drawing is
    appended to ``jobs``. ``cells``: with the columns of :func:`gnibench.reports.setups.add_setups`;
    ``by_cell``: :func:`trajectories` of the samples (if already split); ``memo``: fitted growth
    exponents, shared with the table of cells; ``style``, ``names``: each family's style and
    name by setup id; ``options``: the ``[report]`` section."""
    out: list[Figure] = []
    for name, plot, title, caption in time_plots(problem, cells, samples, by_cell, memo, style,
                                                 names, options):
        jobs.append(Job(plot, out_dir / f"{prefix}-{name}.png"))
        out.append(Figure(f"{slug}/{prefix}-{name}.png", title, caption))
    return out


def time_plots(problem: str, cells, samples, by_cell=None, memo=None, style=None, names=None,
               options: dict | None = None) -> list[tuple[str, Plot, str, str]]:
    """The time plots of one problem as (name, plot, title, caption): see :func:`time_figures`."""
    from gnibench.reports.palette import styles
    from gnibench.reports.setups import family_names

    options = options or {}
    kinds = options.get("figures") or ("invariants", "global-error", "eta", "sections")
    yscale = options.get("error_axis", "log")
    axis = options.get("time_axis", "auto")
    out = []
    traj = samples[samples["crossing"].isna()] if "crossing" in samples else samples
    by_cell = trajectories(samples) if by_cell is None else by_cell
    style = styles(cells) if style is None else style
    names = family_names(cells) if names is None else names
    shade = shades(cells)
    ids, note = choose_cells(cells[cells["cell"].isin(traj["cell"].unique())], options)
    short = brief(problem, problem_id_of(problem, cells))

    def finish(panel: Panel) -> Panel:
        if axis != "auto":
            panel.xscale = axis
        return panel

    integrals = [i for i in dict.fromkeys("/".join(cells["integrals"].fillna("")).split("/")) if i]
    integrals = [i for i in integrals if f"err_{i}" in traj and traj[f"err_{i}"].notna().any()]
    scale_words = f"{yscale} scale, t axis {'chosen: ' + axis if axis != 'auto' else 'log when the samples span two decades'}"
    if ids and integrals and "invariants" in kinds:
        panels, zeros = [], 0
        one = len(integrals) == 1           # one legend for all panels: exponents in one only
        for name in integrals:
            panel, z = _panel(cells, by_cell, ids, f"err_{name}", style, name, names,
                              with_exponent=one, memo=memo, shade=shade, yscale=yscale)
            panel.ylabel = f"|{name}(y(t)) − {name}(y0)|"
            panel.title = f"error of {name}"
            panels.append(finish(panel))
            zeros += z
        cap = (f"Invariant errors against time ({scale_words}; legend: family, swept value, "
               f"[cell]" + (", growth exponent in t of the error envelope fitted over [0.01 T, T]"
                            ", none over less than 0.8 decade" if one else "; the growth "
                            "exponents in t are in the table of cells") + ").")
        cap += f" {zeros} exact zeros are not drawn." if zeros else ""
        out.append(("invariants", page_plot(panels, cols=1 if one else 2, panel_height=3.2,
                                            title=f"{short}: invariant errors"),
                    f"{problem}: invariant errors", f"{cap} {note}".strip()))
    if ids and "global-error" in kinds and "global_error" in traj and \
            traj.loc[traj["cell"].isin(ids), "global_error"].notna().any():
        panel, _ = _panel(cells, by_cell, ids, "global_error", style, "global", names, memo=memo,
                          shade=shade, yscale=yscale)
        panel.ylabel = "global error |y − y_ref|"
        refs = sorted({r for r in cells["reference"].fillna("") if r}) if "reference" in cells else []
        title = f"{short}: global error" + (f" (against {', '.join(refs)})" if refs else "")
        out.append(("global-error", page_plot([finish(panel)], title=title),
                    f"{problem}: global error",
                    f"Global error against time ({scale_words}; legend: its growth exponent in "
                    f"t). {note}".strip()))
    if ids and "eta" in kinds and "eta" in traj and traj["eta"].notna().any():
        panel, _ = _panel(cells, by_cell, ids, "eta", style, "eta", names, with_exponent=False,
                          shade=shade, yscale=yscale)
        panel.ylabel = "η(nT) (rad)"
        out.append(("eta", page_plot([finish(panel)], title=f"{short}: η(nT), angle "
                                                           f"between q(0) and q(nT)"),
                    f"{problem}: η(nT)", f"η(nT) at whole periods ([B] §5.2, Fig 12), {yscale} "
                                         f"scale."))
    if "sections" in kinds and "crossing" in samples and samples["crossing"].notna().any():
        plot = section_plot(problem, cells, samples[samples["crossing"].notna()], style, names)
        if plot is not None:
            coords = section_coords(str(cells["problem_id"].iloc[0]))
            out.append(("sections", plot, f"{problem}: Poincaré section",
                        f"Section crossings in the section's coordinates ({coords[0]}, "
                        f"{coords[1]}), one panel per section cell."))
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


def section_plot(problem: str, cells, points, style, names) -> Plot | None:
    """One panel per section cell: its crossings in the section's coordinates."""
    coords = section_coords(str(cells["problem_id"].iloc[0]))
    if len(coords) < 2:
        return None
    ids = [int(c) for c in cells["cell"] if c in set(points["cell"])][:MAX_CURVES]
    panels = []
    for cid in ids:
        row = cells.loc[cells["cell"] == cid].iloc[0]
        s = points[points["cell"] == cid]
        x, y = s[coords[0]].to_numpy(float), s[coords[1]].to_numpy(float)
        panel = Panel(xlabel=coords[0], ylabel=coords[1], title_size=10,
                      title=clip(f"{cell_label(row, names)}  ({len(s)} points)", 60))
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
            panel.series.append(Series(x, y, {"s": 1.5,
                                              "color": style[int(row["setup"])]["color"],
                                              "linewidths": 0}, scatter=True))
        panels.append(panel)
    return page_plot(panels, cols=2 if len(ids) > 1 else 1, panel_height=4.6,
                     title=f"{brief(problem, problem_id_of(problem, cells))}: Poincaré section")
