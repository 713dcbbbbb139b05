"""Drawing the report's figures: a figure is first described as plain data (:class:`Plot`: panels of
series, labels, scales, layout; numbers as arrays), then rendered by :func:`render` with
matplotlib's Agg canvas (no pyplot, no GUI). The description is everything the picture depends
on, so its hash (:func:`plot_key`, with this module's source and the matplotlib version) keys the
cache of drawn images (:mod:`gnibench.reports.drawing`).

Lighter than the defaults where it costs nothing visible: tick labels of log axes are plain
Unicode text (``10⁻⁵``, ``2×10⁻³``) instead of mathtext (whose parser costs tens of ms per
distinct label and figure), unhinted glyphs, no minor ticks on log axes (thousands of tick objects
per page), fixed margins instead of ``tight_layout`` (which measures every label), titles at the
top of their axes without measuring the tick labels (there are none above the axes), an RGB PNG
at zlib level 3.
"""
from __future__ import annotations

import dataclasses
import hashlib
import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

DPI = 100
#: glyphs unhinted: a fifth of the drawing is FreeType's TrueType hinting interpreter, and at
#: 100 dpi unhinted text is as legible (slightly softer)
RC = {"text.hinting": "no_hinting",
      # readable at the page's width (a figure is shown at its own size: reports/layout.py)
      "font.size": 10, "axes.labelsize": 10.5, "xtick.labelsize": 9.5, "ytick.labelsize": 9.5,
      "legend.fontsize": 9, "axes.titlesize": 11}


@dataclass
class Series:
    """One curve (``ax.plot``) or point set (``ax.scatter``) with its matplotlib keywords; with
    ``band`` (the lower y, and ``y`` the upper), a shaded band between them
    (``ax.fill_between``: quantiles over an ensemble's orbits)."""

    x: np.ndarray
    y: np.ndarray
    style: dict
    scatter: bool = False
    band: np.ndarray | None = None


@dataclass
class Panel:
    """One axes: its series in drawing order, scales, labels; ``legend``: ``ax.legend`` keywords
    (drawn when a series has a label); ``colorbar``: ``fig.colorbar`` keywords for the last
    scatter."""

    series: list[Series] = field(default_factory=list)
    xscale: str = "linear"
    yscale: str = "linear"
    xlabel: str = ""
    ylabel: str = ""
    title: str = ""
    title_size: float = 10.0
    grid: bool = False
    legend: dict | None = None
    colorbar: dict | None = None
    xticks: list | None = None
    xticklabels: list | None = None          # at ``xticks``, font size 7
    ylim: tuple | None = None


@dataclass
class Plot:
    """One image: a grid of panels (in reading order; grid places beyond them are hidden), the
    figure size (inches), margins (``subplots_adjust``), a title over all, and a figure legend
    (keywords; one entry per distinct label of the panels, in order)."""

    size: tuple[float, float]
    rows: int
    cols: int
    panels: list[Panel]
    adjust: dict
    suptitle: str = ""
    suptitle_style: dict = field(default_factory=dict)
    legend: dict | None = None

    def cost(self) -> int:
        """A rough measure of the drawing work (for the order of parallel drawing)."""
        return sum(5000 + sum(len(s.x) for s in p.series) for p in self.panels)


# -- the cache key ------------------------------------------------------------------------------

def _feed(h, obj) -> None:
    if isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"a{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes() if a.dtype != object else repr(a.tolist()).encode())
    elif dataclasses.is_dataclass(obj):
        h.update(f"d{type(obj).__name__}".encode())
        for f in dataclasses.fields(obj):
            h.update(f.name.encode())
            _feed(h, getattr(obj, f.name))
    elif isinstance(obj, dict):
        h.update(f"m{len(obj)}".encode())
        for k in sorted(obj, key=str):
            _feed(h, k)
            _feed(h, obj[k])
    elif isinstance(obj, (list, tuple, range)):
        h.update(f"l{len(obj)}".encode())
        for v in obj:
            _feed(h, v)
    elif isinstance(obj, float):
        h.update(b"f" + struct.pack("<d", obj))
    else:
        h.update(f"{type(obj).__name__}:{obj!r};".encode())


_VERSION: list[str] = []


def renderer_version() -> str:
    """This module's source and matplotlib's version: what turns a description into pixels."""
    if not _VERSION:
        from importlib.metadata import version

        _VERSION.append(hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]
                        + f"-mpl{version('matplotlib')}-pillow{version('pillow')}")
    return _VERSION[0]


def plot_key(plot: Plot) -> str:
    """The hash of a figure's description and of the renderer."""
    h = hashlib.sha256(renderer_version().encode())
    _feed(h, plot)
    return h.hexdigest()


# -- rendering ------------------------------------------------------------------------------------

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
_MATH = re.compile(r"^\$\\mathdefault\{(.*)\}\$$")
_POWER = re.compile(r"\^\{(-?\d+)\}")


def plain_label(text: str) -> str:
    """A tick label of matplotlib's log formatter (``$\\mathdefault{2\\times10^{-3}}$``) as plain
    Unicode (``2×10⁻³``); anything else is returned unchanged."""
    m = _MATH.match(text)
    if m is None:
        return text
    body = _POWER.sub(lambda p: p.group(1).translate(_SUPERSCRIPT),
                      m.group(1).replace(r"\times", "\u2009×\u2009"))      # thin spaces
    if any(c in body for c in "\\{}^$"):
        return text
    return body.replace("-", "−")            # the sign: a minus, as mathtext draws it


_FORMATTER: list = []


def _log_formatter(**kw):
    if not _FORMATTER:
        from matplotlib.ticker import LogFormatterSciNotation

        class PlainLogFormatter(LogFormatterSciNotation):
            def __call__(self, x, pos=None):
                return plain_label(super().__call__(x, pos))

        _FORMATTER.append(PlainLogFormatter)
    return _FORMATTER[0](**kw)


def _ticks(ax) -> None:
    import math

    from matplotlib.ticker import LogLocator, MaxNLocator, NullLocator

    for axis, lim in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        if axis.get_scale() == "log":
            axis.set_minor_locator(NullLocator())
            lo, hi = min(lim), max(lim)
            if lo > 0 and hi / lo < 30:       # under 1.5 decades: label 1, 2, 5
                k = range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
                if sum(lo <= m * 10.0**e <= hi for e in k for m in (1, 2, 5)) >= 2:
                    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
                else:     # LogLocator would fall back to about 8 linear ticks whose labels collide
                    axis.set_major_locator(MaxNLocator(nbins=3, steps=[1, 2, 2.5, 5, 10]))
                axis.set_major_formatter(_log_formatter(minor_thresholds=(2, 2)))
            else:
                axis.set_major_formatter(_log_formatter())


def _panel(fig, ax, panel: Panel) -> None:
    last = None
    for s in panel.series:
        if s.band is not None:
            ax.fill_between(s.x, s.band, s.y, **s.style)
        elif s.scatter:
            last = ax.scatter(s.x, s.y, **s.style)
        else:
            ax.plot(s.x, s.y, **s.style)
    if panel.colorbar is not None and last is not None:
        fig.colorbar(last, ax=ax, **panel.colorbar)
    ax.set_xscale(panel.xscale)
    ax.set_yscale(panel.yscale)
    if panel.ylim is not None:
        ax.set_ylim(*panel.ylim)
    if panel.xticks is not None:
        ax.set_xticks(panel.xticks)
        if panel.xticklabels is not None:
            ax.set_xticklabels(panel.xticklabels, fontsize=7)
    if panel.grid:
        ax.grid(True, which="major", alpha=0.3)
    ax.set_xlabel(panel.xlabel)
    ax.set_ylabel(panel.ylabel)
    if panel.title:
        ax.set_title(panel.title, fontsize=panel.title_size, y=1.0)
    if panel.legend is not None and ax.get_legend_handles_labels()[0]:
        ax.legend(**panel.legend)


def render(plot: Plot, path: Path) -> None:
    """Draw ``plot`` into the PNG file ``path``."""
    import matplotlib

    with matplotlib.rc_context(RC):
        _render(plot, path)


def figure(plot: Plot):
    """``plot`` as a matplotlib Figure, with the report's styles (:data:`RC`)."""
    import matplotlib

    with matplotlib.rc_context(RC):
        return draw_figure(plot)


def _render(plot: Plot, path: Path) -> None:
    canvas = draw_figure(plot).canvas
    canvas.draw()
    _write_png(canvas, path)


def draw_figure(plot: Plot):
    """``plot`` drawn on a new matplotlib Figure (on an Agg canvas; no pyplot): what
    :func:`render` writes, and what the plot helpers of ``gnibench.plot`` return."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=plot.size, dpi=DPI)
    FigureCanvasAgg(fig)
    axes = fig.subplots(plot.rows, plot.cols, squeeze=False).ravel()
    fig.subplots_adjust(**plot.adjust)
    for ax in axes[len(plot.panels):]:
        ax.set_visible(False)
    for ax, panel in zip(axes, plot.panels):
        _panel(fig, ax, panel)
    if plot.suptitle:
        fig.suptitle(plot.suptitle, **plot.suptitle_style)
    if plot.legend is not None:
        handles, labels = [], []
        for ax in axes:
            for h, lab in zip(*ax.get_legend_handles_labels()):
                if lab not in labels and not lab.startswith("_"):
                    handles.append(h)
                    labels.append(lab)
        if handles:
            fig.legend(handles, labels, **plot.legend)
    for ax in fig.axes:
        _ticks(ax)
    return fig


def _write_png(canvas, path: Path) -> None:
    """The canvas as an RGB PNG (the figure is opaque: the alpha channel savefig writes is 255
    everywhere) at zlib level 3: a fifth smaller and 40 % faster to encode than savefig's RGBA at
    level 6 (the encoding is a sixth of a figure's drawing)."""
    from matplotlib import __version__
    from PIL import Image, PngImagePlugin

    rgba = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba(), "raw",
                            "RGBA", 0, 1)
    info = PngImagePlugin.PngInfo()
    info.add_text("Software", f"Matplotlib version{__version__}, https://matplotlib.org/")
    rgba.convert("RGB").save(path, format="png", pnginfo=info, dpi=(DPI, DPI), compress_level=3)
