"""The README tables of the input files' keys, rendered from the schema records.

The tables of ``suite/experiments/README.md`` (experiment, groups, point sets, ensembles, scales,
figure) and
of ``README.md`` (claims) sit between ``<!-- schema: NAME -->`` and ``<!-- /schema -->`` markers
and are generated from the records (:mod:`gnibench.suite.runs.experiment_schema`,
:mod:`gnibench.suite.runs.figure_schema`, :class:`gnibench.suite.ledger.entries.Claim`);
``tests/runs/test_schema_docs.py`` fails when they differ. Regenerate them after changing a record::

    python -m gnibench.suite.cli.schema_docs            # rewrite the tables in place
    python -m gnibench.suite.cli.schema_docs --check    # exit 1 when a table is stale
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

from gnibench.suite.foundation.records import markdown_table
from gnibench.suite.ledger.entries import Claim, Value
from gnibench.suite.runs import experiment_schema as ex
from gnibench.suite.runs import figure_schema as fig

ROOT = Path(__file__).resolve().parents[2]
#: table name -> [(heading, record, key prefix)]
TABLES = {
    "experiment": [("Top level", ex.ExperimentFile, "")],
    "group": [("`[[cells]]`", ex.Group, "")],
    "points": [("`[cells.points]`", ex.Points, "points."),
               ("`circle = {...}`", ex.Circle, "circle."),
               ("`polygon = {...}`", ex.Polygon, "polygon.")],
    "ensemble": [("`[cells.ensemble]`", ex.Ensemble, "ensemble.")],
    "scales": [("`[scale.<paper|quick>]`", ex.ScaleTop, ""),
               ("`[cells.scale.<paper|quick>]`", ex.ScaleGroup, "")],
    "figure": [("`[figure]`", fig.Figure, ""), ("`[[figure.panels]]`", fig.Panel, ""),
               ("`zoom = {...}`", fig.Zoom, "zoom."),
               ("`[[figure.panels.curves]]`", fig.Curve, ""),
               ("`cells = {...}` (a curve's or a table row's cells)", fig.Select, "cells."),
               ("`[[figure.panels.fields]]`", fig.FieldLayer, ""),
               ("`[figure.table]`", fig.Table, ""), ("`columns = [{...}]`", fig.Column, ""),
               ("`[[figure.table.rows]]`", fig.Row, "")],
    "claim": [("`[[claim]]`", Claim, ""), ("`values.<name> = {...}`", Value, "")],
}
FILES = {"suite/experiments/README.md": ("experiment", "group", "points", "ensemble", "scales",
                                         "figure"),
         "README.md": ("claim",)}
_BLOCK = re.compile(r"(<!-- schema: (\w+) -->\n)(.*?)(<!-- /schema -->)", re.DOTALL)


def render(name: str) -> str:
    """The Markdown of one schema table (its records' keys, one table each)."""
    parts = []
    for heading, record, prefix in TABLES[name]:
        parts.append(f"{heading}\n\n{markdown_table(record, prefix)}")
    return "\n".join(parts)


def refreshed(text: str) -> str:
    """``text`` with every marked table replaced by its rendering."""
    return _BLOCK.sub(lambda m: m.group(1) + render(m.group(2)) + m.group(4), text)


def stale(root: Path = ROOT) -> list[str]:
    """The files whose tables differ from the records (or that lack a table)."""
    out = []
    for path, names in FILES.items():
        text = (root / path).read_text(encoding="utf-8")
        found = {m.group(2) for m in _BLOCK.finditer(text)}
        if set(names) - found or refreshed(text) != text:
            out.append(path)
    return out


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--check" in argv:
        files = stale()
        for path in files:
            print(f"{path}: schema tables differ from the records; run python -m "
                  f"gnibench.suite.cli.schema_docs", file=sys.stderr)
        return 1 if files else 0
    for path in FILES:
        file = ROOT / path
        file.write_text(refreshed(file.read_text(encoding="utf-8")), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
