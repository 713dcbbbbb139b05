"""The batched driver facade: the orbits of an ensemble through one compiled kernel.

:func:`integrate_batch` runs N initial conditions of one compiled cell (fixed step or adaptive,
sampled every K steps or on a time grid) by the cell's batched module (the output
``batch_<output>`` of :func:`gnibench.methods.assembly.assemble`, methods/assembly/bindings.py;
its loop methods/assembly/templates/batch.py): a compiled loop over the orbits that calls the
single-orbit loop a cell of each initial condition runs, with the same flags and arguments, its run-time parameters (a
modifier's H0 is the orbit's, [B] (2.5)) and output rows sized for the horizon. Each orbit's
samples are therefore those of :func:`gnibench.suite.cell.driver.integrate` for that initial
condition, bit for bit (tests/runs/test_ensembles.py checks it).

An adaptive method without a time grid is sampled at t = 0 and the end only (its orbits' step
sequences differ; every K accepted steps would give each orbit other times). The orbits are run
in slices of about ``SECONDS`` of work, so that Ctrl-C stops the run between two slices and the
progress is reported (fraction of the orbits done).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from gnibench.suite.foundation.status import Status

SECONDS = 0.1             # one batched call lasts about this long (progress, Ctrl-C between)
COUNTERS = 5              # the columns of a driver's counters (suite/cell/calls.py)


@dataclass
class OrbitSamples:
    """The samples of the orbits of an ensemble, one entry per orbit (in order)."""

    t: list = field(default_factory=list)
    y: list = field(default_factory=list)
    counters: list = field(default_factory=list)      # (rows, 4): steps, nfev, njev, rejected
    status: list = field(default_factory=list)
    reason: list = field(default_factory=list)
    trajectories: list | None = None                  # one by one: the orbits' trajectories
    wall: float = 0.0
    compile: float = 0.0
    provenance: dict = field(default_factory=dict)


def call_budget(done: int, seconds: float, orbits: int) -> int:
    """Orbits in the next batched call: about :data:`SECONDS` of work at the pace so far."""
    if done == 0 or seconds <= 0:
        return max(1, min(orbits, 16))
    return max(1, min(orbits, int(done * SECONDS / seconds)))


def batched(spec) -> bool:
    """Whether the batched driver runs this typed cell's orbits: a compiled method on the problem
    itself (fixed step forward, or adaptive), not a section."""
    from gnibench.suite.cell.cellspec import CellKind

    return spec.kind in (CellKind.FIXED, CellKind.ADAPTIVE) and not spec.reverse


def plan(spec) -> tuple[str, dict, int, int]:
    """The single-orbit driver of the cell, its arguments (as the driver objects of
    :mod:`gnibench.suite.cell.drivers` pass them), the rows of one orbit and the grid's time
    component."""
    from gnibench.suite.cell.drivers import AdaptiveDriver, FixedStepDriver

    gp = spec.grid_plan
    every = spec.every
    grid = {"dt_out": 0.0 if gp is None else gp.dt_out, "n_out": 0 if gp is None else gp.n_out}
    if spec.adaptive:
        v = spec.method.base.values
        if gp is None:                        # t = 0 and the end only
            every = int(v["max_steps"]) + 1
        args = {"t_end": float(spec.t_end), "h0": float(v["h0"]),
                "hmax": float(v["hmax"]) if v["hmax"] > 0 else float(spec.t_end),
                "rtol": float(v["rtol"]), "atol": float(v["atol"]), "every": every, **grid,
                "max_steps": int(v["max_steps"])}
        rows = 3 if gp is None else -(-gp.n_out // every) + 3   # t = 0, the end, a failure
        names = AdaptiveDriver.names
    else:
        args = {"h": float(spec.h), "nsteps": int(spec.nsteps), "h_last": float(spec.h_last),
                "every": every, **grid}
        rows = spec.rows + 1 if gp is None else -(-gp.n_out // every) + 3
        names = FixedStepDriver.names
    return names["samples"] if gp is None else gp.driver, args, rows, -1


def orbit_parameters(problem, method, pk, y0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The run-time parameters of each orbit (rows, as :func:`gnibench.suite.cell.compiled.
    compile_cell` makes ``par`` for one cell: the problem's model parameters, each modifier's
    numbers from the orbit's own integrals at y0, the method's runtime options and data) and
    the integrals at each y0."""
    H0 = pk.integrals(y0)
    base = method.base
    tail = [float(base.values[name]) for name in base.record.runtime]
    tail += [float(x) for x in base.record.runtime_data]
    rows = []
    for h0 in H0:
        extra = []
        for m in method.modifiers:
            idx = [pk.integral_names.index(x) for x in m.values["on"]]
            extra.extend(m.record.runtime(m.values, [float(h0[k]) for k in idx]))
        rows.append(np.concatenate([pk.par, np.array(extra + tail, dtype=np.float64)]))
    return np.ascontiguousarray(rows, dtype=np.float64).reshape(len(y0), -1), H0


def integrate_batch(spec, y0: np.ndarray, progress=None):
    """The orbits of ``y0`` (shape (n, N)) through the batched driver: an
    :class:`OrbitSamples` (each orbit's t, y, counters, status and
    reason, the wall time of the compiled calls and the compile or load time)."""
    from gnibench.methods.assembly import assemble
    from gnibench.methods.assembly.bindings import DRIVER_NAMES, DRIVERS
    from gnibench.methods.assembly.loading import cache_misses, compiling, record_compiled
    from gnibench.suite.cell.compiled import problem_kernel
    from gnibench.suite.cell.drivers import adaptive_reason, fixed_reason
    from gnibench.suite.foundation.provenance import versions

    problem, method = spec.problem, spec.method
    name, args, rows, tcomp = plan(spec)
    kind, output = DRIVER_NAMES[name]
    n, dim = y0.shape
    t0 = time.perf_counter()
    with compiling():
        kernel = assemble(problem, method, f"batch_{output}")
        pk = problem_kernel(problem)
        fn = getattr(kernel, DRIVERS[kind].entry(f"batch_{output}"))
        par, _ = orbit_parameters(problem, method, pk, y0[:1])
        _call(fn, y0[:1], par, 0, 0, args, tcomp, rows, dim)      # compile or load: not timed
        record_compiled(kernel, pk.kernel)
    out = OrbitSamples(compile=time.perf_counter() - t0)
    par, _ = orbit_parameters(problem, method, pk, y0)
    done = 0
    while done < n:
        count = call_budget(done, out.wall, n - done)
        w0 = time.perf_counter()
        t, y, c, r, s = _call(fn, y0, par, done, count, args, tcomp, rows, dim)
        out.wall += time.perf_counter() - w0
        for i in range(count):
            k = int(r[i])
            status = Status.from_code(int(s[i]))
            if status is Status.BUFFER_FULL:                 # sized for the horizon: a bug
                raise RuntimeError("batched driver: output rows too few for the horizon")
            out.t.append(t[i, :k].copy())
            out.y.append(y[i, :k].copy())
            out.counters.append(c[i, :k, :4].copy())
            out.status.append(status)
            if "t_end" in args:
                last = float(t[i, k - 1]) if k else 0.0
                out.reason.append(adaptive_reason(status, last, args["t_end"], args["max_steps"]))
            else:
                out.reason.append(fixed_reason(status, int(c[i, k - 1, 0]) if k else 0, method))
        done += count
        if progress is not None:
            progress(done / n)
    out.provenance = {"versions": versions(), **{k: v for k, v in args.items()}, "seed": None,
                      "driver": f"batch_{name}", "wall_seconds": out.wall,
                      "compile_seconds": out.compile,
                      "numba_cache_misses": cache_misses(kernel)}
    return out


def _call(fn, y0, par, first: int, count: int, args: dict, tcomp: int, rows: int, dim: int):
    """One call of the batched driver on orbits first .. first + count - 1 (buffers for those)."""
    size = max(count, 1)
    out_t = np.empty((size, rows))
    out_y = np.empty((size, rows, dim))
    out_c = np.zeros((size, rows, COUNTERS))
    r = np.zeros(size, dtype=np.int64)
    s = np.zeros(size, dtype=np.int64)
    # the kernel indexes its orbits from ``first``: the buffers are those orbits' (offset views)
    fn(y0[first:first + count] if count else y0[:0], par[first:first + count] if count else par[:0],
       0, count, *args.values(), tcomp, out_t, out_y, out_c, r, s)
    return out_t, out_y, out_c, r, s

