"""The key tables of the input files (experiments, figures, claims), rendered from the schema
records.

The documentation's reference page "Experiment files" (``docs/reference/input-files.md``) shows
them through its ``gnibench-schema`` directive, which calls :func:`render` when the documentation
builds, so the tables are never copied by hand and cannot disagree with the records
(:mod:`gnibench.suite.runs.experiment_schema`, :mod:`gnibench.suite.runs.figure_schema`,
:class:`gnibench.suite.ledger.entries.Claim`). ``tests/runs/test_schema_docs.py`` checks that the
page shows every table and that every key of every record is in its table. Print them::

    python -m gnibench.suite.cli.schema_docs            # every table, as Markdown
    python -m gnibench.suite.cli.schema_docs claim      # one
"""
from __future__ import annotations

import sys

from gnibench.suite.foundation.records import markdown_table
from gnibench.suite.ledger.entries import Claim, Value
from gnibench.suite.runs import experiment_schema as ex
from gnibench.suite.runs import figure_schema as fig

#: table name -> [(heading, record, key prefix)]
TABLES = {
    "experiment": [("Top level", ex.ExperimentFile, "")],
    "group": [("`[[cells]]`", ex.Group, "")],
    "points": [("`[cells.points]`", ex.Points, "points."),
               ("`circle = {...}`", ex.Circle, "circle."),
               ("`polygon = {...}`", ex.Polygon, "polygon.")],
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
def render(name: str) -> str:
    """The Markdown of one schema table (its records' keys, one table each)."""
    parts = []
    for heading, record, prefix in TABLES[name]:
        parts.append(f"{heading}\n\n{markdown_table(record, prefix)}")
    return "\n".join(parts)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    names = argv or list(TABLES)
    unknown = [n for n in names if n not in TABLES]
    if unknown:
        print(f"unknown table {unknown[0]!r}; allowed: {', '.join(TABLES)}", file=sys.stderr)
        return 2
    for name in names:
        print(f"<!-- {name} -->\n{render(name)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
