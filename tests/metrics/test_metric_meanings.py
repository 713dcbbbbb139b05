"""What each per-cell number means where it differs from its neighbours.

A scalar and its neighbour often coincide on the cells the seeds run (a growing error: its final
value is its maximum; a steady precession: its least-squares rate is its shift over the run), so
a swapped or mistaken definition passes every claim. Each test below builds samples on which the
neighbours differ by construction (an error that is not monotone, a wobbling pericenter, an
integral of negative value) and checks every scalar against its own definition, computed here
independently of the metric's code (numpy on the samples, the problem's formulas written out):

* global error ([HLW] Fig 2.3): final_global_error = |y(T) - y_ref(T)| at the last sample,
  max_global_error = max over the samples, on an error that peaks mid-run;
* integral errors ([B] §2): err_H = H(y) - H(y0) with its sign, relerr_H = err_H / |H(y0)| (H < 0
  for the Kepler problem: a division by H(y0) flips it), max_abs / max_rel their maxima;
* precession ([HLW] I.2.3): the rate is the least-squares slope of ω, not the shift over the run
  divided by the time; the shift is ω(T) - ω(0); per period = rate x the period;
* growth (the claims inventory's conventions): drift = least-squares slope over the window, mean, oscillation =
  half the peak-to-peak of the residual, max over [0, T/2] and [T/2, T] and their ratio.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.spec import parse_problem
from gnibench.suite.metrics.compute import apply, parse_metrics
from support import synthetic_trajectory


def kepler_samples(spec="kepler-2d:e=0.6", periods=3, per_period=200):
    prob = parse_problem(spec)
    T = prob.record.period(prob.values)
    t = np.arange(periods * per_period + 1) * (T / per_period)
    return prob, t, prob.record.exact(t, prob.record.y0(prob.values), prob.values)


def bump(t):
    """A positive error that peaks mid-run and ends below its maximum, not monotone."""
    x = t / t[-1]
    return 1e-3 * (0.2 + np.sin(math.pi * x) ** 2 + 0.3 * np.sin(7 * math.pi * x) ** 2)


def test_final_and_maximum_global_error_differ_where_the_error_is_not_monotone():
    prob, t, y = kepler_samples()
    a = bump(t)
    assert a[-1] < 0.5 * a.max() and np.any(np.diff(a) < 0) and np.any(np.diff(a) > 0)
    moved = y.copy()
    moved[:, 2] += a                                 # q1 off by a(t): |y - y_ref| = a(t)
    traj = synthetic_trajectory("kepler-2d:e=0.6", t, moved, exact_reference=True, y0=y[0])
    out, skipped = apply(traj, parse_metrics("global_error"))
    assert not skipped
    g = np.linalg.norm(moved - y, axis=1)            # the definition, on the samples
    assert np.array_equal(out.columns["global_error"], g)
    assert out.scalars["final_global_error"] == g[-1]
    assert out.scalars["max_global_error"] == g.max()
    assert out.scalars["final_global_error"] < 0.5 * out.scalars["max_global_error"]


def test_global_error_of_a_solved_cell_is_its_distance_to_the_exact_solution():
    """A real cell (Störmer-Verlet on the eccentric orbit, whose error swings within each
    period): the scalars are the distance of the last and the worst sample to the problem's
    exact solution evaluated here."""
    from gnibench.suite.cell.solve import solve

    traj = solve("kepler-2d:e=0.6", "stormer-verlet:h=0.05", t_end=15.5)
    prob = parse_problem("kepler-2d:e=0.6")
    exact = prob.record.exact(traj.t, prob.record.y0(prob.values), prob.values)
    g = np.linalg.norm(traj.y - exact, axis=1)
    out, _ = apply(traj, parse_metrics("global_error"))
    assert np.any(np.diff(g) < 0), "the error of this cell must not be monotone"
    assert out.scalars["final_global_error"] == pytest.approx(g[-1], rel=1e-12, abs=1e-15)
    assert out.scalars["max_global_error"] == pytest.approx(g.max(), rel=1e-12)
    assert out.scalars["final_global_error"] < 0.9 * out.scalars["max_global_error"]


def energy(y):
    """H = |p|²/2 - 1/|q| of kepler-2d (μ = 1; state (p1, p2, q1, q2)), written out."""
    return 0.5 * (y[:, 0] ** 2 + y[:, 1] ** 2) - 1.0 / np.hypot(y[:, 2], y[:, 3])


def with_energy_error(y, d):
    """The samples with the momenta scaled so that H(y) - H(y0) = d(t) (d(0) = 0)."""
    p2 = y[:, 0] ** 2 + y[:, 1] ** 2
    s = np.sqrt(1.0 + 2.0 * d / p2)
    out = y.copy()
    out[:, :2] *= s[:, None]
    return out


def test_integral_errors_keep_their_sign_and_the_relative_one_divides_by_the_magnitude():
    prob, t, y = kepler_samples()
    d = 1e-4 * np.sin(3 * t) * t / t[-1]             # both signs, not monotone
    moved = with_energy_error(y, d)
    traj = synthetic_trajectory("kepler-2d:e=0.6", t, moved)
    out, _ = apply(traj, parse_metrics("invariant_error,relative_invariant_error"))
    H0 = energy(moved[:1])[0]
    assert H0 < 0
    err = energy(moved) - H0
    assert np.max(np.abs(err - d)) < 1e-13            # the construction
    assert np.max(np.abs(out.columns["err_H"] - err)) < 1e-15
    assert np.max(np.abs(out.columns["relerr_H"] - err / abs(H0))) < 1e-15
    assert out.scalars["max_abs_err_H"] == pytest.approx(np.max(np.abs(err)), rel=1e-12)
    assert out.scalars["max_rel_err_H"] == pytest.approx(np.max(np.abs(err)) / abs(H0), rel=1e-12)


def turned(spec, t, y, phi):
    """The orbit's samples turned by phi(t) about its angular momentum c0 (q and p both)."""
    from test_metric_eta import rotation

    y = y.copy()
    if spec.startswith("kepler-2d"):
        c, s = np.cos(phi), np.sin(phi)
        for a, b in ((0, 1), (2, 3)):
            y[:, a], y[:, b] = c * y[:, a] - s * y[:, b], s * y[:, a] + c * y[:, b]
        return y
    c0 = np.cross(y[0, :3], y[0, 3:])
    for k in range(len(t)):
        R = rotation(c0, phi[k])
        y[k, :3], y[k, 3:] = R @ y[k, :3], R @ y[k, 3:]
    return y


@pytest.mark.parametrize("spec", ["kepler-2d:e=0.6", "kepler-3d", "kepler-3d:i=2.5"])
def test_precession_rate_is_the_fitted_slope_and_the_shift_the_change(spec):
    """ω(t) = ω0 + Ω t + A sin(ν t): the least-squares slope of ω, its change over the run and
    the rate per period are three different numbers, each checked against its definition
    (prograde > 0: a retrograde orbit, i > π/2, turned in its own sense too)."""
    prob, t, y = kepler_samples(spec, periods=4, per_period=50)
    phi = 0.002 * t + 0.03 * np.sin(1.3 * t)
    traj = synthetic_trajectory(spec, t, turned(spec, t, y, phi))
    out, _ = apply(traj, parse_metrics("precession"))
    omega = out.columns["pericenter_angle"]
    assert np.max(np.abs(omega - omega[0] - phi)) < 1e-12
    slope = np.polyfit(t, phi, 1)[0]
    shift = phi[-1] - phi[0]
    assert abs(shift / t[-1] - slope) > 1e-4            # the neighbours differ here
    assert out.scalars["precession_rate"] == pytest.approx(slope, abs=1e-13)
    assert out.scalars["pericenter_shift"] == pytest.approx(shift, abs=1e-12)
    T = prob.record.period(prob.values)
    assert out.scalars["precession_per_period"] == pytest.approx(slope * T, abs=1e-12)


@pytest.mark.parametrize("spec", ["kepler-3d", "kepler-3d:i=2.5"])
def test_spatial_pericenter_is_unmoved_by_a_turn_of_the_node(spec):
    """Closed form of [B] §5.1's ω: turning the whole orbit about e_3 moves its node (Ω) and
    leaves its argument of the pericenter unchanged, whatever the angle; turning it about c0 by
    +α (the direction of motion) adds +α to ω, also on a retrograde orbit."""
    from test_metric_eta import rotation

    prob, t, y = kepler_samples(spec, periods=2, per_period=40)
    nodal = y.copy()
    for k, tk in enumerate(t):
        R = rotation(np.array([0.0, 0.0, 1.0]), 0.05 * tk)
        nodal[k, :3], nodal[k, 3:] = R @ y[k, :3], R @ y[k, 3:]
    out, _ = apply(synthetic_trajectory(spec, t, nodal), parse_metrics("precession"))
    assert np.max(np.abs(out.columns["pericenter_angle"] - prob.values["omega"])) < 1e-12
    assert abs(out.scalars["precession_rate"]) < 1e-13
    ahead = turned(spec, t, y, 0.01 * t)
    out, _ = apply(synthetic_trajectory(spec, t, ahead), parse_metrics("precession"))
    assert out.scalars["precession_rate"] == pytest.approx(0.01, abs=1e-13)


@pytest.mark.parametrize("late_larger", [False, True])
def test_growth_scalars_are_their_definitions_on_a_drifting_oscillating_error(late_larger):
    """An error larger early than late, and one larger late than early: each maximum is over its
    own half, the ratio theirs."""
    prob, t, y = kepler_samples(periods=6, per_period=100)
    T = t[-1]
    fade = np.exp(t / T) if late_larger else np.exp(-t / T)
    d = 2e-6 * t / T + 1e-5 * np.sin(2.1 * t) * fade
    moved = with_energy_error(y, d)
    traj = synthetic_trajectory("kepler-2d:e=0.6", t, moved)
    out, _ = apply(traj, parse_metrics("growth:of=H,window=0.25/1"))
    s = out.scalars
    err = energy(moved) - energy(moved[:1])[0]
    inside = (t >= 0.25 * T) & (t <= T)
    slope, offset = np.polyfit(t[inside], err[inside], 1)
    residual = err[inside] - (offset + slope * t[inside])
    early, late = np.max(np.abs(err[t <= T / 2])), np.max(np.abs(err[t >= T / 2]))
    assert (late > 1.25 * early) if late_larger else (late < 0.8 * early)   # they differ
    assert s["drift_H"] == pytest.approx(slope, rel=1e-9)
    assert s["mean_err_H"] == pytest.approx(np.mean(err[inside]), rel=1e-9)
    assert s["oscillation_H"] == pytest.approx(np.ptp(residual) / 2, rel=1e-9)
    assert s["max_early_H"] == pytest.approx(early, rel=1e-9)
    assert s["max_late_H"] == pytest.approx(late, rel=1e-9)
    assert s["late_early_ratio_H"] == pytest.approx(late / early, rel=1e-9)
    assert (s["growth_window_start"], s["growth_window_end"]) == (0.25 * T, T)
    env = out.columns["envelope_H"]
    assert np.max(np.abs(env - np.maximum.accumulate(np.abs(err)))) < 1e-15


def test_two_samples_are_enough_for_a_precession_rate():
    """The least-squares slope of two points is the line through them: a cell sampled only at its
    start and end (every = all its steps) still has a precession rate, (ω1 - ω0) / (t1 - t0)."""
    prob, t, y = kepler_samples("kepler-2d:e=0.6", periods=1, per_period=8)
    t2 = t[[0, 3]]
    phi = np.array([0.0, 0.02])
    traj = synthetic_trajectory("kepler-2d:e=0.6", t2, turned("kepler-2d", t2, y[[0, 3]], phi))
    out, skipped = apply(traj, parse_metrics("precession"))
    assert not skipped
    assert out.scalars["precession_rate"] == pytest.approx(0.02 / t2[1], rel=1e-12)
    assert out.scalars["pericenter_shift"] == pytest.approx(0.02, rel=1e-12)


def test_eta_scalars_differ_where_the_phase_is_not_monotone():
    """[B] §5.2's η at whole periods n T: an orbit turned by φ(n) about c0, with φ rising and
    falling back (so the final η is far below the maximum, and the envelope of the phase grows
    more slowly over the last decade [T_end/10, T_end] than from the first period on: the
    window's growth exponent is not the whole run's; a window needs 0.8 of a decade of t,
    suite/metrics/growth.py): each scalar against its definition."""
    from gnibench.suite.metrics.growth import envelope, growth_exponent
    from test_metric_eta import exact_at, period, rotation

    spec = "kepler-3d"
    T = period(spec)
    n = np.arange(0, 81)
    phi = 0.3 * np.sin(np.pi * n / 80) + np.where(n > 40, 5e-5 * (n - 40.0) ** 2, 0.0)
    y = exact_at(spec, n * T)
    c0 = np.cross(y[0, :3], y[0, 3:])
    for k in n:
        R = rotation(c0, phi[k])
        y[k, :3], y[k, 3:] = R @ y[k, :3], R @ y[k, 3:]
    out, _ = apply(synthetic_trajectory(spec, n * T, y), parse_metrics("eta:window=0.1/1"))
    s = out.scalars
    assert np.max(np.abs(out.columns["eta_phase"] - phi)) < 1e-10
    assert s["eta_final"] == pytest.approx(abs(phi[-1]), abs=1e-10)
    assert s["eta_max"] == pytest.approx(np.max(np.abs(phi[1:])), abs=1e-10)
    assert s["eta_final"] < 0.5 * s["eta_max"]                          # they differ here
    assert s["eta_phase_final"] == pytest.approx(phi[-1], abs=1e-10)
    assert s["eta_phase_rate"] == pytest.approx(np.polyfit(n, phi, 1)[0], abs=1e-10)
    t = n * T
    late = growth_exponent(t, envelope(phi), 0.1 * t[-1], t[-1])
    whole = growth_exponent(t, envelope(phi), t[1], t[-1])
    assert abs(late - whole) > 0.1                                       # the window matters
    assert s["eta_exponent"] == pytest.approx(late, abs=1e-6)


def test_a_diverged_run_has_no_precession_rate_and_no_error():
    """Every state non-finite (a run that diverged at once): ω is NaN everywhere and the rate is
    NaN, a value, not an exception."""
    prob, t, y = kepler_samples("kepler-2d:e=0.6", periods=1, per_period=8)
    bad = np.full_like(y, np.nan)
    bad[0] = y[0]
    traj = synthetic_trajectory("kepler-2d:e=0.6", t, bad, y0=y[0])
    traj.integrals[0] = np.nan                       # not even the first sample is usable
    out, _ = apply(traj, parse_metrics("precession"))
    assert math.isnan(out.scalars["precession_rate"])
