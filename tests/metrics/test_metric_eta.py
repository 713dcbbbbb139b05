"""η(nT), the position in the orbit ([B] §5.2, Fig 12), against exact answers.

* the exact Kepler flow returns to q(0) at every whole period: η = 0 to round-off. The period
  comes from the initial energy H0 = |p0|^2/2 - μ/|q0|, known to κ ε relative with κ =
  (|p0|^2/2 + μ/|q0|)/|H0| (cancellation); T = 2π (-μ/2H0)^(3/2)/√μ then to (3/2) κ ε, and at the
  pericenter the angle moves dν/dM = (1+e)^2/(1-e^2)^(3/2) times faster than the mean anomaly, so
  after n periods the round-off bound is n 2π (dν/dM) (3/2) κ c ε (c = 4 for the few operations);
* the exact orbit turned by n α about c0 at t = nT: signed phase n α, η = |n α| wrapped to [0, π];
* the exact orbit late by δ of a period at every t = nT, i.e. at mean anomaly -2 π n δ: the
  phase is minus the true anomaly ν(2 π n δ), from Kepler's equation solved here by brentq;
* Störmer-Verlet, order 2: its phase error per period is O(h^2) ([HLW] Table 2.1: global error
  O(t h^2)), so halving h divides the phase drift rate by 4 (asymptotically).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import parse_problem
from gnibench.suite.metrics.compute import apply, parse_metrics, sampling_needs, steps_per_period
from scipy.optimize import brentq
from support import synthetic_trajectory

ETA = parse_metrics("eta")


def exact_at(spec: str, t: np.ndarray) -> np.ndarray:
    prob = parse_problem(spec)
    return prob.record.exact(t, prob.record.y0(prob.values), prob.values)


def period(spec: str) -> float:
    prob = parse_problem(spec)
    return prob.record.period(prob.values)


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation matrix about a unit axis."""
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def true_anomaly(M: float, e: float) -> float:
    """ν for mean anomaly M in (-π, π): E - e sin E = M by brentq, then tan(ν/2) = √((1+e)/(1-e))
    tan(E/2) ([HLW] I.2.2)."""
    E = brentq(lambda E: E - e * math.sin(E) - M, -math.pi, math.pi, xtol=1e-15, rtol=1e-15)
    return 2 * math.atan2(math.sqrt(1 + e) * math.sin(E / 2), math.sqrt(1 - e) * math.cos(E / 2))


def roundoff_bound(spec: str, n) -> np.ndarray:
    """Round-off of η(nT) for the exact flow (module docstring)."""
    prob = parse_problem(spec)
    y0 = np.asarray(prob.record.y0(prob.values))
    p_names, q_names = prob.record.canonical
    state = list(prob.record.state)
    q = y0[[state.index(s) for s in q_names]]
    p = y0[[state.index(s) for s in p_names]]
    mu = prob.values.get("mu", 1.0)
    kinetic, potential = p @ p / 2, mu / np.linalg.norm(q)
    kappa = (kinetic + potential) / abs(kinetic - potential)
    e = prob.values["e"]
    dnu_dM = (1 + e) ** 2 / (1 - e * e) ** 1.5
    return np.asarray(n) * 2 * math.pi * dnu_dM * 1.5 * kappa * 4 * np.finfo(float).eps


def test_period_records():
    assert period("kepler-2d") == pytest.approx(2 * math.pi, rel=1e-14)         # [HLW] (2.11)
    assert period("kepler-2d:e=0.3") == pytest.approx(2 * math.pi, rel=1e-14)
    assert period("kepler-3d") == pytest.approx(1.0, rel=1e-14)                 # [B] §5.2
    assert period("kepler-3d:a=4") == pytest.approx(8.0, rel=1e-14)             # a^(3/2)
    assert period("kepler-3d:ks=true") == period("kepler-3d")
    assert period("harmonic-oscillator") == 2 * math.pi
    assert parse_problem("pendulum").record.period is None


@pytest.mark.parametrize("spec", ["kepler-2d", "kepler-3d", "kepler-3d:ks=true"])
def test_exact_flow_has_no_drift(spec):
    T = period(spec)
    t = np.arange(0, 401) * (T / 4)                  # quarter periods: η only at the whole ones
    traj = synthetic_trajectory(spec, t, exact_at(spec, t))
    out, skipped = apply(traj, ETA)
    assert not skipped
    eta = out.columns["eta"]
    whole = np.arange(len(t)) % 4 == 0
    assert np.all(np.isnan(eta[~whole])) and np.all(np.isfinite(eta[whole]))
    bound = roundoff_bound(spec, np.arange(0, 101))
    assert np.all(eta[whole] <= bound + 1e-15)
    s = out.scalars
    assert s["eta_periods"] == 100 and s["eta_final"] <= bound[-1]
    assert abs(s["eta_phase_rate"]) <= bound[1]


@pytest.mark.parametrize("alpha", [0.1, -0.07])
def test_orbit_turned_by_a_known_angle_per_period(alpha):
    spec = "kepler-3d"
    T = period(spec)
    n = np.arange(0, 101)
    y = exact_at(spec, n * T)
    q0, p0 = y[0, :3], y[0, 3:]
    c0 = np.cross(q0, p0)
    for k in n:
        R = rotation(c0, alpha * k)
        y[k, :3], y[k, 3:] = R @ y[k, :3], R @ y[k, 3:]
    out, _ = apply(synthetic_trajectory(spec, n * T, y), ETA)
    phase = out.columns["eta_phase"]
    bound = roundoff_bound(spec, n) + 1e-14
    assert np.all(np.abs(phase - alpha * n) <= bound)              # unwrapped past π
    wrapped = np.abs(np.angle(np.exp(1j * alpha * n)))
    assert np.all(np.abs(out.columns["eta"] - wrapped) <= bound)
    s = out.scalars
    assert abs(s["eta_phase_rate"] - alpha) <= bound[1]
    assert abs(s["eta_exponent"] - 1.0) < 1e-9                      # |phase| = |α| t / T
    assert abs(s["eta_final"] - wrapped[-1]) <= bound[-1]


def test_orbit_late_by_a_fraction_of_a_period():
    spec, e, delta = "kepler-2d", 0.6, 1e-3
    T = period(spec)
    n = np.arange(0, 101)
    y = exact_at(spec, (1 - delta) * n * T)
    out, _ = apply(synthetic_trajectory(spec, n * T, y), ETA)
    expected = np.array([-true_anomaly(2 * math.pi * k * delta, e) for k in n])
    bound = roundoff_bound(spec, n) + 1e-14
    assert np.all(np.abs(out.columns["eta_phase"] - expected) <= bound)
    assert np.all(np.abs(out.columns["eta"] - np.abs(expected)) <= bound)


def test_integrated_eta_is_the_seed_formula():
    """On a real trajectory, η equals [B] §5.2's arccos formula where arccos is accurate."""
    spec = "kepler-2d"
    T = period(spec)
    N = 200
    traj = solve(spec, f"stormer-verlet:h={T / N!r}", steps=N * 30, every=N // 4)
    out, _ = apply(traj, ETA)
    eta = out.columns["eta"]
    q = traj.y[:, 2:]
    cos = q @ q[0] / (np.linalg.norm(q, axis=1) * np.linalg.norm(q[0]))
    seed = np.arccos(np.clip(cos, -1, 1))
    whole = np.isfinite(eta)
    assert whole.sum() == 31 and np.all(np.isnan(eta[np.arange(len(eta)) % 4 != 0]))
    big = whole & (seed > 1e-3) & (seed < math.pi - 1e-3)
    assert big.sum() > 20
    assert np.allclose(eta[big], seed[big], rtol=0, atol=1e-10)


def test_stormer_verlet_phase_drift_is_second_order():
    spec = "kepler-2d"
    T = period(spec)
    rates = []
    for N in (1600, 3200):
        traj = solve(spec, f"stormer-verlet:h={T / N!r}", steps=N * 10, every=N)
        out, _ = apply(traj, ETA)
        rates.append(out.scalars["eta_phase_rate"])
    assert rates[0] < 0 and rates[1] < 0                  # it lags behind (measured)
    assert 3.98 < rates[0] / rates[1] < 4.02


def test_ks_trajectory_mapped_back():
    """K-S [B] (5.4) runs in s: at s = n (one revolution per unit s for the default orbit) t is n
    only to the integration error, so the samples are whole periods only at a loose rtol."""
    spec = "kepler-3d:ks=true"
    traj = solve(spec, "rk4:h=0.005", steps=1000, every=200)
    _, skipped = apply(traj, ETA)
    assert "no sample at a whole period" in skipped["eta"]
    out, skipped = apply(traj, parse_metrics(["eta:rtol=1e-6"]))
    assert not skipped and out.scalars["eta_periods"] == 5
    # the angle is at most the position error over |q(0)| (to first order)
    q0 = np.linalg.norm(traj.y0[:3])
    assert out.scalars["eta_max"] <= 2 * out.scalars["max_global_error"] / q0


def test_where_eta_does_not_apply():
    traj = solve("pendulum", "rk4:h=0.1", steps=10)
    assert apply(traj, ETA)[1] == {"eta": "pendulum has no period"}
    traj = solve("harmonic-oscillator", "rk4:h=0.1", steps=10)
    assert "position component" in apply(traj, ETA)[1]["eta"]
    traj = solve("kepler-2d", "rk4:h=0.1", steps=10)
    assert "no sample at a whole period" in apply(traj, ETA)[1]["eta"]


def test_sampling_helpers():
    prob = parse_problem("kepler-3d")
    assert sampling_needs(ETA, prob) == {"dt_out": prob.record.period(prob.values)}
    assert sampling_needs(parse_metrics("growth"), prob) == {}
    assert sampling_needs(ETA, parse_problem("pendulum")) == {}
    T = 2 * math.pi
    assert steps_per_period(T / 100, T) == 100 and steps_per_period(0.1, T) is None


def test_eta_sets_the_period_grid_in_experiments_and_solve():
    """A group with eta and no dt_out samples at t = nT: adaptive and engine cells get dt_out = T;
    a fixed-step cell whose `every` steps make whole periods keeps its own grid; an explicit
    dt_out is kept."""
    from gnibench.suite.runs.experiment import parse_experiment

    head = 'name = "e"\ntitle = "t"\nreference = "[B] §5.2"\nt_end = 3.0\nmetrics = ["eta"]\n'
    cells = parse_experiment(head + '[[cells]]\nproblems = ["kepler-3d"]\n'
                             'methods = ["dopri5:rtol=1e-8,atol=1e-8", "rk4:h=0.01"]\nevery = 100\n'
                             '[[cells]]\nproblems = ["kepler-3d"]\nmethods = ["rk4:h=0.01"]\n'
                             'every = 7\n[[cells]]\nproblems = ["kepler-3d"]\n'
                             'methods = ["dopri5:rtol=1e-8,atol=1e-8"]\ndt_out = 0.5\n', "e").cells
    assert [c.dt_out for c in cells] == [pytest.approx(1.0, rel=1e-14), None,
                                         pytest.approx(1.0, rel=1e-14), 0.5]


@pytest.mark.parametrize("angle", [1e-12, 1e-9, 3e-8, 1e-4, 1.0, math.pi - 1e-9, -1e-10])
def test_tiny_and_near_pi_angles_keep_their_digits(angle):
    """η ([B] §5.2, the angle between q(nT) and q(0)) by atan2(|q0 × q|, q0·q): absolute error
    a few ε at every angle. The seed's arccos(q0·q / |q0||q|) cannot resolve angles below
    √(2ε) ≈ 2e-8 (cos θ = 1 - θ²/2 rounds to 1) nor within that of π (mutant eta-arccos)."""
    from gnibench.suite.metrics.position_in_orbit import signed_angles

    q0 = np.array([0.3, -1.2, 0.7])
    p0 = np.array([0.9, 0.4, -0.2])
    c0 = np.cross(q0, p0)
    q = (rotation(c0, angle) @ q0)[None, :] * np.array([[1.0], [2.5]])    # any |q|
    got = signed_angles(q0, q, c0)
    assert np.all(np.abs(got - angle) <= 8 * np.finfo(float).eps * max(1.0, abs(angle))), got
