"""Reports: the site and its Markdown twin from result tables, escaping of every user or file string,
league tables, method families, the reproduced-figure manifest, the command line."""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pandas as pd
import pytest
from gnibench.reports.league import cost_to_reach, league
from gnibench.reports.pages import split_description
from gnibench.reports.results import load_manifest
from gnibench.reports.site import build_site
from gnibench.suite.cli.main import main
from support_reports import HOSTILE_REASON, make_results, png_bytes


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    root = tmp_path_factory.mktemp("reports")
    with pytest.MonkeyPatch.context() as mp:
        return make_results(root, mp)


@pytest.fixture(scope="module")
def site(results, tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    build_site([results], out, thresholds=(1e-3, 1e-6))
    return out


def test_site_files_and_images(site):
    for name in ("index.html", "index.md", "hostile.html", "hostile.md"):
        assert (site / name).is_file(), name
    html = (site / "hostile.html").read_text()
    for src in re.findall(r'<img src="([^"]+)"', html):
        assert (site / src).is_file(), src
    assert "img/hostile/figure/fig.png" in html                # the reproduced figure
    md = (site / "hostile.md").read_text()
    for src in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md):
        assert (site / src).is_file(), src
    assert "Work-precision diagrams" in html and "League tables" in html


def test_html_escapes_every_user_string(site):
    html = (site / "hostile.html").read_text()
    # the only scripts: plotly.js, the diagrams' JSON (no markup can end it) and the few lines
    # that hand the JSON to plotly
    scripts = re.findall(r"<script[^>]*>", html)
    assert scripts and set(scripts) <= {'<script src="assets/plotly.min.js">', "<script>"} | {
        s for s in scripts if re.fullmatch(r'<script type="application/json" id="wp-[\w.-]+">', s)}
    for data in re.findall(r'<script type="application/json"[^>]*>(.*?)</script>', html, re.S):
        assert "<" not in data and ">" not in data and "&" not in data
        assert json.loads(data)["data"]
    assert html.count("<script>") == 1 and "Plotly.newPlot" in html
    assert "<img src=x" not in html and "<b>label</b>" not in html and "<em>markup" not in html
    assert "&lt;script&gt;alert(&#39;t&#39;)&lt;/script&gt;" in html
    assert "&lt;img src=x onerror=alert(1)&gt;" in html           # the failed cell's reason
    assert "Caption &lt;script&gt;x&lt;/script&gt;" in html
    index = (site / "index.html").read_text()
    assert "<script" not in index and "&lt;script&gt;" in index


def test_markdown_escapes_every_user_string(site):
    md = (site / "hostile.md").read_text()
    body = md.split("```")[0]                                     # before the TOML fence
    headings = [line for line in body.splitlines() if line.startswith("#")]
    assert all(line.startswith(("# &lt;script", "## ", "### ")) for line in headings), headings
    assert not any("Fake heading" in h for h in headings)
    head = md.split("Experiment file (")[0]                       # the TOML text is in a fence
    for raw in ("<script", "<img", "<b>", "<em>"):
        assert raw not in head, raw
    assert "| fake | table |" not in head and "\\|---\\|---\\|" in head
    assert "&lt;img src=x onerror=alert(1)&gt; \\| # boom" in md
    # table rows: every line of a table has as many unescaped | as its header
    for block in re.findall(r"(\| cell \|.*?)\n\n", md, flags=re.DOTALL):
        lines = block.splitlines()
        widths = {len(re.findall(r"(?<!\\)\|", line)) for line in lines}
        assert len(widths) == 1, lines
    # the TOML text sits in a fence longer than any backtick run inside it
    fence = re.search(r"^(`{3,})toml$", md, flags=re.MULTILINE).group(1)
    assert len(fence) == 5 and md.count(fence) == 2


def test_experiment_page_content(site):
    html = (site / "hostile.html").read_text()
    assert "(choice)</span> A choice with &lt;em&gt;markup" in html
    assert "(reading)</span> A reading." in html
    assert "[HLW] Fig 2.3" in html and "note | # one" in html
    assert "RuntimeError" in html and "error" in html
    for package in ("numpy", "numba", "gnibench"):
        assert f"<td>{package}</td>" in html
    assert "dopri5" in html and "ε = 1e-03" in html


def test_description_split():
    paragraphs, notes = split_description("a\nb\n\nc\n(choice) one\ncontinued\n(reading) two\n\nd")
    assert paragraphs == ["a b", "c", "d"]
    assert notes == [{"kind": "choice", "text": "one continued"}, {"kind": "reading", "text": "two"}]


def test_cost_to_reach():
    costs, ids = np.array([100.0, 1000.0, 10000.0]), np.array([0, 1, 2])
    errors = np.array([1e-2, 1e-4, 1e-6])
    c = cost_to_reach(costs, errors, ids, 1e-5)               # halfway in log between 1e-4 and 1e-6
    assert c.how == "interpolated" and c.cells == (1, 2) and math.isclose(c.value, 10 ** 3.5)
    c = cost_to_reach(costs, errors, ids, 1e-1)
    assert c.how == "bound" and c.value == 100.0 and c.cells == (0,)
    assert cost_to_reach(costs, errors, ids, 1e-9).how == "not reached"
    assert cost_to_reach(np.full(3, np.nan), errors, ids, 1e-5).how == "–"
    # a plateau (round-off) after the first hit does not move the cost
    c = cost_to_reach(costs, np.array([1e-2, 1e-7, 1e-6]), ids, 1e-5)
    assert c.cells == (0, 1) and 100 < c.value < 1000


def test_league_ranks_ties_and_failures():
    cells = pd.DataFrame({
        "cell": range(7), "family": ["a", "a", "b", "b", "c", "d", "d"],
        "setup": [0, 0, 2, 2, 4, 5, 5], "swept": "rtol",
        "status": ["ok", "ok", "ok", "ok", "nonfinite", "ok", "ok"],
        "reason": ["", "", "", "", "overflow", "", ""],
        "nfev": [100.0, 1000, 100, 1000, 50, np.nan, np.nan],
        "max_global_error": [1e-2, 1e-6, 1e-2, 1e-6, np.inf, 1e-3, 1e-9]})
    wall = {0: 1e-3, 1: 1e-2, 2: 2e-3, 3: 2e-2, 4: 1e-4, 5: 1e-4, 6: 2e-4}
    rows = {r.family: r for r in league(cells, wall, 1e-5)}
    assert {r.family for r in league(cells, wall, 1e-5, names={0: "a (T = 1)"})} == \
        {"a (T = 1)", "b", "c", "d"}
    assert rows["a"].rank_nfev == rows["b"].rank_nfev == 1          # a tie shares the rank
    assert rows["a"].rank_wall == 2 and rows["b"].rank_wall == 3
    assert rows["d"].rank_nfev is None and rows["d"].rank_wall == 1  # no nfev: wall time only
    assert rows["c"].nfev.how == "not reached" and rows["c"].failed == [(4, "nonfinite", "overflow")]
    assert [r.family for r in league(cells, wall, 1e-5)][-1] == "c"


def test_manifest_refuses_files_outside(tmp_path):
    fig = tmp_path / "figure"
    fig.mkdir()
    (fig / "a.png").write_bytes(png_bytes())
    (tmp_path / "secret.png").write_bytes(png_bytes())
    for files, message in ((["../secret.png"], "outside"), (["/etc/passwd"], "outside"),
                           (["missing.png"], "does not exist"), (["figure.json"], "not a PNG")):
        (fig / "figure.json").write_text(json.dumps({"caption": "c", "files": files}))
        with pytest.raises(ValueError, match=message):
            load_manifest(fig)
    (fig / "figure.json").write_text(json.dumps({"caption": "c", "files": ["a.png"], "notes": "n"}))
    assert load_manifest(fig)["images"] == ["a.png"] and load_manifest(fig)["notes"] == ["n"]


@pytest.mark.parametrize("label, want", [
    ("fit $t^{0.24}$", "fit t^0.24"),                       # [B] Fig 10's legend
    (r"$\mu = p_\varphi = 1$", "μ = p_φ = 1"),
    ("$|y_n - y(t_n)|$", "|yₙ - y(tₙ)|"),
    (r"$A,\ \Phi_h(A),\ \Phi_h^2(A)$", "A, Φₕ(A), Φₕ²(A)"),   # [HLW] Fig 1.1
    (r"$\varphi_{2t}(A)$", "φ₂ₜ(A)"),
    ("no math: t^2 {kept}", "no math: t^2 {kept}"),
])
def test_the_pages_show_mathtext_labels_as_plain_text(tmp_path, label, want):
    """The HTML and Markdown pages do not render TeX: a panel's title, axis labels and curve
    labels in mathtext (drawn by matplotlib in the PNG) are written as Unicode there."""
    fig = tmp_path / "figure"
    fig.mkdir()
    (fig / "a.png").write_bytes(png_bytes())
    (fig / "figure.json").write_text(json.dumps({"caption": "c", "files": ["a.png"], "panels": [
        {"id": "p", "title": label, "xlabel": "t", "ylabel": label, "curves": [{"label": label}]}]}))
    panel = load_manifest(fig)["panels"][0]
    assert panel["title"] == panel["ylabel"] == want and panel["curves"] == [want]


def test_the_pages_list_only_labelled_curves(tmp_path):
    """[HLW] Fig 1.1's panels draw the cat's eyes as curves without a label: the page's list of
    curves read "A, φₜ(A), φ₂ₜ(A), φ₃ₜ(A), ," before."""
    fig = tmp_path / "figure"
    fig.mkdir()
    (fig / "a.png").write_bytes(png_bytes())
    (fig / "figure.json").write_text(json.dumps({"caption": "c", "files": ["a.png"], "panels": [
        {"id": "p", "curves": [{"label": "A"}, {"label": ""}, {}, {"label": " "}, "B"]}]}))
    assert load_manifest(fig)["panels"][0]["curves"] == ["A", "B"]


def test_bad_manifest_is_reported_on_the_page(results, tmp_path):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(results, copy)
    (copy / "figure" / "figure.json").write_text('{"files": ["../../x.png"]}')
    build_site([copy], tmp_path / "site")
    html = (tmp_path / "site" / "hostile.html").read_text()
    assert "figure/figure.json could not be used: file &#39;../../x.png&#39; lies outside" in html


def test_cli_report_and_errors(results, tmp_path, capsys):
    out = tmp_path / "s"
    assert main(["report", str(results), "-o", str(out), "--accuracy", "1e-2"]) == 0
    assert "ε = 1e-02" in (out / "hostile.html").read_text()
    assert main(["report", str(tmp_path / "nothing")]) == 2
    assert "no results directory" in capsys.readouterr().err
    assert main(["report", str(results), "-o", str(out), "--accuracy", "x"]) == 2
    assert "bad --accuracy" in capsys.readouterr().err
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["report", str(empty)]) == 2
    assert "holds no results" in capsys.readouterr().err


def test_reason_reaches_the_markdown_table_escaped(site):
    md = (site / "hostile.md").read_text()
    assert HOSTILE_REASON not in md


def test_run_writes_the_report_unless_told_not(tmp_path, capsys):
    path = tmp_path / "t.toml"
    path.write_text('name = "t"\ntitle = "T"\nreference = "r"\nsteps = 5\n'
                    '[[cells]]\nproblems = ["pendulum"]\nmethods = ["euler"]\nvary.h = [0.1, 0.05]\n')
    assert main(["run", str(path), "-o", str(tmp_path / "a"), "-j", "1"]) == 0
    assert (tmp_path / "a" / "report" / "index.html").is_file()
    assert (tmp_path / "a" / "report" / "t.md").is_file() and (tmp_path / "a" / "summary.md").is_file()
    assert main(["run", str(path), "-o", str(tmp_path / "b"), "-j", "1", "--no-report"]) == 0
    assert (tmp_path / "b" / "summary.md").is_file() and not (tmp_path / "b" / "report").exists()


def test_tiny_work_precision_with_competitors(tmp_path):
    """A tiny variant of wp-kepler-2d: adaptive, heyoka and IAS15 sweeps in one run; the engines
    that count no f-evaluations are drawn against wall time only, and the page says so."""
    from gnibench.suite.runs.runner import run_experiment

    path = tmp_path / "wp.toml"
    path.write_text('name = "wp-tiny"\ntitle = "tiny wp"\nreference = "r"\n'
                    't_end = 6.283185307179586\nevery = 1000\n'
                    '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["dop853:atol=1e-14"]\n'
                    'vary.rtol = [1e-6, 1e-9]\n'
                    '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["heyoka-taylor:dt_out=3.14"]\n'
                    'vary.tol = [1e-9, 1e-15]\n'
                    '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["rebound-ias15:dt_out=3.14"]\n'
                    'vary.epsilon = [1e-4, 1e-9]\n')
    out = run_experiment(path, tmp_path / "out", jobs=1, log=open("/dev/null", "w"))  # noqa: SIM115
    build_site([out], tmp_path / "site", thresholds=(1e-6,))
    html = (tmp_path / "site" / "wp-tiny.html").read_text()
    assert "heyoka-taylor, rebound-ias15 do not count f-evaluations" in html
    assert "wp-tiny/00-kepler-2d_e_0.6-work-precision.png" in html
    rows = re.findall(r"<tr>\s*<td>([^<]*)</td><td><code>([^<]*)</code></td>", html)
    ranks = {fam: rank for rank, fam in rows}
    assert ranks["dop853"] == "1" and ranks["heyoka-taylor"] == "–" and ranks["rebound-ias15"] == "–"


def test_index_card_names_problems_briefly():
    """The index card: a short spec as it is, a long one by its id, several specs of one problem
    by the id and their number (the experiment page lists them all)."""
    from gnibench.reports.pages import short_problems
    from gnibench.reports.plots import BRIEF, brief

    long = "kepler-3d:mu=39.47841760435743,a=1,e=0.8,i=0.7853981633974483"
    assert len(long) > BRIEF
    def cells(problems):
        return pd.DataFrame({"problem": problems,
                             "problem_id": [p.partition(":")[0] for p in problems]})

    assert short_problems(cells(["kepler-2d:e=0.6", "kepler-2d:e=0.6", long])) == [
        "kepler-2d:e=0.6", "kepler-3d"]
    assert short_problems(cells(["lotka-volterra:u0=2,v0=2", "lotka-volterra:u0=4,v0=8",
                                 "pendulum"])) == ["lotka-volterra (2 parameter sets)", "pendulum"]
    label = "a-problem-with-a-long-id-and-many-starts (12 initial values)"
    assert brief(label, None) == label[:BRIEF - 1] + "…"


def test_every_registered_method_has_its_own_colour():
    """The methods of one work-precision diagram (all the registered ones) get distinct colours:
    the palette names each of them, none twice (a hashed colour can repeat)."""
    from gnibench.methods import METHODS
    from gnibench.reports.figures.style import PALETTE

    assert [m for m in METHODS if m not in PALETTE] == []
    colours = [PALETTE[m].upper() for m in METHODS]
    assert [m for m, c in zip(METHODS, colours) if colours.count(c) > 1] == []


@pytest.mark.parametrize("text, want", [
    ("h = 0.1 (choice), [B] (2.5)", "h = 0.1 (choice), [B] (2.5)"),   # prose stays readable
    ("[B]: http://x", "\\[B\\]: http://x"), ("see [a][b] ![i](u)", "see [a\\][b] ![i\\](u)"),
    ("# Fake heading", "\\# Fake heading"), ("- item", "\\- item"), ("+ item", "\\+ item"),
    ("1. item", "1\\. item"), ("12) item", "12\\) item"), ("3.14 is pi", "3.14 is pi"),
    ("===", "\\==="), ("*em* _u_ `c` ~~s~~", "\\*em\\* \\_u\\_ \\`c\\` \\~\\~s\\~\\~"),
    ("[a](javascript:x)", "\\[a\\](javascript:x)"), ("a | b", "a \\| b"),
    ("<b>x</b> & y", "&lt;b&gt;x&lt;/b&gt; &amp; y"), ("two\nlines", "two lines")])
def test_markdown_escape(text, want):
    """Markup made inert ([x](y) is no link with its ] escaped, a table no table with its pipes
    escaped), with the first character of a heading, a list item or a link definition escaped,
    and nothing else."""
    from gnibench.reports.markdown import escape

    assert escape(text) == want


def test_the_chart_colour_bar_shows_the_problems_charts_only():
    """so(4)'s section points carry charts Γ1..Γ8 ([B] §7.1): the colour bar has eight colours,
    tick k on the colour of the points of chart k, and none of tab10's two unused colours, even
    when the run crossed only some of the charts."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from gnibench.reports.plots import section_plot
    from gnibench.reports.render import _panel

    cells = pd.DataFrame({"cell": [0], "problem": ["euler-so4"], "method": ["rk4:h=0.01"],
                          "label": ["rk4"], "family": ["rk4"], "problem_id": ["euler-so4"],
                          "setup": [0], "swept_text": ["h=0.01"]})
    charts = np.array([1, 2, 2, 6], dtype=float)
    points = pd.DataFrame({"cell": 0, "x5": [0.1, 0.2, 0.3, 0.4], "x6": [0.0, 0.1, 0.2, 0.3],
                           "chart": charts})
    panel = section_plot("euler-so4", cells, points, {0: {"color": "k"}}, {0: "rk4"}).panels[0]
    fig, ax = plt.subplots()
    _panel(fig, ax, panel)
    bar = fig.axes[-1]
    assert [t for t in bar.get_yticks()] == list(range(1, 9))
    colorbar = ax.collections[0].colorbar
    assert len(colorbar.values) == 8
    tab10 = matplotlib.colormaps["tab10"].colors
    shown = colorbar.cmap(colorbar.norm(np.asarray(colorbar.values)))[:, :3]
    assert np.allclose(shown, tab10[:8])
    points = ax.collections[0]
    points_rgb = points.to_rgba(points.get_array())[:, :3]
    assert np.allclose(points_rgb, [tab10[int(k) - 1] for k in charts])
    plt.close(fig)


def test_the_index_badge_tells_complete_failures_and_incomplete(tmp_path):
    """The index card's badge: ``complete`` (every cell ok), ``complete, with failures`` (a cell
    ended otherwise), ``incomplete`` (the tables of an interrupted run: metadata complete false)."""
    import shutil

    import pyarrow.parquet as pq

    path = tmp_path / "t.toml"
    path.write_text('name = "t"\ntitle = "T"\nreference = "r"\nt_end = 10.0\n'
                    '[[cells]]\nproblems = ["pendulum"]\n'
                    'methods = ["dopri5:max_steps=3", "rk4:h=0.1"]\n')
    assert main(["run", str(path), "-o", str(tmp_path / "a"), "-j", "1", "--no-report"]) == 0
    build_site([tmp_path / "a"], tmp_path / "s1")
    index = (tmp_path / "s1" / "index.html").read_text()
    assert '<span class="badge partial">complete, with failures: 1 max_steps, 1 ok</span>' in index
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    for name in ("samples", "cells", "timings"):       # the three tables of one write agree
        table = pq.read_table(tmp_path / "b" / f"{name}.parquet")
        meta = json.loads(table.schema.metadata[b"gnibench"])
        meta.update(complete=False, cells_done=1, cells_total=2)
        pq.write_table(table.replace_schema_metadata(
            {**table.schema.metadata, b"gnibench": json.dumps(meta).encode()}),
            tmp_path / "b" / f"{name}.parquet")
    build_site([tmp_path / "b"], tmp_path / "s2")
    index = (tmp_path / "s2" / "index.html").read_text()
    assert '<span class="badge warn">incomplete: 1 of 2 cells done</span>' in index
    assert "badge ok" not in index and "badge partial" not in index
    path.write_text(path.read_text().replace('"dopri5:max_steps=3", ', ""))
    assert main(["run", str(path), "-o", str(tmp_path / "c"), "-j", "1", "--no-report"]) == 0
    build_site([tmp_path / "c"], tmp_path / "s3")
    assert '<span class="badge ok">complete</span>' in (tmp_path / "s3" / "index.html").read_text()
