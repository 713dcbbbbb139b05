"""GBS extrapolation kernels (templates): Gragg's midpoint rule, Aitken-Neville, ODEX's control.

Layout of the tableau ``T`` (a KMAX x N array made once per run), as in ODEX: after column j has
been added, ``T[0]`` holds the most extrapolated value T_jj and ``T[1]`` the subdiagonal T_j,j-1
(both as increments over y, see ``gragg_column``),
whose difference is the error estimate (HNW I, §II.9, (9.22)-(9.23)). Columns are numbered from 1
as in HNW; the arrays are indexed by ``j - 1``.

The adaptive driver follows ODEX's ODXCOR with its default constants (HNW I, §II.9 "Order and step
size control"): convergence monitor in line k-1, hope for convergence in line k+1, order and step
chosen by the work per unit step W_j = A_j / H_j. It is resumable like methods/kernels/adaptive.py:
its state lives in ``y_io`` (y, f(y)) and ``st`` (t, h, k, reject, nacc, nrej, nfev, started,
last_row_step). The per-step arrays (T, H_j, W_j) are rebuilt within each step, so nothing else
has to survive between calls.
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.methods.kernels.free import (
    GRID,
    GRID_ULPS,
    SECTION,
    ST_FOUND,
    ST_KOUT,
    ST_ROLLBACKS,
    ST_TCOMP,
    ST_WANTED,
    STATUS_BUFFER_FULL,
    STATUS_MAX_STEPS,
    STATUS_OK,
    STATUS_PAUSED,
    STATUS_STEP_TOO_SMALL,
    N,
    crosses,
    f,
    grid_sample_adaptive,
    henon_crossing,
    post_step,
    project,
    record_row,
    section_event,
    section_g_0,
    store,
    to_tuple,
    to_tuple_shift,
)

# bound in each generated module (methods/extrapolation.py writes them)
NJ = WORK_A = ()
KMAX = K_FIXED = MSTAB = JSTAB = 0
SAFE1 = SAFE2 = SAFE3 = FAC1 = FAC2 = FAC3 = FAC4 = UROUND = 0.0


def _unbound(*args):  # pragma: no cover - only reached if a template is called un-generated
    raise RuntimeError("kernel template called outside a generated module")


first_step = scaled = _unbound        # adaptive.first_step; scaled(a, v) -> a v as a tuple


def gragg_column(y, fy, h, nj, par, T, row, check, rtol, atol):
    """Gragg's midpoint rule with nj substeps plus the smoothing step (HNW (9.13)).

    Written for the increments z_m = y_m - y (identical in exact arithmetic): rounding then acts
    on the small increments instead of on y, and is not amplified by the extrapolation weights
    (sum |c_j| = 26 for 6 lines, 256 for 9). T[row] receives the increment T_j1 - y.

    Returns the number of f evaluations, negated when ODEX's stability check fails: the first
    substep's f must not differ from f(y) by more than twice |f(y)| in the scaled norm (MSTAB,
    JSTAB). The scale is atol + rtol |y| (ODEX keeps the previous column's scale; this one is
    rebuilt from y so a resumed run repeats every operation).
    """
    hj = h / nj
    z_prev = scaled(0.0, fy)
    z_mid = scaled(hj, fy)                             # explicit Euler start
    for m in range(1, nj):
        dy = f(to_tuple_shift(y, 1.0, z_mid), par)
        z_next = to_tuple_shift(z_prev, 2.0 * hj, dy)
        z_prev = z_mid
        z_mid = z_next
        if check and m <= MSTAB:
            del1 = 0.0
            del2 = 0.0
            for i in range(N):
                sk = atol + rtol * abs(y[i])
                del1 += (fy[i] / sk) ** 2
                del2 += ((dy[i] - fy[i]) / sk) ** 2
            if del2 / max(UROUND, del1) > 4.0:
                return -m
    dy = f(to_tuple_shift(y, 1.0, z_mid), par)        # smoothing step
    for i in range(N):
        T[row, i] = 0.5 * (z_prev[i] + z_mid[i] + hj * dy[i])
    return nj


def neville(T, j):
    """Add row j (raw value in T[j-1]) to the Aitken-Neville tableau in place (HNW (9.10))."""
    nj = NJ[j - 1]
    for l in range(j - 1, 0, -1):
        ratio = nj / NJ[l - 1]
        fac = ratio * ratio - 1.0
        for i in range(N):
            T[l - 1, i] = T[l, i] + (T[l, i] - T[l - 1, i]) / fac


def make_ws():
    return np.empty((K_FIXED, N))


def step(y, h, par, ws):
    """Fixed step of order 2 K_FIXED: T_KK of the harmonic sequence (HNW Theorem II.9.1)."""
    fy = f(y, par)
    nfev = 1.0
    for j in range(1, K_FIXED + 1):
        nfev += gragg_column(y, fy, h, NJ[j - 1], par, ws, j - 1, False, 0.0, 0.0)
        neville(ws, j)
    return to_tuple_shift(y, 1.0, to_tuple(ws[0])), nfev, 0.0, STATUS_OK


def partial_adaptive(y, fy, sigma, par, T, kc):
    """odex's own step of size sigma with the kc lines of the accepted step (T_kc,kc, order 2 kc;
    the tableau T is scratch between steps): a partial step for the time grid."""
    nfev = 0.0
    for j in range(1, kc + 1):
        nfev += gragg_column(y, fy, sigma, NJ[j - 1], par, T, j - 1, False, 0.0, 0.0)
        neville(T, j)
    return to_tuple_shift(y, 1.0, to_tuple(T[0])), nfev, 0.0, STATUS_OK


def column(j, y, fy, h, hmax, par, T, hh, w, rtol, atol, errold):
    """ODEX's MIDEX: line j of the tableau, its error and optimal step H_j and work W_j.

    Returns (err, errold, nfev, atov); atov (the step must be redone with h * SAFE3) on a failed
    stability check, a non-finite or huge error, or an error that grows from line to line.
    """
    nf = gragg_column(y, fy, h, NJ[j - 1], par, T, j - 1, j <= JSTAB, rtol, atol)
    if nf < 0:
        return 0.0, errold, float(-nf), True
    neville(T, j)
    if j == 1:
        return 0.0, errold, float(nf), False
    acc = 0.0
    for i in range(N):
        sk = atol + rtol * max(abs(y[i]), abs(y[i] + T[0, i]))
        acc += ((T[0, i] - T[1, i]) / sk) ** 2
    err = math.sqrt(acc / N)
    if not err * UROUND < 1.0 or (j > 2 and err >= errold):
        return err, errold, float(nf), True
    errold = max(4.0 * err, 1.0)
    expo = 1.0 / (2 * j - 1)
    facmin = FAC1 ** expo
    fac = min(FAC2 / facmin, max(facmin, (err / SAFE1) ** expo / SAFE2))
    hh[j - 1] = min(h / fac, hmax)
    w[j - 1] = WORK_A[j - 1] / hh[j - 1]
    return err, errold, float(nf), False


def integrate_adaptive(y_io, st, par, t_end, h0, hmax, rtol, atol, every, dt_out, n_out, max_steps,
                       budget, out_t, out_y, out_c):
    # dt_out, n_out: the dense-output grid of the embedded pairs' driver; odex has no dense output
    # here (its ``dt_out`` is always 0), the arguments keep one signature for every adaptive driver
    T = np.empty((KMAX, N))
    hh = np.zeros(KMAX)
    w = np.zeros(KMAX)
    y = to_tuple(y_io[0])
    rows = out_t.shape[0]
    row = 0
    if st[7] == 0.0:
        fy = f(y, par)
        st[1], st[6] = first_step(y, fy, par, h0, hmax, rtol, atol)
        if h0 <= 0.0:
            st[1] = min(st[1], 0.5 * t_end)
        st[0] = 0.0
        st[2] = max(2, min(KMAX - 1, int(-math.log10(rtol + 1.0e-40) * 0.6 + 1.5)))
        st[3] = 0.0
        st[7] = 1.0
        if not SECTION:                    # a section run writes crossings only
            record_row(out_t, out_y, out_c, 0, 0.0, y, 0.0, st[6], 0.0, 0.0)
            row = 1
        if GRID:
            st[ST_KOUT] = every
    else:
        fy = to_tuple(y_io[1])
    t, h, k = st[0], st[1], int(st[2])
    reject = st[3] != 0.0
    nacc, nrej, nfev = int(st[4]), int(st[5]), st[6]
    kout = int(st[ST_KOUT]) if GRID else 0
    tc = int(st[ST_TCOMP]) if GRID else -1
    g0 = section_g_0(y, par) if SECTION else 0.0
    status = STATUS_OK
    stop = nacc + nrej + budget              # attempts in this call (STATUS_PAUSED after them)
    while True:
        if row >= rows or (GRID and rows - row < 2):
            status = STATUS_BUFFER_FULL
            break
        if nacc + nrej >= max_steps:
            status = STATUS_MAX_STEPS
            break
        if nacc + nrej >= stop:
            status = STATUS_PAUSED
            break
        # the state before this attempt: a gridded step whose samples do not fit is redone
        h_start, k_start, reject_start, nrej_start, nfev_start = h, k, reject, nrej, nfev
        h = min(h, hmax)
        if 0.1 * abs(h) <= abs(t) * 2.220446049250313e-16 or not h > 0.0:
            status = STATUS_STEP_TOO_SMALL
            break
        last = False
        if t + 1.01 * h - t_end > 0.0:
            h = t_end - t
            last = True
        # one attempt; go: 55 hope for line k+1, 60 accept, 100 reject, 10 ATOV (h * SAFE3)
        go = 0
        kc = 0
        err = 0.0
        errold = 1.0e10
        if nacc + nrej == 0 or last:               # first and last step: lines 1..k
            for j in range(1, k + 1):
                kc = j
                err, errold, nf, atov = column(j, y, fy, h, hmax, par, T, hh, w, rtol, atol,
                                               errold)
                nfev += nf
                if atov:
                    go = 10
                    break
                if j > 1 and err <= 1.0:
                    go = 60
                    break
            if go == 0:
                go = 55
        else:                                      # basic step: lines 1..k-1, then monitor
            kc = k - 1
            for j in range(1, kc + 1):
                err, errold, nf, atov = column(j, y, fy, h, hmax, par, T, hh, w, rtol, atol,
                                               errold)
                nfev += nf
                if atov:
                    go = 10
                    break
            if go == 0 and not (k == 2 or reject):   # convergence monitor in line k-1
                if err <= 1.0:
                    go = 60
                elif err > (NJ[k] * NJ[k - 1] / 4.0) ** 2:
                    go = 100
            if go == 0:
                err, errold, nf, atov = column(k, y, fy, h, hmax, par, T, hh, w, rtol, atol,
                                               errold)
                nfev += nf
                kc = k
                if atov:
                    go = 10
                elif err <= 1.0:
                    go = 60
                else:
                    go = 55
        if go == 55:                               # hope for convergence in line k+1
            if err > (NJ[k] / 2.0) ** 2:
                go = 100
            else:
                kc = k + 1
                err, errold, nf, atov = column(kc, y, fy, h, hmax, par, T, hh, w, rtol, atol,
                                               errold)
                nfev += nf
                if atov:
                    go = 10
                elif err > 1.0:
                    go = 100
                else:
                    go = 60
        if go == 10:
            h *= SAFE3
            reject = True
            nrej += 1
            continue
        if go == 100:
            k = min(k, kc, KMAX - 1)
            if k > 2 and w[k - 2] < w[k - 1] * FAC3:
                k -= 1
            nrej += 1
            h = hh[k - 1]
            reject = True
            continue
        # accepted
        y1, pst = project(to_tuple_shift(y, 1.0, to_tuple(T[0])), par)
        if pst != STATUS_OK:
            status = pst
            break
        nacc += 1
        t_old = t
        h_acc = h
        t = t_end if last else t + h
        y_old = y
        fy_old = fy
        y = post_step(y1, par)
        fy = f(y, par)
        nfev += 1.0
        if kc == 2:                                # optimal order by work per unit step
            kopt = min(3, KMAX - 1)
            if reject:
                kopt = 2
        elif kc <= k:
            kopt = kc
            if w[kc - 2] < w[kc - 1] * FAC3:
                kopt = kc - 1
            if w[kc - 1] < w[kc - 2] * FAC4:
                kopt = min(kc + 1, KMAX - 1)
        else:
            kopt = kc - 1
            if kc > 3 and w[kc - 3] < w[kc - 2] * FAC3:
                kopt = kc - 2
            if w[kc - 1] < w[kopt - 1] * FAC4:
                kopt = min(kc, KMAX - 1)
        if reject:                                 # after a rejection: never a larger step
            k = min(kopt, kc)
            h = min(h, hh[k - 1])
            reject = False
        else:
            if kopt <= kc:
                h = hh[kopt - 1]
            elif kc < k and w[kc - 1] < w[kc - 2] * FAC4:
                h = hh[kc - 1] * WORK_A[kopt] / WORK_A[kc - 1]
            else:
                h = hh[kc - 1] * WORK_A[kopt - 1] / WORK_A[kc - 1]
            k = kopt
        if SECTION:
            g1 = section_g_0(y, par)
            if crosses(g0, g1):
                ys, ts, nf = henon_crossing(y_old, t_old, t, par, st)
                nfev += nf
                row += section_event(ys, ts, par, st, out_t, out_y, out_c, row, nacc, nfev, 0.0,
                                     nrej)
                if st[ST_FOUND] >= st[ST_WANTED]:
                    break
            g0 = g1
        elif GRID:
            # samples at t_k = k dt_out in this step by partial steps with the kc lines of this
            # step (methods/kernels/events.py); redone by the next call when they do not fit
            t_hi = t if tc < 0 else y[tc]
            tol = GRID_ULPS * 2.220446049250313e-16 * abs(t_hi)
            row_start = row
            kout_start = kout
            full = False
            tk = kout * dt_out
            while kout < n_out and (tk < t_hi - tol or (not last and tk <= t_hi + tol)):
                if row >= rows - 1:
                    full = True
                    break
                yk, sk, nf, _, s = grid_sample_adaptive(y_old, fy_old, t_old, y, t, h_acc,
                                                        tk, tc, par, T, kc)
                nfev += nf
                if s != STATUS_OK:
                    status = s
                    break
                record_row(out_t, out_y, out_c, row, sk, yk, nacc, nfev, 0.0, nrej)
                row += 1
                kout += every
                tk = kout * dt_out
            if full:                       # redo this step in the next call, with a new buffer
                y = y_old
                fy = fy_old
                t = t_old
                h, k, reject, nrej, nfev = h_start, k_start, reject_start, nrej_start, nfev_start
                nacc -= 1
                kout = kout_start
                row = row_start
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
            row += 1
            st[8] = nacc
        if last:
            break
    if not SECTION and status != STATUS_OK and status != STATUS_BUFFER_FULL \
            and status != STATUS_PAUSED and nacc > st[8] and row < rows:
        record_row(out_t, out_y, out_c, row, t, y, nacc, nfev, 0.0, nrej)
        row += 1
    store(y, y_io, 0)
    store(fy, y_io, 1)
    st[0], st[1], st[2] = t, h, k
    st[3] = 1.0 if reject else 0.0
    st[4], st[5], st[6] = nacc, nrej, nfev
    if GRID:
        st[ST_KOUT] = kout
    return status, row
