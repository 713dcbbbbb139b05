"""The typed cell (suite/cell/cellspec.py): parsed once at the edge, picklable by registry
references, methods' kind as data, spec structure without hand splitting, refusals of issue 18."""
from __future__ import annotations

import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from gnibench.methods import COMPILED, METHODS
from gnibench.methods.base import KINDS
from gnibench.suite.cell.cellspec import CellSpec
from gnibench.suite.cell.driver import integrate
from gnibench.suite.cell.solve import solve
from gnibench.suite.cell.spec import parse_method, parse_problem, prepare, structure
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.metrics.cells import make_cell
from gnibench.suite.runs.experiment import parse_experiment

ROOT = Path(__file__).resolve().parents[2]

EXPERIMENT = """
name = "typed"
title = "typed cells"
reference = "[HLW] I.2"
t_end = 6.283185307179586
every = 50
metrics = ["eta", "growth:of=H"]
[[cells]]
problems = ["kepler-2d:e=0.6"]
methods = ["rk4:h=0.01+observer:on=H/L,theta=2", "heyoka-taylor"]
"""


def test_cell_is_typed_and_pickles_by_registry_reference():
    cell = parse_experiment(EXPERIMENT, "typed.toml").cells[0]
    spec = cell.spec
    assert isinstance(spec, CellSpec)
    assert spec.problem.record is parse_problem("kepler-2d").record
    assert spec.method.modifiers[0].values["on"] == ("H", "L")
    assert [c.metric.id for c in spec.metrics] == ["eta", "growth"]
    assert spec.dt_out == pytest.approx(2 * np.pi)      # eta: on the grid t = nT
    back = pickle.loads(pickle.dumps(cell))
    assert back == cell and back.method == cell.method and back.metrics == cell.metrics
    assert back.spec.method.base.record is spec.method.base.record      # the registry's record
    assert back.spec.metrics[1].metric is spec.metrics[1].metric
    engine = parse_experiment(EXPERIMENT, "typed.toml").cells[1]
    assert engine.spec.method_kind == "external" and engine.spec.method.base.values["dt_out"] > 0


def test_a_fresh_interpreter_resolves_the_records_it_unpickles(tmp_path):
    """A spawned worker (Dask) has imported nothing: unpickling imports the registries."""
    cell = parse_experiment(EXPERIMENT, "typed.toml").cells[0]
    path = tmp_path / "cell.pickle"
    path.write_bytes(pickle.dumps(cell))
    code = ("import pickle, sys; c = pickle.loads(open(sys.argv[1], 'rb').read()); "
            "print(c.method, c.spec.problem.record.id, c.spec.metrics[0].metric.id)")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == [cell.method, "kepler-2d", "eta"]


def test_a_record_made_on_the_fly_pickles_by_value():
    from dataclasses import replace

    rec = replace(METHODS["rk4"], id="rk4-copy")
    assert pickle.loads(pickle.dumps(rec.describe())) == rec.describe()
    with pytest.raises((pickle.PicklingError, AttributeError, TypeError)):
        pickle.dumps(rec)              # it holds a local function: by value, as a dataclass would


def test_text_and_typed_values_give_the_same_cell_and_samples():
    a = make_cell("pendulum:p0=1.4,q0=0", "stormer-verlet:h=0.1", steps=50, every=10)
    p, m = prepare("pendulum:p0=1.4,q0=0", "stormer-verlet:h=0.1")
    b = make_cell(p, m, steps=50, every=10)
    assert a == b and a.problem_text == "pendulum:p0=1.4,q0=0"
    t1 = solve("pendulum:p0=1.4,q0=0", "stormer-verlet:h=0.1", steps=50, every=10)
    t2 = solve(p, m, steps=50, every=10)
    t3 = integrate(a)
    assert np.array_equal(t1.y, t2.y) and np.array_equal(t1.y, t3.y)
    # a method parsed without the problem is checked against it (modifiers resolved)
    loose = parse_method("rk4:h=0.01+observer:theta=3")
    cell = make_cell("double-oscillator", loose, steps=10)
    assert cell.method.modifiers[0].values["on"] == ("H1", "H2")
    with pytest.raises(UserError, match="needs a partitioned system"):
        make_cell("euler-so4", parse_method("symplectic-euler"), steps=10)


def test_method_kind_is_data():
    assert {m.kind for m in METHODS.values()} <= set(KINDS)
    externals = {k for k, m in METHODS.items() if m.kind == "external"}
    assert externals == {"heyoka-taylor", "rebound-ias15", "rebound-whfast", "scipy-rk45",
                         "scipy-rk23", "scipy-dop853", "scipy-radau", "scipy-bdf", "scipy-lsoda"}
    assert set(COMPILED) == set(METHODS) - externals
    for path in list((ROOT / "suite").rglob("*.py")) + list((ROOT / "methods").rglob("*.py")):
        assert not re.search(r"getattr\([^)]*[\"']run[\"']", path.read_text()), path


def test_no_hand_splitting_of_spec_text_outside_the_spec_module():
    # split(":"), partition("+"), a modifier looked for as a substring ("+observer" in spec),
    # an id as a prefix of the spec (method.startswith(...): "symplectic-euler" is a prefix of
    # "symplectic-euler-adjoint")
    pattern = re.compile(r"""(partition|split)\(["'][:+]["']|["']\+[a-z]\w*["'] (not )?in """
                         r"""|\b(method|problem|spec)\.startswith\(""")
    for top in ("suite", "methods", "problems", "reports"):
        for path in (ROOT / top).rglob("*.py"):
            if path.name == "spec.py":
                continue
            for n, line in enumerate(path.read_text().splitlines(), 1):
                assert not pattern.search(line), f"{path}:{n}: {line.strip()}"


def test_ledger_closed_forms_read_spec_ids_not_prefixes():
    """pendulum_asymmetry ([HLW] Fig 1.4) takes symplectic Euler and Störmer-Verlet cells by
    their ids: a symplectic-euler-adjoint cell is refused, not counted as symplectic Euler."""
    from gnibench.suite.ledger.closed_forms_hlw import pendulum_asymmetry

    t = np.linspace(0.0, 1.0, 5)
    samples = pd.DataFrame({"cell": [0] * 5, "t": t, "q": np.sin(t), "p": np.cos(t)})
    cells = pd.DataFrame({"cell": [0], "method": ["symplectic-euler:h=0.3"],
                          "base_method": ["symplectic-euler"]})
    assert set(pendulum_asymmetry(cells, samples)) == {"se"}
    with pytest.raises(ValueError, match="not symplectic-euler-adjoint"):
        pendulum_asymmetry(cells.assign(method="symplectic-euler-adjoint:h=0.3",
                                        base_method="symplectic-euler-adjoint"), samples)


@pytest.mark.parametrize("spec, family", [
    ("dopri5:adaptive=true,rtol=1e-08,atol=1e-08", ("dopri5", "rtol", 1e-8, True)),
    ("merson:adaptive=true,rtol=1e-05,atol=1e-06", ("merson:adaptive=true", "rtol", 1e-5, True)),
    ("heyoka-taylor:dt_out=0.01,tol=1e-10,precision=long double",
     ("heyoka-taylor:precision=long double", "tol", 1e-10, True)),
    ("rk4:h=0.1+observer:mode=simple,on=H/L,theta=1/1",
     ("rk4+observer:mode=simple,on=H/L,theta=1/1", "h", 0.1, False)),
    ("dopri5:adaptive=false,h=0.05", ("dopri5:adaptive=false", "h", 0.05, False)),
])
def test_method_families_come_from_the_typed_method(spec, family):
    """The family of a method (cells.parquet's columns family, sweep, sweep_value, adaptive)
    from its typed values, not from its text."""
    _, method = prepare("kepler-2d", spec)
    f = method.family()
    assert (f.label, f.sweep, f.value, f.adaptive) == family


def test_structure_of_spec_texts():
    s = structure("rk4:h=1e+6+observer:on=H/L,theta=2+projection")
    assert s.id == "rk4" and [m.id for m in s.modifiers] == ["observer", "projection"]
    assert s.base.given == {"h": "1e+6"} and s.modifier("observer").given["on"] == "H/L"
    assert s.without("h").text() == "rk4+observer:on=H/L,theta=2+projection"
    assert structure("kepler-2d:e=0.6", "problem").id == "kepler-2d"
    with pytest.raises(UserError, match="expected key=value"):
        structure("rk4:h")


@pytest.mark.parametrize("args", [
    ["solve", "kepler-2d", "rk4:h=0.01\n", "--steps", "3"],
    ["solve", "kepler-2d\n", "rk4:h=0.01", "--steps", "3"],
    ["solve", "kepler-2d", "rk4:h=0.01+observer:on=H\n", "--steps", "3"],
    ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "3", "--metrics", "eta\n"],
    ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "3", "--reference", "exact\n"],
    ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "3", "--metrics", ","],
    ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "3", "--metrics", ""],
    ["solve", "kepler-2d", "rk4:h=0.01", "--steps", "3", "--metrics", "eta,,growth"],
])
def test_trailing_newlines_and_empty_metrics_are_refused(args, capsys):
    assert main(args) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and err.startswith("gnibench: error: bad ")


def test_cells_table_says_how_each_method_runs(tmp_path):
    path = tmp_path / "typed.toml"
    path.write_text(EXPERIMENT.replace('"heyoka-taylor"', '"heyoka-taylor:tol=1e-12"'))
    assert main(["run", str(path), "-o", str(tmp_path / "out"), "-j", "1", "--no-report"]) == 0
    cells = pd.read_parquet(tmp_path / "out" / "cells.parquet")
    assert list(cells["method_kind"]) == ["compiled", "external"]
    assert list(cells.columns[:14]) == ["cell", "group", "label", "problem", "method",
                                        "problem_id", "base_method", "modifiers", "method_kind",
                                        "family", "sweep", "sweep_value", "adaptive", "h"]
    # the parts of the specs, from the typed cells (the reports read them, never the texts)
    assert list(cells["problem_id"]) == ["kepler-2d", "kepler-2d"]
    assert list(cells["base_method"]) == ["rk4", "heyoka-taylor"]
    assert list(cells["modifiers"]) == ["observer", ""]
    assert list(cells["family"]) == ["rk4+observer:mode=simple,on=H/L,theta=2/2", "heyoka-taylor"]
    assert list(cells["sweep"]) == ["h", "tol"] and list(cells["adaptive"]) == [False, True]
    assert cells["sweep_value"].tolist() == [0.01, 1e-12]


CELL_KINDS = [  # problem, method, options, kind
    ("kepler-2d", "rk4:h=0.05", {"steps": 40, "every": 8}, "fixed step"),
    ("kepler-2d", "rk4:h=0.05", {"t_end": 2.0, "dt_out": 0.5}, "fixed step"),
    ("kepler-2d", "dopri5:rtol=1e-8,atol=1e-8", {"t_end": 2.0}, "adaptive"),
    ("kepler-2d", "scipy-rk45:rtol=1e-8,atol=1e-8", {"t_end": 2.0, "dt_out": 0.5}, "engine"),
    ("kepler-3d:ks=true", "rk4:h=0.01", {"steps": 50}, "transformed"),
    ("henon-heiles", "dop853:rtol=1e-10,atol=1e-10", {"t_end": 100.0, "section": 3}, "section"),
    ("henon-heiles", "scipy-dop853:rtol=1e-10,atol=1e-10,dt_out=0.05", {"t_end": 30.0,
                                                                        "section": 2}, "section"),
]


@pytest.mark.parametrize("problem, method, options, kind", CELL_KINDS)
def test_integrate_takes_the_typed_cell_as_it_is(monkeypatch, problem, method, options, kind):
    """A cell is validated once, by build(): integrate(cell) dispatches on its kind and checks
    nothing again (the horizon, the budgets, every, dt_out: each check made to fail after
    build() and the integration still runs, with the same samples)."""
    import sys

    from gnibench.suite.cell import cellspec, grid, timegrid
    from gnibench.suite.cell.cellspec import build
    from gnibench.suite.foundation import budgets

    cell = build(problem, method, **options)
    assert cell.kind == kind
    expected = integrate(cell)

    def refused(*a, **k):
        raise AssertionError("checked again after build()")

    checks = [grid.grid, budgets.check_count, budgets.check_output, budgets.check_integer,
              cellspec.check_budgets, cellspec.build, timegrid.check_dt_out,
              timegrid.effective_dt_out, timegrid.engine_method]
    for name, module in list(sys.modules.items()):     # wherever they were imported by name
        if name.startswith("gnibench."):
            for attr, value in list(vars(module).items()):
                if any(value is f for f in checks):
                    monkeypatch.setattr(module, attr, refused)
    again = integrate(cell)
    assert again.status == "ok" and np.array_equal(again.y, expected.y) and len(again.t) > 1


@pytest.mark.parametrize("problem, method, options, message", [
    ("kepler-2d", "dopri5", {"steps": 10}, "needs t_end=T"),
    ("kepler-3d:ks=true", "scipy-rk45", {"t_end": 1.0}, "cannot integrate the transformed"),
    ("kepler-2d", "rk4", {"steps": 10, "locator": "dense"}, "applies to section crossings only"),
    ("henon-heiles", "rk4:h=0.01", {"t_end": 7.0, "section": 1, "locator": "dense"},
     "dense output does not locate"),
    ("henon-heiles", "rk4:h=0.01", {"t_end": 7.0, "section": 1, "locator": "newton"},
     "bad locator 'newton'"),
    ("kepler-2d", "dopri5", {"t_end": 1.0, "reverse": True}, "reverse=True applies"),
])
def test_what_does_not_apply_is_refused_when_the_cell_is_made(problem, method, options, message):
    """Refusals that the driver facade used to make in the middle of a run are made by build(),
    before any work."""
    from gnibench.suite.cell.cellspec import build

    with pytest.raises(UserError, match=message):
        build(problem, method, **options)
