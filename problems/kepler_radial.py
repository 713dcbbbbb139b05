"""Radial (reduced) planar Kepler problem, [B] §4.1, (4.1).

For a fixed angular momentum p_phi the radial motion of the planar Kepler problem is the Hamiltonian
system (4.1) with H1(r, p) = (p^2 + p_phi^2/r^2)/2 - mu/r  [B] §4.1, the reduced Hamiltonian.

[B] integrates the orbit with H1 = -0.4 but gives neither mu nor p_phi nor the initial point.
(choice) mu = 1, p_phi = 1, start at the pericenter: p = 0 and r the smaller root of
H0 r^2 + mu r - p_phi^2/2 = 0, i.e. r = (1 - sqrt 0.2)/0.8 = 0.69098..., eccentricity sqrt 0.2.

Exact solution: the planar Kepler orbit with the same H and L = p_phi through q = (r0, 0),
p = (p0, p_phi/r0) gives r(t) = |q(t)| and p_r(t) = q.p/|q| (:mod:`gnibench.problems.kepler_exact`).
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.problems.base import Model, Problem, require
from gnibench.problems.kepler_exact import kepler_orbit_2d
from gnibench.suite.foundation.params import Param


def model(S):
    H1 = (S.p**2 + S.p_phi**2 / S.r**2) / 2 - S.mu / S.r                # [B] (4.1)
    return Model(hamiltonian=H1, integrals={"H": H1})


def pericenter(H0: float, mu: float, p_phi: float) -> float:
    """Pericenter distance of the orbit with energy H0 < 0: smaller root of H0 r^2 + mu r - p_phi^2/2."""
    disc = mu * mu + 2 * H0 * p_phi * p_phi
    return (mu - math.sqrt(max(disc, 0.0))) / (-2 * H0)


def initial(v):
    return (pericenter(v["H0"], v["mu"], v["p_phi"]), 0.0)


def exact(t, y0, values):
    """r(t), p_r(t) from the planar orbit with angular momentum p_phi (Kepler's equation)."""
    r0, pr0 = float(y0[0]), float(y0[1])
    p_phi = values["p_phi"]
    q, p = kepler_orbit_2d(np.array([r0, 0.0]), np.array([pr0, p_phi / r0]),
                           np.asarray(t, dtype=float), mu=values["mu"])
    r = np.hypot(q[:, 0], q[:, 1])
    return np.column_stack([r, np.sum(q * p, axis=1) / r])


class KeplerRadial(Problem):
    def validate(self, values):
        mu, p_phi, H0 = values["mu"], values["p_phi"], values["H0"]
        lowest = -mu * mu / (2 * p_phi * p_phi)
        require(H0 >= lowest, f"kepler-radial: H0 = {H0:g} is below the circular-orbit energy "
                              f"-mu^2/(2 p_phi^2) = {lowest:g}; allowed: {lowest:g} <= H0 < 0")
        r, p = self.y0(values)
        require(r > 0, f"kepler-radial: initial r = {r:g}; allowed: r > 0")
        energy = 0.5 * (p * p + p_phi * p_phi / (r * r)) - mu / r
        require(energy < 0, f"kepler-radial: initial point has H = {energy:g}; allowed: a bound "
                            "orbit, H < 0")


PROBLEM = KeplerRadial(
    id="kepler-radial",
    title="Radial Kepler problem (reduced system)",
    reference="[B] §4.1, (4.1), Figs 1-5",
    state=("r", "p"),
    params=(
        Param("mu", 1.0, "gravitational parameter (choice: 1)", low=0.0, low_open=True),
        Param("p_phi", 1.0, "angular momentum (choice: 1)", low=0.0, low_open=True),
        Param("H0", -0.4, "energy of the default initial point (at the pericenter)", high=0.0,
              high_open=True),
    ),
    model=model,
    initial=initial,
    canonical=(("p",), ("r",)),
    exact=exact,
    notes="(choice) mu = 1, p_phi = 1 (not given in [B]); default start at the pericenter with "
          "H = -0.4: p = 0, r = (1 - sqrt 0.2)/0.8 = 0.69098, eccentricity sqrt 0.2.",
)
