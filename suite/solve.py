"""Integrate one cell (problem x method) and measure it: the unit of work of every command."""
from __future__ import annotations

import math
import platform
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from suite import __version__
from suite.codegen import STATUS, load
from suite.errors import UserError
from suite.spec import Bound, MethodConfig, parse_method, parse_problem


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


def _check_independent(mod, idx, y0, par, modifier, problem) -> None:
    """[B] §2 assumes rank D_H = q on Γ; refuse observed integrals that are dependent at y0."""
    D = np.array([getattr(mod, f"grad_{k}")(tuple(y0), par) for k in idx])
    sv = np.linalg.svd(D, compute_uv=False)
    if sv[0] == 0.0 or sv[-1] <= 1e-10 * sv[0]:
        on = "/".join(modifier.values["on"])
        raise UserError(
            f"{modifier.id}: the observed integrals {on} of {problem.id} are not functionally "
            f"independent at the initial point (rank D_H < {len(idx)}, [B] §2); "
            f"observe an independent subset with on=...")


def versions() -> dict:
    import numba

    return {"gnibench": __version__, "python": sys.version.split()[0], "numpy": np.__version__,
            "numba": numba.__version__, "platform": platform.platform()}


def prepare(problem_text: str, method_text: str) -> tuple[Bound, MethodConfig]:
    """Parse and validate a cell's specs (raises UserError on bad input)."""
    problem = parse_problem(problem_text)
    return problem, parse_method(method_text, problem)


def solve(problem_text: str, method_text: str, steps: int | None = None,
          t_end: float | None = None, every: int = 1) -> Result:
    """Integrate one cell. Bad input raises UserError; divergence is a status, not an exception."""
    problem, method = prepare(problem_text, method_text)
    if every < 1:
        raise UserError(f"bad --every {every}; allowed: an integer >= 1")
    h = float(method.base.values["h"])
    nsteps, h_last = grid(h, steps, t_end)
    rec = problem.record
    y0 = rec.y0(problem.values)

    t0 = time.perf_counter()
    mod, meta, _ = load(problem, method)
    ppar = np.array(rec.par(problem.values), dtype=np.float64)
    names = tuple(meta["integrals"])
    y0a = np.array(y0, dtype=np.float64)
    h0_all = mod.invariants(tuple(y0), ppar) if names else ()
    extra = []
    for m in method.modifiers:
        idx = [names.index(x) for x in m.values["on"]]
        if m.record.needs_independent:
            _check_independent(mod, idx, y0, ppar, m, problem)
        extra.extend(m.record.runtime(m.values, [h0_all[k] for k in idx]))
    par = np.concatenate([ppar, np.array(extra, dtype=np.float64)])
    # warm-up: one step on scratch arrays loads (or compiles) every function of the cell
    scratch = (np.empty(3), np.empty((3, rec.dim)), np.empty((3, 3)))
    mod.integrate(y0a, par, h, 1, h, 1, *scratch)
    compile_seconds = time.perf_counter() - t0

    rows = 2 + nsteps // every + (1 if nsteps % every else 0)
    out_t, out_y, out_c = np.empty(rows), np.empty((rows, rec.dim)), np.empty((rows, 3))
    t1 = time.perf_counter()
    code, done, nrows = mod.integrate(y0a, par, h, nsteps, h_last, every, out_t, out_y, out_c)
    wall = time.perf_counter() - t1

    t, y, c = out_t[:nrows], out_y[:nrows], out_c[:nrows]
    inv = np.empty((nrows, len(names)))
    mod.eval_invariants(y, ppar, nrows, inv)
    inv_err = inv - np.asarray(h0_all)[None, :]
    gerr = None
    if rec.exact is not None:
        ex = rec.exact(t, y0, problem.values)
        gerr = np.sqrt(np.sum((y - ex) ** 2, axis=1))
    status = STATUS[int(code)]
    reason = ""
    if status == "nonfinite":
        reason = f"state overflowed or became NaN at step {done + 1}"
    elif status == "newton_failed":
        reason = (f"Newton did not converge in newton_maxit="
                  f"{method.base.values.get('newton_maxit')} iterations at step {done + 1}")
    misses = sum(sum(v.stats.cache_misses.values()) for v in vars(mod).values()
                 if hasattr(v, "stats") and hasattr(v.stats, "cache_misses"))
    return Result(
        problem=problem.text(), method=method.text(), status=status, reason=reason,
        state_names=rec.state, integral_names=names, t=t, y=y, invariant_errors=inv_err,
        global_error=gerr, steps=c[:, 0].astype(np.int64), nfev=c[:, 1], njev=c[:, 2],
        wall_seconds=wall, compile_seconds=compile_seconds, cache_misses=int(misses), h=h,
        y0=tuple(y0),
        meta={"versions": versions(), "nsteps": nsteps, "h_last": h_last, "every": every,
              "seed": None, "H0": [float(x) for x in h0_all]},
    )
