"""Progress on stderr: a bar on a terminal (tqdm), plain lines otherwise.

:class:`RunProgress` follows a matrix: cells done of all, failures so far, elapsed time, ETA and
the cells running now with how far each got. :class:`SolveProgress` follows one integration
(fraction of the horizon, or of the section crossings) and stays silent for the first couple of
seconds of the integration, so short commands print nothing. When stderr is not a terminal, both write plain lines
(a line per finished cell; a line every ``LINE_SECONDS`` for long work), which logs and CI keep
readable.
"""
from __future__ import annotations

import sys
import time

QUIET_SECONDS = 2.0        # a solve shorter than this shows no progress
LINE_SECONDS = 10.0        # plain lines: at most one progress line per this many seconds


def is_terminal(stream) -> bool:
    return hasattr(stream, "isatty") and stream.isatty()


def _bar(total: float, desc: str, stream, unit: str):
    from tqdm import tqdm

    # no monitor thread: the local pool forks workers after the bar exists
    tqdm.monitor_interval = 0
    return tqdm(total=total, desc=desc, file=stream, unit=unit, dynamic_ncols=True, leave=True,
                mininterval=0.2)


class RunProgress:
    """Progress of a matrix of cells."""

    def __init__(self, total: int, reused: int, stream=None, name: str = "cells"):
        self.stream = sys.stderr if stream is None else stream
        self.total, self.done, self.failed = total, reused, 0
        self.running: dict[int, float] = {}
        self.t0 = self.last_line = time.monotonic()
        self.bar = None
        if is_terminal(self.stream):
            self.bar = _bar(total, name, self.stream, "cell")
            self.bar.update(reused)

    def cell_progress(self, cell_id: int, fraction: float) -> None:
        self.running[cell_id] = fraction
        if self.bar is not None:
            self._postfix()
        elif time.monotonic() - self.last_line >= LINE_SECONDS:
            self.last_line = time.monotonic()
            now = ", ".join(f"cell {c} {f:.0%}" for c, f in sorted(self.running.items()))
            self._line(f"running: {now}")

    def cell_done(self, outcome) -> None:
        self.done += 1
        self.running.pop(outcome.cell.id, None)
        if outcome.status not in ("ok",):
            self.failed += 1
        if self.bar is not None:
            self.bar.update(1)
            self._postfix()
        else:
            self._line(_describe(outcome))

    def _postfix(self) -> None:
        now = " ".join(f"{c}:{f:.0%}" for c, f in sorted(self.running.items())[:4])
        self.bar.set_postfix_str(f"failed {self.failed}" + (f" | running {now}" if now else ""),
                                 refresh=False)

    def _line(self, text: str) -> None:
        elapsed = time.monotonic() - self.t0
        print(f"[{self.done}/{self.total}] {elapsed:.0f} s: {text}", file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _describe(o) -> str:
    c, timing = o.cell, o.timing
    line = f"cell {c.id}: {c.problem} {c.method}: {o.status}"
    ens = getattr(c, "ensemble", None)
    if ens is not None and o.status != "error":         # a unit of an ensemble: its orbits
        orbits = f"orbits {ens.first}-{ens.first + ens.n - 1} of {ens.total}"
        return (f"{line}, {orbits}, compile/load {timing['compile_seconds']:.2f} s, run "
                f"{timing['wall_seconds'] * 1e3:.3g} ms" + (f" ({o.reason})" if o.reason else ""))
    if o.status != "error":
        steps = o.row["steps"]                  # None: a Python solver that reports none
        steps = "steps not reported" if steps is None else f"{steps} steps"
        line += (f", {steps}, compile/load {timing['compile_seconds']:.2f} s, "
                 f"run {timing['wall_seconds'] * 1e3:.3g} ms")
    return line + (f" ({o.reason})" if o.reason else "")


class SolveProgress:
    """Progress of one integration: call it with the fraction done.

    The clock starts at the first call (the compiled driver has returned once: the kernel is
    compiled or loaded and the integration runs), so compiling is not counted as progress; the
    first plain line comes ``QUIET_SECONDS`` after that, then one every ``LINE_SECONDS``."""

    def __init__(self, what: str, stream=None):
        self.stream = sys.stderr if stream is None else stream
        self.what = what
        self.t0 = self.last_line = None
        self.bar = None

    def __call__(self, fraction: float) -> None:
        now = time.monotonic()
        if self.t0 is None:
            self.t0, self.last_line = now, now - LINE_SECONDS
        if now - self.t0 < QUIET_SECONDS:
            return
        if is_terminal(self.stream):
            if self.bar is None:
                self.bar = _bar(1.0, self.what, self.stream, "")
                self.bar.bar_format = "{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}"
            self.bar.n = min(max(fraction, 0.0), 1.0)
            self.bar.refresh()
        elif now - self.last_line >= LINE_SECONDS:
            self.last_line = now
            print(f"gnibench: {self.what}: {fraction:.0%} after {now - self.t0:.0f} s",
                  file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
