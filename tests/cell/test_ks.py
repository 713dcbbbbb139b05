"""K-S regularization as a problem transform, [B] (5.4)."""
from __future__ import annotations

import numpy as np
import pytest
from gnibench.problems import kepler_ks
from gnibench.suite.cell.solve import solve
from gnibench.suite.metrics.global_error import global_errors
from gnibench.suite.metrics.invariants import invariant_errors
from gnibench.suite.foundation.errors import UserError


def test_forward_back_maps_round_trip():
    """(q, p) -> (u, v) -> (q, p) to round-off on both branches, with the bilinear relation."""
    rng = np.random.default_rng(1)
    for _ in range(200):
        q, p = rng.normal(size=3), rng.normal(size=3)
        u, v = kepler_ks.forward(q, p)
        assert abs(u[3] * v[0] - u[2] * v[1] + u[1] * v[2] - u[0] * v[3]) <= 1e-15 * (1 + np.abs(v).max())
        _, y = kepler_ks.backward(np.array([[*u, *v, 0.0]]))
        scale = 1 + np.abs(np.r_[q, p]).max()
        assert np.abs(y[0] - np.r_[q, p]).max() <= 4e-15 * scale


def test_energy_formula_of_5_4():
    """H = (2 v0.v0 - mu)/(u0.u0) [B] (5.4) equals |p|^2/2 - mu/|q|."""
    q, p, mu = np.array([0.3, -0.2, 0.5]), np.array([0.1, 1.2, -0.4]), 2.0
    u, v = kepler_ks.forward(q, p)
    assert (2 * v @ v - mu) / (u @ u) == pytest.approx(0.5 * p @ p - mu / np.linalg.norm(q), rel=1e-14)


def test_ks_rk4_agrees_with_plain_rk4_on_a_mild_orbit():
    """K-S + rk4 in fictitious time and plain rk4 in t reach the same state at the same t."""
    ks = solve("kepler-3d:e=0.1,ks=true", "rk4:h=0.002", steps=3000, every=3000)
    t_final = float(ks.t[-1])
    plain = solve("kepler-3d:e=0.1", "rk4:h=0.0005", t_end=t_final, every=10**6)
    assert ks.status == plain.status == "ok"
    assert 5.5 < t_final < 6.5                           # Δs = 1 per revolution (a = 1, mu = 4 pi^2)
    assert np.abs(ks.y[-1] - plain.y[-1]).max() < 1e-8
    assert global_errors(ks)[-1] < 1e-8 and global_errors(plain)[-1] < 1e-8


def test_ks_keeps_the_eccentric_orbit_where_plain_rk4_fails():
    """[B] §5: on the e = 0.8 orbit K-S regularization gives a far smaller global error."""
    ks = solve("kepler-3d:ks=true", "rk4:h=0.001", steps=10000, every=10000)
    plain = solve("kepler-3d", "rk4:h=0.001", steps=10000, every=10000)
    assert global_errors(ks)[-1] < 1e-3 * global_errors(plain)[-1]


def test_ks_runs_under_symplectic_and_modified_methods():
    """The K-S system is separable in the partition ((v, t), u): Yoshida runs explicitly on it."""
    r = solve("kepler-3d:ks=true", "yoshida4:h=0.095", steps=20000, every=100)
    assert r.status == "ok"
    err_h = np.abs(invariant_errors(r)[:, 0])          # H: bounded, no secular growth
    half = len(err_h) // 2
    assert err_h[half:].max() < 1.5 * err_h[:half].max()
    r = solve("kepler-3d:ks=true", "rk4:h=0.01+observer:on=K", steps=500, every=500)
    assert r.status == "ok"


def test_a_time_grid_beyond_the_row_budget_is_refused_before_any_work(capsys):
    """A K-S cell's grid t = k dt_out in the original time plans t_end / dt_out rows: refused
    up front like any other problem's (before: 10^9 rows asked, 1 min 51 s and 3.9 GB, then
    ``max_rows``), in solve and in an experiment."""
    from gnibench.suite.cli.main import main
    from gnibench.suite.runs.experiment import parse_experiment

    code = main(["solve", "kepler-3d:ks=true", "rk4:h=0.01", "--t-end", "1", "--dt-out", "1e-9"])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and "needs 1e+09 output rows" in err
    text = ('name = "g"\ntitle = "t"\nreference = "r"\nt_end = 1\ndt_out = 1e-9\n[[cells]]\n'
            'problems = ["kepler-3d:ks=true"]\nmethods = ["rk4:h=0.01"]\n')
    with pytest.raises(UserError, match="needs 1e\\+09 output rows"):
        parse_experiment(text, "g.toml", "paper")
