"""Spatial Kepler problem, [B] §5, (5.1)-(5.2).

H = |p|^2/2 - mu/|q|  [B] §5.1; angular momentum c = q x p and Laplace vector
e = p x c/mu - q/|q|  [B] (5.1); c_sq = c.c is the second observed integral of [B] (5.2).

Default orbit [B] §5.2: a = 1, e = 0.8, Omega = omega = pi/2, i = pi/4, mu = 4 pi^2 (period 1), start at
the pericenter (mean anomaly M0 = 0). The initial point is built from these elements
(:func:`gnibench.problems.kepler3d_exact.state_from_elements`), with i measured from the q3-axis.

The seven integrals are dependent: c.e = 0 and 2 H c^2 = mu^2 (e^2 - 1). [B] §5.1 prints
"H c^2 = mu^2 (e^2 - 1)" without the factor 2; with a = -mu/(2H) and c^2 = mu a (1 - e^2) the
factor 2 is needed (default orbit: H = -2 pi^2, c^2 = 0.36 mu, so 2 H c^2 = -0.36 mu^2).
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.problems import kepler_ks
from gnibench.problems.base import Model, Problem, Transform, require
from gnibench.problems.kepler3d_exact import kepler_orbit_3d, state_from_elements
from gnibench.problems.kepler_exact import kepler_period
from gnibench.suite.foundation.params import Param


def model(S):
    from sympy import sqrt

    q = (S.q1, S.q2, S.q3)
    p = (S.p1, S.p2, S.p3)
    r = sqrt(q[0]**2 + q[1]**2 + q[2]**2)
    H = (p[0]**2 + p[1]**2 + p[2]**2) / 2 - S.mu / r                    # [B] §5.1
    c = (q[1] * p[2] - q[2] * p[1], q[2] * p[0] - q[0] * p[2], q[0] * p[1] - q[1] * p[0])  # [B] (5.1)
    pxc = (p[1] * c[2] - p[2] * c[1], p[2] * c[0] - p[0] * c[2], p[0] * c[1] - p[1] * c[0])
    e = tuple(pxc[k] / S.mu - q[k] / r for k in range(3))               # [B] (5.1)
    c_sq = c[0]**2 + c[1]**2 + c[2]**2                                  # [B] (5.2)
    integrals = {"H": H, "c1": c[0], "c2": c[1], "c3": c[2], "c_sq": c_sq,
                 "e1": e[0], "e2": e[1], "e3": e[2]}
    return Model(hamiltonian=H, integrals=integrals)


def initial(v):
    q, p = state_from_elements(v["a"], v["e"], v["i"], v["Omega"], v["omega"], v["M0"], v["mu"])
    return tuple(q) + tuple(p)


def exact(t, y0, values):
    """Exact solution through Kepler's equation (any bound orbit with c != 0), to round-off."""
    y0 = np.asarray(y0, dtype=float)
    q, p = kepler_orbit_3d(y0[:3], y0[3:], np.asarray(t, dtype=float), values["mu"])
    return np.column_stack([q, p])


def period(values) -> float:
    """2 pi sqrt(a^3/mu) with a = -mu/(2 H0) from the initial point ([B] §5.2: 1 for the default
    orbit); the same under ks=true (the period of the motion in t)."""
    y0 = PROBLEM.y0(values)
    return kepler_period(y0[:3], y0[3:], mu=values["mu"])


def _to_ks(y0, values):
    """Initial point and parameters of the K-S system [B] (5.4) for this orbit."""
    q, p = np.asarray(y0[:3]), np.asarray(y0[3:])
    u, v = kepler_ks.forward(q, p)
    mu = values["mu"]
    energy = (2 * v @ v - mu) / (u @ u)                                  # [B] (5.4)
    init = dict(zip((f"{s}0" for s in kepler_ks.PROBLEM.state), [*u, *v, 0.0]))
    return {"H": float(energy), "mu": mu, **{k: float(x) for k, x in init.items()}}


def _from_ks(Z, values):
    return kepler_ks.backward(Z)


KS = Transform(option="ks", problem=kepler_ks.PROBLEM, to_transformed=_to_ks, back=_from_ks,
               doc="K-S regularization [B] (5.4): integrate in fictitious time s (h, --t-end in s)",
               time="t")


class Kepler3D(Problem):
    def validate(self, values):
        q1, q2, q3, p1, p2, p3 = self.y0(values)
        r = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
        require(r > 0, "kepler-3d: initial point has q = 0; allowed: q != 0")
        energy = 0.5 * (p1 * p1 + p2 * p2 + p3 * p3) - values["mu"] / r
        c = (q2 * p3 - q3 * p2, q3 * p1 - q1 * p3, q1 * p2 - q2 * p1)
        require(energy < 0, f"kepler-3d: initial point has H = {energy:g}; allowed: a bound orbit, H < 0")
        require(any(c), "kepler-3d: initial point has c = q x p = 0 (straight-line orbit); "
                        "allowed: c != 0")


NOTES = ("Default orbit of [B] §5.2: a = 1, e = 0.8, Omega = omega = pi/2, i = pi/4, mu = 4 pi^2 "
         "(period 1), started at the pericenter (M0 = 0). (reading) i is the angle between c and the "
         "q3-axis (the text says q1-axis, a slip). (reading) the identity is 2 H c^2 = mu^2 (e^2 - 1); "
         "[B] §5.1 prints it without the factor 2.")

PROBLEM = Kepler3D(
    id="kepler-3d",
    title="Spatial Kepler problem",
    reference="[B] §5, (5.1)-(5.2)",
    state=("q1", "q2", "q3", "p1", "p2", "p3"),
    params=(
        Param("mu", 4 * math.pi**2, "gravitational parameter [B] §5.2", low=0.0, low_open=True),
        Param("a", 1.0, "semi-major axis of the default orbit", low=0.0, low_open=True),
        Param("e", 0.8, "eccentricity of the default orbit", low=0.0, high=1.0, high_open=True),
        Param("i", math.pi / 4, "inclination (angle between c and the q3-axis)", low=0.0,
              high=math.pi),
        Param("Omega", math.pi / 2, "longitude of the ascending node"),
        Param("omega", math.pi / 2, "argument of the pericenter"),
        Param("M0", 0.0, "mean anomaly of the initial point (0: pericenter)"),
        Param("ks", False, "integrate the K-S regularized system [B] (5.4) in fictitious time s "
              "(h and --t-end in s; results mapped back to (t, q, p))", kind="bool",
              show_default=False),
    ),
    model=model,
    initial=initial,
    canonical=(("p1", "p2", "p3"), ("q1", "q2", "q3")),
    exact=exact,
    period=period,
    notes=NOTES,
    transform=KS,
)
