"""Every shipped figure of the seeds (registry-parametrized), and the drawing helpers.

At the quick scale each figure is reproduced and checked once per test run, by the test file of
its section (tests/support_figures.py: ``SECTION_FIGURES``, ``check_figure``: the cells run
through the runner into a results store, the figure is drawn, and the manifest read back from
matplotlib must show the axis labels, scales and titles declared in the experiment's ``[figure]``
section, every declared curve with data, every panel with something drawn, and the PNG and SVG
files); here every figure of the registry must have exactly one such file, and every claim of
the ledger exactly one file that verifies it at the quick scale (its claims are derived from the
ledger: ``claims_of``; a claim stated at the paper scale only is verified there as skipped).
Paper scale: ``pytest -m slow``.
"""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from gnibench.suite.ledger.entries import load_ledger
from gnibench.suite.runs.reproduce import figures, load_figures, run_figures
from support_figures import SECTION_FIGURES, check_figure, claim_file, claims_of

IDS = list(figures())
CLAIM_IDS = list(load_ledger())


def _reproduce(fid: str, scale: str, out):
    from gnibench.reports.figures import draw_figure

    (experiment,) = load_figures([fid], scale)
    (results,) = run_figures([experiment], out, jobs=1, log=open(os.devnull, "w"))  # noqa: SIM115
    draw_figure(results)
    return results


@pytest.mark.parametrize("fid", IDS)
def test_figure_is_reproduced_at_the_quick_scale_by_one_section_file(fid):
    assert [f for f, ids in SECTION_FIGURES.items() if fid in ids] != [], \
        f"{fid}: no test file reproduces it (tests/support_figures.py: SECTION_FIGURES)"
    assert len([f for f, ids in SECTION_FIGURES.items() if fid in ids]) == 1, fid


def test_section_files_list_only_shipped_figures():
    listed = [fid for ids in SECTION_FIGURES.values() for fid in ids]
    assert sorted(listed) == sorted(IDS)
    here = Path(__file__).parent
    assert all((here / f"{name}.py").is_file() for name in SECTION_FIGURES), SECTION_FIGURES.keys()


@pytest.mark.parametrize("cid", CLAIM_IDS)
def test_claim_is_verified_by_one_seed_file(cid):
    """Each claim of the ledger has exactly one seed test file, where it is verified at the quick
    scale (or found skipped there, when it is stated at the paper scale only): the file of its
    figure, else of its experiment when that is a figure, else of its section."""
    claim = load_ledger()[cid]
    files = claim_file(claim)
    assert len(files) == 1, f"{cid}: verified by {files or 'no file'} (tests/support_figures.py)"
    assert cid in claims_of(files[0])
    if claim.figure and claim.figure in IDS:           # a figure's claims go with the figure
        assert claim.figure in SECTION_FIGURES[files[0]], (cid, claim.figure, files)


def test_every_seed_file_verifies_the_claims_derived_for_it():
    """The seed test files take their claims from the ledger (``CLAIMS = claims_of(...)``), none
    typed by hand; together they verify every claim once."""
    import importlib.util

    here = Path(__file__).parent
    verified = []
    for name in SECTION_FIGURES:
        spec = importlib.util.spec_from_file_location(f"_seed_file_{name}", here / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        assert module.CLAIMS == claims_of(name), name
        verified += module.CLAIMS
    assert sorted(verified) == sorted(CLAIM_IDS)


@pytest.mark.slow
@pytest.mark.parametrize("fid", IDS)
def test_figure_at_paper_scale(fid, tmp_path):
    check_figure(_reproduce(fid, "paper", tmp_path), "paper")


def test_pieces_break_a_line_at_its_jumps():
    from gnibench.reports.figures.plot import _pieces

    t = np.linspace(0.0, 1.0, 101)
    x = np.concatenate([t, t + 5.0, t])                 # two jumps of 4 and 6 (steps of 0.01)
    xs, _, origins = _pieces(x, np.zeros_like(x))
    assert origins == [0, 102, 204] and np.isnan(xs[[101, 203]]).all()
    assert xs[origins].tolist() == [0.0, 5.0, 0.0]


def _thin_by_buckets(x, y, limit, logx=False):
    """thin() as first written: a loop over the buckets with nanargmin and nanargmax."""
    n, nb = len(x), limit // 2
    if n <= limit:
        return x, y
    pos = np.log(np.where(x > 0, x, np.nan)) if logx else x.astype(float)
    ok = np.isfinite(pos)
    if ok.sum() > 1 and np.all(np.diff(pos[ok]) >= 0):
        edges = np.linspace(pos[ok][0], pos[ok][-1], nb + 1)
        bucket = np.where(ok, np.clip(np.searchsorted(edges, pos, side="right") - 1, 0, nb - 1),
                          -1)
        starts = np.flatnonzero(np.diff(np.concatenate([[-2], bucket])) != 0)
        buckets = np.split(np.arange(n), starts[1:])
    else:
        buckets = np.array_split(np.arange(n), nb)
    keep = [0, n - 1]
    finite = np.where(np.isfinite(y), y, np.nan)
    for b in buckets:
        part = finite[b]
        if np.all(np.isnan(part)):
            keep.append(int(b[0]))
            continue
        keep += [int(b[np.nanargmin(part)]), int(b[np.nanargmax(part)])]
    idx = np.unique(keep)
    return x[idx], y[idx]


@pytest.mark.parametrize("case", range(12))
def test_thinning_keeps_each_buckets_first_extremes(case):
    """thin() keeps the same samples as the loop over buckets it replaced: time series (with
    non-finite x, on log x) and curves whose x goes back, y with ties, NaN, inf and all-NaN
    buckets."""
    from gnibench.reports.figures.data import thin

    rng = np.random.default_rng(case)
    n = int(rng.integers(50, 3000))
    x = np.cumsum(rng.exponential(1.0, n)) if case % 3 else rng.normal(size=n)
    y = np.round(rng.normal(size=n), 1 if case % 2 else 6)          # ties when rounded
    y[rng.random(n) < 0.05] = np.nan
    y[rng.random(n) < 0.02] = np.inf * rng.choice([-1, 1])
    y[n // 3:n // 3 + 40] = np.nan                                  # whole buckets without y
    if case % 4 == 1:
        x[rng.random(n) < 0.03] = np.nan
    logx = case % 5 == 2
    limit = int(rng.integers(10, 200))
    got, want = thin(x, y, limit, logx), _thin_by_buckets(x, y, limit, logx)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
    assert len(got[0]) < n


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


@pytest.fixture(scope="module")
def fig_1_4(tmp_path_factory):
    """[HLW] Fig 1.4 run at the quick scale once for the tests that only draw from its tables."""
    from gnibench.suite.cli.main import main

    out = tmp_path_factory.mktemp("fig-1.4")
    assert main(["reproduce", "hlw-fig-1.4", "--scale", "quick", "-o", str(out), "-j", "1",
                 "--no-report"]) == 0
    return out / "hlw-fig-1.4"


def test_images_are_those_of_matplotlibs_own_layout_and_the_same_bytes_each_time(
        fig_1_4, tmp_path, monkeypatch):
    """draw_figure lays a figure out once (``_lay_out_once``) and draws the PNG and the SVG once
    each: the PNG is byte for byte the one savefig writes when it runs the constrained layout
    itself, and a second drawing writes the same bytes (the SVG's ids are salted by
    ``svg.hashsalt``; the SVG keeps the PNG's layout, where savefig would lay it out again at
    72 dpi and move the axes by a fraction of a point)."""
    import gnibench.reports.figures as figs

    results = fig_1_4

    def images(out):
        figs.draw_figure(results, out)
        return {ext: (out / f"hlw-fig-1.4.{ext}").read_bytes() for ext in ("png", "svg")}

    once, again = images(tmp_path / "a"), images(tmp_path / "b")
    assert once == again
    monkeypatch.setattr(figs, "_lay_out_once", lambda fig: None)   # savefig's own layout runs
    assert images(tmp_path / "c")["png"] == once["png"]


def test_titles_over_log_axes_are_where_matplotlib_would_measure_them_to_be(
        fig_1_4, tmp_path, monkeypatch):
    """A panel with a log y axis gets its title at y = 1 without matplotlib's measuring of the
    tick labels (reports/figures/plot.py): the PNG is byte for byte the one drawn with the
    title placed by matplotlib; on linear y axes matplotlib still places it."""
    import copy

    import gnibench.reports.figures as figs
    from gnibench.reports.figures.data import Results
    from matplotlib.axes import Axes

    results = fig_1_4
    figure = copy.deepcopy(Results.read(results).figure)
    for panel in figure["panels"]:
        panel.update(yscale="log", ylim=None)
    assert all(panel["title"] for panel in figure["panels"])
    placed = []
    set_title = Axes.set_title

    def spy(ax, label, *args, **kw):
        placed.append(kw.get("y"))
        return set_title(ax, label, *args, **kw)

    monkeypatch.setattr(Axes, "set_title", spy)
    figs.draw_figure(results, tmp_path / "a", figure=figure)
    assert placed and set(placed) == {1.0}
    monkeypatch.setattr(Axes, "set_title", lambda ax, label, *a, y=None, **kw:
                        set_title(ax, label, *a, **kw))     # matplotlib measures and places
    figs.draw_figure(results, tmp_path / "b", figure=figure)
    assert (tmp_path / "a" / "hlw-fig-1.4.png").read_bytes() \
        == (tmp_path / "b" / "hlw-fig-1.4.png").read_bytes()
    placed.clear()
    monkeypatch.setattr(Axes, "set_title", spy)
    figs.draw_figure(results, tmp_path / "c")          # the figure's own linear axes
    assert placed and set(placed) == {None}


def test_legend_samples_of_point_sets_are_legible():
    """A point set drawn as 0.6-point pixels ([B] Figs 26-29: thousands of crossings) gets a
    legend sample of LEGEND_MARKER points; the points themselves keep their size."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from gnibench.reports.figures.plot import LEGEND_MARKER, LINE, legible_markers

    fig, ax = plt.subplots()
    (points,) = ax.plot([0, 1], [0, 1], label="crossings", **LINE["pixels"])
    ax.plot([0, 1], [1, 0], label="orbit", **LINE["line"])
    legend = ax.legend()
    legible_markers(legend)
    sample, line = legend.legend_handles
    assert sample.get_markersize() == LEGEND_MARKER and points.get_markersize() == 0.6
    assert line.get_marker() in (None, "None", "")
    plt.close(fig)


def test_pixel_clouds_keep_their_ink_whatever_their_size():
    """"pixels" are 0.6 points for the seeds' 140 000 crossings and for more; a smaller cloud
    gets larger markers, about the same ink (size² × points), up to the 2 points of "dots"."""
    from gnibench.reports.figures.plot import LINE, PIXEL_CROWD, PIXEL_LARGEST, pixel_size

    smallest = LINE["pixels"]["markersize"]
    assert pixel_size(PIXEL_CROWD) == smallest == pixel_size(10 * PIXEL_CROWD) == 0.6
    assert pixel_size(0) == pixel_size(100) == PIXEL_LARGEST == LINE["dots"]["markersize"]
    for n in (20_000, 50_000, 100_000):
        assert pixel_size(n) ** 2 * n == pytest.approx(smallest ** 2 * PIXEL_CROWD)
    sizes = [pixel_size(n) for n in (500, 3_000, 15_000, 60_000, 140_000)]
    assert sizes == sorted(sizes, reverse=True)
