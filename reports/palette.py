"""Colours, line styles and markers of the report figures: one place, so a method has the same
colour in every figure of every page.

A method family (:func:`gnibench.reports.families.family_of`, e.g. ``dopri5``, ``rk4+observer:...``)
gets the colour of its base method (:data:`METHOD_COLOURS`, then a fallback cycle for methods added
later); families that share a base method are told apart by line style, in the order given. The
marker says how the method chooses its steps: fixed step (square), adaptive (circle), external
engine (triangle).
"""
from __future__ import annotations

import hashlib

#: base method id -> colour (matplotlib's tab20 and a few darker tones, chosen to separate the
#: methods that usually share a plot: the adaptive pairs, the compositions, the competitors)
METHOD_COLOURS = {
    "euler": "#7f7f7f",
    "rk4": "#1f77b4",
    "merson": "#17becf",
    "rkf45": "#9467bd",
    "dopri5": "#ff7f0e",
    "dop853": "#d62728",
    "odex": "#8c564b",
    "implicit-euler": "#c7c7c7",
    "implicit-midpoint": "#bcbd22",
    "gauss4": "#98df8a",
    "gauss6": "#2ca02c",
    "symplectic-euler": "#aec7e8",
    "symplectic-euler-adjoint": "#c5b0d5",
    "stormer-verlet": "#e377c2",
    "yoshida4": "#f7b6d2",
    "yoshida6": "#c49c94",
    "yoshida8": "#7b4173",
    "lie-poisson": "#393b79",
    "generating-function4": "#637939",
    "heyoka-taylor": "#000000",
    "rebound-ias15": "#843c39",
    "rebound-whfast": "#e7969c",
}
FALLBACK = ("#3182bd", "#e6550d", "#31a354", "#756bb1", "#636363", "#6baed6", "#fd8d3c",
            "#74c476", "#9e9ac8", "#969696")
LINESTYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 3)))
MARKERS = {"fixed": "s", "adaptive": "o", "external": "^"}
EXTERNAL = ("heyoka-taylor", "rebound-ias15", "rebound-whfast")


def colour(base: str) -> str:
    """The colour of a base method id (stable for ids not in the table)."""
    if base in METHOD_COLOURS:
        return METHOD_COLOURS[base]
    digest = int(hashlib.sha256(base.encode()).hexdigest(), 16)
    return FALLBACK[digest % len(FALLBACK)]


def base_of(family: str) -> str:
    """The base method id of a family or method spec."""
    return family.split("+", 1)[0].split(":", 1)[0].strip()


def styles(families: list[str], adaptive: dict[str, bool] | None = None) -> dict[str, dict]:
    """matplotlib keyword arguments (``color``, ``linestyle``, ``marker``) for each family, in
    order: the base method's colour, a new line style for each further family of the same base."""
    adaptive = adaptive or {}
    seen: dict[str, int] = {}
    out = {}
    for fam in families:
        base = base_of(fam)
        k = seen.get(base, 0)
        seen[base] = k + 1
        kind = "external" if base in EXTERNAL else ("adaptive" if adaptive.get(fam) else "fixed")
        out[fam] = {"color": colour(base), "linestyle": LINESTYLES[k % len(LINESTYLES)],
                    "marker": MARKERS[kind]}
    return out
