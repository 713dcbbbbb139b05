"""The gallery: the seeds' figures and tables, drawn by this build, each beside its ledger verdicts.

When the documentation builds, ``gnibench.reproduce("all", scale="quick")`` draws every figure
and table of [B] and [HLW] that is a computation, and ``gnibench.verify("all", scale="quick")``
judges the claims on the same runs (one resumable store, ``docs/_build/seeds``: a second build
reuses its cells). One page per figure shows the picture, the seed's caption, what the seed says
and what we measured, the choices made where the seed is silent, and the verdict of every claim
that belongs to the figure. Nothing here is stored: the pictures and verdicts are this build's.

``GNIBENCH_DOCS_GALLERY=skip`` builds the pages without drawing (for quick local builds of
other pages); each page then says that it holds no picture.
"""
from __future__ import annotations

import json
import os
import tomllib
from pathlib import Path

from . import claims as claims_mod
from .common import Tree, cell, table

VERDICTS = ("reproduced", "partly", "not reproduced", "not checkable", "skipped", "error")


def figure_ids() -> list[str]:
    """The shipped experiments with a ``[figure]`` section, in the seeds' order."""
    from gnibench.suite.runs.experiment import shipped

    out = []
    for name, text in shipped().items():
        doc = tomllib.loads(text)
        if "figure" in doc:
            out.append(name)
    return sorted(out, key=_order)


def _order(fid: str):
    import re

    seed, _, rest = fid.partition("-")
    nums = [float(x) if "." in x else int(x) for x in re.findall(r"\d+(?:\.\d+)?", rest)]
    return (0 if seed == "hlw" else 1, "table" in fid, nums)


def draw(out: Path) -> tuple[dict, object]:
    """Reproduce every figure at the quick scale and verify every claim; ({id: dir}, ledger)."""
    import gnibench

    dirs = gnibench.reproduce("all", scale="quick", output=str(out))
    ledger = gnibench.verify("all", scale="quick", output=str(out))
    return {k: Path(v) for k, v in dirs.items()}, ledger


def _verdict_rows(fid: str, ledger) -> list[list[str]]:
    rows = []
    for c in claims_mod.by_figure().get(fid, []):
        row = None
        if ledger is not None:
            hit = ledger[ledger["id"] == c["id"]]
            row = hit.iloc[0].to_dict() if len(hit) else None
        verdict = row["verdict"] if row else "not run in this build"
        if row and row.get("unexpected"):
            verdict += f" (differs from the recorded {row['expected']})"
        rows.append([f"{{ref}}`{c['id']} <{claims_mod.anchor(c['id'])}>`",
                     cell(" ".join(str(c.get("claim", "")).split())), cell(verdict),
                     cell(row.get("measured_text", "") if row else ""), cell(c.get("seed_value", ""))])
    return rows


def _choices(description: str) -> list[str]:
    out, current = [], None
    for line in description.splitlines():
        if line.startswith("(choice)"):
            current = [line]
            out.append(current)
        elif current is not None and line.strip() and not line.startswith("("):
            current.append(line)
        else:
            current = None
    return [" ".join(" ".join(c).split()).replace("(choice) ", "", 1) for c in out]


def figure_page(fid: str, meta: dict | None, tree: Tree, figdir: Path | None, ledger) -> str:
    number = meta.get("number", fid) if meta else fid
    ref = meta.get("reference", "") if meta else ""
    out = [f"# {ref or fid}: {meta.get('title', '') if meta else ''}\n" if meta else f"# {fid}\n"]
    if meta:
        out.append(f"**{number}.** *{' '.join(meta.get('caption', '').split())}*\n")
    png = figdir / f"{fid}.png" if figdir else None
    if png is not None and png.is_file():
        tree.copy(png, f"{fid}.png")
        out.append(f"```{{image}} {fid}.png\n:alt: {number}\n:width: 100%\n```\n")
        table_md = figdir / "table.md"
        if table_md.is_file():
            out.append("## The table, measured\n")
            out.append(_table_body(table_md.read_text(encoding="utf-8")) + "\n")
    else:
        out.append("*This build did not draw the figure (`GNIBENCH_DOCS_GALLERY=skip`); "
                   f"`gnibench reproduce {fid} --scale quick` draws it.*\n")
    if meta:
        cells = meta.get("cells", {})
        statuses = ", ".join(f"{n} {s}" for s, n in sorted(cells.get("statuses", {}).items()))
        out.append(f"Drawn at the quick scale (`gnibench reproduce {fid} --scale quick`) from "
                   f"{cells.get('total', '?')} cells ({statuses}).\n")
        if meta.get("note"):
            out.append("## What the seed says, what we measured\n")
            out.append(" ".join(meta["note"].split()) + "\n")
        chosen = _choices(meta.get("description", ""))
        if chosen:
            out.append("## Choices where the seed is silent\n")
            out += [f"- {c}" for c in chosen]
            out.append("")
    rows = _verdict_rows(fid, ledger)
    if rows:
        out.append("## Its claims, judged by this build\n")
        out.append("`gnibench verify` at the quick scale, on the runs drawn above "
                   "({doc}`/explanation/ledger`).\n")
        out.append(table(["claim", "in our words", "verdict", "measured", "the seed says"], rows))
    return "\n".join(out)


def _table_body(text: str) -> str:
    """The Markdown table of a reproduced table (its title lines dropped)."""
    lines = text.splitlines()
    start = next((i for i, x in enumerate(lines) if x.startswith("|")), len(lines))
    return "\n".join(lines[start:])


def overview(fids: list[str], metas: dict, ledger) -> str:
    rows = []
    for fid in fids:
        meta = metas.get(fid) or {}
        counts = {}
        for c in claims_mod.by_figure().get(fid, []):
            if ledger is not None:
                hit = ledger[ledger["id"] == c["id"]]
                v = hit.iloc[0]["verdict"] if len(hit) else "not run"
            else:
                v = "not run"
            counts[v] = counts.get(v, 0) + 1
        summary = ", ".join(f"{n} {v}" for v, n in sorted(counts.items())) or "–"
        thumb = f"![{fid}](figures/{fid}.png)" if (meta.get("_drawn")) else "–"
        rows.append([thumb, f"{{doc}}`{meta.get('reference', fid)} <figures/{fid}>`",
                     cell(" ".join(meta.get("caption", "").split())[:160]), cell(summary)])
    return table(["", "figure", "caption", "claims"], rows)


def write(srcdir: Path, store: Path) -> None:
    tree = Tree(srcdir / "gallery" / "figures")
    fids = figure_ids()
    dirs, ledger = ({}, None)
    if os.environ.get("GNIBENCH_DOCS_GALLERY", "draw") != "skip":
        dirs, ledger = draw(store)
    metas = {}
    for fid in fids:
        figdir = dirs[fid] / "figure" if fid in dirs else None
        meta = None
        if figdir is not None and (figdir / "figure.json").is_file():
            meta = json.loads((figdir / "figure.json").read_text(encoding="utf-8"))
            meta["_drawn"] = (figdir / f"{fid}.png").is_file()
        metas[fid] = meta or {}
        tree.write(f"{fid}.md", figure_page(fid, meta, tree, figdir, ledger))
    tree.write("_overview.md", overview(fids, metas, ledger))
    tree.prune()
