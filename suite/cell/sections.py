"""Poincaré sections: ``gnibench solve PROBLEM METHOD (--t-end T | --steps N) --section K``.

Design
------
1. *Samples.* The cell is integrated with a sample at every step (every = 1), in chunks, so that a
   long horizon never holds the whole trajectory in memory and the run stops as soon as K crossings
   have been found. Compiled fixed-step methods restart the driver from the last state of the
   previous chunk (the drivers are one-step: the restart continues the same numerical trajectory);
   compiled adaptive methods resume their driver state, and also report the size of every accepted
   step; external engines and transformed problems (K-S) are solved once over the whole horizon
   with every = 1 and then scanned.
2. *Detection.* A crossing of {g = 0} lies in (t_n, t_n+1] when g(y_n) > 0 >= g(y_n+1) or
   g(y_n) < 0 <= g(y_n+1) (a sample exactly on the section belongs to the interval that ends there;
   the initial point, often on the section, is never a crossing).
3. *Location.* The crossing of the numerical solution is located by one of two locators, recorded
   in ``meta.locator``:

   * ``dense`` -- where the method has a continuous extension and the accepted points are its
     endpoints (dopri5, dop853 in adaptive mode, without a step modifier such as +projection and on
     a problem without an identification map ``post_step``; :func:`gnibench.suite.cell.solve.dense_output_refusal`).
     The step (t_n, t_n+1] is recomputed from y_n with the driver's step size by the cell's
     ``dense_coeffs``, i.e. by the very operations of ``step_err``: its end point must equal the
     sample y_n+1 bit for bit (else the crossing falls back to Hénon's trick and is counted in
     ``meta.dense.fallbacks``). The continuous extension u(θ) (DOPRI5: order 4, DOP853: order 7;
     methods/dense_output.py) is then solved for g(u(θ)) = 0 by Newton's method with
     du/dθ from the same extension, kept inside the sign bracket on [0, 1] (bisection when a Newton
     step leaves it), until the step no longer changes θ; the iterate of smallest |g| is reported,
     at t_n + θ h. The located point is the method's own dense output: it lies on the numerical
     orbit within the extension's error, of the order of the tolerance (on henon-heiles at
     rtol = 1e-12 the dense and Hénon crossings differ by 3e-12; tests/test_sections.py).
   * ``henon`` (Hénon 1982) -- every other method, the fixed-step mode of the embedded pairs, and
     cells with a step modifier or a problem ``post_step`` (their accepted point is not the end of
     the continuous extension). From the sample y_n before the crossing, the system is integrated
     with g as the independent variable, dy/dg = F(y) / (grad g . F(y)), dt/dg = 1 / (grad g .
     F(y)), over Delta g = -g(y_n), by DOP853 (order 8) with m equal substeps, m doubled from 2 until
     two successive results agree to 1e-15 (relative). F is the field the method integrates: the
     compiled cell's ``f``, i.e. the base field or the modified one (observer, penalty); for
     external engines and transformed problems it is the base field of the problem. The located
     point is on the exact flow through y_n.

   When g is a state coordinate (every current section), g at the located point is 0 up to
   round-off with either locator; the largest located |g| is reported (``meta.max_abs_g``).
4. *Selection.* The crossing counts when ``condition(y*) > 0`` at the located point y*.

Output columns: ``crossing`` (1, 2, ...), ``t``, ``chart`` (multi-chart sections, e.g. so(4)'s
Gamma_k), the section coordinates, the remaining state components, and ``err_<integral>`` = H(y*) - H(y0).
"""
from __future__ import annotations

import time

import numpy as np
from gnibench.suite.cell.compiled import (
    ADAPTIVE_STATE,
    COUNTERS,
    FIXED_STATE,
    compile_cell,
    dense_output_refusal,
    problem_kernel,
)
from gnibench.suite.cell.grid import grid, grid_step
from gnibench.suite.cell.trajectory import Trajectory
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.foundation.status import Status

CHUNK = 8192                  # steps per chunk of the compiled drivers
HENON_RTOL = 1e-15            # agreement of m and 2m DOP853 substeps
HENON_MAX_SUBSTEPS = 4096
DENSE_MAXIT = 60              # Newton (or bisection) iterations on the continuous extension


# -- the section's functions ------------------------------------------------------------------------

def section_of(rec, index: int = 0):
    """The problem's section record and its generated functions (g, grad g, condition)."""
    if not rec.sections:
        raise UserError(f"{rec.id} has no Poincaré section; --section applies to problems with one "
                        f"(see `gnibench list problems`)")
    from gnibench.problems.codegen import python_functions

    fns = python_functions(rec)
    return (rec.sections[index], fns[f"section_g_{index}"], fns[f"section_grad_{index}"],
            fns[f"section_cond_{index}"], fns)


def _g_values(g, Y: np.ndarray, par) -> np.ndarray:
    """g at every row of Y: vectorized over columns when the expression allows it, else row-wise."""
    try:
        with np.errstate(all="ignore"):
            v = np.asarray(g(tuple(Y.T), par), dtype=float)
        if v.shape == (len(Y),):
            return v
    except TypeError:
        pass
    return np.array([g(tuple(row), par) for row in Y], dtype=float)


def crossing_intervals(gv: np.ndarray) -> np.ndarray:
    """Indices n with a crossing of g = 0 in (t_n, t_n+1]."""
    a, b = gv[:-1], gv[1:]
    return np.nonzero(((a > 0) & (b <= 0)) | ((a < 0) & (b >= 0)))[0]


# -- Hénon's trick ----------------------------------------------------------------------------------

def _dop853():
    from gnibench.methods.dop853_coefficients import N_STAGES, A, B, C

    return A[:N_STAGES, :N_STAGES], np.asarray(B, dtype=float), C[:N_STAGES]


def henon(y: np.ndarray, t: float, F, grad_g, g, par_g) -> tuple[np.ndarray, float, int]:
    """Integrate (y, t) in the independent variable g from g(y) to 0: the point on the section.

    ``F(y) -> array`` is the vector field, ``grad_g(y, par_g)`` the gradient of g. Returns the point,
    its time and the number of DOP853 substeps used.
    """
    A, B, C = _dop853()
    n = len(y)
    dg_total = -g(tuple(y), par_g)

    def rhs(z):
        f = np.asarray(F(z[:n]), dtype=float)
        d = float(np.dot(np.asarray(grad_g(tuple(z[:n]), par_g), dtype=float), f))
        out = np.empty(n + 1)
        out[:n] = f / d
        out[n] = 1.0 / d
        return out

    def run(m):
        z = np.append(np.asarray(y, dtype=float), t)
        hs = dg_total / m
        K = np.empty((len(C), n + 1))
        for _ in range(m):
            for i in range(len(C)):
                K[i] = rhs(z + hs * (A[i, :i] @ K[:i]))
            z = z + hs * (B @ K)
        return z

    if dg_total == 0.0:
        return np.asarray(y, dtype=float), t, 0
    m = 2
    prev = run(m)
    while m < HENON_MAX_SUBSTEPS:
        m *= 2
        cur = run(m)
        if np.all(np.abs(cur - prev) <= HENON_RTOL * np.maximum(1.0, np.abs(cur))):
            return cur[:n], float(cur[n]), m
        prev = cur
    return prev[:n], float(prev[n]), m


# -- dense output ------------------------------------------------------------------------------------

def dense_crossing(mod, par, y0, t0: float, h: float, y1_sample, t1: float, g, grad_g, par_g):
    """The crossing of {g = 0} by the continuous extension of the step from (t0, y0) of size h,
    which ended at the sample (t1, y1_sample).

    ``mod`` is the cell's compiled module (``f``, ``dense_coeffs``, ``dense_eval``,
    ``dense_slope``), ``par`` its parameters; ``g(y, par_g)`` and ``grad_g`` the section function.
    Returns (point, time, Newton iterations), or None when the recomputed step does not end on
    ``y1_sample`` (then the caller falls back to Hénon's trick).
    """
    y0 = tuple(float(x) for x in y0)
    y1, cf = mod.dense_coeffs(y0, h, par, mod.f(y0, par))
    end = tuple(float(x) for x in y1_sample)
    if y1 != end:
        return None
    g_end = g(end, par_g)
    if g_end == 0.0:
        return np.array(end), t1, 0
    lo, g_lo, hi, g_hi = 0.0, g(y0, par_g), 1.0, g(mod.dense_eval(cf, 1.0), par_g)
    best = (abs(g_end), 1.0, end)
    if g_lo * g_hi > 0.0:              # u(1) and y1 differ by round-off and g(y1) is that small
        return np.array(end), t1, 0
    theta = lo - g_lo * (hi - lo) / (g_hi - g_lo)
    it = 0
    for it in range(1, DENSE_MAXIT + 1):
        u = mod.dense_eval(cf, theta)
        gu = g(u, par_g)
        if abs(gu) < best[0]:
            best = (abs(gu), theta, u)
        if gu == 0.0:
            break
        if (gu > 0.0) == (g_lo > 0.0):
            lo, g_lo = theta, gu
        else:
            hi, g_hi = theta, gu
        slope = float(np.dot(grad_g(u, par_g), mod.dense_slope(cf, theta)))
        new = theta - gu / slope if slope != 0.0 else np.nan
        if not lo < new < hi:
            new = 0.5 * (lo + hi)        # Newton left the bracket: bisect
        if new == theta or hi - lo <= 2.3e-16 * hi:
            break
        theta = new
    _, theta, u = best
    if theta == 1.0:
        return np.array(end), t1, it
    return np.array(u, dtype=float), t0 + theta * h, it


# -- sample streams ---------------------------------------------------------------------------------

def _fixed_chunks(cell, rec, h, nsteps, h_last, budget):
    """Yield (t, y, None, status, done) chunks of the resumable fixed-step driver, a sample at
    every step (no step sizes: the crossings of fixed-step cells are located by Hénon's trick)."""
    y_io = np.array([cell.y0, np.zeros(rec.dim)], dtype=np.float64)
    st = np.zeros(FIXED_STATE)
    while True:
        out_t, out_y, out_c = np.empty(CHUNK), np.empty((CHUNK, rec.dim)), np.zeros((CHUNK, COUNTERS))
        code, rows = cell.kernel.integrate(y_io, st, cell.par, h, nsteps, h_last, 1, budget,
                                           out_t, out_y, out_c)
        status = Status.from_code(code)
        more = status in (Status.BUFFER_FULL, Status.PAUSED)
        yield (out_t[:rows].copy(), out_y[:rows].copy(), None, Status.OK if more else status,
               int(st[0]), st[0] / nsteps)
        if not more:
            return


def _adaptive_chunks(cell, rec, v, t_end, budget):
    """Yield (t, y, h, status, done) chunks of the resumable adaptive driver; h[i] is the size of
    the accepted step ending at sample i (the driver's 5th output column; 0 where unknown)."""
    y_io = np.array([cell.y0, np.zeros(rec.dim)], dtype=np.float64)
    st = np.zeros(ADAPTIVE_STATE)
    hmax = v["hmax"] if v["hmax"] > 0 else t_end
    while True:
        out_t, out_y, out_c = np.empty(CHUNK), np.empty((CHUNK, rec.dim)), np.zeros((CHUNK, COUNTERS))
        code, rows = cell.kernel.integrate_adaptive(y_io, st, cell.par, t_end, v["h0"], hmax,
                                                    v["rtol"], v["atol"], 1, 0.0, 0,
                                                    v["max_steps"], budget, out_t, out_y, out_c)
        status = Status.from_code(code)
        more = status in (Status.BUFFER_FULL, Status.PAUSED)
        t, y, h = out_t[:rows].copy(), out_y[:rows].copy(), out_c[:rows, 4].copy()
        yield t, y, h, Status.OK if more else status, int(st[4]), st[0] / t_end
        if not more:
            return


# -- the command ------------------------------------------------------------------------------------

def integrate_section(problem, method, crossings: int, steps: int | None = None,
                      t_end: float | None = None, locator: str | None = None,
                      progress=None, samples: Trajectory | None = None) -> Trajectory:
    """Integrate until ``crossings`` crossings of the problem's first section (or the horizon);
    the trajectory's samples are the located crossings (``kind = "section"``).

    ``locator``: None (dense output where it applies, else Hénon's trick), ``"henon"`` (always
    Hénon's trick, e.g. to compare the two) or ``"dense"`` (a UserError where it does not apply).
    ``samples``: for external engines and transformed problems, their trajectory sampled at every
    step (from the driver facade), scanned for crossings.
    """

    if crossings < 1:
        raise UserError(f"bad --section {crossings}; allowed: an integer >= 1 (number of crossings)")
    if locator not in (None, "dense", "henon"):
        raise UserError(f"bad locator {locator!r}; allowed: dense, henon")
    rec = problem.record
    sec, g, grad_g, cond, fns = section_of(rec)
    ppar = tuple(float(x) for x in rec.par(problem.values))
    h = grid_step(method)
    nsteps, h_last = grid(h, steps, t_end)
    external = getattr(method.base.record, "run", None) is not None
    transformed = rec.transformed(problem.values) is not None
    adaptive = bool(method.base.values.get("adaptive"))
    t0 = time.perf_counter()
    dense_why = "external engine or transformed problem"
    compile_seconds = 0.0
    if external or transformed:
        res = samples
        stream = iter([(res.t, res.y, None, res.status, len(res.t) - 1, 1.0)])
        reason0 = res.reason
        compile_seconds = res.compile_seconds

        def F(y):
            return fns["base_f"](tuple(y), ppar)

        field_used = "base field of the problem"
    else:
        cell = compile_cell(problem, method)
        compile_seconds = cell.compile_seconds
        dense_why = dense_output_refusal(problem, method)
        if locator == "henon":
            dense_why = "Hénon's trick asked for (locator='henon')"
        if adaptive:
            if t_end is None:
                raise UserError(f"{method.base.id} with adaptive=true needs --t-end T (not --steps)")
            stream = _adaptive_chunks(cell, rec, method.base.values, float(t_end), CHUNK)
        else:
            stream = _fixed_chunks(cell, rec, h, nsteps, h_last, CHUNK)
        reason0 = ""
        f_c, par_c = cell.kernel.f, cell.par

        def F(y):
            return f_c(tuple(float(x) for x in y), par_c)

        field_used = ("field integrated by the method (" +
                      ("modified: " + "+".join(m.record.id for m in method.modifiers)
                       if method.modifiers else "base") + ")")
    if locator == "dense" and dense_why:
        raise UserError(f"dense output does not locate these crossings: {dense_why}")
    y0 = rec.y0(problem.values)

    pts_t, pts_y, max_g, max_sub, max_it, fallbacks = [], [], 0.0, 0, 0, 0
    prev = None                                  # last sample of the previous chunk
    status, t_last = Status.OK, 0.0
    for t, Y, H, code, _, fraction in stream:
        if prev is not None and len(t) and t[0] == prev[0][0]:
            t, Y = t[1:], Y[1:]                  # the restart repeats the previous last sample
        if prev is not None:
            t = np.concatenate([prev[0], t])
            Y = np.concatenate([prev[1], Y])
            H = None if H is None else np.concatenate([prev[2], H])
        if len(t) == 0:
            break
        gv = _g_values(g, Y, ppar)
        for n in crossing_intervals(gv):
            found = None
            if not dense_why:
                found = (dense_crossing(cell.kernel, cell.par, Y[n], float(t[n]), float(H[n + 1]),
                                        Y[n + 1], float(t[n + 1]), g, grad_g, ppar)
                         if H[n + 1] > 0 else None)
                fallbacks += found is None
            if found is not None:
                ys, ts, it = found
                max_it = max(max_it, it)
            else:
                ys, ts, m = henon(Y[n], float(t[n]), F, grad_g, g, ppar)
                max_sub = max(max_sub, m)
            if not cond(tuple(ys), ppar) > 0:
                continue
            pts_t.append(ts)
            pts_y.append(ys)
            max_g = max(max_g, abs(g(tuple(ys), ppar)))
            if len(pts_t) == crossings:
                break
        t_last = float(t[-1])
        if progress is not None:
            progress(max(len(pts_t) / crossings, fraction))
        if code is not Status.OK:
            status = code
            break
        if len(pts_t) == crossings:
            break
        prev = (t[-1:], Y[-1:], None if H is None else H[-1:])
    wall = time.perf_counter() - t0
    reason = ""
    if status is not Status.OK:
        reason = reason0 or f"the integration stopped ({status}) at t = {t_last:.17g}"
    elif len(pts_t) < crossings:
        reason = (f"only {len(pts_t)} of {crossings} crossings of {sec.name} before "
                  f"t = {t_last:.17g}; raise --t-end / --steps")
    Yc = np.array(pts_y, dtype=float).reshape(len(pts_y), rec.dim)
    chart = None
    if sec.chart is not None:
        chart = (np.asarray(sec.chart(Yc), dtype=np.int64) if len(Yc)
                 else np.zeros(0, dtype=np.int64))
    pk = problem_kernel(problem)
    rows = len(pts_t)
    meta = {"versions": versions(), "section": sec.name, "section_reference": sec.reference,
            "section_coords": list(sec.coords), "crossings_requested": crossings,
            "crossings_found": rows, "max_abs_g": max_g, "locator": "henon" if dense_why else "dense",
            "wall_seconds": wall, "compile_seconds": compile_seconds, "h": h, "nsteps": nsteps,
            "t_last_sample": t_last, "y0": list(y0), "H0": list(pk.at(y0)),
            "design": "suite/cell/sections.py"}
    if dense_why:
        meta["locator_note"] = f"no dense output: {dense_why}"
    else:
        ext = method.base.record.data.dense
        meta["dense"] = {"extension": ext.reference, "order": ext.order,
                         "root": "Newton on g(u(theta)) inside the sign bracket",
                         "max_iterations": max_it, "fallbacks": fallbacks}
    if dense_why or fallbacks:
        meta["henon"] = {"integrator": "DOP853, m equal substeps in g", "max_substeps": max_sub,
                         "rtol": HENON_RTOL, "field": field_used}
    nan = np.full(rows, np.nan)
    return Trajectory(
        problem=problem.text(), method=method.text(), state_names=rec.state,
        t=np.array(pts_t, dtype=float), y=Yc, steps=np.zeros(rows, dtype=np.int64), nfev=nan,
        njev=nan.copy(), rejected=nan.copy(), integral_names=pk.integral_names,
        integrals=pk.integrals(Yc), H0=pk.at(y0), y0=tuple(y0), status=status, reason=reason,
        kind="section", chart=chart, provenance=meta)
