"""Modified Gavrilov-Shil'nikov system, [B] §6.2 (the Hamiltonian after Fig 23).

H = omega K - |p|^2/2 + |q|^2/2 + (|p|^2/2) (|p|^2/2 + A K + B |q|^2),  K = q1 p2 - q2 p1,
state x = (q1, q2, p1, p2). Integrable with the same second integral K; for B > -1 it has the
"figure 8" homoclinic loop in the (r, P) plane of (6.2).

Defaults [B] §6.2: A = 0.2, B = -0.2, omega = 2 pi, start (0, -P, 0, r) with r = 1e-10 and
P = r sqrt((2 - r^2)/(2 (1 + B r^2))): then K = 0 and H = (P^2 - r^2)/2 + r^2 (r^2/2 + B P^2)/2 = 0,
a point of the loop about 1e-10 from the equilibrium. Section {p1 = 0, p2 > 0} as for G-S
(choice: recorded coordinates (q2, p2)).
"""
from __future__ import annotations

import math

from gnibench.problems.base import Model, Problem, require
from gnibench.problems.gavrilov_shilnikov import SECTION
from gnibench.suite.foundation.params import Param


def model(S):
    K = S.q1 * S.p2 - S.q2 * S.p1
    p_sq = S.p1**2 + S.p2**2
    q_sq = S.q1**2 + S.q2**2
    H = (S.omega * K - p_sq / 2 + q_sq / 2
         + p_sq / 2 * (p_sq / 2 + S.A * K + S.B * q_sq))              # [B] §6.2, after Fig 23
    return Model(hamiltonian=H, integrals={"H": H, "K": K})


def loop_P(r: float, B: float) -> float:
    """P with (0, -P, 0, r) on H = K = 0 ([B] §6.2)."""
    return r * math.sqrt((2 - r * r) / (2 * (1 + B * r * r)))


class ModifiedGS(Problem):
    def validate(self, values):
        r, B = values["r0"], values["B"]
        require(1 + B * r * r > 0, f"gavrilov-shilnikov-modified: 1 + B r0^2 = {1 + B * r * r:g}; "
                                   "allowed: 1 + B r0^2 > 0")


PROBLEM = ModifiedGS(
    id="gavrilov-shilnikov-modified",
    title="Modified Gavrilov-Shil'nikov system",
    reference="[B] §6.2, Hamiltonian after Fig 23, Figs 24-25",
    state=("q1", "q2", "p1", "p2"),
    params=(
        Param("A", 0.2, "coefficient of |p|^2 K / 2"),
        Param("B", -0.2, "coefficient of |p|^2 |q|^2 / 2 (> -1: figure-8 homoclinic loop)",
              low=-1.0, low_open=True),
        Param("omega", 2 * math.pi, "rotation frequency omega"),
        Param("r0", 1e-10, "distance parameter r of the start (0, -P, 0, r) on the loop",
              low=0.0, high=math.sqrt(2.0), low_open=True),
    ),
    model=model,
    initial=lambda v: (0.0, -loop_P(v["r0"], v["B"]), 0.0, v["r0"]),
    canonical=(("p1", "p2"), ("q1", "q2")),
    sections=(SECTION,),
    notes="Defaults of [B] §6.2: A = 0.2, B = -0.2, omega = 2 pi, start (0, -P, 0, r) with r = 1e-10, "
          "P = r sqrt((2 - r^2)/(2(1 + B r^2))), so H = K = 0. (choice) section {p1 = 0, p2 > 0} "
          "records (q2, p2).",
)
