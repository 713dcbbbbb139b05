"""Partitioned Euler step (template), implicit in block I and explicit in block E, [HLW] (1.9).

w1 = w0 + h g_I(w1, e0),  e1 = e0 + h g_E(w1, e0). With I = u this is symplectic Euler, with I = v
its adjoint. Used when block I cannot be updated explicitly (otherwise the writer,
methods/assembly/steps/partitioned.py, writes a straight tuple update); the index sets I and E
are arguments, constant tuples of the kernel module (``block_step`` is written into its callers
``pstep_u``/``pstep_v`` by numba's inliner). Evaluating only one block of f counts as half an
f-evaluation. Under ``sum=compensated`` (``block_step_sum``) Newton solves for the increment z_I = w1 - w0 instead, and
each block's increment (z_I, then h g_E) is added to y with the carried rounding error e
(methods/summation.py).
"""
from __future__ import annotations

import numpy as np
from gnibench.methods.assembly.templates.slots import (
    STATUS_NEWTON_FAILED,
    STATUS_OK,
)


def block_ws(ni):
    """The workspace of a block step whose implicit block has ni components."""
    return (np.empty((N, N)), np.empty((ni, ni)), np.empty(ni), np.empty(ni, dtype=np.int64),
            np.empty(N), np.empty(N), np.empty(N))


def block_step(y, h, par, ws, I_IDX, E_IDX):
    J, M, r, piv, ya, _, _ = ws
    scale = 1.0
    for i in range(N):
        ya[i] = y[i]
        scale = max(scale, abs(y[i]))
    nfev = 0.0
    njev = 0.0
    prev = np.inf
    for it in range(NEWTON_MAXIT + 1):
        if it == NEWTON_MAXIT:
            return y, nfev, njev, STATUS_NEWTON_FAILED
        Y = to_tuple(ya)
        g = f(Y, par)
        fjac(Y, par, J)
        nfev += 0.5
        njev += 1.0
        for k in range(len(I_IDX)):
            i = I_IDX[k]
            r[k] = y[i] + h * g[i] - ya[i]
            for m in range(len(I_IDX)):
                M[k, m] = -h * J[i, I_IDX[m]]
            M[k, k] += 1.0
        if not lu_solve(M, r, len(I_IDX), piv):
            return y, nfev, njev, STATUS_NEWTON_FAILED
        dnorm = 0.0
        for k in range(len(I_IDX)):
            ya[I_IDX[k]] += r[k]
            dnorm = max(dnorm, abs(r[k]))
        if not dnorm < np.inf:
            return y, nfev, njev, STATUS_NEWTON_FAILED
        if newton_done(dnorm, prev, scale):
            break
        prev = dnorm
    g = f(to_tuple(ya), par)
    nfev += 0.5
    for k in range(len(E_IDX)):
        i = E_IDX[k]
        ya[i] = y[i] + h * g[i]
    return to_tuple(ya), nfev, njev, STATUS_OK


def block_step_sum(y, e, h, par, ws, I_IDX, E_IDX):
    J, M, r, piv, ya, za, ea = ws
    scale = 1.0
    for i in range(N):
        ya[i] = y[i]
        za[i] = 0.0
        scale = max(scale, abs(y[i]))
    nfev = 0.0
    njev = 0.0
    prev = np.inf
    for it in range(NEWTON_MAXIT + 1):
        if it == NEWTON_MAXIT:
            return y, e, nfev, njev, STATUS_NEWTON_FAILED
        Y = to_tuple(ya)
        g = f(Y, par)
        fjac(Y, par, J)
        nfev += 0.5
        njev += 1.0
        for k in range(len(I_IDX)):
            i = I_IDX[k]
            r[k] = h * g[i] - za[i]
            for m in range(len(I_IDX)):
                M[k, m] = -h * J[i, I_IDX[m]]
            M[k, k] += 1.0
        if not lu_solve(M, r, len(I_IDX), piv):
            return y, e, nfev, njev, STATUS_NEWTON_FAILED
        dnorm = 0.0
        for k in range(len(I_IDX)):
            i = I_IDX[k]
            za[i] += r[k]
            ya[i] = y[i] + za[i]
            dnorm = max(dnorm, abs(r[k]))
        if not dnorm < np.inf:
            return y, e, nfev, njev, STATUS_NEWTON_FAILED
        if newton_done(dnorm, prev, scale):
            break
        prev = dnorm
    for i in range(N):
        ea[i] = e[i]
    for k in range(len(I_IDX)):
        i = I_IDX[k]
        ya[i], ea[i] = carry_sum(y[i], e[i], za[i])
    g = f(to_tuple(ya), par)
    nfev += 0.5
    for k in range(len(E_IDX)):
        i = E_IDX[k]
        ya[i], ea[i] = carry_sum(y[i], e[i], h * g[i])
    return to_tuple(ya), to_tuple(ea), nfev, njev, STATUS_OK
