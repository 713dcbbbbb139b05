"""[B] §6, the Gavrilov–Shil'nikov system: Figs 15-25 reproduced at the quick scale (files, labels,
data) and the verdicts of the §6 claims at the quick scale (derived from the ledger:
tests/support_figures.py, claims_of)."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from support_figures import SECTION_FIGURES, check_figure, check_verdicts, claims_of, paper_only, reused_cells

FIGURES = SECTION_FIGURES[Path(__file__).stem]
CLAIMS = claims_of(Path(__file__).stem)


def _gnibench(*args):
    return subprocess.run([sys.executable, "-m", "gnibench.suite.cli.main", *args],
                          check=False, capture_output=True, text=True)


@pytest.fixture(scope="session")    # once per worker (pyproject: --dist loadscope, one worker)
def reproduced(tmp_path_factory):
    out = tmp_path_factory.mktemp("s6")
    r = _gnibench("reproduce", *FIGURES, "--scale", "quick", "-o", str(out), "-j", "1", "--no-report")
    assert r.returncode == 0, r.stderr
    return out


@pytest.mark.parametrize("fid", FIGURES)
def test_figure_files_labels_and_data(reproduced, fid):
    manifest = check_figure(reproduced / fid)          # declared labels, curves, files
    assert (reproduced / fid / "figure" / f"{fid}.png").stat().st_size > 10_000
    panels = manifest["panels"]
    if fid == "b-fig-15":
        assert [p["xlabel"] for p in panels] == ["r", "r"]
        assert all(p["ylabel"] == "P" for p in panels)
        assert all(f["points"] > 100 for p in panels for f in p["fields"])
        return
    assert all((p["xlabel"], p["ylabel"]) == ("q₂", "p₂") for p in panels)
    curves = [c for p in panels for c in p["curves"]]
    assert curves and all(c["points"] > 0 for c in curves)
    assert panels[0]["fields"][0]["levels"] == [0.0]
    zooms = [p for p in panels if p["zoom_of"] is not None]
    assert all(p["zoom_of"] == 0 for p in zooms)


def test_sections_are_on_the_plane(reproduced):
    s = pd.read_parquet(reproduced / "b-fig-16" / "samples.parquet")
    assert len(s) == 500 and s["p1"].abs().max() < 1e-14 and (s["p2"] > 0).all()
    # Fig 17 is a zoom of Fig 16's run: the same cell, computed once
    c16 = pd.read_parquet(reproduced / "b-fig-16" / "cells.parquet")
    c17 = pd.read_parquet(reproduced / "b-fig-17" / "cells.parquet")
    assert list(c16["method"]) == list(c17["method"])


def test_claims_quick_verdicts(reproduced):
    """Every §6 claim has its expected outcome at the quick scale (the paper-only ones skipped;
    the observer runs that stop near the equilibrium: not measured, as expected)."""
    r = _gnibench("verify", *CLAIMS, "--scale", "quick", "-o", str(reproduced), "-j", "1",
                  "--no-report", "--format", "json")
    assert r.returncode == 0, r.stderr
    assert reused_cells(r.stderr) > 0               # the figures' cells, from the same store
    rows = {row["id"]: row for row in json.loads(r.stdout)}
    check_verdicts(rows, CLAIMS)
    assert paper_only(CLAIMS) == {"B-6.2-b", "B-6.2-c", "B-6.2-k", "B-6.2-p"}
    ledger = pd.read_parquet(reproduced / "ledger.parquet").set_index("id")
    assert [ledger.loc[i, "outcome"] for i in ("B-6.2-h", "B-6.2-i", "B-6.2-o")] == \
        ["not measured"] * 3
