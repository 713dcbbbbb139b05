"""The figures of the seeds at the quick scale: which test file reproduces each, and the check
every reproduced figure must pass (imported as ``support_figures``; tests/ is on sys.path).

Each shipped figure is reproduced once per test run, by the file of its section, in that file's
session fixture (``gnibench reproduce`` of the section's figures into one results store); the file
checks it with :func:`check_figure` and with what the section's figures must show besides. The
file's claims are verified at the quick scale in the same store, as ``gnibench verify -o DIR`` after
``gnibench reproduce -o DIR`` does: the cells of the figures are reused, not computed again.
tests/seeds/test_seed_figures.py checks that every figure of the registry has exactly one such file.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

#: test file -> the figures it reproduces at the quick scale
SECTION_FIGURES = {
    "test_b_sections_2_to_4": [f"b-fig-{k}" for k in range(1, 9)],
    "test_b_section_5": [f"b-fig-{k}" for k in range(9, 15)],
    "test_b_section_6": [f"b-fig-{k}" for k in range(15, 26)],
    "test_b_sections_7_8": [f"b-fig-{k}" for k in range(26, 33)],
    "test_hlw_chapter_1": ["hlw-fig-1.1", "hlw-fig-1.2", "hlw-fig-1.3", "hlw-fig-1.4", "hlw-fig-2.2",
                        "hlw-fig-2.3", "hlw-fig-2.4", "hlw-fig-3.1", "hlw-table-2.1"],
}


def reused_cells(stderr: str) -> int:
    """How many cells a ``verify`` or ``reproduce`` took from its store instead of computing them
    (its first line: ``N cells -> DIR (K reused from the store, M to compute)``)."""
    import re

    found = re.search(r"\((\d+) reused from the store, \d+ to compute\)", stderr)
    assert found, stderr
    return int(found.group(1))


def check_figure(results: Path, scale: str = "quick") -> dict:
    """The figure drawn from the tables in ``results`` (``<out>/<figure id>``) against the
    ``[figure]`` section of its experiment: the manifest read back from matplotlib shows the
    declared number, axis labels, scales and titles, every declared curve with data (points > 0,
    no cell missing), every panel with something drawn, the PNG and SVG files; a table has every
    row's fitted entries. Returns the manifest."""
    from gnibench.suite.runs.reproduce import load_figures

    (experiment,) = load_figures([results.name], scale)
    manifest = json.loads((results / "figure" / "figure.json").read_text())
    declared = experiment.figure
    assert manifest["id"] == experiment.name and manifest["number"] == declared["number"]
    assert manifest["scale"] == scale and manifest["complete"]
    for f in manifest["files"]:
        if f.endswith((".png", ".svg")):
            assert (results / "figure" / f).stat().st_size > 1000, f
    assert {f.rsplit(".", 1)[-1] for f in manifest["files"]} >= {"png", "svg"}
    if declared["kind"] == "table":
        table = manifest["panels"][0]["table"]
        assert len(table["rows"]) >= len(declared["table"]["rows"])
        for row in table["rows"]:
            for entry in row["measured"]:
                assert entry["zero"] or math.isfinite(entry["growth_exponent"]), (row["label"], entry)
        return manifest
    assert len(manifest["panels"]) == len(declared["panels"])
    for drawn, panel in zip(manifest["panels"], declared["panels"]):
        where = f"{experiment.name} panel {panel['title']!r}"
        assert (drawn["xlabel"], drawn["ylabel"]) == (panel["xlabel"], panel["ylabel"]), where
        assert (drawn["xscale"], drawn["yscale"]) == (panel["xscale"], panel["yscale"]), where
        assert drawn["title"] == panel["title"], where
        assert drawn["drawn"] > 0, f"{where}: nothing drawn"
        for curve in drawn["curves"]:
            assert curve["points"] > 0 and not curve["missing"], f"{where}: {curve['label']!r}"
        for field in drawn["fields"]:
            assert field["points"] > 0, f"{where}: empty field {field}"
    return manifest
