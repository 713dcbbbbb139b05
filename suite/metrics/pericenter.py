"""Argument of the pericenter and its precession, from the Runge-Lenz / Laplace vector.

The Runge-Lenz vector A = p × L e_z - q/|q| of the planar Kepler problem (kepler-2d, integrals
A1, A2) and the Laplace vector e = p × c/μ - q/|q| of the spatial one ([B] (5.1); kepler-3d,
integrals e1, e2, e3 with c = q × p, integrals c1, c2, c3) point from the focus to the pericenter,
with length the eccentricity ([B] §5.1). Along a numerical solution they turn: [HLW] I.2.3 (Fig
2.2) "all methods exhibit a precession effect, clockwise for Störmer-Verlet and symplectic Euler,
anti-clockwise for the implicit midpoint rule".

The argument of the pericenter ω(t):

* in the plane, the angle of A from the q1-axis, anticlockwise positive;
* in space, [B] §5.1's ω: the angle in the orbital plane from the line of nodes (the ascending
  node n = e_3 × c) to e, positive about c (the direction of motion), with the instantaneous c;
  for an orbit in the (q1, q2)-plane (no line of nodes: |e_3 × c0| <= 1e-12 |c0|) it is measured
  from the q1-axis about c.

ω is unwrapped from sample to sample (the samples must be close enough that ω changes by less
than π between them). The precession rate is the least-squares slope of ω against t (rad per unit
time; > 0 anticlockwise in the plane, prograde in space).
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.metrics.base import Metric, MetricOutput, integral_names

PLANAR = ("A1", "A2")                                       # kepler-2d: Runge-Lenz vector
SPATIAL = ("e1", "e2", "e3", "c1", "c2", "c3")              # kepler-3d: [B] (5.1)
EQUATORIAL = 1e-12


def _columns(traj, names) -> np.ndarray:
    idx = [traj.integral_names.index(n) for n in names]
    return traj.integrals[:, idx]


def pericenter_angle(traj) -> tuple[np.ndarray, np.ndarray]:
    """(ω(t) unwrapped, eccentricity |A| or |e|) at every sample (see the module docstring)."""
    names = set(traj.integral_names)
    if set(PLANAR) <= names:
        A = _columns(traj, PLANAR)
        angle = np.arctan2(A[:, 1], A[:, 0])
        ecc = np.hypot(A[:, 0], A[:, 1])
    else:
        v = _columns(traj, SPATIAL)
        e, c = v[:, :3], v[:, 3:]
        c_hat = c / np.linalg.norm(c, axis=1)[:, None]
        c0 = c[0]
        if np.hypot(c0[0], c0[1]) <= EQUATORIAL * np.linalg.norm(c0):
            node = np.broadcast_to(np.array([1.0, 0.0, 0.0]), c.shape)
        else:
            node = np.column_stack([-c[:, 1], c[:, 0], np.zeros(len(c))])      # e_3 × c
            node = node / np.linalg.norm(node, axis=1)[:, None]
        sin = np.einsum("ij,ij->i", np.cross(node, e), c_hat)
        angle = np.arctan2(sin, np.einsum("ij,ij->i", node, e))
        ecc = np.linalg.norm(e, axis=1)
    omega = np.full(len(angle), np.nan)
    finite = np.isfinite(angle)
    omega[finite] = np.unwrap(angle[finite])
    return omega, ecc


def precession_rate(t: np.ndarray, omega: np.ndarray) -> float:
    """Least-squares slope of the unwrapped ω against t (rad per unit time); NaN with fewer than
    two finite samples."""
    ok = np.isfinite(omega)
    if ok.sum() < 2 or np.ptp(t[ok]) == 0:
        return float("nan")
    return float(np.polyfit(t[ok], omega[ok], 1)[0])


def _compute(traj, problem, values) -> MetricOutput:
    omega, ecc = pericenter_angle(traj)
    rate = precession_rate(traj.t, omega)
    period = getattr(problem.record, "period", None)
    per_period = rate * float(period(problem.values)) if period is not None else float("nan")
    finite = ecc[np.isfinite(ecc)]
    return MetricOutput(
        columns={"pericenter_angle": omega, "eccentricity": ecc},
        scalars={"precession_rate": rate, "precession_per_period": per_period,
                 "pericenter_shift": float(omega[-1] - omega[0]) if len(omega) else float("nan"),
                 "eccentricity_range": float(np.ptp(finite)) if len(finite) else float("nan")})


def _problem_check(problem, values) -> str:
    names = set(integral_names(problem))
    if set(PLANAR) <= names or set(SPATIAL) <= names:
        return ""
    return (f"{problem.id} has no Runge-Lenz (A1, A2) or Laplace (e1..e3 with c1..c3) vector among "
            "its integrals")


def _check(traj, problem, values) -> str:
    return "" if len(traj.t) >= 2 else f"only {len(traj.t)} sample"


precession = Metric(
    id="precession", title="argument of the pericenter and its precession rate",
    reference="[HLW] I.2.3, Fig 2.2; [B] (5.1), §5.1-5.2",
    doc=("ω(t), the angle of the Runge-Lenz vector (A1, A2) from the q1-axis (plane), or [B]'s "
         "argument of the pericenter (Laplace vector e from the line of nodes, about c; space), "
         "unwrapped; its least-squares slope against t (> 0 anticlockwise / prograde); the "
         "eccentricity |A| or |e|"),
    compute=_compute, needs=("integrals", "samples"),
    columns=(("pericenter_angle", "ω(t), unwrapped, rad"),
             ("eccentricity", "|A| (plane) or |e| (space)")),
    scalars=(("precession_rate", ("least-squares slope of ω against t, rad per unit time (> 0 "
                                 "anticlockwise in the plane, prograde in space)")),
             ("precession_per_period", "precession_rate times the period (NaN without one)"),
             ("pericenter_shift", "ω at the last sample minus ω(0)"),
             ("eccentricity_range", ("max - min of the eccentricity over the samples ([HLW] Fig "
                                    "2.2: symplectic Euler distorts the ellipse)"))),
    problem_check=_problem_check, check=_check,
)
