"""Two uncoupled harmonic oscillators, [B] §4.2, (4.2).

H1 = (p1^2 + q1^2)/2 and H2 = (p1^2 + p2^2 + q1^2 + q2^2)/2 (the Hamiltonian); (H1, H2) = (1.5, 1.9).
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.problems.base import Model, Problem


def model(S):
    H1 = (S.p1**2 + S.q1**2) / 2                                 # [B] (4.2)
    H2 = (S.p1**2 + S.p2**2 + S.q1**2 + S.q2**2) / 2
    return Model(hamiltonian=H2, integrals={"H1": H1, "H2": H2})


def exact(t, y0, values):
    q1, q2, p1, p2 = (float(x) for x in y0)
    c, s = np.cos(t), np.sin(t)
    return np.column_stack([q1 * c + p1 * s, q2 * c + p2 * s, -q1 * s + p1 * c, -q2 * s + p2 * c])


PROBLEM = Problem(
    id="double-oscillator",
    title="Double harmonic oscillator",
    reference="[B] §4.2, (4.2), Figs 6-8",
    state=("q1", "q2", "p1", "p2"),
    params=(),
    model=model,
    initial=lambda v: (math.sqrt(3.0), math.sqrt(0.8), 0.0, 0.0),
    canonical=(("p1", "p2"), ("q1", "q2")),
    exact=exact,
    notes="(choice) q = (sqrt 3, sqrt 0.8), p = (0, 0), giving (H1, H2) = (1.5, 1.9).",
)
