"""The driver facade: the one function through which every cell is integrated.

:func:`integrate` takes a parsed problem and method and returns a
:class:`~gnibench.suite.cell.trajectory.Trajectory`, whatever the kind of cell:

* compiled fixed-step methods (``methods/kernels/driver.py``), and compiled adaptive methods
  (embedded pairs with Hairer's control, odex), sampled every K steps;
* adaptive pairs with dense output on a time grid (``dt_out``; methods/dense_output.py);
* Poincaré section crossings (``section=K``; :mod:`gnibench.suite.cell.sections`);
* external engines (heyoka, rebound: ``Method.run``);
* transformed problems (K-S, [B] (5.4)): the transformed system is integrated and its samples
  mapped back;
* the benchmark loop (``gnibench bench``: ``budget=None``, one call of the compiled driver).

The compiled drivers are resumable: the facade calls them until they are done, with a work budget
per call tuned so that one call lasts about ``CALL_SECONDS`` (progress reports and Ctrl-C are
handled between calls, so an interrupt stops any integration within a fraction of a second) and
a new output buffer whenever one is full. Only the time spent inside the compiled calls counts as
wall time.
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from gnibench.suite.cell.compiled import (
    ADAPTIVE_STATE,
    COUNTERS,
    FIXED_STATE,
    CompiledCell,
    compile_cell,
    dense_output_refusal,
    problem_kernel,
)
from gnibench.suite.cell.grid import SampleGrid, grid, grid_step
from gnibench.suite.cell.sections import integrate_section
from gnibench.suite.cell.trajectory import ReferenceSamples, Trajectory
from gnibench.suite.foundation.budgets import check_count, check_integer, check_output
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Bound
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.foundation.status import Status

CALL_SECONDS = 0.1          # target duration of one call of a compiled driver
FIRST_BUDGET = 256          # steps (attempts) in the first call, then scaled to CALL_SECONDS
ADAPTIVE_CHUNK = 4096       # rows of one output buffer of an adaptive driver
UNLIMITED = 1 << 62

Progress = Callable[[float], None]


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during an integration; ``partial`` is the trajectory up to the interrupt."""

    def __init__(self, partial: Trajectory):
        super().__init__("interrupted")
        self.partial = partial


def integrate(problem: Bound, method, *, steps: int | None = None, t_end: float | None = None,
              every: int = 1, section: int | None = None, locator: str | None = None,
              reference=None, progress: Progress | None = None,
              budget: int | None = 0) -> Trajectory:
    """Integrate one cell; bad input raises UserError, divergence is a status.

    Parameters
    ----------
    problem, method:
        A parsed problem (:func:`gnibench.suite.cell.spec.parse_problem`) and method
        (:func:`~gnibench.suite.cell.spec.parse_method`, checked against the problem).
    steps, t_end:
        The horizon: exactly one of them (``t_end``: the last step lands exactly on it).
    every:
        A sample every K steps (or every K-th point of a ``dt_out`` grid), plus the final point.
    section, locator:
        Integrate until ``section`` crossings of the problem's Poincaré section and return
        the located crossings (``locator``: None, ``dense`` or ``henon``).
    reference:
        A :class:`~gnibench.suite.cell.reference.ReferenceSpec` (or None): its samples at the
        trajectory's times are attached to the trajectory.
    progress:
        Called with the fraction of the horizon done, between calls of the compiled driver.
    budget:
        Steps per call of a compiled driver: 0 tunes it to ``CALL_SECONDS`` a call, None does
        the whole horizon in one call (the benchmark loop).
    """
    check_integer(every, "--every")
    check_budgets(problem, method, steps, t_end, every, section)
    if section is not None:
        samples = None
        external = getattr(method.base.record, "run", None) is not None
        if external or problem.record.transformed(problem.values) is not None:
            samples = integrate(problem, method, steps=steps, t_end=t_end, every=1,
                                progress=progress, budget=budget)
        return integrate_section(problem, method, section, steps=steps, t_end=t_end,
                                 locator=locator, progress=progress, samples=samples)
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    transformed = problem.record.transformed(problem.values)
    if getattr(method.base.record, "run", None) is not None:
        if transformed is not None:
            raise UserError(f"{method.base.id} is an external engine; it cannot integrate the "
                            f"transformed system of {problem.id} (drop the transform option)")
        traj = _external(problem, method, SampleGrid(h, nsteps, h_last, every))
    elif transformed is not None:
        if method.base.values.get("adaptive") and method.base.values.get("dt_out", 0.0) > 0.0:
            raise UserError(f"dt_out spaces a grid in the integrated system's time, which for the "
                            f"transformed system of {problem.id} is not t (drop dt_out or the "
                            f"transform option)")
        traj = _transformed(problem, transformed, method, steps, t_end, every, progress, budget)
    else:
        traj = _compiled(problem, method, steps, t_end, every, progress, budget)
    if traj.status is Status.INTERRUPTED:
        traj.reason = f"interrupted by the user at t = {traj.t[-1]:.17g}" if len(traj.t) else \
            "interrupted by the user"
        raise Interrupted(traj)
    if reference is not None:
        attach_reference(traj, problem, reference)
    return traj


def check_budgets(problem: Bound, method, steps, t_end, every, section) -> None:
    """Refuse, before any work, a cell beyond the budgets (:mod:`gnibench.suite.foundation.budgets`):
    steps of a fixed-step method, output rows and their memory."""
    v = method.base.values
    h = grid_step(method)
    nsteps, _ = grid(h, steps, t_end)
    columns = problem.record.dim + COUNTERS + 1
    external = getattr(method.base.record, "run", None) is not None
    adaptive = bool(v.get("adaptive"))
    what = f"{problem.text()} {method.text()}"
    if adaptive:
        check_count(v["max_steps"], what + " (max_steps)", "GNIBENCH_MAX_STEPS", "steps")
    elif not external:
        check_count(nsteps, what, "GNIBENCH_MAX_STEPS", "steps")
    if section is not None:
        check_integer(section, "--section")
        check_output(section, columns, what)
        return
    dt_out = float(v.get("dt_out", 0.0) or 0.0) if adaptive else 0.0
    if dt_out > 0.0 and t_end is not None:
        check_output(t_end / dt_out / every + 2, columns, what)
    elif not adaptive:
        check_output(nsteps / every + 2, columns, what)


def attach_reference(traj: Trajectory, problem: Bound, reference) -> None:
    """The reference solution at the trajectory's sample times (:mod:`.reference`)."""
    from gnibench.suite.cell.reference import reference_solution

    if len(traj.t) == 0:
        return
    sol = reference_solution(problem, traj.t, reference)
    traj.reference = ReferenceSamples(sol.y, {**reference.describe(), "cached": sol.cached,
                                              "seconds": sol.seconds})


# -- calling a resumable compiled driver --------------------------------------------------------

class Buffers:
    """Output buffers of a compiled driver: the rows written so far, and views with room left."""

    def __init__(self, rows: int, dim: int, grow: bool):
        self.dim, self.grow, self.chunks = dim, grow, []
        self._new(rows)

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

    def full(self) -> None:
        """The driver asked for room (BUFFER_FULL): keep what is written, start a new buffer."""
        if not self.grow:
            raise RuntimeError("compiled driver: output buffer too small (sized for the horizon)")
        kept = Buffers.__new__(Buffers)
        kept.t, kept.y, kept.c = self.t[:self.row], self.y[:self.row], self.c[:self.row]
        self.chunks[-1] = kept
        self._new(len(self.t))

    def arrays(self):
        parts = self.chunks[:-1] + [self]
        t = np.concatenate([p.t[:p.row] if p is self else p.t for p in parts])
        y = np.concatenate([p.y[:p.row] if p is self else p.y for p in parts])
        c = np.concatenate([p.c[:p.row] if p is self else p.c for p in parts])
        return t, y, c


def run_driver(call: Callable, buffers: Buffers, fraction: Callable[[], float],
               progress: Progress | None, budget: int | None) -> tuple[Status, float]:
    """Call a resumable driver (``call(budget, out_t, out_y, out_c) -> (code, rows)``) until it
    returns a final status; return it and the seconds spent inside the calls."""
    wall = 0.0
    b = UNLIMITED if budget is None else (budget or FIRST_BUDGET)
    while True:
        try:
            t0 = time.perf_counter()
            code, rows = call(b, *buffers.views())
            dt = time.perf_counter() - t0
            wall += dt
            buffers.advance(int(rows))
        except KeyboardInterrupt:
            return Status.INTERRUPTED, wall
        status = Status.from_code(int(code))
        if status is Status.BUFFER_FULL:
            if rows == 0 and buffers.row == 0:
                raise RuntimeError("compiled driver: output buffer too small for one step")
            buffers.full()
        elif status is not Status.PAUSED:
            return status, wall
        if progress is not None:
            progress(fraction())
        if budget == 0 and status is Status.PAUSED:      # tune the next call to CALL_SECONDS
            scale = CALL_SECONDS / max(dt, 1e-6)
            b = int(min(max(b * min(scale, 8.0), b / 4.0, 16), UNLIMITED))


def _compiled(problem, method, steps, t_end, every, progress, budget) -> Trajectory:
    """A compiled cell: the fixed-step driver, or the adaptive one (with dense output on a grid)."""
    v = method.base.values
    adaptive = bool(v.get("adaptive"))
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    if adaptive and t_end is None:
        raise UserError(f"{method.base.id} with adaptive=true needs --t-end T (not --steps); "
                        f"for fixed steps use {method.base.id}:adaptive=false,h=...")
    if adaptive and v.get("dt_out", 0.0) > 0.0:
        why = dense_output_refusal(problem, method)
        if why:
            raise UserError(f"dt_out needs dense output, which does not apply here: {why}; "
                            f"use --every K instead")
    cell = compile_cell(problem, method)
    if adaptive:
        return _adaptive(problem, method, cell, float(t_end), every, progress, budget)
    y_io = np.array([cell.y0, np.zeros(len(cell.y0))], dtype=np.float64)
    st = np.zeros(FIXED_STATE)
    sg = SampleGrid(h, nsteps, h_last, every)
    buffers = Buffers(sg.rows + 1, problem.record.dim, grow=False)

    def call(b, out_t, out_y, out_c):
        return cell.kernel.integrate(y_io, st, cell.par, h, nsteps, h_last, every, b,
                                     out_t, out_y, out_c)

    status, wall = run_driver(call, buffers, lambda: st[0] / nsteps, progress, budget)
    done = int(st[0])
    reason = ""
    if status is Status.NONFINITE:
        reason = f"state overflowed or became NaN at step {done + 1}"
    elif status is Status.NEWTON_FAILED:
        reason = (f"Newton (or the projection) did not converge at step {done + 1}; raise "
                  f"newton_maxit (now {v.get('newton_maxit', '-')}) or lower h")
    return _trajectory(problem, method, cell, buffers, status, reason, wall,
                       {"h": h, "nsteps": nsteps, "h_last": h_last, "every": every})


def _adaptive(problem, method, cell: CompiledCell, t_end, every, progress, budget) -> Trajectory:
    """Adaptive embedded RK and odex: the resumable driver fills buffers until t_end.

    With ``dt_out`` > 0 the samples are the grid k dt_out (every ``every``-th point) plus t_end,
    spaced as the external engines space theirs (:class:`SampleGrid`), filled by dense output."""
    v = method.base.values
    dt_out = float(v.get("dt_out", 0.0))
    n_out, grid_meta = 0, {}
    if dt_out > 0.0:
        n_out, _ = grid(dt_out, None, t_end)
        dense = method.base.record.data.dense
        grid_meta = {"dense_output": {"dt_out": dt_out, "grid_intervals": n_out,
                                      "order": dense.order, "extension": dense.reference,
                                      "extra_f_per_dense_step": dense.extra_stages}}
    y_io = np.array([cell.y0, np.zeros(len(cell.y0))], dtype=np.float64)
    st = np.zeros(ADAPTIVE_STATE)
    hmax = v["hmax"] if v["hmax"] > 0 else t_end
    # dense output: the whole grid in one buffer (a step may hold many grid points)
    rows = ADAPTIVE_CHUNK if dt_out == 0.0 else -(-n_out // every) + 3
    drive = cell.kernel.integrate_dense if dt_out > 0.0 else cell.kernel.integrate_adaptive
    buffers = Buffers(rows, problem.record.dim, grow=True)

    def call(b, out_t, out_y, out_c):
        return drive(y_io, st, cell.par, t_end, v["h0"], hmax, v["rtol"], v["atol"], every,
                     dt_out, n_out, v["max_steps"], b, out_t, out_y, out_c)

    status, wall = run_driver(call, buffers, lambda: st[0] / t_end, progress, budget)
    reason = {Status.MAX_STEPS: f"more than max_steps={v['max_steps']} steps before t = {t_end:g}",
              Status.STEP_TOO_SMALL: f"step size underflow at t = {st[0]:.17g} (stiff, or "
                                     f"diverging)",
              Status.NEWTON_FAILED: f"the projection did not converge at t = {st[0]:.17g}",
              }.get(status, "")
    return _trajectory(problem, method, cell, buffers, status, reason, wall,
                       {"h": v["h0"], "t_end": t_end, "every": every, "accepted": int(st[4]),
                        "rejected": int(st[5]), **grid_meta})


def _trajectory(problem, method, cell: CompiledCell, buffers: Buffers, status, reason, wall,
                grid_meta) -> Trajectory:
    t, y, c = buffers.arrays()
    integrals = np.empty((len(t), len(cell.integral_names)))
    if len(t) and cell.integral_names:
        cell.problem_kernel.eval_invariants(y, cell.problem_par, len(t), integrals)
    return Trajectory(
        problem=problem.text(), method=method.text(), state_names=problem.record.state, t=t, y=y,
        steps=c[:, 0].astype(np.int64), nfev=c[:, 1], njev=c[:, 2], rejected=c[:, 3],
        integral_names=cell.integral_names, integrals=integrals, H0=cell.H0, y0=cell.y0,
        status=status, reason=reason,
        provenance={"versions": versions(), **grid_meta, "seed": None, "y0": list(cell.y0),
                    "H0": list(cell.H0), "wall_seconds": wall,
                    "compile_seconds": cell.compile_seconds,
                    "numba_cache_misses": cell.cache_misses})


def _transformed(problem, transformed, method, steps, t_end, every, progress, budget):
    """Integrate the transformed problem (e.g. K-S), then map its samples back to (t, y)."""
    inner = _compiled(transformed, method, steps, t_end, every, progress, budget)
    t, y = problem.record.transform.back(inner.y, problem.values)
    pk = problem_kernel(problem)
    y0 = tuple(problem.record.y0(problem.values))
    prov = {**inner.provenance, "y0": list(y0), "H0": list(pk.at(y0)),
            "transform": {"option": problem.record.transform.option,
                          "problem": transformed.text(), "s": inner.t.tolist()[-1:],
                          "doc": problem.record.transform.doc}}
    return Trajectory(
        problem=problem.text(), method=method.text(), state_names=problem.record.state,
        t=np.ascontiguousarray(t), y=np.ascontiguousarray(y), steps=inner.steps, nfev=inner.nfev,
        njev=inner.njev, rejected=inner.rejected, integral_names=pk.integral_names,
        integrals=pk.integrals(y), H0=pk.at(y0), y0=y0, status=inner.status, reason=inner.reason,
        provenance=prov)


def _external(problem: Bound, method, sg: SampleGrid) -> Trajectory:
    """An external engine's cell: ``Method.run`` on the sample grid instead of a compiled driver."""
    rec = problem.record
    y0 = tuple(rec.y0(problem.values))
    pk = problem_kernel(problem)
    run = method.base.record.run(problem, method.base.values, sg)
    t = sg.t[:len(run.y)]
    status = Status(run.status)
    return Trajectory(
        problem=problem.text(), method=method.text(), state_names=rec.state, t=t, y=run.y,
        steps=run.steps, nfev=np.asarray(run.nfev, dtype=float), njev=np.zeros(len(t)),
        rejected=np.zeros(len(t)), integral_names=pk.integral_names, integrals=pk.integrals(run.y),
        H0=pk.at(y0), y0=y0, status=status, reason=run.reason,
        provenance={"versions": versions(), "h": sg.h, "nsteps": sg.nsteps, "h_last": sg.h_last,
                    "every": sg.every, "seed": None, "y0": list(y0), "H0": list(pk.at(y0)),
                    "grid_param": method.base.record.grid_param, "engine": run.info,
                    "wall_seconds": run.seconds, "compile_seconds": run.setup_seconds,
                    "numba_cache_misses": 0})

