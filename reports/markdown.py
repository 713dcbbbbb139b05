"""The Markdown summary of an experiment run, rendered from its tables only (it never integrates).

:func:`render_summary` takes the provenance dict and the ``cells`` and ``timings`` DataFrames;
:func:`summary_from_dir` reads them back from a run's Parquet files.
"""
from __future__ import annotations

import re
from pathlib import Path


def _num(x, fmt: str = ".2e") -> str:
    """A number for a table: ``fmt`` for floats, ``–`` for missing values."""
    import pandas as pd

    if x is None or pd.isna(x):
        return "–"
    if isinstance(x, float):
        return format(x, fmt)
    return str(x)


def _count(x) -> str:
    """Evaluation counts: integers, or one decimal for the half evaluations of partitioned steps."""
    import pandas as pd

    if x is None or pd.isna(x):
        return "–"
    x = float(x)
    return f"{x:.0f}" if float(x).is_integer() else f"{x:.1f}"


_MARKDOWN_SPECIAL = set("\\`*_|~")             # markup wherever they stand
_LINK_END = re.compile(r"\](?=[(\[:])")          # [text](url), [text][ref], [ref]: url
_LINE_START = re.compile(r"[#+=\[-]|\d{1,9}(?=[.)](\s|$))")  # heading, list item, underline
_HTML = {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"}


def escape(text) -> str:
    """User or file text made inert in Markdown (and in the HTML a Markdown renderer makes of
    it): HTML specials become entities, the characters that make markup wherever they stand
    (emphasis, code, tables, strikethrough) are backslash-escaped, and so are a ``]`` that would
    close a link's text and a first character that would start a heading, a list or a link
    reference definition; line breaks become spaces. No input can add markup, script, links,
    headings or tables, and prose keeps its citations, periods, hyphens and parentheses as they
    are (``[HLW] (1.5), h = 0.1``)."""
    out = []
    for c in " ".join(str(text).split()):
        if c in _HTML:
            out.append(_HTML[c])
        elif c in _MARKDOWN_SPECIAL:
            out.append("\\" + c)
        else:
            out.append(c)
    text = _LINK_END.sub(r"\\]", "".join(out))
    m = _LINE_START.match(text)
    if m is None:
        return text
    cut = m.end() if text[0].isdigit() else 0         # "1." and "1)": before the delimiter
    return text[:cut] + "\\" + text[cut:]


def escape_block(text) -> str:
    """A multi-line user text (a description): each paragraph escaped, paragraphs kept."""
    paragraphs = [p for p in str(text).replace("\r", "").split("\n\n") if p.strip()]
    return "\n\n".join(escape(p) for p in paragraphs)


def code(text) -> str:
    """A spec as inline code: a code span cannot hold a backtick, so one is never emitted."""
    return "`" + str(text).replace("`", "'").replace("\n", " ") + "`"


def _cell(x) -> str:
    """Text safe inside a Markdown table cell (already escaped or code)."""
    return str(x).replace("\n", " ")


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(_cell(v) for v in row) + " |" for row in rows]
    return out


def render_summary(meta: dict, cells, timings) -> str:
    """Markdown: title, reference, description, then one table per problem (a row per cell).

    Columns: cell, method, status, steps, nfev, max |I(y) − I(y0)| for each integral of the
    problem, final and max global error (where an exact solution exists), wall time of the
    integration in ms, compile or cache-load time in s. The reasons of the cells that are not
    ``ok`` are listed under each table.
    """
    import pandas as pd

    lines = [f"# {escape(meta.get('title', meta.get('experiment', '')))}", ""]
    lines.append(f"Experiment {code(meta.get('experiment'))} — reference: "
                 f"{escape(meta.get('reference', ''))}")
    lines.append("")
    if meta.get("description"):
        lines += [escape_block(meta["description"]), ""]
    total, done = meta.get("cells_total", len(cells)), meta.get("cells_done", len(cells))
    counts = cells["status"].value_counts()
    order = ("ok", "nonfinite", "newton_failed", "error", "pending")
    status_text = ", ".join(f"{counts[s]} {s}" for s in sorted(
        counts.index, key=lambda s: order.index(s) if s in order else len(order)))
    state = "complete" if meta.get("complete", True) else f"INCOMPLETE: {done} of {total} cells done"
    lines += [f"{total} cells ({status_text}); {state}.", ""]
    wall = dict(zip(timings["cell"], timings["wall_seconds"])) if len(timings) else {}
    comp = dict(zip(timings["cell"], timings["compile_seconds"])) if len(timings) else {}
    by_problem: dict[str, list[dict]] = {}
    for record in cells.to_dict("records"):      # one pass: an experiment may have many problems
        by_problem.setdefault(record["problem"], []).append(record)
    err_columns = [c for c in cells.columns if c.startswith("max_abs_err_")]
    for problem, records in by_problem.items():
        errs = [c for c in err_columns if any(pd.notna(d[c]) for d in records)]
        has_exact = any(pd.notna(d["final_global_error"]) for d in records)
        orbits = any(pd.notna(d.get("orbits")) for d in records)
        header = ["cell", "method", "status"] + (["orbits (failed)"] if orbits else [])
        header += ["t", "steps", "nfev"]
        header += [f"max \\|err {c[len('max_abs_err_'):]}\\|" for c in errs]
        if has_exact:
            header += ["final global error", "max global error"]
        header += ["run ms", "compile s"]
        rows = []
        for d in records:
            kind = " (runs in Python)" if d.get("method_kind") == "python" else ""
            row = [d["cell"], code(d["method"]) + kind, escape(d["status"])]
            if orbits:
                row.append(f"{_count(d['orbits'])} ({_count(d['failed_orbits'])})"
                           if pd.notna(d.get("orbits")) else "")
            row += [_num(d["t_final"], ".4g"), _num(d["steps"]), _count(d["nfev"])]
            row += [_num(d[c]) for c in errs]
            if has_exact:
                row += [_num(d["final_global_error"]), _num(d["max_global_error"])]
            ms = wall.get(d["cell"], float("nan")) * 1e3
            row += [_num(ms, ".3g"), _num(comp.get(d["cell"]), ".2f")]
            rows.append(row)
        lines += [f"## {code(problem)}", ""] + _table(header, rows) + [""]
        if orbits:
            lines += ["An ensemble cell's values are the medians over its orbits (a failed orbit "
                      "as +inf); every orbit is in `ensemble.parquet`, the statistics in "
                      "`ensemble_stats.parquet`.", ""]
        notes = [f"- cell {d['cell']} ({escape(d['status'])}): {escape(d['reason'])}"
                 for d in records if d["status"] not in ("ok", "pending") and d["reason"]]
        if notes:
            lines += notes + [""]
    lines += [("Tables: `samples.parquet` (one row per cell and sample), `cells.parquet` (one row "
               "per cell), `timings.parquet` (wall and compile times). Wall times are not "
               "reproducible; everything else is."), ""]
    return "\n".join(lines)


def summary_from_dir(out_dir: str | Path) -> str:
    """Render the summary of a finished (or partial) run from its Parquet files."""
    import pandas as pd
    from gnibench.suite.runs.storage import read_parquet_meta

    out = Path(out_dir)
    meta = read_parquet_meta(out / "cells.parquet")
    return render_summary(meta, pd.read_parquet(out / "cells.parquet"),
                          pd.read_parquet(out / "timings.parquet"))
