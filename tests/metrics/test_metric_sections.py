"""Section statistics ([B] §6.2 Fig 18, §7 Figs 26-30) on crossings known in closed form.

Explicit Euler on the harmonic oscillator q' = p, p' = -q maps (q, p) to (q + h p, p - h q): a
turn by α = atan(h) (the direction of the flow) and a stretch by √(1 + h^2). From (q, p) = (0, 1),
at angle θ_n = n α from the p-axis, the numerical orbit crosses {q = 0, p > 0} in the step after
n_k = ceil(2πk/α) - 1 (θ_n < 2πk <= θ_n+1). Hénon's trick locates the crossing on the exact flow
through y_n, a rotation, so the k-th section point is p_k = |y_n_k| = (1 + h^2)^(n_k/2) exactly
(the section test problem is the harmonic oscillator with a temporary section, as in
tests/cell/test_sections.py).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.metrics.compute import apply, parse_metrics

OSC_ID = "harmonic-oscillator-stats-test"
P = f"{OSC_ID}:q0=0,p0=1"
H, K = 0.01, 20


@pytest.fixture
def osc(monkeypatch):
    from support import section_oscillator   # here: a subprocess imports this module too

    return section_oscillator(monkeypatch, OSC_ID)


def closed_form_points(h: float, k: int) -> np.ndarray:
    alpha = math.atan(h)
    n = np.array([math.ceil(2 * math.pi * j / alpha) - 1 for j in range(1, k + 1)])
    return (1 + h * h) ** (n / 2)


@pytest.fixture
def crossings(osc):
    traj = solve(P, f"euler:h={H}", t_end=K * 2 * math.pi + 1, section=K)
    assert len(traj.t) == K
    return traj


def test_known_crossing_points(crossings):
    p = crossings.y[:, crossings.state_names.index("p")]
    assert np.allclose(p, closed_form_points(H, K), rtol=1e-12, atol=0)


def test_fraction_within_a_radius_of_a_point(crossings):
    p = closed_form_points(H, K)
    radius = float((p[4] + p[5]) / 2 - 1)           # between the 5th and the 6th point
    for spec in (f"section_stats:point=1,radius={radius!r}",
                 f"section_stats:space=state,point=0/1,radius={radius!r}"):
        out, skipped = apply(crossings, parse_metrics([spec]))
        assert not skipped
        s = out.scalars
        assert (s["section_points"], s["section_points_within"]) == (K, 5)
        assert s["section_fraction_within"] == 5 / K
        assert np.allclose(out.columns["section_distance"], p - 1, rtol=1e-12, atol=1e-13)
    # default: within 1e-3 of the origin (the equilibrium): none, every point has p >= 1
    out, _ = apply(crossings, parse_metrics("section_stats"))
    assert out.scalars["section_points_within"] == 0
    assert np.allclose(out.columns["section_distance"], p, rtol=1e-12)
    assert not any(k.startswith("section_points_chart") for k in out.scalars)


def test_bad_point_and_trajectories_without_a_section(crossings):
    _, skipped = apply(crossings, parse_metrics(["section_stats:point=1/2"]))
    assert "point has 2 coordinates; the section space has 1" in next(iter(skipped.values()))
    traj = solve("harmonic-oscillator", "euler:h=0.1", steps=10)
    _, skipped = apply(traj, parse_metrics("section_stats"))
    assert "not section crossings" in skipped["section_stats"]


def test_points_per_chart_of_so4():
    """so(4)'s charts Γ1..Γ8 ([B] §7.1): one count per chart, zeros included, summing to all."""
    traj = solve("euler-so4", "rk4:h=0.01", t_end=200.0, section=100)
    out, _ = apply(traj, parse_metrics("section_stats"))
    s = out.scalars
    counts = [s[f"section_points_chart{k}"] for k in range(1, 9)]
    assert counts == [int(np.sum(traj.chart == k)) for k in range(1, 9)]
    assert sum(counts) == s["section_points"] == len(traj.t) == 100
    assert "section_points_chart9" not in s
