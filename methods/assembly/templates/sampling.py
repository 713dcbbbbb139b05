"""What a driver does after an accepted step (templates): its time-grid samples, its crossing.

Both driver loops (templates/fixed.py and templates/adaptive.py) call these once per accepted step
(s0, y0) -> (s1, y1) of size h, after the step modifiers and ``post_step``, so the grid and section
code exists once. The module of each output holds one copy, its flags module constants
(methods/assembly/drivers.py): ``grid_rows`` by partial steps of the method (``grid_sample``) or by
the continuous extension (``DENSE_OUTPUT``); ``section_rows`` by Hénon's trick or on the extension
(``SECTION_DENSE``). The rules are those of :mod:`gnibench.suite.cell.timegrid` and
:mod:`gnibench.suite.cell.sections`.

``e0``, ``es0``: the carried compensations of y0 and s0 under ``sum=compensated``
(methods/summation.py; zero otherwise): samples and crossings inside the step start from
y0 + e0 at s0 + es0. ``ks`` and ``fy1`` (the step's stages and f(y1)) are read by the
dense-output copies only (0 elsewhere).
"""
from __future__ import annotations

from gnibench.methods.assembly.templates.slots import (
    GRID_ULPS,
    STATUS_OK,
    ST_LOC_NFEV,
    ST_NEWTON,
)

EPS = 2.220446049250313e-16


def grid_rows(y0, e0, fy0, s0, es0, y1, s1, h, last, kout, tc, dt_out, n_out, every, par, ws, kc,
              ks, fy1, out_t, out_y, out_c, row, steps, nfev, njev, rejected):
    """The samples at t_k = k dt_out (k = kout, kout + every, ... < n_out) in the step, written from
    ``row`` on with the step's counters: (row, kout, nfev, njev, status, full). t_k is the step's end
    when within GRID_ULPS ulps of it (and t_k = s1 only on the horizon's ``last`` step: the final
    row is the caller's), else located by the extension (``DENSE_OUTPUT``) or by a partial step of
    the method (``grid_sample``; ``ws``, ``kc``: its workspace and, for odex, the lines of the
    accepted step). ``full``: no room for all of them; the caller undoes the step and redoes it in
    the next call (the same operations)."""
    rows = out_t.shape[0]
    t_hi = s1 if tc < 0 else y1[tc]
    tol = GRID_ULPS * EPS * abs(t_hi)
    status = STATUS_OK
    full = False
    tk = kout * dt_out
    if kout < n_out and (tk < t_hi - tol or (not last and tk <= t_hi + tol)):
        if DENSE_OUTPUT:
            # fy1 = f(y1): dense output is refused with projection or post_step
            cf = dense_from_stages(y0, y1, h, par, ks, fy1)
            nfev += DENSE_NFEV
        while kout < n_out and (tk < t_hi - tol or (not last and tk <= t_hi + tol)):
            if row >= rows - 1:
                full = True
                break
            if abs(tk - t_hi) <= tol:
                yk = y1
                sk = s1 if tc >= 0 else tk
            elif DENSE_OUTPUT:
                if tc < 0:
                    if COMPENSATED:
                        yk = carry_apply(dense_eval(cf, ((tk - s0) - es0) / h), e0)
                    else:
                        yk = dense_eval(cf, (tk - s0) / h)
                    sk = tk
                else:
                    theta, yk, _ = dense_root(cf, par, tc, tk, y0[tc] - tk,
                                                   dense_eval(cf, 1.0)[tc] - tk,
                                                   abs(t_hi - tk), y1)
                    if theta == 1.0:
                        sk = s1
                    elif COMPENSATED:
                        yk = carry_apply(yk, e0)
                        sk = s0 + (es0 + theta * h)
                    else:
                        sk = s0 + theta * h
            else:
                yk, sk, nf, nj, s = grid_sample(y0, e0, fy0, s0, es0, y1, s1, h, tk, tc, par, ws,
                                                kc)
                nfev += nf
                njev += nj
                if s != STATUS_OK:
                    status = s
                    break
            record_row(out_t, out_y, out_c, row, sk, yk, steps, nfev, njev, rejected)
            row += 1
            kout += every
            tk = kout * dt_out
    return row, kout, nfev, njev, status, full


def section_rows(y0, e0, s0, es0, g0, y1, s1, g1, h, par, st, ks, fy1, out_t, out_y, out_c, row,
                 steps, nfev, njev, rejected):
    """The crossing of the section in the step (g changed sign from g0 to g1), located on the
    step's continuous extension (``SECTION_DENSE``) or by Hénon's trick from y0 on the flow of the
    cell's field, and written with the step's counters when its direction condition holds:
    (rows written, nfev)."""
    if SECTION_DENSE:
        # fy1 = f(y1): dense output is refused with projection or post_step
        cf = dense_from_stages(y0, y1, h, par, ks, fy1)
        nfev += DENSE_NFEV
        st[ST_LOC_NFEV] += DENSE_NFEV
        ys, ts, it = dense_crossing(cf, y0, s0, g0, y1, s1, g1, h, par)
        st[ST_NEWTON] = max(st[ST_NEWTON], it)
    else:
        ys, ts, nf = henon_crossing(y0, s0, s1, par, st)
        nfev += nf
    if COMPENSATED and ts != s1:
        ys = carry_apply(ys, e0)
        ts = s0 + ((ts - s0) + es0)
    return section_event(ys, ts, par, st, out_t, out_y, out_c, row, steps, nfev, njev,
                         rejected), nfev
