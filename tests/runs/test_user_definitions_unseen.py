"""Held-out user definitions (issue 16, "How it will be checked"): a problem from outside the
seeds with its integrals (the periodic Toda lattice, Toda (1967), Hénon (1974) for the cubic
integral; the Lagrange top as a right-hand side with four integrals), tableaus from the literature
(Kutta's 3/8 rule, Radau IIA with 3 stages, Lobatto IIIA-IIIB with 2 stages, [HLW] II.2.2),
compositions (Yoshida (1990) order 6 from its printed decimals; the triple jump of the triple
jump, [HLW] II.4 (4.4)-(4.5), nested) and a Python step, loaded through the API, run by solve and
run, and compared with independent numpy implementations of the same methods, with closed forms
and with solve_ivp called directly."""
from __future__ import annotations

import math
from pathlib import Path

import gnibench
import numpy as np
import pytest
from gnibench.suite.cell.user import loader
from scipy.integrate import solve_ivp

S3, S6 = math.sqrt(3), math.sqrt(6)
DEFS = r'''
[[problem]]
id = "toda3"
states = ["q1", "q2", "q3", "p1", "p2", "p3"]
hamiltonian = "(p1^2 + p2^2 + p3^2)/2 + exp(q1 - q2) + exp(q2 - q3) + exp(q3 - q1)"
integrals = {P = "p1 + p2 + p3", I3 = "p1*p2*p3 - p1*exp(q2 - q3) - p2*exp(q3 - q1) - p3*exp(q1 - q2)"}
initial = {q1 = 1, q2 = 0, q3 = -0.5, p1 = -1.5, p2 = 1, p3 = 0.5}

[[problem]]
id = "lagrange-top"
states = ["M1", "M2", "M3", "g1", "g2", "g3"]
rhs = {M1 = "mu*g2 + M2*M3/C - M2*M3/A", M2 = "-mu*g1 - M1*M3/C + M1*M3/A", M3 = "0", g1 = "M3*g2/C - M2*g3/A", g2 = "-M3*g1/C + M1*g3/A", g3 = "-M1*g2/A + M2*g1/A"}
integrals = {H = "(M1^2/A + M2^2/A + M3^2/C)/2 + mu*g3", Mg = "M1*g1 + M2*g2 + M3*g3", gg = "g1^2 + g2^2 + g3^2"}
parameters = {A = 2.0, C = 1.0, mu = 1.0}
initial = {M1 = 0.3, M2 = -0.2, M3 = 1.5, g1 = 0.6, g2 = 0, g3 = 0.8}

[[problem]]
id = "spiral"
states = ["x", "y"]
rhs = {x = "a*x - w*y", y = "w*x + a*y"}
parameters = {a = -0.2, w = 3.0}
initial = {x = 1, y = 0.5}
partition = [["x"], ["y"]]
exact = {x = "exp(a*t)*(x0*cos(w*t) - y0*sin(w*t))", y = "exp(a*t)*(x0*sin(w*t) + y0*cos(w*t))"}

[[method]]
id = "kutta38"
kind = "explicit-rk"
order = 4
c = [0, "1/3", "2/3", 1]
A = [[], ["1/3"], ["-1/3", 1], [1, -1, 1]]
b = ["1/8", "3/8", "3/8", "1/8"]

[[method]]
id = "radau3h"
kind = "implicit-rk"
order = 5
c = ["(4 - sqrt(6))/10", "(4 + sqrt(6))/10", 1]
A = [["(88 - 7*sqrt(6))/360", "(296 - 169*sqrt(6))/1800", "(-2 + 3*sqrt(6))/225"], ["(296 + 169*sqrt(6))/1800", "(88 + 7*sqrt(6))/360", "(-2 - 3*sqrt(6))/225"], ["(16 - sqrt(6))/36", "(16 + sqrt(6))/36", "1/9"]]
b = ["(16 - sqrt(6))/36", "(16 + sqrt(6))/36", "1/9"]

[[method]]
id = "lobatto2ab"
kind = "partitioned-rk"
order = 2
u = {c = [0, 1], A = [[0, 0], ["1/2", "1/2"]], b = ["1/2", "1/2"]}
v = {c = ["1/2", "1/2"], A = [["1/2", 0], ["1/2", 0]], b = ["1/2", "1/2"]}

[[method]]
id = "yoshida6a"
kind = "composition"
order = 6
basis = "stormer-verlet"
gamma = ["0.784513610477560", "0.235573213359357", "-1.17767998417887", "1 - 2*(0.784513610477560 + 0.235573213359357 - 1.17767998417887)", "-1.17767998417887", "0.235573213359357", "0.784513610477560"]

[[method]]
id = "tj4"
kind = "composition"
order = 4
basis = "stormer-verlet"
gamma = ["1/(2-2^(1/3))", "-2^(1/3)/(2-2^(1/3))", "1/(2-2^(1/3))"]

[[method]]
id = "tj6"
kind = "composition"
order = 6
basis = "tj4"
gamma = ["1/(2-2^(1/5))", "-2^(1/5)/(2-2^(1/5))", "1/(2-2^(1/5))"]

[[method]]
id = "py-kutta38"
kind = "python"
entry = "heldout_step:kutta38"
'''
STEP = '''
def kutta38(f, t, y, h):
    k1 = f(t, y)
    k2 = f(t + h/3, y + h*k1/3)
    k3 = f(t + 2*h/3, y + h*(-k1/3 + k2))
    k4 = f(t + h, y + h*(k1 - k2 + k3))
    return y + h*(k1 + 3*k2 + 3*k3 + k4)/8
'''
Y0 = np.array([1, 0, -0.5, -1.5, 1, 0.5], float)
KUTTA38 = ([[0, 0, 0, 0], [1 / 3, 0, 0, 0], [-1 / 3, 1, 0, 0], [1, -1, 1, 0]],
           [1 / 8, 3 / 8, 3 / 8, 1 / 8], [0, 1 / 3, 2 / 3, 1])
RADAU3 = ([[(88 - 7 * S6) / 360, (296 - 169 * S6) / 1800, (-2 + 3 * S6) / 225],
           [(296 + 169 * S6) / 1800, (88 + 7 * S6) / 360, (-2 - 3 * S6) / 225],
           [(16 - S6) / 36, (16 + S6) / 36, 1 / 9]],
          [(16 - S6) / 36, (16 + S6) / 36, 1 / 9], [(4 - S6) / 10, (4 + S6) / 10, 1])
W = (0.784513610477560, 0.235573213359357, -1.17767998417887)
X4, X6 = 1 / (2 - 2 ** (1 / 3)), 1 / (2 - 2 ** (1 / 5))
TJ4 = [X4, -2 ** (1 / 3) * X4, X4]
GAMMAS = {"yoshida6a": [*W, 1 - 2 * sum(W), *W[::-1]], "tj4": TJ4,
          "tj6": [g * x for x in (X6, -2 ** (1 / 5) * X6, X6) for g in TJ4]}


@pytest.fixture(scope="module")
def defs(tmp_path_factory):
    d = tmp_path_factory.mktemp("heldout")
    (d / "defs.toml").write_text(DEFS)
    (d / "heldout_step.py").write_text(STEP)
    yield d
    loader.unload()


@pytest.fixture(autouse=True)
def _loaded(defs):
    gnibench.load(defs / "defs.toml")           # a no-op after the first time
    yield
    for name in loader.loaded():                # a test's own files: ids free for the next
        if name != str((defs / "defs.toml").resolve()):
            loader.unload(name)


def toda_f(y):
    q, p = y[:3], y[3:]
    e12, e23, e31 = np.exp(q[0] - q[1]), np.exp(q[1] - q[2]), np.exp(q[2] - q[0])
    return np.concatenate([p, [e31 - e12, e12 - e23, e23 - e31]])


def toda_integrals(y):
    q, p = y[:3], y[3:]
    e12, e23, e31 = np.exp(q[0] - q[1]), np.exp(q[1] - q[2]), np.exp(q[2] - q[0])
    return {"H": p @ p / 2 + e12 + e23 + e31, "P": p.sum(),
            "I3": p[0] * p[1] * p[2] - p[0] * e23 - p[1] * e31 - p[2] * e12}


def rk(tableau, f, y, h, n):
    """Runge-Kutta steps (stages by fixed-point iteration to round-off when A is not strictly
    lower triangular)."""
    A, b, _ = (np.asarray(x, float) for x in tableau)
    for _ in range(n):
        K = np.array([f(y)] * len(b))
        for _ in range(1 if not np.triu(A).any() else 200):
            if not np.triu(A).any():
                for i in range(len(b)):
                    K[i] = f(y + h * (A[i, :i] @ K[:i]))
            else:
                new = np.array([f(y + h * (A[i] @ K)) for i in range(len(b))])
                done, K = np.max(abs(new - K)) < 1e-16, new
                if done:
                    break
        y = y + h * (b @ K)
    return y


def verlet(y, h):
    """Störmer-Verlet for q' = p, p' = F(q) ([HLW] (I.1.17)), the p half-step first."""
    q, p = y[:3], y[3:] + h / 2 * toda_f(y)[3:]
    q = q + h * p
    return np.concatenate([q, p + h / 2 * toda_f(np.concatenate([q, p]))[3:]])


def verlet_q(y, h):
    """The other Störmer-Verlet, the q half-step first: Lobatto IIIA on u = p and IIIB on v = q
    (a Hamiltonian problem's partition is p | q)."""
    q = y[:3] + h / 2 * y[3:]
    p = y[3:] + h * toda_f(np.concatenate([q, y[3:]]))[3:]
    return np.concatenate([q + h / 2 * p, p])


def composed(gammas, y, h, n, step=verlet):
    for _ in range(n):
        for g in gammas:
            y = step(y, g * h)
    return y


@pytest.mark.parametrize("method", ["kutta38", "py-kutta38", "radau3h", "lobatto2ab",
                                    "yoshida6a", "tj4", "tj6"])
def test_toda_by_held_out_methods_matches_independent_implementations(method):
    """The final state and the errors of H, P and the cubic integral I3 agree to round-off with
    the same method written here in numpy; the integrals are those of the Toda lattice."""
    h, n = 0.1, 20
    traj = gnibench.solve("toda3", f"{method}:h={h}", t_end=h * n)
    assert traj.status == "ok"
    last = traj.samples.iloc[-1]
    got = last[["q1", "q2", "q3", "p1", "p2", "p3"]].to_numpy(float)
    if method == "lobatto2ab":
        want = composed([1.0], Y0, h, n, verlet_q)
    elif method in GAMMAS:
        want = composed(GAMMAS[method], Y0, h, n)
    else:
        want = rk(RADAU3 if method == "radau3h" else KUTTA38, toda_f, Y0, h, n)
    assert np.max(np.abs(got - want)) < 1e-12
    i0, i1 = toda_integrals(Y0), toda_integrals(want)
    for name in ("H", "P", "I3"):
        assert last[f"err_{name}"] == pytest.approx(i1[name] - i0[name], abs=1e-12), name
    assert abs(last["err_H"]) > 1e-12                     # the test can fail: errors are seen


def test_rhs_problem_keeps_a_user_integral_named_H():
    """Regression: an integral called H of a right-hand-side problem was dropped (only a
    Hamiltonian's own H is implicit)."""
    traj = gnibench.solve("lagrange-top:mu=2", "radau3h:h=0.1", t_end=2.0)
    assert {"err_H", "err_Mg", "err_gg"} <= set(traj.samples.columns)
    A, C, mu = 2.0, 1.0, 2.0

    def f(y):
        M, g = y[:3], y[3:]
        w = M / np.array([A, A, C])
        return np.concatenate([np.cross(M, w) + mu * np.cross(g, [0, 0, 1]), np.cross(g, w)])

    y0 = np.array([0.3, -0.2, 1.5, 0.6, 0, 0.8])
    y = rk(RADAU3, f, y0, 0.1, 20)
    H = lambda y: (y[0] ** 2 / A + y[1] ** 2 / A + y[2] ** 2 / C) / 2 + mu * y[5]
    last = traj.samples.iloc[-1]
    assert last["err_H"] == pytest.approx(H(y) - H(y0), abs=1e-13)
    assert last["err_gg"] == pytest.approx(y[3:] @ y[3:] - 1, abs=1e-13)
    assert abs(last["err_H"]) > 1e-12


def test_measured_orders_of_held_out_methods(tmp_path, defs):
    """The order metric of an experiment (its load key relative to the file) against the closed
    form of a linear spiral given as the user's exact solution: the declared orders."""
    exp = tmp_path / "exp.toml"
    exp.write_text(f'''name = "heldout-orders"
title = "held-out orders"
reference = "tests/runs/test_user_definitions_unseen.py"
load = ["{Path(defs / 'defs.toml').as_posix()}"]
t_end = 2.0
every = 10
metrics = ["order:at=final"]
[[cells]]
problems = ["spiral"]
methods = ["kutta38", "py-kutta38", "radau3h", "tj4"]
vary.h = [0.1, 0.05, 0.025, 0.0125]
''')
    res = gnibench.run(exp, jobs=1)
    cells = res.cells.assign(base=res.cells["method"].str.split(":").str[0])
    assert (cells["status"] == "ok").all()
    orders = cells.groupby("base")["order_global"].first()
    for method, p in {"kutta38": 4, "py-kutta38": 4, "radau3h": 5}.items():
        assert abs(orders[method] - p) < 0.3, (method, orders[method])
    assert abs(orders["tj4"] - 4) < 0.3                 # Verlet on a non-separable partition
    kinds = dict(zip(cells["base"], cells["method_kind"]))
    assert kinds["py-kutta38"] == "python" and kinds["kutta38"] == "compiled"


def test_scipy_dop853_on_kepler_is_solve_ivp_with_an_independent_field():
    """rtol = atol = 1e-10, one period of kepler-2d (e = 0.6): the same nfev as solve_ivp called
    directly on a field written here, and the same samples to round-off."""
    T, e = 2 * np.pi, 0.6

    def f(t, y):
        p1, p2, q1, q2 = y
        r3 = math.hypot(q1, q2) ** 3
        return [-q1 / r3, -q2 / r3, p1, p2]

    y0 = [0.0, math.sqrt((1 + e) / (1 - e)), 1 - e, 0.0]
    traj = gnibench.solve("kepler-2d", f"scipy-dop853:rtol=1e-10,atol=1e-10,dt_out={T / 10!r}",
                          t_end=T)
    grid = traj.samples["t"].to_numpy()
    sol = solve_ivp(f, (0, T), y0, method="DOP853", rtol=1e-10, atol=1e-10, t_eval=grid)
    assert traj.samples["nfev"].iloc[-1] == sol.nfev
    assert np.max(np.abs(traj.samples[["p1", "p2", "q1", "q2"]].to_numpy() - sol.y.T)) < 1e-11
    assert np.max(np.abs(sol.y[:, -1] - y0)) == pytest.approx(
        traj.metrics["final_global_error"], rel=0.5)   # one period: back at the start


@pytest.mark.parametrize("value, says", [("nan", "not a finite number"),
                                         ("inf", "not a finite number"),
                                         ("1e400", "not a finite number"),
                                         ('"1e400"', "beyond")])
def test_non_finite_numbers_in_definitions_are_refused(tmp_path, value, says):
    """Regression: a TOML nan or inf (or a float beyond the doubles) was a traceback."""
    path = tmp_path / "bad.toml"
    path.write_text(f'[[problem]]\nid = "x"\nstates = ["q", "p"]\nhamiltonian = "p^2/2 + q^2/2"\n'
                    f'initial = {{q = {value}, p = 0}}\n')
    with pytest.raises(gnibench.UserError, match=says) as err:
        gnibench.load(path)
    assert "initial.q" in str(err.value) and "\n" not in str(err.value)


BAD_SOLVERS = '''
import numpy as np
def wrong_shape(f, y0, t_span, t_eval, rtol, atol):
    return np.zeros((len(t_eval), len(y0) + 1))
def raises(f, y0, t_span, t_eval, rtol, atol):
    raise RuntimeError("no convergence")
def bad_count(f, y0, t_span, t_eval, rtol, atol):
    return {"y": np.tile(y0, (len(t_eval), 1)), "nfev": "many"}
'''


@pytest.mark.parametrize("entry, says", [("wrong_shape", "expected (4, 4)"),
                                         ("raises", "RuntimeError: no convergence"),
                                         ("bad_count", "returned nfev = 'many'")])
def test_a_failing_python_solver_is_a_status(tmp_path, entry, says):
    """Regression: a python-solver that raised, returned a wrong shape or a bad count crashed
    the cell (no sample to build a trajectory on); it is status error with the reason, and the
    initial point as the one sample."""
    (tmp_path / "bad_solvers.py").write_text(BAD_SOLVERS)
    (tmp_path / "bad.toml").write_text(f'[[method]]\nid = "bad-{entry}"\nkind = "python-solver"\n'
                                       f'entry = "bad_solvers:{entry}"\nrtol = 1e-6\natol = 1e-6\n')
    gnibench.load(tmp_path / "bad.toml")
    traj = gnibench.solve("kepler-2d", f"bad-{entry}:dt_out=0.5", t_end=1.5)
    assert traj.status == "error" and says in traj.reason
    assert len(traj.samples) == 1 and traj.samples["t"].iloc[0] == 0.0
    assert traj.samples["q1"].iloc[0] == pytest.approx(0.4)


def test_an_edited_definitions_file_is_solved_as_edited(tmp_path):
    """Regression: the API reloads an edited file, but the compiled cell of the same specs was
    kept (keyed by the spec text only): the old initial point and the old vector field."""
    path = tmp_path / "osc.toml"
    text = ('[[problem]]\nid = "osc-edit"\nstates = ["q", "p"]\nhamiltonian = "p^2/2 + q^2/2"\n'
            'initial = {q = 1, p = 0}\n')
    path.write_text(text)
    gnibench.load(path)
    before = gnibench.solve("osc-edit", "kutta38:h=0.01", steps=100).samples.iloc[-1]
    assert before["q"] == pytest.approx(math.cos(1.0), abs=1e-6)
    path.write_text(text.replace("q^2/2", "2*q^2").replace("q = 1", "q = 3"))
    after = gnibench.solve("osc-edit", "kutta38:h=0.01", steps=100).samples.iloc[-1]
    assert after["q"] == pytest.approx(3 * math.cos(2.0), abs=1e-6)     # omega = 2 now


GAUSS2 = ('c = ["1/2 - sqrt(3)/6", "1/2 + sqrt(3)/6"]\nA = [["1/4", "1/4 - sqrt(3)/6"], '
          '["1/4 + sqrt(3)/6", "1/4"]]\nb = ["1/2", "1/2"]\norder = 4\nkind = "implicit-rk"\n')
RADAU2 = ('c = ["1/3", 1]\nA = [["5/12", "-1/12"], ["3/4", "1/4"]]\nb = ["3/4", "1/4"]\norder = 3\n'
          'kind = "implicit-rk"\n')
TRAPEZOID = 'c = [0, 1]\nA = [[0, 0], ["1/2", "1/2"]]\nb = ["1/2", "1/2"]\norder = 2\nkind = "implicit-rk"\n'
KUTTA = ('c = [0, "1/3", "2/3", 1]\nA = [[], ["1/3"], ["-1/3", 1], [1, -1, 1]]\n'
         'b = ["1/8", "3/8", "3/8", "1/8"]\norder = 4\nkind = "explicit-rk"\n')
LOBATTO = ('kind = "partitioned-rk"\norder = 2\nu = {c = [0, 1], A = [[0, 0], ["1/2", "1/2"]], '
           'b = ["1/2", "1/2"]}\nv = {c = ["1/2", "1/2"], A = [["1/2", 0], ["1/2", 0]], '
           'b = ["1/2", "1/2"]}\n')


@pytest.mark.parametrize("body, flags, refused", [
    (GAUSS2, "symplectic = true\nsymmetric = true\n", None),            # [HLW] VI.4, V.2
    (LOBATTO, "symplectic = true\nsymmetric = true\n", None),
    (TRAPEZOID, "symmetric = true\n", None),
    (TRAPEZOID, "symplectic = true\n", "symplectic"),                   # symmetric, not symplectic
    (RADAU2, "symmetric = true\n", "symmetric"),
    (KUTTA, "symplectic = true\n", "symplectic"),                       # no explicit RK is
    ('kind = "composition"\norder = 2\nbasis = "stormer-verlet"\ngamma = ["1/3", "2/3"]\n',
     "symmetric = true\n", "symmetric"),
    ('kind = "composition"\norder = 1\nbasis = "euler"\ngamma = ["1/2", "1/2"]\n',
     "symplectic = true\n", "symplectic"),
])
def test_declared_properties_are_checked(tmp_path, body, flags, refused):
    """Regression: symplectic and symmetric were taken on trust (Kutta's 3/8 rule could be listed
    as symplectic and symmetric); they are checked as the order is."""
    path = tmp_path / "flags.toml"
    path.write_text(f'[[method]]\nid = "flagged"\n{flags}{body}')
    if refused is None:
        gnibench.load(path)
        row = gnibench.list_methods().set_index("id").loc["flagged"]
        for flag in ("symplectic", "symmetric"):
            assert bool(row[flag]) == (flag in flags), flag
        return
    with pytest.raises(gnibench.UserError, match=f"key '{refused}': declared true, but") as err:
        gnibench.load(path)
    assert "[HLW]" in str(err.value)


KEPLER = '''
[[problem]]
id = "kepler-user"
states = ["q1", "q2", "p1", "p2"]
hamiltonian = "(p1^2 + p2^2)/2 - 1/sqrt(q1^2 + q2^2)"
integrals = {L = "q1*p2 - q2*p1"}
parameters = {e = 0.6}
initial = {q1 = "1 - e", q2 = 0, p1 = 0, p2 = "sqrt((1 + e)/(1 - e))"}
period = "2*pi*(-2*((p10^2 + p20^2)/2 - 1/sqrt(q10^2 + q20^2)))^(-3/2)"
'''


def test_a_user_kepler_problem_gives_the_shipped_eta(tmp_path):
    """The plane Kepler problem written by the user (period from the initial energy, [B] §5.2)
    gives the η(nT) of the shipped kepler-2d to round-off, at another eccentricity too."""
    (tmp_path / "kepler.toml").write_text(KEPLER)
    gnibench.load(tmp_path / "kepler.toml")
    T = 2 * math.pi
    for e in (0.6, 0.3):
        user, shipped = (gnibench.solve(f"{p}:e={e}", "gauss4:h=0.05", t_end=5 * T, every=20,
                                        metrics="eta") for p in ("kepler-user", "kepler-2d"))
        assert user.metrics["eta_period"] == pytest.approx(T, rel=1e-13)
        assert user.metrics["eta_final"] == pytest.approx(shipped.metrics["eta_final"], rel=1e-6)
        assert user.metrics["eta_final"] > 1e-9


def test_options_where_an_initial_value_or_the_period_fails(tmp_path):
    """Regression: an option making an initial expression complex or infinite (e >= 1 here) was
    a TypeError traceback; a period that is not real (an unbound orbit) refused every cell, also
    those that never use it: now η alone refuses it, the orbit is integrated."""
    (tmp_path / "kepler.toml").write_text(KEPLER)
    gnibench.load(tmp_path / "kepler.toml")
    for e, says in ((1.5, "the initial value p2 = .* is 0\\+2.23607j"), (1, "not a number")):
        with pytest.raises(gnibench.UserError, match=says):
            gnibench.solve(f"kepler-user:e={e}", "gauss4:h=0.05", steps=2)
    unbound = gnibench.solve("kepler-user:p20=5", "gauss4:h=0.05", t_end=1.0)
    assert unbound.status == "ok" and unbound.samples["q2"].iloc[-1] > 4      # flies off
    with pytest.raises(gnibench.UserError, match="its period .* \\(not real\\)"):
        gnibench.solve("kepler-user:p20=5", "gauss4:h=0.05", t_end=1.0, metrics="eta")
