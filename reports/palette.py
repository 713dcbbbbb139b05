"""Colours, line styles and markers of the report figures: one place, so a method has the same
colour in every figure of every page.

A method family (:func:`gnibench.reports.families.family_of`, e.g. ``dopri5``, ``rk4+observer:...``)
gets the colour of its base method (the palette of the seeds' figures,
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


def base_of(family: str) -> str:
    """The base method id of a family or method spec."""
    from gnibench.suite.cell.spec import item_id

    return item_id(family, "method")


def styles(families: list[str], adaptive: dict[str, bool] | None = None,
           kinds: dict[str, str] | None = None) -> dict[str, dict]:
    """matplotlib keyword arguments (``color``, ``linestyle``, ``marker``) for each family, in
    order: the base method's colour, a new line style for each further family of the same base.
    ``kinds``: each family's ``method_kind`` (compiled, external, python)."""
    adaptive, kinds = adaptive or {}, kinds or {}
    seen: dict[str, int] = {}
    out = {}
    for fam in families:
        base = base_of(fam)
        k = seen.get(base, 0)
        seen[base] = k + 1
        kind = kinds.get(fam, "compiled")
        if kind == "compiled":
            kind = "adaptive" if adaptive.get(fam) else "fixed"
        out[fam] = {"color": colour(base), "linestyle": LINESTYLES[k % len(LINESTYLES)],
                    "marker": MARKERS[kind]}
    return out
