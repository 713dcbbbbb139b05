"""Euler equations on the Lie algebra so(4), non-Manakov case, [B] §7, (7.1)-(7.7).

x' given by (7.1), the Euler equations of the "Hamiltonian" (1/2) sum lambda_i x_i^2; first integrals
H1 = x1 x4 + x2 x5 + x3 x6, H2 = sum x_i^2 (the Casimirs) and H3 = sum lambda_i x_i^2  [B] (7.2).
Not canonical and no partition: partitioned methods refuse it.

Default data [B] (7.3)-(7.4): lambda = (1, 5, 2, 1, 3, 4), level M(h1, h2, h3) = M(1, 15, 25).

Section (reading, catalog note): the text says "x3 = 0", but the point X = (x1, 0, x3, ...) and (7.5)
show that the section is x2 = 0. On it, with lambda1 = lambda4 = l:
  (lambda3 - l) x3^2 = h3 - l h2 - (lambda5 - l) x5^2 - (lambda6 - l) x6^2,  x3 = eps sqrt(.)   (7.5)
  x1 x4 = h1 - x3 x6 = P,   x1^2 + x4^2 = h2 - x3^2 - x5^2 - x6^2 = S                     (7.6)-(7.7)
  x1 + x4 = eta sqrt(S + 2P),   x1 - x4 = theta sqrt(S - 2P),
so (x5, x6) and the signs (eps, eta, theta) of (x3, x1 + x4, x1 - x4) fix the point.
(choice) Charts Gamma_1..Gamma_8 list the sign triples in lexicographic order, - before +:
Gamma_1 = (-,-,-), Gamma_2 = (-,-,+), ..., Gamma_8 = (+,+,+) (what the OCR'd table suggests);
k = 1 + 4[eps = +] + 2[eta = +] + [theta = +], a zero counting as +.
(choice) The section is crossed with x2' < 0; the recorded coordinates are (x5, x6) and the chart k.
The symmetry (x2, x3, x5, x6) -> -(x2, x3, x5, x6) of (7.1)-(7.2) maps x2' < 0 crossings in
Gamma(eps, eta, theta) at (x5, x6) to x2' > 0 crossings in Gamma(-eps, eta, theta) at (-x5, -x6), so the
direction only relabels the charts; with x2' < 0 the default chaotic orbit crosses mostly in Gamma_1
(244548 of its 335024 crossings up to t = 400000, RK4 h = 0.01), the chart [B] draws in Fig 26
(with x2' > 0 it would fill Gamma_5 instead).

The initial point is built on the level from the options chart, sec_x5, sec_x6 (x2 = 0). (choice)
Default: chart 1 (the chart of Fig 26), (x5, x6) = (0.5, 0.5), i.e. x = (-2.0811, 0, -2.9580,
-1.1912, 0.5, 0.5), itself a crossing with x2' < 0. [B] does not give its "one chaotic orbit"; this
point was picked from a scan of Gamma_1 on a 0.2-grid of (x5, x6) (RK4, h = 0.01, two nearby
orbits): finite-time Lyapunov exponents at t = 2000 split into regular points (< 0.1) and the chaotic
sea (0.3-0.8); at (0.5, 0.5) it is 0.50 at t = 10000, and the orbit's section fills the chaotic
region of Gamma_1 around islands.
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.problems.base import Model, Problem, Section, require
from gnibench.suite.foundation.params import Param

LAMBDA = (1.0, 5.0, 2.0, 1.0, 3.0, 4.0)          # [B] (7.3)
LEVEL = (1.0, 15.0, 25.0)                         # [B] (7.4)
DEFAULT_CHART, DEFAULT_X5, DEFAULT_X6 = 1, 0.5, 0.5


def model(S):
    x1, x2, x3, x4, x5, x6 = (S.x1, S.x2, S.x3, S.x4, S.x5, S.x6)
    l1, l2, l3, l4, l5, l6 = (S.lam1, S.lam2, S.lam3, S.lam4, S.lam5, S.lam6)
    rhs = ((l3 - l2) * x2 * x3 + (l6 - l5) * x5 * x6,                  # [B] (7.1)
           (l1 - l3) * x1 * x3 + (l4 - l6) * x4 * x6,
           (l2 - l1) * x1 * x2 + (l5 - l4) * x4 * x5,
           (l3 - l5) * x3 * x5 + (l6 - l2) * x2 * x6,
           (l4 - l3) * x3 * x4 + (l1 - l6) * x1 * x6,
           (l2 - l4) * x2 * x4 + (l5 - l1) * x1 * x5)
    xs = (x1, x2, x3, x4, x5, x6)
    lams = (l1, l2, l3, l4, l5, l6)
    H1 = x1 * x4 + x2 * x5 + x3 * x6                                    # [B] (7.2)
    H2 = sum(x**2 for x in xs)
    H3 = sum(lam * x**2 for lam, x in zip(lams, xs))
    return Model(rhs=rhs, integrals={"H1": H1, "H2": H2, "H3": H3})


def chart_signs(k: int) -> tuple[int, int, int]:
    """(eps, eta, theta) of chart Gamma_k, k = 1..8 (catalog choice: lexicographic, - before +)."""
    b = k - 1
    return (1 if b & 4 else -1, 1 if b & 2 else -1, 1 if b & 1 else -1)


def chart(y) -> np.ndarray:
    """Chart index k (1..8) of points y (..., 6) of the section x2 = 0: signs of x3, x1+x4, x1-x4."""
    y = np.asarray(y, dtype=float)
    x1, x3, x4 = y[..., 0], y[..., 2], y[..., 3]
    return 1 + 4 * (x3 >= 0) + 2 * (x1 + x4 >= 0) + (x1 - x4 >= 0)


def section_terms(v) -> dict[str, float]:
    """x3^2, P, S of (7.5)-(7.7) for the chart coordinates (sec_x5, sec_x6) (needs lam1 = lam4)."""
    lam = [v[f"lam{i}"] for i in range(1, 7)]
    h1, h2, h3 = v["h1"], v["h2"], v["h3"]
    x5, x6 = v["sec_x5"], v["sec_x6"]
    l = lam[0]
    x3_sq = (h3 - l * h2 - (lam[4] - l) * x5**2 - (lam[5] - l) * x6**2) / (lam[2] - l)   # (7.5)
    eps, _, _ = chart_signs(int(v["chart"]))
    x3 = eps * math.sqrt(max(x3_sq, 0.0))
    P = h1 - x3 * x6                                                    # (7.6)
    S = h2 - x3 * x3 - x5 * x5 - x6 * x6                                # (7.7)
    return {"x3_sq": x3_sq, "x3": x3, "P": P, "S": S}


def initial(v):
    """The point of M(h1, h2, h3) with x2 = 0 in chart Gamma_k with coordinates (x5, x6)."""
    t = section_terms(v)
    _, eta, theta = chart_signs(int(v["chart"]))
    plus = eta * math.sqrt(max(t["S"] + 2 * t["P"], 0.0))             # x1 + x4
    minus = theta * math.sqrt(max(t["S"] - 2 * t["P"], 0.0))          # x1 - x4
    return ((plus + minus) / 2, 0.0, t["x3"], (plus - minus) / 2, v["sec_x5"], v["sec_x6"])


class EulerSO4(Problem):
    def validate(self, values):
        if all(values.get(f"x{i}0") is not None for i in range(1, 7)):
            return                                   # the whole point is given explicitly
        lam1, lam3, lam4 = values["lam1"], values["lam3"], values["lam4"]
        where = (f"euler-so4: chart {values['chart']}, (x5, x6) = ({values['sec_x5']:g}, "
                 f"{values['sec_x6']:g})")
        require(lam1 == lam4 and lam3 != lam1,
                f"euler-so4: the section chart construction (7.5)-(7.7) needs lam1 = lam4 != lam3 "
                f"(got lam1 = {lam1:g}, lam3 = {lam3:g}, lam4 = {lam4:g}); give x10..x60 instead")
        t = section_terms(values)
        require(t["x3_sq"] >= 0, f"{where} is not on the level M(h1, h2, h3): x3^2 = {t['x3_sq']:g} < 0 "
                                 "in (7.5); allowed: x3^2 >= 0")
        require(t["S"] + 2 * t["P"] >= 0 and t["S"] - 2 * t["P"] >= 0,
                f"{where} is not on the level M(h1, h2, h3): S = {t['S']:g}, P = {t['P']:g}, "
                f"S - 2|P| = {t['S'] - 2 * abs(t['P']):g} < 0 in (7.6)-(7.7); allowed: S >= 2|P|")


SECTION = Section(
    name="x2=0", g=lambda S: S.x2,
    condition=lambda S: -((S.lam1 - S.lam3) * S.x1 * S.x3 + (S.lam4 - S.lam6) * S.x4 * S.x6),  # -x2'
    coords=("x5", "x6"), reference="[B] §7.1, (7.5)-(7.7)", chart=chart, charts=8)

PROBLEM = EulerSO4(
    id="euler-so4",
    title="Euler equations on so(4), non-Manakov case",
    reference="[B] §7, (7.1)-(7.7), Figs 26-30",
    state=("x1", "x2", "x3", "x4", "x5", "x6"),
    params=tuple(Param(f"lam{i + 1}", LAMBDA[i], f"lambda_{i + 1} [B] (7.3)") for i in range(6))
    + (Param("h1", LEVEL[0], "level of H1 for the initial point [B] (7.4)"),
       Param("h2", LEVEL[1], "level of H2 for the initial point [B] (7.4)", low=0.0),
       Param("h3", LEVEL[2], "level of H3 for the initial point [B] (7.4)"),
       Param("chart", DEFAULT_CHART, "chart Gamma_k of the initial point (signs of x3, x1+x4, x1-x4)",
             kind="int", low=1, high=8),
       Param("sec_x5", DEFAULT_X5, "x5 of the initial point (chart coordinate, x2 = 0)"),
       Param("sec_x6", DEFAULT_X6, "x6 of the initial point (chart coordinate, x2 = 0)")),
    model=model,
    initial=initial,
    sections=(SECTION,),
    notes="lambda = (1,5,2,1,3,4) (non-Manakov), level (h1,h2,h3) = (1,15,25) [B] (7.3)-(7.4). "
          "(reading) the section is x2 = 0 (the text says x3 = 0). (choice) Gamma_1..Gamma_8 = sign "
          "triples of (x3, x1+x4, x1-x4) in lexicographic order, - before +; crossings with x2' < 0 "
          "(the default orbit then fills Gamma_1, as in Fig 26). (choice) default initial point: "
          "chart 1, (x5, x6) = (0.5, 0.5), in the chaotic region (finite-time Lyapunov exponent "
          "0.50 at t = 10000; regular orbits < 0.05).",
)
