"""Lotka-Volterra model, [HLW] I.1.1, (1.1), (1.4): u' = u(v - 2), v' = v(1 - u).

Invariant I = ln u - u + 2 ln v - v  [HLW] (1.4). Partition (u, v) as in [HLW] (1.8)-(1.9).
No closed-form solution: global errors come from a reference solution (not in this problem).
"""
from __future__ import annotations

from gnibench.problems.base import Model, Problem, require


def model(S):
    from sympy import log

    rhs = (S.u * (S.v - 2), S.v * (1 - S.u))                     # [HLW] (1.1)
    invariant = log(S.u) - S.u + 2 * log(S.v) - S.v              # [HLW] (1.4)
    return Model(rhs=rhs, integrals={"I": invariant})


class LotkaVolterra(Problem):
    def validate(self, values):
        u, v = self.y0(values)
        require(u > 0 and v > 0, f"lotka-volterra: initial point (u, v) = ({u:g}, {v:g}); allowed: u > 0, v > 0")


PROBLEM = LotkaVolterra(
    id="lotka-volterra",
    title="Lotka-Volterra predator-prey model",
    reference="[HLW] I.1.1, (1.1), (1.4), Fig 1.2",
    state=("u", "v"),
    params=(),
    model=model,
    initial=lambda v: (4.0, 2.0),
    partition=(("u",), ("v",)),
    notes="(choice) default initial point (u, v) = (4, 2), the first symplectic-Euler start of Fig 1.2.",
)
