"""``reference/ids.md``: the catalogue of public ids: problems, methods, modifiers, metrics
(links to their pages) and the shipped experiments, generated from the registries and
``suite/experiments/*.toml``."""
from __future__ import annotations

import tomllib
from pathlib import Path

from . import registry
from .common import Tree, cell, code, table

INTRO = """# Public ids

The ids below are the public names of gnibench: they are used on the command line, in
experiment files, in tables and in reports, and they do not change without a line in the
changelog. Integral names (`H`, `L`, `A1`, ...) are those of each problem's page.
"""


def experiments() -> list[dict]:
    from gnibench.suite.runs.experiment import shipped

    out = []
    for name, text in sorted(shipped().items()):
        doc = tomllib.loads(text)
        fig = doc.get("figure") or {}
        out.append({"name": name, "title": doc.get("title", ""), "reference": doc.get("reference", ""),
                    "figure": fig.get("number", ""), "cells": len(doc.get("cells", []))})
    return out


def page() -> str:
    out = [INTRO]
    for kind in registry.KINDS:
        ids = registry.ids(kind)
        prefix = "+" if kind == "modifiers" else ""
        links = ", ".join(f"[`{prefix}{i}`]({kind}/{i}.md)" for i in ids)
        out.append(f"## {registry.TITLE[kind]} ({len(ids)})\n\n{links}\n")
    rows = []
    for e in experiments():
        fig = (f"{{doc}}`{e['figure']} </gallery/figures/{e['name']}>`" if e["figure"] else "")
        rows.append([code(e["name"]), cell(e["title"]), cell(e["reference"]), fig])
    out.append(f"## Experiments ({len(rows)})\n\n`gnibench run NAME` runs one; those with a figure "
               "are also `gnibench reproduce` ids.\n")
    out.append(table(["name", "title", "source", "figure"], rows))
    return "\n".join(out)


def write(srcdir: Path) -> None:
    Tree(srcdir / "reference").write("ids.md", page())
