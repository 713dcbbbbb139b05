"""Closed forms of the radial Kepler flow ([B] §4.1, (4.1)) and the runs checked against them.

On the level H1 = H0 < 0 of H1(r, p) = (p² + p_φ²/r²)/2 − μ/r the radial motion oscillates
between the roots of H0 r² + μ r − p_φ²/2 = 0 (p = 0),

    r_p, r_a = (μ ∓ √(μ² + 2 H0 p_φ²)) / (−2 H0),

with the period T = 2π a^{3/2}/√μ, a = μ/(−2 H0) (Kepler's third law). [B] §4.1, Fig 5: with the
simple observer "the computed orbit is always elliptic, exactly as in Figure 1": the extreme radii
of the last ten orbits of a run are compared with r_p and r_a.
"""
from __future__ import annotations

import math

import numpy as np


def apsides(mu: float, p_phi: float, H0: float) -> tuple[float, float, float]:
    """(r_p, r_a, T) of the bound radial Kepler orbit on H1 = H0 < 0 ([B] (4.1))."""
    root = math.sqrt(max(mu * mu + 2.0 * H0 * p_phi * p_phi, 0.0))
    a = mu / (-2.0 * H0)
    return (mu - root) / (-2.0 * H0), (mu + root) / (-2.0 * H0), 2 * math.pi * a ** 1.5 / math.sqrt(mu)


def kepler_radial_apsides(cells, samples) -> dict:
    """For every selected cell: the largest relative deviation of min r and max r over its last
    ten orbits from r_p and r_a, and sup H1 over the run (elliptic: < 0). Worst (``deviation``)
    and best (``best``) over the cells, e.g. the points of a sweep over μ, p_φ."""
    from gnibench.suite.cell.spec import parse_problem

    worst, best, sup_h, parts = 0.0, math.inf, -math.inf, []
    for _, row in cells.iterrows():
        values = parse_problem(row["problem"]).values
        mu, p_phi, H0 = values["mu"], values["p_phi"], values["H0"]
        r_p, r_a, period = apsides(mu, p_phi, H0)
        rows = samples[samples["cell"] == row["cell"]]
        t, r = rows["t"].to_numpy(float), rows["r"].to_numpy(float)
        last = t >= t[-1] - 10 * period
        dev = max(abs(np.min(r[last]) - r_p) / r_p, abs(np.max(r[last]) - r_a) / r_a)
        dev = dev if np.all(np.isfinite(r)) else math.inf
        h = float(np.max(H0 + rows["err_H"].to_numpy(float)))
        worst, best, sup_h = max(worst, dev), min(best, dev), max(sup_h, h)
        parts.append(f"{row['problem']}: apsides {dev:.2g}, sup H1 {h:.4g}")
    return {"deviation": float(worst), "best": float(best), "sup_H": float(sup_h),
            "_detail": "; ".join(parts)}


CLOSED_FORMS = {"kepler_radial_apsides": kepler_radial_apsides}
