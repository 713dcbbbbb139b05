"""Exact solutions evaluated block by block exactly as in one array.

An iteration run on a whole array until *every* element has converged (Newton on Kepler's
equation, :func:`gnibench.problems.kepler_exact.solve_kepler`) gives each element a value that
depends on the other elements: the elements that converged early take the extra sweeps the slowest
one needs, and a sweep at round-off may move an element by an ulp. ``gnibench solve`` evaluates the
exact solution on blocks of samples (its memory does not grow with the number of rows,
:mod:`gnibench.suite.runs.streaming`), and must give the bytes the one-array evaluation gives.

Such an iteration is written as :func:`sweeps` (``sweep(x) -> (x, all converged)``). Outside a
:class:`Plan` it is the plain loop. Inside a recording plan each evaluation (one block) records at
which sweeps all of its elements had converged; :meth:`Plan.fix` then finds the sweep count of the
one-array loop (the first sweep at which every block had converged) and each later evaluation runs
exactly that many sweeps. Several iterations in one evaluation are told apart by their order.
"""
from __future__ import annotations

import contextlib
from contextvars import ContextVar

_PLAN: ContextVar[Plan | None] = ContextVar("gnibench_blockwise_plan", default=None)
#: sweeps recorded past a block's own convergence (enough unless convergence is lost again)
MARGIN = 8


def sweeps(sweep, x, limit: int):
    """``x`` after the sweeps of ``sweep(x) -> (x, converged)``: until converged (at most
    ``limit``), or as the current :class:`Plan` says."""
    plan = _PLAN.get()
    if plan is None:
        for _ in range(limit):
            x, done = sweep(x)
            if done:
                break
        return x
    return plan.run(sweep, x, limit)


class Plan:
    """The sweep counts of the iterations of an evaluation split into blocks (see the module
    docstring): record every block (:meth:`evaluating`), :meth:`fix`, then evaluate again."""

    def __init__(self, margin: int = MARGIN):
        self.margin = margin
        self.records: list[list[tuple[list[bool], int]]] = []   # per iteration: per block
        self.counts: list[int] | None = None                   # fixed: sweeps per iteration
        self._calls = 0

    @contextlib.contextmanager
    def evaluating(self):
        """One block's evaluation under this plan."""
        self._calls = 0
        token = _PLAN.set(self)
        try:
            yield self
        finally:
            _PLAN.reset(token)

    def run(self, sweep, x, limit: int):
        i, self._calls = self._calls, self._calls + 1
        if self.counts is not None:
            for _ in range(self.counts[i] if i < len(self.counts) else limit):
                x, _ = sweep(x)
            return x
        flags, stop = [], limit
        for k in range(limit):
            x, done = sweep(x)
            flags.append(bool(done))
            if done and stop == limit:
                stop = min(limit, k + 1 + self.margin)
            if k + 1 >= stop:
                break
        while len(self.records) <= i:
            self.records.append([])
        self.records[i].append((flags, limit))
        return x

    def fix(self) -> bool:
        """Fix the sweep counts from the records: False when a record is too short to tell
        (record again with a larger margin)."""
        counts = []
        for blocks in self.records:
            limit = blocks[0][1]
            found = limit
            for k in range(limit):
                known = [flags[k] for flags, _ in blocks if k < len(flags)]
                if not all(known):
                    continue                    # some block had not converged at sweep k + 1
                if len(known) < len(blocks):
                    return False                # unknown for a block whose record stopped
                found = k + 1
                break
            counts.append(found)
        self.counts = counts
        return True
