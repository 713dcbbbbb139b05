"""Gavrilov-Shil'nikov system, [B] §6, (6.1).

H = omega (q1 p2 - q2 p1) - (eps/2)(p1^2 + p2^2) + (1/2)(q1^2 + q2^2) + (1/4)(p1^2 + p2^2)^2,
K = q1 p2 - q2 p1  [B] (6.1), state x = (q1, q2, p1, p2).

(reading) The OCR'd (6.1) shows eps in front of all three last terms. [B] studies only eps = 1
("the G-S system"), where every reading agrees. For other eps we follow the text after (6.1): the
equilibrium is a centre-centre for eps < 0, a non-semisimple 1:1 resonance for eps = 0 and a saddle-
focus for eps > 0; that holds for the quadratic part omega K - (eps/2)|p|^2 + (1/2)|q|^2 (eigenvalues
+-sqrt(eps) +- i omega), not for eps (|q|^2 - |p|^2)/2 (eigenvalues +-eps +- i omega for every eps != 0).
The quartic term is taken as (1/4)|p|^4, as in the modified system after Fig 23 with A = B = 0.

Defaults [B] §6.2: eps = 1, omega = 2 pi, start (0, 0, 0, sqrt 2) on the homoclinic loop H = K = 0.
For eps > 0 the default start is (0, 0, 0, sqrt(2 eps)), which stays on the loop. Poincaré section
{p1 = 0, p2 > 0} [B] §6.2; (choice) recorded coordinates (q2, p2): by (6.2) at phi = pi/2 they are
(-P, r), the plane of the reduced system (6.3) where the loop is drawn (Figs 15-25).
"""
from __future__ import annotations

import math

from gnibench.problems.base import Model, Problem, Section
from gnibench.suite.foundation.params import Param


def model(S):
    K = S.q1 * S.p2 - S.q2 * S.p1                                       # [B] §6.1
    p_sq = S.p1**2 + S.p2**2
    H = (S.omega * K - S.eps / 2 * p_sq + (S.q1**2 + S.q2**2) / 2
         + p_sq**2 / 4)                                                 # [B] (6.1)
    return Model(hamiltonian=H, integrals={"H": H, "K": K})


SECTION = Section(name="p1=0,p2>0", g=lambda S: S.p1, condition=lambda S: S.p2,
                  coords=("q2", "p2"), reference="[B] §6.2")

PROBLEM = Problem(
    id="gavrilov-shilnikov",
    title="Gavrilov-Shil'nikov system",
    reference="[B] §6, (6.1)-(6.3), Figs 16-23",
    state=("q1", "q2", "p1", "p2"),
    params=(
        Param("eps", 1.0, "unfolding parameter epsilon ([B]: 1; > 0 for a saddle-focus with a "
                          "homoclinic loop)", low=0.0, low_open=True),
        Param("omega", 2 * math.pi, "rotation frequency omega [B] §6.2"),
    ),
    model=model,
    initial=lambda v: (0.0, 0.0, 0.0, math.sqrt(2 * v["eps"])),
    canonical=(("p1", "p2"), ("q1", "q2")),
    sections=(SECTION,),
    notes="Defaults of [B] §6.2: eps = 1, omega = 2 pi, start (0, 0, 0, sqrt 2) on the homoclinic "
          "loop H = K = 0. (reading) H = omega K - (eps/2)|p|^2 + |q|^2/2 + |p|^4/4 (the OCR puts eps "
          "on every term; identical at eps = 1). (choice) section {p1 = 0, p2 > 0} records (q2, p2).",
)
