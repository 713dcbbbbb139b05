"""Partitioned Runge-Kutta methods and compositions given as data (user definitions).

**Partitioned RK** ([HLW] II.2.2): a tableau (A, b) for the block u of the problem's partition and
(Â, b̂) for v. When the problem's structure makes every stage explicit (a separable Hamiltonian:
f_u does not depend on u, f_v not on v) and the stages can be ordered so that each one needs only
stages before it, the step is unrolled in that order (each stage evaluates one block: half an
f-evaluation, as for the shipped partitioned methods); otherwise Newton solves the stage equations
(templates/prk.py). An implicit RK method is the case Â = A on one block. The steps are written
by methods/assembly/steps/prk.py.

**Compositions** ([HLW] II.4): Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h} of a registered basis method Φ;
the basis's step is compiled from a kernel module of its own and called once per γ.

:data:`PRK_FORMS` gives the shipped partitioned methods as partitioned tableaus, so that a
composition of them can be checked by the order conditions of the composed tableau.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as Fr

from gnibench.methods.base import Method
from gnibench.suite.foundation.errors import UserError

_H = Fr(1, 2)
#: (A_u, b_u), (A_v, b_v) of the shipped partitioned methods ([HLW] (1.9), (1.17); II.2.2)
PRK_FORMS = {
    "symplectic-euler": (([[1]], [1]), ([[0]], [1])),
    "symplectic-euler-adjoint": (([[0]], [1]), ([[1]], [1])),
    "stormer-verlet": (([[_H, 0], [_H, 0]], [_H, _H]), ([[0, 0], [_H, _H]], [_H, _H])),
}


def compose(forms: tuple, gammas) -> tuple:
    """The partitioned tableau of Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h} for a basis given as a partitioned
    tableau ((A, b), (Â, b̂)): stages concatenated, block (k, k) = γ_k A, block (k, l < k) = γ_l 1 bᵀ,
    weights γ_k b (HNW I §II.4, composition of RK methods)."""
    out = []
    for a, b in forms:
        s, m = len(b), len(gammas)
        big = [[0] * (s * m) for _ in range(s * m)]
        for k, g in enumerate(gammas):
            for i in range(s):
                for l in range(k):
                    for j in range(s):
                        big[k * s + i][l * s + j] = gammas[l] * b[j]
                for j in range(s):
                    big[k * s + i][k * s + j] = g * a[i][j]
        out.append((big, [g * x for g in gammas for x in b]))
    return tuple(out)


@dataclass(frozen=True)
class CompositionMethod(Method):
    """A composition of a registered basis method: the basis's structure needs and refusals."""

    basis: Method | None = None

    def check_structure(self, problem, has_modifiers: bool) -> None:
        """The basis's refusal, said of this method (the one the user named)."""
        try:
            self.basis.check_structure(problem, has_modifiers)
        except UserError as e:
            raise UserError(f"method {self.id} (a composition of {self.basis.id}): "
                            f"{e}".replace(f"method {self.basis.id} ", "it ", 1)) from None
