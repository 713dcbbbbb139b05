"""Adaptive driver (template): Hairer's step-size control as in DOPRI5/DOP853 (HNW I, §II.4).

err = ||h Σ e_j k_j / sk||_rms with sk_i = atol + rtol max(|y_i|, |y1_i|) (DOP853: its combined
3rd/5th-order estimate); accepted if err <= 1. New step h / fac, with
fac = clip(err^EXPO / facold^BETA / SAFE, 1/FAC2, 1/FAC1); after a rejection the next step is not
larger than the rejected one; |h| <= hmax; the last step lands exactly on t_end. The initial step is
Hairer's HINIT heuristic when h0 = 0.

The driver is resumable: its whole state lives in ``y_io`` (y, f(y)) and ``st`` so Python can empty
a full output buffer and call again without changing a single operation (status 5).

Samples: every ``every`` accepted steps plus the final point. For pairs with a continuous extension
(methods/dense_output.py) the same template is also generated with ``DENSE_OUTPUT`` = True as
``integrate_dense``: its samples are the grid t_k = k dt_out for k = 0, every, 2 every, ... <
``n_out`` plus the final point t_end, filled by dense output as Hairer's SOLOUT does: after each
accepted step that contains grid points, the step's continuous extension is formed (DOP853: 3 more
f-evaluations, counted in nfev; DOPRI5: none) and evaluated there. The steps themselves are the
same: ``step_stages`` runs the very operations of ``step_err``. (``DENSE_OUTPUT`` is a literal in
each generated copy, so the plain driver compiles without the dense-output code: one driver
carrying both took 50 % longer to compile, measured on kepler-3d.)
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
    IORD,
    SAFE,
    STAGES_NEW,
    STATUS_BUFFER_FULL,
    STATUS_MAX_STEPS,
    STATUS_OK,
    STATUS_PAUSED,
    STATUS_STEP_TOO_SMALL,
    N,
    dense_eval,
    dense_from_stages,
    f,
    post_step,
    project,
    record_row,
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


def integrate_adaptive(y_io, st, par, t_end, h0, hmax, rtol, atol, every, dt_out, n_out, max_steps,
                       budget, out_t, out_y, out_c):
    # st: t, h, facold, reject, nacc, nrej, nfev, started, last_row_step, next grid index (dense)
    # out_c: steps, nfev, njev, rejected and, if it has a 5th column, the size of the accepted step
    # that ends at the sample (Poincaré sections recompute that step: suite/sections.py)
    # dt_out, n_out: the dense-output grid (integrate_dense only; integrate_adaptive ignores them)
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
        record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, st[6], 0.0, 0.0)
        if with_h:
            out_c[0, 4] = 0.0
        row = 1
        if DENSE_OUTPUT:
            st[9] = every
    else:
        fy = to_tuple(y_io[1])
    t, h, facold = st[0], st[1], st[2]
    reject = st[3] != 0.0
    nacc, nrej, nfev = int(st[4]), int(st[5]), st[6]
    kout = int(st[9]) if DENSE_OUTPUT else 0
    status = STATUS_OK
    last = False
    stop = nacc + nrej + budget              # attempts in this call (STATUS_PAUSED after them)
    while True:
        if row >= rows:
            status = STATUS_BUFFER_FULL
            break
        # room for every grid point the next step may contain, and the final point
        if DENSE_OUTPUT and rows - row < 2.0 + max(0.0, min((n_out - kout) / every,
                                                             1.01 * h / (dt_out * every))):
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
        if t + 1.01 * h - t_end > 0.0:
            h = t_end - t
            last = True
        if DENSE_OUTPUT:
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
            if DENSE_OUTPUT:
                if kout < n_out and kout * dt_out <= t:
                    # fy = f(y1): dense output is refused with projection or post_step
                    cf = dense_from_stages(y_old, y1, h, par, ks, fy)
                    nfev += DENSE_NFEV
                    while kout < n_out and kout * dt_out <= t:
                        tk = kout * dt_out
                        record_row(out_t, out_y, out_c, row, tk, dense_eval(cf, (tk - t_old) / h),
                                   nacc, nfev, 0.0, nrej)
                        row += 1
                        kout += every
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
    if status != STATUS_OK and status != STATUS_BUFFER_FULL and status != STATUS_PAUSED \
            and nacc > st[8] and row < rows:
        record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
        if with_h:
            out_c[row, 4] = 0.0                 # not a sample of every step: no step size
        row += 1
    store(y, y_io, 0)
    store(fy, y_io, 1)
    st[0], st[1], st[2] = t, h, facold
    st[3] = 1.0 if reject else 0.0
    st[4], st[5], st[6] = nacc, nrej, nfev
    if DENSE_OUTPUT:
        st[9] = kout
    return status, row
