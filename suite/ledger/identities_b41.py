"""Checks of [B] §4.1 that need the step-by-step history of a short run (ten orbits of the radial
Kepler problem (4.1)): where in the orbit the computed H̃1 changes. A small computation, not a
long integration, so it lives beside the identity checks (:mod:`.identities`).

The problems are those of the ledger's sweep over the open μ, p_φ (experiment ``ledger-b-4.1``):
each check is made on every one and reports the worst.
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.ledger.closed_forms_b41 import apsides

#: the sweep over the open μ, p_φ of [B] §4.1 (suite/experiments/ledger-b-4.1.toml)
SWEEP = ("kepler-radial", "kepler-radial:mu=2,p_phi=2", "kepler-radial:mu=4,p_phi=4",
         "kepler-radial:p_phi=1.09", "kepler-radial:p_phi=0.8")
ORBITS = 10
WITHIN = 0.05            # of a period (claim B-4.1-e, proposed)


def _fractions(method: str, peaks_of: str) -> dict:
    """Per problem: the fraction of the first ten orbits (pericenters k = 1..10, windows of one
    period around each) in which the event happens within ±5 % of a period of the pericenter
    passage (the local minimum of the computed r). ``peaks_of``: ``jump`` = the largest
    per-step increase of H̃1, ``peak`` = the largest |H̃1 − H0|."""
    from gnibench.suite.cell.solve import solve
    from gnibench.suite.cell.spec import parse_problem

    out = {}
    for spec in SWEEP:
        v = parse_problem(spec).values
        period = apsides(v["mu"], v["p_phi"], v["H0"])[2]
        traj = solve(spec, method, t_end=(ORBITS + 0.5) * period, every=1, reference="none")
        t, r, err = traj.t, traj.y[:, 0], traj.integrals[:, 0] - traj.H0[0]
        inner = np.flatnonzero((r[1:-1] < r[:-2]) & (r[1:-1] <= r[2:])) + 1
        hits = 0
        for k in inner[:ORBITS]:
            window = np.flatnonzero(np.abs(t - t[k]) <= period / 2)
            window = window[window > 0]
            if peaks_of == "jump":
                at = window[np.argmax(err[window] - err[window - 1])]
            else:
                at = window[np.argmax(np.abs(err[window]))]
            hits += abs(t[at] - t[k]) <= WITHIN * period
        out[spec] = hits / max(len(inner[:ORBITS]), 1)
    return out


def _result(fractions: dict) -> dict:
    detail = "; ".join(f"{k}: {v:.2f}" for k, v in fractions.items())
    return {"measured": float(min(fractions.values())), "best": float(max(fractions.values())),
            "catalog": float(fractions["kepler-radial"]), "_detail": detail}


def euler_jumps_at_pericenter() -> dict:
    """[B] §4.1, Fig 3: Euler's jumps of H̃1 happen at the pericenter passages."""
    return _result(_fractions("euler:h=0.01", "jump"))


def observer_variations_at_pericenter() -> dict:
    """[B] §4.1, Fig 5: with the simple observer (θ = 1) "the strong variations of this error are
    related to the passage through the pericenter": the largest per-step change of H̃1 in each
    orbit. Also (``peak``, worst over the sweep) where |H̃1 − H0| is largest: the relaxation at
    rate θ makes the peak lag the passage."""
    method = "euler:h=0.01+observer:on=H,theta=1"
    out = _result(_fractions(method, "jump"))
    peaks = _fractions(method, "peak")
    out["peak"] = float(min(peaks.values()))
    out["_detail"] += " (largest |H̃1 − H0| within 5 % of a period: " + "; ".join(
        f"{k}: {v:.2f}" for k, v in peaks.items()) + ")"
    return out


CHECKS = {"euler_jumps_at_pericenter": euler_jumps_at_pericenter,
          "observer_variations_at_pericenter": observer_variations_at_pericenter}
