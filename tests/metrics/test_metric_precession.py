"""Argument of the pericenter and precession ([HLW] I.2.3, Fig 2.2; [B] (5.1)) against exact
answers.

* the exact orbit keeps its Runge-Lenz / Laplace vector: rate 0 and a constant eccentricity, to
  round-off; its angle is the orbit's element (ω, or Ω + ω for an orbit in the (q1, q2)-plane);
* the exact orbit turned by Ω t about c0 (q and p both turned) has its vector turned by Ω t,
  since A and e are rotation-equivariant: ω(t) = ω(0) + Ω t, the rate is Ω exactly;
* [HLW] I.2.3: "clockwise for Störmer-Verlet and symplectic Euler, anti-clockwise for the
  implicit midpoint rule" (e = 0.6, h = 0.05, the "step size 100 times larger" than explicit
  Euler's of Fig 2.2).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import parse_problem
from gnibench.suite.metrics.compute import apply, parse_metrics
from support import synthetic_trajectory
from test_metric_eta import rotation

PRECESSION = parse_metrics("precession")


def exact_samples(spec: str, periods: int = 5, per_period: int = 64):
    prob = parse_problem(spec)
    T = prob.record.period(prob.values)
    t = np.arange(0, periods * per_period + 1) * (T / per_period)
    return prob, t, prob.record.exact(t, prob.record.y0(prob.values), prob.values)


@pytest.mark.parametrize("spec,angle", [
    ("kepler-2d", 0.0),                                        # [HLW] (2.11): A along +q1
    ("kepler-3d", math.pi / 2),                                # [B] §5.2: ω = π/2
    ("kepler-3d:omega=1,i=0.3", 1.0),
    ("kepler-3d:i=0,Omega=0.5,omega=1", 1.5),                  # no line of nodes: Ω + ω
])
def test_exact_orbit_does_not_precess(spec, angle):
    prob, t, y = exact_samples(spec)
    out, skipped = apply(synthetic_trajectory(spec, t, y), PRECESSION)
    assert not skipped
    omega = out.columns["pericenter_angle"]
    assert np.max(np.abs(omega - angle)) < 1e-13
    assert abs(out.scalars["precession_rate"]) < 1e-14
    assert out.scalars["eccentricity_range"] < 1e-14
    assert abs(out.columns["eccentricity"][0] - prob.values["e"]) < 1e-14


@pytest.mark.parametrize("spec", ["kepler-2d", "kepler-3d", "kepler-3d:i=0"])
@pytest.mark.parametrize("rate", [0.01, -0.003])
def test_turning_ellipse_precesses_at_its_rate(spec, rate):
    prob, t, y = exact_samples(spec)
    if spec == "kepler-2d":
        c, s = np.cos(rate * t), np.sin(rate * t)
        turn = lambda v: np.column_stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]])
        y = np.column_stack([turn(y[:, :2]), turn(y[:, 2:])])     # (p, q) both turned
    else:
        c0 = np.cross(y[0, :3], y[0, 3:])
        for k, tk in enumerate(t):
            R = rotation(c0, rate * tk)
            y[k, :3], y[k, 3:] = R @ y[k, :3], R @ y[k, 3:]
    out, _ = apply(synthetic_trajectory(spec, t, y), PRECESSION)
    omega = out.columns["pericenter_angle"]
    assert np.max(np.abs(omega - omega[0] - rate * t)) < 1e-12
    assert abs(out.scalars["precession_rate"] - rate) < 1e-13
    T = prob.record.period(prob.values)
    assert abs(out.scalars["precession_per_period"] - rate * T) < 1e-12
    assert abs(out.scalars["pericenter_shift"] - rate * t[-1]) < 1e-12


@pytest.mark.parametrize("method,sign", [
    ("symplectic-euler", -1), ("stormer-verlet", -1), ("implicit-midpoint", +1)])
def test_hlw_precession_directions(method, sign):
    """[HLW] I.2.3, Fig 2.2: clockwise (< 0) for SV and symplectic Euler, anticlockwise (> 0)
    for the implicit midpoint rule."""
    traj = solve("kepler-2d", f"{method}:h=0.05", t_end=20 * math.pi)
    out, _ = apply(traj, PRECESSION)
    rate = out.scalars["precession_rate"]
    assert np.sign(rate) == sign, f"{method}: precession rate {rate:.3e} rad per unit time"
    # and it is a secular turn, not noise: over 10 periods more than 0.05 rad
    assert abs(out.scalars["pericenter_shift"]) > 0.05


def test_where_precession_does_not_apply():
    traj = solve("pendulum", "rk4:h=0.1", steps=10)
    assert "Runge-Lenz" in apply(traj, PRECESSION)[1]["precession"]
