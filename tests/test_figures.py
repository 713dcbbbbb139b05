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
