"""Small dense linear algebra for Newton steps (templates; compiled in each generated module)."""
from __future__ import annotations


def lu_solve(M, r, n, piv):
    """Solve M x = r in place (x returned in r) by Gaussian elimination with partial pivoting.

    Returns False if M is singular to working precision. M is overwritten.
    """
    ok = True
    for k in range(n):
        p = k
        big = abs(M[k, k])
        for i in range(k + 1, n):
            if abs(M[i, k]) > big:
                big = abs(M[i, k])
                p = i
        if big == 0.0:
            ok = False
            break
        piv[k] = p
        if p != k:
            for j in range(n):
                tmp = M[k, j]
                M[k, j] = M[p, j]
                M[p, j] = tmp
            tmp = r[k]
            r[k] = r[p]
            r[p] = tmp
        inv = 1.0 / M[k, k]
        for i in range(k + 1, n):
            m = M[i, k] * inv
            if m != 0.0:
                for j in range(k + 1, n):
                    M[i, j] -= m * M[k, j]
                r[i] -= m * r[k]
    if ok:
        for k in range(n - 1, -1, -1):
            s = r[k]
            for j in range(k + 1, n):
                s -= M[k, j] * r[j]
            r[k] = s / M[k, k]
    return ok
