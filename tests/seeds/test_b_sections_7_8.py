"""[B] §7-§8 figures (b-fig-26 ... b-fig-32) and claims (B-7.2-*, B-8.2-a, B-X-*) at the quick
scale: the figures are drawn with their declared labels and data, the claims get their expected
verdicts; the curve option ``where`` of the figure schema."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from gnibench.reports.figures.plot import LINE, pixel_size
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger.closed_forms_b7 import so4_growth, so4_overlap, so4_plateau
from gnibench.suite.ledger.entries import load_ledger, missing_parts
from support_figures import SECTION_FIGURES, check_figure, check_verdicts, claims_of, paper_only, reused_cells

AXES = {"b-fig-26": ("x₅", "x₆"), "b-fig-27": ("t", "|H3 − H3(x₀)|"),
           "b-fig-28": ("t", "|H1 − H1(x₀)|"), "b-fig-29": ("t", "|H2 − H2(x₀)|"),
           "b-fig-30": ("t", "|Hi − Hi(x₀)|"), "b-fig-31": ("q₁", "q₂"), "b-fig-32": ("t", "|H − H0|")}
FIGURES = SECTION_FIGURES[Path(__file__).stem]
CLAIMS = claims_of(Path(__file__).stem)


@pytest.fixture(scope="session")    # once per worker (pyproject: --dist loadscope, one worker)
def figures(tmp_path_factory):
    out = tmp_path_factory.mktemp("s78")
    assert main(["reproduce", *FIGURES, "--scale", "quick", "-o", str(out), "-j", "1", "--no-report"]) == 0
    return out


def _manifest(root, name):
    return json.loads((root / name / "figure" / "figure.json").read_text())


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_figure_files_labels_and_data(figures, name):
    m = check_figure(figures / name)                   # declared labels, curves, files
    assert (figures / name / "figure" / f"{name}.png").stat().st_size > 10_000
    assert m["number"] == f"Fig {name.split('-')[-1]}"
    for panel in m["panels"]:
        assert (panel["xlabel"], panel["ylabel"]) == AXES[name]
        if panel["xlabel"] == "t":
            assert panel["yscale"] == "log"
        for curve in panel["curves"]:
            assert curve["points"] > 0 and curve["statuses"] == ["ok"], curve


def test_figs_26_to_29_share_their_two_runs(figures):
    cells = [pd.read_parquet(figures / f"b-fig-{k}" / "cells.parquet") for k in (26, 27, 28, 29)]
    for c in cells[1:]:
        assert c[["problem", "method", "t_end", "section"]].equals(
            cells[0][["problem", "method", "t_end", "section"]])
    assert "lie-poisson:h=0.0025" in cells[0]["method"][1]


def test_fig_26_draws_the_points_of_chart_1_only(figures):
    m = _manifest(figures, "b-fig-26")
    cells = pd.read_parquet(figures / "b-fig-26" / "cells.parquet")
    for panel, cell in zip(m["panels"], (0, 1)):
        (curve,) = panel["curves"]
        assert curve["where"] == {"chart": 1.0} and curve["style"] == "pixels"
        n = int(cells["section_points_chart1"][cell])
        assert curve["points"] == n < int(cells["section_points"][cell])  # not thinned, filtered
        assert f"{n} points in Γ1" in curve["label"]
        # a quick-scale cloud (thousands of crossings, not the seed's 140 000) is drawn larger
        assert curve["markersize"] == pixel_size(n) > LINE["pixels"]["markersize"]


def test_fig_31_records_its_random_start(figures):
    m = _manifest(figures, "b-fig-31")
    assert "default_rng(31)" in m["description"] and "default_rng(31)" in m["note"]
    rng = np.random.default_rng(31)
    u = rng.random(3)
    q = 0.6 * np.sqrt(u[0]) * np.array([np.cos(2 * np.pi * u[1]), np.sin(2 * np.pi * u[1])])
    cells = pd.read_parquet(figures / "b-fig-31" / "cells.parquet")
    spec = cells["problem"][0]
    assert f"q10={q[0]:.5f}" in spec and f"q20={q[1]:.6f}" in spec
    assert f"angle={2 * np.pi * u[2]:.6f}" in spec


def test_claims_have_their_expected_verdicts_at_quick_scale(figures, capsys):
    code = main(["verify", *CLAIMS, "--scale", "quick", "-o", str(figures), "-j", "1", "--no-report",
                 "--format", "json"])
    captured = capsys.readouterr()
    assert reused_cells(captured.err) > 0           # the figures' cells, from the same store
    rows = {r["id"]: r for r in json.loads(captured.out)}
    assert paper_only(CLAIMS) == {"B-7.2-a", "B-7.2-b", "B-7.2-c", "B-8.2-a"}
    check_verdicts(rows, CLAIMS)
    assert rows["B-7.2-d"]["measured"] >= 10 and rows["B-7.2-h"]["measured"] < 1
    # a method swap: not checkable, our Casimir-exact splitting's errors shown as a side result
    assert rows["B-7.2-e"]["verdict"] == "not checkable" and "side result" in rows["B-7.2-e"]["measured"]
    for i in ("B-X-a", "B-X-b"):                           # aggregates over §4-§8
        assert rows[i]["verdict"] == rows[i]["expected"] == "partly", rows[i]
    assert code == 0


def test_aggregate_parts_exist_or_are_written_elsewhere():
    assert not missing_parts(load_ledger())


def test_so4_statistics_on_synthetic_traces():
    t = np.linspace(1.0, 1000.0, 4000)
    rng = np.random.default_rng(0)
    x5, x6 = rng.uniform(-1, 1, (2, 4000))
    samples = pd.DataFrame({"cell": np.repeat([0, 1], 2000), "t": np.tile(t[:2000], 2),
                            "chart": 1, "x5": x5, "x6": x6,
                            "err_H1": 1e-6 + 1e-8 * np.sin(np.arange(4000)),
                            "err_H2": 1e-13 * np.sqrt(np.tile(t[:2000], 2))})
    cells = pd.DataFrame({"cell": [0, 1]})
    same = so4_overlap(cells, samples.assign(x5=np.tile(x5[:2000], 2), x6=np.tile(x6[:2000], 2)))
    assert same["jaccard"] == 1.0 and same["points_0"] == same["points_1"] == 2000
    apart = so4_overlap(cells, samples.assign(x5=np.where(samples.cell == 0, x5, x5 + 5)))
    assert apart["jaccard"] == 0.0
    plateau = so4_plateau(cells.iloc[:1], samples[samples.cell == 0].drop(columns="err_H2"))
    assert plateau["drift"] < 0.1 and plateau["mean_over_std"] > 50
    growth = so4_growth(cells.iloc[:1], samples[samples.cell == 0].assign(
        err_H1=lambda d: d["t"] ** 1.0))
    assert abs(growth["exponent_H1"] - 1) < 1e-9 and abs(growth["exponent_H2"] - 0.5) < 1e-6


def _figure_doc(where):
    return ('name = "w"\ntitle = "w"\nreference = "[B] §7.2"\nt_end = 10.0\nsection = 5\n'
            '[[cells]]\nproblems = ["euler-so4"]\nmethods = ["lie-poisson:h=0.01"]\n'
            '[figure]\nnumber = "Fig 0"\ncaption = "c"\n[[figure.panels]]\nx = "x5"\ny = "x6"\n'
            f'[[figure.panels.curves]]\ncells = {{ group = 0 }}\nwhere = {where}\n')


def test_where_is_validated(tmp_path):
    from gnibench.suite.runs.experiment import load_experiment

    ok = tmp_path / "ok.toml"
    ok.write_text(_figure_doc("{ chart = 1 }"), encoding="utf-8")
    exp = load_experiment(str(ok))
    assert exp.figure["panels"][0]["curves"][0]["where"] == {"chart": 1.0}
    for bad, why in (("{ nope = 1 }", "not a column"), ("{ chart = 'one' }", "finite number"),
                     ("1", "allowed: a table")):
        path = tmp_path / "bad.toml"
        path.write_text(_figure_doc(bad), encoding="utf-8")
        with pytest.raises(UserError, match=why):
            load_experiment(str(path))
