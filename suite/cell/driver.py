"""The driver facade: the one function through which every cell is integrated.

:func:`integrate` takes a parsed problem and method and returns a
:class:`~gnibench.suite.cell.trajectory.Trajectory`, whatever the kind of cell:

* compiled fixed-step methods (``methods/kernels/driver.py``), and compiled adaptive methods
  (embedded pairs with Hairer's control, odex), sampled every K steps;
* samples on a time grid t_k = k dt_out for every compiled method (``dt_out``: dense output or
  partial steps, :mod:`gnibench.suite.cell.timegrid`);
* Poincaré section crossings (``section=K``), found and located inside the compiled drivers
  (:mod:`gnibench.suite.cell.sections`);
* external engines (heyoka, rebound: ``Method.run``);
* transformed problems (K-S, [B] (5.4)): the transformed system is integrated and its samples
  mapped back;
* the benchmark loop (``gnibench bench``: ``budget=None``, one call of the compiled driver).

The compiled drivers are resumable: the facade calls them until they are done
(:mod:`gnibench.suite.cell.calls`), with a work budget per call tuned so that one call lasts about
``CALL_SECONDS`` and a new output buffer whenever one is full.
"""
from __future__ import annotations

import numpy as np
from gnibench.methods.kernels.slots import ST_ROLLBACKS, ST_TCOMP
from gnibench.suite.cell.calls import COUNTERS, UNLIMITED, Buffers, Progress, run_driver
from gnibench.suite.cell.compiled import (
    FIXED_DRIVERS,
    STATE,
    CompiledCell,
    compile_cell,
    plain_driver,
    problem_kernel,
)
from gnibench.suite.cell.grid import SampleGrid, grid, grid_step
from gnibench.suite.cell.sections import integrate_section
from gnibench.suite.cell.timegrid import check_dt_out, effective_dt_out, engine_method, plan
from gnibench.suite.cell.trajectory import ReferenceSamples, Trajectory
from gnibench.suite.foundation.budgets import check_count, check_integer, check_output
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Bound
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.foundation.status import Status

__all__ = ["UNLIMITED", "Interrupted", "attach_reference", "integrate"]

ADAPTIVE_CHUNK = 4096       # rows of one output buffer of an adaptive driver
GRID_ROWS = 10**7           # at most this many rows in one buffer of a time grid


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during an integration; ``partial`` is the trajectory up to the interrupt."""

    def __init__(self, partial: Trajectory):
        super().__init__("interrupted")
        self.partial = partial


def integrate(problem: Bound, method, *, steps: int | None = None, t_end: float | None = None,
              every: int = 1, dt_out: float | None = None, section: int | None = None,
              locator: str | None = None, reference=None, progress: Progress | None = None,
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
    dt_out:
        Samples at t = k dt_out (k = 0, every, 2 every, ...) plus the final point, located exactly
        for every compiled method (dense output or a partial step; :mod:`.timegrid`); external
        engines sample on their own ``dt_out`` grid, which this sets.
    section, locator:
        Integrate until ``section`` crossings of the problem's Poincaré section and return
        the located crossings (``locator``: None, ``dense`` or ``henon``; :mod:`.sections`).
    reference:
        A :class:`~gnibench.suite.cell.reference.ReferenceSpec` (or None): its samples at the
        trajectory's times are attached to the trajectory.
    progress:
        Called between calls of the compiled driver with the fraction done (sections: the larger
        of crossings found / K and t / t_end).
    budget:
        Steps per call of a compiled driver: 0 tunes it to ``CALL_SECONDS`` a call, None does
        the whole horizon in one call (the benchmark loop).
    """
    check_integer(every, "--every")
    dt_out = check_dt_out(dt_out)
    check_budgets(problem, method, steps, t_end, every, section, dt_out)
    external = method.kind != "compiled"      # an engine, or Python code: Method.run
    transformed = problem.record.transformed(problem.values)
    if section is not None:
        if dt_out is not None or (not external and effective_dt_out(method, None) is not None):
            raise UserError("--dt-out (or the method option dt_out) does not apply with "
                            "--section (the section points are written)")
        samples = None
        if external or transformed is not None:
            samples = integrate(problem, method, steps=steps, t_end=t_end, every=1,
                                progress=progress, budget=budget)
        traj = integrate_section(problem, method, section, steps=steps, t_end=t_end,
                                 locator=locator, progress=progress, samples=samples,
                                 budget=budget)
    elif external:
        if transformed is not None:
            raise UserError(f"{method.base.id} is an external engine; it cannot integrate the "
                            f"transformed system of {problem.id} (drop the transform option)")
        if dt_out is not None:
            method = engine_method(method, dt_out, problem)
        h = grid_step(method)
        nsteps, h_last = grid(h, steps, t_end)
        traj = _external(problem, method, SampleGrid(h, nsteps, h_last, every))
    elif transformed is not None:
        traj = _transformed(problem, transformed, method, steps, t_end, every, dt_out, progress,
                            budget)
    else:
        traj = _compiled(problem, method, steps, t_end, every, progress, budget, dt_out)
    if traj.status is Status.INTERRUPTED:
        traj.reason = f"interrupted by the user at t = {traj.t[-1]:.17g}" if len(traj.t) else \
            "interrupted by the user"
        raise Interrupted(traj)
    if reference is not None:
        attach_reference(traj, problem, reference)
    return traj


def check_budgets(problem: Bound, method, steps, t_end, every, section, dt_out=None) -> None:
    """Refuse, before any work, a cell beyond the budgets (:mod:`gnibench.suite.foundation.budgets`):
    steps of a fixed-step method, output rows and their memory."""
    v = method.base.values
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    columns = problem.record.dim + COUNTERS + 1
    external = method.kind == "external"
    transformed = problem.record.transformed(problem.values) is not None
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
    spacing = None if external or transformed else effective_dt_out(method, dt_out)
    t_final = t_end if t_end is not None else (nsteps - 1) * h + h_last
    if spacing is not None and not adaptive or spacing is not None and t_end is not None:
        check_output(t_final / spacing / every + 2, columns, what)
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


def _compiled(problem, method, steps, t_end, every, progress, budget, dt_out=None,
              tcomp=-1) -> Trajectory:
    """A compiled cell: the fixed-step driver or the adaptive one, sampled every K steps or on a
    time grid (``tcomp`` >= 0: the grid's time is that state component, :mod:`.timegrid`)."""
    v = method.base.values
    adaptive = bool(v.get("adaptive"))
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    if adaptive and t_end is None:
        raise UserError(f"{method.base.id} with adaptive=true needs --t-end T (not --steps); "
                        f"for fixed steps use {method.base.id}:adaptive=false,h=...")
    dt_out = effective_dt_out(method, dt_out)
    t_final = float(t_end) if adaptive else (nsteps - 1) * h + h_last
    gp = None if dt_out is None else plan(problem, method, dt_out, t_final, tcomp)
    name = plain_driver(method) if gp is None else gp.driver
    cell = compile_cell(problem, method, name)
    fn = getattr(cell.kernel, name)
    y_io = np.array([cell.y0, np.zeros(len(cell.y0))], dtype=np.float64)
    st = np.zeros(STATE)
    st[ST_TCOMP] = -1.0 if gp is None else gp.tcomp
    d_out, n_out = (0.0, 0) if gp is None else (gp.dt_out, gp.n_out)
    if gp is not None:             # the whole grid in one buffer (a step may hold many points)
        rows = min(-(-min(n_out, GRID_ROWS) // every) + 3 if gp.tcomp < 0 else ADAPTIVE_CHUNK,
                   GRID_ROWS)
    else:
        rows = ADAPTIVE_CHUNK if adaptive else SampleGrid(h, nsteps, h_last, every).rows + 1
    buffers = Buffers(rows, problem.record.dim, grow=adaptive or gp is not None)
    if name in FIXED_DRIVERS:
        def call(b, out_t, out_y, out_c):
            return fn(y_io, st, cell.par, h, nsteps, h_last, every, d_out, n_out, b,
                      out_t, out_y, out_c)

        def fraction():
            return st[0] / nsteps
    else:
        hmax = v["hmax"] if v["hmax"] > 0 else t_end

        def call(b, out_t, out_y, out_c):
            return fn(y_io, st, cell.par, t_end, v["h0"], hmax, v["rtol"], v["atol"], every,
                      d_out, n_out, v["max_steps"], b, out_t, out_y, out_c)

        def fraction():
            return st[0] / t_end
    status, wall = run_driver(call, buffers, fraction, progress, budget)
    if adaptive:
        reason = {Status.MAX_STEPS: f"more than max_steps={v['max_steps']} steps before t = "
                                    f"{t_end:g}",
                  Status.STEP_TOO_SMALL: f"step size underflow at t = {st[0]:.17g} (stiff, or "
                                         f"diverging)",
                  Status.NEWTON_FAILED: f"the projection did not converge at t = {st[0]:.17g}",
                  }.get(status, "")
        meta = {"h": v["h0"], "t_end": t_end, "every": every, "accepted": int(st[4]),
                "rejected": int(st[5])}
    else:
        done = int(st[0])
        reason = {Status.NONFINITE: f"state overflowed or became NaN at step {done + 1}",
                  Status.NEWTON_FAILED: f"Newton (or the projection) did not converge at step "
                                        f"{done + 1}; raise newton_maxit (now "
                                        f"{v.get('newton_maxit', '-')}) or lower h"}.get(status, "")
        meta = {"h": h, "nsteps": nsteps, "h_last": h_last, "every": every}
    if gp is not None:
        time_name = "t" if gp.tcomp < 0 else problem.record.state[gp.tcomp]
        meta["time_grid"] = gp.describe(every, time_name, st[ST_ROLLBACKS])
        if gp.locator == "dense output":
            dense = method.base.record.data.dense
            meta["dense_output"] = {"dt_out": gp.dt_out,
                                    "grid_intervals": meta["time_grid"]["grid_intervals"],
                                    "order": dense.order, "extension": dense.reference,
                                    "extra_f_per_dense_step": dense.extra_stages}
    return _trajectory(problem, method, cell, buffers, status, reason, wall, meta)


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


def _transformed(problem, transformed, method, steps, t_end, every, dt_out, progress, budget):
    """Integrate the transformed problem (e.g. K-S), then map its samples back to (t, y); a time
    grid is in the original time, the transformed system's state component ``Transform.time``."""
    tr = problem.record.transform
    tcomp = -1
    if dt_out is not None or effective_dt_out(method, None) is not None:
        if tr.time is None:
            raise UserError(f"bad --dt-out for {problem.id} with {tr.option}=true: the transformed "
                            f"system has no time component; allowed: --every K")
        tcomp = transformed.record.state.index(tr.time)
    inner = _compiled(transformed, method, steps, t_end, every, progress, budget, dt_out, tcomp)
    t, y = tr.back(inner.y, problem.values)
    pk = problem_kernel(problem)
    y0 = tuple(problem.record.y0(problem.values))
    prov = {**inner.provenance, "y0": list(y0), "H0": list(pk.at(y0)),
            "transform": {"option": tr.option, "problem": transformed.text(),
                          "s": inner.t.tolist()[-1:], "doc": tr.doc}}
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
    run = method.base.record.run(problem, method.base.values, sg, pk)
    t = sg.t[:len(run.y)]
    status = Status(run.status)
    return Trajectory(
        problem=problem.text(), method=method.text(), state_names=rec.state, t=t, y=run.y,
        steps=run.steps, nfev=np.asarray(run.nfev, dtype=float),
        njev=np.zeros(len(t)) if run.njev is None else np.asarray(run.njev, dtype=float),
        rejected=np.zeros(len(t)), integral_names=pk.integral_names, integrals=pk.integrals(run.y),
        H0=pk.at(y0), y0=y0, status=status, reason=run.reason,
        provenance={"versions": versions(), "h": sg.h, "nsteps": sg.nsteps, "h_last": sg.h_last,
                    "every": sg.every, "seed": None, "y0": list(y0), "H0": list(pk.at(y0)),
                    "grid_param": method.base.record.grid_param, "engine": run.info,
                    "wall_seconds": run.seconds, "compile_seconds": run.setup_seconds,
                    "numba_cache_misses": 0})

