"""Kepler problem in the plane, [HLW] I.2, (2.2)-(2.4), (2.11).

H = (p1^2 + p2^2)/2 - 1/|q|  [HLW] (2.3); L = q1 p2 - q2 p1  [HLW] (2.4); the Runge-Lenz vector
A = p x L e_z - q/|q| (components A1, A2) is a further first integral. Default initial values
[HLW] (2.11): q = (1 - e, 0), p = (0, sqrt((1+e)/(1-e))), so H0 = -1/2, L0 = sqrt(1-e^2), period 2 pi.
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.problems.base import Model, Problem, require
from gnibench.problems.kepler_exact import kepler_orbit_2d, kepler_period
from gnibench.suite.foundation.params import Param


def model(S):
    from sympy import sqrt

    r = sqrt(S.q1**2 + S.q2**2)
    H = (S.p1**2 + S.p2**2) / 2 - 1 / r                  # [HLW] (2.3)
    L = S.q1 * S.p2 - S.q2 * S.p1                        # [HLW] (2.4)
    A1 = S.p2 * L - S.q1 / r                             # Runge-Lenz vector
    A2 = -S.p1 * L - S.q2 / r
    return Model(hamiltonian=H, integrals={"H": H, "L": L, "A1": A1, "A2": A2})


def initial(v):
    e = v["e"]
    return (0.0, math.sqrt((1 + e) / (1 - e)), 1 - e, 0.0)   # [HLW] (2.11), order (p1,p2,q1,q2)


def exact(t, y0, values):
    """Exact solution through Kepler's equation, to round-off (any bound orbit)."""
    p, q = np.asarray(y0[:2]), np.asarray(y0[2:])
    qt, pt = kepler_orbit_2d(q, p, np.asarray(t, dtype=float), mu=1.0)
    return np.column_stack([pt, qt])


def period(values) -> float:
    """2 pi a^(3/2) with a = -1/(2 H0) from the initial point ([HLW] (2.11): 2 pi)."""
    p1, p2, q1, q2 = PROBLEM.y0(values)
    return kepler_period((q1, q2), (p1, p2), mu=1.0)


class Kepler2D(Problem):
    def validate(self, values):
        y0 = self.y0(values)
        p1, p2, q1, q2 = y0
        energy = 0.5 * (p1 * p1 + p2 * p2) - 1.0 / math.hypot(q1, q2) if (q1 or q2) else math.inf
        require(energy < 0, f"kepler-2d: initial point has H = {energy:g}; allowed: a bound orbit, H < 0")


PROBLEM = Kepler2D(
    id="kepler-2d",
    title="Kepler problem in the plane",
    reference="[HLW] I.2, (2.2)-(2.4), (2.11)",
    state=("p1", "p2", "q1", "q2"),
    params=(Param("e", 0.6, "eccentricity of the default orbit [HLW] (2.11)", low=0.0, high=1.0,
                  high_open=True),),
    model=model,
    initial=initial,
    canonical=(("p1", "p2"), ("q1", "q2")),
    exact=exact,
    period=period,
)
