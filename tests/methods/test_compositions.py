"""Conditions on the composition coefficients (methods/compositions.py); their orders are measured in
tests/methods/test_orders.py.

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


COMPOSED = ["yoshida4", "yoshida8", "suzuki4", "kahan-li6", "kahan-li8", "mclachlan4"]


def _stages(mid: str) -> list[tuple[float, float]]:
    """(a_i, b_i) of stage i, Φ*_{b_i h} ∘ Φ_{a_i h}: (γ_i / 2, γ_i / 2) for a composition of
    Störmer-Verlet ([HLW] (1.17)), McLachlan's (α, β) pairs as given."""
    data = METHODS[mid].data
    return [g if isinstance(g, tuple) else (0.5 * g, 0.5 * g) for g in data]


@pytest.mark.parametrize("modifier", ["", "+observer:on=H,theta=1"])
@pytest.mark.parametrize("summation", ["plain", "compensated"])
def test_every_composition_of_a_problem_shares_one_kernel(summation, modifier):
    """The coefficients are read from par (Method.runtime_data: the stage count, then a_i, b_i
    of each stage), after the modifiers' values, at the place the step reads them."""
    from gnibench.methods.assembly import kernel_text
    from gnibench.suite.cell.compiled import compile_cell, kernel_key
    from gnibench.suite.cell.spec import prepare

    keys = set()
    for mid in COMPOSED:
        problem, cfg = prepare("kepler-2d", f"{mid}:h=0.1,sum={summation}{modifier}")
        keys.add(kernel_key(problem, cfg))
        expected = [float(len(METHODS[mid].data))] + [x for st in _stages(mid) for x in st]
        par = list(compile_cell(problem, cfg).par)
        assert par[-len(expected):] == expected, mid
        at = len(par) - len(expected)
        assert f"stages = int(par[{at}])" in kernel_text(problem, cfg)
    assert len(keys) == 1


@pytest.mark.parametrize("mid", COMPOSED)
def test_a_step_is_its_stages_bit_for_bit(mid):
    """One compiled step of a composition on kepler-2d (explicit blocks), from a point off the
    initial one, against its stages in plain Python: per stage, symplectic Euler ([HLW] (1.9),
    implicit in u: here explicit) with a_i h, then its adjoint with b_i h, the field being the
    problem's generated f run as Python. Same states bit for bit; nfev counts each explicit block
    once (it uses one half of each of its two evaluations of f, methods/partitioned.py)."""
    from gnibench.problems.codegen import problem_code, python_functions
    from gnibench.suite.cell.solve import solve
    from gnibench.suite.cell.spec import prepare

    h = 0.07
    start = solve("kepler-2d", "stormer-verlet:h=0.05", steps=3)
    point = ",".join(f"{s}0={float(v)!r}" for s, v in zip(start.state_names, start.y[-1]))
    one = solve(f"kepler-2d:{point}", f"{mid}:h={h!r},sum=plain", steps=1)
    problem, _ = prepare(f"kepler-2d:{point}", "stormer-verlet")
    meta = problem_code(problem.record)[1]
    f = python_functions(problem.record)["base_f"]
    par = tuple(problem.record.par(problem.values))

    def block(y, hh, first, second):
        g = f(y, par)
        w = tuple(y[i] + hh * g[i] if i in first else y[i] for i in range(len(y)))
        g = f(w, par)
        return tuple(w[i] + hh * g[i] if i in second else w[i] for i in range(len(y)))

    y = tuple(float(v) for v in start.y[-1])
    u, v = meta["u_idx"], meta["v_idx"]
    for a, b in _stages(mid):
        y = block(block(y, a * h, u, v), b * h, v, u)
    assert one.status == "ok" and [x.hex() for x in y] == [float(x).hex() for x in one.y[-1]]
    assert float(one.nfev[-1]) == 2 * len(_stages(mid))


def test_a_user_composition_of_a_composition_reads_its_basis_data(tmp_path):
    """A user composition whose basis is a shipped composition (its coefficients in par): one
    step of γ = (1/2, 1/2) over yoshida4 is two yoshida4 steps of h/2, bit for bit."""
    import gnibench
    from gnibench.suite.cell.solve import solve

    path = tmp_path / "halves.toml"
    path.write_text('[[method]]\nid = "yoshida4-halves"\nkind = "composition"\norder = 4\n'
                    'basis = "yoshida4"\ngamma = ["1/2", "1/2"]\n')
    gnibench.load(path)
    one = solve("kepler-2d", "yoshida4-halves:h=0.1", steps=3)
    two = solve("kepler-2d", "yoshida4:h=0.05", steps=6)
    assert one.status == two.status == "ok"
    assert [float(x).hex() for x in one.y[-1]] == [float(x).hex() for x in two.y[-1]]


def test_a_user_composition_of_stormer_verlet_is_the_shipped_kernel(tmp_path):
    """A user's composition of Störmer-Verlet runs the shipped compositions' kernel (its γ in
    par): the same kernel key as yoshida4's, and γ = (1/2, 1/2) is two Störmer-Verlet steps of
    h/2, bit for bit."""
    import gnibench
    from gnibench.suite.cell.compiled import kernel_key
    from gnibench.suite.cell.solve import solve
    from gnibench.suite.cell.spec import prepare

    path = tmp_path / "sv.toml"
    path.write_text('[[method]]\nid = "sv-halves"\nkind = "composition"\norder = 2\n'
                    'basis = "stormer-verlet"\ngamma = ["1/2", "1/2"]\n')
    gnibench.load(path)
    assert kernel_key(*prepare("kepler-2d", "sv-halves:h=0.1")) == \
        kernel_key(*prepare("kepler-2d", "yoshida4:h=0.1,sum=plain"))
    one = solve("kepler-2d", "sv-halves:h=0.1", steps=3)
    two = solve("kepler-2d", "stormer-verlet:h=0.05", steps=6)
    assert one.status == two.status == "ok"
    assert [float(x).hex() for x in one.y[-1]] == [float(x).hex() for x in two.y[-1]]
    assert one.nfev[-1] == two.nfev[-1]
