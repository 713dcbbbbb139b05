"""How precisely are the section points located? Each one against the same crossing located
independently ([B] §6.2: "Position of points on the section was determined with precision higher
than 10⁻¹⁵").

Hénon's trick (suite/cell/sections.py, methods/assembly/sections.py) lands on the section {g = 0} by taking g
itself as the independent variable, so g at the located point is zero to round-off whatever the
accuracy of the rest of the point (|p₁| at the G-S points measures nothing). The located point y*
is meant to be where the exact flow of the field the method integrates, started from the accepted
point y_n before the crossing, meets g = 0; the dense-output locator's point lies on the method's
continuous extension instead, within its error. This closed form measures, per crossing, the
distance ‖y* − y_ref‖₂ (the whole state) to an independent location of that crossing:

1. *The accepted points.* The cell is run again with a sample at every accepted step (the same
   compiled driver family without the section flag; the steps do not depend on the locator). The
   re-run must be the run: the run's last crossing (``t_final``) must fall in the re-run's step
   number ``steps`` (the cell's count at that crossing), and every crossing time t* in a step
   (t_n, t_n+1] whose ends g brackets; otherwise ValueError (the verdict is ``error``).
2. *The independent crossing.* From (t_n, y_n) (doubles, exact in the wider type), heyoka's Taylor
   method (Biscani & Izzo 2021) in 80-bit extended precision (long double, ε = 1.1e-19, tol = ε,
   compensated summation) integrates the problem's base field to its terminal event g = 0, which
   heyoka locates as a root of the Taylor polynomial of g within the step, to the working
   precision; y_ref is heyoka's state there. Over one step (≲ 1 time unit) its own error is
   ≲ 1e-18, a thousand times below the thresholds of [B] §6.2 (claim B-6.2-q): a distance above
   them is the locator's. Hence only compiled cells of the base field (no +observer/+penalty, no
   identification map): ValueError otherwise.

Values: ``loc_max`` (the largest distance), ``loc_near`` (the largest over the points with
‖y*‖ < 10⁻², near the equilibrium x₀ = 0 of [B] §6.2; 0 when there are none), ``loc_median``,
``dt_max`` (the largest |t* − t_ref|, for comparison only: a crossing time is a sum of steps, so
its round-off grows with t), ``crossings`` and ``near_points``; with several cells each is also
named ``<value>_<label>`` as in closed_forms_b6.py.
"""
from __future__ import annotations

import numpy as np

NEAR = 1e-2                    # ‖y*‖ below this: near the equilibrium x₀ = 0 of [B] §6.2


def _event_integrator(bound):
    """heyoka's long double Taylor integrator of the base field with the terminal event g = 0
    (section 0 of the problem), built from the problem's sympy model."""
    from types import SimpleNamespace

    import heyoka as hy
    import sympy as sp
    from gnibench.methods.engines.heyoka import heyoka_system
    from gnibench.problems.codegen import symbolic

    rec = bound.record
    fp = np.longdouble
    system = heyoka_system(rec)
    ys, ps, _, _ = symbolic(rec)
    ns = SimpleNamespace(**dict(zip(rec.state, ys)), **dict(zip(rec.model_params, ps)))
    names = {y: x for y, x in zip(ys, system.variables)}
    names.update({c: hy.par[i] for i, c in enumerate(ps)})
    g = hy.from_sympy(sp.sympify(rec.sections[0].g(ns)), names)
    pars = [fp(float(x)) for x in rec.par(bound.values)] + [fp(c) for c in system.constants]
    return hy.taylor_adaptive(system.equations, [fp(0)] * rec.dim, fp_type=fp,
                              tol=fp(np.finfo(fp).eps), pars=pars[:system.n_pars],
                              high_accuracy=True, t_events=[hy.t_event(g, fp_type=fp)])


def accepted_points(row, problem, method, t_star: np.ndarray):
    """(t_n, y_n, t_n+1) of the accepted step holding each crossing time, from a re-run of the cell
    with a sample at every step, checked to be the run (module docstring, 1)."""
    from gnibench.suite.cell.compiled import problem_kernel
    from gnibench.suite.cell.solve import solve

    if np.isfinite(row.t_end):
        traj = solve(problem, method, t_end=float(row.t_end), reference="none")
    else:
        traj = solve(problem, method, steps=int(row.steps_planned), reference="none")
    T, Y = traj.t, np.ascontiguousarray(traj.y, dtype=np.float64)
    if not len(t_star):
        return T[:0], Y[:0], T[:0]
    k = np.searchsorted(T, t_star, side="left")
    last = int(np.searchsorted(T, float(row.t_final), side="left"))
    if last != int(row.steps) or np.any(k < 1) or np.any(k >= len(T)):
        raise ValueError(f"the re-run of cell {row.cell} is not its run: the last crossing "
                         f"(t = {row.t_final!r}, step {row.steps}) falls in its step {last}")
    g = np.empty(len(T))
    pk = problem_kernel(problem)
    pk.kernel.section_values(Y, pk.par, g)
    a, b = g[k - 1], g[k]
    bracket = ((a > 0) & (b <= 0)) | ((a < 0) & (b >= 0))
    if not bracket.all():
        bad = int(np.argmin(bracket))
        raise ValueError(f"the re-run of cell {row.cell}: g does not change sign over the step "
                         f"({T[k[bad] - 1]!r}, {T[k[bad]]!r}] of crossing {bad + 1}")
    return T[k - 1], Y[k - 1], T[k]


def locate_independently(problem, t0: np.ndarray, y0: np.ndarray, t1: np.ndarray):
    """(t_ref, y_ref) in long double: the first zero of g on the exact flow from each (t_n, y_n),
    searched up to t_n + 2 (t_n+1 − t_n) (module docstring, 2)."""
    fp = np.longdouble
    ta = _event_integrator(problem)
    t_ref = np.empty(len(t0), dtype=fp)
    y_ref = np.empty((len(t0), problem.record.dim), dtype=fp)
    for j in range(len(t0)):
        ta.time = fp(t0[j])
        ta.state[:] = np.asarray(y0[j], dtype=fp)
        ta.reset_cooldowns()
        outcome = ta.propagate_until(fp(t0[j]) + 2 * (fp(t1[j]) - fp(t0[j])))[0]
        if int(outcome) != -1:
            raise ValueError(f"no crossing of the exact flow from t = {t0[j]!r} within two "
                             f"steps ({outcome})")
        t_ref[j], y_ref[j] = ta.time, ta.state
    return t_ref, y_ref


def cell_precision(row, samples) -> dict:
    """The values of the module docstring for one cell."""
    from gnibench.suite.cell.spec import prepare

    problem, method = prepare(row.problem, row.method)
    rec = problem.record
    if (method.kind != "compiled" or method.modifiers or getattr(rec, "post_step", None) is not None
            or rec.transformed(problem.values) is not None):
        raise ValueError(f"{row.method} on {row.problem}: the independent location integrates the "
                         f"base field, for compiled methods without modifiers only")
    rows = samples[samples["cell"] == row.cell]
    state = list(rec.state)
    t_star = rows["t"].to_numpy(float)
    y_star = rows[state].to_numpy(float)
    t0, y0, t1 = accepted_points(row, problem, method, t_star)
    t_ref, y_ref = locate_independently(problem, t0, y0, t1)
    dist = np.sqrt(np.sum((y_star.astype(np.longdouble) - y_ref) ** 2, axis=1)).astype(float)
    near = np.linalg.norm(y_star, axis=1) < NEAR
    return {"loc_max": float(dist.max()) if len(dist) else np.nan,
            "loc_near": float(dist[near].max()) if near.any() else 0.0,
            "loc_median": float(np.median(dist)) if len(dist) else np.nan,
            "dt_max": float(np.max(np.abs(t_star - t_ref))) if len(dist) else np.nan,
            "crossings": float(len(dist)), "near_points": float(near.sum())}


def section_locator_precision(cells, samples) -> dict:
    """The values of the module docstring for every selected cell."""
    from gnibench.suite.ledger.closed_forms_b6 import per_cell

    return per_cell(cells, lambda row: cell_precision(row, samples))


CLOSED_FORMS = {"section_locator_precision": section_locator_precision}
