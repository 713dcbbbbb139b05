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


def _level_deviation(mu: float, p_phi: float, H0: float, H: np.ndarray) -> float:
    """The largest relative deviation of the apsides of the levels H from those of H0 (the
    roots r_p < r_a of H1(r, p_r = 0) = H, [B] (4.1): monotone in H)."""
    r_p, r_a, _ = apsides(mu, p_phi, H0)
    if not (np.all(np.isfinite(H)) and np.all(H < 0)):
        return math.inf                       # a level that is not a bound orbit
    worst = 0.0
    for h in (float(np.min(H)), float(np.max(H))):
        p, a, _ = apsides(mu, p_phi, h)
        worst = max(worst, abs(p - r_p) / r_p, abs(a - r_a) / r_a)
    return worst


def kepler_radial_apsides(cells, samples) -> dict:
    """For every selected cell over its last ten orbits: ``deviation`` = the largest relative
    deviation of the sampled min r and max r from r_p and r_a (needs samples that resolve the
    apsides: many per orbit), and ``level_deviation`` = that of the apsides of the level H1 of
    every sample (a point of the 1-degree-of-freedom system [B] (4.1) lies on the exact orbit of its
    own level, so this is the orbit's shape whatever the sampling); ``samples_per_orbit``; and
    sup H1 over the run (elliptic: < 0). Worst and best (``best``, ``level_best``) over the
    cells, e.g. the points of a sweep over μ, p_φ."""
    from gnibench.suite.cell.spec import parse_problem

    worst, best, sup_h, parts = 0.0, math.inf, -math.inf, []
    level_worst, level_best, per_orbit = 0.0, math.inf, math.inf
    for _, row in cells.iterrows():
        values = parse_problem(row["problem"]).values
        mu, p_phi, H0 = values["mu"], values["p_phi"], values["H0"]
        r_p, r_a, period = apsides(mu, p_phi, H0)
        rows = samples[samples["cell"] == row["cell"]]
        t, r = rows["t"].to_numpy(float), rows["r"].to_numpy(float)
        H = H0 + rows["err_H"].to_numpy(float)
        last = t >= t[-1] - 10 * period
        dev = max(abs(np.min(r[last]) - r_p) / r_p, abs(np.max(r[last]) - r_a) / r_a)
        dev = dev if np.all(np.isfinite(r)) else math.inf
        level = _level_deviation(mu, p_phi, H0, H[last])
        h = float(np.max(H))
        worst, best, sup_h = max(worst, dev), min(best, dev), max(sup_h, h)
        level_worst, level_best = max(level_worst, level), min(level_best, level)
        per_orbit = min(per_orbit, float(np.sum(last)) / 10)
        parts.append(f"{row['problem']}: apsides sampled {dev:.2g}, of the levels {level:.2g} "
                     f"({np.sum(last) / 10:.3g} samples per orbit), sup H1 {h:.4g}")
    return {"deviation": float(worst), "best": float(best), "level_deviation": float(level_worst),
            "level_best": float(level_best), "samples_per_orbit": float(per_orbit),
            "sup_H": float(sup_h), "_detail": "; ".join(parts)}


CLOSED_FORMS = {"kepler_radial_apsides": kepler_radial_apsides}
