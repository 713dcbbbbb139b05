"""Drawing a site's figures: reused when their description did not change, else drawn, in parallel
when that pays.

Every figure of a page is a :class:`~gnibench.reports.render.Plot` (plain data) with the file it
goes to. A page's image directory keeps a manifest, :data:`MANIFEST`, of the figures drawn into it:
per file the hash of its description (:func:`~gnibench.reports.render.plot_key`, which includes the
renderer's source and matplotlib's version) and the SHA-256 of the PNG written. A figure whose
key matches and whose file still has the recorded checksum is not drawn again (a report rebuilt
after a resumed run, or of unchanged results); a file that does not match its checksum is
redrawn with one warning line. Files of the directory that the page no longer has are removed.

The figures left to draw are drawn by forked worker processes, largest first, when there are
at least :data:`PARALLEL_MIN` of them and more than one core, else in this process. When figures
will probably be drawn (:func:`likely_to_draw`: an image directory without manifest, or older than
its results' tables), the site starts the workers before it prepares the pages
(:func:`early_drawers`): each imports matplotlib while this process reads the tables, which it
then never imports.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from gnibench.reports.render import Plot, plot_key, render

MANIFEST = "figures.json"
PARALLEL_MIN = 2          # a fork costs milliseconds, a figure a tenth of a second or more


@dataclass
class Job:
    """A figure to have in ``path``."""

    plot: Plot
    path: Path
    key: str = ""


def _digest_file(path: Path) -> str | None:
    from gnibench.suite.foundation.cache import digest

    try:
        return digest(path.read_bytes())
    except OSError:
        return None


def _read_manifest(d: Path) -> dict:
    try:
        doc = json.loads((d / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _reusable(job: Job, manifest: dict) -> bool:
    from gnibench.suite.foundation.cache import warn

    entry = manifest.get(job.path.name)
    if not isinstance(entry, dict) or entry.get("key") != job.key or not job.path.is_file():
        return False
    if _digest_file(job.path) == entry.get("sha256"):
        return True
    warn(f"report: {job.path} does not match its recorded checksum; drawn again")
    return False


def _cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                       # not on Linux
        return os.cpu_count() or 1


def _warm() -> None:
    """In a drawing worker, at its start: matplotlib imported, its font list read."""
    from matplotlib import font_manager
    from matplotlib.backends import backend_agg  # noqa: F401
    from matplotlib.figure import Figure  # noqa: F401

    font_manager.findfont("DejaVu Sans")


class Drawers:
    """The processes that draw figures: none until :meth:`start` (or :meth:`run` with enough
    figures) forks them; each imports matplotlib when it starts, so a pool started early (while
    the pages are prepared) has it imported when the figures come."""

    def __init__(self):
        self.pool = None

    def start(self, workers: int) -> None:
        import multiprocessing as mp

        if self.pool is not None or workers < 2 or "fork" not in mp.get_all_start_methods():
            return
        from concurrent.futures import ProcessPoolExecutor

        self.pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("fork"),
                                        initializer=_warm)
        self.pool.submit(int)           # a fork pool starts all its workers with the first task

    def run(self, todo: list[Job]) -> None:
        if len(todo) >= PARALLEL_MIN:
            self.start(min(_cpus(), len(todo)))
        if self.pool is None or not todo:
            for job in todo:
                render(job.plot, job.path)
            return
        futures = [self.pool.submit(render, j.plot, j.path)          # the largest first
                   for j in sorted(todo, key=lambda j: -j.plot.cost())]
        for f in futures:
            f.result()

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)
            self.pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def likely_to_draw(pairs) -> bool:
    """Whether some figure will probably be drawn: (results directory, image directory) pairs of
    which an image directory has no manifest or one older than its results' tables."""
    for results, img in pairs:
        try:
            drawn = (Path(img) / MANIFEST).stat().st_mtime
            if any((Path(results) / f).stat().st_mtime > drawn
                   for f in ("cells.parquet", "samples.parquet", "timings.parquet")):
                return True
        except OSError:
            return True
    return False


def early_drawers(pairs) -> Drawers:
    """Drawing workers, started now when figures will probably be drawn and there are cores."""
    drawers = Drawers()
    if likely_to_draw(pairs):
        drawers.start(_cpus())
    return drawers


def draw(jobs: list[Job], dirs: list[Path] = (), drawers: Drawers | None = None) -> None:
    """Have every job's figure in its file, and nothing else in the jobs' directories and in
    ``dirs`` (see the module docstring); ``drawers``: worker processes already started."""
    from gnibench.suite.foundation.cache import atomic_write

    by_dir: dict[Path, list[Job]] = {Path(d): [] for d in dirs}
    for job in jobs:
        job.key = job.key or plot_key(job.plot)
        by_dir.setdefault(job.path.parent, []).append(job)
    todo = []
    for d, some in by_dir.items():
        d.mkdir(parents=True, exist_ok=True)
        manifest = _read_manifest(d)
        todo += [j for j in some if not _reusable(j, manifest)]
    if drawers is None:
        with Drawers() as own:
            own.run(todo)
    else:
        drawers.run(todo)
    for d, some in by_dir.items():
        keep = {j.path.name for j in some}
        for f in d.iterdir():
            if f.is_file() and f.name not in keep and f.name != MANIFEST:
                f.unlink()
        doc = {j.path.name: {"key": j.key, "sha256": _digest_file(j.path)} for j in some}
        atomic_write(d / MANIFEST, lambda p, doc=doc: Path(p).write_text(
            json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8"))
