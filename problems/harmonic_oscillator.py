"""Harmonic oscillator, [B] end of §3: H = (p^2 + q^2)/2, exact solution a rotation."""
from __future__ import annotations

import numpy as np
from gnibench.problems.base import Model, Problem


def model(S):
    H = (S.p**2 + S.q**2) / 2                                    # [B] §3
    return Model(hamiltonian=H, integrals={"H": H})


def exact(t, y0, values):
    q0, p0 = float(y0[0]), float(y0[1])
    c, s = np.cos(t), np.sin(t)
    return np.column_stack([q0 * c + p0 * s, -q0 * s + p0 * c])


PROBLEM = Problem(
    id="harmonic-oscillator",
    title="Harmonic oscillator",
    reference="[B] end of §3",
    state=("q", "p"),
    params=(),
    model=model,
    initial=lambda v: (1.0, 0.0),
    canonical=(("p",), ("q",)),
    exact=exact,
    period=lambda values: 2 * np.pi,
    notes="(choice) default initial point (q, p) = (1, 0), so H0 = 1/2.",
)
