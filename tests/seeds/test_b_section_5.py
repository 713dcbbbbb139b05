"""[B] §5, the spatial Kepler problem: Figs 9-14 reproduced at the quick scale (files, labels, data,
one run for the figures that share cells) and the verdicts of the claims of §5 (derived from the
ledger: tests/support_figures.py, claims_of)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.ledger.entries import load_ledger
from support_figures import SECTION_FIGURES, check_figure, check_verdicts, claims_of, reused_cells

FIGURES = SECTION_FIGURES[Path(__file__).stem]
CLAIMS = claims_of(Path(__file__).stem)
PAPER_ONLY = {"B-5.2-b", "B-5.2-e", "B-5.2-h"}      # judged over 10⁵ revolutions only
#: distinct cells of the six figures: plain DOPRI, the observer on (H, c²) (Figs 9-14), the penalty,
#: Yoshida 4 on K-S (Figs 10-14), DOPRI on K-S, the observer on (H, c1, c2, c3)
DISTINCT_CELLS = 6


@pytest.fixture(scope="session")    # once per worker (pyproject: --dist loadscope, one worker)
def figures(tmp_path_factory):
    out = tmp_path_factory.mktemp("s5")
    assert main(["reproduce", *FIGURES, "--scale", "quick", "-o", str(out), "-j", "1", "--no-report"]) == 0
    return out


@pytest.mark.parametrize("name", FIGURES)
def test_figure_files_labels_and_data(figures, name):
    drawn = check_figure(figures / name)               # declared labels, curves, files
    assert (figures / name / "figure" / f"{name}.png").stat().st_size > 10_000
    assert drawn["cells"]["statuses"] == {"ok": drawn["cells"]["total"]}
    for got in drawn["panels"]:
        assert got["yscale"] == "log"                       # errors span decades
        for curve in got["curves"]:
            # quick scale: 10³ revolutions sampled every 10 (+ t = 0, off the log axes)
            assert curve["points"] >= 90, (name, curve["label"])
            assert "nan" not in curve["label"]


def test_figures_share_their_runs(figures):
    """Identical cells across b-fig-9 ... b-fig-14 are computed once (one store part per cell)."""
    assert len(list((figures / "parts").glob("*.parquet"))) == DISTINCT_CELLS


def test_captions_and_legends_use_the_seeds_symbols(figures):
    labels = {n: json.loads((figures / n / "figure" / "figure.json").read_text())
              for n in FIGURES}
    assert labels["b-fig-11"]["panels"][0]["ylabel"] == "|e₁ − e₁(0)|"
    assert labels["b-fig-12"]["panels"][0]["ylabel"].startswith("η(nT)")
    assert labels["b-fig-14"]["panels"][0]["ylabel"] == "|c₁ − c₁(0)|"
    legend = [c["label"] for c in labels["b-fig-10"]["panels"][0]["curves"]]
    assert [s[:3] for s in legend] == ["(1)", "(2)", "(3)", "(4)"]


def test_claims_are_linked_and_flagged():
    ledger = load_ledger()
    assert PAPER_ONLY <= set(CLAIMS)
    for cid in CLAIMS:
        c = ledger[cid]
        assert c.experiment in FIGURES + ["ledger-b-5"] or c.kind == "I", cid
        assert (c.scale == "paper") == (cid in PAPER_ONLY), cid
        if c.experiment in FIGURES:
            assert c.figure in FIGURES, cid


def _verify(out, capsys, scale: str) -> dict:
    code = main(["verify", *CLAIMS, "--scale", scale, "-o", str(out), "-j", "1", "--no-report",
                 "--format", "json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    if scale == "quick":
        assert reused_cells(captured.err) > 0       # the figures' cells, from the same store
    return {r["id"]: r for r in json.loads(captured.out)}


def test_claims_quick(figures, capsys):
    rows = _verify(figures, capsys, "quick")
    check_verdicts(rows, CLAIMS)
    assert rows["B-5.1-d"]["measured"] >= 1.0                 # η ~ t², err_H ~ t
    assert abs(rows["B-5.2-g"]["measured"] - 2) < 0.2         # K-S: η quadratic, not linear
    assert rows["B-5.2-c"]["measured"] > 1e3                  # max step 0.01 on K-S
    assert rows["B-5.2-d"]["measured"] > 10                   # Yoshida h = 0.095: not the same level


@pytest.mark.slow
def test_claims_paper(tmp_path, capsys):
    rows = _verify(tmp_path / "v", capsys, "paper")
    for cid in CLAIMS:
        assert rows[cid]["outcome"] == rows[cid]["expected"], (cid, rows[cid]["measured"])
