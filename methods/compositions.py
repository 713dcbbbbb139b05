"""Compositions of Störmer-Verlet and of symplectic Euler with its adjoint, coefficients as data.

Φ_h = SV(γ_s h) ∘ … ∘ SV(γ_1 h), [B] §5 uses Yoshida's integrators ([HLW] V.3.2, symmetric
compositions of a symmetric method of order 2):

* Yoshida (1990): order 4, the triple jump γ = (x1, x0, x1), x1 = 1/(2 − 2^(1/3)),
  x0 = −2^(1/3) x1; orders 6 and 8, solutions A (7 stages) and D (15 stages), given by him to 15
  digits, composed as w_m … w_1 w_0 w_1 … w_m with w_0 = 1 − 2 Σ w_i.
* Suzuki (1990), Phys. Lett. A 146, 319-323, the fractal 4th-order scheme of 5 stages:
  γ = (p, p, 1 − 4p, p, p), p = 1/(4 − 4^(1/3)).
* Kahan & Li (1997), Math. Comp. 66, 1089-1099: order 6 with 9 stages and order 8 with 17 stages
  (their s9odr6a and s17odr8a, to 26 digits, as printed in [HLW] V.3.2).

McLachlan (1995), SIAM J. Sci. Comput. 16, 151-168: order 4 with 5 stages as a composition of a
first-order method Φ (symplectic Euler, ``pstep_u``) and its adjoint Φ* (``pstep_v``),
Φ*_{α_5 h} ∘ Φ_{β_5 h} ∘ … ∘ Φ*_{α_1 h} ∘ Φ_{β_1 h} with β_i = α_{6−i} ([HLW] V.3.3, "p4 s5"):
α_1 = (146 + 5√19)/540, α_2 = (−2 + 10√19)/135, α_3 = 1/5, α_4 = (−23 − 20√19)/270,
α_5 = (14 − √19)/108. A Störmer-Verlet composition is the special case α_i = β_i = γ_i / 2.

Every stage reuses the partitioned kernels of methods/partitioned.py (explicit for separable
problems, Newton otherwise). The step reads the coefficients from ``par`` at run time
(``Method.runtime_data``, ``partitioned.compose``), so all compositions of a problem share one
compiled kernel. The orders are checked by measurement (tests/methods/test_orders.py) and the
consistency and symmetry conditions here. Under ``sum=compensated`` every stage's block
updates add their increments with the carried rounding error (methods/summation.py). Adding a
composition: its coefficients here and one line in :mod:`methods` (``summation="compensated"``
makes that its default).
"""
from __future__ import annotations

from gnibench.methods.base import H_PARAM, NEWTON_PARAMS, Method
from gnibench.methods.assembly.steps.partitioned import composed_step


def _symmetric(w):
    w0 = 1.0 - 2.0 * sum(w)
    return tuple(reversed(w)) + (w0,) + tuple(w)


def _palindrome(first_half, middle):
    return tuple(first_half) + (middle,) + tuple(reversed(first_half))


_X1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
YOSHIDA4 = (_X1, -(2.0 ** (1.0 / 3.0)) * _X1, _X1)
YOSHIDA6 = _symmetric((-0.117767998417887e1, 0.235573213359357e0, 0.784513610477560e0))
YOSHIDA8 = _symmetric((0.102799849391985e0, -0.196061023297549e1, 0.193813913762276e1,
                       -0.158240635368243e0, -0.144485223686048e1, 0.253693336566229e0,
                       0.914844246229740e0))
_P = 1.0 / (4.0 - 4.0 ** (1.0 / 3.0))
SUZUKI4 = (_P, _P, 1.0 - 4.0 * _P, _P, _P)
KAHAN_LI6 = _palindrome((0.39216144400731413927925056, 0.33259913678935943859974864,
                         -0.70624617255763935980996482, 0.08221359629355080023149045),
                        0.79854399093482996339895035)
KAHAN_LI8 = _palindrome((0.13020248308889008087881763, 0.56116298177510838456196441,
                         -0.38947496264484728640807860, 0.15884190655515560089621075,
                         -0.39590389413323757733623154, 0.18453964097831570709183254,
                         0.25837438768632204729397911, 0.29501172360931029887096624),
                        -0.60550853383003451169892108)
_R19 = 19.0 ** 0.5
_ALPHA = ((146 + 5 * _R19) / 540, (-2 + 10 * _R19) / 135, 1 / 5, (-23 - 20 * _R19) / 270,
          (14 - _R19) / 108)
# (coefficient of Φ = pstep_u, coefficient of Φ* = pstep_v) per stage, in the order applied
MCLACHLAN4 = tuple((_ALPHA[4 - i], _ALPHA[i]) for i in range(5))

for _g in (YOSHIDA4, YOSHIDA6, YOSHIDA8, SUZUKI4, KAHAN_LI6, KAHAN_LI8):
    assert abs(sum(_g) - 1.0) < 1e-14 and _g == tuple(reversed(_g))   # consistent and symmetric
assert abs(sum(a + b for a, b in MCLACHLAN4) - 1.0) < 1e-14
assert [b for b, _ in MCLACHLAN4] == [a for _, a in reversed(MCLACHLAN4)]   # symmetric


def substeps(data) -> tuple[tuple[float, float], ...]:
    """(u, v) coefficients per stage: a Störmer-Verlet composition γ gives (γ/2, γ/2)."""
    return tuple(x if isinstance(x, tuple) else (0.5 * x, 0.5 * x) for x in data)


def runtime_data(data) -> tuple[float, ...]:
    """(s, u_1, v_1, …, u_s, v_s): the stage count and the coefficients of h of the two block
    steps of each stage (:func:`substeps`), as the composed step reads them from ``par``."""
    return (float(len(data)),) + tuple(c for stage in substeps(data) for c in stage)


def composition(id, data, order, doc, reference="[B] §5; Yoshida (1990)", *, summation="plain"):
    """A composition with coefficients ``data`` (γ of Störmer-Verlet, or (α, β) pairs of
    symplectic Euler and its adjoint); ``summation``: the default of its option ``sum``."""
    return Method(id=id, family="composition", order=order, reference=reference,
                  doc=doc, generate=composed_step, params=(H_PARAM,) + NEWTON_PARAMS,
                  symplectic=True, symmetric=True, needs=("partition",), implicit=True,
                  explicit_when="separable", data=data, summation=summation,
                  runtime_data=runtime_data(data))


yoshida4 = composition("yoshida4", YOSHIDA4, 4, "Yoshida's 4th-order triple jump of Störmer-Verlet")
yoshida6 = composition("yoshida6", YOSHIDA6, 6, "Yoshida's 6th-order composition (solution A)")
yoshida8 = composition("yoshida8", YOSHIDA8, 8, "Yoshida's 8th-order composition (solution D)")
suzuki4 = composition("suzuki4", SUZUKI4, 4, "Suzuki's fractal 4th-order composition of "
                      "Störmer-Verlet (5 stages)", "Suzuki, Phys. Lett. A 146 (1990) 319",
                      summation="compensated")
mclachlan4 = composition("mclachlan4", MCLACHLAN4, 4, "McLachlan's 4th-order composition of "
                         "symplectic Euler and its adjoint (5 stages)",
                         "McLachlan, SIAM J. Sci. Comput. 16 (1995) 151; [HLW] V.3.3",
                         summation="compensated")
kahan_li6 = composition("kahan-li6", KAHAN_LI6, 6, "Kahan-Li 6th-order composition of "
                        "Störmer-Verlet (9 stages)", "Kahan, Li, Math. Comp. 66 (1997) 1089",
                        summation="compensated")
kahan_li8 = composition("kahan-li8", KAHAN_LI8, 8, "Kahan-Li 8th-order composition of "
                        "Störmer-Verlet (17 stages)", "Kahan, Li, Math. Comp. 66 (1997) 1089",
                        summation="compensated")
