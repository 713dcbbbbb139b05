"""heyoka references of geodesic-genus2: the sides of the octagon Omega as terminal events, the
identification (8.3)-(8.4) applied at each crossing (gnibench.methods.engines.heyoka._propagate_identified)."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from gnibench.problems.geodesic_genus2 import PROBLEM, SIDE_CENTRE, inside, post_step
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
