"""The experiment runner: validation before running, statuses, outputs, reproducibility."""
from __future__ import annotations

import math

import gnibench.suite.cell.driver
import pandas as pd
import pytest
from gnibench.reports.markdown import summary_from_dir
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.runs.experiment import load_experiment, parse_experiment, shipped, with_options
from gnibench.suite.runs.storage import read_parquet_meta

OUTPUTS = ("samples.parquet", "cells.parquet", "timings.parquet", "summary.md")
STORE = (".lock", "parts")       # the resumable store (tests/runs/test_runner_store.py)

# One kernel (kepler-2d x euler) serves every cell: h is a run-time number.
TINY = """
name = "tiny"
title = "Tiny test experiment"
reference = "[HLW] (2.2)"
steps = 20
every = 5

[[cells]]
label = "euler"
problems = ["kepler-2d"]
methods = ["euler"]
vary.h = [0.05, 1e200, 0.025]
"""


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


@pytest.fixture
def failing_cell(monkeypatch):
    """Make the cell with h = 0.025 raise, as an unexpected bug would."""
    real = gnibench.suite.cell.driver.integrate

    def integrate(cell, **kw):
        method = cell.method_text
        if "h=0.025" in method:
            raise RuntimeError("boom")
        return real(cell, **kw)

    monkeypatch.setattr(gnibench.suite.cell.driver, "integrate", integrate)


@pytest.mark.parametrize("name", sorted(shipped()))
def test_shipped_experiments_validate(name):
    e = load_experiment(name)
    assert e.name == name and e.title and e.reference and e.cells
    assert [c.id for c in e.cells] == list(range(len(e.cells)))


def test_vary_overrides_spec_and_reaches_only_named_modifier():
    assert with_options("euler:h=0.1", "method", {"h": "0.2"}) == "euler:h=0.2"
    assert with_options("rk4+observer:theta=1", "observer", {"theta": "15"}) == \
        "rk4+observer:theta=15"
    assert with_options("rk4", "observer", {"theta": "15"}) == "rk4"
    assert with_options("pendulum:q0=0", "problem", {"p0": "0.7"}) == "pendulum:q0=0,p0=0.7"


def test_expansion_order_and_horizon_override():
    e = parse_experiment("""
name = "x"
title = "t"
reference = "r"
t_end = 1.0
[[cells]]
problems = ["pendulum:q0=0"]
methods = ["euler", "rk4"]
steps = 3
vary.h = [0.1, 0.2]
vary.problem.p0 = [0.7, 1.4]
""", "x.toml")
    got = [(c.problem, c.method, c.steps, c.t_end) for c in e.cells]
    assert got[:3] == [("pendulum:p0=0.7,q0=0", "euler:h=0.1", 3, None),
                       ("pendulum:p0=0.7,q0=0", "euler:h=0.2", 3, None),
                       ("pendulum:p0=0.7,q0=0", "rk4:h=0.1", 3, None)]
    assert len(got) == 8


def test_run_end_to_end(tiny, tmp_path, failing_cell, capsys):
    out = tmp_path / "out"
    assert main(["run", str(tiny), "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUTS + STORE + ("report",))
    cells = pd.read_parquet(out / "cells.parquet")
    assert list(cells["status"]) == ["ok", "nonfinite", "error"]
    assert cells["reason"][1].startswith("state overflowed")
    assert cells["reason"][2] == "RuntimeError: boom"
    assert math.isinf(cells["max_abs_err_H"][1]) and cells["max_abs_err_H"][0] < 1
    assert cells["steps"][0] == 20 and pd.isna(cells["steps"][2])
    samples = pd.read_parquet(out / "samples.parquet")
    assert sorted(set(samples["cell"])) == [0, 1]
    assert list(samples[samples["cell"] == 0]["steps"]) == [0, 5, 10, 15, 20]
    meta = read_parquet_meta(out / "samples.parquet")
    assert meta["experiment"] == "tiny" and meta["experiment_toml"] == TINY
    assert meta["complete"] and meta["cells"][2]["method"] == "euler:h=0.025"
    assert "wall_seconds" in pd.read_parquet(out / "timings.parquet")
    summary = (out / "summary.md").read_text()
    assert "Tiny test experiment" in summary and "RuntimeError: boom" in summary
    assert summary_from_dir(out) == summary          # the report is a function of the tables
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 5 and err[-1].startswith("gnibench: report: ")   # header, cells, report


def test_two_runs_are_bit_identical(tiny, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["run", str(tiny), "-o", str(a), "--no-report"]) == 0
    assert main(["run", str(tiny), "-o", str(b), "--no-report"]) == 0
    for name in ("samples.parquet", "cells.parquet"):
        assert (a / name).read_bytes() == (b / name).read_bytes()


def test_interrupt_keeps_finished_cells(tiny, tmp_path, monkeypatch):
    real = gnibench.suite.cell.driver.integrate

    def integrate(cell, **kw):
        method = cell.method_text
        if "h=1e+200" in method or "h=1e200" in method:
            raise KeyboardInterrupt
        return real(cell, **kw)

    monkeypatch.setattr(gnibench.suite.cell.driver, "integrate", integrate)
    out = tmp_path / "out"
    assert main(["run", str(tiny), "-o", str(out), "-j", "1"]) == 130
    cells = pd.read_parquet(out / "cells.parquet")
    assert list(cells["status"]) == ["ok", "pending", "pending"]
    assert not read_parquet_meta(out / "cells.parquet")["complete"]
    assert "INCOMPLETE: 1 of 3" in (out / "summary.md").read_text()


BAD = {
    "unknown key": ("methods = [\"euler\"]\nmetods = [\"rk4\"]", "unknown key 'metods'"),
    "bad spec": ("methods = [\"eulr:h=0.1\"]", "unknown method 'eulr'"),
    "bad h": ("methods = [\"euler\"]\nvary.h = [0.1, -0.1]", "h='-0.1'"),
    "bad steps": ("methods = [\"euler\"]\nsteps = 0", "bad steps = 0"),
    "bad every": ("methods = [\"euler\"]\nevery = 1.5", "bad every = 1.5"),
    "no modifier": ("methods = [\"euler\"]\nvary.observer.theta = [1]", "modifier 'observer'"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_experiment_exits_2_and_writes_nothing(case, tmp_path, capsys):
    body, message = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text(f'name = "bad"\ntitle = "t"\nreference = "r"\nt_end = 1.0\n'
                    f'[[cells]]\nproblems = ["pendulum"]\n{body}\n')
    out = tmp_path / "out"
    assert main(["run", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err
    assert not out.exists()


def test_unknown_experiment_name_suggests(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "quik"]) == 2
    assert "did you mean 'quick'" in capsys.readouterr().err
    assert not (tmp_path / "results").exists()


def test_section_cells_write_crossings_and_scale_shortens_them(tmp_path):
    """`section = N` in an experiment: the crossings of the problem's Poincaré section (q1 = 0,
    p1 > 0 for Hénon–Heiles), each with q1 = 0 to round-off and p1 > 0; `[scale.quick]` shortens
    N; the section is part of the cell (two cells differing only in it are distinct)."""
    import pandas as pd
    from gnibench.suite.runs.experiment import parse_experiment
    from gnibench.suite.runs.runner import run_experiment

    text = ('name = "sec"\ntitle = "t"\nreference = "r"\nt_end = 2000.0\nsection = 30\n'
            '[scale.quick]\nsection = 12\n'
            '[[cells]]\nproblems = ["henon-heiles"]\nmethods = ["dop853:rtol=1e-11,atol=1e-11"]\n'
            '[[cells]]\nproblems = ["henon-heiles"]\nmethods = ["dop853:rtol=1e-11,atol=1e-11"]\n'
            'section = 5\n')
    path = tmp_path / "sec.toml"
    path.write_text(text)
    assert [c.section for c in parse_experiment(text, "sec").cells] == [30, 5]
    out = run_experiment(path, tmp_path / "out", jobs=1, log=open("/dev/null", "w"),  # noqa: SIM115
                         scale="quick")
    samples = pd.read_parquet(out / "samples.parquet")
    assert samples.groupby("cell").size().tolist() == [12, 5]
    assert (samples["q1"].abs() < 1e-12).all() and (samples["p1"] > 0).all()
    assert samples["crossing"].tolist() == list(range(1, 13)) + list(range(1, 6))
    with pytest.raises(UserError, match="section and dt_out"):
        parse_experiment(text.replace("section = 5\n", "section = 5\ndt_out = 1.0\n"), "sec")
    with pytest.raises(UserError, match="no Poincaré section"):
        parse_experiment(text.replace('"henon-heiles"', '"pendulum"'), "sec")


def test_kernels_to_compile_come_first_the_costliest_first(monkeypatch):
    """runner._groups: the groups whose kernel is not compiled yet (cost > 0: the length of its
    text) first, the costliest first; the compiled ones after, in cell order; cells in order."""
    from gnibench.suite.runs import runner

    plans = {"a": ("k1", 0), "b": ("k2", 100), "c": ("k1", 0), "d": ("k3", 500), "e": ("k4", 0),
             "f": ("k2", 100)}
    monkeypatch.setattr(runner, "kernel_plan", lambda cell: plans[cell])
    assert runner._groups(list("abcdef")) == [["d"], ["b", "f"], ["a", "c"], ["e"]]


def test_tables_of_many_experiments_are_rewritten_within_one_shared_budget():
    """An experiment's tables wait FLUSH_RATIO times what the last writes of all the run's
    experiments took (at least FLUSH_SECONDS): 41 experiments each cheap to write do not keep the
    main process rewriting tables while the workers compute."""
    import time

    from gnibench.suite.runs.runner import FLUSH_RATIO, FLUSH_SECONDS, Consolidator

    costs: dict = {}
    writers = [Consolidator.__new__(Consolidator) for _ in range(41)]
    for w in writers:
        w.costs, w.last_write = costs, time.perf_counter() - 1.5 * FLUSH_SECONDS
    assert writers[0].due()                            # nothing written yet: FLUSH_SECONDS alone
    costs[id(writers[0])] = 0.4 * FLUSH_SECONDS / FLUSH_RATIO
    assert writers[0].due() and writers[1].due()       # its own cost alone would not hold it
    for w in writers[1:]:                               # all 41 together: 16 FLUSH_SECONDS
        costs[id(w)] = costs[id(writers[0])]
    assert not writers[0].due() and not writers[1].due()


# kepler-2d's period is 2 pi ([HLW] (2.11): a = 1); pendulum has none and no Runge-Lenz vector
NOTES = """
name = "notes"
title = "Metrics that do not apply"
reference = "none"
t_end = 12.566370614359172
every = 100
metrics = ["eta", "precession"]

[[cells]]
problems = ["kepler-2d", "pendulum"]
methods = ["stormer-verlet:h=0.06283185307179587"]
"""


def test_metric_notes_name_each_chosen_metric_that_did_not_apply(tmp_path):
    """cells.parquet's ``metric_notes`` (suite/runs/experiment.py): for each chosen metric that
    does not apply to a cell, "metric: why", in the order chosen, joined by "; "; empty where
    every chosen metric applied (and was computed)."""
    path = tmp_path / "notes.toml"
    path.write_text(NOTES)
    out = tmp_path / "out"
    assert main(["run", str(path), "-o", str(out), "--no-report"]) == 0
    cells = pd.read_parquet(out / "cells.parquet").set_index("problem")
    assert cells.loc["kepler-2d:e=0.6", "metric_notes"] == ""
    assert cells.loc["kepler-2d:e=0.6", "eta_periods"] == 2
    assert cells.loc["pendulum", "metric_notes"] == (
        "eta: pendulum has no period; precession: pendulum has no Runge-Lenz (A1, A2) or Laplace "
        "(e1..e3 with c1..c3) vector among its integrals")
    assert pd.isna(cells.loc["pendulum", "eta_periods"])
