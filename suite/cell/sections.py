"""Poincaré sections: ``gnibench solve PROBLEM METHOD (--t-end T | --steps N) --section K``.

Design
------
1. *Inside the compiled driver.* Compiled cells run a section variant of their own driver
   (``integrate_section`` for fixed steps, ``adaptive_section`` / ``adaptive_section_dense`` for
   the embedded pairs and odex; the same templates with a literal flag renamed,
   methods/assembly/templates/fixed.py, adaptive.py, extrapolation.py). After each accepted step (after the
   step modifiers and the problem's ``post_step``) the driver looks for a crossing, locates it,
   and writes one row (t, y and the cumulative counters steps, nfev, njev, rejected of that step)
   to its output buffer; it stops with ``ok`` after K crossings, and is resumable like every
   driver (buffer full, work budget spent: the same crossings whatever the buffer size and
   budget). External engines and transformed problems (K-S) are solved over the whole horizon
   with a sample at every step; their crossings are detected by one vectorised scan and located
   in one compiled call (``henon_all`` in the problem's module), on the base field.
2. *Detection.* A crossing of {g = 0} lies in (t_n, t_n+1] when g(y_n) > 0 >= g(y_n+1) or
   g(y_n) < 0 <= g(y_n+1) (a sample exactly on the section belongs to the interval that ends there;
   the initial point, often on the section, is never a crossing).
3. *Location.* The crossing of the numerical solution is located by one of two locators, recorded
   in ``meta.locator`` (methods/assembly/templates/events.py, methods/assembly/sections.py):

   * ``dense`` -- where the method has a continuous extension and the accepted points are its
     endpoints (dopri5, dop853 in adaptive mode, without a step modifier such as +projection and on
     a problem without an identification map ``post_step``;
     :func:`gnibench.suite.cell.compiled.dense_output_refusal`). The accepted step's stages are at
     hand, so its continuous extension u(θ) (DOPRI5: order 4, DOP853: order 7, 3 more
     f-evaluations counted in nfev; HNW I §II.6, methods/dense_output.py) is formed directly, and
     g(u(θ)) = 0 is solved by Newton's method with du/dθ from the same extension, kept inside the
     sign bracket on [0, 1] (bisection when a Newton step leaves it), until the step no longer
     changes θ; the iterate of smallest |g| is reported, at t_n + θ h. The located point is the
     method's own dense output: it lies on the numerical orbit within the extension's error, of
     the order of the tolerance (on henon-heiles at rtol = 1e-12 the dense and Hénon crossings
     differ by 3e-12; tests/cell/test_sections.py).
   * ``henon`` (Hénon 1982, Physica D 5) -- every other method, the fixed-step mode of the
     embedded pairs, and cells with a step modifier or a problem ``post_step`` (their accepted
     point is not the end of the continuous extension). From the accepted point y_n before the
     crossing, the system is integrated with g as the independent variable,
     dy/dg = F(y) / (grad g . F(y)), dt/dg = 1 / (grad g . F(y)), over Delta g = -g(y_n), by DOP853
     (order 8) with m equal substeps, m doubled from 2 until two successive results agree to
     1e-15 (relative; at most 4096), accumulated as increments over (y_n, t_n) so that rounding
     acts on the small increment. F is the field the method integrates: the compiled cell's
     ``f``, i.e. the base field or the modified one (observer, penalty); for external engines and
     transformed problems it is the base field of the problem. The located point is on the exact
     flow through y_n. Its f-evaluations are counted in nfev (and in ``meta.henon.nfev``).
     (choice) Integrating in g is valid only while g moves monotonically toward 0; when the step
     holds a turning point of g before the crossing (large steps, nearly tangent crossings) the
     trick from y_n would run backward in time to an earlier crossing (the previous code then
     lost the crossing: 3 of 3649 on the so(4) run of benchmarks/test_bench_sections.py). Then
     the same flow is first carried in time from y_n, in 16 (64, 256) equal parts of the step,
     to the last point before g changes sign, and the trick is applied from there
     (``meta.henon.time_walks``; ``not_located`` counts the crossings where even that failed and
     the direct result was kept).

   When g is a state coordinate (every current section), g at the located point is 0 up to
   round-off with either locator; the largest located |g| is reported (``meta.max_abs_g``).
4. *Selection.* The crossing counts when ``condition(y*) > 0`` at the located point y*.
5. *Charts* (multi-chart sections such as so(4)'s Γ1..Γ8, [B] §7) are computed after the run from
   the located states (``Section.chart``).

Output columns: ``crossing`` (1, 2, ...), ``t``, ``chart`` (multi-chart sections, e.g. so(4)'s
Gamma_k), the section coordinates, the remaining state components, and ``err_<integral>`` = H(y*) - H(y0).
"""
from __future__ import annotations

import numpy as np
from gnibench.methods.assembly.sections import HENON_MAX_SUBSTEPS, HENON_RTOL
from gnibench.suite.cell.calls import Buffers
from gnibench.suite.cell.compiled import dense_output_refusal, problem_kernel
from gnibench.suite.cell.drivers import AdaptiveDriver, FixedStepDriver, build_trajectory, kind_of
from gnibench.suite.cell.trajectory import Trajectory
from gnibench.suite.foundation.errors import UserError, spelled
from gnibench.suite.foundation.provenance import versions
from gnibench.suite.foundation.status import Status

CHUNK = 4096                  # rows (crossings) of one output buffer


def section_of(rec, index: int = 0):
    """The problem's section record (a UserError for a problem without one)."""
    if not rec.sections:
        raise UserError(f"{rec.id} has no Poincaré section; {spelled('--section')} applies to "
                        f"problems with one "
                        f"(see `gnibench list problems`)")
    return rec.sections[index]


def crossing_intervals(gv: np.ndarray) -> np.ndarray:
    """Indices n with a crossing of g = 0 in (t_n, t_n+1] (the rule of the compiled drivers)."""
    a, b = gv[:-1], gv[1:]
    return np.nonzero(((a > 0) & (b <= 0)) | ((a < 0) & (b >= 0)))[0]


def integrate_section(cell, progress=None, samples: Trajectory | None = None,
                      budget: int | None = 0) -> Trajectory:
    """Integrate a section cell (:class:`~gnibench.suite.cell.cellspec.CellSpec` with
    ``section`` = K, validated by its ``build``) until K crossings of the problem's first section
    (or the horizon); the trajectory's samples are the located crossings (``kind = "section"``).

    ``cell.locator``: None (dense output where it applies, else Hénon's trick), ``"henon"``
    (always Hénon's trick, e.g. to compare the two) or ``"dense"``. ``samples``: for external
    engines and transformed problems, their trajectory sampled at every step (from the driver
    facade), scanned for crossings. ``budget``: as for
    :func:`gnibench.suite.cell.driver.integrate`.
    """
    problem, method, crossings, locator = cell.problem, cell.method, cell.section, cell.locator
    rec = problem.record
    sec = section_of(rec)
    if samples is not None:
        return _scanned(problem, method, sec, crossings, samples)
    why = dense_output_refusal(problem, method)
    if locator == "henon" and not why:
        why = "Hénon's trick asked for (locator='henon')"
    kind = kind_of(method)
    name = kind.names["section" if why else "section_dense"]
    h, nsteps, h_last = cell.h, cell.nsteps, cell.h_last
    if kind is AdaptiveDriver:
        drv = AdaptiveDriver(problem, method, name, cell.t_end, wanted=crossings)
    else:
        drv = FixedStepDriver(problem, method, name, h, nsteps, h_last, wanted=crossings)
    buffers = Buffers(min(CHUNK, crossings + 1), rec.dim, grow=True)
    status, wall = drv.run(buffers, progress, budget)
    t, y, c = buffers.arrays()
    meta = {"wall_seconds": wall, "compile_seconds": drv.cell.compile_seconds, "h": h,
            "nsteps": nsteps, "t_last_sample": drv.t,
            "locator": "henon" if why else "dense", "max_abs_g": drv.slot("ST_MAX_G"),
            "driver": name}
    if why:
        meta["locator_note"] = f"no dense output: {why}"
        field = ("modified: " + "+".join(m.record.id for m in method.modifiers)
                 if method.modifiers else "base")
        meta["henon"] = _henon_meta(int(drv.slot("ST_SUBSTEPS")),
                                    f"field integrated by the method ({field})",
                                    drv.slot("ST_LOC_NFEV"))
        meta["henon"].update(time_walks=int(drv.slot("ST_WALKS")),
                             not_located=int(drv.slot("ST_HENON_FAILED")))
    else:
        ext = method.base.record.data.dense
        meta["dense"] = {"extension": ext.reference, "order": ext.order,
                         "root": "Newton on g(u(theta)) inside the sign bracket",
                         "max_iterations": int(drv.slot("ST_NEWTON")),
                         "nfev": drv.slot("ST_LOC_NFEV")}
    return _trajectory(problem, method, sec, crossings, t, y, c, status, meta)


def _henon_meta(max_substeps: int, field: str, nfev: float) -> dict:
    return {"integrator": "DOP853, m equal substeps in g", "max_substeps": max_substeps,
            "rtol": HENON_RTOL, "substeps_cap": HENON_MAX_SUBSTEPS, "field": field,
            "nfev": nfev}


def _scanned(problem, method, sec, crossings: int, res: Trajectory) -> Trajectory:
    """External engines and transformed problems: one vectorised scan of the samples, then every
    crossing located by Hénon's trick on the base field in one compiled call."""
    pk = problem_kernel(problem)
    Y = np.ascontiguousarray(res.y, dtype=np.float64)
    T = np.ascontiguousarray(res.t, dtype=np.float64)
    gv = np.empty(len(T))
    if len(T):
        pk.kernel.section_values(Y, pk.par, gv)
    idx = crossing_intervals(gv).astype(np.int64)
    out_t, out_y = np.empty(len(idx)), np.empty((len(idx), problem.record.dim))
    ok, m = np.zeros(len(idx), dtype=np.bool_), np.zeros(len(idx), dtype=np.int64)
    if len(idx):
        pk.kernel.henon_all(T, Y, idx, pk.par, out_t, out_y, ok, m)
    keep = np.nonzero(ok)[0][:crossings]
    after = idx[keep] + 1                       # the sample that ends the step of the crossing
    c = np.column_stack([res.steps[after], res.nfev[after], res.njev[after], res.rejected[after],
                         np.zeros(len(keep))]) if len(keep) else np.zeros((0, 5))
    y = out_y[keep]
    max_g = float(np.max(np.abs(_section_g(pk, y)))) if len(keep) else 0.0
    meta = {"wall_seconds": res.wall_seconds, "compile_seconds": res.compile_seconds,
            "h": res.provenance.get("h"), "nsteps": res.provenance.get("nsteps"),
            "t_last_sample": float(T[-1]) if len(T) else 0.0, "locator": "henon",
            "max_abs_g": max_g, "locator_note": "no dense output: external engine or transformed "
                                                "problem (samples scanned after the run)",
            "henon": _henon_meta(int(m.max()) if len(m) else 0, "base field of the problem",
                                 float("nan"))}
    status = res.status
    traj = _trajectory(problem, method, sec, crossings, out_t[keep], y, c, status, meta)
    if res.reason and status is not Status.OK:
        traj.reason = res.reason
    return traj


def _section_g(pk, Y: np.ndarray) -> np.ndarray:
    out = np.empty(len(Y))
    pk.kernel.section_values(np.ascontiguousarray(Y), pk.par, out)
    return out


def _trajectory(problem, method, sec, crossings, t, y, c, status, meta) -> Trajectory:
    rec = problem.record
    pk = problem_kernel(problem)
    y0 = rec.y0(problem.values)
    rows = len(t)
    reason = ""
    if status is not Status.OK:
        reason = f"the integration stopped ({status}) at t = {meta['t_last_sample']:.17g}"
    elif rows < crossings:
        reason = (f"only {rows} of {crossings} crossings of {sec.name} before "
                  f"t = {meta['t_last_sample']:.17g}; raise {spelled('--t-end')} / {spelled('--steps')}")
    y = np.asarray(y, dtype=float).reshape(rows, rec.dim)
    chart = None
    if sec.chart is not None:
        chart = np.asarray(sec.chart(y), dtype=np.int64) if rows else np.zeros(0, dtype=np.int64)
    meta = {"versions": versions(), "section": sec.name, "section_reference": sec.reference,
            "section_coords": list(sec.coords), "crossings_requested": crossings,
            "crossings_found": rows, **meta, "y0": list(y0), "H0": list(pk.at(y0)),
            "design": "suite/cell/sections.py"}
    return build_trajectory(problem, method, t, y, c, status, reason, meta, kind="section",
                            chart=chart)
