"""The order-condition checker (methods/order_conditions.py) and every shipped tableau against it.

The trees are counted against OEIS A000081; the checker is tested on tableaus with known orders and
known defects; then every Runge-Kutta tableau of the registry (and every embedded estimate, and
every continuous extension) is checked here without the cached verdicts of methods/tableau.py.
"""
from __future__ import annotations

import math
from fractions import Fraction as Fr

import pytest
from gnibench.methods import METHODS
from gnibench.methods import order_conditions as oc
from gnibench.methods.embedded_rk import Pair
from gnibench.methods.explicit_rk import RK4
from gnibench.methods.tableau import Tableau, tableau


def test_tree_counts_are_a000081():
    counts = [len(level) for level in oc.trees(12)]
    assert counts == [1, 1, 2, 4, 9, 20, 48, 115, 286, 719, 1842, 4766]
    # each tree once: no two representations of the same unordered tree
    assert all(len(set(level)) == len(level) for level in oc.trees(12))


def test_densities_and_notation():
    """The four trees of order 4 with Butcher's densities 4, 8, 12, 24 (HNW I, Table II.2.1)."""
    t4 = oc.trees(4)[3]
    assert sorted(oc.density(t) for t in t4) == [4, 8, 12, 24]
    assert sorted(oc.bracket(t) for t in t4) == sorted(["[τ³]", "[[τ],τ]", "[[τ²]]", "[[[τ]]]"])
    bushy = next(t for t in t4 if oc.density(t) == 8)
    assert oc.expression(bushy) == "Σ b_i c_i a_ij c_j"
    tall = ((((),),),)
    assert oc.density(tall) == math.factorial(4)


def test_rk4_has_order_4_and_the_order_5_failures_are_named():
    assert oc.check(RK4.a, RK4.b, RK4.c, 4) == []
    fails = oc.check(RK4.a, RK4.b, RK4.c, 5)
    text = [str(f) for f in fails]
    assert "order 5 condition for tree [τ⁴]: Σ b_i c_i⁴ = 5/24 ≠ 1/5" in text
    assert all(f.order == 5 for f in fails)
    assert oc.order_of(RK4.a, RK4.b) == 4


def test_a_wrong_digit_is_caught_and_reported_by_tree():
    a = [list(r) for r in RK4.a]
    a[2][1] = Fr(1, 2) + Fr(1, 10 ** 12)                   # the c_3 row no longer sums to 1/2
    fails = oc.check(a, RK4.b, RK4.c, 4)
    assert fails and str(fails[0]).startswith("row sum: Σ_j a_3j (row 3)")
    assert any(f.tree == "[[τ]]" for f in fails)           # Σ b_i a_ij c_j = 1/6 no longer holds
    with pytest.raises(ValueError, match=r"order 2 condition for tree \[τ\]: Σ b_i c_i"):
        tableau(a, RK4.b, [0, "1/2", Fr(1, 2) + Fr(1, 10 ** 12), 1], order=4)


def test_tolerance_for_decimal_data():
    """Decimal data: 1/3 to 50 digits satisfies Simpson's-rule conditions to ~1e-50, not exactly."""
    third = "0." + "3" * 50
    b = ["1/6", third[:-1] + "4", third, "1/6"]           # b_2 + b_3 = 2/3 within 1e-50
    assert oc.check(RK4.a, [Fr(x) if "/" in x else x for x in b], None, 4) != []
    assert oc.check(RK4.a, b, None, 4, tol=1e-45) == []


def test_surds():
    """Gauss-Legendre with two stages, exactly in Q(√3): order 4, not 5."""
    a = [["1/4", "1/4-1/6*sqrt(3)"], ["1/4+1/6*sqrt(3)", "1/4"]]
    c = ["1/2-1/6*sqrt(3)", "1/2+1/6*sqrt(3)"]
    assert oc.check(a, ["1/2", "1/2"], c, 4) == []
    assert oc.check(a, ["1/2", "1/2"], c, 5) != []
    x = oc.number("1/4-1/6*sqrt(3)")
    assert x * x == oc.number("7/48-1/12*sqrt(3)")
    assert abs(float(x) - (0.25 - 3 ** 0.5 / 6)) < 1e-16


def _tableaus():
    """Every Runge-Kutta tableau of the registry: (method id, tableau, estimate or None)."""
    out = []
    for mid, m in METHODS.items():
        data = m.data
        if isinstance(data, Tableau):
            out.append((mid, data, None))
        elif isinstance(data, Pair):
            out.append((mid, data.tab, data))
    return out


@pytest.mark.parametrize("mid,tab,pair", _tableaus(), ids=[t[0] for t in _tableaus()])
def test_every_shipped_tableau_has_its_order(mid, tab, pair):
    """The conditions up to the stated order hold (exactly, or within the tableau's tolerance for
    decimal or double data), recomputed here without any cached verdict; and not one order up
    (in floats: the smallest defect one order up, Vern8's b at order 9, is 4.2e-7; below the
    order the float residuals stay under 3.3e-11, Vern6's cancelling weights)."""
    assert oc.check(tab.a, tab.b, tab.c, tab.order, tab.tol) == []
    assert _float_defect(tab.a, tab.b, tab.order + 1) > 1e-10
    if pair is not None and pair.embedded_order:
        bhat = [x - oc.number(e) for x, e in zip(tab.b, pair.e)]
        assert oc.check(tab.a, bhat, None, pair.embedded_order, pair.tol) == []
        assert _float_defect(tab.a, bhat, pair.embedded_order + 1) > 1e-10


def _float_defect(a, b, k) -> float:
    """max over the trees with k nodes of |Σ b_i Φ_i(t) - 1/γ(t)|, in floats: "not one order
    up" (exactly, Feagin's order-11 check alone takes half a minute)."""
    from gnibench.methods.dense_output import elementary_weights
    af, bf, memo = [[float(x) for x in row] for row in a], [float(x) for x in b], {}
    return max(abs(sum(x * y for x, y in zip(bf, elementary_weights(af, t, memo))) - 1 / oc.density(t))
               for t in oc.trees(k)[k - 1])


def test_the_record_of_shipped_verdicts_is_exactly_the_registry():
    """methods/order_verdicts.json lists the verdict keys of exactly the registry's tableaus,
    estimates and extensions (a fresh process: the keys asked for while importing the registry),
    each of which the tests above and tests/kernels/test_dense_output.py recompute without it."""
    import json
    import subprocess
    import sys

    code = ("import json, gnibench.methods; from gnibench.methods import tableau; "
            "print(json.dumps(sorted(tableau.SEEN)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    from gnibench.methods.tableau import _SHIPPED_PATH
    assert json.loads(out.stdout) == sorted(json.loads(_SHIPPED_PATH.read_text()))
