"""GBS extrapolation kernels (templates): Gragg's midpoint rule, Aitken-Neville, ODEX's control.

Layout of the tableau ``T`` (a KMAX x N array made once per run), as in ODEX: after column j has
been added, ``T[0]`` holds the most extrapolated value T_jj and ``T[1]`` the subdiagonal T_j,j-1
(both as increments over y, see ``gragg_column``),
whose difference is the error estimate (HNW I, §II.9, (9.22)-(9.23)). Columns are numbered from 1
as in HNW; the arrays are indexed by ``j - 1``.

The adaptive mode runs the resumable loop every adaptive method shares (templates/adaptive.py)
with odex's attempt and controller below, after ODEX's ODXCOR with its default constants (HNW I,
§II.9 "Order and step size control"): convergence monitor in line k-1, hope for convergence in
line k+1, order and step chosen by the work per unit step W_j = A_j / H_j. The controller's state
is the order k (slot ``ST_CONTROL``); the per-step arrays (T, H_j, W_j: ``adaptive_ws``) are
rebuilt within each step, so nothing else has to survive between calls. Under
``sum=compensated`` the extrapolated increment T_kk - y is added to y with the carried rounding
error (methods/summation.py).
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.methods.assembly.templates.slots import (
    ACCEPT,
    REJECT,
    STATUS_OK,
    UNSTABLE,
)

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
    nfev = nj
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
                nfev = -m
                break
    if nfev == nj:
        dy = f(to_tuple_shift(y, 1.0, z_mid), par)    # smoothing step
        for i in range(N):
            T[row, i] = 0.5 * (z_prev[i] + z_mid[i] + hj * dy[i])
    return nfev


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


def fixed_increment(y, h, par, ws):
    """T_KK - y of the harmonic sequence with K_FIXED lines (in ws[0]) and the f-evaluations."""
    fy = f(y, par)
    nfev = 1.0
    for j in range(1, K_FIXED + 1):
        nfev += gragg_column(y, fy, h, NJ[j - 1], par, ws, j - 1, False, 0.0, 0.0)
        neville(ws, j)
    return nfev


def step(y, h, par, ws):
    """Fixed step of order 2 K_FIXED: T_KK of the harmonic sequence (HNW Theorem II.9.1)."""
    nfev = fixed_increment(y, h, par, ws)
    return to_tuple_shift(y, 1.0, to_tuple(ws[0])), nfev, 0.0, STATUS_OK


def step_sum(y, e, h, par, ws):
    """``step`` with the increment added to y with the carried error e (sum=compensated)."""
    nfev = fixed_increment(y, h, par, ws)
    y1, e1 = carry_add(y, e, to_tuple(ws[0]))
    return y1, e1, nfev, 0.0, STATUS_OK


def solution(y, e, T):
    """y + T_kk (the increment in T[0]) with its carry: (y1, e1)."""
    if COMPENSATED:
        y1, e1 = carry_add(y, e, to_tuple(T[0]))
    else:
        y1, e1 = to_tuple_shift(y, 1.0, to_tuple(T[0])), e
    return y1, e1


def partial_step(y, e, fy, sigma, par, ws, kc):
    """odex's own step of size sigma with the kc lines of the accepted step (T_kc,kc, order 2 kc;
    the tableau T is scratch between steps): a partial step for the time grid."""
    T = ws[0]
    nfev = 0.0
    for j in range(1, kc + 1):
        nfev += gragg_column(y, fy, sigma, NJ[j - 1], par, T, j - 1, False, 0.0, 0.0)
        neville(T, j)
    return solution(y, e, T)[0], nfev, 0.0, STATUS_OK


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


def adaptive_ws():
    """The per-call scratch: the tableau T, the optimal steps H_j, the work per unit step W_j, and
    the attempt's parameters and outcome (``controller_prepare``, ``attempt_outcome``): order k,
    first, last, after a rejection, hmax; lines used kc, f-evaluations, verdict."""
    return np.empty((KMAX, N)), np.zeros(KMAX), np.zeros(KMAX), np.zeros(8)


def controller_init(y, fy, par, h0, hmax, rtol, atol, t_end):
    """ODEX's first step (h0, else HINIT, then at most t_end / 2) and first order k."""
    h, nfev = first_step(y, fy, par, h0, hmax, rtol, atol)
    if h0 <= 0.0:
        h = min(h, 0.5 * t_end)
    return h, nfev, max(2, min(KMAX - 1, int(-math.log10(rtol + 1.0e-40) * 0.6 + 1.5)))


def controller_state(x):
    return int(x)


def controller_clip(h, hmax):
    return min(h, hmax)


def controller_prepare(ws, k, first, last, reject, hmax):
    """What the attempt reads: the order k, first or last step, after a rejection, hmax."""
    info = ws[3]
    info[0] = k
    info[1] = 1.0 if first else 0.0
    info[2] = 1.0 if last else 0.0
    info[3] = 1.0 if reject else 0.0
    info[4] = hmax


def attempt_outcome(ws, err):
    """The lines kc of the last attempt, its f-evaluations and verdict."""
    info = ws[3]
    return int(info[5]), info[6], int(info[7])


def attempt(y, e, fy, h, par, ws, rtol, atol):
    """One attempt of ODEX with the order k of ``controller_prepare``: (y1, e1, err, fy); its lines
    kc, f-evaluations and verdict go to ``attempt_outcome``. The first and the last step compute
    lines 1..k, the others 1..k-1 and then the convergence monitor; then the hope for convergence
    in line k+1 (ODEX's labels 55, 60, 100)."""
    T, hh, w, info = ws
    k = int(info[0])
    first = info[1] != 0.0
    last = info[2] != 0.0
    reject = info[3] != 0.0
    hmax = info[4]
    go = 0                     # 55: hope for line k+1, 60 accept, 100 reject, 10 ATOV (unstable)
    kc = 0
    err = 0.0
    errold = 1.0e10
    nfev = 0.0
    if first or last:                              # first and last step: lines 1..k
        for j in range(1, k + 1):
            kc = j
            err, errold, nf, atov = column(j, y, fy, h, hmax, par, T, hh, w, rtol, atol, errold)
            nfev += nf
            if atov:
                go = 10
                break
            if j > 1 and err <= 1.0:
                go = 60
                break
        if go == 0:
            go = 55
    else:                                          # basic step: lines 1..k-1, then monitor
        kc = k - 1
        for j in range(1, kc + 1):
            err, errold, nf, atov = column(j, y, fy, h, hmax, par, T, hh, w, rtol, atol, errold)
            nfev += nf
            if atov:
                go = 10
                break
        if go == 0 and not (k == 2 or reject):     # convergence monitor in line k-1
            if err <= 1.0:
                go = 60
            elif err > (NJ[k] * NJ[k - 1] / 4.0) ** 2:
                go = 100
        if go == 0:
            err, errold, nf, atov = column(k, y, fy, h, hmax, par, T, hh, w, rtol, atol, errold)
            nfev += nf
            kc = k
            if atov:
                go = 10
            elif err <= 1.0:
                go = 60
            else:
                go = 55
    if go == 55:                                   # hope for convergence in line k+1
        if err > (NJ[k] / 2.0) ** 2:
            go = 100
        else:
            kc = k + 1
            err, errold, nf, atov = column(kc, y, fy, h, hmax, par, T, hh, w, rtol, atol, errold)
            nfev += nf
            if atov:
                go = 10
            elif err > 1.0:
                go = 100
            else:
                go = 60
    info[5] = kc
    info[6] = nfev
    y1, e1 = y, e
    if go == 60:
        info[7] = ACCEPT
        y1, e1 = solution(y, e, T)
    else:
        info[7] = UNSTABLE if go == 10 else REJECT
    return y1, e1, err, fy


def controller_reject(h, k, err, verdict, kc, ws, nacc):
    """After a rejection: h * SAFE3 on instability, else line min(k, kc) (one lower when it is
    cheaper per unit step) and its optimal step: (h_new, k, counted)."""
    if verdict == UNSTABLE:
        h_new = h * SAFE3
    else:
        hh, w = ws[1], ws[2]
        k = min(k, kc, KMAX - 1)
        if k > 2 and w[k - 2] < w[k - 1] * FAC3:
            k -= 1
        h_new = hh[k - 1]
    return h_new, k, True


def controller_accept(h, k, err, reject, kc, ws, hmax):
    """ODEX's order and step after an accepted step of size h with kc lines: (h_new, k)."""
    hh, w = ws[1], ws[2]
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
    else:
        if kopt <= kc:
            h = hh[kopt - 1]
        elif kc < k and w[kc - 1] < w[kc - 2] * FAC4:
            h = hh[kc - 1] * WORK_A[kopt] / WORK_A[kc - 1]
        else:
            h = hh[kc - 1] * WORK_A[kopt - 1] / WORK_A[kc - 1]
        k = kopt
    return h, k
