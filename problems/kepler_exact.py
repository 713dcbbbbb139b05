"""Exact Kepler motion through Kepler's equation, [HLW] I.2.2, (2.1).

The orbit is rebuilt from the initial point's elements (semi-major axis from the energy, the
eccentricity vector from the Runge-Lenz vector) and advanced in mean anomaly; Kepler's equation
E - e sin E = M is solved by Newton's method to round-off.

Everything is computed in long double (x87 80-bit, eps 1.1e-19) and rounded to doubles at the end:
in doubles the mean anomaly M = M0 + n t and the elements carry relative errors of a few ulps, which
at e = 0.6 after 20 periods put the "exact" state 3.3e-13 off (measured against 40 digits with
mpmath), more than the integrators it is meant to judge; in long double it is within 1 ulp or so.
"""
from __future__ import annotations

import numpy as np
from gnibench.problems.blockwise import sweeps

LD = np.longdouble
PI = LD("3.14159265358979323846264338327950288")


def solve_kepler(M: np.ndarray, e) -> np.ndarray:
    """Solve E - e sin E = M (vectorized), Newton from Danby's start, to round-off, in the
    precision of M (long double when M is: :func:`kepler_anomaly`)."""
    M = np.asarray(M)
    if M.dtype == LD:
        return kepler_anomaly(M, e)[0]
    M = M.astype(float)
    Mr = np.remainder(M + np.pi, 2 * np.pi) - np.pi              # reduce to [-pi, pi)
    return _newton(Mr, float(e), Mr + 0.85 * float(e) * np.sign(Mr)) + (M - Mr)


def _newton(Mr: np.ndarray, e, E: np.ndarray) -> np.ndarray:
    """Newton's iteration on E - e sin E = Mr from E (Danby's start), to round-off in double: the
    array's sweeps until all its elements converged (evaluated by blocks as in one array:
    :mod:`gnibench.problems.blockwise`)."""
    eps = np.finfo(Mr.dtype).eps

    def sweep(E):
        f = E - e * np.sin(E) - Mr
        dE = f / (1 - e * np.cos(E))
        E = E - dE
        return E, np.all(np.abs(dE) <= 2 * eps * (1 + np.abs(E)))

    return sweeps(sweep, E, 60)


def kepler_anomaly(M: np.ndarray, e) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """E, sin E and cos E (long double) of E - e sin E = M (long double): Newton in double to
    round-off, then two Newton steps in long double (the double root is within a few 1e-16,
    so one step leaves an error of order 1e-31 and the second makes the root's sine and cosine
    consistent at long double round-off); the second step's correction dE (of order
    eps_LD) is carried into sin E and cos E to first order (the second-order term, dE^2, is
    1e-38), so the orbit needs no long double sine or cosine more: long double trig is slow
    (three evaluations in all, where the whole Newton sequence in long double took six to ten)."""
    e = LD(e)
    Mr = np.remainder(M + PI, 2 * PI) - PI                         # reduce to [-pi, pi)
    d = Mr.astype(float)
    E = _newton(d, float(e), d + 0.85 * float(e) * np.sign(d)).astype(LD)
    E = E - (E - e * np.sin(E) - Mr) / (1 - e * np.cos(E.astype(float)).astype(LD))
    sin, cos = np.sin(E), np.cos(E)
    dE = (E - e * sin - Mr) / (1 - e * cos)
    return E - dE + (M - Mr), sin - cos * dE, cos + sin * dE


def kepler_period(q0, p0, mu: float = 1.0) -> float:
    """Period 2 pi a^(3/2) / sqrt(mu) of the bound orbit through (q0, p0) (any dimension), with
    a = -mu / (2 H0) from the initial energy H0 = |p0|^2/2 - mu/|q0| ([B] §5.1; [HLW] (2.11): 2 pi)."""
    q0, p0 = np.asarray(q0, dtype=float), np.asarray(p0, dtype=float)
    energy = 0.5 * float(p0 @ p0) - mu / float(np.sqrt(q0 @ q0))
    if energy >= 0:
        raise ValueError("kepler_period needs a bound orbit (H < 0)")
    a = -mu / (2 * energy)
    return float(2 * np.pi * np.sqrt(a**3 / mu))


def kepler_orbit_2d(q0, p0, t, mu=1.0):
    """Positions and momenta (arrays (len(t), 2)) of the bound Kepler orbit through (q0, p0),
    computed in long double, returned as doubles."""
    q0 = np.asarray(q0, dtype=float).astype(LD)
    p0 = np.asarray(p0, dtype=float).astype(LD)
    mu = LD(mu)
    t = np.asarray(t, dtype=float).astype(LD)
    r0 = np.hypot(*q0)
    L = q0[0] * p0[1] - q0[1] * p0[0]
    energy = 0.5 * p0 @ p0 - mu / r0
    if energy >= 0:
        raise ValueError("kepler_orbit_2d needs a bound orbit (H < 0)")
    a = -mu / (2 * energy)
    evec = np.array([p0[1] * L, -p0[0] * L]) / mu - q0 / r0          # Runge-Lenz / mu
    e = np.hypot(*evec)
    n = np.sqrt(mu / a**3)
    s = 1.0 if L >= 0 else -1.0
    if e < 1e-13:                                                   # circular: measure from q0
        evec_dir = q0 / r0
        E0 = 0.0
    else:
        evec_dir = evec / e
        cosE = (1 - r0 / a) / e
        sinE = (q0 @ p0) / (e * np.sqrt(mu * a))
        E0 = np.arctan2(sinE, cosE)
    M = (E0 - e * np.sin(E0)) + n * t
    _, sin, cos = kepler_anomaly(M, e)        # no long double sine or cosine of E again
    b = a * np.sqrt(1 - e * e)
    x, y = a * (cos - e), b * sin
    denom = 1 - e * cos
    vx, vy = -a * n * sin / denom, b * n * cos / denom
    ex, ey = evec_dir
    # perifocal -> inertial: x along the eccentricity vector, y rotated by +90 deg times sign(L)
    qx, qy = ex * x - s * ey * y, ey * x + s * ex * y
    px, py = ex * vx - s * ey * vy, ey * vx + s * ex * vy
    return (np.column_stack([qx, qy]).astype(float), np.column_stack([px, py]).astype(float))
