"""Colours, markers and line styles of the report figures: one place, so a method has the same
look in every figure of a report (its PNGs and its interactive diagrams alike).

A method family (the cells' column ``family``, e.g. ``dop853``, ``rk4+observer:theta=15``) gets a
style the first time a report meets it (:class:`Palette`), in the order of the report's pages and
cells, and keeps it on every page: the k-th family gets colour k mod 9 of Paul Tol's "muted"
scheme (a qualitative scheme designed to stay distinct under the common colour-vision
deficiencies, https://personal.sron.nl/~pault/), marker k mod 8 and line style ⌊k/9⌋ mod 3, so
the first 72 families differ in colour or marker, and families with the same colour differ in
marker and line style. Families of one figure that share their label (the same method in two
setups, e.g. two ``atol``) are told apart by dotted and dash-dotted line styles (hollow markers
mean something else: an error below the reference's accuracy).
"""
from __future__ import annotations

#: Paul Tol's "muted" qualitative scheme (without its pale grey for missing data)
COLOURS = ("#332288", "#CC6677", "#117733", "#882255", "#44AA99", "#999933", "#AA4499",
           "#88CCEE", "#DDCC77")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
LINESTYLES = ("-", "--", "-.")
#: the line styles of a family's second, third, ... setup in one figure
VARIANTS = (":", (0, (1, 3)), (0, (3, 1, 1, 1, 1, 1)), (0, (5, 1)))

#: the same styles in plotly's names (the interactive diagrams)
PLOTLY_MARKERS = {"o": "circle", "s": "square", "^": "triangle-up", "D": "diamond",
                  "v": "triangle-down", "P": "cross", "X": "x", "*": "star"}
PLOTLY_DASH = {"-": "solid", "--": "dash", "-.": "dashdot", ":": "dot"}


class Palette:
    """Styles of method families, given in the order families are met (:meth:`of`)."""

    def __init__(self, families=()):
        self.index: dict[str, int] = {}
        for f in families:
            self.of(f)

    def of(self, family: str, variant: int = 0) -> dict:
        """matplotlib keywords (``color``, ``marker``, ``linestyle``) of a family label (its
        ``variant``-th setup in a figure: another line style); a new label gets the next
        style."""
        k = self.index.setdefault(str(family), len(self.index))
        style = {"color": COLOURS[k % len(COLOURS)], "marker": MARKERS[k % len(MARKERS)],
                 "linestyle": LINESTYLES[(k // len(COLOURS)) % len(LINESTYLES)]}
        if variant:
            style["linestyle"] = VARIANTS[(variant - 1) % len(VARIANTS)]
        return style


def plotly_style(style: dict) -> dict:
    """A style of :meth:`Palette.of` in plotly's terms: colour, marker symbol, line dash."""
    dash = style["linestyle"]
    return {"color": style["color"], "symbol": PLOTLY_MARKERS[style["marker"]],
            "dash": PLOTLY_DASH.get(dash, "dot") if isinstance(dash, str) else "longdashdot"}


def styles(cells, palette: Palette | None = None) -> dict:
    """The style of each family of the cells, by setup id (column ``setup``): the palette's style
    of its label (column ``family``), a variant for each further setup of the same label."""
    palette = palette if palette is not None else Palette()
    seen: dict[str, int] = {}
    out = {}
    first = cells.drop_duplicates("setup")
    for setup, label in zip(first["setup"], first["family"]):
        k = seen.get(label, 0)
        seen[label] = k + 1
        out[int(setup)] = palette.of(label, k)
    return out
