"""Lie–Poisson splitting integrator for the Euler equations on so(4), [B] §7, (7.1)–(7.2).

[B] §7.2 mentions that (7.1) "can also be integrated by the so-called Lie–Poisson integrators", and
shows (Fig 26(b), from its ref [62]) the Ge–Marsden scheme in Channell–Scovel's form, which the seeds
do not spell out. This module is a Lie–Poisson integrator of the splitting kind instead: every
sub-flow is an exact coadjoint rotation, so the Casimirs H1 and H2 are conserved to round-off,
whatever the step (the "Hamiltonian" H3 only up to O(h^order) oscillations, without drift).

Derivation. (7.1) is x' = J(x) ∇H with the "Hamiltonian" H = (1/2) Σ λ_i x_i² ([B] after (7.1)),
∇H = (λ_1 x_1, …, λ_6 x_6), and J(x) the antisymmetric matrix, linear in x, of the Lie–Poisson
bracket of so(4). Reading J off (7.1) term by term (x_k' = Σ_i J_ki λ_i x_i), its nonzero entries
above the diagonal are

    J_12 = -x3, J_13 = x2, J_15 = -x6, J_16 = x5,  J_23 = -x1, J_24 = x6, J_26 = -x4,
    J_34 = -x5, J_35 = x4, J_45 = -x3, J_46 = x2,  J_56 = -x1,

and J_14 = J_25 = J_36 = 0. H1 and H2 of (7.2) satisfy J ∇H1 = J ∇H2 = 0 (they are the Casimirs,
[B] after (7.2)), so the flow of *any* Hamiltonian with this bracket conserves them.

Split H = Σ_i H^(i), H^(i) = (1/2) λ_i x_i². The field of H^(i) is x_k' = λ_i x_i J_ki(x). Since
J_ii = 0, x_i is constant along it, so ω_i = λ_i x_i is constant and the field is linear in the other
coordinates: two simultaneous plane rotations with angular velocity ω_i. Writing a pair (a, b) for
a' = ω b, b' = -ω a (solution: a ← c a + s b, b ← -s a + c b, c = cos ωτ, s = sin ωτ):

    H^(1): (x2, x3), (x5, x6)    H^(2): (x3, x1), (x6, x4)    H^(3): (x1, x2), (x4, x5)
    H^(4): (x2, x6), (x5, x3)    H^(5): (x6, x1), (x3, x4)    H^(6): (x1, x5), (x4, x2)

(``ROTATIONS`` below, 0-based; tests/methods/test_lie_poisson.py checks symbolically that the six fields
add up to (7.1)). Each sub-flow rotates two orthogonal planes by the same angle, so it keeps H2 = |x|²
and the inner product x2 x5 + x3 x6 (resp. the analogous pairing) of H1 exactly; only round-off
moves them. J_14 = J_25 = J_36 = 0 means {x1², x4²} = {x2², x5²} = {x3², x6²} = 0: the flows of
H^(1) and H^(4) commute (and so on), which lets the Strang step be written over three groups
G_a = (1, 4), G_b = (2, 5), G_c = (3, 6).

Composition. order=2: Strang splitting, symmetric,
    Φ_h = G_a(h/2) ∘ G_b(h/2) ∘ G_c(h) ∘ G_b(h/2) ∘ G_a(h/2)
(10 rotations; G_c(h) = φ_3(h/2) φ_6(h) φ_3(h/2) because φ_3 and φ_6 commute). order=4: Yoshida's
triple jump Φ_{γ1 h} ∘ Φ_{γ0 h} ∘ Φ_{γ1 h} (``YOSHIDA4`` of methods/compositions.py); adjacent
sub-flows of the same H^(i) are merged (they form a one-parameter group), 28 rotations per step.

Round-off. Within a step the state is carried as y + e (compensated summation: each rotation's
increment is added with an error-free two_sum and the error kept in e), and rounded once at the end
of the step, so H1, H2 random-walk by one rounding per coordinate per step rather than one per
sub-flow: measured on the default orbit, 10^5 steps of h = 0.005 move H1 by <= 1e-13 and H2 by
<= 2.5e-13 (|H2| = 15) for both orders. The step stays a pure function of y.

Cost accounting: the method never evaluates f; ``nfev`` counts exact sub-flows (one sin/cos pair and
two compensated plane rotations each); ``Method.order`` is that of the default, order=2.
"""
from __future__ import annotations

from dataclasses import dataclass

from gnibench.methods.assembly.steps.lie_poisson import write_lie_poisson
from gnibench.methods.base import H_PARAM, Method
from gnibench.methods.compositions import YOSHIDA4
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.params import Param

# ROTATIONS[i] = the two planes (a, b), a' = ω b, b' = -ω a, rotated by the flow of (1/2) λ_i x_i²
ROTATIONS = (
    ((1, 2), (4, 5)),
    ((2, 0), (5, 3)),
    ((0, 1), (3, 4)),
    ((1, 5), (4, 2)),
    ((5, 0), (2, 3)),
    ((0, 4), (3, 1)),
)
COMMUTING_GROUPS = ((0, 3), (1, 4), (2, 5))      # J_14 = J_25 = J_36 = 0
STATE = ("x1", "x2", "x3", "x4", "x5", "x6")
LAMBDAS = ("lam1", "lam2", "lam3", "lam4", "lam5", "lam6")


def strang(weight: float) -> list[tuple[int, float]]:
    """(sub-flow, fraction of h) of one Strang step of length weight·h, over the commuting groups."""
    (a1, a2), (b1, b2), (c1, c2) = COMMUTING_GROUPS
    half = 0.5 * weight
    return [(a1, half), (a2, half), (b1, half), (b2, half), (c1, weight), (c2, weight),
            (b2, half), (b1, half), (a2, half), (a1, half)]


def schedule(order: int) -> list[tuple[int, float]]:
    """The sub-flows of one step, adjacent flows of the same H^(i) merged."""
    gammas = (1.0,) if order == 2 else YOSHIDA4
    flat = [item for g in gammas for item in strang(g)]
    merged: list[tuple[int, float]] = []
    for i, w in flat:
        if merged and merged[-1][0] == i:
            merged[-1] = (i, merged[-1][1] + w)
        else:
            merged.append((i, w))
    return merged


_SO4_CHECKED: dict[str, bool] = {}


def _is_so4(problem) -> bool:
    """The problem's field is (7.1): states x1..x6, first parameters lam1..lam6, and the rotation
    fields of ROTATIONS add up to its right-hand side (checked symbolically, once per problem)."""
    if problem.state != STATE or problem.model_params[:6] != LAMBDAS:
        return False
    if problem.id not in _SO4_CHECKED:
        import sympy as sp
        from gnibench.problems.codegen import symbolic

        ys, ps, rhs, _ = symbolic(problem)
        _SO4_CHECKED[problem.id] = all(sp.expand(f - g) == 0
                                       for f, g in zip(rhs, split_field(ys, ps[:6])))
    return _SO4_CHECKED[problem.id]


def split_field(ys, lams) -> list:
    """Σ_i of the fields of (1/2) λ_i x_i² (ROTATIONS), as expressions in ys (a list of 6 symbols)."""
    total = [0] * 6
    for i, planes in enumerate(ROTATIONS):
        omega = lams[i] * ys[i]
        for a, b in planes:
            total[a] += omega * ys[b]
            total[b] -= omega * ys[a]
    return total


@dataclass(frozen=True)
class LiePoissonMethod(Method):
    """A Method whose structure need ``so4`` is checked here (Method.check_structure knows only
    ``partition``)."""

    def check_structure(self, problem, has_modifiers: bool) -> None:
        if not _is_so4(problem):
            raise UserError(
                f"method {self.id} needs the Euler equations on so(4) ([B] (7.1): states x1..x6, "
                f"parameters lam1..lam6), but problem {problem.id} is not; use it with euler-so4")


lie_poisson = LiePoissonMethod(
    id="lie-poisson", family="splitting", order=2, reference="[B] §7.2; Ge-Marsden, Channell-Scovel",
    doc="Lie-Poisson splitting for euler-so4 into exact coadjoint rotations (Strang, or Yoshida's "
        "triple jump with order=4); conserves the Casimirs H1, H2 to round-off",
    generate=write_lie_poisson(ROTATIONS, schedule), symmetric=True, needs=("so4",),
    field_modifiers_refused="it integrates (7.1) itself by exact sub-flows",
    params=(H_PARAM, Param("order", "2", "order of the composition: 2 (Strang) or 4 (Yoshida "
                                         "triple jump)", kind="str", choices=("2", "4"))))
