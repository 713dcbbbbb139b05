"""Generic implicit Runge-Kutta step (template): Newton on the stage increments.

Stage increments Z_i = Y_i - y solve Z_i = h sum_j a_ij f(y + Z_j); the new point is
y1 = y + sum_j d_j Z_j with d = b^T A^{-1} (no extra f-evaluation). Newton uses the Jacobian of f
at the current iterate (full Newton, ``stages_newton``), so it converges quadratically to
round-off. The cell's solver is bound as ``solve_stages`` (methods/assembly/steps/irk.py).

``stages_fixed_point`` (method option ``fixed_point = K``) solves the same equations by at most K
fixed-point iterations Z <- h A F(y + Z), the simplest solver and the one behind [HLW] Fig 2.4's
implicit Euler (I.2.4): a step whose iteration has not converged after K iterations is accepted
with its last iterate (not a failure), and counted in ``njev`` (no Jacobian is evaluated by this
solver, so ``njev`` records where the iteration did not converge). Under ``sum=compensated``
(``step_sum``) the increment Σ_j d_j Z_j is added to y with the carried rounding error e
(methods/summation.py).
"""
from __future__ import annotations

import numpy as np
from gnibench.methods.assembly.templates.slots import (
    STATUS_NEWTON_FAILED,
    STATUS_OK,
)


def make_ws():
    return (np.zeros((S, N)), np.empty((S, N)), np.empty((S * N, S * N)), np.empty(S * N),
            np.empty((N, N)), np.empty(S * N, dtype=np.int64), np.empty(N))


def stages_newton(y, h, par, ws):
    """Newton for the stage increments Z (in ws[0]): (nfev, njev, status)."""
    Z, F, M, r, J, piv, _ = ws
    scale = 1.0
    for i in range(N):
        scale = max(scale, abs(y[i]))
        for j in range(S):
            Z[j, i] = 0.0
    nfev = 0.0
    njev = 0.0
    prev = np.inf
    status = STATUS_OK
    for it in range(NEWTON_MAXIT + 1):
        if it == NEWTON_MAXIT:
            status = STATUS_NEWTON_FAILED
            break
        for j in range(S):
            Yj = shifted(y, Z, j)
            store(f(Yj, par), F, j)
            fjac(Yj, par, J)
            for a in range(S):
                c = -h * A[a][j]
                for i in range(N):
                    for k in range(N):
                        M[a * N + i, j * N + k] = c * J[i, k]
                if a == j:
                    for i in range(N):
                        M[a * N + i, j * N + i] += 1.0
        nfev += S
        njev += S
        for a in range(S):
            for i in range(N):
                acc = 0.0
                for j in range(S):
                    acc += A[a][j] * F[j, i]
                r[a * N + i] = h * acc - Z[a, i]
        if not lu_solve(M, r, S * N, piv):
            status = STATUS_NEWTON_FAILED
            break
        dnorm = 0.0
        for a in range(S):
            for i in range(N):
                Z[a, i] += r[a * N + i]
                dnorm = max(dnorm, abs(r[a * N + i]))
        if not dnorm < np.inf:
            status = STATUS_NEWTON_FAILED
            break
        if newton_done(dnorm, prev, scale):
            break
        prev = dnorm
    return nfev, njev, status


def increment(ws):
    """Σ_j d_j Z_j (d = bᵀA⁻¹, from the stage increments Z in ws[0]) as a tuple, through ws[6]."""
    Z, out = ws[0], ws[6]
    for i in range(N):
        acc = 0.0
        for j in range(S):
            acc += D[j] * Z[j, i]
        out[i] = acc
    return to_tuple(out)


def step(y, h, par, ws):
    nfev, njev, s = solve_stages(y, h, par, ws)
    y1 = y
    if s == STATUS_OK:
        y1 = carry_apply(y, increment(ws))
    return y1, nfev, njev, s


def stages_fixed_point(y, h, par, ws):
    """At most ``fixed_point`` fixed-point iterations for Z (in ws[0]; the count is the method's
    runtime option, ``par[FIXED_POINT_AT]``): (nfev, njev, status), njev 1.0 when the iteration
    has not converged (the step is accepted all the same)."""
    Z, F = ws[0], ws[1]
    scale = 1.0
    for i in range(N):
        scale = max(scale, abs(y[i]))
        for j in range(S):
            Z[j, i] = 0.0
    nfev = 0.0
    njev = 1.0
    prev = np.inf
    for it in range(int(par[FIXED_POINT_AT])):
        for j in range(S):
            store(f(shifted(y, Z, j), par), F, j)
        nfev += S
        dnorm = 0.0
        for a in range(S):
            for i in range(N):
                acc = 0.0
                for j in range(S):
                    acc += A[a][j] * F[j, i]
                dz = h * acc - Z[a, i]
                Z[a, i] += dz
                dnorm = max(dnorm, abs(dz))
        if not dnorm < np.inf:
            break
        if newton_done(dnorm, prev, scale):
            njev = 0.0
            break
        prev = dnorm
    return nfev, njev, STATUS_OK


def step_sum(y, e, h, par, ws):
    nfev, njev, s = solve_stages(y, h, par, ws)
    y1, e1 = y, e
    if s == STATUS_OK:
        y1, e1 = carry_add(y, e, increment(ws))
    return y1, e1, nfev, njev, s
