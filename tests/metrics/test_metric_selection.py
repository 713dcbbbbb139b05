"""Choosing metrics (gnibench solve --metrics, gnibench list metrics) and the metric records'
self-description: what a metric documents is what it writes, and the README documents it."""
from __future__ import annotations

import io
import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import parse_problem
from gnibench.suite.cli.main import main
from gnibench.suite.metrics import METRICS
from gnibench.suite.metrics.compute import apply, parse_metrics

ROOT = Path(__file__).resolve().parents[2]


def _pattern(name: str) -> re.Pattern:
    """A documented name with placeholders (<I>, <X>, <k>) as a regular expression."""
    return re.compile("^" + re.sub(r"<[A-Za-z]>", "[A-Za-z0-9_]+", re.escape(name)
                                   .replace(r"\<", "<").replace(r"\>", ">")) + "$")


def _cases():
    """(metric id, trajectory) for every cell metric, where it applies."""
    T = 2 * math.pi
    periods = solve("kepler-2d", f"stormer-verlet:h={T / 100!r}", steps=1000, every=25)
    section = solve("euler-so4", "rk4:h=0.01", t_end=100.0, section=20)
    return {"invariant_error": periods, "relative_invariant_error": periods,
            "global_error": periods, "eta": periods, "precession": periods, "growth": periods,
            "section_stats": section}


def test_every_metric_writes_what_it_documents():
    cases = _cases()
    assert set(cases) == {m.id for m in METRICS.values() if m.scope == "cell"}
    for mid, traj in cases.items():
        metric = METRICS[mid]
        out = metric.compute(traj, parse_problem(traj.problem), parse_metrics([mid])[0].values)
        assert all(len(v) == len(traj.t) for v in out.columns.values())
        for kind, written in (("columns", out.columns), ("scalars", out.scalars)):
            documented = [_pattern(n) for n, _ in getattr(metric, kind)]
            for name in written:
                assert any(p.match(name) for p in documented), f"{mid}: undocumented {name}"
            for (doc_name, _), p in zip(getattr(metric, kind), documented):
                assert any(p.match(n) for n in written), f"{mid}: documents {doc_name}, not written"


def test_records_cite_the_seeds_and_the_docs_document_them():
    """Every metric cites its place in the seeds, has its formulas on the documentation's page
    "How each metric is computed", and its generated reference page names every column and
    value it writes (docs/_ext/gnibench_docs/registry.py)."""
    import sys

    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    from gnibench_docs.registry import metric_page

    explained = (ROOT / "docs" / "explanation" / "metrics.md").read_text(encoding="utf-8")
    for metric in METRICS.values():
        assert "[B]" in metric.reference or "[HLW]" in metric.reference, metric.id
        assert f"`{metric.id}`" in explained, f"docs/explanation/metrics.md does not explain {metric.id}"
        page = metric_page(metric)
        for name, _ in metric.columns + metric.scalars:
            assert f"`{name}`" in page, f"the page of {metric.id} does not document {name}"


def test_list_metrics_is_generated_from_the_records(capsys):
    assert main(["list", "metrics", "--format", "json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["id"] for r in rows] == list(METRICS)
    order = next(r for r in rows if r["id"] == "order")
    assert order["scope"] == "family" and "order_<X>" in order["scalars"]
    assert main(["list", "metrics"]) == 0
    text = capsys.readouterr().out
    assert "eta  position in the orbit" in text and "options: rtol=1e-12" in text


def test_solve_writes_the_chosen_metrics_and_says_why_one_does_not_apply(capsys):
    assert main(["solve", "kepler-2d", "stormer-verlet:h=0.06283185307179587", "--steps", "300",
                 "--every", "50", "--metrics", "eta,growth:of=H,window=0.5/1,order"]) == 0
    captured = capsys.readouterr()
    df = pd.read_csv(io.StringIO(captured.out))
    assert {"eta", "eta_phase", "envelope_H"} <= set(df.columns)
    assert np.isfinite(df["eta"]).sum() == 4                      # n = 0, 1, 2, 3
    assert captured.err.strip() == ("gnibench: metric order does not apply: order is computed "
                                    "across the cells of an experiment that differ only in h "
                                    "(gnibench run), not from one cell")
    assert main(["solve", "pendulum", "rk4:h=0.1", "--steps", "5", "--metrics", "eta"]) == 0
    assert capsys.readouterr().err.strip() == ("gnibench: metric eta does not apply: pendulum has "
                                               "no period")
    assert main(["solve", "pendulum", "rk4:h=0.1", "--steps", "5", "--metrics", "etta"]) == 2
    assert "unknown metric 'etta'; did you mean 'eta'?" in capsys.readouterr().err


def test_json_meta_carries_the_per_cell_values(capsys):
    assert main(["solve", "kepler-2d", "stormer-verlet:h=0.05", "--t-end", "10", "--format",
                 "json", "--metrics", "precession"]) == 0
    meta = json.loads(capsys.readouterr().out)["meta"]
    assert meta["metrics"]["precession_rate"] < 0                    # clockwise ([HLW] I.2.3)


@pytest.mark.parametrize("text,ids", [
    ("eta", ["eta"]),
    ("eta,growth:of=H,window=0.5/1,precession", ["eta", "growth", "precession"]),
    ("section_stats:radius=0.1,point=0/1", ["section_stats"]),
])
def test_metric_list_splitting(text, ids):
    assert [c.metric.id for c in parse_metrics(text)] == ids


def test_default_metrics_apply_without_choice():
    traj = solve("kepler-2d", "rk4:h=0.1", steps=5)
    out, skipped = apply(traj)
    assert "err_H" in out.columns and "global_error" in out.columns and not skipped
