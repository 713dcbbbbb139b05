"""``gnibench report``: a static site (HTML, and the same content as GitHub-readable Markdown) from
one or more results directories.

Layout of the site directory::

    index.html, index.md            the experiments, with links
    <experiment>.html, .md          one page per experiment (reports/pages.py)
    timing.html, timing.md          benchmark history (with a benchmark storage directory)
    <ledger>.html, .md              a claims ledger (gnibench verify), as a table
    img/<experiment>/*.png          figures; img/<experiment>/figure/ the reproduced figure's files
    assets/plotly.min.js            plotly.js, for the interactive work-precision diagrams

Every page works offline from ``file://``: styles are inline, images local; the only scripts
are plotly.js, copied into ``assets/`` (:mod:`gnibench.reports.interactive`), and the page's own
few lines that hand it the interactive work-precision diagrams (JSON data, escaped). Every
string that comes from a user or a file goes through the template engine: HTML with Jinja2's
autoescape; Markdown through :func:`gnibench.reports.markdown.escape` (the environment's
``finalize``), specs in code spans that cannot be broken out of, the TOML text in a fence longer
than any backtick run inside it. The Markdown pages show the static PNGs.
"""
from __future__ import annotations

import contextlib
import re
import shutil
import time
from pathlib import Path
from urllib.parse import quote

from gnibench.reports.drawing import Figures, early_drawers
from gnibench.reports.league import DEFAULT_THRESHOLDS
from gnibench.reports.markdown import code, escape
from gnibench.reports.pages import experiment_page, index_entry
from gnibench.reports.results import find_results, slug

_NUMBER = re.compile(r"^(–|-?inf|-?\d+(\.\d+)?(e[+-]?\d+)?)$")


def _bytecode_cache(kind: str):
    """Compiled templates kept in the cache directory (``templates-<kind>``), checksummed when
    written and verified when read (:mod:`gnibench.suite.foundation.cache`); compiling the
    templates costs more than rendering them. None when the cache directory is not usable."""
    import jinja2
    from gnibench.suite.foundation.cache import cache_dir, read_checked, write_checked

    class CheckedBytecodeCache(jinja2.BytecodeCache):
        def __init__(self, directory: Path):
            self.directory = directory

        def load_bytecode(self, bucket) -> None:
            with contextlib.suppress(OSError):
                data = read_checked(self.directory / f"{bucket.key}.bc", "compiled template")
                if data is not None:
                    bucket.bytecode_from_string(data)

        def dump_bytecode(self, bucket) -> None:
            with contextlib.suppress(OSError):
                write_checked(self.directory / f"{bucket.key}.bc", bucket.bytecode_to_string())

    try:
        return CheckedBytecodeCache(cache_dir(f"templates-{kind}"))
    except OSError:
        return None


def _environments():
    import jinja2
    from markupsafe import Markup

    loader = jinja2.PackageLoader("gnibench.reports", "templates")
    html = jinja2.Environment(loader=loader, autoescape=True, trim_blocks=False,
                              undefined=jinja2.StrictUndefined,
                              bytecode_cache=_bytecode_cache("html"))

    def md_finalize(value):
        if isinstance(value, Markup):
            return str(value)
        text = "" if value is None else str(value)
        return text if _NUMBER.match(text) else escape(text)

    def code_span(value):
        return Markup(code(value))

    def code_cell(value):                # GFM splits table cells at |, also inside code spans
        return Markup(code(value).replace("|", "\\|"))

    def fence(value):
        text = str(value).replace("\r", "")
        longest = max((len(m) for m in re.findall(r"`+", text)), default=0)
        bar = "`" * max(3, longest + 1)
        return Markup(f"{bar}toml\n{text.rstrip()}\n{bar}")

    def link(value):
        return Markup(quote(str(value), safe="/._-"))

    md = jinja2.Environment(loader=loader, autoescape=False, finalize=md_finalize,
                            undefined=jinja2.StrictUndefined, bytecode_cache=_bytecode_cache("md"))
    md.filters.update(code=code_span, code_cell=code_cell, fence=fence, link=link)
    return html, md


def _write(path: Path, text: str) -> None:
    """A page, committed by a rename (a full disk leaves no half-written page and names it)."""
    from gnibench.suite.foundation.cache import atomic_write

    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def _copy_figure(res, img_dir: Path) -> None:
    if not res.figure:
        return
    dest = img_dir / "figure"
    for f in res.figure["images"]:
        target = dest / f
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(res.dir / "figure" / f, target)


def _unique(name: str, taken: set[str]) -> str:
    base, k = slug(name), 2
    out = base
    while out in taken or out in ("index", "timing", "img"):
        out, k = f"{base}-{k}", k + 1
    taken.add(out)
    return out


def ledger_page(ledger, name: str, pages: set[str]) -> dict:
    """A claims ledger (gnibench verify): per section of the seeds, each claim with its verdict,
    the measured number beside the seed's and a link to its figure's page when the site has it."""
    from gnibench.reports.ledger import ledger_context, mutation_summary, render_ledger

    meta = ledger.meta or {}
    mutants = mutation_summary(ledger.dir)
    return {"title": f"Claims ledger ({ledger.dir.name})", "name": name,
            "source": str(ledger.dir / "ledger.parquet"),
            "markdown": render_ledger(ledger.table, meta, mutants),
            **ledger_context(ledger.table, meta, pages, mutants)}


MAX_NAV = 8


def natural_key(name: str) -> tuple:
    """Sort key with the numbers inside a name compared as numbers (hlw-fig-1.2 < hlw-fig-1.10)."""
    return tuple((0, int(p), "") if p.isdigit() else (1, 0, p)
                 for p in re.split(r"(\d+)", str(name)) if p)


def _page(res, img_dir: Path, thresholds, jobs, palette=None, plots=None) -> dict:
    """One experiment's page; its figures (to be drawn into ``img_dir``) are appended to
    ``jobs`` (a :class:`~gnibench.reports.drawing.Figures`)."""
    import numpy as np

    with np.errstate(all="ignore"):
        page = experiment_page(res, img_dir, img_dir.name, thresholds, jobs, palette, plots)
    if (img_dir / "figure").exists():
        shutil.rmtree(img_dir / "figure")
    _copy_figure(res, img_dir)
    return page


def build_site(dirs: list[Path], site: Path, thresholds=DEFAULT_THRESHOLDS,
               benchmarks: Path | None = None, log=None, drawers=None,
               plots: dict | None = None) -> Path:
    """Write the site for the results directories ``dirs`` into ``site``; return index.html.

    ``thresholds``: the accuracies ε of the league tables. ``benchmarks``: a benchmark storage
    directory (pytest-benchmark layout, ``<machine>/NNNN_<commit>.json``) for the timing page.
    ``drawers``: a :class:`~gnibench.reports.drawing.Drawers` started earlier by the caller (who
    closes it), e.g. before the run whose results are reported; default: one of this call's.
    ``plots``: ``[report]`` keys that replace those of every experiment file
    (:mod:`gnibench.suite.runs.report_schema`). Diverged cells (inf, overflow on log axes) are
    drawn as far as they are finite, silently. A method family has one style on every page
    (:class:`gnibench.reports.palette.Palette`).
    """
    import numpy as np

    with np.errstate(all="ignore"):
        return _build_site(dirs, site, thresholds, benchmarks, log, drawers, plots)


def _build_site(dirs: list[Path], site: Path, thresholds, benchmarks: Path | None,
                log, given, plots=None) -> Path:
    from gnibench.reports.interactive import copy_library
    from gnibench.reports.palette import Palette
    from gnibench.reports.timing import timing_page

    found, ledgers = find_results(dirs)
    found = sorted(found, key=lambda r: natural_key(r.name))   # b-fig-2 before b-fig-10
    site = Path(site)
    site.mkdir(parents=True, exist_ok=True)
    img = site / "img"
    html, md = _environments()
    taken: set[str] = set()
    dirs = [img / _unique(res.name, taken) for res in found]
    with contextlib.nullcontext(given) if given is not None else \
            early_drawers([(res.dir, d) for res, d in zip(found, dirs)]) as drawers:
        # each figure is drawn (or reused) as soon as its page describes it: reports/drawing.py
        figures = Figures(drawers, dirs + ([img / "timing"] if benchmarks else []))
        palette = Palette()
        pages = [_page(res, d, thresholds, figures, palette, plots) for res, d in zip(found, dirs)]
        timing = timing_page(benchmarks, img / "timing", "timing", figures) if benchmarks \
            else None
        figures.finish()
    if log is not None:
        for res in found:
            print(f"gnibench: report: {res.name} ({len(res.cells)} cells)", file=log, flush=True)
    if any(p["interactive"] for p in pages):
        copy_library(site)
    slugs = {p["slug"] for p in pages}
    ledger_pages = [ledger_page(lg, _unique(f"ledger-{lg.dir.name}", taken), slugs)
                    for lg in ledgers]
    nav = pages if len(pages) <= MAX_NAV else []       # many experiments: the index lists them
    common = {"nav": [{"slug": p["slug"], "name": p["name"]} for p in nav],
              "has_timing": timing is not None,
              "ledgers": [{"slug": lp["name"], "name": lp["title"], "total": lp["total"],
                           "counts": lp["counts"]} for lp in ledger_pages],
              "generated": time.strftime("%Y-%m-%d %H:%M")}
    for p in pages:
        _write(site / f"{p['slug']}.html", html.get_template("experiment.html").render(p=p, **common))
        _write(site / f"{p['slug']}.md", md.get_template("experiment.md").render(p=p, **common))
    for lp in ledger_pages:
        _write(site / f"{lp['name']}.html", html.get_template("ledger.html").render(t=lp, **common))
        _write(site / f"{lp['name']}.md", lp["markdown"] + "\n")
    for t, name in [(timing, "timing")] if timing else []:
        _write(site / f"{name}.html", html.get_template("table.html").render(t=t, **common))
        _write(site / f"{name}.md", md.get_template("table.md").render(t=t, **common))
    entries = [index_entry(p) for p in pages]
    _write(site / "index.html", html.get_template("index.html").render(entries=entries, **common))
    _write(site / "index.md", md.get_template("index.md").render(entries=entries, **common))
    return site / "index.html"
