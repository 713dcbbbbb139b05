"""The default figures of an experiment page, drawn from its tables (matplotlib, Agg).

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
from gnibench.reports.palette import styles

MAX_CURVES = 12
DPI = 100


@dataclass
class Figure:
    """A written figure: file name (relative to the site), title, caption."""

    file: str
    title: str
    caption: str


def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


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


def _label(row) -> str:
    label = str(row["method"])
    return label if len(label) <= 48 else label[:45] + "…"


def _save(fig, out_dir: Path, name: str) -> str:
    from matplotlib.ticker import LogLocator, NullLocator

    for ax in fig.axes:          # minor ticks of log axes: thousands of tick objects per page
        for axis, lim in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
            if axis.get_scale() == "log":
                axis.set_minor_locator(NullLocator())
                if lim[0] > 0 and lim[1] / lim[0] < 30:       # under 1.5 decades: label 1, 2, 5
                    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    out_dir.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_dir / name, dpi=DPI)
    pyplot().close(fig)
    return name


def _log_x(ts: list[np.ndarray]) -> bool:
    pos = np.concatenate([t[t > 0] for t in ts]) if ts else np.array([])
    return len(pos) > 1 and pos.max() / pos.min() >= 100


def exponent(row, samples_cell, name: str) -> float:
    """The growth exponent in t of err_<name> (or ``global``) of one cell."""
    from gnibench.suite.metrics.growth import envelope, growth_exponent

    col = f"growth_exponent_{name}"
    if col in row and row[col] is not None and not (isinstance(row[col], float)
                                                   and math.isnan(row[col])):
        return float(row[col])
    err_col = "global_error" if name == "global" else f"err_{name}"
    if err_col not in samples_cell or len(samples_cell) < 3:
        return math.nan
    t = samples_cell["t"].to_numpy(float)
    return growth_exponent(t, envelope(samples_cell[err_col].to_numpy(float)), 0.01 * t[-1], t[-1])


def shades(cells) -> dict[int, float]:
    """Opacity per cell: the cells of one family from 0.45 (coarsest h or loosest tolerance) to 1."""
    out = {}
    for _, part in cells.groupby("family", sort=False):
        part = part.sort_values("sweep_value", ascending=False, kind="stable")
        n = len(part)
        for k, cid in enumerate(part["cell"]):
            out[int(cid)] = 1.0 if n == 1 else 0.45 + 0.55 * k / (n - 1)
    return out


def _panel(ax, cells, samples, ids, column, style, name, with_exponent=True) -> int:
    """Draw |column| against t for the cells, with a legend on the right of the panel (cell,
    method, growth exponent in t); returns how many exact zeros were left out."""
    zeros = 0
    shade = shades(cells)
    ts = []
    for cid in ids:
        row = cells.loc[cells["cell"] == cid].iloc[0]
        s = samples[samples["cell"] == cid]
        if column not in s or s[column].isna().all():
            continue
        t, e = s["t"].to_numpy(float), np.abs(s[column].to_numpy(float))
        ok = np.isfinite(e) & (e > 0) & (t > 0)
        zeros += int(np.sum(e == 0))
        if not ok.any():
            continue
        ts.append(t[ok])
        label = f"c{cid} {_label(row)}"
        if with_exponent:
            p = exponent(row, s, name)
            label += f"  t^{p:.2f}" if math.isfinite(p) else ""
        st = style[row["family"]]
        ax.plot(t[ok], e[ok], color=st["color"], linestyle=st["linestyle"], linewidth=1.1,
                alpha=shade.get(cid, 1.0), label=label)
    ax.set_yscale("log")
    if _log_x(ts):
        ax.set_xscale("log")
    ax.grid(True, which="major", alpha=0.3)
    ax.set_xlabel("t")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return zeros


def layout(fig, rows: int, right: float = 0.98) -> None:
    """Fixed margins (tight_layout measures every tick label: seconds per page on log axes)."""
    height = fig.get_size_inches()[1]
    fig.subplots_adjust(left=0.09, right=right, bottom=0.55 / height + 0.02,
                        top=1 - 0.45 / height, hspace=0.42, wspace=0.28)


def _grid(n: int, cols: int = 1, right: float = 0.56):
    """n panels, one per row by default, legends to their right."""
    plt = pyplot()
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(13.0 if cols == 1 else 6.2 * cols,
                                                  3.3 * rows + 0.8), squeeze=False)
    layout(fig, rows, right=right)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    return fig, axes.ravel()[:n]


def time_figures(problem: str, cells, samples, out_dir: Path, prefix: str, slug: str) -> list[Figure]:
    """The time-series figures of one problem (see the module docstring)."""
    plt = pyplot()
    out: list[Figure] = []
    traj = samples[samples["crossing"].isna()] if "crossing" in samples else samples
    ids, note = pick_cells(cells[cells["cell"].isin(traj["cell"].unique())])
    style = styles(list(dict.fromkeys(cells["family"])),
                   dict(zip(cells["family"], cells["adaptive"])),
                   dict(zip(cells["family"], cells["method_kind"])))
    integrals = [i for i in dict.fromkeys("/".join(cells["integrals"].fillna("")).split("/")) if i]
    integrals = [i for i in integrals if f"err_{i}" in traj and traj[f"err_{i}"].notna().any()]
    if ids and integrals:
        fig, axes = _grid(len(integrals))
        zeros = 0
        for ax, name in zip(axes, integrals):
            zeros += _panel(ax, cells, traj, ids, f"err_{name}", style, name)
            ax.set_ylabel(f"|{name}(y(t)) − {name}(y0)|")
            ax.set_title(f"{problem}: error of {name}", fontsize=10)
        file = _save(fig, out_dir, f"{prefix}-invariants.png")
        cap = ("Invariant errors against time (log scale; legend: growth exponent in t of the "
               "error envelope, fitted over [0.01 T, T]).")
        cap += f" {zeros} exact zeros are not drawn." if zeros else ""
        out.append(Figure(f"{slug}/{file}", f"{problem}: invariant errors", f"{cap} {note}".strip()))
    if ids and "global_error" in traj and traj.loc[traj["cell"].isin(ids), "global_error"].notna().any():
        fig, (ax,) = _grid(1)
        _panel(ax, cells, traj, ids, "global_error", style, "global")
        ax.set_ylabel("global error |y − y_ref|")
        refs = sorted({r for r in cells["reference"].fillna("") if r}) if "reference" in cells else []
        ax.set_title(f"{problem}: global error" + (f" (against {', '.join(refs)})" if refs else ""),
                     fontsize=10)
        file = _save(fig, out_dir, f"{prefix}-global-error.png")
        out.append(Figure(f"{slug}/{file}", f"{problem}: global error",
                          f"Global error against time (legend: its growth exponent in t). {note}".strip()))
    if ids and "eta" in traj and traj["eta"].notna().any():
        fig, (ax,) = _grid(1)
        _panel(ax, cells, traj[traj["eta"].notna()], ids, "eta", style, "eta", with_exponent=False)
        ax.set_ylabel("η(nT) (rad)")
        ax.set_title(f"{problem}: η(nT), angle between q(0) and q(nT)", fontsize=10)
        file = _save(fig, out_dir, f"{prefix}-eta.png")
        out.append(Figure(f"{slug}/{file}", f"{problem}: η(nT)",
                          "η(nT) at whole periods ([B] §5.2, Fig 12), log scale."))
    if "crossing" in samples and samples["crossing"].notna().any():
        out += section_figures(problem, cells, samples[samples["crossing"].notna()], out_dir,
                               prefix, slug, style)
    plt.close("all")
    return out


def section_coords(problem: str) -> tuple[str, ...]:
    """The recorded coordinates of a problem's (first) Poincaré section (``problem``: a spec)."""
    from gnibench.problems import REGISTRY
    from gnibench.suite.cell.spec import item_id

    record = REGISTRY.get(item_id(problem, "problem"))
    if record is None or not record.sections:
        return ()
    return tuple(record.sections[0].coords)


def section_figures(problem: str, cells, points, out_dir: Path, prefix: str, slug: str,
                    style) -> list[Figure]:
    """One panel per section cell: its crossings in the section's coordinates."""
    coords = section_coords(str(cells["problem"].iloc[0]))
    if len(coords) < 2:
        return []
    ids = [int(c) for c in cells["cell"] if c in set(points["cell"])][:MAX_CURVES]
    fig, axes = _grid(len(ids), cols=2 if len(ids) > 1 else 1, right=0.95)
    for ax, cid in zip(axes, ids):
        row = cells.loc[cells["cell"] == cid].iloc[0]
        s = points[points["cell"] == cid]
        x, y = s[coords[0]].to_numpy(float), s[coords[1]].to_numpy(float)
        if "chart" in s and s["chart"].notna().any():
            sc = ax.scatter(x, y, s=1.5, c=s["chart"].to_numpy(float), cmap="tab10", vmin=0.5,
                            vmax=10.5, linewidths=0)
            fig.colorbar(sc, ax=ax, label="chart", ticks=range(1, 9))
        else:
            ax.scatter(x, y, s=1.5, color=style[row["family"]]["color"], linewidths=0)
        ax.set_xlabel(coords[0])
        ax.set_ylabel(coords[1])
        ax.set_title(f"cell {cid}: {_label(row)}  ({len(s)} points)", fontsize=9)
    file = _save(fig, out_dir, f"{prefix}-sections.png")
    return [Figure(f"{slug}/{file}", f"{problem}: Poincaré section",
                   f"Section crossings in the section's coordinates ({coords[0]}, {coords[1]}), "
                   "one panel per section cell.")]
