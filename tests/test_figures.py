"""Every shipped figure of the seeds, reproduced at the quick scale (registry-parametrized).

For each figure experiment (``gnibench reproduce --list``): the cells run through the runner into
a results directory, the figure is drawn, and the manifest read back from matplotlib must show the
axis labels, scales and titles declared in the experiment's ``[figure]`` section, every declared
curve with data (points > 0, no cell missing), every panel with something drawn, and the PNG and
SVG files. Table figures must have every row's fitted entries. Paper scale: ``pytest -m slow``.
"""
from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest
from gnibench.suite.runs.reproduce import figures, load_figures, run_figures

IDS = list(figures())


def _reproduce(fid: str, scale: str, out):
    from gnibench.reports.figures import draw_figure

    (experiment,) = load_figures([fid], scale)
    (results,) = run_figures([experiment], out, jobs=1, log=open(os.devnull, "w"))  # noqa: SIM115
    return experiment, draw_figure(results), results


def _check(experiment, manifest, results):
    declared = experiment.figure
    assert manifest["id"] == experiment.name and manifest["number"] == declared["number"]
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
        return
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


@pytest.mark.parametrize("fid", IDS)
def test_figure_at_quick_scale(fid, tmp_path):
    experiment, manifest, results = _reproduce(fid, "quick", tmp_path)
    _check(experiment, manifest, results)
    assert json.loads((results / "figure" / "figure.json").read_text())["scale"] == "quick"


@pytest.mark.slow
@pytest.mark.parametrize("fid", IDS)
def test_figure_at_paper_scale(fid, tmp_path):
    experiment, manifest, results = _reproduce(fid, "paper", tmp_path)
    _check(experiment, manifest, results)


def test_pieces_break_a_line_at_its_jumps():
    from gnibench.reports.figures.plot import _pieces

    t = np.linspace(0.0, 1.0, 101)
    x = np.concatenate([t, t + 5.0, t])                 # two jumps of 4 and 6 (steps of 0.01)
    xs, _, origins = _pieces(x, np.zeros_like(x))
    assert origins == [0, 102, 204] and np.isnan(xs[[101, 203]]).all()
    assert xs[origins].tolist() == [0.0, 5.0, 0.0]


def test_domain_field_is_the_octagon():
    """min_k g_k of geodesic-genus2's sides ([B] §8.1): positive inside Ω, zero on a side (the
    circle of centre C e_0, radius sqrt(C² − 1), crosses the q1 axis at C − sqrt(C² − 1)),
    negative beyond it."""
    from gnibench.suite.runs.figure_fields import evaluate, parse_field

    field = parse_field({"problem": "geodesic-genus2", "function": "domain", "x": "q1",
                         "y": "q2", "xrange": [-1, 1], "yrange": [-1, 1]}, "test")
    assert field["levels"] == [0.0]
    from gnibench.problems.geodesic_genus2 import _side_constants

    c = float(_side_constants()[3])
    edge = c - math.sqrt(c * c - 1)
    v = evaluate(field, np.array([0.0, edge, edge + 0.01]), np.zeros(3))
    assert v[0] > 0 and abs(v[1]) < 1e-12 and v[2] < 0


def test_redraw_uses_the_tables_and_refuses_stale_ones(tmp_path, capsys, monkeypatch):
    """`reproduce ID --redraw` draws again from the tables (no integration: the store may be
    gone) with the figure section as it is now; when the file's cells changed it refuses."""
    import shutil

    from gnibench.suite.cli.main import main
    from gnibench.suite.runs import experiment

    assert main(["reproduce", "hlw-fig-1.4", "--scale", "quick", "-o", str(tmp_path), "-j", "1",
                 "--no-report"]) == 0
    png = tmp_path / "hlw-fig-1.4" / "figure" / "hlw-fig-1.4.png"
    png.unlink()
    shutil.rmtree(tmp_path / "parts")
    assert main(["reproduce", "hlw-fig-1.4", "--redraw", "-o", str(tmp_path), "--no-report"]) == 0
    assert png.stat().st_size > 1000 and not (tmp_path / "parts").exists()
    text = experiment.shipped()["hlw-fig-1.4"]
    monkeypatch.setattr(experiment, "shipped", lambda: {"hlw-fig-1.4": text.replace(
        "h=0.3", "h=0.25")})
    capsys.readouterr()
    assert main(["reproduce", "hlw-fig-1.4", "--redraw", "-o", str(tmp_path)]) == 2
    assert "the cells of the file changed" in capsys.readouterr().err
