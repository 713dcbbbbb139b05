"""Figures and tables of the seeds, drawn from the tables of a results directory.

:func:`draw_figure` reads ``cells.parquet`` (whose metadata holds the normalized figure of the
experiment's ``[figure]`` section, :mod:`gnibench.suite.runs.figure_spec`), ``samples.parquet`` and
``fields.parquet``, and writes into ``<results>/figure/``:

* ``<id>.png`` and ``<id>.svg``: matplotlib (Agg), titled with the seed's number and caption;
* ``figure.json``, the manifest the HTML reports read: id, number, caption, reference, scale,
  files, notes, and per panel the axis labels, scales, and each curve's label, cells, colour,
  number of points drawn (and, for point sets, the area of each polygon);
* for tables also ``table.md`` (the seed's entries beside the measured ones).

It never integrates and never imports the runner.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from gnibench.reports.figures.data import FigureDataError, Results

__all__ = ["MANIFEST", "FigureDataError", "draw_figure"]

MANIFEST = "figure.json"


def _clean(x):
    """JSON without NaN (null instead)."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if hasattr(x, "item"):
        return _clean(x.item())
    return x


def draw_figure(results_dir: str | Path, out_dir: str | Path | None = None,
                figure: dict | None = None) -> dict:
    """Draw the figure of a results directory; returns the manifest (also written).

    Parameters
    ----------
    results_dir:
        A directory written by the runner for an experiment with a ``[figure]`` section.
    out_dir:
        Where the images and the manifest go (default ``<results_dir>/figure``).
    figure:
        A normalized figure to draw instead of the one stored with the tables (a redraw after
        the figure section was edited; its cells must be those of the tables).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from gnibench.reports.figures.style import RC

    results = Results.read(results_dir, figure)
    figure = results.figure
    out = Path(out_dir) if out_dir is not None else Path(results_dir) / "figure"
    out.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context(RC):
        if figure["kind"] == "table":
            from gnibench.reports.figures.table import draw_table, markdown

            fig, panels = draw_table(results, figure)
            (out / "table.md").write_text(markdown(panels[0]["table"]), encoding="utf-8")
        else:
            from gnibench.reports.figures.plot import draw_plot

            fig, panels = draw_plot(results, figure)
        _lay_out_once(fig)
        files = []
        for ext in ("png", "svg"):
            path = out / f"{figure['id']}.{ext}"
            fig.savefig(path, metadata=_metadata(figure, ext))
            files.append(path.name)
        plt.close(fig)
    if figure["kind"] == "table":
        files.append("table.md")
    meta = results.meta
    manifest = {"id": figure["id"], "number": figure["number"], "caption": figure["caption"],
                "reference": figure["reference"], "scale": figure.get("scale", "paper"),
                "kind": figure["kind"], "title": meta.get("title", ""),
                "description": meta.get("description", ""), "note": figure.get("note", ""),
                "files": files, "complete": meta.get("complete", True),
                "cells": {"total": meta.get("cells_total"), "done": meta.get("cells_done"),
                          "statuses": results.cells["status"].astype(str).value_counts()
                          .to_dict()},
                "panels": panels}
    manifest = _clean(manifest)
    (out / MANIFEST).write_text(json.dumps(manifest, indent=1, ensure_ascii=False) + "\n",
                                encoding="utf-8")
    return manifest


def _lay_out_once(fig) -> None:
    """Run the figure's constrained layout once, then drop the layout engine.

    With a layout engine set, each ``savefig`` first draws the figure without rendering (to run
    the layout) and then draws it again; the SVG, drawn after the PNG, measured every tick label
    once more for the same positions. Here the layout runs in one draw without rendering at the
    PNG's resolution (``savefig.dpi``, as ``savefig`` would), and the PNG and the SVG are each
    drawn once, with the same images as before (the 41 figures of the seeds byte for byte;
    drawing them 25.7 s -> 23.1 s of CPU, 2026-11-28). The layout engine is run by itself, without
    the draw of ``draw_without_rendering`` around it (the same bytes; with the titles of log axes
    placed unmeasured, reports/figures/plot.py: 23.4-23.7 s -> 19.3 s of CPU for the 41)."""
    import matplotlib

    if fig.get_layout_engine() is None:
        return
    dpi, saved = fig.dpi, matplotlib.rcParams["savefig.dpi"]
    fig.dpi = dpi if saved == "figure" else saved
    try:
        fig.get_layout_engine().execute(fig)      # what draw_without_rendering runs, less a draw
    finally:
        fig.dpi = dpi
    fig.set_layout_engine(None)


def _metadata(figure: dict, ext: str) -> dict:
    """Image metadata: the figure's id and caption (no date, so the files are reproducible)."""
    title = f"{figure['number']}. {figure['caption']}"
    if ext == "png":
        return {"Title": title, "Software": "gnibench"}
    return {"Title": title, "Date": None, "Creator": "gnibench"}
