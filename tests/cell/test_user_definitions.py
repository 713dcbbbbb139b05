"""User definitions (suite/cell/user): TOML problems and methods, Python integrators, their
refusals (naming file, entry and key), the safe expression subset, and records reaching a process
that never loaded them. End-to-end runs, measured orders and the example package:
tests/runs/test_user_runs.py."""
from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.user import loader
from gnibench.suite.cell.user.expressions import ExpressionError, parse
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
DEFS = EXAMPLES / "definitions.toml"


@pytest.fixture(autouse=True)
def _clean_registries():
    yield
    loader.unload()


def test_solve_a_user_problem_with_user_methods_against_its_exact_solution():
    loader.load(DEFS)
    T = 2 * np.pi / 3
    cases = {"heun3:h=0.01": 3, "radau2a:h=0.01": 3, "lobatto-3a3b:h=0.01": 4,
             "triple-jump:h=0.01": 4, "py-rk4:h=0.01": 4}
    for method, order in cases.items():
        traj = solve("oscillator:omega=3,q0=0.5,p0=1", method, t_end=T)
        err = np.max(np.abs(traj.y - traj.reference.y))
        assert str(traj.status) == "ok"
        assert 1e-4 * 0.03 ** order < err < 10 * 0.03 ** order, (method, err)  # C (omega h)^p
        assert traj.y[-1] == pytest.approx([0.5, 1.0], abs=10 * 0.03 ** order)  # one period
    adaptive = solve("oscillator", "bs23:rtol=1e-9,atol=1e-9", t_end=10.0)
    assert np.max(np.abs(adaptive.y - adaptive.reference.y)) < 1e-6
    lv = solve("lotka-volterra-3", "lobatto-3a3b:h=0.01", t_end=5.0)
    assert np.max(np.abs(lv.integrals - lv.integrals[0])) < 1e-8    # I of [HLW] (1.4), general rates


def test_cli_list_and_solve_with_load(tmp_path, capsys):
    assert main(["list", "methods", "--load", str(DEFS), "--format", "json"]) == 0
    rows = {r["id"]: r for r in json.loads(capsys.readouterr().out)}
    assert rows["py-rk4"]["kind"] == "python" and rows["heun3"]["kind"] == "compiled"
    assert rows["bs23"]["family"] == "embedded-rk" and rows["triple-jump"]["properties"]["symmetric"]
    assert main(["list", "problems", "--load", str(DEFS)]) == 0
    assert "lotka-volterra-3" in capsys.readouterr().out
    out = tmp_path / "s.json"
    assert main(["solve", "oscillator", "py-dop853:dt_out=0.25", "--t-end", "2", "--load",
                 str(DEFS), "--format", "json", "-o", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["meta"]["status"] == "ok" and doc["meta"]["metrics"]["max_global_error"] < 1e-7
    assert doc["columns"]["t"][-1] == 2.0 and doc["columns"]["t"][1] == 0.25


def test_gnibench_load_environment_variable(tmp_path):
    env = {**os.environ, "GNIBENCH_LOAD": f"{tmp_path / 'none.toml'}:{DEFS}"}
    (tmp_path / "none.toml").write_text("")
    proc = subprocess.run([sys.executable, "-m", "gnibench.suite.cli.main", "list", "methods"],
                          capture_output=True, text=True, env=env, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "triple-jump  order 4  composition" in proc.stdout and "py-rk4" in proc.stdout


def test_records_reach_a_process_that_never_loaded_them(tmp_path):
    """A Dask worker started by spawn: the origin travels with the pickled record."""
    from gnibench.suite.metrics.cells import make_cell

    loader.load(DEFS)
    cell = make_cell("oscillator:omega=2", "triple-jump:h=0.05", steps=10)
    path = tmp_path / "cell.pickle"
    path.write_bytes(pickle.dumps(cell))
    code = ("import pickle, sys\n"
            "from gnibench.suite.cell.driver import integrate\n"
            "cell = pickle.loads(open(sys.argv[1], 'rb').read())\n"
            "print(cell.method_text, repr(float(integrate(cell).y[-1, 0])))\n")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True,
                         check=True, cwd=tmp_path).stdout.split()
    here = solve("oscillator:omega=2", "triple-jump:h=0.05", steps=10)
    assert out == [cell.method_text, repr(float(here.y[-1, 0]))]


def _defs(tmp_path, text: str) -> Path:
    path = tmp_path / "defs.toml"
    path.write_text(text)
    return path


GOOD_RK = '[[method]]\nid = "my-rk"\nkind = "explicit-rk"\norder = 3\nc = [0, "1/3", "2/3"]\n' \
          'A = [[], ["1/3"], [0, "2/3"]]\nb = ["1/4", 0, "3/4"]\n'
OSC = '[[problem]]\nid = "osc"\nstates = ["q", "p"]\nhamiltonian = "p^2/2 + q^2/2"\n' \
      'initial = {q = 1, p = 0}\n'
REFUSED = {
    "collides with a shipped method": (GOOD_RK.replace('"my-rk"', '"rk4"'), "method", 1, "id",
                                       "collides with a shipped one"),
    "collides with a shipped problem": (OSC.replace('"osc"', '"pendulum"'), "problem", 1, "id",
                                        "collides with a shipped one"),
    "a shipped method's id in capitals": (GOOD_RK.replace('"my-rk"', '"RK4"'), "method", 1, "id",
                                          "id 'RK4' collides with 'rk4', a shipped one, in all "
                                          "but letter case"),
    "a shipped problem's id in capitals": (OSC.replace('"osc"', '"Kepler-2D"'), "problem", 1,
                                           "id", "id 'Kepler-2D' collides with 'kepler-2d', a "
                                                 "shipped one, in all but letter case"),
    "another entry's id in capitals": (GOOD_RK + GOOD_RK.replace('"my-rk"', '"My-RK"'), "method",
                                       2, "id", "collides with 'my-rk', another entry of this "
                                                "file, in all but letter case"),
    "p-first states": (OSC.replace('["q", "p"]', '["p", "q"]'), "problem", 1, "states",
                       "['p', 'q'] reads p-first ('p' among the q's, 'q' among the p's), which "
                       "would run the time-reversed flow; list the q's first, or give q = [...] "
                       "and p = [...]"),
    "p-first states named px, x": (OSC.replace('["q", "p"]', '["px", "x"]').replace(
        '"p^2/2 + q^2/2"', '"px^2/2 + x^2/2"').replace("{q = 1, p = 0}", "{x = 1, px = 0}"),
        "problem", 1, "states", "('px' among the q's, 'x' among the p's)"),
    "q without p": (OSC + 'q = ["q"]\n', "problem", 1, "p", "give both 'q' and 'p'"),
    "q and p not the states": (OSC + 'q = ["q"]\np = ["r"]\n', "problem", 1, "q",
                               "must hold every state of ['q', 'p'] once"),
    "q and p for a right-hand side": (OSC.replace('hamiltonian = "p^2/2 + q^2/2"',
                                                  'rhs = {q = "p", p = "-q"}')
                                      + 'q = ["q"]\np = ["p"]\n', "problem", 1, "q",
                                      "a right-hand side's blocks are its 'partition'"),
    "failing order condition": (GOOD_RK.replace("order = 3", "order = 4"), "method", 1, "order",
                                "order 4 condition for tree"),
    "wrong row sum": (GOOD_RK.replace('c = [0, "1/3", "2/3"]', 'c = [0, "1/2", "2/3"]'), "method",
                      1, "c", "row sum"),
    "attribute access": (OSC.replace('"p^2/2 + q^2/2"', '"p.__class__"'), "problem", 1,
                         "hamiltonian", "attribute access"),
    "a call": (OSC.replace('"p^2/2 + q^2/2"', '"__import__(\'os\')"'), "problem", 1,
               "hamiltonian", "this call"),
    "an unknown name": (OSC.replace('"p^2/2 + q^2/2"', '"p^2/2 + k*q^2"'), "problem", 1,
                        "hamiltonian", "the name 'k'"),
    "bad key": (GOOD_RK + "bogus = 1\n", "method", 1, "bogus", "unknown key"),
    "bad kind": (GOOD_RK.replace("explicit-rk", "magic"), "method", 1, "kind", "bad value"),
    "above the diagonal": (GOOD_RK.replace('[0, "2/3"]]', '[0, "2/3", 1]]'), "method", 1, "A",
                           "on or above the diagonal"),
    "missing entry function": (('[[method]]\nid = "p"\nkind = "python"\n'
                               'entry = "no_such_module_x:step"\n'),
                               "method", 1, "entry", "cannot load"),
    "composition beyond II.4": (('[[method]]\nid = "c"\nkind = "composition"\norder = 6\n'
                                'basis = "lie-poisson"\ngamma = [1]\n'), "method", 1, "order",
                                "at most order"),
    "composition order": (('[[method]]\nid = "c"\nkind = "composition"\norder = 4\n'
                          'basis = "stormer-verlet"\ngamma = ["1/2", "1/2"]\n'), "method", 1,
                          "order", "order 3 condition"),
    "second entry": (OSC + GOOD_RK + GOOD_RK.replace('"my-rk"', '"rk2"').replace(
        'b = ["1/4", 0, "3/4"]', 'b = "oops"'), "method", 2, "b", "bad value"),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refusals_name_file_entry_and_key(case, tmp_path):
    text, kind, index, key, message = REFUSED[case]
    path = _defs(tmp_path, text)
    with pytest.raises(UserError) as e:
        loader.load(path)
    msg = str(e.value)
    assert "\n" not in msg and message in msg, msg
    assert msg.startswith(f"{path.resolve()}: [[{kind}]] {index} (id "), msg
    assert f"key {key!r}" in msg or f"key '{key}[" in msg or f"key '{key}." in msg, msg
    from gnibench.methods import METHODS
    from gnibench.problems import REGISTRY

    assert "my-rk" not in METHODS and "osc" not in REGISTRY          # nothing registered


def test_collision_with_another_file_and_reloading(tmp_path):
    a = _defs(tmp_path, GOOD_RK)
    assert loader.load(a) == ["my-rk"] and loader.load(a) == ["my-rk"]     # again: a no-op
    other = tmp_path / "other.toml"
    other.write_text(GOOD_RK)
    with pytest.raises(UserError, match=f"collides with the one of {a.resolve()}"):
        loader.load(other)
    other.write_text(GOOD_RK.replace('"my-rk"', '"MY-RK"'))         # the same but for case
    with pytest.raises(UserError, match=f"collides with 'my-rk', the one of {a.resolve()}, in "
                                        f"all but letter case"):
        loader.load(other)
    a.write_text(GOOD_RK.replace('"my-rk"', '"my-rk-2"'))           # changed: replaces its own
    assert loader.load(a) == ["my-rk-2"]
    with pytest.raises(UserError, match="unknown method 'my-rk'"):
        solve("pendulum", "my-rk:h=0.1", steps=1)


def test_cli_refusal_is_one_line_exit_2(tmp_path, capsys):
    path = _defs(tmp_path, GOOD_RK.replace("order = 3", "order = 4"))
    assert main(["solve", "pendulum", "my-rk", "--steps", "3", "--load", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "key 'order'" in err


PENDULUM_P_FIRST = """
[[problem]]
id = "my-pendulum"
states = ["p", "q"]                 # as the shipped pendulum lists them
hamiltonian = "p^2/2 - cos(q)"
initial = {p = 0, q = 0.5}
"""


def test_a_p_first_hamiltonian_is_refused_or_integrated_as_declared(tmp_path, capsys):
    """Regression: states = ["p", "q"] was taken as q = p, p = q (the time-reversed flow, no
    error). Alone it is refused, one line; with q = [...], p = [...] it is the pendulum."""
    path = _defs(tmp_path, PENDULUM_P_FIRST)
    assert main(["solve", "my-pendulum", "rk4:h=0.01", "--steps", "3", "--load", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert f"{path.resolve()}: [[problem]] 1 (id 'my-pendulum'), key 'states': " in err
    path.write_text(PENDULUM_P_FIRST + 'q = ["q"]\np = ["p"]\n')
    loader.load(path)
    for method in ("rk4:h=0.01", "stormer-verlet:h=0.01"):      # stormer-verlet: the partition
        mine = solve("my-pendulum", method, t_end=2.0)
        shipped = solve("pendulum", method, t_end=2.0)          # (p, q) too, exact solution
        exact = shipped.reference.y
        assert mine.y[1, 0] < 0 and exact[1, 0] < 0             # p' = -sin q < 0 at q = 0.5
        assert np.max(np.abs(mine.y - exact)) < 1e-3, method
        assert np.array_equal(mine.y, shipped.y), method          # the same field, bit for bit


def test_q_and_p_keys_take_the_states_in_any_order(tmp_path):
    """Two oscillators (frequencies 1 and 2) with states interleaved, exact solution given (the
    load check of the exact solution holds only with the declared pairs)."""
    loader.load(_defs(tmp_path, """
[[problem]]
id = "two-osc"
states = ["x", "px", "y", "py"]
q = ["x", "y"]
p = ["px", "py"]
hamiltonian = "px^2/2 + py^2/2 + x^2/2 + 2*y^2"
initial = {x = 1, px = 0, y = 1, py = 0}
exact = {x = "cos(t)", px = "-sin(t)", y = "cos(2*t)", py = "-2*sin(2*t)"}
"""))
    from gnibench.problems import REGISTRY

    assert REGISTRY["two-osc"].canonical == (("px", "py"), ("x", "y"))
    for method, tol in (("rk4:h=0.01", 1e-7), ("stormer-verlet:h=0.01", 1e-3)):
        traj = solve("two-osc", method, t_end=3.0)
        assert np.max(np.abs(traj.y - traj.reference.y)) < tol, method


@pytest.mark.parametrize("load, said", [
    ('["missing.toml"]', "no definitions file"),
    ('["defs.toml"]', "key 'order': the tableau does not have the declared order 4")])
def test_an_experiment_s_bad_load_names_the_experiment_and_the_key(tmp_path, capsys, load, said):
    _defs(tmp_path, GOOD_RK.replace("order = 3", "order = 4"))
    exp = tmp_path / "exp.toml"
    exp.write_text(f'name = "x"\ntitle = "x"\nreference = "x"\nload = {load}\nt_end = 1.0\n'
                   '[[cells]]\nproblems = ["pendulum"]\nmethods = ["rk4"]\n')
    out = tmp_path / "out"
    assert main(["run", str(exp), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"gnibench: error: {exp.name}: load[0]: "), err
    assert said in err and not out.exists()


def test_a_large_power_is_not_expanded_to_find_the_explicit_blocks(tmp_path, monkeypatch):
    """(q + p + 1)^1000 is within the expressions' bounds; its Jacobian entries are nonzero at a
    point, so sympy's simplify (which expands the power and runs for hours) is never asked."""
    import sympy as sp
    from gnibench.problems import REGISTRY
    from gnibench.problems.codegen import problem_meta, vanishes

    monkeypatch.setenv("GNIBENCH_CACHE_DIR", str(tmp_path / "cache"))
    loader.load(_defs(tmp_path, OSC.replace("q^2/2", "(q + p + 1)^1000")))

    def refuse(*args, **kwargs):
        raise AssertionError("simplify asked about an entry that is nonzero at a point")

    monkeypatch.setattr(sp, "simplify", refuse)
    meta = problem_meta(REGISTRY["osc"])
    assert meta["explicit_u"] is False and meta["explicit_v"] is False
    monkeypatch.undo()
    u, v = sp.symbols("u v", real=True)               # zero only after simplification
    assert vanishes(sp.diff(v * sp.tan(u) * sp.cos(u) - v * sp.sin(u), u), [u, v])
    assert not vanishes(sp.diff(v * sp.log(u), u), [u, v])


@pytest.mark.parametrize("text", ["x.real", "os.system('ls')", "[1, 2]", "lambda: 1", "x if x else 1",
                                  "x < 1", "'a'", "f(x)", "sin(x, y)", "sqrt(x=1)", "2^(10^9)",
                                  "x[0]", "1/0", "exp(*x)", "x\n+1"])
def test_expressions_outside_the_safe_subset_are_refused(text):
    import sympy as sp

    with pytest.raises(ExpressionError):
        parse(text, {"x": sp.Symbol("x"), "y": sp.Symbol("y")})


@pytest.mark.parametrize("text", ["-" * 19990 + "x", "+".join(["x"] * 6000),
                                  "x" + "**x" * 4000])
def test_expressions_too_deep_for_the_parser_are_one_short_line(text):
    """Within the 20000 characters, chains that overflow Python's own parser (MemoryError,
    RecursionError) were tracebacks; the message quotes at most 80 characters of the text."""
    import sympy as sp

    with pytest.raises(ExpressionError, match="too deep for Python's parser") as caught:
        parse(text, {"x": sp.Symbol("x")})
    assert len(str(caught.value)) < 200


def test_expressions_are_exact():
    import sympy as sp

    x = sp.Symbol("x")
    assert parse("0.1") == sp.Rational(1, 10) and parse("2-2^(1/3)") == 2 - sp.cbrt(2)
    assert parse("-x**2 + atan2(x, 1) + pi", {"x": x}) == -x ** 2 + sp.atan2(x, 1) + sp.pi


def test_a_composition_refused_by_its_basis_names_itself(tmp_path):
    """The user named the composition: the refusal says so (and that it comes from its basis)."""
    path = _defs(tmp_path, '''
[[method]]
id = "tj4-of-sv"
kind = "composition"
basis = "stormer-verlet"
gamma = ["1/(2-2^(1/3))", "-2^(1/3)/(2-2^(1/3))", "1/(2-2^(1/3))"]
order = 4
''')
    loader.load(path)
    with pytest.raises(UserError, match=r"^method tj4-of-sv \(a composition of stormer-verlet\): "
                                        r"it needs a partitioned system"):
        solve("euler-so4", "tj4-of-sv:h=0.01", steps=2)


def test_an_id_longer_than_64_characters_is_refused_up_front(tmp_path):
    """An id names cache files: 5000 characters failed later with "File name too long" naming a
    cache path. Refused when the file is loaded, the id shortened in the message."""
    from gnibench.suite.cell.user.loader import load
    from gnibench.suite.foundation.errors import UserError

    defs = tmp_path / "long.toml"
    for n, ok in ((64, True), (65, False), (5000, False)):
        defs.write_text(f'[[problem]]\nid = "{"a" * n}"\nq = ["q"]\np = ["p"]\n'
                        f'hamiltonian = "p**2/2 + q**2/2"\ninitial = {{ q = "1", p = "0" }}\n')
        if ok:
            assert load(defs) == ["a" * n]
            continue
        with pytest.raises(UserError, match=rf"bad id 'a{{20}}'\.\.\. \({n} characters\); "
                                            r"allowed: .*at most 64 characters") as e:
            load(defs)
        assert len(str(e.value)) < 300
