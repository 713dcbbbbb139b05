"""Drawing a site's figures: reused when their description did not change, else drawn, in parallel
when that pays.

Every figure of a page is a :class:`~gnibench.reports.render.Plot` (plain data) with the file it
goes to. A page's image directory keeps a manifest, :data:`MANIFEST`, of the figures drawn into it:
per file the hash of its description (:func:`~gnibench.reports.render.plot_key`, which includes the
renderer's source and matplotlib's version) and the SHA-256 of the PNG written. A figure whose
key matches and whose file still has the recorded checksum is not drawn again (a report rebuilt
after a resumed run, or of unchanged results); a file that does not match its checksum is
redrawn with one warning line. Files of the directory that the page no longer has are removed.

Where the figures are drawn (:class:`Drawers`): when a drawing process was started, each figure
goes to it as soon as its page has described it (the drawing overlaps the rest of the page's
preparation); the drawing process imported matplotlib when it started and forks one worker per
core from itself, so matplotlib is imported once and this process never imports it. The site
starts the drawing process before it prepares the pages when figures will probably be drawn
(:func:`likely_to_draw`: an image directory without manifest, or older than its results' tables),
and ``gnibench run`` before the cells run. Without one, the figures are drawn in this process, or
by a drawing process started then when there are at least :data:`PARALLEL_MIN` of them and more
than one core, largest first. ``gnibench reproduce`` draws the seeds' figures by the same
workers (:meth:`Drawers.map`) before the report's, from a drawing process started before the
cells run, which has imported the figures' modules meanwhile.
"""
from __future__ import annotations

import contextlib
import gc
import json
import os
from dataclasses import dataclass
from pathlib import Path

from gnibench.reports.render import Plot, plot_key, render
from gnibench.suite.foundation.processes import quiet_worker

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
    from gnibench.suite.foundation.files import read_regular

    try:
        return digest(read_regular(path))
    except OSError:
        return None


def _read_manifest(d: Path) -> dict:
    from gnibench.suite.foundation.files import read_regular

    try:
        doc = json.loads(read_regular(d / MANIFEST))
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


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                       # not on Linux
        return os.cpu_count() or 1


# -- the drawing process ----------------------------------------------------------------------

def _serve(conn, parent: int, workers: int, preload: tuple = ()) -> None:
    """The drawing process: import matplotlib (and the modules ``preload`` names), then draw
    what comes ("draw", plot, path) by ``workers`` processes forked from this one; ("wait",)
    answers ("ok", None) or the failures; ("map", fn, argument tuples) answers ("ok", results
    in order) or the first failure. A failure is ("fault", errno, strerror, path) for an
    ``OSError``, else ("error", traceback text)."""
    import importlib
    import multiprocessing as mp
    import traceback
    from concurrent.futures import ProcessPoolExecutor

    quiet_worker(parent)
    from matplotlib import font_manager
    from matplotlib.backends import backend_agg  # noqa: F401
    from matplotlib.figure import Figure  # noqa: F401

    for name in preload:
        importlib.import_module(name)
    font_manager.findfont("DejaVu Sans")           # the font list read once, before the forks
    # what this process holds now (the command's objects, forked, and matplotlib) lives until it
    # ends: frozen for the cyclic garbage collector, so that the full collections of the drawing
    # workers forked from it walk only what they make (a cold `reproduce all --scale quick`:
    # 2.1 s and 2.5 s of the two workers' 5.3 s and 5.8 s of CPU were full collections)
    gc.freeze()
    pool, futures = None, []
    try:
        while True:
            try:
                message = conn.recv()
            except (EOFError, OSError):
                return
            if message[0] in ("draw", "map") and pool is None:
                pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("fork"),
                                           initializer=quiet_worker, initargs=(os.getpid(),))
            if message[0] == "draw":
                futures.append((pool.submit(render, *message[1:]), message[2]))
            elif message[0] == "map":
                done = [pool.submit(message[1], *args) for args in message[2]]
                failed = next((f.exception() for f in done if f.exception() is not None), None)
                conn.send(("ok", [f.result() for f in done]) if failed is None else
                          ("fault", failed.errno, failed.strerror, failed.filename or "a figure")
                          if isinstance(failed, OSError) else
                          ("error", "".join(traceback.format_exception(failed))))
            elif message[0] == "wait":
                failed = [(f.exception(), path) for f, path in futures
                          if f.exception() is not None]
                futures = []
                faults = [(e.errno, e.strerror, str(path)) for e, path in failed
                          if isinstance(e, OSError)]
                conn.send(("fault", *faults[0]) if faults else ("error", "\n".join(
                    "".join(traceback.format_exception(e)) for e, _ in failed))
                    if failed else ("ok", None))
            else:
                return
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _fault(number, why, path):
    """A figure that could not be written (a full disk, a vanished directory): a one-line Fault;
    the tables are written already, the next report draws what is missing."""
    from gnibench.suite.foundation.outputs import fault

    return fault(OSError(number, why), f"drawing {path}",
                 "run the same command again once the cause is removed")


class Drawers:
    """Where the figures are drawn (see the module docstring): :meth:`submit` each, then
    :meth:`wait`."""

    def __init__(self):
        self.process, self.conn, self.local = None, None, []

    def start(self, workers: int | None = None, preload: tuple = ()) -> Drawers:
        """Fork the drawing process now (if there is more than one worker to give it: by default
        one per core); it imports matplotlib and the modules named in ``preload`` before it forks
        its workers."""
        import multiprocessing as mp

        workers = cores() if workers is None else workers
        if self.process is None and workers >= 2 and "fork" in mp.get_all_start_methods():
            ctx = mp.get_context("fork")
            self.conn, child = ctx.Pipe()
            self.process = ctx.Process(target=_serve, args=(child, os.getpid(), workers, preload),
                                       name="gnibench-drawing")
            self.process.start()
            child.close()
        return self

    def submit(self, job: Job) -> None:
        if self.process is None:
            self.local.append(job)
        else:
            self._send(("draw", job.plot, job.path))

    def map(self, fn, args: list[tuple], cost=None) -> list:
        """``fn(*a)`` for each ``a`` of ``args`` (``fn`` a module-level function), by the drawing
        process's workers, the costliest first (``cost(a)``), or here in order when there is no
        drawing process; the results in the order of ``args``. A failure raises here: an
        ``OSError`` as a one-line Fault, anything else with its traceback."""
        if self.process is None:
            return [fn(*a) for a in args]
        order = sorted(range(len(args)), key=lambda i: -cost(args[i])) if cost else \
            list(range(len(args)))
        self._send(("map", fn, [args[i] for i in order]))
        results = [None] * len(args)
        for i, result in zip(order, self._reply()):
            results[i] = result
        return results

    def _reply(self):
        """The drawing process's answer: its value, or its failure raised here."""
        try:
            reply = self.conn.recv()
        except (EOFError, OSError) as e:
            raise RuntimeError(f"the drawing process ended unexpectedly ({e})") from None
        if reply[0] == "fault":
            raise _fault(*reply[1:])
        if reply[0] == "error":
            raise RuntimeError(f"drawing a figure failed:\n{reply[1]}")
        return reply[1]

    def _send(self, message) -> None:
        try:
            self.conn.send(message)
        except OSError as e:
            raise RuntimeError(f"the drawing process ended unexpectedly ({e})") from None

    def wait(self) -> None:
        """Until every figure submitted is drawn; a figure that failed raises here."""
        local, self.local = sorted(self.local, key=lambda j: -j.plot.cost()), []
        if self.process is None and len(local) >= PARALLEL_MIN:
            self.start()
        if self.process is None:
            for job in local:
                try:
                    render(job.plot, job.path)
                except OSError as e:       # a full disk, say: one line, exit 1
                    raise _fault(e.errno, e.strerror, job.path) from None
            return
        for job in local:
            self.submit(job)
        self._send(("wait",))
        self._reply()

    def close(self, now: bool = False) -> None:
        if self.process is None:
            return
        if not now:
            with contextlib.suppress(OSError, ValueError):
                self.conn.send(("stop",))
            self.process.join(timeout=10)
        if self.process.is_alive():
            self.process.terminate()
            self.process.join(timeout=5)
        self.conn.close()
        self.process = self.conn = None

    def __enter__(self):
        return self

    def __exit__(self, kind, *exc) -> None:
        self.close(now=kind is not None)


# -- the figures of a site ----------------------------------------------------------------------

class Figures:
    """The figures of a site, as the pages describe them (``append`` a :class:`Job`): each is
    reused or submitted to ``drawers`` at once, and a figure with the description of one already
    there or submitted (pages of experiments that share their cells) is copied from it instead of
    drawn again; :meth:`finish` waits for them, makes the copies, removes the other files of their
    directories and of ``dirs``, and writes the manifests."""

    def __init__(self, drawers: Drawers, dirs=()):
        self.drawers = drawers
        self.by_dir: dict[Path, list[Job]] = {Path(d): [] for d in dirs}
        self.manifests: dict[Path, dict] = {}
        self.source: dict[str, Path] = {}          # a file that has (or will have) each key
        self.copies: list[tuple[Path, Job]] = []

    def append(self, job: Job) -> None:
        job.key = job.key or plot_key(job.plot)
        d = job.path.parent
        self.by_dir.setdefault(d, []).append(job)
        if d not in self.manifests:
            d.mkdir(parents=True, exist_ok=True)
            self.manifests[d] = _read_manifest(d)
        if _reusable(job, self.manifests[d]):
            self.source.setdefault(job.key, job.path)
        elif job.key in self.source:
            self.copies.append((self.source[job.key], job))
        else:
            self.source[job.key] = job.path
            self.drawers.submit(job)

    def finish(self) -> None:
        import shutil

        from gnibench.suite.foundation.cache import atomic_write

        self.drawers.wait()
        for source, job in self.copies:
            if source != job.path:
                try:
                    atomic_write(job.path, lambda p, s=source: shutil.copyfile(s, p))
                except OSError as e:
                    raise _fault(e.errno, e.strerror, job.path) from None
        for d, jobs in self.by_dir.items():
            d.mkdir(parents=True, exist_ok=True)
            keep = {j.path.name for j in jobs}
            for f in d.iterdir():
                if f.is_file() and f.name not in keep and f.name != MANIFEST:
                    f.unlink()
            doc = {j.path.name: {"key": j.key, "sha256": _digest_file(j.path)} for j in jobs}
            atomic_write(d / MANIFEST, lambda p, doc=doc: Path(p).write_text(
                json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8"))


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
    """A drawing process, started now when figures will probably be drawn and there are cores."""
    drawers = Drawers()
    return drawers.start() if likely_to_draw(pairs) else drawers


def draw(jobs: list[Job], dirs=(), drawers: Drawers | None = None) -> None:
    """Have every job's figure in its file, and nothing else in the jobs' directories and in
    ``dirs`` (see the module docstring)."""
    with contextlib.nullcontext(drawers) if drawers is not None else Drawers() as used:
        figures = Figures(used, dirs)
        for job in jobs:
            figures.append(job)
        figures.finish()
