"""One look for every figure: a colour per method, line styles, fonts.

The palette is keyed by the *method key*: the base method id followed by its modifiers
(``euler``, ``euler+observer``, ``dopri5+observer+projection``), read from a canonical method spec.
The base methods of the seeds have fixed colours (Okabe–Ito's colour-blind-safe set first, so the
methods of [HLW] Ch. I — explicit Euler, implicit Euler, symplectic Euler, implicit midpoint,
Störmer–Verlet — are told apart also in grey print); a modified method that has no entry of its own
takes a colour of ``EXTRA`` chosen by a stable hash of its key, the same in every figure. Every
key listed has its own colour. ``exact`` (a reference or an exact solution) is black.
"""
from __future__ import annotations

import hashlib

PALETTE = {
    "exact": "#000000",
    "euler": "#D55E00",
    "implicit-euler": "#CC79A7",
    "symplectic-euler": "#0072B2",
    "symplectic-euler-adjoint": "#56B4E9",
    "implicit-midpoint": "#E69F00",
    "stormer-verlet": "#009E73",
    "rk4": "#8C564B",
    "merson": "#6A3D9A",
    "rkf45": "#B15928",
    "dopri5": "#1F78B4",
    "dop853": "#555555",
    "odex": "#33A02C",
    "gauss4": "#E31A1C",
    "gauss6": "#FB9A99",
    "yoshida4": "#117733",
    "yoshida6": "#44AA99",
    "yoshida8": "#88CCEE",
    "lie-poisson": "#882255",
    "generating-function4": "#999933",
    "vern6": "#FF7F0E",             # the high-accuracy families (issue 19): own colours, not
    "vern7": "#C51B7D",             # the hashed EXTRA ones, which gave vern6 and feagin10 (and
    "vern8": "#4D9221",             # vern8, suzuki4 and kahan-li6) one colour in the same
    "vern9": "#542788",             # work-precision diagram
    "feagin10": "#FFD92F",
    "suzuki4": "#BF812D",
    "mclachlan4": "#35978F",
    "kahan-li6": "#A6D854",
    "kahan-li8": "#F46D43",
    "heyoka-taylor": "#661100",
    "rebound-ias15": "#6699CC",
    "rebound-whfast": "#AA4499",
    "scipy-rk45": "#17BECF",
    "scipy-rk23": "#9EDAE5",
    "scipy-dop853": "#BCBD22",
    "scipy-radau": "#D01C8B",
    "scipy-bdf": "#01665E",
    "scipy-lsoda": "#E377C2",
    "euler+observer": "#332288",
    "euler+penalty": "#2CA02C",
    "rk4+observer": "#DDCC77",
    "rk4+projection": "#117799",
    "dopri5+observer": "#9467BD",
    "dopri5+penalty": "#7B8F00",
    "rkf45+observer": "#A6761D",
    "merson+observer": "#1B9E77",
    "odex+observer": "#E7298A",
    "odex+penalty": "#66A61E",
}
EXTRA = ("#332288", "#117733", "#44AA99", "#88CCEE", "#DDCC77", "#AA4499", "#882255", "#999933",
         "#661100", "#6699CC")
FIELD_COLOR = "#9A9A9A"
QUIVER_COLOR = "#4D4D4D"

RC = {
    "font.size": 9.5,
    "axes.titlesize": 10,
    "axes.labelsize": 10,
    "legend.fontsize": 8.5,
    "legend.framealpha": 0.85,
    "xtick.labelsize": 8.5,
    "ytick.labelsize": 8.5,
    "lines.linewidth": 1.2,
    "axes.grid": False,
    "svg.fonttype": "path",
    "svg.hashsalt": "gnibench",    # the SVG's element ids fixed: the same figure, the same bytes
    "figure.dpi": 100,
    "savefig.dpi": 150,
}


def method_key(row: dict) -> str:
    """The palette key of a cell (a row of cells.parquet): its base method and modifier ids,
    ``rk4+observer`` for ``rk4:h=0.01+observer:theta=1``."""
    modifiers = row.get("modifiers") or ""
    return str(row["base_method"]) + ("+" + str(modifiers) if modifiers else "")


def color_of(key: str) -> str:
    """The colour of a method key (or a palette name such as ``exact``)."""
    if key in PALETTE:
        return PALETTE[key]
    digest = int(hashlib.sha1(key.encode()).hexdigest(), 16)
    return EXTRA[digest % len(EXTRA)]


def curve_color(curve: dict, row: dict) -> str:
    """A curve's colour: its ``color`` (a palette key or a matplotlib colour), else the method's
    of its first cell (``row``, its row of cells.parquet)."""
    from matplotlib.colors import is_color_like

    given = curve.get("color") or ""
    if given in PALETTE:
        return PALETTE[given]
    if given and is_color_like(given):
        return given
    return color_of(method_key(row))
