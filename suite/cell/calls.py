"""Calling a resumable compiled driver: output buffers, work budget, progress and Ctrl-C.

Every compiled driver (methods/assembly/templates/fixed.py, adaptive.py, extrapolation.py and their grid and
section variants) keeps its whole state in ``y_io`` and ``st`` and returns ``STATUS_BUFFER_FULL``
(its output buffer is full) or ``STATUS_PAUSED`` (the work budget of one call is spent) to be
called again; :func:`run_driver` does so, with a budget tuned so that one call lasts about
``CALL_SECONDS`` (progress reports and Ctrl-C are handled between calls, so an interrupt stops any
integration within a fraction of a second) and a new buffer whenever one is full. Only the time
spent inside the compiled calls counts as wall time. The results do not depend on the buffer size
or the budget (tests/cell/test_sections.py, tests/cell/test_time_grid.py).
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from gnibench.suite.foundation.errors import spelled
from gnibench.suite.foundation.status import Status

CALL_SECONDS = 0.1          # target duration of one call of a compiled driver
FIRST_BUDGET = 256          # steps (attempts) in the first call, then scaled to CALL_SECONDS
UNLIMITED = 1 << 62
#: counter columns of the output buffer: steps, nfev, njev, rejected, size of the last step
COUNTERS = 5

Progress = Callable[[float], None]


def row_budget(dim: int) -> int:
    """The most rows a cell's growing buffers may hold: ``GNIBENCH_MAX_ROWS``, and no more than
    ``GNIBENCH_MAX_OUTPUT_MB`` of t, y and the counters (:mod:`gnibench.suite.foundation.budgets`,
    checked before the run for the rows a horizon plans; this bounds the rows it did not plan)."""
    from gnibench.suite.foundation.budgets import limit

    per_row = 8 * (1 + dim + COUNTERS)
    return max(2, min(limit("GNIBENCH_MAX_ROWS"), limit("GNIBENCH_MAX_OUTPUT_MB") * 2 ** 20 // per_row))


def budget_reason(status: Status, buffers: Buffers, t: float) -> str:
    """Why a run ended by the output budget (``max_rows``), with the numbers; "" otherwise."""
    if status is not Status.MAX_ROWS:
        return ""
    from gnibench.suite.foundation.budgets import limit

    rows = buffers.rows
    return (f"the output budget is full at t = {t:.17g} after {rows} rows (at most {buffers.cap} "
            f"rows of {buffers.dim} states: GNIBENCH_MAX_ROWS={limit('GNIBENCH_MAX_ROWS')}, "
            f"GNIBENCH_MAX_OUTPUT_MB={limit('GNIBENCH_MAX_OUTPUT_MB')}); sample less often "
            f"({spelled('--every')}, {spelled('--dt-out')}) or raise the limits")


class Buffers:
    """Output buffers of a compiled driver: the rows written so far, and views with room left.

    With a ``sink`` (``sink(t, y, c)``, and ``sink.rows``: the rows of one block), a full buffer is
    handed to the sink and reused, so that memory does not grow with the rows (``gnibench solve``
    writing a file, :mod:`gnibench.suite.runs.streaming`); :meth:`arrays` then hands over the
    rows left and returns the last row only. The row budget (:func:`row_budget`) counts every row
    either way."""

    def __init__(self, rows: int, dim: int, grow: bool, sink=None):
        self.dim, self.grow, self.chunks, self.sink = dim, grow, [], sink
        self.before = 0                 # rows in the chunks already full (or handed to the sink)
        self.cap = row_budget(dim)
        rows = max(min(int(rows), self.cap) if grow else int(rows), 2)
        if not grow:                    # sized for the horizon, checked before the run
            self.cap = max(self.cap, rows)
        self._new(rows if sink is None else max(min(rows, sink.rows, self.cap), 2))

    def _new(self, rows: int) -> None:
        self.t, self.y = np.empty(rows), np.empty((rows, self.dim))
        self.c = np.zeros((rows, COUNTERS))
        self.row = 0
        self.chunks.append(self)

    def views(self):
        r = self.row
        return self.t[r:], self.y[r:], self.c[r:]

    def advance(self, rows: int) -> None:
        self.row += rows

    def full(self) -> bool:
        """The driver asked for room (BUFFER_FULL): keep what is written, start a new buffer (twice
        as large when not even one step's rows fitted into an empty one); False, and no new
        buffer, once the rows would pass :func:`row_budget` (a K-S run whose physical time ran
        away asked for 10^7 rows in one step and the next buffer doubled until the OOM killer
        ended the worker)."""
        if not self.grow and self.sink is None:
            raise RuntimeError("compiled driver: output buffer too small (sized for the horizon)")
        size = min(len(self.t) if self.row else 2 * len(self.t), self.cap - self.before - self.row)
        if size <= 0 or (not self.row and size <= len(self.t)):
            return False                # no room left, or one step needs more than is left
        if self.sink is not None:
            self._hand_over()
            if size != len(self.t):     # a step's rows that did not fit, or the budget's last
                self.chunks.pop()
                self._new(size)
            return True
        self.before += self.row
        if not self.row:                # nothing written: this buffer is replaced, not kept
            self.chunks.pop()
            self._new(size)
            return True
        kept = Buffers.__new__(Buffers)
        kept.t, kept.y, kept.c = self.t[:self.row], self.y[:self.row], self.c[:self.row]
        self.chunks[-1] = kept
        self._new(size)
        return True

    def _hand_over(self) -> None:
        """The rows written so far to the sink; the buffer is free again."""
        r = self.row
        self.before, self.row = self.before + r, 0      # counted first: a Ctrl-C in the sink
        if r:                                           # must not hand them over twice
            self.last = self.t[r - 1:r].copy(), self.y[r - 1:r].copy(), self.c[r - 1:r].copy()
            self.sink(self.t[:r], self.y[:r], self.c[:r])

    def arrays(self):
        if self.sink is not None:       # the rows left to the sink; the last row is kept
            self._hand_over()
            return getattr(self, "last", (self.t[:0], self.y[:0], self.c[:0]))
        parts = self.chunks[:-1] + [self]
        t = np.concatenate([p.t[:p.row] if p is self else p.t for p in parts])
        y = np.concatenate([p.y[:p.row] if p is self else p.y for p in parts])
        c = np.concatenate([p.c[:p.row] if p is self else p.c for p in parts])
        return t, y, c

    @property
    def rows(self) -> int:
        """The rows written in all (handed to the sink or kept)."""
        return self.before + self.row


def run_driver(call: Callable, buffers: Buffers, fraction: Callable[[], float],
               progress: Progress | None, budget: int | None) -> tuple[Status, float]:
    """Call a resumable driver (``call(budget, out_t, out_y, out_c) -> (code, rows)``) until it
    returns a final status; return it and the seconds spent inside the calls.

    ``budget``: steps per call; 0 tunes it to ``CALL_SECONDS`` a call, None does the whole
    horizon in one call (the benchmark loop)."""
    wall = 0.0
    b = UNLIMITED if budget is None else (budget or FIRST_BUDGET)
    while True:
        try:        # Ctrl-C inside a call, or between calls (progress, budget): keep the rows
            t0 = time.perf_counter()
            code, rows = call(b, *buffers.views())
            dt = time.perf_counter() - t0
            wall += dt
            buffers.advance(int(rows))
            status = Status.from_code(int(code))
            if status is Status.BUFFER_FULL:
                if not buffers.full():                  # the output budget is spent
                    return Status.MAX_ROWS, wall
            elif status is not Status.PAUSED:
                return status, wall
            if progress is not None:
                progress(fraction())
            if budget == 0 and status is Status.PAUSED:      # tune the next call to CALL_SECONDS
                scale = CALL_SECONDS / max(dt, 1e-6)
                b = int(min(max(b * min(scale, 8.0), b / 4.0, 16), UNLIMITED))
        except KeyboardInterrupt:
            return Status.INTERRUPTED, wall
