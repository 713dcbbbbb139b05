"""Partial first integrals [B] §2, (2.12)-(2.13), on the Hess case of the heavy top.

1. Symbolic: h = e.M is a partial first integral, D_h F = l h with l = -kappa M2/B, and H, Mg, gg
   are first integrals (problems/heavy_top_hess.py derives them); the generated code agrees.
2. Main Lemma for (PPP): along ξ' = F + D_hᵀ (D_h D_hᵀ)⁻¹ [K (0 − h) − l h] (the reading of (2.13)
   in methods/modifiers.py), d/dt h = l h − θ h − l h = −θ h, so from h(x0) = 1e-6 rk4 at small step
   follows h0 e^{−θt}; the plain method follows h0 exp(∫ l), which does not decay.
3. On Γ0 = {h = 0}: the observer keeps |h| at the rounding level of h. (Measured: h is linear in the
   state and D_h F = l h, so every Runge-Kutta method maps Γ0 into itself up to rounding; the plain
   rk4 drift is rounding amplified by the transverse dynamics, ~1e-14 at t = 1e4, not a truncation
   drift.)
"""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.problems import REGISTRY
from gnibench.problems.codegen import problem_meta, python_functions, symbolic
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import parse_method, parse_problem
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.invariants import invariant_errors

PID = "heavy-top-hess"
THETA = 2.0
T_END = 6.0
H_OFF = 1e-6


def _record():
    return REGISTRY[PID]


def _values():
    return {p.name: p.default for p in _record().params}


def _partials_sympy():
    """(state symbols, rhs, integrals, {name: (h, l)}) of the problem."""
    from types import SimpleNamespace

    import sympy as sp

    rec = _record()
    ys, ps, rhs, integrals = symbolic(rec)
    # positive parameters: sqrt((A - B) ...) simplifies under A > B > C > 0
    a, b, c = sp.symbols("a b c", positive=True)
    A, B, C = c + a + b, c + b, c                   # A > B > C > 0 by construction
    names = dict(zip(rec.model_params, ps))
    sub = {names["A"]: A, names["B"]: B, names["C"]: C}
    ns = SimpleNamespace(**dict(zip(rec.state, ys)), **{k: v for k, v in names.items()})
    partial = rec.model(ns).partial_integrals
    return ys, [e.subs(sub) for e in rhs], {k: v.subs(sub) for k, v in integrals.items()}, \
        {k: (h.subs(sub), lv.subs(sub)) for k, (h, lv) in partial.items()}


def test_hess_relation_is_a_partial_first_integral():
    """D_h F − l h = 0 identically ([B] (2.12), q = 1), and D_H F = 0 for H, Mg, gg."""
    import sympy as sp

    ys, rhs, integrals, partial = _partials_sympy()
    F = sp.Matrix(rhs)
    h, lv = partial["h"]
    Dh = sp.Matrix([h]).jacobian(ys)
    assert sp.simplify((Dh * F)[0] - lv * h) == 0
    assert sp.simplify((Dh * F)[0]) != 0              # not a first integral: l is not 0
    for name, H in integrals.items():
        assert sp.simplify((sp.Matrix([H]).jacobian(ys) * F)[0]) == 0, name


def test_generated_partial_functions():
    """partial_0, pgrad_0 and pl_0 of the generated code against numpy at a random point."""
    rec, v = _record(), _values()
    meta = problem_meta(rec)
    assert meta["partial_integrals"] == ["h"] and meta["partial_L_nonzero"] == [[True]]
    fns = python_functions(rec)
    par = rec.par(v)
    A, B, C = v["A"], v["B"], v["C"]
    y = tuple(np.random.default_rng(1).normal(size=6))
    n1, n3 = np.sqrt(C * (A - B)), -np.sqrt(A * (B - C))
    e = np.array([n1, 0.0, n3]) / np.hypot(n1, n3)
    assert fns["partial_0"](y, par) == pytest.approx(e @ np.array(y[:3]), abs=1e-15)
    assert np.allclose(fns["pgrad_0"](y, par), np.r_[e, 0, 0, 0], atol=1e-15)
    kappa = np.sqrt((A - B) * (B - C) / (A * C))
    assert fns["pl_0"](y, par)[0] == pytest.approx(-kappa * y[1] / B, rel=1e-14)
    # the default start lies on Gamma_0
    assert abs(fns["partial_0"](rec.y0(v), par)) < 1e-15


def _h_along(y):
    rec = _record()
    fns, par = python_functions(rec), rec.par(_values())
    return np.array([fns["partial_0"](tuple(row), par) for row in y])


def _off_start() -> str:
    """Problem spec starting at h(x0) = H_OFF: M1 moved by H_OFF / e1."""
    rec, v = _record(), _values()
    e1 = python_functions(rec)["pgrad_0"](rec.y0(v), rec.par(v))[0]
    return f"{PID}:M10={rec.y0(v)[0] + H_OFF / e1!r}"


@pytest.mark.parametrize("method,tol", [("rk4:h=0.01", 1e-14), ("implicit-midpoint:h=0.005", 1e-10)])
def test_main_lemma_partial(method, tol):
    """[B] (2.13): h(t) = h0 e^{−θt} under the observer; the plain method does not decay.

    Measured: rk4 h = 0.01 max |h − h0 e^{−θt}| = 5e-16 (rounding of h = e.M, |M| ~ 1), fitted rate
    2.00000003; implicit midpoint h = 0.005 (its Newton uses the leading Jacobian −D_hᵀ G⁻¹ (θ + l) D_h)
    3e-12, its own O(h²) error on the decay. Plain: |h| stays in [3.5e-7, 1e-6] (h0 exp ∫ l).
    """
    prob = _off_start()
    r = solve(prob, f"{method}+observer:on=h,theta={THETA}", t_end=T_END, every=10)
    assert r.status == "ok", r.reason
    h = _h_along(r.y)
    exact = H_OFF * np.exp(-THETA * r.t)
    assert h[0] == pytest.approx(H_OFF, rel=1e-9)
    assert np.max(np.abs(h - exact)) < tol
    m = np.abs(h) > 1e-4 * H_OFF                     # above the rounding level of h
    rate = -np.polyfit(r.t[m], np.log(np.abs(h[m])), 1)[0]
    assert abs(rate - THETA) < 1e-4, rate
    plain = _h_along(solve(prob, method, t_end=T_END, every=10).y)
    assert np.min(np.abs(plain)) > 0.1 * H_OFF      # h0 exp(∫ l): stays off Γ0


def test_mixed_observer_decays_both():
    """First and partial integrals observed together: ε_H = H0 − H and h both decay at their θ."""
    prob = _off_start()
    r = solve(prob, "rk4:h=0.01+observer:on=h/H,theta=3/1.5,H0=-0.5", t_end=T_END, every=10)
    assert r.status == "ok", r.reason
    h = _h_along(r.y)
    assert np.max(np.abs(h - H_OFF * np.exp(-3.0 * r.t))) < 1e-14
    eps = -0.5 - (invariant_errors(r)[:, 0] + r.provenance["H0"][0])
    err = np.max(np.abs(eps - eps[0] * np.exp(-1.5 * r.t)))
    assert err < 1e-9 * abs(eps[0]), (err, eps[0])


def test_observer_keeps_orbit_on_gamma0():
    """From the default start on Γ0: over t = 1e4 the observer keeps |h| at its rounding level."""
    plain = solve(PID, "rk4:h=0.1", t_end=1e4, every=100)
    obs = solve(PID, "rk4:h=0.1+observer:on=h,theta=1", t_end=1e4, every=100)
    assert plain.status == obs.status == "ok"
    hp, ho = np.abs(_h_along(plain.y)), np.abs(_h_along(obs.y))
    assert ho.max() < 1e-15
    assert hp.max() > ho.max()
    # the observer does not touch the dynamics on Γ0: the first integrals behave alike
    assert np.allclose(np.abs(invariant_errors(obs)).max(0), np.abs(invariant_errors(plain)).max(0),
                       rtol=1e-3)


def test_resolve_partial_names():
    prob = parse_problem(PID)
    cfg = parse_method("rk4:h=0.1+observer:on=h/H,theta=3/1.5", prob)
    assert cfg.text() == "rk4:h=0.1+observer:mode=simple,on=H,partial=h,theta=1.5/3"
    assert parse_method(cfg.text(), prob).text() == cfg.text()
    assert parse_method("rk4+observer:on=h", prob).text().endswith("observer:mode=simple,partial=h,theta=1")
    with pytest.raises(UserError, match="only the observer"):
        parse_method("rk4+penalty:on=h", prob)
    with pytest.raises(UserError, match="target"):
        parse_method("rk4+observer:on=h,H0=1", prob)
    with pytest.raises(UserError, match=r"h \(partial\)"):
        parse_method("rk4+observer:on=x", prob)
