"""Every column that a run writes is described on the documentation's page of the tables
(docs/reference/tables.md) or by the metric that writes it (its record's columns and values)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

import gnibench

PAGE = Path(__file__).resolve().parents[2] / "docs" / "reference" / "tables.md"


def _section(name: str) -> str:
    text = PAGE.read_text(encoding="utf-8")
    return text.split(f"## `{name}`", 1)[1].split("\n## ", 1)[0]


def _patterns(names) -> list[re.Pattern]:
    out = []
    for name in names:
        rx = re.escape(name).replace(re.escape("<I>"), r"\w+").replace(re.escape("<X>"), r"\w+")
        out.append(re.compile(rx + r"\Z"))
    return out


def _described(table: str) -> list[re.Pattern]:
    rows = [line for line in _section(table).splitlines() if line.startswith("| ")]
    names = [n for row in rows for n in re.findall(r"`([^`]+)`", row.split(" | ")[0])]
    return _patterns(names)


def _metric_names(kind: str) -> list[re.Pattern]:
    return _patterns(k for d in gnibench.list_metrics()[kind] for k in (d or {}))


@pytest.fixture(scope="module")
def run():
    return gnibench.run({
        "name": "columns", "title": "every kind of column", "reference": "tests",
        "t_end": 2.0,
        "cells": [{"problems": ["kepler-2d"], "methods": ["rk4", "rk4+observer:on=H/L"],
                   "vary": {"h": [0.1, 0.05]},
                   "metrics": ["growth:of=H/global", "order", "precession", "relative_invariant_error"]},
                  {"problems": ["kepler-2d"], "methods": ["dop853:rtol=1e-8,atol=1e-8"]},
                  {"problems": ["henon-heiles"], "methods": ["rk4:h=0.05"], "section": 3,
                   "t_end": 200.0, "metrics": ["section_stats"]}],
    }, jobs=1)


@pytest.mark.parametrize("table, metric_kind", [("samples", "columns"), ("cells", "scalars"),
                                                ("timings", None)])
def test_every_column_is_described(run, table, metric_kind):
    known = _described(f"{table}.parquet")
    if metric_kind:
        known += _metric_names(metric_kind)
    states = {s for st in gnibench.list_problems()["state"] for s in st}
    columns = list(getattr(run, table).columns)
    undescribed = [c for c in columns
                   if c not in states and not any(p.match(c) for p in known)]
    assert undescribed == [], f"{table}: columns not described on {PAGE.name}: {undescribed}"


def test_a_column_that_is_not_described_is_found(run):
    known = _described("cells.parquet")
    assert not any(p.match("a_new_column") for p in known)
    assert any(p.match("max_abs_err_H") for p in known)
