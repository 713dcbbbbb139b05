"""Drawing a ``kind = "plot"`` figure: panels of curves (cells' samples) and field layers.

Each panel is drawn from its normalized description (:mod:`gnibench.suite.runs.figure_spec`):
curves in the colour of their method (:mod:`gnibench.reports.figures.style`), one legend entry per
curve however many cells it joins, log axes of |value| for signed columns, point sets as closed
polygons at the requested times (their enclosed areas go to the manifest: [HLW] Fig 1.3's area
preservation as a number), contour and quiver layers from ``fields.parquet``, magnifications as
panels of the same curves in a window marked on the panel they magnify.
"""
from __future__ import annotations

import math
import textwrap

import numpy as np
from gnibench.reports.figures.data import (
    at_times,
    format_label,
    polygon_area,
    thin,
    values,
    where,
    wrap,
)
from gnibench.reports.figures.style import FIELD_COLOR, QUIVER_COLOR, curve_color

LINE = {"line": {"linestyle": "-", "marker": None},
        "dots": {"linestyle": "none", "marker": ".", "markersize": 2.0},
        "points": {"linestyle": "none", "marker": "o", "markersize": 2.2},
        "markers": {"linestyle": "-", "linewidth": 0.6, "marker": "o", "markersize": 2.4},
        "pixels": {"linestyle": "none", "marker": ".", "markersize": 0.6, "markeredgewidth": 0}}
#: styles of unconnected points: never thinned (the density of a section trace is the picture)
POINT_CLOUDS = ("dots", "points", "pixels")
#: "pixels" are 0.6 points wide for the seeds' ~140 000 crossings ([B] Fig 26); a cloud of
#: fewer points (the quick scale's 2-4 thousand) keeps about the same ink: the marker grows as
#: sqrt(PIXEL_CROWD / n), up to the 2 points of "dots"
PIXEL_CROWD, PIXEL_LARGEST = 140_000, 2.0


def pixel_size(points: int) -> float:
    """The marker size (points) of a "pixels" cloud of ``points`` points."""
    smallest = LINE["pixels"]["markersize"]
    return min(PIXEL_LARGEST, max(smallest, smallest * math.sqrt(PIXEL_CROWD / max(points, 1))))


def figure_size(figure: dict) -> tuple[float, float]:
    if figure.get("size"):
        return tuple(figure["size"])
    rows, cols = figure["layout"]
    return (min(4.4 * cols, 15.0), 3.9 * rows + 0.9)


def title_text(figure: dict, width_in: float) -> str:
    """``Fig 1.4. <caption>`` wrapped to the figure's width (and the scale when not paper)."""
    text = f"{figure['number']}. {figure['caption']}"
    if figure.get("scale") and figure["scale"] != "paper":
        text += f"  [{figure['scale']} scale]"
    # DejaVu Sans at 10.5 pt: about 11.4 characters per inch on average; keep a margin
    return "\n".join(textwrap.wrap(text, width=max(40, int(width_in * 10.5))))


def draw_plot(results, figure: dict):
    """The matplotlib figure and the manifest entries of its panels."""
    import matplotlib.pyplot as plt

    size = figure_size(figure)
    fig = plt.figure(figsize=size, layout="constrained")
    rows, cols = figure["layout"]
    axes = [fig.add_subplot(rows, cols, k + 1) for k in range(len(figure["panels"]))]
    fig.suptitle(title_text(figure, size[0]), fontsize=10.5)
    manifest = []
    outside = {}
    for k, (ax, panel) in enumerate(zip(axes, figure["panels"])):
        source = figure["panels"][panel["zoom"]["of"]] if panel.get("zoom") else panel
        entry = _draw_panel(ax, results, source, k if not panel.get("zoom") else
                            panel["zoom"]["of"], panel)
        manifest.append(entry)
        if panel["legend"] == "outside":
            handles, labels = ax.get_legend_handles_labels()
            outside.update({lab: h for h, lab in zip(handles, labels)})
        if panel.get("zoom") and panel["zoom"]["mark"]:
            _mark(axes[panel["zoom"]["of"]], panel, k)
    if outside:
        legible_markers(fig.legend(list(outside.values()), list(outside),
                                   loc="outside lower center", ncols=min(len(outside), 4)))
    return fig, manifest


#: the least marker size (points) of a legend's sample: the "pixels" and "dots" of a point set
#: (0.6 and 2 points, right for thousands of crossings) were invisible in their legend entry
LEGEND_MARKER = 4.0


def legible_markers(legend) -> None:
    """Enlarge the markers of a legend's samples to :data:`LEGEND_MARKER` points at least (the
    curves themselves keep their size)."""
    for handle in legend.legend_handles:
        if hasattr(handle, "get_markersize") and handle.get_marker() not in (None, "None", ""):
            handle.set_markersize(max(handle.get_markersize(), LEGEND_MARKER))


def _draw_panel(ax, results, source: dict, source_index: int, panel: dict) -> dict:
    logx, logy = panel["xscale"] == "log", panel["yscale"] == "log"
    entry = {"title": panel["title"], "xlabel": panel["xlabel"], "ylabel": panel["ylabel"],
             "xscale": panel["xscale"], "yscale": panel["yscale"], "note": panel["note"],
             "zoom_of": panel["zoom"]["of"] if panel.get("zoom") else None,
             "curves": [], "fields": []}
    for k, field in enumerate(source.get("fields", [])):
        entry["fields"].append(_draw_field(ax, results.field(source_index, k), field))
    for curve in source.get("curves", []):
        entry["curves"].append(_draw_curve(ax, results, curve, logx, logy))
    # a log y axis has no offset text (the one thing, with tick labels above the axes, that
    # matplotlib measures every tick label of the axes to place a title clear of): the title
    # goes at the top of the axes unmeasured, where matplotlib would put it
    ax.set_title(panel["title"], y=1.0 if logy else None)
    ax.set_xlabel(panel["xlabel"])
    ax.set_ylabel(panel["ylabel"])
    ax.set_xscale(panel["xscale"])
    ax.set_yscale(panel["yscale"])
    if panel["xlim"]:
        ax.set_xlim(*panel["xlim"])
    if panel["ylim"]:
        ax.set_ylim(*panel["ylim"])
    if panel["aspect"] == "equal":
        ax.set_aspect("equal", adjustable="datalim" if not (panel["xlim"] and panel["ylim"])
                      else "box")
    if panel["legend"] not in ("none", "outside") and ax.get_legend_handles_labels()[0]:
        legible_markers(ax.legend(loc=panel["legend"]))
    # what the axes really carry (read back from matplotlib, for the manifest and the tests)
    entry.update(xlabel=ax.get_xlabel(), ylabel=ax.get_ylabel(), xscale=ax.get_xscale(),
                 yscale=ax.get_yscale(), title=ax.get_title(),
                 drawn=int(sum(len(line.get_xdata()) for line in ax.get_lines())
                           + sum(len(c.get_offsets()) for c in ax.collections
                                 if hasattr(c, "get_offsets"))))
    return entry


def _draw_curve(ax, results, curve: dict, logx: bool, logy: bool) -> dict:
    rows = [results.cell_row(c) for c in curve["cells"]]
    color = curve_color(curve, rows[0])
    label = format_label(curve["label"], rows)
    out = {"label": label, "cells": curve["cells"], "x": curve["x"], "y": curve["y"],
           "style": curve["style"], "color": color, "points": 0, "samples": 0,
           "statuses": sorted({str(r.get("status")) for r in rows}), "missing": []}
    if curve.get("where"):
        out["where"] = curve["where"]
    if curve.get("at") is not None:
        return _draw_sets(ax, results, curve, out, logx, logy)
    style = LINE[curve["style"] if curve["style"] in LINE else "line"]
    first = True
    for cell in curve["cells"]:
        df = results.cell_samples(cell)
        if not len(df):
            out["missing"].append(cell)
            continue
        df = where(df, curve.get("where"))
        x, y = values(df, curve["x"], logx), values(df, curve["y"], logy)
        out["samples"] += len(df)
        ok = np.isfinite(x) & np.isfinite(y)
        out["points"] += int(ok.sum())
        if curve["style"] not in POINT_CLOUDS:      # a cloud of points is drawn whole
            x, y = thin(x, y, logx=logx)
        if curve.get("xwrap") or curve.get("ywrap"):
            x, y = wrap(x, y, curve.get("xwrap"), curve.get("ywrap"))
        style = {"linewidth": curve.get("linewidth", 1.2), **style}
        if curve["style"] == "pixels":
            style["markersize"] = out["markersize"] = pixel_size(int(ok.sum()))
        if curve.get("pieces"):
            x, y, origins = _pieces(x, y)
            out["pieces"] = len(origins)
            for n, i in enumerate(origins[:MAX_PIECE_NUMBERS], start=1):
                ax.annotate(str(n), (x[i], y[i]), xytext=(3, 3), textcoords="offset points",
                            fontsize=8, color="black")
        ax.plot(x, y, color=color, label=label if first and label else None, **style)
        first = False
        if curve.get("start") and ok.any():
            i = int(np.argmax(ok))
            ax.annotate(curve["start"], (x[i], y[i]), xytext=(4, 4), textcoords="offset points",
                        fontsize=8.5, fontweight="bold", color="black",
                        bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "alpha": 0.75,
                              "edgecolor": "none"})
    return out


MAX_PIECE_NUMBERS = 40


def _pieces(x: np.ndarray, y: np.ndarray, jump: float = 10.0):
    """The line broken where it jumps (a step of more than ``jump`` times the median step, e.g.
    the map back into the fundamental domain, [B] (8.3)-(8.4)): x, y with a NaN at each break,
    and the index of each piece's first point."""
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if len(x) < 3:
        return x, y, [0] if len(x) else []
    d = np.hypot(np.diff(x), np.diff(y))
    breaks = np.flatnonzero(d > jump * np.median(d)) + 1
    xs, ys = np.insert(x, breaks, np.nan), np.insert(y, breaks, np.nan)
    origins = [0] + [int(b) + k + 1 for k, b in enumerate(breaks)]
    return xs, ys, origins


def _draw_sets(ax, results, curve: dict, out: dict, logx: bool, logy: bool) -> dict:
    """The images of a point set: one shape per time of ``at`` (a closed polygon, or points)."""
    color = curve_color(curve, results.cell_row(curve["cells"][0]))
    frames = [where(results.cell_samples(c), curve.get("where")) for c in curve["cells"]]
    out["shapes"] = []
    for n, t in enumerate(curve["at"]):
        xs, ys = [], []
        for cell, df in zip(curve["cells"], frames):
            k = at_times(df, [t])[0]
            if k is None:
                out["missing"].append(cell)
                xs.append(math.nan)
                ys.append(math.nan)
                continue
            row = df.iloc[[k]]
            xs.append(float(values(row, curve["x"], logx)[0]))
            ys.append(float(values(row, curve["y"], logy)[0]))
        x, y = np.array(xs), np.array(ys)
        ok = np.isfinite(x) & np.isfinite(y)
        out["points"] += int(ok.sum())
        out["samples"] += len(x)
        label = out["label"] if n == 0 and out["label"] else None
        if curve["style"] == "polygon":
            ax.fill(x[ok], y[ok], facecolor=color, alpha=0.25, edgecolor="none")
            ax.plot(np.append(x[ok], x[ok][:1]), np.append(y[ok], y[ok][:1]), color=color,
                    linewidth=0.9, label=label)
        else:
            ax.plot(x[ok], y[ok], color=color, label=label, **LINE[curve["style"]])
        if n == 0 and curve.get("start") and ok.any():
            ax.annotate(curve["start"], (float(np.mean(x[ok])), float(np.mean(y[ok]))),
                        ha="center", va="center", fontsize=9, fontweight="bold", color="black")
        out["shapes"].append({"t": t, "vertices": int(ok.sum()),
                              "area": polygon_area(x, y) if curve["style"] == "polygon" else None})
    out["missing"] = sorted(set(out["missing"]))
    return out


def _draw_field(ax, df, field: dict) -> dict:
    n = field["n"]
    X = df["x"].to_numpy().reshape(n, n)
    Y = df["y"].to_numpy().reshape(n, n)
    color = field.get("color") or (FIELD_COLOR if field["kind"] == "contour" else QUIVER_COLOR)
    out = {"label": field["label"], "kind": field["kind"], "function": field["function"],
           "problem": field["problem"], "grid": n}
    if field["kind"] == "contour":
        Z = df["value"].to_numpy().reshape(n, n)
        cs = ax.contour(X, Y, Z, levels=field["levels"], colors=color, linewidths=0.8,
                        linestyles="solid")
        out["levels"] = [float(v) for v in cs.levels]
        out["points"] = int(sum(len(p.vertices) for p in _paths(cs)))
    else:
        U = df["u"].to_numpy().reshape(n, n)
        V = df["v"].to_numpy().reshape(n, n)
        speed = np.hypot(U, V)
        with np.errstate(all="ignore"):      # arrows of one length: the direction of the field
            ax.quiver(X, Y, U / speed, V / speed, color=color, angles="xy", pivot="mid",
                      width=0.005, headwidth=3.5, headlength=4, scale=n * 1.3)
        out["points"] = int(np.isfinite(speed).sum())
    if field["label"]:
        ax.plot([], [], color=color, linewidth=0.8, label=field["label"])
    return out


def _paths(cs):
    try:
        return cs.get_paths()
    except AttributeError:                   # matplotlib < 3.8
        return [p for c in cs.collections for p in c.get_paths()]


def _mark(ax, panel: dict, index: int) -> None:
    from matplotlib.patches import Rectangle

    (x0, x1), (y0, y1) = panel["xlim"], panel["ylim"]
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor="black",
                           linewidth=0.8, linestyle="--"))
    ax.annotate(panel["title"] or f"panel {index}", (x1, y1), xytext=(2, 2),
                textcoords="offset points", fontsize=7.5)
