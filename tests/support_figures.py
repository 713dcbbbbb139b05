"""The figures and claims of the seeds at the quick scale: which test file reproduces each figure
and verifies each claim, and the check every reproduced figure must pass (imported as
``support_figures``; tests/ is on sys.path).

Each shipped figure is reproduced once per test run, by the file of its section, in that file's
session fixture (``gnibench reproduce`` of the section's figures into one results store); the file
checks it with :func:`check_figure` and with what the section's figures must show besides. The
file's claims are verified at the quick scale in the same store, as ``gnibench verify -o DIR`` after
``gnibench reproduce -o DIR`` does: the cells of the figures are reused, not computed again.

The claims of a file are derived from the ledger (suite/claims/*.toml), never listed by hand
(:func:`claim_file`): a claim goes to the file of its ``figure``, else of its ``experiment`` when
that is a figure, else to the file of its section (the number after the seed in its id:
``B-4.1-a`` -> §4, ``HLW-...`` -> [HLW]). A claim stated at the paper scale only (``scale =
"paper"``) is verified there as ``skipped`` and at the paper scale by the file's ``slow`` test.
tests/seeds/test_seed_figures.py checks that every figure and every claim has exactly one file.
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


#: test file -> the seed and its sections whose claims the file verifies (beside its figures')
SECTION_CLAIMS = {
    "test_b_sections_2_to_4": ("B", ("2", "3", "4")),
    "test_b_section_5": ("B", ("5",)),
    "test_b_section_6": ("B", ("6",)),
    "test_b_sections_7_8": ("B", ("7", "8", "X")),
    "test_hlw_chapter_1": ("HLW", None),                 # every section of [HLW]
}


def claim_file(claim) -> list[str]:
    """The seed test files that verify a claim (a ledger entry): exactly one for every claim of
    the ledger (tests/seeds/test_seed_figures.py)."""
    for link in (claim.figure, claim.experiment):
        files = [f for f, ids in SECTION_FIGURES.items() if link and link in ids]
        if files:
            return files
    seed, _, rest = claim.id.partition("-")
    section = rest.split("-")[0].split(".")[0]
    return [f for f, (s, sections) in SECTION_CLAIMS.items()
            if s == seed and (sections is None or section in sections)]


def claims_of(test_file: str) -> list[str]:
    """The claims a seed test file verifies, in ledger order (its paper-only ones included:
    skipped at the quick scale)."""
    from gnibench.suite.ledger.entries import load_ledger

    return [c.id for c in load_ledger().values() if claim_file(c) == [test_file]]


def paper_only(ids: list[str]) -> set[str]:
    """The claims among ``ids`` stated at the paper scale only (``scale = "paper"``)."""
    from gnibench.suite.ledger.entries import load_ledger

    ledger = load_ledger()
    return {i for i in ids if ledger[i].scale == "paper"}


def check_verdicts(rows: dict, ids: list[str]) -> None:
    """Every claim verified at the quick scale has its expected outcome; a paper-only one is
    skipped (``rows``: the JSON rows of ``gnibench verify --format json``, by id)."""
    assert set(rows) >= set(ids), sorted(set(ids) - set(rows))
    skipped = paper_only(ids)
    for cid in ids:
        r = rows[cid]
        if cid in skipped:
            assert r["verdict"] == "skipped", (cid, r["verdict"])
        else:
            assert r["outcome"] == r["expected"], (cid, r["verdict"], r["measured"], r["detail"])


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
