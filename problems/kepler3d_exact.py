"""Spatial Kepler orbits: orbital elements <-> state, and exact motion, [B] §5, (5.1).

The orbit's plane is spanned by the unit vector P towards the pericenter (along the Laplace vector
e, [B] (5.1)) and Q = c/|c| x P. In that basis the motion is the planar Kepler motion of
:func:`gnibench.problems.kepler_exact.kepler_orbit_2d`, so the 3-D solution reuses Kepler's equation there.

Elements follow the usual convention: the inclination i is the angle between c and the q3-axis
(the OCR'd text of [B] §5.1 says "the q1-axis", a slip: the line of nodes is the intersection with
the (q1, q2)-plane), Ω the longitude of the ascending node, ω the argument of the pericenter, M the
mean anomaly. Position = R3(Ω) R1(i) R3(ω) (perifocal position).
"""
from __future__ import annotations

import numpy as np
from gnibench.problems.kepler_exact import kepler_orbit_2d, solve_kepler


def _rotation(i: float, Omega: float, omega: float) -> np.ndarray:
    """R3(Ω) R1(i) R3(ω): columns are P (to the pericenter), Q, and c/|c|."""
    cO, sO, ci, si, cw, sw = (np.cos(Omega), np.sin(Omega), np.cos(i), np.sin(i),
                              np.cos(omega), np.sin(omega))
    R3O = np.array([[cO, -sO, 0.0], [sO, cO, 0.0], [0.0, 0.0, 1.0]])
    R1i = np.array([[1.0, 0.0, 0.0], [0.0, ci, -si], [0.0, si, ci]])
    R3w = np.array([[cw, -sw, 0.0], [sw, cw, 0.0], [0.0, 0.0, 1.0]])
    return R3O @ R1i @ R3w


def state_from_elements(a: float, e: float, i: float, Omega: float, omega: float, M: float,
                        mu: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and momentum (unit mass) of the elliptic orbit with these elements at anomaly M."""
    E = float(solve_kepler(np.array([M]), e)[0])
    n = np.sqrt(mu / a**3)
    b = a * np.sqrt(1 - e * e)
    denom = 1 - e * np.cos(E)
    x, y = a * (np.cos(E) - e), b * np.sin(E)
    vx, vy = -a * n * np.sin(E) / denom, b * n * np.cos(E) / denom
    R = _rotation(i, Omega, omega)
    return R @ np.array([x, y, 0.0]), R @ np.array([vx, vy, 0.0])


def elements_from_state(q, p, mu: float) -> dict[str, float]:
    """Elements (a, e, i, Omega, omega, M) of the bound orbit through (q, p); angles in [0, 2π)."""
    q, p = np.asarray(q, dtype=float), np.asarray(p, dtype=float)
    r = np.linalg.norm(q)
    c = np.cross(q, p)                                      # [B] (5.1)
    evec = np.cross(p, c) / mu - q / r                      # [B] (5.1)
    energy = 0.5 * p @ p - mu / r
    a = -mu / (2 * energy)
    e = float(np.linalg.norm(evec))
    i = float(np.arccos(c[2] / np.linalg.norm(c)))
    node = np.array([-c[1], c[0], 0.0])                     # e3 x c: towards the ascending node
    Omega = float(np.arctan2(node[1], node[0]))
    # ω: angle from the node to e, measured in the orbit plane in the sense of motion
    nhat = node / np.linalg.norm(node)
    omega = float(np.arctan2(np.cross(nhat, evec) @ c / np.linalg.norm(c), nhat @ evec))
    cosE = (1 - r / a) / e
    sinE = (q @ p) / (e * np.sqrt(mu * a))
    E = np.arctan2(sinE, cosE)
    M = float(E - e * np.sin(E))
    tau = 2 * np.pi
    return {"a": float(a), "e": e, "i": i, "Omega": Omega % tau, "omega": omega % tau, "M": M % tau}


def kepler_orbit_3d(q0, p0, t, mu: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions and momenta (arrays (len(t), 3)) of the bound spatial Kepler orbit through (q0, p0).

    Needs c = q x p != 0 (not a straight-line orbit) and H < 0.
    """
    q0, p0 = np.asarray(q0, dtype=float), np.asarray(p0, dtype=float)
    c = np.cross(q0, p0)
    cn = np.linalg.norm(c)
    if cn == 0.0:
        raise ValueError("kepler_orbit_3d needs c = q x p != 0")
    k = c / cn
    P = q0 / np.linalg.norm(q0)                 # any in-plane basis works: kepler_orbit_2d
    Q = np.cross(k, P)                          # measures from the Laplace vector itself
    q2, p2 = kepler_orbit_2d(np.array([q0 @ P, q0 @ Q]), np.array([p0 @ P, p0 @ Q]),
                             np.asarray(t, dtype=float), mu=mu)
    basis = np.stack([P, Q])                    # (2, 3)
    return q2 @ basis, p2 @ basis
