"""Mathematical pendulum, [HLW] I.1.3, (1.12)-(1.13).

H = p^2/2 - cos q  [HLW] (1.12). Default initial point (p, q) = (0, 0.5), the explicit-Euler start of
[HLW] Fig 1.4. The exact solution is written with Jacobi elliptic functions (scipy.special):
libration (H < 1): sin(q/2) = k sn(t + u0, k), p = 2k cn(t + u0, k), k^2 = (1 + H)/2;
rotation (H > 1): q = 2 s am(t/k + u0, k), p = (2 s/k) dn(t/k + u0, k), k^2 = 2/(1 + H), s = sign p.
"""
from __future__ import annotations

import numpy as np
from gnibench.problems.base import Model, Problem


def model(S):
    from sympy import cos

    H = S.p**2 / 2 - cos(S.q)                                    # [HLW] (1.12)
    return Model(hamiltonian=H, integrals={"H": H})


def exact(t, y0, values):
    """Exact pendulum motion through Jacobi elliptic functions (accurate to ~1e-14)."""
    from scipy.special import ellipj, ellipk, ellipkinc

    p0, q0 = float(y0[0]), float(y0[1])
    t = np.asarray(t, dtype=float)
    H = 0.5 * p0 * p0 - np.cos(q0)
    if H < 1.0:
        m = (1.0 + H) / 2.0
        k = np.sqrt(m)
        if k == 0.0:
            return np.column_stack([np.zeros_like(t), np.zeros_like(t)])
        # Jacobi amplitude phi0 with sn = sin(phi0) = sin(q0/2)/k, cn = cos(phi0) = p0/(2k)
        qn = np.remainder(q0 + np.pi, 2 * np.pi) - np.pi
        phi0 = np.arctan2(np.sin(qn / 2) / k, p0 / (2 * k))
        u = ellipkinc(phi0, m) + t
        K4 = 4 * ellipk(m)
        sn, cn, dn, _ = ellipj(np.remainder(u, K4), m)
        q = 2 * np.arcsin(np.clip(k * sn, -1, 1)) + (q0 - qn)
        return np.column_stack([2 * k * cn, q])
    m = 2.0 / (1.0 + H)
    k = np.sqrt(m)
    s = 1.0 if p0 > 0 else -1.0
    u0 = ellipkinc(s * q0 / 2, m)
    sn, cn, dn, ph = ellipj(t / k + u0, m)
    return np.column_stack([2 * s * dn / k, 2 * s * ph])


PROBLEM = Problem(
    id="pendulum",
    title="Mathematical pendulum",
    reference="[HLW] I.1.3, (1.12)-(1.13), Fig 1.4",
    state=("p", "q"),
    params=(),
    model=model,
    initial=lambda v: (0.0, 0.5),
    canonical=(("p",), ("q",)),
    exact=exact,
    notes="(choice) default initial point (p, q) = (0, 0.5), the explicit-Euler start of Fig 1.4.",
)
