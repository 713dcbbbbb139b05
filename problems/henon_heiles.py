"""Hénon-Heiles model, [HLW] I.3, (3.1)-(3.2).

H = (p1^2 + p2^2)/2 + U(q)  [HLW] (3.1),  U = (q1^2 + q2^2)/2 + q1^2 q2 - q2^3/3  [HLW] (3.2).

The seed stops at the start of I.3. (choice) Poincaré section q1 = 0, p1 > 0 at the energy H0 = 1/8
(default) or 1/12, the book's standard setting. The initial point lies on the section and on the
level H = H0: q1 = 0 and (q2, p2) = (sec_q2, sec_p2) are given, and p1 = +sqrt(2 H0 - p2^2 - 2 U(0, q2))
is solved from the energy (p1 > 0: the crossing direction of the section). (choice) default
(sec_q2, sec_p2) = (-0.2, 0), i.e. the start (p1, p2, q1, q2) = (0.452401, 0, 0, -0.2) at H0 = 1/8, on a
chaotic orbit (two orbits 1e-9 apart separate to 0.38 by t = 300), whereas q2 = p2 = 0 looks regular
(separation 4e-8 at t = 500).
"""
from __future__ import annotations

import math

from gnibench.problems.base import Model, Problem, Section, require
from gnibench.suite.foundation.params import Param


def model(S):
    U = (S.q1**2 + S.q2**2) / 2 + S.q1**2 * S.q2 - S.q2**3 / 3          # [HLW] (3.2)
    H = (S.p1**2 + S.p2**2) / 2 + U                                   # [HLW] (3.1)
    return Model(hamiltonian=H, integrals={"H": H})


def _p1_squared(v) -> float:
    q2, p2 = v["sec_q2"], v["sec_p2"]
    U = q2 * q2 / 2 - q2**3 / 3                                       # U(0, q2), [HLW] (3.2)
    return 2 * v["H0"] - p2 * p2 - 2 * U


def initial(v):
    """(p1, p2, q1, q2) on the section q1 = 0 with p1 > 0 solved from H = H0."""
    return (math.sqrt(max(_p1_squared(v), 0.0)), v["sec_p2"], 0.0, v["sec_q2"])


class HenonHeiles(Problem):
    def validate(self, values):
        s = _p1_squared(values)
        require(s >= 0, f"henon-heiles: no point of the level H0 = {values['H0']:g} on the section "
                        f"q1 = 0 has (q2, p2) = ({values['sec_q2']:g}, {values['sec_p2']:g}) "
                        f"(p1^2 = {s:g} < 0); allowed: p2^2 + q2^2 - 2 q2^3/3 <= 2 H0")


SECTION = Section(name="q1=0,p1>0", g=lambda S: S.q1, condition=lambda S: S.p1,
                  coords=("q2", "p2"), reference="[HLW] I.3 (choice)")

PROBLEM = HenonHeiles(
    id="henon-heiles",
    title="Hénon-Heiles model",
    reference="[HLW] I.3, (3.1)-(3.2)",
    state=("p1", "p2", "q1", "q2"),
    params=(
        Param("H0", 1 / 8, "energy of the initial point (choice: 1/8; also 1/12)", low=0.0,
              low_open=True),
        Param("sec_q2", -0.2, "q2 of the initial point on the section q1 = 0"),
        Param("sec_p2", 0.0, "p2 of the initial point on the section q1 = 0"),
    ),
    model=model,
    initial=initial,
    canonical=(("p1", "p2"), ("q1", "q2")),
    sections=(SECTION,),
    notes="(choice) section q1 = 0, p1 > 0 at H0 = 1/8 (default) or 1/12. Initial point: q1 = 0, "
          "(q2, p2) = (sec_q2, sec_p2), p1 > 0 solved from H = H0; default (q2, p2) = (-0.2, 0), a "
          "chaotic orbit at H0 = 1/8.",
)
