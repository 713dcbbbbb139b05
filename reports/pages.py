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
         "max_global_error", "family", "sweep", "sweep_value", "adaptive", "problem_id",
         "base_method", "modifiers", "swept", "setup_method", "setup", "context", "swept_text",
         "_key", "solution_size", "max_reference_error", "final_reference_error"}
#: columns of the metrics shown in the table's notes rather than as columns
QUIET = ("growth_exponent_", "growth_reason_", "order_reason_", "scale_", "order_used_",
         "order_error_")
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


def cells_table(part, samples, wall: dict[int, tuple], compile_s: dict[int, float],
                by_cell: dict | None = None, memo: dict | None = None,
                names: dict | None = None) -> dict:
    """The table of one problem's cells: header, rows of strings, which columns are specs.
    ``wall``: each cell's (fastest, median, spread, runs) wall times; ``by_cell``:
    :func:`~gnibench.reports.plots.trajectories` of ``samples`` (if already split); ``memo``:
    fitted growth exponents, shared with the figures; ``names``: family names by setup id.
    The last column, notes, says why an order or a growth exponent is missing and which errors
    do not measure the method (saturated, below the reference's accuracy)."""
    from gnibench.suite.metrics.regime import trusted

    integrals = [i for i in dict.fromkeys("/".join(part["integrals"].fillna("")).split("/")) if i]
    errs = [i for i in integrals if f"max_abs_err_{i}" in part and part[f"max_abs_err_{i}"].notna().any()]
    has_global = part["final_global_error"].notna().any()
    extra = [c for c in part.columns if c not in FIXED and not c.startswith("max_abs_err_")
             and not c.startswith(QUIET) and part[c].notna().any()
             and not (part[c].astype(str) == "").all()]
    header = ["cell", "method", "family", "swept", "status", "horizon", "every", "t reached",
              "steps", "nfev", "run ms (fastest)", "median ms, spread", "compile s"]
    header += [f"max |err {i}|" for i in errs] + [f"growth exp. {i}" for i in errs]
    if has_global:
        header += ["final global error", "max global error", "reference's accuracy",
                   "growth exp. global", "reference"]
    header += extra + ["notes"]
    if samples is not None and by_cell is None:
        by_cell = plots.trajectories(samples)
    verdicts = {"max_global_error": trusted(part, "max_global_error")} if has_global else {}
    for i in errs:
        verdicts[f"max_abs_err_{i}"] = trusted(part, f"max_abs_err_{i}")
    rows = []
    for k, r in enumerate(part.to_dict("records")):
        cid = int(r["cell"])
        s = by_cell.get(cid) if samples is not None else None
        kind = " (runs in Python)" if r.get("method_kind") == "python" else ""
        fastest, median, spread, runs = wall.get(cid, (math.nan, math.nan, math.nan, 0))
        notes = []
        row = [str(cid), str(r["method"]) + kind, (names or {}).get(int(r["setup"]), r["family"]),
               str(r.get("swept_text") or "–"), str(r["status"]), _horizon(r), num(r["every"]),
               num(r["t_final"], ".6g"), num(r["steps"]), num(r["nfev"]),
               num(fastest * 1e3),
               f"{num(median * 1e3)}, {num(spread * 100, '.0f')} % ({runs} runs)" if runs > 1
               else "–", num(compile_s.get(cid), ".2f")]
        row += [num(r[f"max_abs_err_{i}"]) for i in errs]
        for i in errs:
            p, why = plots.exponent(r, s, i, memo) if samples is not None else (math.nan, "")
            row.append(num(p, ".2f"))
            notes += [f"growth {i}: {why}"] if why else []
        if has_global:
            p, why = plots.exponent(r, s, "global", memo) if samples is not None else \
                (math.nan, "")
            notes += [f"growth global: {why}"] if why else []
            row += [num(r["final_global_error"]), num(r["max_global_error"]),
                    num(r.get("max_reference_error")), num(p, ".2f"),
                    str(r.get("reference") or "–")]
        row += [num(r[c]) if isinstance(r[c], (int, float)) else str(r[c]) for c in extra]
        notes += [f"{c.removeprefix('max_')}: {v[k]}" for c, v in verdicts.items()
                  if v[k] and v[k] != "failed"]
        notes += [f"{c.removeprefix('order_reason_')} order: {r[c]}" for c in r
                  if c.startswith("order_reason_") and isinstance(r[c], str) and r[c]]
        row.append("; ".join(notes) or "–")
        rows.append(row)
    return {"header": header, "rows": rows, "code": [1], "status_col": 4,
            "wrap": [len(header) - 1]}


def league_tables(part, wall: dict[int, float], thresholds, names: dict | None = None) -> dict:
    """The league tables of one context, one per threshold, with the words stating them."""
    column, words = league.accuracy_column(part)
    if not column or not workprecision.has_sweeps(part):
        return {}
    tables = []
    for eps in thresholds:
        why = league.unrankable(part, column, eps)
        if why:
            tables.append({"threshold": f"{eps:.0e}", "rows": [], "note": why})
            continue
        rows = league.league(part, wall, eps, column, names)
        body = []
        for r in rows:
            failed = "; ".join(f"cell {c} {s}: {why}" if why else f"cell {c} {s}"
                               for c, s, why in r.failed)
            left = "; ".join(f"cell {c}: {why}" for c, why in r.excluded)
            order = num(r.order, ".2f") if math.isfinite(r.order) else \
                (f"NA: {r.order_reason}" if r.order_reason else "–")
            body.append([num(r.rank_nfev) if r.rank_nfev else "–", r.family,
                         _cost(r.nfev, ".3g"), _cost(r.wall, ".3g", 1e3),
                         num(r.rank_wall) if r.rank_wall else "–", num(r.best_error), order,
                         f"{r.cells}", "; ".join(x for x in (failed, left) if x) or "–"])
        tables.append({"threshold": f"{eps:.0e}", "rows": body, "note": ""})
    return {"measure": column, "words": words, "tables": tables,
            "header": ["rank (nfev)", "family", "nfev to reach ε", "wall ms to reach ε",
                       "rank (wall)", "best error", "order in h", "cells",
                       "failed or left-out cells"],
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


def experiment_page(res, img_dir: Path, slug: str, thresholds, jobs, palette=None,
                    plots_options: dict | None = None) -> dict:
    """The content of one experiment's page; the drawing of its figures (into ``img_dir``) is
    appended to ``jobs``. ``palette``: the report's styles of the families
    (:class:`gnibench.reports.palette.Palette`, shared by the pages); ``plots_options``: replace
    the ``[report]`` keys of the experiment file."""
    from gnibench.reports.palette import Palette
    from gnibench.reports.section import problem_section
    from gnibench.reports.setups import add_setups
    from gnibench.suite.runs.report_schema import report_options

    meta = res.meta
    cells = add_setups(res.cells)
    options = report_options({**(meta.get("report") or {}), **(plots_options or {})},
                             f"{res.name}: report").model_dump()
    palette = palette if palette is not None else Palette()
    paragraphs, notes = split_description(meta.get("description", ""))
    counts = cells["status"].value_counts()
    complete = bool(meta.get("complete", True))
    page = {
        "slug": slug, "name": res.name, "title": str(meta.get("title") or res.name),
        "reference": str(meta.get("reference") or ""), "source": str(meta.get("source") or ""),
        "paragraphs": paragraphs, "notes": notes, "complete": complete,
        "state": "incomplete" if not complete else ("failures" if (cells["status"] != "ok").any()
                                                    else "complete"),
        "cells_done": str(meta.get("cells_done", len(cells))),
        "cells_total": str(meta.get("cells_total", len(cells))),
        "statuses": ", ".join(f"{n} {s}" for s, n in counts.items()),
        "versions": [[str(k), str(v)] for k, v in sorted((meta.get("versions") or {}).items())],
        "written_at": res.written_at, "toml": str(meta.get("experiment_toml") or ""),
        "dir": str(res.dir), "figure": res.figure, "figure_error": res.figure_error,
        "thresholds": [f"{e:.0e}" for e in thresholds], "problems": [],
        "target": f"{options.get('target') or min(thresholds):.0e}",
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
        page["problems"].append(problem_section(problem, part, ps, img_dir, prefix, slug, jobs,
                                                res, thresholds, palette, options))
    page["interactive"] = any(c["interactive"] for pr in page["problems"]
                              for c in pr["contexts"])
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
    """What the index shows of an experiment page: its state (complete, complete with
    failures, incomplete), a thumbnail (the reproduced figure, else the first work-precision
    diagram, else the first figure) and one headline (the cheapest family to reach the target
    accuracy in the first context that ranks any)."""
    contexts = [c for pr in page["problems"] for c in pr["contexts"]]
    wp = [f["file"] for c in contexts for f in c["wp"]]
    figs = [f["file"] for pr in page["problems"] for f in pr["figures"]]
    heads = [c["headline"] for c in contexts if c["headline"]["text"]]
    head = next((h for h in heads if h["rank"]), heads[0] if heads else {"text": ""})
    return {k: page[k] for k in ("slug", "name", "title", "reference", "complete", "cells_done",
                                 "cells_total", "statuses", "state")} | {
        "problems": page["problem_ids"],
        "has_figure": bool(page.get("figure")),
        "headline": head["text"], "ranked": bool(head.get("rank")),
        "thumb": next(iter((page.get("figure") or {}).get("images") or wp or figs), "")}
