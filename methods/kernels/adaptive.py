"""Adaptive driver (template): Hairer's step-size control as in DOPRI5/DOP853 (HNW I, §II.4).

err = ||h Σ e_j k_j / sk||_rms with sk_i = atol + rtol max(|y_i|, |y1_i|) (DOP853: its combined
3rd/5th-order estimate); accepted if err <= 1. New step h / fac, with
fac = clip(err^EXPO / facold^BETA / SAFE, 1/FAC2, 1/FAC1); after a rejection the next step is not
larger than the rejected one; |h| <= hmax; the last step lands exactly on t_end. The initial step is
Hairer's HINIT heuristic when h0 = 0.

The driver is resumable: its whole state lives in ``y_io`` (y, f(y)) and ``st`` so Python can empty
a full output buffer and call again without changing a single operation (status 5).

Samples: every ``every`` accepted steps plus the final point. The same template is generated in
specialised copies, each flag a literal (``template`` renaming, as for every variant below), so
that the plain driver compiles without the others' code (one driver carrying both the plain and
the dense-output loops took 50 % longer to compile, measured on kepler-3d):

* ``integrate_dense`` (``DENSE_OUTPUT``, pairs with a continuous extension, methods/dense_output.py):
  samples on the grid t_k = k dt_out for k = 0, every, 2 every, ... < ``n_out`` plus the final
  point t_end, filled by dense output as Hairer's SOLOUT does (HNW I §II.6): after each accepted
  step that contains grid points, the step's continuous extension is formed from its stages
  (DOP853: 3 more f-evaluations, counted in nfev; DOPRI5: none) and evaluated there. The steps are
  the same: ``step_stages`` runs the very operations of ``step_err``.
* ``adaptive_grid`` (``GRID``): the same grid by partial steps of the pair itself from y_n
  (``partial_adaptive``; methods/kernels/events.py), for pairs without a continuous extension or
  whose accepted points are not its endpoints (projection, post_step).
* ``adaptive_section`` (``SECTION``) and ``adaptive_section_dense`` (``SECTION_DENSE`` too): a
  Poincaré section crossing in each accepted step is located by Hénon's trick, or on the step's
  continuous extension formed from the stages at hand (no recomputation), and written with the
  counters of its step; the run stops with ``STATUS_OK`` after ``st[ST_WANTED]`` crossings.

A grid point t_k within GRID_ULPS ulps of a step end is that step end. When a step's grid samples
do not fit the output buffer, the step is undone and redone by the next call (same operations).
With ``st[ST_TCOMP]`` = i >= 0 the grid's time is the state component i (the physical time t of a
transformed problem, K-S) instead of the integration variable: located by Newton on the extension
(``dense_root_time``) or by the secant method on the partial step size.
"""
from __future__ import annotations

import math

from gnibench.methods.kernels.free import (
    BETA,
    DENSE_NFEV,
    DENSE_OUTPUT,
    EXPO,
    FAC1,
    FAC2,
    FSAL,
    GRID_ULPS,
    GRIDDED,
    IORD,
    SAFE,
    SECTION,
    SECTION_DENSE,
    ST_FOUND,
    ST_KOUT,
    ST_LOC_NFEV,
    ST_NEWTON,
    ST_ROLLBACKS,
    ST_TCOMP,
    ST_WANTED,
    STAGES_NEW,
    STATUS_BUFFER_FULL,
    STATUS_MAX_STEPS,
    STATUS_OK,
    STATUS_PAUSED,
    STATUS_STEP_TOO_SMALL,
    WITH_STAGES,
    N,
    crosses,
    dense_crossing,
    dense_eval,
    dense_from_stages,
    dense_root_time,
    f,
    grid_sample_adaptive,
    henon_crossing,
    post_step,
    project,
    record_row,
    section_event,
    section_g_0,
    step_err,
    step_stages,
    store,
    to_tuple,
    to_tuple_shift,
)


def initial_step(y, fy, par, hmax, rtol, atol):
    """Hairer's HINIT: a first guess from |y|/|f| and an estimate of the second derivative."""
    dnf = 0.0
    dny = 0.0
    for i in range(N):
        sk = atol + rtol * abs(y[i])
        dnf += (fy[i] / sk) ** 2
        dny += (y[i] / sk) ** 2
    h = 1.0e-6 if (dnf <= 1.0e-10 or dny <= 1.0e-10) else math.sqrt(dny / dnf) * 0.01
    h = min(h, hmax)
    y1 = to_tuple_shift(y, h, fy)
    f1 = f(y1, par)
    der2 = 0.0
    for i in range(N):
        sk = atol + rtol * abs(y[i])
        der2 += ((f1[i] - fy[i]) / sk) ** 2
    der2 = math.sqrt(der2) / h
    der12 = max(abs(der2), math.sqrt(dnf))
    h1 = max(1.0e-6, abs(h) * 1.0e-3) if der12 <= 1.0e-15 else (0.01 / der12) ** (1.0 / IORD)
    return min(100.0 * abs(h), h1, hmax)


def first_step(y, fy, par, h0, hmax, rtol, atol):
    """The first step (h0 if given, capped by hmax, else HINIT) and the f-evaluations so far:
    f(y0), plus HINIT's probe."""
    if h0 > 0.0:
        return min(h0, hmax), 1.0
    return initial_step(y, fy, par, hmax, rtol, atol), 2.0


def dense_coeffs(y, h, par, fy):
    """The accepted step from y of size h (fy = f(y)), recomputed by the operations of step_err
    (so y1 is the driver's, bit for bit), and its continuous extension: (y1, (y0, F0, F1, ...))."""
    y1, _, f1, ks = step_stages(y, h, par, fy, 1.0, 1.0)
    if not FSAL:
        f1 = f(y1, par)
    return y1, dense_from_stages(y, y1, h, par, ks, f1)


def partial_adaptive(y, fy, sigma, par, ws, k):
    """A partial step of an embedded pair: its own step of size sigma from y (fy = f(y)), the error
    estimate unused (time grid without dense output)."""
    y1, _, _ = step_err(y, sigma, par, fy, 1.0, 1.0)
    return y1, STAGES_NEW, 0.0, STATUS_OK


def integrate_adaptive(y_io, st, par, t_end, h0, hmax, rtol, atol, every, dt_out, n_out, max_steps,
                       budget, out_t, out_y, out_c):
    # st: t, h, facold, reject, nacc, nrej, nfev, started, last_row_step; slots of
    # methods/kernels/slots.py (grid: next grid index, time component; sections: crossings found
    # and wanted, statistics). out_c: steps, nfev, njev, rejected and, if it has a 5th column, the
    # size of the accepted step that ends at the sample (tests/test_dense_output.py).
    # dt_out, n_out: the time grid (integrate_dense, adaptive_grid; the others ignore them)
    y = to_tuple(y_io[0])
    rows = out_t.shape[0]
    with_h = out_c.shape[1] > 4
    row = 0
    if st[7] == 0.0:
        fy = f(y, par)
        st[1], st[6] = first_step(y, fy, par, h0, hmax, rtol, atol)
        st[0] = 0.0
        st[2] = 1.0e-4
        st[7] = 1.0
        if not SECTION:                    # a section run writes crossings only
            record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, st[6], 0.0, 0.0)
            if with_h:
                out_c[0, 4] = 0.0
            row = 1
        if GRIDDED:
            st[ST_KOUT] = every
    else:
        fy = to_tuple(y_io[1])
    t, h, facold = st[0], st[1], st[2]
    reject = st[3] != 0.0
    nacc, nrej, nfev = int(st[4]), int(st[5]), st[6]
    kout = int(st[ST_KOUT]) if GRIDDED else 0
    tc = int(st[ST_TCOMP]) if GRIDDED else -1
    g0 = section_g_0(y, par) if SECTION else 0.0
    status = STATUS_OK
    last = False
    stop = nacc + nrej + budget              # attempts in this call (STATUS_PAUSED after them)
    while True:
        if row >= rows or (GRIDDED and rows - row < 2):
            status = STATUS_BUFFER_FULL
            break
        if nacc + nrej >= max_steps:
            status = STATUS_MAX_STEPS
            break
        if nacc + nrej >= stop:
            status = STATUS_PAUSED
            break
        if 0.1 * abs(h) <= abs(t) * 2.220446049250313e-16 or not h > 0.0:
            status = STATUS_STEP_TOO_SMALL
            break
        # the state before this attempt: a gridded step whose samples do not fit is redone
        h_start, facold_start, reject_start, nrej_start, nfev_start = h, facold, reject, nrej, nfev
        if t + 1.01 * h - t_end > 0.0:
            h = t_end - t
            last = True
        if WITH_STAGES:
            y1, err, f1, ks = step_stages(y, h, par, fy, rtol, atol)
        else:
            y1, err, f1 = step_err(y, h, par, fy, rtol, atol)
        nfev += STAGES_NEW
        fac11 = err ** EXPO
        fac = fac11 / facold ** BETA
        fac = max(1.0 / FAC2, min(1.0 / FAC1, fac / SAFE))
        hnew = h / fac
        if err <= 1.0:
            y1, pst = project(y1, par)
            if pst != STATUS_OK:
                status = pst
                break
            facold = max(err, 1.0e-4)
            nacc += 1
            t_old = t
            t = t_end if last else t + h
            y2 = post_step(y1, par)
            fy_old = fy
            if FSAL and y2 == y1:
                fy = f1
            else:
                fy = f(y2, par)
                nfev += 1.0
            y_old = y
            y = y2
            if abs(hnew) > hmax:
                hnew = hmax
            if reject:
                hnew = min(abs(hnew), abs(h))
            reject = False
            if SECTION:
                g1 = section_g_0(y, par)
                if crosses(g0, g1):
                    if SECTION_DENSE:
                        # fy = f(y1): dense output is refused with projection or post_step
                        cf = dense_from_stages(y_old, y1, h, par, ks, fy)
                        nfev += DENSE_NFEV
                        st[ST_LOC_NFEV] += DENSE_NFEV
                        ys, ts, it = dense_crossing(cf, y_old, t_old, g0, y, t, g1, h, par)
                        st[ST_NEWTON] = max(st[ST_NEWTON], it)
                    else:
                        ys, ts, nf = henon_crossing(y_old, t_old, t, par, st)
                        nfev += nf
                    row += section_event(ys, ts, par, st, out_t, out_y, out_c, row, nacc, nfev,
                                         0.0, nrej)
                    if st[ST_FOUND] >= st[ST_WANTED]:
                        h = hnew
                        break
                g0 = g1
            elif GRIDDED:
                # samples at t_k = k dt_out in this step; with tc >= 0 the grid's time is the state
                # component tc (the physical time of a transformed problem)
                t_hi = t if tc < 0 else y[tc]
                tol = GRID_ULPS * 2.220446049250313e-16 * abs(t_hi)
                row_start = row
                kout_start = kout
                full = False
                tk = kout * dt_out
                if kout < n_out and (tk < t_hi - tol or (not last and tk <= t_hi + tol)):
                    if DENSE_OUTPUT:
                        # fy = f(y1): dense output is refused with projection or post_step
                        cf = dense_from_stages(y_old, y1, h, par, ks, fy)
                        nfev += DENSE_NFEV
                    while kout < n_out and (tk < t_hi - tol or (not last and tk <= t_hi + tol)):
                        if row >= rows - 1:
                            full = True
                            break
                        if abs(tk - t_hi) <= tol:
                            yk = y
                            sk = t if tc >= 0 else tk
                        elif DENSE_OUTPUT:
                            if tc < 0:
                                yk = dense_eval(cf, (tk - t_old) / h)
                                sk = tk
                            else:
                                theta, yk, _ = dense_root_time(cf, par, tc, tk, y_old[tc] - tk,
                                                               dense_eval(cf, 1.0)[tc] - tk,
                                                               abs(t_hi - tk), y)
                                sk = t if theta == 1.0 else t_old + theta * h
                        else:
                            yk, sk, nf, _, s = grid_sample_adaptive(y_old, fy_old, t_old, y, t, h,
                                                                    tk, tc, par, 0, 0)
                            nfev += nf
                            if s != STATUS_OK:
                                status = s
                                break
                        record_row(out_t, out_y, out_c, row, sk, yk, nacc, nfev, 0.0, nrej)
                        row += 1
                        kout += every
                        tk = kout * dt_out
                if full:                   # redo this step in the next call, with a new buffer
                    y = y_old
                    fy = fy_old
                    t = t_old
                    h, facold, reject, nrej, nfev = (h_start, facold_start, reject_start,
                                                     nrej_start, nfev_start)
                    nacc -= 1
                    kout = kout_start
                    row = row_start
                    last = False
                    st[ST_ROLLBACKS] += 1.0
                    status = STATUS_BUFFER_FULL
                    break
                if status != STATUS_OK:
                    break
                if last:
                    record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
                    row += 1
                    st[8] = nacc
            elif nacc % every == 0 or last:
                record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
                if with_h:
                    out_c[row, 4] = h
                row += 1
                st[8] = nacc
            if last:
                break
            h = hnew
        else:
            hnew = h / min(1.0 / FAC1, fac11 / SAFE)
            reject = True
            if nacc >= 1:
                nrej += 1
            last = False
            h = hnew
    if not SECTION and status != STATUS_OK and status != STATUS_BUFFER_FULL \
            and status != STATUS_PAUSED and nacc > st[8] and row < rows:
        record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
        if with_h:
            out_c[row, 4] = 0.0                 # not a sample of every step: no step size
        row += 1
    store(y, y_io, 0)
    store(fy, y_io, 1)
    st[0], st[1], st[2] = t, h, facold
    st[3] = 1.0 if reject else 0.0
    st[4], st[5], st[6] = nacc, nrej, nfev
    if GRIDDED:
        st[ST_KOUT] = kout
    return status, row
