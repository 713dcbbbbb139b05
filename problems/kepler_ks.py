"""Kustaanheimo-Stiefel regularization of the spatial Kepler problem, [B] (5.4).

In fictitious time s (dt/ds = |u|^2) the Kepler problem becomes the linear system
u' = v, v' = (H/2) u, t' = u.u with u, v in R^4 and H = (2 v0.v0 - mu)/(u0.u0) the energy [B] (5.4).
Positions are q = L(u) u with the K-S matrix of [B] §5; momenta p = 2 L(u) v / |u|^2 (so that
v = L(u)^T p / 2 satisfies the bilinear relation u4 v1 - u3 v2 + u2 v3 - u1 v4 = 0).

The transformed problem is integrated by any method; :func:`forward` and :func:`backward` map
(q, p) <-> (u, v, t), so every metric of ``kepler-3d`` applies unchanged. For a = 1 and
mu = 4 pi^2 one revolution is Δs = 1 (catalog note on the Yoshida step h = 0.095).
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.problems.base import Model, Problem
from gnibench.suite.foundation.params import Param


def ks_matrix(u):
    """The 3 x 4 K-S matrix L(u) of [B] §5 (rows for q1, q2, q3)."""
    u1, u2, u3, u4 = u
    return np.array([[u1, -u2, -u3, u4], [u2, u1, -u4, -u3], [u3, u4, u1, u2]])


def forward(q, p):
    """(q, p) -> (u, v): a K-S preimage of q (the usual branch choice) and v = L(u)^T p / 2."""
    q1, q2, q3 = (float(x) for x in q)
    r = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
    if q1 >= 0:
        u1 = math.sqrt(0.5 * (r + q1))
        u = (u1, q2 / (2 * u1), q3 / (2 * u1), 0.0)
    else:
        u2 = math.sqrt(0.5 * (r - q1))
        u = (q2 / (2 * u2), u2, 0.0, q3 / (2 * u2))
    v = 0.5 * ks_matrix(u).T @ np.asarray(p, dtype=float)
    return np.array(u), v


def backward(Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows (u, v, t) -> (t, rows (q, p)) with q = L(u) u and p = 2 L(u) v / |u|^2."""
    u, v, t = Z[:, :4], Z[:, 4:8], Z[:, 8]
    u1, u2, u3, u4 = u.T
    v1, v2, v3, v4 = v.T
    q = np.column_stack([u1 * u1 - u2 * u2 - u3 * u3 + u4 * u4, 2 * (u1 * u2 - u3 * u4),
                         2 * (u1 * u3 + u2 * u4)])
    Lv = np.column_stack([u1 * v1 - u2 * v2 - u3 * v3 + u4 * v4,
                          u2 * v1 + u1 * v2 - u4 * v3 - u3 * v4,
                          u3 * v1 + u4 * v2 + u1 * v3 + u2 * v4])
    r = np.sum(u * u, axis=1)
    return t, np.column_stack([q, 2 * Lv / r[:, None]])


def model(S):
    u = (S.u1, S.u2, S.u3, S.u4)
    v = (S.v1, S.v2, S.v3, S.v4)
    rhs = v + tuple(S.H / 2 * x for x in u) + (sum(x * x for x in u),)     # [B] (5.4)
    energy = 2 * sum(x * x for x in v) - S.H * sum(x * x for x in u)       # = mu along orbits
    bilinear = S.u4 * S.v1 - S.u3 * S.v2 + S.u2 * S.v3 - S.u1 * S.v4
    return Model(rhs=rhs, integrals={"K": energy, "bilinear": bilinear})


PROBLEM = Problem(
    id="kepler-3d-ks",
    title="K-S regularized spatial Kepler problem (fictitious time s)",
    reference="[B] (5.4)",
    state=("u1", "u2", "u3", "u4", "v1", "v2", "v3", "v4", "t"),
    params=(Param("H", -2 * math.pi**2, "energy of the orbit (fixed by the initial point)",
                  high=0.0, high_open=True),
            Param("mu", 4 * math.pi**2, "gravitational parameter", low=0.0, low_open=True)),
    model=model,
    initial=lambda values: (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0),
    # u-block (v, t): its field (H/2 u, |u|^2) depends on u only; v-block u: field v -> separable
    partition=(("v1", "v2", "v3", "v4", "t"), ("u1", "u2", "u3", "u4")),
    notes="internal: reached through kepler-3d:ks=true; h and --t-end are in fictitious time s",
)
