"""Geodesic flow on a compact surface of genus 2 and curvature -1 (an Anosov flow), [B] §8, (8.1)-(8.4).

H = (1 - |q|^2)^2 |p|^2 / 4 on the Poincaré disc  [B] (8.2), state (q1, q2, p1, p2), canonical.

The surface is D^2/Gamma with fundamental region Omega, a regular hyperbolic octagon [B] §8.1: with
beta = pi/8 and R0 = sin beta/(cos beta + sqrt(cos 2 beta)) = 0.21684534..., its side in the octant
Pi_1 = {|q2| <= q1 tan beta} is the arc 1 + |q|^2 - 2 q1 (1 + R0^2)/(1 - R0^2) = 0; the other sides are
its rotations by k pi/4. A point of Pi_1 beyond that side is mapped back by the homography (8.3),
gamma(z) = (a z + b)/(b z + a), a = 1 + 1/R0^2, b = 1 - 1/R0^2 (in real form exactly the two lines of
(8.3)), which maps the side at angle 0 onto the opposite side; in octant k the map is
z -> rho gamma(conj(rho) z), rho = exp(i k pi/4). Momenta map by (8.4), p_bar = (D_gamma^T)^-1 p; for a
holomorphic gamma this is p_bar = p / conj(gamma'(z)) (complex notation), and since
|gamma'(z)| = (1 - |gamma z|^2)/(1 - |z|^2) for a disc automorphism, H is preserved exactly.

:func:`post_step` is the identification applied after every accepted step ([B] §8.2: integrate until
the first point with q outside Omega, then map it back). It is a numba-compilable template, tuple in,
tuple out, with its constants inside (it is copied alone into the generated module).

(choice) [B] takes "at random a point q0 in Omega and a vector p0". Default: q0 = (0.2, 0.1), p0 in
the direction of angle 1 rad with H0 = 1/2; options H0 and angle (direction of p0) build p0 at q0
(q10, q20 may move q0; it must lie inside Omega).
"""
from __future__ import annotations

import math

from gnibench.problems.base import Boundary, Model, Problem, require
from gnibench.suite.foundation.params import Param

BETA = math.pi / 8
R0 = math.sin(BETA) / (math.cos(BETA) + math.sqrt(math.cos(2 * BETA)))     # [B] §8.1
SIDE_CENTRE = (1 + R0 * R0) / (1 - R0 * R0)        # side arc: |q - (SIDE_CENTRE, 0)|^2 = SIDE_CENTRE^2 - 1
DEFAULT_Q = (0.2, 0.1)


def model(S):
    H = (1 - S.q1**2 - S.q2**2)**2 * (S.p1**2 + S.p2**2) / 4            # [B] (8.2)
    return Model(hamiltonian=H, integrals={"H": H})


def post_step(y, par):
    """Map a point with q outside Omega back into Omega by the side pairings (8.3)-(8.4).

    Identity (the same tuple) when q is inside Omega. Each map strictly decreases the hyperbolic
    distance of q to the centre, so a few iterations suffice near a vertex.
    """
    q1, q2, p1, p2 = y
    beta = math.pi / 8.0
    r0 = math.sin(beta) / (math.cos(beta) + math.sqrt(math.cos(2.0 * beta)))
    a = 1.0 + 1.0 / (r0 * r0)                                            # [B] (8.3)
    b = 1.0 - 1.0 / (r0 * r0)
    centre = (1.0 + r0 * r0) / (1.0 - r0 * r0)
    moved = False
    for _ in range(16):
        k = math.floor(math.atan2(q2, q1) / (math.pi / 4.0) + 0.5)        # octant of q
        ck = math.cos(k * math.pi / 4.0)
        sk = math.sin(k * math.pi / 4.0)
        w1 = ck * q1 + sk * q2                                           # w = conj(rho) q
        w2 = -sk * q1 + ck * q2
        w_sq = w1 * w1 + w2 * w2
        if 1.0 + w_sq - 2.0 * centre * w1 >= 0.0:                        # inside Omega
            break
        moved = True
        den = b * b * w_sq + 2.0 * a * b * w1 + a * a
        g1 = (a * b * w_sq + (a * a + b * b) * w1 + a * b) / den         # [B] (8.3)
        g2 = (a * a - b * b) * w2 / den
        # [B] (8.4): p_bar = p conj(b w + a)^2 / (a^2 - b^2), as gamma' = (a^2 - b^2)/(b w + a)^2
        d1 = b * w1 + a
        d2 = b * w2
        m1 = (d1 * d1 - d2 * d2) / (a * a - b * b)
        m2 = -2.0 * d1 * d2 / (a * a - b * b)
        p1, p2 = p1 * m1 - p2 * m2, p1 * m2 + p2 * m1
        q1, q2 = ck * g1 - sk * g2, sk * g1 + ck * g2                    # rho gamma(w)
    if not moved:
        return y
    return (q1, q2, p1, p2)


def inside(q1: float, q2: float) -> bool:
    """Whether q lies in the open fundamental octagon Omega."""
    if q1 * q1 + q2 * q2 >= 1.0:
        return False
    k = math.floor(math.atan2(q2, q1) / (math.pi / 4) + 0.5)
    ck, sk = math.cos(k * math.pi / 4), math.sin(k * math.pi / 4)
    w1, w2 = ck * q1 + sk * q2, -sk * q1 + ck * q2
    return 1 + w1 * w1 + w2 * w2 - 2 * SIDE_CENTRE * w1 > 0


def _side_constants():
    """Exact (sympy) R0, a, b of [B] §8.1, (8.3) and the centre distance of the side arcs."""
    import sympy as sp

    beta = sp.pi / 8
    r0 = sp.sin(beta) / (sp.cos(beta) + sp.sqrt(sp.cos(2 * beta)))
    return r0, 1 + 1 / r0**2, 1 - 1 / r0**2, (1 + r0**2) / (1 - r0**2)


def _rotation(k):
    import sympy as sp

    return sp.cos(k * sp.pi / 4), sp.sin(k * sp.pi / 4)


def boundary_sides(S):
    """g_k = |q - c_k|^2 - rho^2 = 1 + |q|^2 - 2 C (q . e_k), k = 0..7: side k of Omega is the arc
    of the circle of centre c_k = C e_k, e_k = (cos k pi/4, sin k pi/4), C = (1 + R0^2)/(1 - R0^2),
    radius rho = sqrt(C^2 - 1) (orthogonal to the unit circle); Omega = {g_k > 0 for all k}."""
    centre = _side_constants()[3]
    out = []
    for k in range(8):
        ck, sk = _rotation(k)
        out.append(1 + S.q1**2 + S.q2**2 - 2 * centre * (ck * S.q1 + sk * S.q2))
    return tuple(out)


def boundary_maps(S):
    """Per side k, the state after the identification z -> rho gamma(conj(rho) z), rho = e^{ik pi/4},
    with (8.3)-(8.4): the formulas of :func:`post_step` in octant k, without its inside test."""
    _, a, b, _ = _side_constants()
    out = []
    for k in range(8):
        ck, sk = _rotation(k)
        w1 = ck * S.q1 + sk * S.q2
        w2 = -sk * S.q1 + ck * S.q2
        w_sq = w1**2 + w2**2
        den = b**2 * w_sq + 2 * a * b * w1 + a**2
        g1 = (a * b * w_sq + (a**2 + b**2) * w1 + a * b) / den                  # [B] (8.3)
        g2 = (a**2 - b**2) * w2 / den
        d1, d2 = b * w1 + a, b * w2                                            # [B] (8.4)
        m1 = (d1**2 - d2**2) / (a**2 - b**2)
        m2 = -2 * d1 * d2 / (a**2 - b**2)
        out.append((ck * g1 - sk * g2, sk * g1 + ck * g2,
                    S.p1 * m1 - S.p2 * m2, S.p1 * m2 + S.p2 * m1))
    return tuple(out)


def _q0(v) -> tuple[float, float]:
    q1 = v.get("q10") if v.get("q10") is not None else DEFAULT_Q[0]
    q2 = v.get("q20") if v.get("q20") is not None else DEFAULT_Q[1]
    return q1, q2


def initial(v):
    """q0 and the momentum of direction ``angle`` with H(q0, p0) = H0."""
    q1, q2 = _q0(v)
    size = 2 * math.sqrt(v["H0"]) / (1 - q1 * q1 - q2 * q2)           # from (8.2)
    return (q1, q2, size * math.cos(v["angle"]), size * math.sin(v["angle"]))


class GeodesicGenus2(Problem):
    def validate(self, values):
        q1, q2, _, _ = self.y0(values)
        require(inside(q1, q2), f"geodesic-genus2: q0 = ({q1:g}, {q2:g}) is not inside the fundamental "
                                "octagon Omega ([B] §8.1); allowed: a point of Omega")


PROBLEM = GeodesicGenus2(
    id="geodesic-genus2",
    title="Geodesic flow on a genus-2 surface of curvature -1",
    reference="[B] §8, (8.1)-(8.4), Figs 31-32",
    state=("q1", "q2", "p1", "p2"),
    params=(
        Param("H0", 0.5, "energy of the default initial point", low=0.0, low_open=True),
        Param("angle", 1.0, "direction of the initial momentum p0 (radians)"),
    ),
    model=model,
    initial=initial,
    canonical=(("p1", "p2"), ("q1", "q2")),
    post_step=post_step,
    boundary=Boundary(boundary_sides, boundary_maps, "[B] §8.1, (8.3)-(8.4)"),
    notes="(choice) q0 = (0.2, 0.1), p0 of direction 1 rad with H0 = 1/2 ([B] picks them at random). "
          "After every step a point outside the octagon Omega is mapped back by (8.3)-(8.4) "
          "(post_step), which preserves H exactly.",
)
