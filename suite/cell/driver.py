"""The driver facade: the one function through which every cell is integrated.

:func:`integrate` takes a typed cell (:class:`~gnibench.suite.cell.cellspec.CellSpec`, validated
once by :func:`~gnibench.suite.cell.cellspec.build`) and returns a
:class:`~gnibench.suite.cell.trajectory.Trajectory`, choosing its branch by the cell's kind
(:class:`~gnibench.suite.cell.cellspec.CellKind`):

* compiled fixed-step methods (``methods/assembly/templates/fixed.py``), and compiled adaptive methods
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
from gnibench.suite.cell.calls import UNLIMITED, Buffers, Progress, budget_reason
from gnibench.suite.cell.cellspec import CellKind, CellSpec
from gnibench.suite.cell.compiled import problem_kernel
from gnibench.suite.cell.drivers import AdaptiveDriver, FixedStepDriver, build_trajectory, kind_of
from gnibench.suite.cell.grid import SampleGrid
from gnibench.suite.cell.sections import integrate_section
from gnibench.suite.cell.trajectory import ReferenceSamples, Trajectory
from gnibench.suite.foundation.params import Bound
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.foundation.status import Status

__all__ = ["STREAMED", "UNLIMITED", "Interrupted", "attach_reference", "integrate"]

ADAPTIVE_CHUNK = 4096       # rows of one output buffer of an adaptive driver
GRID_ROWS = 10**7           # at most this many rows in one buffer of a time grid


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during an integration; ``partial`` is the trajectory up to the interrupt."""

    def __init__(self, partial: Trajectory):
        super().__init__("interrupted")
        self.partial = partial


def integrate(cell: CellSpec, *, progress: Progress | None = None,
              budget: int | None = 0, sink=None) -> Trajectory:
    """Integrate one typed cell (:func:`gnibench.suite.cell.cellspec.build`: validated there,
    nothing is checked again here); divergence is a status, Ctrl-C raises :class:`Interrupted`
    with the samples so far.

    Parameters
    ----------
    cell:
        The typed cell; its :attr:`~gnibench.suite.cell.cellspec.CellSpec.kind` chooses the
        branch: a compiled fixed-step or adaptive method (sampled every K steps, or on the time
        grid t = k dt_out, :mod:`.timegrid`), an external engine (``Method.run``), a transformed
        problem (K-S), or the crossings of a Poincaré section (:mod:`.sections`). Its reference
        solution, if any, is attached at the trajectory's times.
    progress:
        Called between calls of the compiled driver with the fraction done (sections: the larger
        of crossings found / K and t / t_end).
    budget:
        Steps per call of a compiled driver: 0 tunes it to ``CALL_SECONDS`` a call, None does
        the whole horizon in one call (the benchmark loop).
    sink:
        For the kinds of :data:`STREAMED`: each block of the driver's raw output rows (t, y and
        the counters of the integrated system: the transformed one for K-S) is handed to
        ``sink(t, y, c)`` and the buffer reused (:class:`.calls.Buffers`); the trajectory
        returned holds the last row only and no reference
        (:mod:`gnibench.suite.runs.streaming` makes the table from the blocks).
    """
    if sink is not None and cell.kind not in STREAMED:
        raise ValueError(f"a {cell.kind} cell is not streamed")
    traj = _BRANCHES[cell.kind](cell, progress, budget, sink)
    if traj.status is Status.INTERRUPTED:
        traj.reason = f"interrupted by the user at t = {traj.t[-1]:.17g}" if len(traj.t) else \
            "interrupted by the user"
        raise Interrupted(traj)
    if cell.reference is not None and sink is None:
        attach_reference(traj, cell.problem, cell.reference)
    return traj


def _section(cell: CellSpec, progress, budget, sink=None) -> Trajectory:
    """Section crossings: located inside the compiled drivers, or scanned from the samples of an
    engine or a transformed problem taken at every step."""
    samples = None
    if cell.method_kind != "compiled" or cell.transformed is not None:
        inner = cell.samples_cell()
        samples = _BRANCHES[inner.kind](inner, progress, budget, None)
    return integrate_section(cell, progress=progress, samples=samples, budget=budget)


def _engine(cell: CellSpec, progress, budget, sink=None) -> Trajectory:
    """An external engine's cell (or a user's Python integrator): ``Method.run`` on the sample
    grid instead of a compiled driver."""
    problem, method = cell.problem, cell.method
    sg = SampleGrid(cell.h, cell.nsteps, cell.h_last, cell.every)
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


def _compiled_cell(cell: CellSpec, progress, budget, sink=None) -> Trajectory:
    """A compiled fixed-step or adaptive cell on the problem itself."""
    return _compiled(cell.problem, cell, progress, budget, sink)


def _transformed(cell: CellSpec, progress, budget, sink=None) -> Trajectory:
    """Integrate the transformed problem (e.g. K-S), then map its samples back to (t, y); a time
    grid is in the original time, the transformed system's state component ``Transform.time``."""
    problem, transformed = cell.problem, cell.transformed
    tr = problem.record.transform
    inner = _compiled(transformed, cell, progress, budget, sink)
    t, y = tr.back(inner.y, problem.values)
    pk = problem_kernel(problem)
    y0 = tuple(problem.record.y0(problem.values))
    prov = {**inner.provenance, "y0": list(y0), "H0": list(pk.at(y0)),
            "transform": {"option": tr.option, "problem": transformed.text(),
                          "s": inner.t.tolist()[-1:], "doc": tr.doc}}
    counters = np.column_stack([inner.steps, inner.nfev, inner.njev, inner.rejected])
    return build_trajectory(problem, cell.method, t, y, counters, inner.status, inner.reason, prov)


def _compiled(problem: Bound, cell: CellSpec, progress, budget, sink=None) -> Trajectory:
    """A compiled cell on ``problem`` (the cell's, or its transformed system): the fixed-step
    driver or the adaptive one, sampled every K steps or on the cell's time grid
    (:attr:`~gnibench.suite.cell.cellspec.CellSpec.grid_plan`; in a state component of a
    transformed system, :mod:`.timegrid`)."""
    method, every = cell.method, cell.every
    h, nsteps, h_last = cell.h, cell.nsteps, cell.h_last
    adaptive = kind_of(method) is AdaptiveDriver
    gp = cell.grid_plan
    kind = AdaptiveDriver if adaptive else FixedStepDriver
    name = kind.names["samples"] if gp is None else gp.driver
    grid_kw = {} if gp is None else {"dt_out": gp.dt_out, "n_out": gp.n_out, "tcomp": gp.tcomp}
    if adaptive:
        drv = AdaptiveDriver(problem, method, name, cell.t_end, every=every, **grid_kw)
    else:
        sign = -1.0 if cell.reverse else 1.0
        drv = FixedStepDriver(problem, method, name, sign * h, nsteps, sign * h_last, every=every,
                              **grid_kw)
    if gp is not None:             # the whole grid in one buffer (a step may hold many points)
        rows = min(-(-min(gp.n_out, GRID_ROWS) // every) + 3 if gp.tcomp < 0 else ADAPTIVE_CHUNK,
                   GRID_ROWS)
    elif adaptive:
        rows = ADAPTIVE_CHUNK
    else:
        rows = cell.rows + 1
    buffers = Buffers(rows, problem.record.dim, grow=adaptive or gp is not None, sink=sink)
    status, wall = drv.run(buffers, progress, budget)
    meta = drv.meta()
    if gp is not None:
        time_name = "t" if gp.tcomp < 0 else problem.record.state[gp.tcomp]
        redone = drv.slot("ST_ROLLBACKS")
        if sink is not None and gp.tcomp < 0 and buffers.rows + 2 <= rows:
            redone = 0.0    # redone only at hand-overs to the sink: the one buffer had room
        meta["time_grid"] = gp.describe(every, time_name, redone)
        if gp.locator == "dense output":
            pair = method.base.record.data
            dense = pair.dense
            meta["dense_output"] = {"dt_out": gp.dt_out,
                                    "grid_intervals": meta["time_grid"]["grid_intervals"],
                                    "order": dense.order, "extension": dense.reference,
                                    "extra_f_per_dense_step": dense.new_stages(pair.tab)}
    if cell.reverse:
        meta["reverse"] = True
    reason = drv.reason(status) or budget_reason(status, buffers, drv.t)
    return drv.trajectory(buffers, status, reason, meta, wall)


#: the kinds of cell whose output rows :func:`integrate` can hand to a sink block by block
STREAMED = frozenset({CellKind.FIXED, CellKind.ADAPTIVE, CellKind.TRANSFORMED})
#: the branch of :func:`integrate` for each kind of cell
_BRANCHES = {CellKind.FIXED: _compiled_cell, CellKind.ADAPTIVE: _compiled_cell,
             CellKind.ENGINE: _engine, CellKind.TRANSFORMED: _transformed,
             CellKind.SECTION: _section}


def attach_reference(traj: Trajectory, problem: Bound, reference) -> None:
    """The reference solution at the trajectory's sample times (:mod:`.reference`)."""
    from gnibench.suite.cell.reference import reference_accuracy, reference_solution

    if len(traj.t) == 0:
        return
    sol = reference_solution(problem, traj.t, reference)
    traj.reference = ReferenceSamples(sol.y, {**reference.describe(), "cached": sol.cached,
                                              "seconds": sol.seconds},
                                      reference_accuracy(problem, sol))
