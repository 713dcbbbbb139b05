"""heyoka references of geodesic-genus2: the sides of the octagon Omega as terminal events, the
identification (8.3)-(8.4) applied at each crossing (gnibench.methods.engines.heyoka._propagate_identified)."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from gnibench.methods.engines.heyoka import heyoka_propagate
from gnibench.problems.geodesic_genus2 import PROBLEM, R0, SIDE_CENTRE, inside, post_step
from gnibench.suite.cell.reference import reference_solution
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import parse_problem
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError

T_END = 8.0          # 7 identifications for the default initial point; chaos (Anosov) makes the
                     # compiled-vs-reference difference grow about e^{1.4 t}: 1e-8 at t = 8


def _H(y):
    return (1 - y[:, 0]**2 - y[:, 1]**2)**2 * (y[:, 2]**2 + y[:, 3]**2) / 4


@pytest.fixture(scope="module")
def runs():
    res = solve("geodesic-genus2", "dop853:rtol=1e-12,atol=1e-12", t_end=T_END, every=1)
    ref = reference_solution(parse_problem("geodesic-genus2"), res.t, "heyoka")
    return res, ref


def test_boundary_maps_agree_with_post_step():
    """The sympy side maps (Problem.boundary) are post_step's maps, side by side."""
    from types import SimpleNamespace

    import sympy as sp

    S = SimpleNamespace(**{n: sp.Symbol(n) for n in PROBLEM.state})
    sides, maps = PROBLEM.boundary.sides(S), PROBLEM.boundary.maps(S)
    f = sp.lambdify([S.q1, S.q2, S.p1, S.p2], list(sides) + [c for m in maps for c in m])
    rho = math.sqrt(SIDE_CENTRE**2 - 1)                 # side k: circle of centre C e_k, radius rho
    rng = np.random.default_rng(3)
    for k in range(8):
        e = np.array([math.cos(k * math.pi / 4), math.sin(k * math.pi / 4)])
        phi = rng.uniform(-0.1, 0.1)
        u = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]]) @ e
        on = SIDE_CENTRE * e - rho * u                  # on side k (inside its segment)
        assert abs(f(*on, 0.0, 0.0)[k]) < 1e-14
        y = (*(SIDE_CENTRE * e - (rho - 1e-3) * u), *rng.normal(size=2))   # just beyond side k
        v = f(*y)
        assert int(np.argmin(v[:8])) == k and v[k] < 0
        assert np.allclose(v[8 + 4 * k: 12 + 4 * k], post_step(y, ()), rtol=1e-13, atol=1e-14)
        assert inside(*v[8 + 4 * k: 10 + 4 * k])


def test_heyoka_reference_identifies_and_keeps_H(runs):
    _res, ref = runs
    assert ref.info["identifications"] >= 5                      # 7 with the defaults
    y = ref.y
    assert np.abs(_H(y) / _H(y[:1]) - 1).max() <= 1e-12
    assert all(inside(q1, q2) for q1, q2 in y[:, :2])


def test_heyoka_reference_agrees_with_dop853(runs):
    """At the sample times both states are mapped into Omega; the difference is dop853's error
    (rtol = 1e-12) grown by the Anosov flow: measured 1.4e-8 at t = 8, 3e-10 up to t = 6."""
    res, ref = runs
    assert res.status == "ok"
    d = np.abs(res.y - ref.y).max(axis=1)
    assert d.max() < 5e-8
    assert d[res.t <= 6.0].max() < 2e-9
    jumps = int(np.sum(np.hypot(*np.diff(res.y[:, :2], axis=0).T) > 0.3))
    assert jumps == ref.info["identifications"]                   # the same sides crossed


def test_long_double_reference_is_closer():
    """The maps and the events run in the working precision: long double vs double differ by the
    double reference's own error."""
    pb = parse_problem("geodesic-genus2")
    t = np.linspace(0.0, T_END, 17)
    d = reference_solution(pb, t, "heyoka").y
    ld = reference_solution(pb, t, "heyoka", precision="long double")
    assert ld.info["identifications"] >= 5
    assert np.abs(d - ld.y).max() < 1e-9
    assert np.abs(_H(ld.y) / _H(ld.y[:1]) - 1).max() <= 1e-15


def test_no_boundary_is_refused():
    from gnibench.methods.engines.heyoka import check_heyoka

    with pytest.raises(UserError, match="boundary"):
        check_heyoka(dataclasses.replace(PROBLEM, boundary=None))
    check_heyoka(PROBLEM)


def test_cli_geodesic_reference_heyoka(capsys):
    code = main(["solve", "geodesic-genus2", "rk4:h=0.01", "--t-end", "5", "--reference", "heyoka"])
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = out.strip().splitlines()
    row = dict(zip(lines[0].split(","), map(float, lines[-1].split(","))))
    assert row["t"] == 5.0 and 0.0 < row["global_error"] < 1e-6          # global error of rk4
    assert row["reference_error"] < row["global_error"]         # the reference measures rk4


def _radial_geodesic(t, k: int, H0: float) -> np.ndarray:
    """The exact geodesic from q = 0 along e_k = (cos k pi/4, sin k pi/4), mapped into Omega.

    On the diameter q = r e_k, p = pi e_k, [B] (8.2) gives r' = (1 - r^2)^2 pi / 2 with
    pi = 2 sqrt(H0) / (1 - r^2), so r = tanh u, u = sqrt(H0) t, and pi = 2 sqrt(H0) cosh^2 u.
    The diameter meets side k at its midpoint r_m = C - rho = (1 - R0)/(1 + R0) ([B] §8.1),
    u_m = artanh r_m = ln(1/R0)/2; the pairing (8.3) of side k, tanh u -> tanh(u + artanh(b/a))
    on the diameter, shifts u by artanh(b/a) = ln R0 = -2 u_m and keeps the direction (8.4): the
    orbit re-enters at the midpoint of the opposite side. So u(t) = sqrt(H0) t folded into
    [-u_m, u_m) with period 2 u_m."""
    u_m = math.log(1 / R0) / 2
    u = (math.sqrt(H0) * np.asarray(t) + u_m) % (2 * u_m) - u_m
    e = np.array([math.cos(k * math.pi / 4), math.sin(k * math.pi / 4)])
    r, size = np.tanh(u), 2 * math.sqrt(H0) * np.cosh(u)**2
    return np.column_stack([r[:, None] * e, size[:, None] * e])


@pytest.mark.parametrize("k", range(8))
def test_heyoka_identifies_each_side_by_its_own_pairing(k):
    """heyoka's engine (not a cached reference) along the diameter through side k: two crossings,
    at t = u_m / sqrt(H0) and three times that, each sent by side k's pairing to the opposite
    side; the samples are the exact mapped geodesic (:func:`_radial_geodesic`)."""
    H0 = 0.5
    pb = parse_problem(f"geodesic-genus2:H0={H0},angle={k * math.pi / 4!r},q10=0,q20=0")
    t_cross = math.log(1 / R0) / 2 / math.sqrt(H0)
    t = np.linspace(0.0, 4 * t_cross, 39)                  # no sample at a crossing
    run = heyoka_propagate(pb, t)
    assert run.status == "ok" and run.info["identifications"] == 2
    np.testing.assert_allclose(run.y, _radial_geodesic(t, k, H0), rtol=0, atol=1e-12)


@pytest.mark.parametrize("precision", ["double", "long double"])
def test_heyoka_provenance_names_its_identifications_and_their_precision(precision):
    """The engine's provenance counts the identifications and names the precision the maps ran in
    (the working precision) for a problem with a boundary; a problem without one (kepler-2d) has
    neither entry."""
    t = np.linspace(0.0, 4.0, 9)
    info = heyoka_propagate(parse_problem("geodesic-genus2"), t, precision).info
    assert info["identification_precision"] == info["precision"] == precision
    assert info["identifications"] == 3            # the default point crosses 3 sides by t = 4
    plain = heyoka_propagate(parse_problem("kepler-2d"), t, precision).info
    assert plain["precision"] == precision
    assert "identifications" not in plain and "identification_precision" not in plain
