"""Drawing the report's figures: plain tick labels, the cache of drawn figures (keyed by the hash of
their description, verified by the PNG's checksum, stale files removed), parallel drawing giving
the same files as serial drawing, a rebuilt site drawing nothing."""
from __future__ import annotations

import json
import os
import re

import numpy as np
import pytest
from gnibench.reports import drawing
from gnibench.reports.drawing import MANIFEST, Drawers, Job, draw, likely_to_draw
from gnibench.reports.render import Panel, Plot, Series, plain_label, plot_key
from gnibench.reports.site import build_site
from gnibench.suite.foundation.outputs import Fault
from support_reports import make_results


def small_plot(scale: float = 1.0, colour: str = "#1F78B4", log: bool = True) -> Plot:
    t = np.linspace(0.1, 100.0, 200)
    panel = Panel(xscale="log" if log else "linear", yscale="log", xlabel="t", ylabel="err",
                  title="a panel", grid=True, legend={"fontsize": 7})
    panel.series.append(Series(t, scale * (1e-8 + t**2), {"color": colour, "label": "c0 rk4"}))
    return Plot((4.0, 3.0), 1, 1, [panel], {"left": 0.2, "right": 0.95, "bottom": 0.2, "top": 0.9})


@pytest.mark.parametrize("text, plain", [
    (r"$\mathdefault{10^{-5}}$", "10⁻⁵"),
    (r"$\mathdefault{10^{12}}$", "10¹²"),
    (r"$\mathdefault{2\times10^{3}}$", "2\u2009×\u200910³"),
    (r"$\mathdefault{-10^{2}}$", "−10²"),
    (r"$\mathdefault{5\times10^{-7}}$", "5\u2009×\u200910⁻⁷"),
    ("", ""), ("0.5", "0.5"),
    (r"$\alpha^{2}$", r"$\alpha^{2}$"),                   # not a log label: left to mathtext
    (r"$\mathdefault{10^{1.50}}$", r"$\mathdefault{10^{1.50}}$"),
])
def test_plain_log_labels(text, plain):
    assert plain_label(text) == plain


def test_key_follows_data_and_style():
    key = plot_key(small_plot())
    assert key == plot_key(small_plot())
    bumped = small_plot()
    bumped.panels[0].series[0].y[7] = np.nextafter(bumped.panels[0].series[0].y[7], np.inf)
    others = [bumped, small_plot(colour="#000000"), small_plot(log=False)]
    relabelled = small_plot()
    relabelled.panels[0].series[0].style["label"] = "c1 rk4"
    resized = small_plot()
    resized.size = (4.0, 3.5)
    assert len({key} | {plot_key(p) for p in others + [relabelled, resized]}) == 6


@pytest.fixture
def serial_count(monkeypatch):
    """Draw in this process and count the figures drawn."""
    count = {"n": 0}
    real = drawing.render

    def render(plot, path):
        count["n"] += 1
        real(plot, path)

    monkeypatch.setattr(drawing, "cores", lambda: 1)
    monkeypatch.setattr(drawing, "render", render)
    return count


def test_cache_reuses_verifies_and_removes_stale_files(tmp_path, serial_count, capsys):
    d = tmp_path / "img" / "page"
    jobs = [Job(small_plot(1.0), d / "a.png"), Job(small_plot(2.0), d / "b.png")]
    draw(jobs)
    assert serial_count["n"] == 2 and (d / "a.png").is_file() and (d / "b.png").is_file()
    manifest = json.loads((d / MANIFEST).read_text())
    assert set(manifest) == {"a.png", "b.png"}

    draw([Job(small_plot(1.0), d / "a.png"), Job(small_plot(2.0), d / "b.png")])
    assert serial_count["n"] == 2                               # unchanged: nothing drawn

    draw([Job(small_plot(1.0), d / "a.png"), Job(small_plot(3.0), d / "b.png")])
    assert serial_count["n"] == 3                               # b's data changed
    assert capsys.readouterr().err == ""

    with open(d / "a.png", "ab") as f:                          # damaged: drawn again, one line
        f.write(b"\0")
    (d / "stray.png").write_bytes(b"x")
    draw([Job(small_plot(1.0), d / "a.png")])
    err = capsys.readouterr().err.strip().splitlines()
    assert serial_count["n"] == 4
    assert len(err) == 1 and "a.png does not match its recorded checksum" in err[0]
    assert sorted(f.name for f in d.iterdir()) == ["a.png", MANIFEST]   # b and stray removed
    assert set(json.loads((d / MANIFEST).read_text())) == {"a.png"}

    (d / MANIFEST).write_text("{not json")                      # an unreadable manifest: redrawn
    draw([Job(small_plot(1.0), d / "a.png")])
    assert serial_count["n"] == 5


def test_parallel_drawing_gives_the_serial_files(tmp_path, monkeypatch):
    plots = [small_plot(1.0), small_plot(2.0, colour="#D55E00"), small_plot(3.0, log=False)]
    monkeypatch.setattr(drawing, "cores", lambda: 2)
    draw([Job(p, tmp_path / "par" / f"{i}.png") for i, p in enumerate(plots)])
    monkeypatch.setattr(drawing, "cores", lambda: 1)
    draw([Job(p, tmp_path / "ser" / f"{i}.png") for i, p in enumerate(plots)])
    for i in range(3):
        assert (tmp_path / "par" / f"{i}.png").read_bytes() == \
            (tmp_path / "ser" / f"{i}.png").read_bytes()


def test_likely_to_draw(tmp_path):
    results, img = tmp_path / "results", tmp_path / "img"
    results.mkdir()
    for f in ("cells.parquet", "samples.parquet", "timings.parquet"):
        (results / f).write_bytes(b"")
    assert likely_to_draw([(results, img)])                     # never drawn
    img.mkdir()
    (img / MANIFEST).write_text("{}")
    os.utime(results / "cells.parquet", (1, 1))
    os.utime(results / "samples.parquet", (1, 1))
    os.utime(results / "timings.parquet", (1, 1))
    assert not likely_to_draw([(results, img)])                 # drawn after the tables
    os.utime(results / "samples.parquet")
    os.utime(img / MANIFEST, (2, 2))
    assert likely_to_draw([(results, img)])                     # tables newer than the drawing


def test_rebuilt_site_draws_nothing_and_says_the_same(tmp_path, monkeypatch):
    results = make_results(tmp_path, monkeypatch)
    site = tmp_path / "site"
    build_site([results], site)
    pngs = sorted((site / "img" / "hostile").glob("*.png"))
    assert len(pngs) >= 3
    stamps = {p.name: p.stat().st_mtime_ns for p in pngs}
    def page() -> str:                                          # but the time it was made
        return re.sub(r"\d{4}-\d\d-\d\d \d\d:\d\d", "T", (site / "hostile.html").read_text())

    html = page()
    build_site([results], site)
    assert {p.name: p.stat().st_mtime_ns for p in pngs} == stamps
    assert page() == html


def test_a_failing_figure_is_an_error_of_the_drawing_process(tmp_path):
    bad = small_plot()
    bad.panels[0].series[0].style["no_such_property"] = 1
    drawers = Drawers().start(2)
    with drawers, pytest.raises(RuntimeError, match="no_such_property"):
        drawers.submit(Job(small_plot(), tmp_path / "good.png"))
        drawers.submit(Job(bad, tmp_path / "bad.png"))
        drawers.wait()
    assert (tmp_path / "good.png").is_file() and drawers.process is None


@pytest.mark.parametrize("workers", [2, 0])
def test_a_figure_that_cannot_be_written_is_one_line(tmp_path, workers):
    """A figure whose file cannot be written (a full disk, a vanished directory) is a one-line
    Fault naming it, drawn in the drawing process or here; it was a RuntimeError carrying the
    workers' tracebacks (ENOSPC in ``gnibench report``: 430 lines)."""
    gone = tmp_path / "gone" / "a.png"
    drawers = Drawers().start(workers) if workers else Drawers()
    with drawers, pytest.raises(Fault) as caught:
        drawers.submit(Job(small_plot(), gone))
        drawers.wait()
    assert str(gone) in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize("label, n", [
    ("rk4 h=0.1 [3]  t^1.02", 3), ("dop853 (T = 17.0652; atol swept) rtol=atol=1e-07 [1]", 12),
    ("m" * 64, 24), ("W" * 80, 2),
])
def test_a_figure_is_as_wide_as_the_page_with_its_legend_below_uncut(tmp_path, label, n):
    """reports/layout.py ``page_plot``: every figure is 12.4 in wide (1240 px, shown at its own
    size in the page's 1300 px column, so its 9-10 pt text stays 12-14 px), two panels side by
    side; the legend sits below the panels in as many columns as fit and is not cut by the
    figure's edges, up to 24 entries and labels of 64 characters (longer ones are clipped)."""
    from gnibench.reports.layout import MAX_LABEL, WIDTH, page_plot
    from gnibench.reports.render import DPI, render
    from PIL import Image

    x = np.array([1e2, 2e2, 4e2])
    panels = []
    for _ in range(2):
        panel = Panel(xscale="log", yscale="log", xlabel="nfev", ylabel="error", grid=True)
        for k in range(n):
            panel.series.append(Series(x, x ** -(k + 1.0), {"color": "#332288", "marker": "s",
                                                             "label": f"{label}{k}"}))
        panels.append(panel)
    plot = page_plot(panels, cols=2, title="p: work-precision")
    render(plot, tmp_path / "f.png")
    pixels = np.asarray(Image.open(tmp_path / "f.png").convert("L"))
    assert pixels.shape[1] == int(WIDTH * DPI) == 1240
    inked_cols = np.nonzero((pixels < 250).any(axis=0))[0]
    inked_rows = np.nonzero((pixels < 250).any(axis=1))[0]
    assert inked_cols[0] > 3 and inked_cols[-1] < pixels.shape[1] - 4      # nothing cut
    assert inked_rows[-1] < pixels.shape[0] - 3
    axes_bottom = int((1 - plot.adjust["bottom"]) * pixels.shape[0])
    assert (pixels[axes_bottom + 60:] < 250).any()                        # the legend below
    labels = [str(s.style["label"]) for s in plot.panels[0].series]
    assert max(map(len, labels)) <= MAX_LABEL
    assert plot.legend["fontsize"] >= 9


def test_the_advance_widths_are_the_fonts():
    """reports/layout.py ``ADVANCE``: DejaVu Sans's advance widths for the characters 32-126."""
    from gnibench.reports.layout import ADVANCE
    from matplotlib import font_manager, ft2font

    font = ft2font.FT2Font(font_manager.findfont("DejaVu Sans"))
    font.set_size(100, 72)
    widths = []
    for code in range(32, 127):
        font.set_text(chr(code))
        widths.append(round(font.get_width_height()[0] / 64))
    assert tuple(widths) == ADVANCE


def _square_or_fail(x):
    """For test_map: x² in a drawing worker, with its pid; ValueError at -1, OSError at -2."""
    if x == -1:
        raise ValueError("no square today")
    if x == -2:
        raise OSError(28, "No space left on device", "fig.png")
    return x * x, os.getpid()


def test_map_gives_the_results_in_order_from_the_workers_costliest_first(tmp_path):
    """Drawers.map (the seeds' figures in gnibench reproduce): fn runs in the drawing process's
    workers, the costliest argument first, and the results come back in the order of the
    arguments; a failure raises here (an OSError as a one-line Fault); without a drawing process
    fn runs in this process."""
    from gnibench.suite.foundation.outputs import Fault

    args = [(x,) for x in (3, 1, 4, 1, 5, 9, 2, 6)]
    with Drawers().start(2) as drawers:
        sent, send = [], drawers._send
        drawers._send = lambda message: (sent.append(message), send(message))
        results = drawers.map(_square_or_fail, args, cost=lambda a: a[0])
        assert [a[0] for a in sent[0][2]] == sorted((x for (x,) in args), reverse=True)
        assert [r[0] for r in results] == [x * x for (x,) in args]
        assert os.getpid() not in {r[1] for r in results}
        with pytest.raises(RuntimeError, match="no square today"):
            drawers.map(_square_or_fail, [(2,), (-1,)])
        with pytest.raises(Fault, match="No space left on device"):
            drawers.map(_square_or_fail, [(-2,)])
        assert [r[0] for r in drawers.map(_square_or_fail, [(7,)])] == [49]   # still serving
    here = Drawers().map(_square_or_fail, args)
    assert [r for r, pid in here] == [x * x for (x,) in args]
    assert {pid for _, pid in here} == {os.getpid()}


def test_a_figure_shared_by_two_pages_is_drawn_once_and_copied(tmp_path, serial_count):
    """Pages of experiments that share their cells describe the same figure: it is drawn once,
    the other page gets a copy (the same bytes, the same manifest entry); a changed one is drawn."""
    a, b = tmp_path / "img" / "b-fig-26", tmp_path / "img" / "b-fig-27"
    draw([Job(small_plot(1.0), a / "x.png"), Job(small_plot(1.0), b / "x.png"),
          Job(small_plot(2.0), b / "y.png")])
    assert serial_count["n"] == 2
    assert (a / "x.png").read_bytes() == (b / "x.png").read_bytes()
    ma, mb = (json.loads((d / MANIFEST).read_text()) for d in (a, b))
    assert ma["x.png"] == mb["x.png"]
    (a / "x.png").unlink()                             # reused where intact, copied from there
    draw([Job(small_plot(1.0), b / "x.png"), Job(small_plot(1.0), a / "x.png")])
    assert serial_count["n"] == 2 and (a / "x.png").read_bytes() == (b / "x.png").read_bytes()
    draw([Job(small_plot(1.0), a / "x.png"), Job(small_plot(3.0), b / "x.png")])
    assert serial_count["n"] == 3
