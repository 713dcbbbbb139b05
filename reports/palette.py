"""Colours, line styles and markers of the report figures: one place, so a method has the same
colour in every figure of every page.

A method family (the cells' column ``family``, e.g. ``dopri5``, ``rk4+observer:...``)
gets the colour of its base method (column ``base_method``) (the palette of the seeds' figures,
:mod:`gnibench.reports.figures.style`, with a stable hash for methods added later); families that share a base method are told apart by line style, in the order given. The
marker says how the method chooses its steps and runs: fixed step (square), adaptive (circle),
external engine (triangle), Python code of the user's (diamond; ``method_kind`` of the cells
table).
"""
from __future__ import annotations

LINESTYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 3)))
MARKERS = {"fixed": "s", "adaptive": "o", "external": "^", "python": "D"}


def colour(base: str) -> str:
    """The colour of a base method id: the one of the seeds' figures
    (:func:`gnibench.reports.figures.style.color_of`), so a method has one colour everywhere."""
    from gnibench.reports.figures.style import color_of

    return color_of(base)


def styles(cells) -> dict[str, dict]:
    """matplotlib keyword arguments (``color``, ``linestyle``, ``marker``) for each family of the
    cells table, in order: the base method's colour, a new line style for each further family of
    the same base; the marker from ``method_kind`` (compiled, external, python) and
    ``adaptive``."""
    first = cells.drop_duplicates("family")
    seen: dict[str, int] = {}
    out = {}
    for fam, base, kind, adaptive in zip(first["family"], first["base_method"],
                                         first["method_kind"], first["adaptive"]):
        k = seen.get(base, 0)
        seen[base] = k + 1
        if kind == "compiled":
            kind = "adaptive" if adaptive else "fixed"
        out[fam] = {"color": colour(base), "linestyle": LINESTYLES[k % len(LINESTYLES)],
                    "marker": MARKERS[kind]}
    return out
