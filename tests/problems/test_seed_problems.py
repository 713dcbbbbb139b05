"""The seed problems of [B] §4-§8 and [HLW] I.2.4, I.3: catalog values, conservation, exact solutions.

Each problem is compiled once (its rk4 cell); the reference trajectories use scipy's DOP853 with
rtol = atol = 1e-13 on the compiled base field.
"""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from gnibench.methods.assembly import assemble
from gnibench.problems.codegen import problem_meta
from gnibench.suite.cell import spec
from gnibench.suite.cell.solve import solve
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.global_error import global_errors
from gnibench.suite.metrics.invariants import invariant_errors
from scipy.integrate import solve_ivp

NEW = ("kepler-radial", "kepler-3d", "outer-solar-system", "henon-heiles", "gavrilov-shilnikov",
       "gavrilov-shilnikov-modified", "euler-so4", "geodesic-genus2")
# reference time span: a few periods / one excursion; OSS in days (Jupiter's period is ~4333 days)
SPAN = {"kepler-radial": 20.0, "kepler-3d": 3.0, "outer-solar-system": 5000.0, "henon-heiles": 100.0,
        "gavrilov-shilnikov": 10.0, "gavrilov-shilnikov-modified": 40.0, "euler-so4": 50.0,
        "geodesic-genus2": 4.0}


@functools.cache
def compiled(problem_text: str):
    """(bound problem, compiled module, par array, integral names) of a problem spec."""
    problem = spec.parse_problem(problem_text)
    mod = assemble(problem, spec.parse_method("rk4", problem))
    meta = problem_meta(problem.record)
    par = np.array(problem.record.par(problem.values), dtype=np.float64)
    return problem, mod, par, tuple(meta["integrals"])


def integrals(mod, names, y, par) -> np.ndarray:
    return np.array([getattr(mod, f"integral_{k}")(tuple(y), par) for k in range(len(names))])


@functools.cache
def reference(problem_text: str, t_end: float, n: int = 53):
    """DOP853 (rtol = atol = 1e-13) on the compiled base field: (t, Y). n = 53 samples: their spacing
    is not commensurate with the rotation period 2 pi/omega = 1 of G-S (at multiples of a quarter
    period both terms of K vanish on the loop)."""
    problem, mod, par, _ = compiled(problem_text)
    y0 = np.array(problem.record.y0(problem.values))
    t = np.linspace(0.0, t_end, n)
    sol = solve_ivp(lambda _, y: np.array(mod.base_f(tuple(y), par)), (0.0, t_end), y0,
                    method="DOP853", rtol=1e-13, atol=1e-13, t_eval=t)
    assert sol.success, sol.message
    return t, sol.y.T


def scale(mod, k, Y, par) -> float:
    """Size of integral k: |I_k(Y[0])|, or, when that is (nearly) zero, the size of its terms along
    the states Y, max sum_i |y_i dI_k/dy_i| (e.g. G-S: H = K = 0 on the homoclinic loop). The sum is
    invariant under rescaling single variables (the OSS mixes q ~ 30 AU with p ~ 1e-6)."""
    Y = np.atleast_2d(Y)
    value = abs(getattr(mod, f"integral_{k}")(tuple(Y[0]), par))
    size = max(np.abs(np.array(getattr(mod, f"grad_{k}")(tuple(y), par)) * y).sum() for y in Y)
    return value if value > 1e-6 * size else size


# ---------------------------------------------------------------------------------------------
# catalog values of the initial points


def test_kepler_radial_initial():
    problem, mod, par, names = compiled("kepler-radial")
    y0 = problem.record.y0(problem.values)
    assert y0 == pytest.approx(((1 - math.sqrt(0.2)) / 0.8, 0.0), abs=1e-15)
    assert integrals(mod, names, y0, par)[0] == pytest.approx(-0.4, abs=1e-15)


def test_kepler_3d_elements_and_period():
    from gnibench.problems.kepler3d_exact import elements_from_state

    problem, _mod, _par, _ = compiled("kepler-3d")
    y0 = np.array(problem.record.y0(problem.values))
    el = elements_from_state(y0[:3], y0[3:], 4 * math.pi**2)
    want = {"a": 1.0, "e": 0.8, "i": math.pi / 4, "Omega": math.pi / 2, "omega": math.pi / 2, "M": 0.0}
    for key, value in want.items():
        assert el[key] == pytest.approx(value, abs=1e-13), key
    # period 1 ([B] §5.2): the exact solution returns to the start
    ex = problem.record.exact(np.array([0.0, 0.5, 1.0, 2.0]), tuple(y0), problem.values)
    size = np.abs(y0).max()
    assert np.abs(ex[2] - y0).max() < 1e-12 * size and np.abs(ex[3] - y0).max() < 1e-12 * size
    # the pericenter: r = a (1 - e), along the Laplace vector
    assert np.linalg.norm(y0[:3]) == pytest.approx(0.2, rel=1e-14)


def test_kepler_3d_elements_roundtrip():
    from gnibench.problems.kepler3d_exact import elements_from_state, state_from_elements

    rng = np.random.default_rng(1)
    for _ in range(20):
        a, e, i = rng.uniform(0.5, 3), rng.uniform(0.01, 0.95), rng.uniform(0.05, 3.0)
        Om, om, M = rng.uniform(0, 2 * math.pi, 3)
        q, p = state_from_elements(a, e, i, Om, om, M, mu=2.5)
        el = elements_from_state(q, p, mu=2.5)
        got = np.array([el[k] for k in ("a", "e", "i", "Omega", "omega", "M")])
        diff = got - np.array([a, e, i, Om, om, M])
        diff[3:] = (diff[3:] + math.pi) % (2 * math.pi) - math.pi
        assert np.abs(diff).max() < 1e-11


def test_kepler_3d_identities_along_orbit():
    """c.e = 0 and 2 H c^2 = mu^2 (e^2 - 1) ([B] §5.1 prints the second without the factor 2)."""
    problem, mod, par, names = compiled("kepler-3d")
    y0 = problem.record.y0(problem.values)
    mu = problem.values["mu"]
    Y = problem.record.exact(np.linspace(0, 1, 17), y0, problem.values)
    for y in Y:
        v = dict(zip(names, integrals(mod, names, y, par)))
        c = np.array([v["c1"], v["c2"], v["c3"]])
        e = np.array([v["e1"], v["e2"], v["e3"]])
        assert abs(c @ e) < 1e-13 * np.linalg.norm(c)
        assert v["c_sq"] == pytest.approx(c @ c, rel=1e-14)
        assert 2 * v["H"] * v["c_sq"] == pytest.approx(mu * mu * (e @ e - 1), rel=1e-12)
        assert np.linalg.norm(e) == pytest.approx(0.8, rel=1e-12)
        assert v["H"] == pytest.approx(-mu / 2, rel=1e-13)                 # a = 1


def test_outer_solar_system_initial():
    from gnibench.problems import outer_solar_system as oss

    problem, mod, par, names = compiled("outer-solar-system")
    y0 = np.array(problem.record.y0(problem.values))
    p, q = y0[:18].reshape(6, 3), y0[18:].reshape(6, 3)
    assert np.all(p[0] == 0) and np.all(q[0] == 0)                       # the sun at rest at 0
    assert q[1] == pytest.approx([-3.5023653, -3.8169847, -1.5507963])    # Jupiter, Table 2.2
    assert p[5] == pytest.approx(np.array([0.00276725, -0.00170702, -0.00136504]) / 1.3e8)
    assert np.allclose(p, np.array(oss.MASSES)[:, None] * np.array(oss.VELOCITIES), rtol=1e-15)
    assert problem.values["G"] == 2.95912208286e-4 and problem.values["m0"] == 1.00000597682
    v = dict(zip(names, integrals(mod, names, y0, par)))
    assert v["Px"] == pytest.approx(p[:, 0].sum(), rel=1e-14)
    assert v["H"] < 0


def test_henon_heiles_initial():
    problem, mod, par, _ = compiled("henon-heiles")
    p1, p2, q1, q2 = problem.record.y0(problem.values)
    assert (q1, q2, p2) == (0.0, -0.2, 0.0) and p1 > 0
    assert mod.integral_0((p1, p2, q1, q2), par) == pytest.approx(1 / 8, abs=1e-16)
    other = spec.parse_problem("henon-heiles:H0=0.08333333333333333,sec_q2=0.1,sec_p2=0.2")
    y = other.record.y0(other.values)
    assert mod.integral_0(y, par) == pytest.approx(1 / 12, abs=1e-16) and y[0] > 0 and y[2] == 0


def test_gavrilov_shilnikov_initial():
    problem, mod, par, _ = compiled("gavrilov-shilnikov")
    y0 = problem.record.y0(problem.values)
    assert y0 == (0.0, 0.0, 0.0, math.sqrt(2.0))
    assert abs(mod.integral_0(y0, par)) < 1e-15 and mod.integral_1(y0, par) == 0.0   # H = K = 0


def test_gavrilov_shilnikov_modified_initial():
    problem, mod, par, _ = compiled("gavrilov-shilnikov-modified")
    r, B = 1e-10, -0.2
    P = r * math.sqrt((2 - r * r) / (2 * (1 + B * r * r)))
    y0 = problem.record.y0(problem.values)
    assert y0 == (0.0, -P, 0.0, r)
    # H is a sum of terms of size r^2 = 1e-20: zero up to their round-off
    assert abs(mod.integral_0(y0, par)) < 1e-15 * r * r and mod.integral_1(y0, par) == 0.0
    far = spec.parse_problem("gavrilov-shilnikov-modified:r0=0.7")
    assert abs(mod.integral_0(far.record.y0(far.values), par)) < 1e-15


def test_euler_so4_initial():
    from gnibench.problems.euler_so4 import chart

    problem, mod, par, names = compiled("euler-so4")
    y0 = np.array(problem.record.y0(problem.values))
    assert y0[1] == 0.0 and chart(y0) == 1
    assert integrals(mod, names, y0, par) == pytest.approx([1.0, 15.0, 25.0], abs=1e-13)
    for k in range(1, 9):                                  # every chart: on the level, right signs
        other = spec.parse_problem(f"euler-so4:chart={k},sec_x5=0.3,sec_x6=-0.2")
        y = np.array(other.record.y0(other.values))
        assert chart(y) == k
        assert integrals(mod, names, y, par) == pytest.approx([1.0, 15.0, 25.0], abs=1e-13)


def test_geodesic_initial():
    from gnibench.problems.geodesic_genus2 import inside

    problem, mod, par, _ = compiled("geodesic-genus2")
    y0 = problem.record.y0(problem.values)
    assert y0[:2] == (0.2, 0.1) and inside(*y0[:2])
    assert mod.integral_0(y0, par) == pytest.approx(0.5, rel=1e-15)


@pytest.mark.parametrize("text, fragment", [
    ("euler-so4:sec_x5=0,sec_x6=1", "S - 2|P|"),
    ("euler-so4:sec_x5=3", "x3^2"),
    ("euler-so4:lam4=2", "lam1 = lam4"),
    ("henon-heiles:sec_q2=0.6,sec_p2=0.3", "p1^2"),
    ("geodesic-genus2:q10=0.7", "octagon"),
    ("kepler-radial:H0=-0.6", "circular"),
    ("kepler-3d:e=1", "allowed"),
    ("kepler-3d:q10=0,q20=0,q30=0", "q = 0"),
    ("gavrilov-shilnikov-modified:B=-1", "allowed"),
])
def test_bad_initial_points_are_user_errors(text, fragment):
    with pytest.raises(UserError, match=fragment.replace("|", r"\|").replace("^", r"\^")):
        spec.parse_problem(text)


def test_sections_contain_the_initial_points():
    """Where a problem's default start lies on its section, g(y0) = 0 and the direction holds."""
    import sympy as sp
    from gnibench.problems.codegen import symbolic

    for pid in ("henon-heiles", "gavrilov-shilnikov", "gavrilov-shilnikov-modified", "euler-so4"):
        problem, _, par, _ = compiled(pid)
        rec = problem.record
        ys, ps, _, _ = symbolic(rec)
        ns = type("S", (), dict(zip(rec.state, ys), **dict(zip(rec.model_params, ps))))
        (section,) = rec.sections
        args = ys + ps
        values = list(rec.y0(problem.values)) + list(par)
        g = sp.lambdify(args, section.g(ns))(*values)
        cond = sp.lambdify(args, section.condition(ns))(*values)
        assert abs(g) < 1e-15 and cond > 0, pid
        assert set(section.coords) <= set(rec.state)


# ---------------------------------------------------------------------------------------------
# conservation, exact solutions, D_H F = 0


@pytest.mark.parametrize("pid", NEW)
def test_integrals_constant_along_reference(pid):
    _problem, mod, par, names = compiled(pid)
    _t, Y = reference(pid, SPAN[pid])
    I0 = integrals(mod, names, Y[0], par)
    for k, name in enumerate(names):
        s = scale(mod, k, Y, par)
        drift = max(abs(integrals(mod, names, y, par)[k] - I0[k]) for y in Y)
        assert drift <= 1e-10 * s, f"{pid}: {name} drifts by {drift:.3g} (scale {s:.3g})"


@pytest.mark.parametrize("pid", ["kepler-radial", "kepler-3d"])
def test_exact_solution_matches_reference(pid):
    problem, _, _, _ = compiled(pid)
    t, Y = reference(pid, SPAN[pid])
    ex = problem.record.exact(t, tuple(Y[0]), problem.values)
    err = np.abs(ex - Y).max() / np.abs(Y).max()
    assert err < 1e-9, f"{pid}: exact vs DOP853 differ by {err:.3g}"


def _random_points(pid, rng, n=20):
    """Random states in each problem's domain: near y0 (relative perturbations keep the OSS bodies
    apart and Kepler radii positive), inside the disc for the geodesic flow."""
    problem, _, _, _ = compiled(pid)
    y0 = np.array(problem.record.y0(problem.values))
    if pid == "geodesic-genus2":
        return np.column_stack([rng.uniform(-0.6, 0.6, (n, 2)), rng.normal(size=(n, 2))])
    if pid == "kepler-radial":
        return np.column_stack([rng.uniform(0.2, 3, n), rng.normal(size=n)])
    noise = y0 * 0.3 * rng.normal(size=(n, y0.size))
    if pid != "outer-solar-system":                     # also move the components that are 0
        noise += 0.1 * np.abs(y0).max() * rng.normal(size=(n, y0.size))
    return y0 + noise


@pytest.mark.parametrize("pid", NEW)
def test_integrals_are_first_integrals(pid):
    """D_H F = 0 at random points ([B] §2): every integral's gradient is orthogonal to F.

    Scale: sum_i |dI/dy_i F_i|, the size of the terms that cancel (|grad I| |F| would mix the OSS's
    q ~ 30 and p ~ 1e-6 scales); measured ratios <= 2.7e-16.
    """
    _problem, mod, par, names = compiled(pid)
    rng = np.random.default_rng(7)
    for y in _random_points(pid, rng):
        F = np.array(mod.base_f(tuple(y), par))
        for k, name in enumerate(names):
            g = np.array(getattr(mod, f"grad_{k}")(tuple(y), par))
            assert abs(g @ F) <= 1e-14 * np.abs(g * F).sum(), (pid, name)


def test_euler_so4_field_is_even():
    """(7.1) is quadratic, F(-x) = F(x): x -> -x reverses time (used for the section's symmetry)."""
    _problem, mod, par, _ = compiled("euler-so4")
    y = np.random.default_rng(3).normal(size=6)
    assert np.allclose(mod.base_f(tuple(y), par), mod.base_f(tuple(-y), par), rtol=0, atol=0)


# ---------------------------------------------------------------------------------------------
# the geodesic flow's identification map [B] (8.3)-(8.4)


def test_geodesic_constants():
    from gnibench.problems import geodesic_genus2 as g

    assert g.R0 == pytest.approx(0.21684534, abs=5e-9)
    # the side arc crosses the axis at the octagon's inradius: cosh d = cot(pi/8) (angles pi/4)
    x = g.SIDE_CENTRE - math.sqrt(g.SIDE_CENTRE**2 - 1)
    assert math.cosh(2 * math.atanh(x)) == pytest.approx(1 / math.tan(math.pi / 8), rel=1e-14)
    # ... and its vertices lie at the circumradius: cosh R = cot^2(pi/8)
    c, s = math.cos(math.pi / 8), math.sin(math.pi / 8)
    lo, hi = 0.0, 0.99
    for _ in range(60):
        m = 0.5 * (lo + hi)
        lo, hi = (m, hi) if g.inside(m * c, m * s * (1 - 1e-9)) else (lo, m)
    assert math.cosh(2 * math.atanh(hi)) == pytest.approx(1 / math.tan(math.pi / 8) ** 2, rel=1e-8)


def _hamiltonian(y):
    q1, q2, p1, p2 = y
    return (1 - q1 * q1 - q2 * q2) ** 2 * (p1 * p1 + p2 * p2) / 4


def test_post_step_maps_each_side_inside_and_keeps_H():
    from gnibench.problems.geodesic_genus2 import SIDE_CENTRE, inside, post_step

    mid = SIDE_CENTRE - math.sqrt(SIDE_CENTRE**2 - 1)              # side midpoint on the axis
    rng = np.random.default_rng(5)
    par = np.zeros(0)
    for k in range(8):
        for offset in np.linspace(-0.999, 0.999, 21):             # along the side, up to the vertices
            ang = k * math.pi / 4 + offset * math.pi / 8
            # a point just beyond the side in direction ang: bisect for the boundary, step out
            lo, hi = 0.0, 0.99
            for _ in range(60):
                m = 0.5 * (lo + hi)
                lo, hi = (m, hi) if inside(m * math.cos(ang), m * math.sin(ang)) else (lo, m)
            for eps in (1e-12, 1e-3, 5e-2):
                r = hi + eps
                y = (r * math.cos(ang), r * math.sin(ang), *rng.normal(size=2))
                assert not inside(y[0], y[1])
                z = post_step(y, par)
                assert inside(z[0], z[1]), (k, offset, eps)
                assert _hamiltonian(z) == pytest.approx(_hamiltonian(y), rel=1e-13)
    assert 0.6 < mid < 0.7


def test_post_step_is_identity_inside():
    from gnibench.problems.geodesic_genus2 import inside, post_step

    rng = np.random.default_rng(6)
    for q in rng.uniform(-0.7, 0.7, (200, 2)):
        if inside(*q):
            y = (q[0], q[1], 0.3, -1.2)
            assert post_step(y, np.zeros(0)) is y


def test_post_step_opposite_sides_and_numba():
    """gamma maps the side at angle 0 onto the opposite side; the template compiles with numba."""
    import numba
    from gnibench.problems.geodesic_genus2 import SIDE_CENTRE, post_step

    mid = SIDE_CENTRE - math.sqrt(SIDE_CENTRE**2 - 1)
    z = post_step((mid + 1e-12, 0.0, 1.0, 0.0), np.zeros(0))
    assert z[0] == pytest.approx(-mid, abs=1e-10) and abs(z[1]) < 1e-12
    jit = numba.njit(post_step)
    rng = np.random.default_rng(8)
    for _ in range(50):
        y = (*rng.uniform(-0.8, 0.8, 2), *rng.normal(size=2))
        if y[0] ** 2 + y[1] ** 2 < 0.95:
            assert np.allclose(jit(y, np.zeros(0)), post_step(y, np.zeros(0)), rtol=1e-14, atol=1e-15)


def test_geodesic_solve_stays_in_the_octagon():
    """Through the solver, post_step keeps q in Omega; H is kept across the identifications."""
    from gnibench.problems.geodesic_genus2 import inside

    res = solve("geodesic-genus2", "rk4:h=0.01", steps=3000, every=1)
    assert res.status == "ok"
    assert all(inside(q1, q2) for q1, q2 in res.y[:, :2])
    jumps = np.sum(np.hypot(*np.diff(res.y[:, :2], axis=0).T) > 0.3)
    assert jumps >= 5                                  # the geodesic crossed sides of Omega
    assert np.abs(invariant_errors(res)).max() < 1e-8 * 0.5


# ---------------------------------------------------------------------------------------------
# the problems run through the solver


RUNS = [
    ("kepler-radial", "rk4:h=0.01", 500), ("kepler-radial", "stormer-verlet:h=0.01", 500),
    ("kepler-3d", "rk4:h=0.001", 1000), ("kepler-3d", "stormer-verlet:h=0.001", 1000),
    ("outer-solar-system", "rk4:h=10", 300), ("outer-solar-system", "stormer-verlet:h=10", 300),
    ("henon-heiles", "rk4:h=0.05", 400), ("henon-heiles", "stormer-verlet:h=0.05", 400),
    ("gavrilov-shilnikov", "rk4:h=0.01", 300), ("gavrilov-shilnikov", "stormer-verlet:h=0.01", 300),
    ("gavrilov-shilnikov-modified", "rk4:h=0.01", 300),
    ("gavrilov-shilnikov-modified", "stormer-verlet:h=0.01", 300),
    ("euler-so4", "rk4:h=0.01", 500),
    ("geodesic-genus2", "rk4:h=0.01", 200), ("geodesic-genus2", "stormer-verlet:h=0.01", 200),
]


@pytest.mark.parametrize("pid, method, steps", RUNS)
def test_problem_runs_through_solve(pid, method, steps):
    res = solve(pid, method, steps=steps, every=37)   # not commensurate with G-S period 1
    assert res.status == "ok", res.reason
    assert res.y.shape[1] == len(res.state_names)
    _problem, mod, par, _ = compiled(pid)
    scales = np.array([scale(mod, k, res.y, par) for k in range(len(res.integral_names))])
    # a sanity bound only (h is moderate): every integral stays within 5e-2 of its size
    errors = np.abs(invariant_errors(res)).max(axis=0)
    assert np.all(errors <= 5e-2 * scales), (method, errors / scales)
    if res.reference is not None and method.startswith("rk4"):
        assert global_errors(res).max() < 1e-3 * np.abs(res.y).max()


def test_euler_so4_refuses_partitioned_methods():
    with pytest.raises(UserError, match="partition"):
        solve("euler-so4", "stormer-verlet:h=0.01", steps=10)
