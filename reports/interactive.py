"""Interactive work-precision diagrams for the HTML pages, drawn by plotly.js.

The same points, families, styles, Pareto fronts and levels as the static figure
(:mod:`gnibench.reports.workprecision`), as a plotly figure (``data`` and ``layout``, plain JSON
in the page): hovering a point shows its cell (id, full method spec, error, nfev, wall time with
the spread of its repeated runs, whether the error is below the reference's accuracy);
clicking a family in the legend hides or shows it in every panel (double-click: it alone).

Why plotly.js: a well-kept library (MIT) that draws log–log scatter plots with linked legends
and hover text from JSON, and the ``plotly`` Python package ships it as one file
(``plotly.offline.get_plotlyjs()``), so the site copies it next to the pages
(:data:`ASSET`) and opens from ``file://`` without a network. Every string that goes into hover
or legend text is HTML-escaped (plotly renders a few tags in them).
"""
from __future__ import annotations

import html
import json
import math
from pathlib import Path

import numpy as np

ASSET = "assets/plotly.min.js"


def _esc(text) -> str:
    return html.escape(str(text), quote=True)


def _num(x, fmt: str = ".3g") -> str:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return "–"
    return "–" if math.isnan(v) else format(v, fmt)


def hover_rows(cells, timing: dict[int, tuple]) -> dict[int, list[str]]:
    """The hover text fields of each cell: id, spec, nfev, wall time min / median / spread /
    runs (``timing``: cell -> (min s, median s, spread, runs))."""
    out = {}
    for r in cells.to_dict("records"):
        cid = int(r["cell"])
        wmin, wmed, spread, runs = timing.get(cid, (math.nan, math.nan, math.nan, 0))
        out[cid] = [str(cid), _esc(r["method"]), _num(r.get("nfev"), ".0f"),
                    _num(wmin * 1e3), _num(wmed * 1e3), _num(spread * 100, ".0f") + " %",
                    str(int(runs or 0))]
    return out


HOVER = ("<b>%{fullData.name}</b><br>cell %{customdata[0]}: %{customdata[1]}<br>"
         "error %{y:.3e}<br>nfev %{customdata[2]}<br>wall %{customdata[3]} ms (fastest; median "
         "%{customdata[4]} ms, spread %{customdata[5]} over %{customdata[6]} runs)"
         "%{customdata[7]}<extra></extra>")


def wp_figure_json(title: str, cells, timing: dict[int, tuple], style: dict, names: dict,
                   options: dict | None = None) -> dict | None:
    """The plotly figure (``{"data": [...], "layout": {...}}``) of one context's work-precision
    diagram; None when there is no error measure."""
    from gnibench.reports.palette import plotly_style
    from gnibench.reports.workprecision import COSTS, levels_line, measures, panel_points, pareto
    from gnibench.suite.metrics.regime import BELOW_FLOOR, saturation_words

    options = options or {}
    rows = measures(cells, options.get("measures"))
    costs = [COSTS[c] for c in options.get("costs") or ("nfev", "wall")]
    if not rows:
        return None
    cells = cells.assign(wall_ms=[timing.get(int(c), (math.nan,))[0] * 1e3
                                  for c in cells["cell"]])
    hover = hover_rows(cells, timing)
    data, layout, shown = [], {}, set()
    k = 0
    for col, label in rows:
        sat, acc = levels_line(cells, col)
        for xcol, xlabel in costs:
            k += 1
            ax = "" if k == 1 else str(k)
            layout[f"xaxis{ax}"] = {"type": "log", "title": {"text": _esc(xlabel)},
                                    "exponentformat": "power", "showgrid": True}
            layout[f"yaxis{ax}"] = {"type": "log", "title": {"text": _esc(label)},
                                    "exponentformat": "power", "showgrid": True}
            where = {"xaxis": f"x{ax}", "yaxis": f"y{ax}"}
            fx, fy = [], []
            xs = []
            for setup, (x, y, ids, verdict) in panel_points(cells, col, xcol).items():
                st = plotly_style(style[setup])
                below = verdict == BELOW_FLOOR
                note = ["<br><i>below the reference's accuracy: not ranked</i>" if b else ""
                        for b in below]
                custom = [hover[int(c)] + [n] for c, n in zip(ids, note)]
                group = f"f{setup}"
                data.append({**where, "type": "scatter", "mode": "lines+markers",
                             "x": x.tolist(), "y": y.tolist(), "customdata": custom,
                             "name": _esc(names[setup]), "legendgroup": group,
                             "showlegend": group not in shown, "hovertemplate": HOVER,
                             "line": {"color": st["color"], "dash": st["dash"], "width": 1.6},
                             "marker": {"color": st["color"], "size": 8,
                                        "symbol": [st["symbol"].removesuffix("-open") + "-open"
                                                   if b else st["symbol"] for b in below]}})
                shown.add(group)
                trusted = verdict == ""
                fx += x[trusted].tolist()
                fy += y[trusted].tolist()
                xs += x.tolist()
            if fx:
                px, py = pareto(np.array(fx), np.array(fy))
                data.append({**where, "type": "scatter", "mode": "lines", "x": px.tolist(),
                             "y": py.tolist(), "name": "Pareto front", "legendgroup": "pareto",
                             "showlegend": "pareto" not in shown, "hoverinfo": "skip",
                             "line": {"color": "black", "dash": "dash", "width": 1,
                                      "shape": "hv"}})
                shown.add("pareto")
            for level, name, dash in ((sat, f"saturation ({saturation_words(col)})", "dash"),
                                      (acc, "reference's own accuracy", "dot")):
                if xs and math.isfinite(level) and level > 0:
                    data.append({**where, "type": "scatter", "mode": "lines",
                                 "x": [min(xs), max(xs)], "y": [level, level],
                                 "name": _esc(name), "legendgroup": name,
                                 "showlegend": name not in shown, "hoverinfo": "skip",
                                 "line": {"color": "#777777", "dash": dash, "width": 1}})
                    shown.add(name)
    n_rows, n_cols = len(rows), len(costs)
    layout.update({
        "title": {"text": _esc(title), "font": {"size": 15}},
        "grid": {"rows": n_rows, "columns": n_cols, "pattern": "independent",
                 "xgap": 0.12, "ygap": 0.16},
        "height": 120 + 380 * n_rows, "hovermode": "closest",
        "legend": {"font": {"size": 12}, "groupclick": "togglegroup"},
        "margin": {"l": 70, "r": 20, "t": 60, "b": 60},
        "font": {"family": "DejaVu Sans, Verdana, sans-serif", "size": 12},
        "plot_bgcolor": "white"})
    return {"data": data, "layout": layout}


def script_json(doc: dict) -> str:
    """JSON that is safe inside a ``<script type="application/json">`` element of an HTML page
    (no ``<``, ``>`` or ``&`` that could end it)."""
    text = json.dumps(doc, allow_nan=False, separators=(",", ":"), default=float)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def copy_library(site: Path) -> None:
    """plotly.js into the site (:data:`ASSET`), written only when it differs from the copy there."""
    from gnibench.suite.foundation.cache import atomic_write
    from plotly.offline import get_plotlyjs

    text = get_plotlyjs().encode("utf-8")
    path = Path(site) / ASSET
    try:
        if path.read_bytes() == text:
            return
    except OSError:
        pass
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, lambda p: Path(p).write_bytes(text))
