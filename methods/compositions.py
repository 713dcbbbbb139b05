"""Symmetric compositions of Störmer-Verlet (Yoshida 1990), coefficients as data.

Φ_h = SV(γ_s h) ∘ … ∘ SV(γ_1 h), [B] §5 uses Yoshida's integrators. Order 4: the triple jump
γ = (x1, x0, x1), x1 = 1/(2 − 2^(1/3)), x0 = −2^(1/3) x1. Orders 6 and 8: Yoshida's solutions A
(6th order, 7 stages) and D (8th order, 15 stages), given by him to 15 digits, composed as
w_m … w_1 w_0 w_1 … w_m with w_0 = 1 − 2 Σ w_i. Every stage reuses the partitioned kernels of
methods/partitioned.py (explicit for separable problems, Newton otherwise); under
``sum=compensated`` every stage's block updates add their increments with the carried rounding
error (``partitioned.compose``, methods/summation.py). Adding a composition: its γ here and one
line in :mod:`methods` (``summation="compensated"`` makes that its default).
"""
from __future__ import annotations

from gnibench.methods.base import H_PARAM, NEWTON_PARAMS, Method
from gnibench.methods.partitioned import _block, compose


def _symmetric(w):
    w0 = 1.0 - 2.0 * sum(w)
    return tuple(reversed(w)) + (w0,) + tuple(w)


_X1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
YOSHIDA4 = (_X1, -(2.0 ** (1.0 / 3.0)) * _X1, _X1)
YOSHIDA6 = _symmetric((-0.117767998417887e1, 0.235573213359357e0, 0.784513610477560e0))
YOSHIDA8 = _symmetric((0.102799849391985e0, -0.196061023297549e1, 0.193813913762276e1,
                       -0.158240635368243e0, -0.144485223686048e1, 0.253693336566229e0,
                       0.914844246229740e0))

for _g in (YOSHIDA4, YOSHIDA6, YOSHIDA8):
    assert abs(sum(_g) - 1.0) < 1e-14 and _g == tuple(reversed(_g))   # consistent and symmetric


def _generate(gammas):
    def generate(ctx) -> str:
        src_u, ws_u = _block(ctx, "u")
        src_v, ws_v = _block(ctx, "v")
        blocks = [(block, repr(0.5 * g), w) for g in gammas for block, w in (("u", 0), ("v", 1))]
        return (src_u + src_v + f"\n@njit(cache=True)\ndef make_ws():\n    return ({ws_u}, {ws_v})\n"
                + compose("step", blocks))
    return generate


def composition(id, gammas, order, doc, summation="plain", reference="[B] §5; Yoshida (1990)"):
    """A symmetric composition of Störmer-Verlet with coefficients ``gammas``; ``summation``: the
    default of its option ``sum``."""
    return Method(id=id, family="composition", order=order, reference=reference,
                  doc=doc, generate=_generate(gammas), params=(H_PARAM,) + NEWTON_PARAMS,
                  symplectic=True, symmetric=True, needs=("partition",), implicit=True,
                  explicit_when="separable", data=gammas, summation=summation)


yoshida4 = composition("yoshida4", YOSHIDA4, 4, "Yoshida's 4th-order triple jump of Störmer-Verlet")
yoshida6 = composition("yoshida6", YOSHIDA6, 6, "Yoshida's 6th-order composition (solution A)")
yoshida8 = composition("yoshida8", YOSHIDA8, 8, "Yoshida's 8th-order composition (solution D)")
