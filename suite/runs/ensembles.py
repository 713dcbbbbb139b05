"""An ensemble unit at work: its orbits integrated, measured, made rows (in the worker).

:func:`run_ensemble` runs the orbits of one unit of an ensemble cell
(:mod:`gnibench.suite.runs.ensemble_spec`) and returns a
:class:`~gnibench.suite.runs.cellwork.CellOutcome` whose ``orbits`` hold one row per orbit and
whose ``samples`` hold the samples of the kept orbits (with their ``orbit``). The cell's row and
statistics are made when the tables are (:mod:`gnibench.suite.runs.ensemble_tables`), from the
orbits of all its units.

**How the orbits run.** A compiled method (fixed step, adaptive, on a time grid) runs all of
them in one call of the cell module's batched driver (:mod:`gnibench.suite.cell.batch`): a
compiled loop over the initial conditions calling the single-orbit driver, each orbit with its
own state, run-time parameters and output rows. Other cells (external engines, Python solvers,
transformed problems, section crossings) run their orbits one by one through
:func:`gnibench.suite.cell.driver.integrate`. Either way each orbit's samples are those of a
single cell of the same initial condition, bit for bit.

**What each orbit gives.** The samples are the cell's: every K steps or on the time grid
``dt_out``; an adaptive method without ``dt_out`` is sampled at t = 0 and at the end only (its
orbits' step sequences differ, the rows then do not). Its row (``ensemble.parquet``, columns in
``suite/experiments/README.md``): the orbit's index and initial state (``<state>0``), status,
reason, the time reached (``t_final``) and the time it failed at (``t_failed``, NaN when it did
not), the counters at its last sample, its final state (``final_<state>``), and every per-cell
value of its metrics (the defaults ``max_abs_err_<I>``, ``final_global_error``,
``max_global_error``, and those chosen): the same values a cell of that initial condition
writes in ``cells.parquet``.

**References.** The exact solution of each orbit where the problem has one; else the chosen
reference, integrated for all the unit's orbits at once (:mod:`gnibench.suite.cell.
ensemble_reference`: heyoka's ensemble propagation).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from gnibench.suite.cell.batch import OrbitSamples
from gnibench.suite.foundation.status import Status


def orbit_problems(cell) -> list:
    """The parsed problem of each orbit of a unit: the cell's, with the sampled options set."""
    from gnibench.suite.foundation.params import Bound

    ens, problem = cell.ensemble, cell.spec.problem
    return [Bound(problem.record, {**problem.values, **dict(zip(ens.options, map(float, x)))})
            for x in ens.points]


def initial_states(cell) -> np.ndarray:
    """y0 of each orbit, shape (n, N): the cell's initial point with the sampled components set
    (the problem's ``initial`` is evaluated once, not per orbit)."""
    rec, problem, ens = cell.spec.problem.record, cell.spec.problem, cell.ensemble
    base = np.array(rec.y0(problem.values), dtype=np.float64)
    y0 = np.repeat(base[None, :], ens.n, axis=0)
    for j, o in enumerate(ens.options):
        y0[:, rec.state.index(o[:-1])] = ens.points[:, j]
    return y0


def run_ensemble(cell, progress=None) -> tuple:
    """What one ensemble unit gives (see the module docstring): the kept orbits' samples, the
    unit's row and timings row, the state names and the orbits' rows, as
    :class:`~gnibench.suite.runs.cellwork.CellOutcome` takes them."""
    from gnibench.suite.cell.batch import batched, integrate_batch
    from gnibench.suite.runs.tables import cell_row

    spec = cell.spec
    y0 = initial_states(cell)
    if batched(spec):
        runs = integrate_batch(spec, y0, progress=progress)
    else:
        runs = _one_by_one(cell, progress)
    orbits, samples, names, refs = _measure(cell, y0, runs)
    failed = sum(1 for s in runs.status if s is not Status.OK)
    row = cell_row(cell, None, None, str(Status.OK),
                   f"{failed} of {cell.ensemble.n} orbits failed" if failed else "")
    notes = {}
    for choice in spec.metrics:
        if choice.metric.scope == "ensemble":
            why = "" if cell.ensemble.curve is not None else \
                "needs initial points on a closed curve (sample = circle or polygon)"
            if why:
                notes[choice.text()] = why
            else:
                row.update(choice.metric.compute(_carried(cell, y0, runs, refs, choice.values),
                                                 choice.values))
    if notes:
        row["metric_notes"] = "; ".join(f"{k}: {v}" for k, v in notes.items())
    timing = {"cell": cell.id, "problem": cell.problem, "method": cell.method,
              "status": str(Status.OK), "wall_seconds": runs.wall,
              "compile_seconds": runs.compile,
              "cache_misses": runs.provenance.get("numba_cache_misses")}
    return samples, row, timing, tuple(spec.problem.record.state), orbits


def _one_by_one(cell, progress) -> OrbitSamples:
    """Each orbit through the driver facade (cells the batched driver does not run)."""
    from gnibench.suite.cell.driver import integrate

    spec, out = cell.spec, OrbitSamples(trajectories=[])
    problems = orbit_problems(cell)
    for i, problem in enumerate(problems):
        orbit = replace(spec, problem=problem, reference=None)   # its reference: _measure's
        traj = integrate(orbit)
        out.trajectories.append(traj)
        out.t.append(traj.t)
        out.y.append(traj.y)
        out.counters.append(np.column_stack([traj.steps, traj.nfev, traj.njev, traj.rejected]))
        out.status.append(traj.status)
        out.reason.append(traj.reason)
        out.wall += float(traj.provenance.get("wall_seconds") or 0.0)
        out.compile += float(traj.provenance.get("compile_seconds") or 0.0) if i == 0 else 0.0
        if progress is not None:
            progress((i + 1) / len(problems))
    if out.trajectories:
        out.provenance = dict(out.trajectories[0].provenance)
    return out


def _measure(cell, y0: np.ndarray, runs: OrbitSamples):
    """(orbit columns, kept orbits' sample columns, state names) of a unit's runs."""
    from gnibench.suite.cell.ensemble_reference import ensemble_references
    from gnibench.suite.cell.compiled import problem_kernel
    from gnibench.suite.metrics.compute import apply
    from gnibench.suite.runs.tables import cell_sample_columns

    spec, ens = cell.spec, cell.ensemble
    rec = spec.problem.record
    pk = problem_kernel(spec.problem)
    H0 = pk.integrals(y0)
    refs = ensemble_references(spec.problem, y0, runs.t, spec.reference, ens.options,
                               ens.points) if spec.reference is not None else None
    chosen = bool(spec.metrics) or runs.trajectories is not None
    kept = set(ens.kept())
    rows: list[dict] = []
    samples: list[dict] = []
    problems = orbit_problems(cell) if chosen or kept else None
    for i in range(ens.n):
        t, y, c = runs.t[i], runs.y[i], runs.counters[i]
        ref = None if refs is None else refs[i]
        if chosen or i in kept:
            traj = _trajectory(cell, problems[i], runs, i, ref)
            metrics, _ = apply(traj, spec.metrics, problem=problems[i], families=False)
            scalars = metrics.scalars
            if i in kept:
                cols = cell_sample_columns(traj, metrics)
                samples.append({"orbit": np.full(len(t), ens.first + i, np.int64), **cols})
        else:
            scalars = _default_metrics(pk, y, H0[i], ref)
        rows.append(_orbit_row(rec, ens.first + i, y0[i], t, y, c, runs.status[i],
                               runs.reason[i], scalars))
    return _columns(rows), _concatenate(samples), rec.state, refs


def _carried(cell, y0: np.ndarray, runs: OrbitSamples, refs, values: dict):
    """The ensemble's closed curve carried by the flow (:class:`gnibench.suite.metrics.area.
    CarriedSet`): its orbits on their common sample times, and how to carry more points of the
    curve (the same integration, batched or one by one; their references likewise)."""
    from gnibench.suite.cell.batch import batched, integrate_batch
    from gnibench.suite.cell.ensemble_reference import ensemble_references
    from gnibench.suite.metrics.area import CarriedSet
    from gnibench.suite.runs import sampling
    from gnibench.suite.runs.ensemble_spec import EnsembleSpec

    spec, ens = cell.spec, cell.ensemble
    rec = spec.problem.record
    times = max(runs.t, key=len)
    shape, *curve = ens.curve
    n = ens.n

    def on_times(t_list, y_list) -> np.ndarray:
        out = np.full((len(t_list), len(times), rec.dim), np.nan)
        for i, (t, y) in enumerate(zip(t_list, y_list)):
            k = min(len(t), len(times))
            same = np.flatnonzero(t[:k] == times[:k])
            out[i, same] = y[same]
        return out

    def advance(s: np.ndarray):
        pts = sampling.circle_at(*curve, s) if shape == "circle" else \
            sampling.polygon_at(curve[0], s)
        more = EnsembleSpec(ens.options, ens.sample, np.ascontiguousarray(pts), (), len(s), 0,
                            len(s), ens.curve)
        unit = replace(cell, ensemble=more)
        start = initial_states(unit)
        got = integrate_batch(spec, start) if batched(spec) else _one_by_one(unit, None)
        ref = None if spec.reference is None else ensemble_references(
            spec.problem, start, got.t, spec.reference, ens.options, pts)
        return on_times(got.t, got.y), None if ref is None else on_times(got.t, ref)

    names = values.get("of") or tuple(o[:-1] for o in ens.options)
    coords = (rec.state.index(names[0]), rec.state.index(names[1]))
    exact = None if refs is None else on_times(runs.t, refs)
    s = np.arange(n) / n
    return CarriedSet(s, np.asarray(times), on_times(runs.t, runs.y), exact, coords, advance)


def _trajectory(cell, problem, runs: OrbitSamples, i: int, ref):
    """Orbit i as a trajectory (the one by one run's own, or made from the batched arrays), with
    its reference samples."""
    from gnibench.suite.cell.drivers import build_trajectory
    from gnibench.suite.cell.trajectory import ReferenceSamples

    if runs.trajectories is not None:
        traj = runs.trajectories[i]
    else:
        traj = build_trajectory(problem, cell.spec.method, runs.t[i], runs.y[i],
                                runs.counters[i], runs.status[i], runs.reason[i],
                                dict(runs.provenance))
    if ref is not None:
        traj.reference = ReferenceSamples(ref, {**cell.spec.reference.describe()})
    return traj


def _default_metrics(pk, y: np.ndarray, h0: np.ndarray, ref) -> dict:
    """The default metrics' per-cell values of one orbit, as their metrics compute them
    (:mod:`gnibench.suite.metrics.invariants`, :mod:`~gnibench.suite.metrics.global_error`), from
    its samples alone."""
    from gnibench.suite.metrics.base import max_abs

    out = {}
    err = pk.integrals(y) - np.asarray(h0, dtype=float)[None, :]
    for k, name in enumerate(pk.integral_names):
        out[f"max_abs_err_{name}"] = max_abs(err[:, k])
    if ref is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            g = np.sqrt(np.sum((y - ref) ** 2, axis=1))
        out["final_global_error"] = float(g[-1]) if len(g) else float("nan")
        out["max_global_error"] = max_abs(g)
    return out


def _orbit_row(rec, orbit: int, y0, t, y, c, status: Status, reason: str, scalars: dict) -> dict:
    last = len(t) - 1
    row = {"orbit": orbit}
    row.update({f"{s}0": float(v) for s, v in zip(rec.state, y0)})
    t_final = float(t[last]) if last >= 0 else np.nan
    row.update(status=str(status), reason=reason, t_final=t_final,
               t_failed=np.nan if status is Status.OK else t_final,
               steps=float(c[last, 0]) if last >= 0 else np.nan,
               nfev=float(c[last, 1]) if last >= 0 else np.nan,
               njev=float(c[last, 2]) if last >= 0 else np.nan,
               rejected=float(c[last, 3]) if last >= 0 else np.nan)
    row.update({f"final_{s}": float(y[last, k]) if last >= 0 else np.nan
                for k, s in enumerate(rec.state)})
    row.update({k: v for k, v in scalars.items() if isinstance(v, (int, float, np.number))
                and not isinstance(v, bool)})
    return row


def _columns(rows: list[dict]) -> dict:
    """Rows (dicts with the same keys in the same order, metrics possibly differing) as
    columns: numbers as float64 (int64 for ``orbit``), text as object arrays."""
    names: dict[str, None] = {}
    for r in rows:
        names.update(dict.fromkeys(r))
    out = {}
    for name in names:
        values = [r.get(name, np.nan) for r in rows]
        if name == "orbit":
            out[name] = np.array(values, dtype=np.int64)
        elif name in ("status", "reason"):
            out[name] = np.array(values, dtype=object)
        else:
            out[name] = np.array(values, dtype=np.float64)
    return out


def _concatenate(samples: list[dict]) -> dict | None:
    """The kept orbits' sample columns in one table (a column an orbit lacks is NaN there)."""
    if not samples:
        return None
    names: dict[str, None] = {}
    for s in samples:
        names.update(dict.fromkeys(s))
    out = {}
    for name in names:
        parts = [s[name] if name in s else np.full(len(s["orbit"]), np.nan) for s in samples]
        out[name] = np.concatenate(parts)
    return out
