"""The Lie–Poisson splitting integrator for euler-so4 ([B] §7, methods/lie_poisson.py).

Checks: the six rotation fields add up to (7.1) and leave H1, H2 invariant (symbolic); observed
orders 2 (Strang) and 4 (Yoshida triple jump) against scipy's DOP853 at rtol = atol = 1e-13 on the
problem's generated field; the Casimirs H1 and H2 conserved to round-off (≤ 1e-13 relative) over
10^5 steps, H3 bounded without drift; refusal, with one-line UserErrors, of other problems, field
modifiers and bad orders.
"""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from gnibench.methods.lie_poisson import COMMUTING_GROUPS, ROTATIONS, schedule, split_field
from gnibench.problems import REGISTRY
from gnibench.problems.codegen import python_functions, symbolic
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import prepare
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.invariants import invariant_errors

PID = "euler-so4"
T = 1.0
N0 = 32
LEVELS = 7


def test_rotation_fields_add_up_to_the_euler_equations():
    """Σ_i λ_i x_i J(x) e_i = (7.1), and each field is tangent to the Casimir levels H1, H2."""
    ys, ps, rhs, integrals = symbolic(REGISTRY[PID])
    assert all(sp.expand(f - g) == 0 for f, g in zip(rhs, split_field(ys, ps[:6])))
    for i in range(6):
        lams = [ps[k] if k == i else 0 for k in range(6)]
        field = split_field(ys, lams)
        assert sp.expand(field[i]) == 0                       # x_i is constant along its own flow
        for name in ("H1", "H2"):
            H = integrals[name]
            assert sp.expand(sum(sp.diff(H, y) * f for y, f in zip(ys, field))) == 0, (i, name)
    assert sorted(k for planes in ROTATIONS for p in planes for k in p) == sorted(4 * list(range(6)))


def test_schedule_is_symmetric_and_consistent():
    """Each H^(i) flows for a total time h, and the sequence of commuting groups (1,4), (2,5), (3,6)
    is a palindrome (so the method is symmetric: flows within a group commute)."""
    for order in (2, 4):
        plan = schedule(order)
        for i in range(6):
            assert abs(sum(w for k, w in plan if k == i) - 1.0) < 1e-14
        groups = [next(g for g, grp in enumerate(COMMUTING_GROUPS) if k in grp) for k, _ in plan]
        assert groups == groups[::-1]
        assert np.allclose([w for _, w in plan], [w for _, w in reversed(plan)], rtol=0, atol=1e-15)
    assert (len(schedule(2)), len(schedule(4))) == (10, 28)


def _reference(y0) -> np.ndarray:
    from scipy.integrate import solve_ivp

    prob = REGISTRY[PID]
    par = tuple(prob.par({p.name: p.default for p in prob.params}))
    base_f = python_functions(prob)["base_f"]
    sol = solve_ivp(lambda t, y: base_f(tuple(y), par), (0.0, T), y0, method="DOP853",
                    rtol=1e-13, atol=1e-13)
    assert sol.success
    return sol.y[:, -1]


@pytest.mark.parametrize("order", [2, 4])
def test_observed_order(order):
    """Global error at T against DOP853: least-squares log-log slope of the finest 4 errors."""
    r0 = solve(PID, "lie-poisson:h=0.1", steps=1)
    ref = _reference(np.array(r0.y0))
    hs, errs = [], []
    for k in range(LEVELS):
        n = N0 * 2**k
        r = solve(PID, f"lie-poisson:h={T / n!r},order={order}", steps=n, every=n, reference="none")
        assert r.status == "ok" and abs(r.t[-1] - T) < 1e-12
        hs.append(T / n)
        errs.append(np.linalg.norm(r.y[-1] - ref))
    hs, errs = np.array(hs), np.array(errs)
    assert errs[-1] > 1e-11, "finest error near the reference's accuracy; the fit would be biased"
    p = np.polyfit(np.log(hs[-4:]), np.log(errs[-4:]), 1)[0]
    assert abs(p - order) <= 0.1, f"observed order {p:.3f}; errors {errs.tolist()}"


@pytest.mark.parametrize("order", [2, 4])
def test_casimirs_conserved_to_round_off(order):
    """10^5 steps of h = 0.005: |ΔH1|, |ΔH2| ≤ 1e-13 relative; H3 error bounded, no drift.

    The default orbit is chaotic, so the size of H3's O(h^order) oscillation varies along it; "no
    drift" is checked as: the second half's maximum within 3x the first half's, and the linear
    trend of the signed error over [0, T] below a quarter of its maximum.
    """
    steps = 100_000
    r = solve(PID, f"lie-poisson:h=0.005,order={order}", steps=steps, every=100, reference="none")
    assert r.status == "ok"
    err = invariant_errors(r)
    h1, h2, h3 = (r.integral_names.index(n) for n in ("H1", "H2", "H3"))
    y = r.y
    # scale of H1's rounding: the size of its terms along the orbit (|H1| = 1 is smaller)
    h1_scale = max(1.0, float(np.max(np.abs(y[:, 0] * y[:, 3]) + np.abs(y[:, 1] * y[:, 4])
                                     + np.abs(y[:, 2] * y[:, 5]))))
    h2_scale = float(np.max(np.sum(y**2, axis=1)))
    assert np.abs(err[:, h1]).max() <= 1e-13 * h1_scale, np.abs(err[:, h1]).max()
    assert np.abs(err[:, h2]).max() <= 1e-13 * h2_scale, np.abs(err[:, h2]).max()
    e3 = err[:, h3]
    half = len(e3) // 2
    top = np.abs(e3).max()
    assert top <= {2: 0.02, 4: 1e-4}[order], top
    assert np.abs(e3[half:]).max() <= 3.0 * np.abs(e3[:half]).max()
    assert abs(np.polyfit(r.t, e3, 1)[0] * r.t[-1]) <= 0.25 * top


@pytest.mark.parametrize("pid", ["pendulum", "kepler-2d", "double-oscillator"])
def test_refuses_other_problems(pid):
    with pytest.raises(UserError, match="needs the Euler equations on so\\(4\\)") as info:
        prepare(pid, "lie-poisson")
    assert "\n" not in str(info.value)


def test_refuses_field_modifiers_and_bad_orders():
    with pytest.raises(UserError, match="cannot take a field modifier"):
        solve(PID, "lie-poisson:h=0.01+observer", steps=2)
    with pytest.raises(UserError, match="allowed: one of 2\\|4"):
        prepare(PID, "lie-poisson:order=3")
    assert solve(PID, "lie-poisson:h=0.01+projection:on=H3", steps=10).status == "ok"
