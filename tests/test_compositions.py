"""Conditions on the composition coefficients (methods/compositions.py); their orders are measured in
tests/test_orders.py.

For a symmetric composition Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h} of a symmetric method Φ of order 2
(Störmer–Verlet), order p requires Σ γ_i = 1 and Σ γ_i^(2k+1) = 0 for 2k + 1 < p (the conditions
of the trees with one vertex, [HLW] V.3.2; the full set has more for p >= 6). Measured residuals:
Kahan–Li and Suzuki to 1e-16 (26 digits, closed form), Yoshida's 15-digit data to 2.7e-12; and
the first sum beyond the order is far from 0 (>= 7.5e-4).
"""
from __future__ import annotations

import pytest
from gnibench.methods import METHODS
from gnibench.methods import compositions as c

SV = {"yoshida4": (c.YOSHIDA4, 1e-14), "yoshida6": (c.YOSHIDA6, 1e-12), "yoshida8": (c.YOSHIDA8, 1e-11),
      "suzuki4": (c.SUZUKI4, 1e-14), "kahan-li6": (c.KAHAN_LI6, 1e-14), "kahan-li8": (c.KAHAN_LI8, 1e-14)}


@pytest.mark.parametrize("mid", sorted(SV))
def test_symmetric_composition_conditions(mid):
    gammas, tol = SV[mid]
    order = METHODS[mid].order
    assert gammas == tuple(reversed(gammas)) and METHODS[mid].data == gammas
    assert abs(sum(gammas) - 1.0) < 1e-14
    for k in range(3, order, 2):
        assert abs(sum(g ** k for g in gammas)) < tol, k
    assert abs(sum(g ** (order + 1) for g in gammas)) > 5e-4


def test_mclachlan_is_symmetric_and_consistent():
    """Φ*_{α_5 h} ∘ Φ_{β_5 h} ∘ … with β_i = α_{6-i}: Σ (α_i + β_i) = 1, Σ α_i = Σ β_i = 1/2."""
    pairs = c.MCLACHLAN4
    assert len(pairs) == 5 and METHODS["mclachlan4"].data == pairs
    assert abs(sum(b for b, _ in pairs) - 0.5) < 1e-15 and abs(sum(a for _, a in pairs) - 0.5) < 1e-15
    assert [b for b, _ in pairs] == [a for _, a in reversed(pairs)]
    assert c.substeps(c.YOSHIDA4) == tuple((0.5 * g, 0.5 * g) for g in c.YOSHIDA4)
