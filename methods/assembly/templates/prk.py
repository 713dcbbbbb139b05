"""Generic partitioned Runge-Kutta step (template): Newton on the stage increments.

Component i of the state belongs to the block u (``IN_U[i]``: tableau AU, BU) or v (AV, BV)
([HLW] II.2.2, (2.2)). The stage increments Z_a = Y_a - y solve, component by component,
Z_a[i] = h Σ_j A^(i)_aj f_i(y + Z_j); full Newton with the field's Jacobian, as the implicit RK
kernel (templates/irk.py). Then y1[i] = y[i] + h Σ_j B^(i)_j f_i(y + Z_j) from a fresh evaluation
at the converged stages (A may be singular, e.g. Lobatto IIIA, so d = b^T A^-1 is not used).
An implicit RK method is the case AU = AV.
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


def step(y, h, par, ws):
    Z, F, M, r, J, piv, out = ws
    scale = 1.0
    for i in range(N):
        scale = max(scale, abs(y[i]))
        for j in range(S):
            Z[j, i] = 0.0
    nfev = 0.0
    njev = 0.0
    prev = np.inf
    for it in range(NEWTON_MAXIT + 1):
        if it == NEWTON_MAXIT:
            return y, nfev, njev, STATUS_NEWTON_FAILED
        for j in range(S):
            Yj = shifted(y, Z, j)
            store(f(Yj, par), F, j)
            fjac(Yj, par, J)
            for a in range(S):
                for i in range(N):
                    c = -h * (AU[a][j] if IN_U[i] else AV[a][j])
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
                    acc += (AU[a][j] if IN_U[i] else AV[a][j]) * F[j, i]
                r[a * N + i] = h * acc - Z[a, i]
        if not lu_solve(M, r, S * N, piv):
            return y, nfev, njev, STATUS_NEWTON_FAILED
        dnorm = 0.0
        for a in range(S):
            for i in range(N):
                Z[a, i] += r[a * N + i]
                dnorm = max(dnorm, abs(r[a * N + i]))
        if not dnorm < np.inf:
            return y, nfev, njev, STATUS_NEWTON_FAILED
        if newton_done(dnorm, prev, scale):
            break
        prev = dnorm
    for j in range(S):
        store(f(shifted(y, Z, j), par), F, j)
    nfev += S
    for i in range(N):
        acc = 0.0
        for j in range(S):
            acc += (BU[j] if IN_U[i] else BV[j]) * F[j, i]
        out[i] = y[i] + h * acc
    return to_tuple(out), nfev, njev, STATUS_OK
