"""Samples on a time grid for every compiled method: ``integrate(..., dt_out=D)``, ``--dt-out D``.

Rules (one set for every compiled method, and for the method option ``dt_out`` of dopri5/dop853):

* The samples are t_k = k D for k = 0, every, 2 every, ... while t_k < T (the end of the
  horizon: ``t_end``, or the end of ``steps`` steps), plus the final point T, spaced as the
  external engines space their output (:class:`~gnibench.suite.cell.grid.SampleGrid` with h = D).
  For [B] §5.2's position-in-orbit drift at t = nT the sample is located at t_k exactly, not at
  the nearest step.
* The steps are exactly those taken without the grid: a sample never changes the trajectory.
* t_k in the accepted step (t_n, t_n+1] is located by the method's continuous extension where it
  applies (adaptive dopri5/dop853 without a step modifier or ``post_step``: Hairer's dense output,
  HNW I §II.6; DOP853's 3 extra f-evaluations per step holding grid points are counted in nfev),
  otherwise by a partial step of the method itself from the last accepted point: step(y_n, t_k -
  t_n) for fixed-step methods, the pair's own step of that size for the embedded pairs, odex's step
  with the lines of the accepted step, each followed by the step modifiers and ``post_step`` as
  every step is. Their f-evaluations are counted in ``nfev``. When t_k coincides with t_n+1 to
  GRID_ULPS ulps, the sample is y_n+1 itself (methods/assembly/templates/events.py).
* Transformed problems (K-S, [B] (5.4)) are integrated in the fictitious time s; the grid is in the
  physical time t, a state component of the transformed system (``Transform.time``). t_k is located
  by the secant method on the partial step size sigma (or by Newton on the continuous extension)
  so that that component equals t_k to round-off, and the sample is mapped back as every sample
  is. T is then the physical time reached at the end of the s-horizon.
* External engines sample on their own ``dt_out`` grid (heyoka's dense output, IAS15's exact
  finish): ``dt_out=D`` sets that option.

A ``dt_out`` given both ways must agree (a one-line UserError otherwise).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from gnibench.suite.cell.compiled import dense_output_refusal
from gnibench.suite.cell.grid import grid
from gnibench.suite.foundation.errors import UserError, named, spelled
from gnibench.suite.foundation.params import Bound

NO_LIMIT = 1 << 62            # grid indices of a grid in a state component (its end is not known)


@dataclass(frozen=True)
class GridPlan:
    """How a compiled cell is sampled on its time grid."""

    dt_out: float
    driver: str               # integrate_grid, adaptive_grid or integrate_dense
    locator: str              # "dense output" or "partial step"
    tcomp: int                # -1: the integration variable; else the state component of t
    n_out: int                # grid indices k < n_out (NO_LIMIT when tcomp >= 0)
    why_not_dense: str = ""

    def describe(self, every: int, time_name: str, rollbacks: float) -> dict:
        return {"dt_out": self.dt_out, "every": every, "locator": self.locator,
                "time": time_name, "grid_intervals": None if self.tcomp >= 0 else self.n_out,
                "nfev": "includes the partial steps" if self.locator == "partial step"
                else "includes the extension's extra stages",
                "why_not_dense": self.why_not_dense, "steps_redone": int(rollbacks),
                "rules": "suite/cell/timegrid.py"}


def check_dt_out(dt_out, name: str = "--dt-out") -> float | None:
    """A grid spacing: None, or a finite number > 0 (``name``: how the user wrote it)."""
    if dt_out is None:
        return None
    if isinstance(dt_out, bool) or not isinstance(dt_out, (int, float)) or not (
            math.isfinite(dt_out) and dt_out > 0):
        raise UserError(f"bad {named(name, repr(dt_out))}; allowed: a finite number > 0")
    return float(dt_out)


def effective_dt_out(method, dt_out: float | None) -> float | None:
    """The grid spacing: the argument, or the method option dt_out of dopri5/dop853 (refused when
    both are given and differ)."""
    option = method.base.values.get("dt_out") if method.base.values.get("adaptive") else None
    option = option if option else None
    if dt_out is not None and option is not None and dt_out != option:
        raise UserError(f"conflicting dt_out: {named('--dt-out', repr(dt_out))} but the method spec has "
                        f"dt_out={option!r}; allowed: one of them, or the same value")
    return dt_out if dt_out is not None else option


def plan(problem: Bound, method, dt_out: float, t_final: float | None,
         tcomp: int = -1) -> GridPlan:
    """The driver and locator of a compiled cell's grid; ``t_final`` is the end of the horizon in
    the grid's time (None when the grid is in a state component)."""
    adaptive = bool(method.base.values.get("adaptive"))
    why = dense_output_refusal(problem, method)
    if tcomp >= 0:
        n_out = NO_LIMIT
    else:
        n_out, _ = grid(dt_out, None, t_final)
    if adaptive and not why:
        return GridPlan(dt_out, "integrate_dense", "dense output", tcomp, n_out)
    return GridPlan(dt_out, "adaptive_grid" if adaptive else "integrate_grid", "partial step",
                    tcomp, n_out, why)


def engine_method(method, dt_out: float, problem=None):
    """An external engine's method with its output grid ``dt_out`` set to D (refused when the spec
    gives another value, or when the engine's grid is its step h). The default dt_out is in units
    of the problem's time scale (:meth:`Problem.time_scale_of`)."""
    from dataclasses import replace

    rec = method.base.record
    if getattr(rec, "grid_param", "h") != "dt_out":
        raise UserError(f"bad {spelled('--dt-out')} for {rec.id}: it is fixed-step and samples "
                        f"every K steps of h; allowed: {named('--every', 'K')}")
    default = next(p.default for p in rec.params if p.name == "dt_out")
    if problem is not None:
        default *= problem.record.time_scale_of(problem.values)
    given = method.base.values["dt_out"]
    if given not in (default, dt_out):
        raise UserError(f"conflicting dt_out: {named('--dt-out', repr(dt_out))} but the method spec has "
                        f"dt_out={given!r}; allowed: one of them, or the same value")
    base = Bound(rec, {**method.base.values, "dt_out": dt_out})
    return replace(method, base=base)
