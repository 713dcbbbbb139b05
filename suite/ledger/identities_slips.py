"""Identity checks of the seeds' slips, as printed and corrected (the ledger's policy on slips:
judge the printed statement, and the corrected relation in a second entry ``<id>.corrected``).

* [B] after (6.1), B-6.1-a: the type of the equilibrium by the sign of ε, with ε on ½|q|² only
  (the claims inventory Part 4, item 4); as printed (ε on all three terms) in :mod:`.identities_b`.
* [B] after Fig 23, B-6.2-m: the modified G-S loop at I = 0, P² = r²(2 − r²)/(2(1 + B r²)), is
  closed iff 1 + B r² > 0 on [0, √2], i.e. B > −1/2 ([B] says B > −1; Part 4, item 5).
* [B] §7.1, B-7.1-c: (7.5)-(7.7) on the section as printed, x3 = 0: the rebuilt points have
  x3 = ε√(h3 − h2 − 2x5² − 3x6²) ≠ 0, so the printed section is not the one (7.5) describes.
* [B] (8.1), B-8.1-c: the curvature of 4|dq|²/(1 − |q|²)² (the factor 4 the printed metric lacks).
"""
from __future__ import annotations

import math

import numpy as np
from gnibench.suite.ledger.identity_tools import problem


def gs_equilibrium_types_corrected() -> dict:
    """[B] after (6.1) with ε on ½|q|² only: H = ωK − ½|p|² + (ε/2)|q|² + ¼|p|⁴ (the claims inventory)."""
    import sympy as sp

    q1, q2, p1, p2 = sp.symbols("q1 q2 p1 p2", real=True)
    omega = 2 * sp.pi
    out = {}
    for eps in (-1, 0, 1):
        H = (omega * (q1 * p2 - q2 * p1) - sp.Rational(1, 2) * (p1**2 + p2**2)
             + sp.Rational(eps, 2) * (q1**2 + q2**2) + sp.Rational(1, 4) * (p1**2 + p2**2)**2)
        rhs = [-sp.diff(H, q1), -sp.diff(H, q2), sp.diff(H, p1), sp.diff(H, p2)]   # p', q'
        J = sp.Matrix(rhs).jacobian([p1, p2, q1, q2]).subs({q1: 0, q2: 0, p1: 0, p2: 0})
        out[eps] = _exact_type(sp.Matrix(J))
    claimed = {-1: "center-center", 0: "non-semisimple", 1: "saddle-focus"}
    hits = sum(out[e] == claimed[e] for e in out)
    return {"matches": float(hits), "measured": "; ".join(f"eps={e}: {t}" for e, t in out.items()),
            "_detail": f"ε on ½|q|² only gives {out}; the seed says {claimed}"}


def _exact_type(J) -> str:
    """The type of a 4x4 linearization from its exact eigenvalues and Jordan structure."""
    import sympy as sp

    ev = J.eigenvals()                                  # {eigenvalue: algebraic multiplicity}
    real = any(sp.re(v) != 0 for v in ev)
    imag = all(sp.im(v) != 0 for v in ev)
    if real:
        return "saddle-focus" if imag else "saddle"
    defective = any(m > 4 - (J - v * sp.eye(4)).rank() for v, m in ev.items())
    return "non-semisimple" if defective else "center-center"


def _loop_closed(B: float) -> bool:
    """Whether the I = 0 level P² = r²(2 − r²)/(2(1 + B r²)) of the modified G-S system closes:
    P² ≥ 0 from r = 0 to r = √2, where it returns to P = 0, on a grid of r."""
    r = np.linspace(0.0, math.sqrt(2.0), 2001)
    den = 1 + B * r * r
    return bool(np.all(den > 0))


#: values of B in (−1, ∞) (the printed range) and around −1/2 (the corrected one)
_PRINTED_B = (-0.9, -0.75, -0.6, -0.2, 0.5)
_AROUND_HALF = (-0.55, -0.51, -0.49, -0.45, -0.2, 0.5)


def gs_modified_loop_range() -> dict:
    """B-6.2-m: K, the linearization and the loop at the seed's B (identities_b), and whether
    the loop closes for every B > −1 as printed (``printed``: share of the B of
    _PRINTED_B where it does), and exactly for B > −1/2 (``corrected``: 1 when closure agrees
    with B > −1/2 at every B of _AROUND_HALF and _PRINTED_B)."""
    from gnibench.suite.ledger.identities_b import gs_modified_integrable

    printed = float(np.mean([_loop_closed(B) for B in _PRINTED_B]))
    agree = all(_loop_closed(B) == (B > -0.5) for B in _AROUND_HALF + _PRINTED_B)
    return {**gs_modified_integrable(), "printed": printed, "corrected": float(agree),
            "measured": printed}


def so4_section_as_printed() -> dict:
    """B-7.1-c as printed: on the section x3 = 0 the points rebuilt by (7.5)-(7.7) should have
    x3 = 0; ``x3_min`` is the smallest |x3| of the rebuilt points over the charts."""
    smallest = math.inf
    for k in range(1, 9):
        bound = problem(f"euler-so4:chart={k},sec_x5=0.3,sec_x6=-0.2")
        y = bound.record.y0(bound.values)
        smallest = min(smallest, abs(y[2]))
    return {"x3_min": float(smallest), "measured": float(smallest)}


def genus2_curvature_corrected() -> dict:
    """B-8.1-c corrected: the curvature of 4(dq1² + dq2²)/(1 − |q|²)², K = −Δ ln λ / λ² with
    λ = 2/(1 − r²) (the Poincaré disc), is −1."""
    import sympy as sp

    x, y = sp.symbols("x y", real=True)
    lam = 2 / (1 - x**2 - y**2)
    K = sp.simplify(-(sp.diff(sp.log(lam), x, 2) + sp.diff(sp.log(lam), y, 2)) / lam**2)
    return {"measured": float(K)}


CHECKS = {f.__name__: f for f in (gs_equilibrium_types_corrected, gs_modified_loop_range,
                                    so4_section_as_printed, genus2_curvature_corrected)}
