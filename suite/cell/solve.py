"""Integrate one cell (problem x method) and measure it: the unit of work of every command."""
from __future__ import annotations

import math
import platform
import sys
import time
from dataclasses import dataclass, field

import numpy as np
from gnibench import __version__
from gnibench.suite.cell.codegen import load
from gnibench.suite.foundation.status import KERNEL_STATUSES

STATUS = {s.code: s.value for s in KERNEL_STATUSES}
from gnibench.suite.cell.spec import MethodConfig, parse_method, parse_problem
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Bound

ADAPTIVE_STATE = 10     # length of ``st``, the resumable state of the adaptive drivers


@dataclass
class Result:
    """One integrated cell: samples, invariant errors, global error, cost and provenance."""

    problem: str
    method: str
    status: str
    reason: str
    state_names: tuple[str, ...]
    integral_names: tuple[str, ...]
    t: np.ndarray
    y: np.ndarray
    invariant_errors: np.ndarray
    global_error: np.ndarray | None
    steps: np.ndarray
    nfev: np.ndarray
    njev: np.ndarray
    wall_seconds: float
    compile_seconds: float
    cache_misses: int
    h: float
    y0: tuple[float, ...]
    meta: dict = field(default_factory=dict)
    rejected: np.ndarray | None = None      # cumulative rejected steps (adaptive methods)


def grid(h: float, steps: int | None, t_end: float | None) -> tuple[int, float]:
    """Number of steps and the last step: n steps of h, or reach t_end exactly (last step shorter)."""
    if (steps is None) == (t_end is None):
        raise UserError("give exactly one of --steps N or --t-end T")
    if steps is not None:
        if steps < 1:
            raise UserError(f"bad --steps {steps}; allowed: an integer >= 1")
        return int(steps), h
    if not (t_end > 0 and math.isfinite(t_end)):
        raise UserError(f"bad --t-end {t_end}; allowed: a finite number > 0")
    ratio = t_end / h
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


def grid_step(method: MethodConfig) -> float:
    """The option that spaces a method's grid: its step h, or dt_out for an adaptive engine."""
    return float(method.base.values[getattr(method.base.record, "grid_param", "h")])


def global_error(problem: Bound, t: np.ndarray, y: np.ndarray, ref) -> tuple[np.ndarray | None, dict]:
    """Euclidean norm of y - reference at every sample, and the reference's provenance."""
    if ref is None or len(t) == 0:
        return None, {"backend": None}
    from gnibench.suite.cell.reference import reference_solution

    sol = reference_solution(problem, t, ref)
    meta = {**ref.describe(), "cached": sol.cached, "seconds": sol.seconds}
    with np.errstate(over="ignore", invalid="ignore"):     # a diverged cell's error is inf
        return np.sqrt(np.sum((y - sol.y) ** 2, axis=1)), meta


def versions() -> dict:
    import numba

    return {"gnibench": __version__, "python": sys.version.split()[0], "numpy": np.__version__,
            "numba": numba.__version__, "platform": platform.platform()}


def prepare(problem_text: str, method_text: str) -> tuple[Bound, MethodConfig]:
    """Parse and validate a cell's specs (raises UserError on bad input)."""
    problem = parse_problem(problem_text)
    target = problem.record.transformed(problem.values) or problem
    return problem, parse_method(method_text, target)


def solve(problem_text: str, method_text: str, steps: int | None = None,
          t_end: float | None = None, every: int = 1, reference: str | None = None) -> Result:
    """Integrate one cell. Bad input raises UserError; divergence is a status, not an exception.

    ``reference`` chooses what ``global_error`` is measured against (:mod:`gnibench.suite.cell.reference`):
    ``exact``, ``heyoka[:precision=...,tol=...]``, ``rebound[:tol=...]`` or ``none``; by default
    the exact solution when the problem has one.
    """
    from gnibench.suite.cell.reference import default_reference, parse_reference

    problem, method = prepare(problem_text, method_text)
    ref = (default_reference(problem.record) if reference is None
           else parse_reference(reference, problem.record))
    if every < 1:
        raise UserError(f"bad --every {every}; allowed: an integer >= 1")
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    transformed = problem.record.transformed(problem.values)
    if getattr(method.base.record, "run", None) is not None:
        if transformed is not None:
            raise UserError(f"{method.base.id} is an external engine; it cannot integrate the "
                            f"transformed system of {problem.id} (drop the transform option)")
        return _solve_external(problem, method, SampleGrid(h, nsteps, h_last, every), ref)
    if transformed is not None:
        if method.base.values.get("adaptive") and method.base.values.get("dt_out", 0.0) > 0.0:
            raise UserError(f"dt_out spaces a grid in the integrated system's time, which for the "
                            f"transformed system of {problem.id} is not t (drop dt_out or the "
                            f"transform option)")
        return _solve_transformed(problem, transformed, method, steps, t_end, every, ref)
    return _solve_bound(problem, method, steps, t_end, every, ref)


def _solve_bound(problem: Bound, method: MethodConfig, steps, t_end, every, ref=None) -> Result:
    """The compiled path for resolved specs (fixed step or adaptive)."""
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    adaptive = method.base.values.get("adaptive")
    if adaptive and t_end is None:
        raise UserError(f"{method.base.id} with adaptive=true needs --t-end T (not --steps); "
                        f"for fixed steps use {method.base.id}:adaptive=false,h=...")
    if adaptive and method.base.values.get("dt_out", 0.0) > 0.0:
        why = dense_output_refusal(problem, method)
        if why:
            raise UserError(f"dt_out needs dense output, which does not apply here: {why}; "
                            f"use --every K instead")
    cell = _compiled_cell(problem, method)
    if adaptive:
        return _solve_adaptive(problem, method, cell, float(t_end), every, ref)
    mod, rec, par = cell.mod, problem.record, cell.par
    y0a = np.array(cell.y0, dtype=np.float64)
    rows = 2 + nsteps // every + (1 if nsteps % every else 0)
    out_t, out_y, out_c = np.empty(rows), np.empty((rows, rec.dim)), np.zeros((rows, 4))
    t1 = time.perf_counter()
    code, done, nrows = mod.integrate(y0a, par, h, nsteps, h_last, every, out_t, out_y, out_c)
    wall = time.perf_counter() - t1
    status = STATUS[int(code)]
    reason = ""
    if status == "nonfinite":
        reason = f"state overflowed or became NaN at step {done + 1}"
    elif status == "newton_failed":
        reason = (f"Newton (or the projection) did not converge at step {done + 1}; raise "
                  f"newton_maxit (now {method.base.values.get('newton_maxit', '-')}) or lower h")
    return _result(problem, method, cell, out_t[:nrows], out_y[:nrows], out_c[:nrows], ref,
                   status, reason, wall, h,
                   {"nsteps": nsteps, "h_last": h_last, "every": every})


@dataclass
class _Cell:
    mod: object
    names: tuple[str, ...]
    ppar: np.ndarray
    par: np.ndarray
    y0: tuple[float, ...]
    h0_all: tuple
    compile_seconds: float


def _compiled_cell(problem: Bound, method: MethodConfig) -> _Cell:
    """Load the cell's compiled module, build ``par`` (H0 and gains of the modifiers), warm up."""
    rec = problem.record
    y0 = rec.y0(problem.values)
    t0 = time.perf_counter()
    mod, meta, _ = load(problem, method)
    ppar = np.array(rec.par(problem.values), dtype=np.float64)
    names = tuple(meta["integrals"])
    h0_all = mod.invariants(tuple(y0), ppar) if names else ()
    extra = []
    for m in method.modifiers:
        idx = [names.index(x) for x in m.values["on"]]
        extra.extend(m.record.runtime(m.values, [h0_all[k] for k in idx]))
    par = np.concatenate([ppar, np.array(extra, dtype=np.float64)])
    # warm-up: one step on scratch arrays loads (or compiles) the driver the cell runs and all it
    # calls (with dt_out, the dense-output driver)
    y0a = np.array(y0, dtype=np.float64)
    if method.base.values.get("adaptive"):
        dense = method.base.values.get("dt_out", 0.0) > 0.0
        drive = mod.integrate_dense if dense else mod.integrate_adaptive
        st, y_io = np.zeros(ADAPTIVE_STATE), np.array([y0a, np.zeros_like(y0a)])
        drive(y_io, st, par, 1.0, 0.0, 1.0, 1e-3, 1e-3, 1, 0.5, 2, 1,
              np.empty(2), np.empty((2, rec.dim)), np.zeros((2, 4)))
    else:
        mod.integrate(y0a, par, float(method.base.values.get("h", 0.01)), 1, 0.01, 1,
                      np.empty(3), np.empty((3, rec.dim)), np.zeros((3, 4)))
    return _Cell(mod, names, ppar, par, tuple(y0), tuple(h0_all), time.perf_counter() - t0)


def dense_output_refusal(problem: Bound, method: MethodConfig) -> str:
    """Why the cell's accepted steps are not the endpoints of its method's continuous extension
    (methods/dense_output.py), or "" when dense output applies."""
    base = method.base
    if getattr(base.record.data, "dense", None) is None:
        return f"{base.id} has no continuous extension (dense output: dopri5, dop853)"
    if not base.values.get("adaptive"):
        return f"{base.id} runs at fixed step (adaptive=false)"
    steps = [m.record.id for m in method.modifiers if m.record.kind == "step"]
    if steps:
        return f"+{steps[0]} moves each accepted point off the continuous extension's endpoint"
    if problem.record.post_step is not None:
        return (f"{problem.id} maps each accepted point by its identification (post_step), off the "
                f"continuous extension's endpoint")
    return ""


def _solve_adaptive(problem, method, cell, t_end, every, ref) -> Result:
    """Adaptive embedded RK: the resumable driver fills fixed-size chunks until t_end.

    With ``dt_out`` > 0 the samples are the grid k dt_out (every ``every``-th point) plus t_end,
    spaced as the external engines space theirs (:class:`SampleGrid`), filled by dense output."""
    v, rec = method.base.values, problem.record
    dt_out = float(v.get("dt_out", 0.0))
    n_out, dense_meta = 0, {}
    if dt_out > 0.0:                      # dense output applies: checked by _solve_bound
        n_out, _ = grid(dt_out, None, t_end)
        dense = method.base.record.data.dense
        dense_meta = {"dense_output": {"dt_out": dt_out, "grid_intervals": n_out,
                                       "order": dense.order, "extension": dense.reference,
                                       "extra_f_per_dense_step": dense.extra_stages}}
    y_io = np.array([cell.y0, np.zeros(rec.dim)], dtype=np.float64)
    st = np.zeros(ADAPTIVE_STATE)
    hmax = v["hmax"] if v["hmax"] > 0 else t_end
    # dense output: the whole grid in one buffer (a step may hold many grid points)
    cap = 4096 if dt_out == 0.0 else -(-n_out // every) + 3
    drive = cell.mod.integrate_dense if dt_out > 0.0 else cell.mod.integrate_adaptive
    chunks, wall = [], 0.0
    while True:
        out_t, out_y, out_c = np.empty(cap), np.empty((cap, rec.dim)), np.zeros((cap, 4))
        t1 = time.perf_counter()
        code, rows = drive(y_io, st, cell.par, t_end, v["h0"], hmax, v["rtol"], v["atol"], every,
                           dt_out, n_out, v["max_steps"], out_t, out_y, out_c)
        wall += time.perf_counter() - t1
        chunks.append((out_t[:rows].copy(), out_y[:rows].copy(), out_c[:rows].copy()))
        if code != 5:
            break
        if rows == 0:
            raise RuntimeError("adaptive driver: output buffer too small for one step")
    t, y, c = (np.concatenate([ch[i] for ch in chunks]) for i in range(3))
    status = STATUS[int(code)]
    reason = {"max_steps": f"more than max_steps={v['max_steps']} steps before t = {t_end:g}",
              "step_too_small": f"step size underflow at t = {st[0]:.17g} (stiff, or diverging)",
              "newton_failed": f"the projection did not converge at t = {st[0]:.17g}",
              }.get(status, "")
    return _result(problem, method, cell, t, y, c, ref, status, reason, wall, v["h0"],
                   {"t_end": t_end, "every": every, "accepted": int(st[4]), "rejected": int(st[5]),
                    **dense_meta})


def _result(problem, method, cell, t, y, c, ref, status, reason, wall, h, grid_meta) -> Result:
    """Integrals, global error and provenance of a compiled cell's samples."""
    mod, names, rec = cell.mod, cell.names, problem.record
    inv = np.empty((len(t), len(names)))
    mod.eval_invariants(y, cell.ppar, len(t), inv)
    gerr, ref_meta = global_error(problem, t, y, ref)
    misses = sum(sum(f.stats.cache_misses.values()) for f in vars(mod).values()
                 if hasattr(f, "stats") and hasattr(f.stats, "cache_misses"))
    return Result(
        problem=problem.text(), method=method.text(), status=status, reason=reason,
        state_names=rec.state, integral_names=names, t=t, y=y,
        invariant_errors=inv - np.asarray(cell.h0_all)[None, :], global_error=gerr,
        steps=c[:, 0].astype(np.int64), nfev=c[:, 1], njev=c[:, 2], rejected=c[:, 3],
        wall_seconds=wall, compile_seconds=cell.compile_seconds, cache_misses=int(misses), h=h,
        y0=cell.y0,
        meta={"versions": versions(), **grid_meta, "seed": None,
              "H0": [float(x) for x in cell.h0_all], "reference": ref_meta},
    )


def _solve_transformed(problem, transformed, method, steps, t_end, every, ref) -> Result:
    """Integrate the transformed problem (e.g. K-S), then map its samples back to (t, y)."""
    inner = _solve_bound(transformed, method, steps, t_end, every)
    t, y = problem.record.transform.back(inner.y, problem.values)
    original = parse_method("euler", problem)              # a cell whose module has the integrals
    cell = _compiled_cell(problem, original)
    inv = np.empty((len(t), len(cell.names)))
    cell.mod.eval_invariants(np.ascontiguousarray(y), cell.ppar, len(t), inv)
    gerr, ref_meta = global_error(problem, t, y, ref)
    return Result(
        problem=problem.text(), method=method.text(), status=inner.status, reason=inner.reason,
        state_names=problem.record.state, integral_names=cell.names, t=t, y=y,
        invariant_errors=inv - np.asarray(cell.h0_all)[None, :], global_error=gerr,
        steps=inner.steps, nfev=inner.nfev, njev=inner.njev, rejected=inner.rejected,
        wall_seconds=inner.wall_seconds, compile_seconds=inner.compile_seconds,
        cache_misses=inner.cache_misses, h=inner.h, y0=cell.y0,
        meta={**inner.meta, "H0": [float(x) for x in cell.h0_all], "reference": ref_meta,
              "transform": {"option": problem.record.transform.option,
                            "problem": transformed.text(), "s": inner.t.tolist()[-1:],
                            "doc": problem.record.transform.doc}},
    )


def _solve_external(problem: Bound, method: MethodConfig, sg: SampleGrid, ref) -> Result:
    """An external engine's cell: ``Method.run`` on the sample grid instead of the compiled driver."""
    from gnibench.methods.engines.base import problem_functions

    rec = problem.record
    y0 = rec.y0(problem.values)
    fns = problem_functions(rec)
    ppar = tuple(rec.par(problem.values))
    names = tuple(fns.names)
    h0_all = fns.invariants(tuple(y0), ppar) if names else ()
    run = method.base.record.run(problem, method.base.values, sg)
    t = sg.t[:len(run.y)]
    inv = np.array([fns.invariants(tuple(row), ppar) for row in run.y]).reshape(len(t), len(names))
    gerr, ref_meta = global_error(problem, t, run.y, ref)
    return Result(
        problem=problem.text(), method=method.text(), status=run.status, reason=run.reason,
        state_names=rec.state, integral_names=names, t=t, y=run.y,
        invariant_errors=inv - np.asarray(h0_all)[None, :], global_error=gerr, steps=run.steps,
        nfev=np.asarray(run.nfev, dtype=float), njev=np.zeros(len(t)), wall_seconds=run.seconds,
        compile_seconds=run.setup_seconds, cache_misses=0, h=sg.h, y0=tuple(y0),
        meta={"versions": versions(), "nsteps": sg.nsteps, "h_last": sg.h_last, "every": sg.every,
              "seed": None, "H0": [float(x) for x in h0_all], "reference": ref_meta,
              "grid_param": method.base.record.grid_param, "engine": run.info},
    )
