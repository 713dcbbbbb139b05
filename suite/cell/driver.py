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

The compiled drivers are resumable: the facade runs them through their driver objects
(:mod:`gnibench.suite.cell.drivers`: one per kind, fixed step and adaptive), which call them until
they are done (:mod:`gnibench.suite.cell.calls`), with a work budget per call tuned so that one
call lasts about ``CALL_SECONDS`` and a new output buffer whenever one is full.
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.cell.calls import COUNTERS, UNLIMITED, Buffers, Progress
from gnibench.suite.cell.compiled import problem_kernel
from gnibench.suite.cell.drivers import AdaptiveDriver, FixedStepDriver, build_trajectory, kind_of
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
              budget: int | None = 0, reverse: bool = False) -> Trajectory:
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
    reverse:
        Integrate backward in time, steps of -h from y0 (fixed-step compiled methods, ``steps``
        or ``t_end`` > 0 giving the length; samples at t = -k h), e.g. to check that a symmetric
        method retraces its steps, Φ_{-h} ∘ Φ_h = id ([HLW] (1.7)).
    """
    check_integer(every, "--every")
    if reverse:
        _check_reverse(problem, method, dt_out, section)
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
        traj = _compiled(problem, method, steps, t_end, every, progress, budget, dt_out,
                         reverse=reverse)
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
    from gnibench.suite.cell.reference import reference_accuracy, reference_solution

    if len(traj.t) == 0:
        return
    sol = reference_solution(problem, traj.t, reference)
    traj.reference = ReferenceSamples(sol.y, {**reference.describe(), "cached": sol.cached,
                                              "seconds": sol.seconds},
                                      reference_accuracy(problem, sol))


def _check_reverse(problem: Bound, method, dt_out, section) -> None:
    if (method.kind != "compiled" or method.base.values.get("adaptive")
            or problem.record.transformed(problem.values) is not None):
        raise UserError(f"reverse=True applies to fixed-step compiled methods; {method.text()} on "
                        f"{problem.text()} is not one")
    if dt_out is not None or section is not None:
        raise UserError("reverse=True samples every K steps; drop --dt-out and --section")


def _compiled(problem, method, steps, t_end, every, progress, budget, dt_out=None,
              tcomp=-1, reverse=False) -> Trajectory:
    """A compiled cell: the fixed-step driver or the adaptive one, sampled every K steps or on a
    time grid (``tcomp`` >= 0: the grid's time is that state component, :mod:`.timegrid`)."""
    kind = kind_of(method)
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    if kind is AdaptiveDriver and t_end is None:
        raise UserError(f"{method.base.id} with adaptive=true needs --t-end T (not --steps); "
                        f"for fixed steps use {method.base.id}:adaptive=false,h=...")
    dt_out = effective_dt_out(method, dt_out)
    t_final = float(t_end) if kind is AdaptiveDriver else (nsteps - 1) * h + h_last
    gp = None if dt_out is None else plan(problem, method, dt_out, t_final, tcomp)
    name = kind.names["samples"] if gp is None else gp.driver
    grid_kw = {} if gp is None else {"dt_out": gp.dt_out, "n_out": gp.n_out, "tcomp": gp.tcomp}
    if kind is AdaptiveDriver:
        drv = AdaptiveDriver(problem, method, name, t_end, every=every, **grid_kw)
    else:
        sign = -1.0 if reverse else 1.0
        drv = FixedStepDriver(problem, method, name, sign * h, nsteps, sign * h_last, every=every,
                              **grid_kw)
    if gp is not None:             # the whole grid in one buffer (a step may hold many points)
        rows = min(-(-min(gp.n_out, GRID_ROWS) // every) + 3 if gp.tcomp < 0 else ADAPTIVE_CHUNK,
                   GRID_ROWS)
    elif kind is AdaptiveDriver:
        rows = ADAPTIVE_CHUNK
    else:
        rows = SampleGrid(h, nsteps, h_last, every).rows + 1
    buffers = Buffers(rows, problem.record.dim, grow=kind is AdaptiveDriver or gp is not None)
    status, wall = drv.run(buffers, progress, budget)
    meta = drv.meta()
    if gp is not None:
        time_name = "t" if gp.tcomp < 0 else problem.record.state[gp.tcomp]
        meta["time_grid"] = gp.describe(every, time_name, drv.slot("ST_ROLLBACKS"))
        if gp.locator == "dense output":
            pair = method.base.record.data
            dense = pair.dense
            meta["dense_output"] = {"dt_out": gp.dt_out,
                                    "grid_intervals": meta["time_grid"]["grid_intervals"],
                                    "order": dense.order, "extension": dense.reference,
                                    "extra_f_per_dense_step": dense.new_stages(pair.tab)}
    if reverse:
        meta["reverse"] = True
    return drv.trajectory(buffers, status, drv.reason(status), meta, wall)


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
    counters = np.column_stack([inner.steps, inner.nfev, inner.njev, inner.rejected])
    return build_trajectory(problem, method, t, y, counters, inner.status, inner.reason, prov)


def _external(problem: Bound, method, sg: SampleGrid) -> Trajectory:
    """An external engine's cell: ``Method.run`` on the sample grid instead of a compiled driver."""
    y0 = tuple(problem.record.y0(problem.values))
    pk = problem_kernel(problem)
    run = method.base.record.run(problem, method.base.values, sg, pk)
    t = sg.t[:len(run.y)]
    njev = np.zeros(len(t)) if run.njev is None else np.asarray(run.njev, dtype=np.float64)
    counters = np.column_stack([np.asarray(run.steps, dtype=np.float64),
                                np.asarray(run.nfev, dtype=np.float64),
                                njev, np.zeros(len(t))]) if len(t) else np.zeros((0, 4))
    prov = {"versions": versions(), "h": sg.h, "nsteps": sg.nsteps, "h_last": sg.h_last,
            "every": sg.every, "seed": None, "y0": list(y0), "H0": list(pk.at(y0)),
            "grid_param": method.base.record.grid_param, "engine": run.info,
            "wall_seconds": run.seconds, "compile_seconds": run.setup_seconds,
            "numba_cache_misses": 0}
    return build_trajectory(problem, method, t, run.y, counters, Status(run.status), run.reason,
                            prov)
