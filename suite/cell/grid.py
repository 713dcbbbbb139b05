"""Horizons and sample grids: how many steps a cell takes and at which times it is sampled."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gnibench.suite.foundation.budgets import INT_LIMIT, check_integer
from gnibench.suite.foundation.errors import UserError, named


def grid(h: float, steps: int | None, t_end: float | None) -> tuple[int, float]:
    """Number of steps and the last step: n steps of h, or reach t_end exactly (last step shorter)."""
    if (steps is None) == (t_end is None):
        raise UserError(f"give exactly one of {named('--steps', 'N')} or {named('--t-end', 'T')}")
    if steps is not None:
        check_integer(steps, "--steps")
        return int(steps), h
    if not (t_end > 0 and math.isfinite(t_end)):
        raise UserError(f"bad {named('--t-end', str(t_end))}; allowed: a finite number > 0")
    ratio = t_end / h
    if not ratio < INT_LIMIT:
        raise UserError(f"{named('--t-end', format(t_end, 'g'))} with a step (or output interval) "
                        f"of {h:g} needs more than 2^62 steps; "
                        f"allowed: a larger step or a shorter horizon")
    n = round(ratio)
    if n >= 1 and abs(ratio - n) <= 1e-9 * max(1.0, ratio):
        return n, t_end - (n - 1) * h
    n = math.ceil(ratio)
    return n, t_end - (n - 1) * h


@dataclass(frozen=True)
class SampleGrid:
    """The sample times of a cell, as the compiled driver takes them.

    ``nsteps`` steps of ``h`` (the last one ``h_last``) sampled every ``every`` steps plus the final
    point, and t = 0. External adaptive engines land on the same times (with ``h`` = dt_out).
    """

    h: float
    nsteps: int
    h_last: float
    every: int

    @property
    def step(self) -> np.ndarray:
        """Step index of each sample."""
        idx = np.arange(0, self.nsteps + 1, self.every)
        return idx if idx[-1] == self.nsteps else np.append(idx, self.nsteps)

    @property
    def t(self) -> np.ndarray:
        k = self.step
        return np.where(k < self.nsteps, k * self.h, (self.nsteps - 1) * self.h + self.h_last)

    @property
    def rows(self) -> int:
        """Number of samples: t = 0, every ``every``-th step, and the last step."""
        return sample_rows(self.nsteps, self.every)


def sample_rows(nsteps: int, every: int) -> int:
    """Samples of ``nsteps`` steps sampled every ``every`` steps: t = 0, every ``every``-th step
    and the last one."""
    return 1 + nsteps // every + (1 if nsteps % every else 0)


def grid_step(method) -> float:
    """The option that spaces a method's grid: its step h, or dt_out for an adaptive engine."""
    return float(method.base.values[getattr(method.base.record, "grid_param", "h")])
