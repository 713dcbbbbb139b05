"""The outer solar system (sun and five outer planets), [HLW] I.2.4, (2.12), Table 2.2.

H = 1/2 sum_i |p_i|^2/m_i - G sum_{i>j} m_i m_j/|q_i - q_j|  [HLW] (2.12), bodies i = 0 (sun, with the
inner planets' mass), 1 Jupiter, 2 Saturn, 3 Uranus, 4 Neptune, 5 Pluto. Units: solar masses,
astronomical units, earth days; G = 2.95912208286e-4, m0 = 1.00000597682 [HLW] I.2.4.

State order (choice): HLW's supervectors p then q, body by body, component by component:
p0x, p0y, p0z, p1x, ..., p5z, q0x, ..., q5z. Initial values: Table 2.2 (5 September 1994), the sun
at rest at the origin; the table gives velocities, so p_i = m_i qdot_i.

First integrals: H, total angular momentum L = sum_i q_i x p_i (Lx, Ly, Lz) and total linear
momentum P = sum_i p_i (Px, Py, Pz). No closed-form solution.
"""
from __future__ import annotations

from gnibench.problems.base import Model, Problem
from gnibench.suite.foundation.params import Param

BODIES = ("sun", "Jupiter", "Saturn", "Uranus", "Neptune", "Pluto")
AXES = ("x", "y", "z")
P_NAMES = tuple(f"p{i}{a}" for i in range(6) for a in AXES)
Q_NAMES = tuple(f"q{i}{a}" for i in range(6) for a in AXES)

G = 2.95912208286e-4                                          # [HLW] I.2.4
MASSES = (1.00000597682, 0.000954786104043, 0.000285583733151, 0.0000437273164546,
          0.0000517759138449, 1 / 1.3e8)                      # [HLW] I.2.4 and Table 2.2
# [HLW] Table 2.2: initial positions (AU) and velocities (AU/day) of the planets; the sun is at rest.
POSITIONS = ((0.0, 0.0, 0.0),
             (-3.5023653, -3.8169847, -1.5507963),
             (9.0755314, -3.0458353, -1.6483708),
             (8.3101420, -16.2901086, -7.2521278),
             (11.4707666, -25.7294829, -10.8169456),
             (-15.5387357, -25.2225594, -3.1902382))
VELOCITIES = ((0.0, 0.0, 0.0),
              (0.00565429, -0.00412490, -0.00190589),
              (0.00168318, 0.00483525, 0.00192462),
              (0.00354178, 0.00137102, 0.00055029),
              (0.00288930, 0.00114527, 0.00039677),
              (0.00276725, -0.00170702, -0.00136504))


def time_scale(values) -> float:
    """1/n of the fastest planet (Jupiter, ~730 days): n = sqrt(G m0 / r^3) at its initial distance
    from the sun, Kepler's third law."""
    import math

    y0 = PROBLEM.y0(values)
    q = [y0[len(P_NAMES) + 3 * i: len(P_NAMES) + 3 * i + 3] for i in range(6)]
    r = min(math.dist(q[i], q[0]) for i in range(1, 6))
    return float(f"{r ** 1.5 / math.sqrt(values['G'] * values['m0']):.2g}")     # 2 digits: a plain h


def model(S):
    from sympy import sqrt

    m = [getattr(S, f"m{i}") for i in range(6)]
    p = [[getattr(S, f"p{i}{a}") for a in AXES] for i in range(6)]
    q = [[getattr(S, f"q{i}{a}") for a in AXES] for i in range(6)]
    kinetic = sum((p[i][0]**2 + p[i][1]**2 + p[i][2]**2) / (2 * m[i]) for i in range(6))
    potential = 0
    for i in range(1, 6):
        for j in range(i):
            dist = sqrt(sum((q[i][k] - q[j][k])**2 for k in range(3)))
            potential -= S.G * m[i] * m[j] / dist
    H = kinetic + potential                                               # [HLW] (2.12)
    L = [sum(q[i][(k + 1) % 3] * p[i][(k + 2) % 3] - q[i][(k + 2) % 3] * p[i][(k + 1) % 3]
             for i in range(6)) for k in range(3)]                        # sum q_i x p_i
    P = [sum(p[i][k] for i in range(6)) for k in range(3)]
    integrals = {"H": H, "Lx": L[0], "Ly": L[1], "Lz": L[2], "Px": P[0], "Py": P[1], "Pz": P[2]}
    return Model(hamiltonian=H, integrals=integrals)


def initial(v):
    m = [v[f"m{i}"] for i in range(6)]
    p = tuple(m[i] * VELOCITIES[i][k] for i in range(6) for k in range(3))   # p_i = m_i qdot_i
    q = tuple(POSITIONS[i][k] for i in range(6) for k in range(3))
    return p + q


PROBLEM = Problem(
    id="outer-solar-system",
    title="Outer solar system (sun + 5 outer planets)",
    reference="[HLW] I.2.4, (2.12), Table 2.2, Fig 2.4",
    state=P_NAMES + Q_NAMES,
    params=(Param("G", G, "gravitational constant (AU^3 / (solar mass day^2))", low=0.0,
                  low_open=True),)
    + tuple(Param(f"m{i}", MASSES[i], f"mass of body {i} ({BODIES[i]}), solar masses", low=0.0,
                  low_open=True) for i in range(6)),
    model=model,
    initial=initial,
    canonical=(P_NAMES, Q_NAMES),
    time_scale=time_scale,
    notes="(choice) state order p0x, p0y, p0z, ..., p5z, q0x, ..., q5z (bodies 0 sun, 1 Jupiter, "
          "2 Saturn, 3 Uranus, 4 Neptune, 5 Pluto). Table 2.2 gives velocities: p_i = m_i qdot_i; "
          "the sun starts at rest at the origin. Time unit: days. Time scale (default h and "
          "dt_out are 0.01 of it): 1/n of Jupiter, ~730 days.",
)
