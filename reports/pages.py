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

import re
from pathlib import Path

from gnibench.reports import plots

_NOTE = re.compile(r"^\s*\((choice|reading)\)\s*", re.IGNORECASE)


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
