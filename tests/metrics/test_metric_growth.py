"""The growth metric (suite/metrics/growth.py) against errors whose growth is known exactly.

* c t^a: the envelope is c t^a itself, its log-log slope is a;
* a + b t + A sin(ωt) over a window of whole periods of length W: the least-squares line has
  slope b + β with |β| <= 12 A / (ω W^2) (the slope of A sin ωt: ∫(t - t̄) sin ωt dt over whole
  periods is -cos(ω t0) W / ω, and Σ(t - t̄)^2 = W^3/12), the residual is A sin ωt - β (t - t̄), so
  the oscillation is A within |β| W / 2 (plus the sampling of the sine's peak, A (ω dt)^2 / 8);
* explicit Euler on the harmonic oscillator: H_n = H0 (1 + h^2)^n exactly ([HLW] (1.5) applied to
  p' = -q, q' = p), so err_H(t) = H0 (e^x - 1) with x = t log(1 + h^2) / h, whose log-log slope
  x e^x / (e^x - 1) lies in [1, 1 + x] (the least-squares slope is a positively weighted mean of
  divided differences, so it lies between the extremes of the local slope).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.compute import apply, parse_metrics
from gnibench.suite.metrics.growth import (
    drift_and_oscillation,
    early_late_maxima,
    envelope,
    growth_exponent,
    growth_fit,
)
from support import synthetic_trajectory


def test_envelope_is_the_running_max_and_keeps_a_divergence():
    err = np.array([0.0, -1.0, 0.5, 2.0, np.nan, 1.0])
    assert envelope(err).tolist() == [0.0, 1.0, 1.0, 2.0, math.inf, math.inf]


@pytest.mark.parametrize("a", [0.5, 1.0, 2.0])
def test_exponent_of_a_power_law(a):
    t = np.linspace(0.0, 100.0, 10_001)
    err = -3.0 * t**a                       # the sign does not matter
    assert abs(growth_exponent(t, envelope(err), 1.0, 100.0) - a) < 1e-12
    # uneven sampling: each decade still weighs the same
    t2 = np.concatenate([np.linspace(0, 10, 11), np.linspace(10.5, 100, 5000)])
    assert abs(growth_exponent(t2, envelope(-3.0 * t2**a), 1.0, 100.0) - a) < 1e-12


def test_exponent_edge_cases():
    t = np.linspace(0.0, 10.0, 101)
    assert growth_exponent(t, np.zeros_like(t), 0.1, 10.0) != growth_exponent(
        t, np.zeros_like(t), 0.1, 10.0)                                     # NaN: nothing to fit
    env = envelope(np.where(t > 5, np.nan, t))
    assert growth_exponent(t, env, 0.1, 10.0) == math.inf                   # diverged in the window


def test_no_exponent_over_less_than_a_decade():
    """A slope of log envelope against log t over [0.3 T, T] says nothing about t^p: NaN and why;
    over a decade (0.8 of one at least) and three samples there is one."""
    t = np.linspace(0.0, 10.0, 11)
    env = envelope(t ** 2)
    p, why = growth_fit(t, env, 3.0, 10.0)
    assert math.isnan(p) and why == ("the samples span t = 3 to 10, 0.52 decades; at least 0.8 "
                                     "needed")
    p, why = growth_fit(t, env, 1.0, 10.0)
    assert abs(p - 2) < 1e-12 and why == ""
    p, why = growth_fit(np.array([0.0, 5.0, 10.0]), np.array([0.0, 1.0, 2.0]), 0.1, 10.0)
    assert math.isnan(p) and why == "2 usable samples in the fit window, 3 needed"


def test_the_metric_says_why_there_is_no_exponent():
    traj = solve("harmonic-oscillator", "euler:h=0.5", steps=20, every=10)
    metrics, _ = apply(traj, parse_metrics(["growth:of=H"]))
    assert math.isnan(metrics.scalars["growth_exponent_H"])
    assert metrics.scalars["growth_reason_H"] == ("2 usable samples in the fit window, 3 needed")


def test_drift_and_oscillation_of_a_line_plus_a_sine():
    a, b, A, omega = 2e-3, 1e-4, 1e-3, 2 * math.pi * 5
    dt = 1e-3
    t = np.arange(0, 100_001) * dt
    err = a + b * t + A * np.sin(omega * t)
    t_lo, t_hi = 1.0, 100.0                    # 495 whole periods of the sine
    W = t_hi - t_lo
    beta = 12 * A / (omega * W**2)
    drift, mean, amplitude = drift_and_oscillation(t, err, t_lo, t_hi)
    assert abs(drift - b) <= beta
    assert abs(amplitude - A) <= beta * W / 2 + A * (omega * dt) ** 2 / 8
    # over whole periods the sine averages to zero: the mean is the line's value at the centre
    assert abs(mean - (a + b * (t_lo + t_hi) / 2)) < 1e-12
    # bounded (b = 0): the envelope is flat after the first peak, the exponent 0
    flat = a + A * np.sin(omega * t)
    assert abs(growth_exponent(t, envelope(flat), t_lo, t_hi)) < 1e-12
    assert early_late_maxima(t, flat)[2] == 1.0


def test_early_late_maxima():
    t = np.linspace(0, 10, 101)
    assert early_late_maxima(t, t) == (5.0, 10.0, 2.0)
    assert early_late_maxima(t, np.zeros_like(t)) == (0.0, 0.0, 1.0)     # exact: no drift
    assert early_late_maxima(t, np.where(t > 6, 1e-16, 0.0))[2] == math.inf


def test_metric_on_the_exact_harmonic_oscillator_and_its_options():
    t = np.linspace(0, 20, 2001)
    y = np.column_stack([np.cos(t), -np.sin(t)])
    traj = synthetic_trajectory("harmonic-oscillator", t, y, exact_reference=True)
    out, skipped = apply(traj, parse_metrics("growth"))
    assert not skipped
    assert set(out.columns) >= {"envelope_H", "envelope_global"}
    assert out.scalars["growth_window_start"] == pytest.approx(0.2)
    assert out.scalars["max_late_H"] < 1e-15 and out.scalars["max_late_global"] < 1e-14
    out, _ = apply(traj, parse_metrics(["growth:of=global,window=0.5/1"]))
    assert "envelope_H" not in out.columns and out.scalars["growth_window_start"] == 10.0
    with pytest.raises(UserError, match="window"):
        parse_metrics(["growth:window=0.5/0.1"])
    with pytest.raises(UserError, match="chosen twice"):
        parse_metrics(["growth:of=H", "growth:of=global"])
    _, skipped = apply(traj, parse_metrics(["growth:of=Q"]))
    assert "has no error Q" in skipped["growth:of=Q"]


def test_explicit_euler_energy_grows_linearly_on_the_oscillator():
    """[HLW] Table 2.1's O(th) for explicit Euler, in closed form on the harmonic oscillator."""
    h, n = 1e-3, 10_000
    traj = solve("harmonic-oscillator", f"euler:h={h}", steps=n, every=10)
    out, _ = apply(traj, parse_metrics("growth:of=H"))
    H0 = 0.5
    x = traj.t * math.log1p(h * h) / h
    exact = H0 * np.expm1(x)
    assert np.allclose(out.columns["envelope_H"], exact, rtol=1e-9, atol=0)
    x_max = x[-1]
    assert 1.0 <= out.scalars["growth_exponent_H"] <= 1.0 + x_max
    assert out.scalars["drift_H"] > 0 and out.scalars["late_early_ratio_H"] > 1.9


def test_symplectic_euler_energy_error_is_bounded_on_the_oscillator():
    """[HLW] I.2.3: no secular terms for symplectic Euler; the claims inventory 'bounded / no drift'."""
    traj = solve("harmonic-oscillator", "symplectic-euler:h=0.01", steps=20_000, every=10)
    out, _ = apply(traj, parse_metrics("growth:of=H"))
    s = out.scalars
    assert s["growth_exponent_H"] <= 0.1 and s["late_early_ratio_H"] <= 1.5
    # the energy error is (h/2)(p0 q0 - p q) + O(h^2) (symplectic Euler keeps H - (h/2) p q up to
    # O(h^2)): amplitude h/4, frequency 2, no drift. Over a window [t0, t1] of length W the
    # least-squares slope of A sin(2t + c) is at most 12 A (W/2 + 1/4) / W^3 (integration by parts).
    h, A = 0.01, s["oscillation_H"]
    assert abs(A - h / 4) <= h**2
    W = s["growth_window_end"] - s["growth_window_start"]
    assert abs(s["drift_H"]) <= 12 * A * (W / 2 + 0.25) / W**3


def test_each_decade_weighs_the_same_for_a_broken_power_law():
    """env = t on [1, 10], 10 (t/10)^3 on [10, 100]: with equal weight per decade (log-spaced
    points, as documented) the least-squares slope over [1, 100] is the mean of the two local
    slopes, 2, up to the sampling (about 1/points); linearly spaced points would weigh the last
    decade ~90 % and give ~2.9."""
    t = np.linspace(0.0, 100.0, 100_001)
    env = np.where(t <= 10, t, 10 * (t / 10) ** 3)
    assert abs(growth_exponent(t, env, 1.0, 100.0) - 2.0) < 0.05


def test_the_fit_window_is_closed_and_reads_nothing_outside_it():
    """The exponent over [t_lo, t_hi] reads exactly the samples with t_lo <= t <= t_hi, both ends
    included (the module's docstring): with env = 2 t^3 sampled at t = 0.5, 1, ..., 200 and the
    window [1, 100] (both sample times), the slope is 3; whatever lies before t_lo or after t_hi
    (here +inf, an error that diverged there) changes nothing, and +inf at either end sample is a
    divergence in the window."""
    t = np.concatenate([[0.0, 0.5], np.geomspace(1.0, 100.0, 41), [150.0, 200.0]])
    env = 2.0 * t**3
    lo, hi = 1.0, 100.0
    assert abs(growth_exponent(t, env, lo, hi) - 3.0) < 1e-12
    outside = env.copy()
    outside[(t > 0) & (t < lo)] = math.inf
    outside[t > hi] = math.inf
    assert abs(growth_exponent(t, outside, lo, hi) - 3.0) < 1e-12
    for end in (lo, hi):
        at_end = np.where(t == end, math.inf, env)
        assert growth_fit(t, at_end, lo, hi) == (math.inf, ""), end
