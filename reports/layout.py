"""The layout of the report's figures: as wide as the page, text readable at the page's width.

A page's main column is 1300 px wide, less its padding; a figure is :data:`WIDTH` inches at
100 dpi (1240 px), so it is shown at its own size and its text at its own size: tick labels
9 pt, axis labels 10 pt, legends 9 pt (:data:`gnibench.reports.render.RC`), about 12 to 14 px.
Panels sit in a grid of fixed margins (``tight_layout`` measures every tick label: seconds per
page on log axes); the legend of a figure (one entry per distinct label of its panels) sits below
the panels in as many columns as its longest label allows, never cut by the figure's edge.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from gnibench.reports.render import Panel, Plot

#: the figure's width (inches) and its margins
WIDTH = 12.4
LEFT, RIGHT, GAP = 1.0, 0.3, 0.95
TOP, BOTTOM = 0.55, 0.6
#: the legend's text size (points), the width of a handle with its pads (inches), a row's height
LEGEND_PT, HANDLE_IN, LEGEND_ROW = 9.0, 0.8, 0.24
#: the longest legend label kept whole (characters); longer ones end in an ellipsis
MAX_LABEL = 64


@dataclass
class Figure:
    """A written figure: file name (relative to the site), title, caption."""

    file: str
    title: str
    caption: str


def clip(text: str, width: int) -> str:
    """``text`` cut to ``width`` characters, an ellipsis marking the cut."""
    return text if len(text) <= width else text[:width - 1] + "…"


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


def margins(size: tuple[float, float], rows: int, right: float = 0.98,
            left: float = 0.09) -> dict:
    """Fixed margins of a figure of ``size`` inches with ``rows`` rows of panels."""
    height = size[1]
    return {"left": left, "right": right, "bottom": 0.55 / height + 0.02,
            "top": 1 - 0.45 / height, "hspace": 0.42, "wspace": 0.28}


def labels(panels: list[Panel]) -> list[str]:
    """The distinct labels of the panels' series, in order (the figure legend's entries)."""
    return list(dict.fromkeys(str(s.style["label"]) for p in panels for s in p.series
                              if s.style.get("label")))


def legend_columns(entries: list[str], width: float = WIDTH - 0.4,
                   points: float = LEGEND_PT) -> int:
    """How many legend columns of the longest entry fit in ``width`` inches."""
    widest = max((text_width(e, points) for e in entries), default=0.0) + HANDLE_IN
    return max(1, min(len(entries), int(width // widest))) if entries else 1


def page_plot(panels: list[Panel], cols: int = 1, panel_height: float = 3.4,
              title: str = "") -> Plot:
    """The panels in a grid of ``cols`` columns as wide as the page (:data:`WIDTH`), each
    ``panel_height`` inches high, a title over all, the legend of their labels below them."""
    for p in panels:
        for s in p.series:
            if s.style.get("label"):
                s.style["label"] = clip(str(s.style["label"]), MAX_LABEL)
        p.legend = None
    rows = max(1, math.ceil(len(panels) / cols))
    entries = labels(panels)
    ncol = legend_columns(entries)
    legend_h = (math.ceil(len(entries) / ncol) * LEGEND_ROW + 0.25) if entries else 0.0
    top = TOP + (0.3 if title else 0.0)
    height = top + rows * panel_height + (rows - 1) * 0.75 + BOTTOM + legend_h
    axes_w = (WIDTH - LEFT - RIGHT - (cols - 1) * GAP) / cols
    adjust = {"left": LEFT / WIDTH, "right": 1 - RIGHT / WIDTH,
              "top": 1 - top / height, "bottom": (BOTTOM + legend_h) / height,
              "wspace": GAP / axes_w, "hspace": 0.75 / panel_height}
    legend = None
    if entries:
        legend = {"loc": "upper center", "bbox_to_anchor": (0.5, (legend_h + 0.05) / height),
                  "ncol": ncol, "fontsize": LEGEND_PT, "frameon": False,
                  "handlelength": 2.6, "columnspacing": 1.2}
    return Plot((WIDTH, round(height, 3)), rows, cols, panels, adjust, suptitle=title,
                suptitle_style={"fontsize": 12, "y": 1 - 0.12 / height}, legend=legend)
