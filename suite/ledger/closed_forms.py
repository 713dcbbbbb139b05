"""Closed forms derived from a method's map or from the flow, and the runs checked against them.

Each function takes the selected cells (rows of ``cells.parquet``) and the samples table and
returns named values for the claim's ``measured`` and ``passes`` expressions.

**Explicit Euler on the oscillators, with or without the simple observer** ([B] §3 end, §4.2).
For H = Σ_k E_k, E_k = (q_k² + p_k²)/2, Euler maps each oscillator's block y_k (the pair
(q_k, p_k), y_k' = J y_k with |J y_k| = |y_k| and y_k·J y_k = 0) to (1 + h s_k) y_k + h J y_k, where
h s_k y_k is the block's part of the observer term D_Hᵀ G⁻¹ K (H0 − H) ([B] (2.5)): ∇E_k = y_k, so
every observed integral H_j = Σ_k c_jk E_k has gradient blocks c_jk y_k, G_ij = Σ_k c_ik c_jk 2E_k
and s_k = Σ_j c_jk (G⁻¹ K (H0 − H))_j. Hence the exact recurrence on the energies

    E_k <- E_k ((1 + h s_k)² + h²),        (plain Euler: s = 0, E_k <- E_k (1 + h²))

which the runs must follow to round-off. For one oscillator observed with gain θ the fixed point
R of H <- H((1 + hθ(H0 − H)/(2H))² + h²) is

    R(h, θ) = H0 hθ / (hθ − 2(1 − √(1 − h²)))  >  H0,   R − H0 ≈ H0 h/θ  (so R -> H0 as h -> 0),

which exists for hθ > 2(1 − √(1 − h²)) ≈ h² (the seed's "2h < θ" is sufficient) and attracts
when |f'(R)| < 1 for the map f above ([B] end of §3).

**Main Lemma** ([B] (2.8)): along the exact flow of (2.5) with the simple observer,
ε = H0 − H obeys ε' = −K ε exactly (D_H F = 0), so ε_i(t) = ε_i(0) e^{−θ_i t}.
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.suite.ledger import (closed_forms_b7, closed_forms_b41, closed_forms_hlw,
                                   closed_forms_locator)
from gnibench.suite.ledger.closed_forms_b6 import gs_section_trace
from gnibench.suite.runs.tables import modifier_ids

#: integrals of the oscillator problems as combinations of the per-oscillator energies E_k
_ENERGIES = {"harmonic-oscillator": {"states": (("q", "p"),), "H": (1.0,)},
             "double-oscillator": {"states": (("q1", "p1"), ("q2", "p2")),
                                   "H1": (1.0, 0.0), "H2": (1.0, 1.0)}}


def _method(text: str):
    """(h, {observed integral: theta}, mode) of an 'euler[+observer...]' canonical spec."""
    from gnibench.suite.cell.spec import parse_method

    method = parse_method(text)
    if method.id != "euler":
        raise ValueError(f"the closed form is for explicit Euler, not {method.id}")
    observed, mode = {}, "simple"
    for m in method.modifiers:
        if m.id != "observer":
            raise ValueError(f"the closed form covers the observer only, not +{m.id}")
        mode = m.values["mode"]
        on = list(m.values["on"])
        theta = list(m.values["theta"])
        theta = theta * len(on) if len(theta) == 1 else theta
        observed = dict(zip(on, theta))
    if mode != "simple":
        raise ValueError("the closed form is for the simple observer")
    return float(method.base.values["h"]), observed


def energy_recurrence(problem_id: str, E0: np.ndarray, h: float, observed: dict,
                      targets: dict, steps: int) -> np.ndarray:
    """Energies E_k after 0..steps Euler steps (rows), by the recurrence above."""
    spec = _ENERGIES[problem_id]
    names = [k for k in spec if k != "states"]
    C = np.array([spec[n] for n in names])                     # c_jk
    obs = [names.index(n) for n in observed]
    theta = np.array(list(observed.values()))
    H0 = np.array([targets[n] for n in observed])
    out = np.empty((steps + 1, len(E0)))
    E = np.array(E0, dtype=float)
    out[0] = E
    for n in range(1, steps + 1):
        s = np.zeros(len(E))
        if obs:
            Co = C[obs]
            G = (Co * (2 * E)) @ Co.T
            coeff = np.linalg.solve(G, theta * (H0 - Co @ E))
            s = Co.T @ coeff
        E = E * ((1 + h * s) ** 2 + h * h)
        out[n] = E
    return out


def euler_oscillator_energy(cells, samples) -> dict:
    """Max relative deviation of the runs' integrals from the recurrence, over the samples of the
    selected cells; also the fitted and closed-form growth rates of ln|err| per step."""
    deviation, rates, closed = 0.0, [], []
    for row in cells.itertuples():
        pid = row.problem_id
        spec = _ENERGIES[pid]
        names = [k for k in spec if k != "states"]
        h, observed = _method(row.method)
        rows = samples[samples["cell"] == row.cell]
        steps = rows["steps"].to_numpy(dtype=int)
        E = np.column_stack([(rows[q].to_numpy() ** 2 + rows[p].to_numpy() ** 2) / 2
                             for q, p in spec["states"]])
        C = np.array([spec[n] for n in names])
        H_run = E @ C.T
        targets = dict(zip(names, H_run[0]))
        pred = energy_recurrence(pid, E[0], h, observed, targets, int(steps[-1]))[steps] @ C.T
        deviation = max(deviation, float(np.max(np.abs(H_run - pred) / np.abs(pred))))
        err = np.abs(H_run - H_run[0])
        half = len(steps) // 2
        if not observed and len(steps) > 3 and np.all(err[half:] > 0):
            slope = np.polyfit(steps[half:], np.log(err[half:, 0] + H_run[0, 0]), 1)[0]
            rates.append(slope)
            closed.append(math.log1p(h * h))
    out = {"deviation": deviation, "cells": float(len(cells))}
    if rates:
        out["rate"] = float(np.max(np.abs(np.array(rates) / np.array(closed) - 1)))
    return out


def observer_limit(h: float, theta: float, H0: float) -> tuple[float, float]:
    """R(h, θ) and |f'(R)| of the energy map of Euler + simple observer on one oscillator."""
    denominator = h * theta - 2 * (1 - math.sqrt(1 - h * h))
    if denominator <= 0:
        return math.inf, math.inf
    R = H0 * h * theta / denominator

    def f(H):
        return H * ((1 + h * theta * (H0 - H) / (2 * H)) ** 2 + h * h)

    d = 1e-7 * R
    return R, abs((f(R + d) - f(R - d)) / (2 * d))


def euler_observer_limit(cells, samples) -> dict:
    """The last sample's H against R(h, θ) over the attracting grid points; R > H0 everywhere;
    the exponents in h of R − H0 (closed form) and of H_N − H0 (runs) at fixed θ, and their
    difference (R -> H0 as h -> 0, [B] end of §3). A grid point whose fixed point does not
    attract (|f'(R)| ≥ 1) may diverge; ``failed_attracting`` counts the runs that did not end
    ``ok`` although R attracts (the closed form says they must converge): it must be 0."""
    worst, above, used, points, failed = 0.0, math.inf, 0, [], 0
    for row in cells.itertuples():
        h, observed = _method(row.method)
        (theta,) = observed.values()
        rows = samples[samples["cell"] == row.cell]
        H = (rows["q"].to_numpy() ** 2 + rows["p"].to_numpy() ** 2) / 2
        R, slope = observer_limit(h, theta, H[0])
        above = min(above, (R - H[0]) / H[0])
        if getattr(row, "status", "ok") != "ok":
            failed += slope < 1
            continue
        if slope < 1:
            used += 1
            worst = max(worst, abs(H[-1] - R) / H[0])
            points.append((theta, h, R - H[0], H[-1] - H[0]))

    def exponent(k):
        by_theta: dict[float, list] = {}
        for p in points:
            by_theta.setdefault(p[0], []).append((p[1], p[k]))
        fits = [np.polyfit(np.log([h for h, _ in v]), np.log([g for _, g in v]), 1)[0]
                for v in by_theta.values() if len(v) >= 2 and all(g > 0 for _, g in v)]
        return float(np.mean(fits)) if fits else math.nan

    closed, runs = exponent(2), exponent(3)
    return {"deviation": worst, "above": above, "attracting": float(used),
            "exponent": closed, "exponent_runs": runs, "exponent_gap": abs(closed - runs),
            "failed_attracting": float(failed), "cells": float(len(cells))}


def euler_observer_improvement(cells, samples) -> dict:
    """[B] §4.2, Fig 8(b), claim B-4.2-g: the observer on H1 only improves the non-observed
    H2. The selected cells are plain Euler (``label=Euler h=1e-3``) and Euler + observer on H1;
    at every sample after the first (same steps in both): ``improved`` = 1 when |err_H2| of the
    observed run is below plain Euler's everywhere; ``ratio_final`` = their ratio at the end;
    ``ratio_deviation`` = the largest relative deviation of the runs' ratio from the ratio the
    recurrence E_k <- E_k((1 + h s_k)² + h²) predicts (closed form, module docstring)."""
    def observes(r) -> bool:
        return "observer" in modifier_ids(r.modifiers)

    plain = [r for r in cells.itertuples() if not observes(r)]
    observed = [r for r in cells.itertuples() if observes(r)]
    if len(plain) != 1 or len(observed) != 1:
        raise LookupError("select one plain Euler cell and one Euler + observer cell")
    (p,), (o,) = plain, observed
    pid = o.problem_id
    spec = _ENERGIES[pid]
    names = [k for k in spec if k != "states"]
    C = np.array([spec[n] for n in names])
    rp, ro = samples[samples["cell"] == p.cell], samples[samples["cell"] == o.cell]
    steps = ro["steps"].to_numpy(dtype=int)
    if not np.array_equal(steps, rp["steps"].to_numpy(dtype=int)):
        raise LookupError("the two runs are not sampled at the same steps")
    e_p, e_o = np.abs(rp["err_H2"].to_numpy()), np.abs(ro["err_H2"].to_numpy())
    E0 = np.array([(ro[q].iloc[0] ** 2 + ro[pp].iloc[0] ** 2) / 2 for q, pp in spec["states"]])
    targets = dict(zip(names, C @ E0))
    h, obs = _method(o.method)
    hp, _ = _method(p.method)
    n = int(steps[-1])
    H_o = energy_recurrence(pid, E0, h, obs, targets, n)[steps] @ C.T
    H_p = energy_recurrence(pid, E0, hp, {}, targets, n)[steps] @ C.T
    k = names.index("H2")
    with np.errstate(all="ignore"):
        predicted = np.abs(H_o[:, k] - H_o[0, k]) / np.abs(H_p[:, k] - H_p[0, k])
        ratio = e_o / e_p
        later = steps > 0
        dev = float(np.max(np.abs(ratio[later] / predicted[later] - 1))) if later.any() else math.nan
    return {"improved": float(bool(later.any() and np.all(e_o[later] < e_p[later]))),
            "ratio_final": float(ratio[-1]), "ratio_predicted": float(predicted[-1]),
            "ratio_deviation": dev, "cells": float(len(cells))}


def main_lemma_decay(cells, samples) -> dict:
    """Slopes of ln|ε_i| against t (they must be −θ_i) and the worst violation of (2.8),
    max (‖ε(t)‖ − 4 ulp(H0)) / (‖ε(0)‖ e^{−ηt}) − 1 (ε is known to the round-off of the integrals)."""
    from gnibench.problems.codegen import problem_meta, python_functions
    from gnibench.suite.cell.spec import parse_method, parse_problem

    slope_error, violation = 0.0, -math.inf
    for row in cells.itertuples():
        problem = parse_problem(row.problem)
        opts = parse_method(row.method).modifiers[0].values
        on = list(opts["on"])
        theta = np.array(opts["theta"], dtype=float) * np.ones(len(on))
        targets = np.array(opts["H0"], dtype=float) * np.ones(len(on))
        rows = samples[samples["cell"] == row.cell]
        fns = python_functions(problem.record)
        names = problem_meta(problem.record)["integrals"]
        I0 = np.array(fns["invariants"](tuple(problem.record.y0(problem.values)),
                                        problem.record.par(problem.values)))
        t = rows["t"].to_numpy()
        eps = np.column_stack([targets[i] - (I0[names.index(n)] + rows[f"err_{n}"].to_numpy())
                               for i, n in enumerate(on)])
        for i in range(len(on)):
            ok = np.abs(eps[:, i]) > 1e-12 * max(1.0, abs(targets[i]))
            if ok.sum() >= 3:
                s = np.polyfit(t[ok], np.log(np.abs(eps[ok, i])), 1)[0]
                slope_error = max(slope_error, abs(s + theta[i]) / theta[i])
        norm = np.linalg.norm(eps, axis=1)
        bound = norm[0] * np.exp(-theta.min() * t)
        # beyond the round-off of the integral values themselves (4 ulp of the targets)
        rounding = 4 * np.finfo(float).eps * float(np.max(np.abs(targets)))
        ok = bound > 1e-12 * max(1.0, float(np.max(np.abs(targets))))
        violation = max(violation, float(np.max((norm[ok] - rounding) / bound[ok] - 1)))
    return {"slope_error": slope_error, "violation": violation, "cells": float(len(cells))}


CLOSED_FORMS = {
    "euler_oscillator_energy": euler_oscillator_energy,
    "euler_observer_limit": euler_observer_limit,
    "main_lemma_decay": main_lemma_decay,
    "euler_observer_improvement": euler_observer_improvement,
    "gs_section_trace": gs_section_trace,          # [B] §6.2 (closed_forms_b6.py)
    **closed_forms_hlw.CLOSED_FORMS,         # [HLW] Ch. I: returns, cycles, asymmetry, planets
}
CLOSED_FORMS.update(closed_forms_b7.CLOSED_FORMS)       # [B] §7.2 section statistics
CLOSED_FORMS.update(closed_forms_b41.CLOSED_FORMS)     # [B] §4.1: the radial Kepler apsides
CLOSED_FORMS.update(closed_forms_locator.CLOSED_FORMS)  # [B] §6.2: the located section points


def check_name(name: str) -> None:
    """KeyError for a closed form nobody defined."""
    if name not in CLOSED_FORMS:
        raise KeyError(f"unknown closed form {name!r} (known: {', '.join(CLOSED_FORMS)})")


def run(name: str, cells, samples) -> dict:
    check_name(name)
    if cells.empty:
        raise LookupError("no cell selected for the closed form")
    return CLOSED_FORMS[name](cells, samples)
