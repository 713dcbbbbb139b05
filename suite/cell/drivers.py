"""The compiled drivers as objects, one per kind: their arguments, state, calls and trajectory.

Every compiled cell runs one of the resumable drivers of its kernel modules
(methods/assembly/bindings.py ``DRIVERS``): the fixed-step loop (templates/fixed.py:
``integrate``, ``integrate_grid``, ``integrate_section``) or the adaptive loop shared by the
embedded pairs and odex (templates/adaptive.py: ``integrate_adaptive``, ``integrate_dense``,
``adaptive_grid``, ``adaptive_section``, ``adaptive_section_dense``), each in the module of its
output. :class:`FixedStepDriver` and :class:`AdaptiveDriver` are the one
place where their arguments are packed, their state (``y_io``, ``st``) is laid out and read by the
slot names of methods/assembly/templates/slots.py, their calls are run (:func:`.calls.run_driver`: budget,
buffers, progress, Ctrl-C) and their kernels warmed up. :func:`build_trajectory` is the one place
a :class:`~gnibench.suite.cell.trajectory.Trajectory` is built, for every kind of cell (compiled,
external engine, transformed problem, section crossings).
"""
from __future__ import annotations

import time
from dataclasses import replace
from typing import ClassVar

import numpy as np
from gnibench.methods.assembly.loading import compiling, record_compiled
from gnibench.methods.assembly.templates.slots import (
    ROW_Y,
    SLOTS,
    ST_NFEV,
    ST_REJECTED,
    ST_STEPS,
    ST_T,
    ST_TCOMP,
    ST_WANTED,
    STATE,
    Y_ROWS,
)
from gnibench.suite.cell.calls import COUNTERS, Buffers, Progress, run_driver
from gnibench.suite.cell.compiled import CompiledCell, compile_cell, forget_damaged, problem_kernel
from gnibench.suite.cell.trajectory import Trajectory
from gnibench.suite.foundation.cache import warn
from gnibench.suite.foundation.params import Bound
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.foundation.status import Status


def build_trajectory(problem: Bound, method, t, y, counters, status: Status, reason: str,
                     provenance: dict, kind: str = "samples", chart=None) -> Trajectory:
    """The record of one cell: samples (t, y) in the problem's own variables, the cumulative
    counters (columns steps, nfev, njev, rejected), the problem's integrals at every sample and at
    y0, status and provenance (given in the caller's order)."""
    rec = problem.record
    pk = problem_kernel(problem)
    y0 = tuple(float(v) for v in rec.y0(problem.values))
    t = np.ascontiguousarray(t, dtype=np.float64)
    y = np.ascontiguousarray(y, dtype=np.float64).reshape(len(t), rec.dim)
    c = np.asarray(counters, dtype=np.float64)
    c = c.reshape(len(t), -1) if len(t) else np.zeros((0, max(c.shape[-1] if c.ndim == 2 else 0,
                                                               COUNTERS - 1)))   # no rows at all
    steps = c[:, 0].astype(np.int64) if np.isfinite(c[:, 0]).all() else c[:, 0].copy()
    return Trajectory(
        problem=problem.text(), method=method.text(), state_names=rec.state, t=t, y=y,
        steps=steps, nfev=c[:, 1].copy(), njev=c[:, 2].copy(),
        rejected=c[:, 3].copy(), integral_names=pk.integral_names, integrals=pk.integrals(y),
        H0=pk.at(y0), y0=y0, status=status, reason=reason, kind=kind, chart=chart,
        provenance=provenance)


class Driver:
    """One run of a compiled resumable driver (``name``, a function of the cell's module).

    ``every``: a sample every K steps (or grid points); ``dt_out``, ``n_out``: the time grid
    t_k = k dt_out, k < n_out (grid drivers); ``tcomp``: the state component that is the grid's
    time (-1: the integration variable); ``wanted``: crossings after which a section driver stops.
    """

    kind = ""
    names: ClassVar[dict[str, str]] = {}    # the kind's drivers: samples, grid, section, ...

    def __init__(self, problem: Bound, method, name: str, *, every: int = 1, dt_out: float = 0.0,
                 n_out: int = 0, tcomp: int = -1, wanted: int = 0,
                 cell: CompiledCell | None = None):
        self.problem, self.method, self.name = problem, method, name
        self.cell = cell if cell is not None else ready_cell(problem, method, name)
        self.fn = self.cell.driver(name)
        self.every, self.dt_out, self.n_out = int(every), float(dt_out), int(n_out)
        self.y_io = np.zeros((Y_ROWS, problem.record.dim))
        self.y_io[ROW_Y] = self.cell.y0
        self.st = np.zeros(STATE)
        self.st[ST_TCOMP] = tcomp
        self.st[ST_WANTED] = wanted

    # -- the state, by slot name (methods/assembly/templates/slots.py) ---------------------------
    def slot(self, name: str) -> float:
        return float(self.st[SLOTS[name]])

    @property
    def steps(self) -> int:
        """Accepted steps so far."""
        return int(self.st[ST_STEPS])

    @property
    def nfev(self) -> float:
        return float(self.st[ST_NFEV])

    @property
    def rejected(self) -> int:
        return int(self.st[ST_REJECTED])

    # -- the calls -------------------------------------------------------------------------------
    def args(self) -> tuple:
        raise NotImplementedError

    def call(self, budget: int, out_t, out_y, out_c):
        """One call of the compiled driver: (status code, rows written)."""
        return self.fn(self.y_io, self.st, self.cell.par, *self.args(), budget, out_t, out_y,
                       out_c)

    def fraction(self) -> float:
        """How far the run got (progress): of the horizon, or of the crossings wanted."""
        if self.st[ST_WANTED] > 0:
            return max(self.slot("ST_FOUND") / self.st[ST_WANTED], self.t / self.t_final)
        return self.done_fraction()

    def done_fraction(self) -> float:
        raise NotImplementedError

    def run(self, buffers: Buffers, progress: Progress | None = None,
            budget: int | None = 0) -> tuple[Status, float]:
        """Call the driver until it is done (:func:`.calls.run_driver`): (status, wall seconds)."""
        return run_driver(self.call, buffers, self.fraction, progress, budget)

    def warm_up(self) -> None:
        """One step on scratch buffers: loads (or compiles) the driver and all it calls."""
        dim = self.problem.record.dim
        self.call(1, np.empty(3), np.empty((3, dim)), np.zeros((3, COUNTERS)))

    # -- the results -----------------------------------------------------------------------------
    def trajectory(self, buffers: Buffers, status: Status, reason: str, meta: dict,
                   wall: float) -> Trajectory:
        """The samples of a run with the cell's provenance (``meta``: horizon and sampling)."""
        t, y, c = buffers.arrays()
        cell = self.cell
        prov = {"versions": versions(), **meta, "seed": None, "y0": list(cell.y0),
                "H0": list(cell.H0), "wall_seconds": wall,
                "compile_seconds": cell.compile_seconds, "numba_cache_misses": cell.cache_misses}
        return build_trajectory(self.problem, self.method, t, y, c, status, reason, prov)


class FixedStepDriver(Driver):
    """``nsteps`` steps of size ``h`` (the last one ``h_last``); t_n = n h (negative h: backward)."""

    kind = "fixed step"
    names: ClassVar[dict[str, str]] = {"samples": "integrate", "grid": "integrate_grid", "section": "integrate_section"}

    def __init__(self, problem: Bound, method, name: str, h: float, nsteps: int, h_last: float,
                 **kw):
        self.h, self.nsteps, self.h_last = float(h), int(nsteps), float(h_last)
        super().__init__(problem, method, name, **kw)

    def args(self) -> tuple:
        return (self.h, self.nsteps, self.h_last, self.every, self.dt_out, self.n_out)

    @property
    def t(self) -> float:
        """The time reached."""
        done = self.steps
        return done * self.h if done < self.nsteps else (self.nsteps - 1) * self.h + self.h_last

    @property
    def t_final(self) -> float:
        return (self.nsteps - 1) * self.h + self.h_last

    def done_fraction(self) -> float:
        return self.steps / self.nsteps

    def reason(self, status: Status) -> str:
        done = self.steps
        maxit = self.method.base.values.get("newton_maxit", "-")
        return {Status.NONFINITE: f"state overflowed or became NaN at step {done + 1}",
                Status.NEWTON_FAILED: f"Newton (or the projection) did not converge at step "
                                      f"{done + 1}; raise newton_maxit (now {maxit}) or lower h"
                }.get(status, "")

    def meta(self) -> dict:
        return {"h": self.h, "nsteps": self.nsteps, "h_last": self.h_last, "every": self.every}

    @classmethod
    def scratch(cls, problem: Bound, method, name: str, cell: CompiledCell) -> FixedStepDriver:
        h = float(method.base.values.get("h", 0.01))
        return cls(problem, method, name, h, 1, h, dt_out=0.5 * h, n_out=1, wanted=1, cell=cell)


class AdaptiveDriver(Driver):
    """Adaptive steps to ``t_end``, with the method's controller options (rtol, atol, h0, hmax,
    max_steps) unless given."""

    kind = "adaptive"
    names: ClassVar[dict[str, str]] = {"samples": "integrate_adaptive", "grid": "adaptive_grid", "dense": "integrate_dense",
             "section": "adaptive_section", "section_dense": "adaptive_section_dense"}

    def __init__(self, problem: Bound, method, name: str, t_end: float, *,
                 options: dict | None = None, **kw):
        v = {**method.base.values, **(options or {})}
        self.t_end = float(t_end)
        self.h0, self.rtol, self.atol = float(v["h0"]), float(v["rtol"]), float(v["atol"])
        self.hmax = float(v["hmax"]) if v["hmax"] > 0 else self.t_end
        self.max_steps = int(v["max_steps"])
        super().__init__(problem, method, name, **kw)

    def args(self) -> tuple:
        return (self.t_end, self.h0, self.hmax, self.rtol, self.atol, self.every, self.dt_out,
                self.n_out, self.max_steps)

    @property
    def t(self) -> float:
        return float(self.st[ST_T])

    @property
    def t_final(self) -> float:
        return self.t_end

    def done_fraction(self) -> float:
        return self.t / self.t_end

    def reason(self, status: Status) -> str:
        t = self.t
        return {Status.MAX_STEPS: f"more than max_steps={self.max_steps} steps before t = "
                                  f"{self.t_end:g}",
                Status.STEP_TOO_SMALL: f"step size underflow at t = {t:.17g} (stiff, or "
                                       f"diverging)",
                Status.NEWTON_FAILED: f"the projection did not converge at t = {t:.17g}",
                }.get(status, "")

    def meta(self) -> dict:
        return {"h": self.h0, "t_end": self.t_end, "every": self.every, "accepted": self.steps,
                "rejected": self.rejected}

    @classmethod
    def scratch(cls, problem: Bound, method, name: str, cell: CompiledCell) -> AdaptiveDriver:
        options = {"h0": 1e-3, "hmax": 1.0, "rtol": 1e-3, "atol": 1e-3, "max_steps": 1}
        return cls(problem, method, name, 1.0, options=options, dt_out=0.5, n_out=2, wanted=1,
                   cell=cell)


def kind_of(method) -> type[Driver]:
    """The driver kind of a compiled method: adaptive (option ``adaptive``) or fixed step."""
    return AdaptiveDriver if method.base.values.get("adaptive") else FixedStepDriver


def ready_cell(problem: Bound, method, name: str | None = None) -> CompiledCell:
    """The cell's kernels loaded (:func:`.compiled.compile_cell`) and the driver ``name`` (by
    default the plain one of its kind) warmed up by one step, so that compiling or loading from
    numba's disk cache is timed apart from the integration: ``compile_seconds`` is what this call
    took."""
    kind = kind_of(method)
    name = name or kind.names["dense" if method.base.values.get("dt_out", 0.0) > 0.0
                              and kind is AdaptiveDriver else "samples"]
    t0 = time.perf_counter()
    with compiling():
        try:
            cell = _warm(kind, problem, method, name)
        except OSError:                 # a full disk, say: not a damaged cache entry
            raise
        except Exception as e:
            # numba's cache files verified by their manifest may still fail to load (rewritten
            # together with it): discarded and compiled afresh, once; any other failure is raised
            if not forget_damaged(problem, method):
                raise
            warn(f"compiled kernels of {problem.id} x {method.id} could not be loaded from the "
                 f"kernel cache ({type(e).__name__}); discarded and recompiled")
            cell = _warm(kind, problem, method, name)
    return replace(cell, compile_seconds=time.perf_counter() - t0)


def _warm(kind, problem: Bound, method, name: str) -> CompiledCell:
    cell = compile_cell(problem, method)
    if name not in cell.warm:
        kind.scratch(problem, method, name, cell).warm_up()
        cell.warm.add(name)
        record_compiled(*cell.loaded())
    return cell
