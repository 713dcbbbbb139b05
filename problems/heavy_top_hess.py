"""Heavy rigid body with a fixed point, Hess case: a partial first integral, [B] §2, (2.12)-(2.13).

[B] §2 names the Euler-Poisson equations of a heavy top as the source of partial first integrals
("invariant relations") but writes none out; the model and the Hess relation below are the standard
ones (Hess 1890; e.g. Borisov-Mamaev, "Rigid body dynamics"), derived again here and checked
symbolically in tests/problems/test_partial_integrals.py.

State x = (M1, M2, M3, g1, g2, g3): angular momentum M = I omega and Poisson vector gamma (the unit
vertical) in the body frame, I = diag(A, B, C), centre of mass at r = (x0, y0, z0), mu = m g |r|:

    M' = M x omega + mu gamma x e,     gamma' = gamma x omega,      omega = (M1/A, M2/B, M3/C),

with e = r / |r|. First integrals: energy H = M.omega/2 + mu e.gamma, area integral Mg = M.gamma,
geometric integral gg = gamma.gamma.

Hess case. With A > B > C and y0 = 0, h = e.M = e1 M1 + e3 M3 has
    h' = e.(M x omega) + mu e.(gamma x e) = M2 [e1 (1/C - 1/B) M3 + e3 (1/B - 1/A) M1],
which is l h for some l exactly when e3^2 (A - B)/(AB) = e1^2 (B - C)/(BC), i.e.
    x0 sqrt(A (B - C)) +- z0 sqrt(C (A - B)) = 0:
r lies on the normal of a circular section of the inertia ellipsoid A x^2 + B y^2 + C z^2 = 1.
(choice) The sign: e = (sqrt(C (A - B)), 0, -sqrt(A (B - C))) / sqrt(C (A - B) + A (B - C)) (the
other sign is its mirror image z -> -z). Then
    D_h F = l h,   l = -kappa M2 / B = -kappa omega2,   kappa = sqrt((A - B)(B - C) / (A C)),
so h is a partial first integral ([B] §2, D_h F = l h, q = 1 in (2.12)) and Gamma_0 = {h = 0} is
invariant (the Hess invariant relation); the observer of [B] (2.13) keeps orbits on it.

(choice) Defaults: A, B, C = 3, 2, 1.5 (A < B + C, a physical body), mu = 1; start on Gamma_0:
gamma = (0.6, 0, 0.8), M = t (-e3, 0, e1) + (0, M2, 0) with t = 0.5, M2 = 1 (h = 0 exactly up
to rounding of e). Any <state>0 option overrides a component (off Gamma_0 in general).
"""
from __future__ import annotations

import math

from gnibench.problems.base import Model, Problem, require
from gnibench.suite.foundation.params import Param


def axis(A, B, C, sqrt=math.sqrt):
    """Unit vector e = (e1, 0, e3) of the centre of mass, Hess condition (see the docstring)."""
    a, c = sqrt(C * (A - B)), sqrt(A * (B - C))
    n = sqrt(C * (A - B) + A * (B - C))
    return a / n, -c / n


def model(S):
    import sympy as sp

    M = sp.Matrix([S.M1, S.M2, S.M3])
    g = sp.Matrix([S.g1, S.g2, S.g3])
    om = sp.Matrix([S.M1 / S.A, S.M2 / S.B, S.M3 / S.C])
    e1, e3 = axis(S.A, S.B, S.C, sqrt=sp.sqrt)
    e = sp.Matrix([e1, 0, e3])
    dM = M.cross(om) + S.mu * g.cross(e)
    dg = g.cross(om)
    H = M.dot(om) / 2 + S.mu * e.dot(g)
    h = e1 * S.M1 + e3 * S.M3
    kappa = sp.sqrt((S.A - S.B) * (S.B - S.C) / (S.A * S.C))
    return Model(rhs=tuple(dM) + tuple(dg),
                 integrals={"H": H, "Mg": M.dot(g), "gg": g.dot(g)},
                 partial_integrals={"h": (h, -kappa * S.M2 / S.B)})


def initial(v):
    e1, e3 = axis(v["A"], v["B"], v["C"])
    t, m2 = 0.5, 1.0
    return (-t * e3, m2, t * e1, 0.6, 0.0, 0.8)


class _Problem(Problem):
    def validate(self, values):
        require(values["A"] > values["B"] > values["C"] > 0,
                f"{self.id}: the Hess case needs A > B > C > 0 (got A={values['A']}, "
                f"B={values['B']}, C={values['C']})")


PROBLEM = _Problem(
    id="heavy-top-hess",
    title="Heavy rigid body, Hess case (partial first integral h = e.M)",
    reference="[B] §2, (2.12)-(2.13) (Euler-Poisson equations named there; Hess case)",
    state=("M1", "M2", "M3", "g1", "g2", "g3"),
    params=(
        Param("A", 3.0, "principal moment of inertia A (largest)", low=0.0, low_open=True),
        Param("B", 2.0, "principal moment of inertia B (middle)", low=0.0, low_open=True),
        Param("C", 1.5, "principal moment of inertia C (smallest)", low=0.0, low_open=True),
        Param("mu", 1.0, "m g |r|: weight times distance of the centre of mass from the fixed point"),
    ),
    model=model,
    initial=initial,
    notes="(choice) A, B, C, mu = 3, 2, 1.5, 1; centre of mass on the normal of a circular section, "
          "e = (sqrt(C(A-B)), 0, -sqrt(A(B-C)))/norm; start on the Hess relation h = e.M = 0: "
          "gamma = (0.6, 0, 0.8), M = 0.5 (-e3, 0, e1) + (0, 1, 0). h is a partial first integral, "
          "D_h F = l h with l = -sqrt((A-B)(B-C)/(AC)) M2/B ([B] (2.12), q = 1).",
)
