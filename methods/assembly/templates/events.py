"""Events inside the compiled drivers (templates): section crossings and time-grid samples.

The drivers (templates/fixed.py and templates/adaptive.py) call these after each
accepted step (t_n, y_n) -> (t_n+1, y_n+1), after projection and ``post_step``; nothing here
allocates, and every state is a tuple. The specification of the locators is the docstring of
:mod:`gnibench.suite.cell.sections`; of the time grid, :mod:`gnibench.suite.cell.timegrid`.

* **Section crossings.** A crossing of {g = 0} lies in (t_n, t_n+1] when g changes sign there with
  the half-open rule of :func:`crosses`. It is located by Hénon's trick (:func:`henon_locate`,
  Hénon 1982, Physica D 5, with the unrolled DOP853 substeps written by methods/assembly/sections.py) or,
  for the adaptive pairs with a continuous extension, on the extension of the step itself
  (:func:`dense_crossing`, HNW I §II.6), and written by :func:`section_event` when the direction
  condition holds at the located point.
* **Time-grid samples.** The state at t_k in (t_n, t_n+1]: the step end when t_k coincides with it
  to GRID_ULPS ulps, else a partial step of the method itself from y_n (``partial_step``, bound
  per driver kind and family: methods/assembly/bindings.py) with the step modifiers and ``post_step``
  applied as to every step (:func:`grid_sample`). When the grid's time is a state component (K-S:
  the physical time t of the system in fictitious time s), the partial step size sigma is found by
  the secant method, safeguarded inside its bracket, so that that component equals t_k.
"""
from __future__ import annotations

import math

from gnibench.methods.assembly.templates.slots import (
    GRID_ULPS,
    STATUS_OK,
    ST_FOUND,
    ST_HENON_FAILED,
    ST_LOC_NFEV,
    ST_MAX_G,
    ST_SUBSTEPS,
    ST_WALKS,
)

EPS = 2.220446049250313e-16
DENSE_MAXIT = 60            # Newton (or bisection) iterations on a continuous extension
SECANT_MAXIT = 60           # secant (or bisection) iterations on a partial step size


def crosses(g0, g1):
    """A crossing in (t_n, t_n+1]: a sample exactly on the section belongs to the interval that
    ends there, so the initial point (often on the section) never counts."""
    return (g0 > 0.0 and g1 <= 0.0) or (g0 < 0.0 and g1 >= 0.0)


def section_event(ys, ts, par, st, out_t, out_y, out_c, row, steps, nfev, njev, rejected):
    """Write the located crossing (ts, ys) with the counters of its step when the direction
    condition holds there; return the number of rows written (0 or 1)."""
    wrote = 0
    if section_cond_0(ys, par) > 0.0:
        record_row(out_t, out_y, out_c, row, ts, ys, steps, nfev, njev, rejected)
        st[ST_FOUND] += 1.0
        st[ST_MAX_G] = max(st[ST_MAX_G], abs(section_g_0(ys, par)))
        wrote = 1
    return wrote


def henon_crossing(y, t, t_next, par, st):
    """Hénon's trick from the accepted point (t, y) before the crossing (the step ends at
    t_next); keeps the statistics."""
    ys, ts, m, nf, walked = henon_locate(y, t, t_next, par)
    st[ST_SUBSTEPS] = max(st[ST_SUBSTEPS], m)
    st[ST_LOC_NFEV] += nf
    if walked == 1:
        st[ST_WALKS] += 1.0
    elif walked == 2:
        st[ST_HENON_FAILED] += 1.0
    return ys, ts, nf


def henon_converge(z0, d, par, in_time):
    """(y, t) carried over d in g (Hénon's system) or in time (``in_time``) by DOP853 with
    m = 2, 4, ... equal substeps until two successive results agree to HENON_RTOL
    (|z_2m - z_m| <= HENON_RTOL max(1, |z_2m|)), at most HENON_MAX_SUBSTEPS: (z, m, nfev).

    Every call of the runs is in the loop, with m computed: a literal m = 2 at a call of its own
    made numba compile each run twice (for ``Literal[int](2)`` and for int64)."""
    m = 1
    prev = z0
    nfev = 0.0
    while m < HENON_MAX_SUBSTEPS:
        m *= 2
        cur = flow_run(z0, d, m, par) if in_time else henon_run(z0, d, m, par)
        nfev += HENON_STAGES * m
        if m > 2:
            agree = True
            for i in range(N + 1):
                if not abs(cur[i] - prev[i]) <= HENON_RTOL * max(1.0, abs(cur[i])):
                    agree = False
                    break
            if agree:
                return cur, m, nfev
        prev = cur
    return prev, m, nfev


def henon_locate(y, t, t_next, par):
    """The crossing on the exact flow through (t, y), the accepted point before a sign change of
    g in (t, t_next]: (y*, t*, m, nfev, walked).

    Hénon's trick integrates in g from g(y) to 0, which is valid while g moves monotonically
    toward the section, i.e. when dt/dg = 1 / (grad g . F) has the sign of Δg = -g(y) along the
    way. When the step holds a turning point of g before the crossing (large steps, nearly
    tangent crossings), it is not valid from y (it runs backward in time, to an earlier crossing):
    then (choice) the same flow is first carried in time, in J equal parts of the step (J = 16,
    64, 256; each part by DOP853 with the same doubling rule), to the last point before g changes
    sign, and Hénon's trick is applied from there (walked = 1). The point stays on the exact flow
    through y. Should that fail too, the direct result is returned (walked = 2)."""
    z0 = henon_join(y, t)
    dg = -section_g_0(y, par)
    if dg == 0.0:
        return y, t, 0, 0.0, 0
    h = t_next - t
    nfev = 0.0
    if henon_slope(y, par) * dg > 0.0:
        z, m, nf = henon_converge(z0, dg, par, False)
        nfev += nf
        if m < HENON_MAX_SUBSTEPS and t < z[N] <= t + 2.0 * h:
            return henon_state(z), z[N], m, nfev, 0
    parts = 16
    while parts <= HENON_WALK_MAX:
        zw = z0
        for _ in range(2 * parts):                     # at most two step lengths ahead
            zn, mw, nf = henon_converge(zw, h / parts, par, True)
            nfev += nf
            gn = section_g_0(henon_state(zn), par)
            if (dg < 0.0 and gn <= 0.0) or (dg > 0.0 and gn >= 0.0):
                yw = henon_state(zw)
                dgw = -section_g_0(yw, par)
                if henon_slope(yw, par) * dgw > 0.0:
                    zz, mz, nf = henon_converge(zw, dgw, par, False)
                    nfev += nf
                    if mz < HENON_MAX_SUBSTEPS and zw[N] < zz[N] <= 2.0 * zn[N] - zw[N]:
                        return henon_state(zz), zz[N], max(mz, mw), nfev, 1
                break
            zw = zn
        parts *= 4
    z, m, nf = henon_converge(z0, dg, par, False)
    return henon_state(z), z[N], m, nfev + nf, 2


def dense_root(cf, par, tc, tk, g_lo, g_hi, best_g, best_u):
    """θ in (0, 1] with root_value(u(θ)) = 0 on the continuous extension u (coefficients ``cf``;
    ``root_value``/``root_slope``: the grid time or the section's g, bound per output):
    Newton with du/dθ from the same extension, kept inside the sign bracket [lo, hi] (bisection
    when a Newton step leaves it), until the step no longer changes θ. Returns the iterate of
    smallest |value| (θ = 1 with ``best_u`` if none beats ``best_g``) and the iterations."""
    lo = 0.0
    hi = 1.0
    best_theta = 1.0
    theta = lo - g_lo * (hi - lo) / (g_hi - g_lo)
    it = 0
    while it < DENSE_MAXIT:
        it += 1
        u = dense_eval(cf, theta)
        gu = root_value(u, par, tc, tk)
        if abs(gu) < best_g:
            best_g = abs(gu)
            best_theta = theta
            best_u = u
        if gu == 0.0:
            break
        if (gu > 0.0) == (g_lo > 0.0):
            lo = theta
            g_lo = gu
        else:
            hi = theta
            g_hi = gu
        slope = root_slope(u, dense_slope(cf, theta), par, tc)
        new = theta - gu / slope if slope != 0.0 else math.nan
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)            # Newton left the bracket: bisect
        if new == theta or hi - lo <= 2.3e-16 * hi:
            break
        theta = new
    return best_theta, best_u, it


def dense_crossing(cf, y0, t0, g0, y1, t1, g1, h, par):
    """The crossing of {g = 0} by the continuous extension of the accepted step (t0, y0) -> (t1, y1)
    of size h: (point, time, Newton iterations). u(0) = y0 exactly; u(1) and y1 may differ by
    round-off, so a crossing whose sign change only y1 shows is y1 itself."""
    if g1 == 0.0:
        return y1, t1, 0
    g_hi = section_g_0(dense_eval(cf, 1.0), par)
    if g0 * g_hi > 0.0:
        return y1, t1, 0
    theta, u, it = dense_root(cf, par, -1, 0.0, g0, g_hi, abs(g1), y1)
    if theta == 1.0:
        return y1, t1, it
    return u, t0 + theta * h, it


def partial_sample(y0, e0, fy0, sigma, par, ws, k):
    """A partial step of size sigma from y0 (+ its carried compensation e0 under sum=compensated;
    the method's own step, then the step modifiers and the problem's identification map, as for
    every step): (y, nfev, njev, status)."""
    y, nf, nj, s = partial_step(y0, e0, fy0, sigma, par, ws, k)
    if s != STATUS_OK:
        return y, nf, nj, s
    y, s = project(y, par)
    return post_step(y, par), nf, nj, s


def grid_sample(y0, e0, fy0, s0, es0, y1, s1, h, tk, tc, par, ws, k):
    """The sample at grid time tk inside the accepted step (s0, y0) -> (s1, y1) of size h:
    (y, s, nfev, njev, status). tc < 0: the grid's time is the integration variable itself, and s
    is tk; else it is the state component tc (increasing along the step) and s is the integration
    variable at the sample. e0, es0: the carried compensations of y0 and s0 (sum=compensated; 0
    otherwise), so the partial step of size (tk - s0) - es0 starts from y0 + e0."""
    t1 = s1 if tc < 0 else y1[tc]
    if abs(tk - t1) <= GRID_ULPS * EPS * abs(t1):
        return y1, s1 if tc >= 0 else tk, 0.0, 0.0, STATUS_OK
    if tc < 0:
        y, nf, nj, s = partial_sample(y0, e0, fy0, (tk - s0) - es0, par, ws, k)
        return y, tk, nf, nj, s
    # secant on sigma for component tc, inside the bracket [0, h] where it goes from < tk to >= tk
    lo = 0.0
    r_lo = y0[tc] - tk
    hi = h
    r_hi = t1 - tk
    sig_prev = hi
    r_prev = r_hi
    sigma = lo - r_lo * (hi - lo) / (r_hi - r_lo)
    best_r = abs(r_hi)
    best_y = y1
    best_sigma = h
    nfev = 0.0
    njev = 0.0
    it = 0
    while it < SECANT_MAXIT:
        it += 1
        y, nf, nj, s = partial_sample(y0, e0, fy0, sigma, par, ws, k)
        nfev += nf
        njev += nj
        if s != STATUS_OK:
            return y, s0 + sigma, nfev, njev, s
        r = y[tc] - tk
        if abs(r) < best_r:
            best_r = abs(r)
            best_y = y
            best_sigma = sigma
        if abs(r) <= EPS * abs(tk):
            break
        if r < 0.0:
            lo = sigma
        else:
            hi = sigma
        new = sigma - r * (sigma - sig_prev) / (r - r_prev) if r != r_prev else math.nan
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)            # the secant left the bracket: bisect
        if new == sigma or hi - lo <= 2.3e-16 * hi:
            break
        sig_prev = sigma
        r_prev = r
        sigma = new
    return best_y, s1 if best_sigma == h else s0 + best_sigma, nfev, njev, STATUS_OK
