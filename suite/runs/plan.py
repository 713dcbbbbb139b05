"""Which cells a free worker of the local pool runs next (:mod:`gnibench.suite.runs.pool`).

* **By kernel.** The cells come in groups that share a compiled kernel, in the order the runner
  gives (the kernels not compiled yet first, the costliest first). The first cell of a group whose
  kernel must be compiled runs alone (it compiles the kernel into the disk cache); once it is
  done, the rest of the group goes preferably to the worker that ran it (the kernel is loaded
  there). A free worker takes the next group not yet started (kernels compile in parallel), and
  only then helps with the largest group under way (it loads the kernel from the disk cache). A
  group whose kernel is in the disk cache already (``warm``) does not wait for its first cell: a
  free worker helps with it at once.
* **Longest first.** Within a group the longest cells go first (:func:`longest_first`), so that
  short ones fill the end of the run.
* **In batches.** A worker gets the cells of a group a batch at a time (:meth:`Plan.batch`):
  as many as take about ``BATCH_SECONDS`` by the group's measured cost per cell (one until a cell
  of the group has been measured), at most ``MAX_BATCH``, and at most a ``1 / (2 workers)`` share of
  the cells left, so that the batches shrink towards the end of the run and the workers finish
  together. A batch only decides which process runs a cell, never its numbers.
"""
from __future__ import annotations

import math
from collections import deque

BATCH_SECONDS = 0.05      # the work a worker gets at a time, once a group's cost is measured
MAX_BATCH = 64


def _planned_steps(cell) -> int:
    try:
        return int(cell.spec.nsteps)
    except Exception:  # noqa: BLE001 - an estimate only
        return 0


def longest_first(group: list) -> list:
    """A kernel group's cells, the longest first (so that short cells fill the end of the run):
    by planned steps (the cells of a group run one kernel: the same cost per step), ties (adaptive
    methods) in reverse cell order (a sweep lists its coarsest step or loosest tolerance first)."""
    backwards = list(reversed(group))               # sorted is stable: ties stay backwards
    return sorted(backwards, key=lambda c: -_planned_steps(c))


class Plan:
    """Which cells a free worker runs next (see the module docstring). ``warm[i]``: the kernel of
    ``groups[i]`` is in the disk cache already (default: none is)."""

    def __init__(self, groups: list[list], warm: list[bool] | None = None):
        warm = [False] * len(groups) if warm is None else list(warm)
        kept = [(g, w) for g, w in zip(groups, warm) if g]
        self.waiting = [deque(longest_first(g)) for g, _ in kept]         # not started
        self.warm = {id(d) for d, (_, w) in zip(self.waiting, kept) if w}
        self.open: list[deque] = []                          # compiled, cells left
        self.compiling: dict[int, deque] = {}                # id(first cell) -> rest of its group
        self.home: dict[int, deque] = {}                     # worker -> the group it loaded
        self.left = sum(len(g) for g, _ in kept)             # cells not handed out yet
        self.group_of = {id(c): i for i, d in enumerate(self.waiting) for c in d}
        self.cost: dict[int, float] = {}                     # group -> measured seconds per cell

    def next_for(self, w: int):
        """The next cell for worker ``w`` (None: nothing for it now)."""
        cell = self._next_for(w)
        if cell is not None:
            self.left -= 1
        return cell

    def batch(self, w: int, workers: int = 1) -> list:
        """The next cells for worker ``w``, all of one group (empty: nothing for it now): the first
        cell of a group to compile alone, else a batch sized as the module docstring says."""
        first = self.next_for(w)
        if first is None:
            return []
        cells = [first]
        group = self.home.get(w)
        if id(first) in self.compiling or group is None:
            return cells
        cost = self.cost.get(self.group_of.get(id(first)))
        if cost is None:
            return cells
        n = max(1, min(MAX_BATCH, int(BATCH_SECONDS / max(cost, 1e-9)),
                       math.ceil(self.left / (2 * max(workers, 1)))))
        while len(cells) < n and group:
            cells.append(group.popleft())
            self.left -= 1
        return cells

    def _next_for(self, w: int):
        group = self.home.get(w)
        if group:                                             # its kernel is loaded here
            return group.popleft()
        if self.waiting:                                      # compile another kernel
            group = self.waiting.pop(0)
            first = group.popleft()
            if id(group) in self.warm:                        # in the disk cache: no waiting
                self.open.append(group)
            else:
                self.compiling[id(first)] = group
            self.home[w] = group
            return first
        self.open = [g for g in self.open if g]
        if self.open:                                         # help the largest group left
            group = max(self.open, key=len)
            self.home[w] = group
            return group.popleft()
        return None

    def done(self, cell) -> None:
        """``cell`` has finished: the rest of its group is open to every worker."""
        group = self.compiling.pop(id(cell), None)
        if group is not None and group:
            self.open.append(group)

    def measured(self, cells: list, seconds: float) -> None:
        """``cells`` (of one group) took ``seconds`` together: the group's cost per cell."""
        if cells:
            group = self.group_of.get(id(cells[0]))
            if group is not None:
                self.cost[group] = seconds / len(cells)
