"""Reference solutions of the orbits of an ensemble, at each orbit's sample times.

* ``exact``: each orbit's exact solution (``Problem.exact`` from its own initial point), as for a
  single cell (:mod:`gnibench.suite.cell.reference`).
* ``heyoka``: all the orbits at once by heyoka's ensemble propagation
  (``heyoka.ensemble_propagate_grid``: one Taylor integrator of the problem's sympy model, copied
  per orbit by a generator that sets the orbit's initial state; threads, here one, since the
  runner's workers are the parallelism), on the union of the orbits' sample times; each orbit's
  rows are read at its own times. Cached on disk as one file per set of orbits and grid,
  checksummed (:func:`gnibench.suite.foundation.cache.write_checked`).
* ``rebound``, and problems whose domain boundary heyoka must locate (``Problem.boundary``):
  orbit by orbit through :func:`~gnibench.suite.cell.reference.reference_solution` (cached per
  orbit).
"""
from __future__ import annotations

import hashlib
import io
import json
from importlib.metadata import version

import numpy as np
from gnibench.suite.foundation.cache import cache_dir, read_checked, write_checked
from gnibench.suite.foundation.params import Bound

FORMAT = 1


def ensemble_references(problem: Bound, y0: np.ndarray, times: list, spec, options=(),
                        points=None) -> list[np.ndarray]:
    """The reference states of each orbit (initial states ``y0``, shape (n, N)) at its sample
    times ``times[i]``: a list of arrays of shape (len(times[i]), N)."""
    rec = problem.record
    if spec.backend == "exact":
        return [np.asarray(rec.exact(np.asarray(t, dtype=float), tuple(map(float, y)),
                                     _values(problem, options, points, i)), dtype=float)
                for i, (t, y) in enumerate(zip(times, y0))]
    if spec.backend == "heyoka" and rec.boundary is None and rec.post_step is None:
        grid = np.unique(np.concatenate([np.asarray(t, dtype=float) for t in times])) \
            if times else np.zeros(0)
        full = _heyoka(problem, y0, grid, spec)
        return [full[i, np.searchsorted(grid, t)] for i, t in enumerate(times)]
    from gnibench.suite.cell.reference import reference_solution

    out = []
    for i, t in enumerate(times):
        orbit = Bound(rec, _values(problem, options, points, i))
        out.append(reference_solution(orbit, t, spec).y if len(t) else np.zeros((0, rec.dim)))
    return out


def _values(problem: Bound, options, points, i: int) -> dict:
    if points is None:
        return dict(problem.values)
    return {**problem.values, **dict(zip(options, map(float, points[i])))}


def _key(problem: Bound, y0: np.ndarray, grid: np.ndarray, spec) -> str:
    from gnibench.problems.codegen import _source_hash
    from gnibench.suite.foundation.provenance import code_digest

    code = code_digest("gnibench.methods.engines.base", "gnibench.methods.engines.heyoka", __name__)
    h = hashlib.sha256(json.dumps({
        "format": FORMAT, "problem": problem.text(), "source": _source_hash(problem.record),
        "spec": spec.text(), "engine": f"heyoka {version('heyoka')}", "engine_code": code},
        sort_keys=True).encode())
    h.update(np.ascontiguousarray(y0, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(grid, dtype="<f8").tobytes())
    return h.hexdigest()[:24]


def _heyoka(problem: Bound, y0: np.ndarray, grid: np.ndarray, spec) -> np.ndarray:
    """Every orbit on ``grid`` (shape (n, len(grid), N); NaN after an orbit heyoka could not
    finish), from the disk cache when it holds them."""
    path = cache_dir("references") / f"{problem.id}-ensemble-{_key(problem, y0, grid, spec)}.npz"

    def parse(raw: bytes) -> np.ndarray:
        with np.load(io.BytesIO(raw), allow_pickle=False) as z:
            y = np.asarray(z["y"], dtype=np.float64)
            if y.shape != (len(y0), len(grid), y0.shape[1]) or not np.array_equal(z["t"], grid):
                raise ValueError("another set of orbits")
            return y

    cached = read_checked(path, "ensemble reference", parse=parse)
    if cached is not None:
        return cached
    y = propagate(problem, y0, grid, spec.precision, spec.tol)
    buffer = io.BytesIO()
    np.savez(buffer, t=grid, y=y)
    write_checked(path, buffer.getvalue())
    return y


def propagate(problem: Bound, y0: np.ndarray, grid: np.ndarray, precision: str = "double",
              tol: float | None = None, threads: int = 1) -> np.ndarray:
    """heyoka's ensemble propagation of the orbits ``y0`` onto ``grid`` (in ``precision``, with
    Taylor tolerance ``tol``, default the precision's epsilon), on ``threads`` threads: shape
    (n, len(grid), N) in double. Each orbit's integrator is independent of the others and of the
    threads, so the numbers do not depend on ``threads``."""
    import heyoka as hy
    from gnibench.methods.engines.heyoka import (
        COMPACT_ABOVE,
        epsilon,
        fp_type,
        heyoka_system,
        precision_name,
    )

    precision = precision_name(precision)
    fp = fp_type(precision)
    tol = epsilon(precision) if tol is None else float(tol)
    rec = problem.record
    system = heyoka_system(rec)
    pars = ([fp(float(x)) for x in rec.par(problem.values)]
            + [fp(c) for c in system.constants])[:system.n_pars]
    n, dim = y0.shape
    ta = hy.taylor_adaptive(system.equations, [fp(float(x)) for x in y0[0]], fp_type=fp,
                            tol=fp(tol), pars=pars, high_accuracy=True,
                            compact_mode=rec.dim > COMPACT_ABOVE)
    start = [[fp(float(x)) for x in row] for row in y0]

    def gen(copy, i):
        copy.state[:] = start[i]
        copy.time = fp(0.0)
        return copy

    times = np.array([fp(float(x)) for x in grid]) if precision == "real128" else \
        np.asarray(grid, fp)
    out = np.full((n, len(grid), dim), np.nan)
    if not len(grid) or not n:
        return out
    results = hy.ensemble_propagate_grid(ta, times, n, gen, algorithm="thread",
                                         max_workers=threads)
    for i, res in enumerate(results):
        outcome, values = res[1], np.asarray(res[-1].astype(np.float64))
        if str(outcome).endswith("time_limit"):
            out[i] = values
        else:                                  # keep the finite rows before heyoka stopped
            finite = np.all(np.isfinite(values), axis=1)
            stop = int(np.argmin(finite)) if not finite.all() else len(values)
            out[i, :stop] = values[:stop]
    return out
