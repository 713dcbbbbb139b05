"""The content of the report pages as plain data (strings, lists, dicts), rendered twice by the
templates: HTML (Jinja2, autoescape) and Markdown (every value through
:func:`gnibench.reports.markdown.escape`). Nothing here writes markup.

An experiment page: title, seed reference, description and every "(choice)" / "(reading)" note,
provenance (versions, source, every cell's specs, horizon and reference, the TOML text), the
reproduced figure of ``figure/figure.json`` if any, then per problem: the default figures, the
work-precision diagrams, league tables, the table of cells (status, cost, metrics) and the failed
cells with their reasons.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

from gnibench.reports import league, plots, workprecision

FIXED = {"cell", "group", "label", "problem", "method", "problem_id", "base_method", "modifiers",
         "method_kind", "h", "t_end",
         "steps_planned", "every", "status", "reason", "steps", "t_final", "nfev", "njev",
         "samples", "integrals", "reference", "metrics", "metric_notes", "final_global_error",
         "max_global_error", "family", "sweep", "sweep_value", "adaptive"}
_NOTE = re.compile(r"^\s*\((choice|reading)\)\s*", re.IGNORECASE)


def num(x, fmt: str = ".3g") -> str:
    """A number for a table; ``–`` for missing values."""
    if x is None:
        return "–"
    try:
        v = float(x)
    except (TypeError, ValueError):
        import pandas as pd

        return "–" if x is pd.NA else str(x)          # NA: a count the method did not report
    if math.isnan(v):
        return "–"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if v.is_integer() and abs(v) < 1e15 and fmt == ".3g":
        return f"{v:.0f}"
    return format(v, fmt)


def split_description(text: str) -> tuple[list[str], list[dict]]:
    """(paragraphs, notes): each line that starts with "(choice)" or "(reading)" starts a note
    that runs to the next such line or blank line; the other lines form the paragraphs."""
    paragraphs: list[list[str]] = [[]]
    notes: list[dict] = []
    in_note = False
    for line in str(text or "").replace("\r", "").split("\n"):
        m = _NOTE.match(line)
        if m:
            notes.append({"kind": m.group(1).lower(), "text": line[m.end():].strip()})
            in_note = True
        elif not line.strip():
            in_note = False
            paragraphs.append([])
        elif in_note:
            notes[-1]["text"] += " " + line.strip()
        else:
            paragraphs[-1].append(line.strip())
    return [" ".join(p) for p in paragraphs if p], notes


def _horizon(row) -> str:
    if row.get("t_end") is not None and not (isinstance(row["t_end"], float)
                                             and math.isnan(row["t_end"])):
        return f"t_end = {num(row['t_end'], '.6g')}"
    return f"steps = {num(row.get('steps_planned'))}"


def cells_table(part, samples, wall: dict[int, float], compile_s: dict[int, float],
                by_cell: dict | None = None, memo: dict | None = None) -> dict:
    """The table of one problem's cells: header, rows of strings, which columns are specs.
    ``by_cell``: :func:`~gnibench.reports.plots.trajectories` of ``samples`` (if already split);
    ``memo``: fitted growth exponents, shared with the figures."""
    integrals = [i for i in dict.fromkeys("/".join(part["integrals"].fillna("")).split("/")) if i]
    errs = [i for i in integrals if f"max_abs_err_{i}" in part and part[f"max_abs_err_{i}"].notna().any()]
    has_global = part["final_global_error"].notna().any()
    extra = [c for c in part.columns if c not in FIXED and not c.startswith("max_abs_err_")
             and not c.startswith("growth_exponent_") and part[c].notna().any()
             and not (part[c].astype(str) == "").all()]
    header = ["cell", "method", "status", "horizon", "every", "t reached", "steps", "nfev",
              "run ms", "compile s"]
    header += [f"max |err {i}|" for i in errs] + [f"growth exp. {i}" for i in errs]
    if has_global:
        header += ["final global error", "max global error", "growth exp. global", "reference"]
    header += extra
    if samples is not None and by_cell is None:
        by_cell = plots.trajectories(samples)
    rows = []
    for r in part.to_dict("records"):
        cid = int(r["cell"])
        s = by_cell.get(cid) if samples is not None else None
        kind = " (runs in Python)" if r.get("method_kind") == "python" else ""
        row = [str(cid), str(r["method"]) + kind, str(r["status"]), _horizon(r), num(r["every"]),
               num(r["t_final"], ".6g"), num(r["steps"]), num(r["nfev"]),
               num(wall.get(cid, math.nan) * 1e3), num(compile_s.get(cid), ".2f")]
        row += [num(r[f"max_abs_err_{i}"]) for i in errs]
        row += [num(plots.exponent(r, s, i, memo) if samples is not None else math.nan, ".2f")
                for i in errs]
        if has_global:
            row += [num(r["final_global_error"]), num(r["max_global_error"]),
                    num(plots.exponent(r, s, "global", memo) if samples is not None
                        else math.nan, ".2f"),
                    str(r.get("reference") or "–")]
        row += [num(r[c]) if isinstance(r[c], (int, float)) else str(r[c]) for c in extra]
        rows.append(row)
    return {"header": header, "rows": rows, "code": [1], "status_col": True}


def league_tables(part, wall: dict[int, float], thresholds) -> dict:
    """The league tables of one problem, one per threshold, with the words stating them."""
    column, words = league.accuracy_column(part)
    if not column or not workprecision.has_sweeps(part):
        return {}
    tables = []
    for eps in thresholds:
        rows = league.league(part, wall, eps, column)
        body = []
        for r in rows:
            failed = "; ".join(f"cell {c} {s}: {why}" if why else f"cell {c} {s}"
                               for c, s, why in r.failed)
            body.append([num(r.rank_nfev) if r.rank_nfev else "–", r.family,
                         _cost(r.nfev, ".3g"), _cost(r.wall, ".3g", 1e3),
                         num(r.rank_wall) if r.rank_wall else "–", num(r.best_error),
                         f"{r.cells}", failed or "–"])
        tables.append({"threshold": f"{eps:.0e}", "rows": body})
    return {"measure": column, "words": words, "tables": tables,
            "header": ["rank (nfev)", "method family", "nfev to reach ε", "wall ms to reach ε",
                       "rank (wall)", "best error", "cells", "failed cells"],
            "code": [1]}


def _cost(c: league.Cost, fmt: str, scale: float = 1.0) -> str:
    if c.how in ("not reached", "–"):
        return c.how
    value = num(c.value * scale, fmt)
    if c.how == "bound":
        return f"≤ {value} (cell {c.cells[0]})"
    if c.how == "interpolated":
        return f"{value} (cells {c.cells[0]}–{c.cells[1]})"
    return f"{value} (cell {c.cells[0]})"


def experiment_page(res, img_dir: Path, slug: str, thresholds, jobs) -> dict:
    """The content of one experiment's page; the drawing of its figures (into ``img_dir``) is
    appended to ``jobs``."""
    meta, cells = res.meta, res.cells
    paragraphs, notes = split_description(meta.get("description", ""))
    wall = res.wall_by_cell()
    t = res.timings
    compile_s = {int(c): float(v) for c, v in zip(t["cell"], t["compile_seconds"])} if len(t) else {}
    counts = cells["status"].value_counts()
    page = {
        "slug": slug, "name": res.name, "title": str(meta.get("title") or res.name),
        "reference": str(meta.get("reference") or ""), "source": str(meta.get("source") or ""),
        "paragraphs": paragraphs, "notes": notes,
        "complete": bool(meta.get("complete", True)),
        "cells_done": str(meta.get("cells_done", len(cells))),
        "cells_total": str(meta.get("cells_total", len(cells))),
        "statuses": ", ".join(f"{n} {s}" for s, n in counts.items()),
        "versions": [[str(k), str(v)] for k, v in sorted((meta.get("versions") or {}).items())],
        "written_at": res.written_at, "toml": str(meta.get("experiment_toml") or ""),
        "dir": str(res.dir), "figure": res.figure, "figure_error": res.figure_error,
        "thresholds": [f"{e:.0e}" for e in thresholds], "problems": [],
    }
    if res.figure:
        page["figure"] = {**res.figure, "images": [f"{slug}/figure/{f}" for f in res.figure["images"]]}
    try:
        samples = res.samples()
    except (OSError, ValueError):
        samples = None
    sections = problem_sections(cells)
    page["problem_ids"] = short_problems(cells)
    for i, problem in enumerate(dict.fromkeys(sections)):
        part = cells[sections == problem]
        prefix = f"{i:02d}-" + re.sub(r"[^A-Za-z0-9._-]+", "_", str(problem))[:40]
        ps = samples[samples["cell"].isin(part["cell"])] if samples is not None else None
        by_cell = plots.trajectories(ps) if ps is not None else None
        memo: dict = {}
        figs = plots.time_figures(problem, part, ps, img_dir, prefix, slug, jobs, by_cell, memo) \
            if ps is not None and len(ps) else []
        wp = workprecision.wp_figures(problem, part, wall, img_dir, prefix, slug, jobs) \
            if workprecision.has_sweeps(part) else []
        failed = [{"cell": str(r.cell), "method": str(r.method), "status": str(r.status),
                   "reason": str(r.reason or "")} for r in part.itertuples() if r.status != "ok"]
        groups = [{"group": str(g), "label": str(lab or "")} for g, lab in
                  part[["group", "label"]].drop_duplicates().itertuples(index=False)]
        page["problems"].append({
            "name": str(problem), "anchor": prefix, "figures": [f.__dict__ for f in figs],
            "wp": [f.__dict__ for f in wp], "no_nfev": workprecision.no_nfev(part) if wp else [],
            "league": league_tables(part, wall, thresholds),
            "table": cells_table(part, ps, wall, compile_s, by_cell, memo), "failed": failed,
            "groups": groups})
    return page


MAX_SPECS_PER_PROBLEM = 6


def problem_sections(cells):
    """The section of the page each cell goes to: its problem spec, or the bare problem id when
    the experiment runs that problem from more than ``MAX_SPECS_PER_PROBLEM`` specs (the
    initial points of a set, [HLW] Figs 1.1 and 1.3: one section, not one per point)."""
    import pandas as pd

    problems = cells["problem"].astype(str)
    ids = cells["problem_id"].astype(str)
    many = {i for i, n in problems.groupby(ids).nunique().items() if n > MAX_SPECS_PER_PROBLEM}
    return pd.Series(problems.where(~ids.isin(many), ids + " (" + problems.groupby(ids)
                                    .transform("nunique").astype(str) + " initial values)"),
                     index=problems.index)


def short_problems(cells) -> list[str]:
    """The problems of an experiment as the index card names them: each spec briefly
    (:func:`gnibench.reports.plots.brief`), a problem run from several specs by its id and their
    number (the page itself lists every spec)."""
    pairs = dict.fromkeys(zip(cells["problem"].astype(str), cells["problem_id"].astype(str)))
    out = []
    for pid in dict.fromkeys(i for _, i in pairs):
        mine = [t for t, i in pairs if i == pid]
        out.append(f"{pid} ({len(mine)} parameter sets)" if len(mine) > 1
                   else plots.brief(mine[0], pid))
    return out


def index_entry(page: dict) -> dict:
    """What the index shows of an experiment page."""
    return {k: page[k] for k in ("slug", "name", "title", "reference", "complete", "cells_done",
                                 "cells_total", "statuses")} | {
        "problems": page["problem_ids"],
        "has_figure": bool(page.get("figure")),
        "thumb": next(iter((page.get("figure") or {}).get("images") or []), "")}
