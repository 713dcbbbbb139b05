"""Paired sweeps (``zip``), the options a family sweeps, repeated timings and the ``[report]``
section of an experiment file (suite/runs/experiment.py, report_schema.py, cellwork.py)."""
from __future__ import annotations

import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.runs.experiment import parse_experiment

HEAD = 'name = "z"\ntitle = "t"\nreference = "r"\nt_end = 1.0\n'


def cells_of(body: str, **kw):
    return parse_experiment(HEAD + body, "z.toml", **kw).cells


def test_zip_gives_the_pairs_only():
    cells = cells_of('[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["dopri5", "dop853"]\n'
                     'vary.rtol = [1e-4, 1e-6, 1e-8]\nvary.atol = [1e-5, 1e-7, 1e-9]\n'
                     'zip = ["rtol", "atol"]\n')
    assert [c.method for c in cells] == [
        f"{m}:adaptive=true,rtol={r},atol={a}" for m in ("dopri5", "dop853")
        for r, a in (("0.0001", "1e-05"), ("1e-06", "1e-07"), ("1e-08", "1e-09"))]
    assert {c.sweep for c in cells} == {("rtol", "atol")}
    assert {c.setup_method for c in cells} == {"dopri5:adaptive=true", "dop853:adaptive=true"}


def test_zip_with_a_product_and_a_modifier():
    """A zipped axis keeps its place in the product (the first zipped key's), next to the other
    vary keys; modifier options zip too."""
    cells = cells_of('[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["rk4+observer:on=H"]\n'
                     'vary.h = [0.1, 0.05]\nvary.observer.theta = [1, 10]\n'
                     'vary.problem.e = [0.1, 0.5]\nzip = ["h", "observer.theta"]\n')
    assert len(cells) == 4
    assert [(c.problem.split("e=")[1], c.method.split(":h=")[1].split("+")[0],
             c.method.split("theta=")[1].split(",")[0]) for c in cells] == [
        ("0.1", "0.1", "1"), ("0.1", "0.05", "10"), ("0.5", "0.1", "1"), ("0.5", "0.05", "10")]
    assert {c.sweep for c in cells} == {("h",)}


def test_without_zip_a_product_whose_other_option_stays_in_the_setup():
    cells = cells_of('[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["dopri5"]\n'
                     'vary.rtol = [1e-4, 1e-6]\nvary.atol = [1e-8, 1e-10]\n')
    assert len(cells) == 4 and {c.sweep for c in cells} == {("rtol",)}
    assert sorted({c.setup_method for c in cells}) == ["dopri5:adaptive=true,atol=1e-08",
                                                        "dopri5:adaptive=true,atol=1e-10"]


@pytest.mark.parametrize("body, line", [
    ('vary.rtol = [1e-4, 1e-6]\nvary.atol = [1e-4]\nzip = ["rtol", "atol"]\n',
     "z.toml: cells[0]: zip = [rtol, atol]: lists of unequal length (vary.rtol has 2, vary.atol "
     "has 1); allowed: lists of one length (the values are taken together, pair by pair)"),
    ('vary.rtol = [1e-4, 1e-6]\nzip = ["rtol", "atol"]\n',
     "z.toml: cells[0]: zip: 'atol' is not a vary key of the group; allowed: its vary keys "
     "(rtol)"),
    ('vary.rtol = [1e-4]\nvary.problem.e = [0.1]\nzip = ["rtol", "problem.e"]\n',
     "z.toml: cells[0]: zip mixes problem and method options"),
    ('vary.rtol = [1e-4]\nzip = ["rtol"]\n', "z.toml: cells[0]: bad zip = ['rtol']; allowed: a "
     "list of at least two distinct vary keys"),
    ('vary.rtol = [1e-4]\nvary.atol = [1e-4]\nzip = ["rtol", "rtol"]\n',
     "z.toml: cells[0]: bad zip = ['rtol', 'rtol']"),
])
def test_bad_zip_is_one_line(body, line):
    with pytest.raises(UserError) as e:
        cells_of('[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["dopri5"]\n' + body)
    assert str(e.value).startswith(line) and "\n" not in str(e.value)


def test_unequal_lists_at_the_quick_scale_are_refused_too():
    body = ('[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["dopri5"]\n'
            'vary.rtol = [1e-4, 1e-6]\nvary.atol = [1e-4, 1e-6]\nzip = ["rtol", "atol"]\n'
            '[cells.scale.quick]\nvary.rtol = [1e-4]\n')
    assert len(cells_of(body)) == 2
    with pytest.raises(UserError, match="lists of unequal length"):
        cells_of(body, scale="quick")


def test_repeat_and_report_sections():
    e = parse_experiment(HEAD + 'repeat = 5\n[report]\ncells = [1]\nfamily = "rk4"\n'
                         'time_axis = "linear"\n[[cells]]\nproblems = ["pendulum"]\n'
                         'methods = ["rk4"]\nvary.h = [0.1, 0.05]\n', "z.toml")
    assert e.repeat == 5 and {c.repeat for c in e.cells} == {5}
    assert e.report == {"cells": [1], "family": "rk4", "time_axis": "linear"}
    assert parse_experiment(HEAD + 'repeat = 5\n[[cells]]\nproblems = ["pendulum"]\n'
                            'methods = ["rk4:h=0.1"]\n', "z.toml", repeat=2).repeat == 2


@pytest.mark.parametrize("body, line", [
    ('repeat = 0\n', "z.toml: bad repeat = 0; allowed: an integer from 1 to 1000"),
    ('[report]\ncells = [7]\n', "z.toml: report: bad cells = 7; allowed: cell ids from 0 to 1"),
    ('[report]\nfamily = "dop853"\n', "z.toml: report: family: unknown family 'dop853'"),
    ('[report]\ntime_axis = "loglog"\n', "z.toml: report: bad time_axis = 'loglog'; allowed: "
     "auto, linear or log"),
    ('[report]\nmeasures = ["max_error"]\n', "z.toml: report: measures: bad measure 'max_error'"),
    ('[report]\nfigures = ["movie"]\n', "z.toml: report: bad figures[0] = 'movie'"),
])
def test_bad_repeat_or_report_is_one_line(body, line):
    with pytest.raises(UserError) as e:
        parse_experiment(HEAD + body + '[[cells]]\nproblems = ["pendulum"]\nmethods = ["rk4"]\n'
                         'vary.h = [0.1, 0.05]\n', "z.toml")
    assert str(e.value).startswith(line) and "\n" not in str(e.value)


def test_repeat_on_the_command_line(tmp_path, capsys):
    path = tmp_path / "r.toml"
    path.write_text(HEAD + '[[cells]]\nproblems = ["pendulum"]\nmethods = ["rk4:h=0.1"]\n')
    assert main(["run", str(path), "-o", str(tmp_path / "o"), "-j", "1", "--no-report",
                 "--repeat", "3"]) == 0
    import pandas as pd

    t = pd.read_parquet(tmp_path / "o" / "timings.parquet")
    assert t["repeats"].tolist() == [3] and t["wall_seconds"].iloc[0] <= t[
        "wall_median_seconds"].iloc[0]
    capsys.readouterr()
    assert main(["run", str(path), "-o", str(tmp_path / "p"), "--repeat", "2000"]) == 2
    err = capsys.readouterr().err
    assert "bad --repeat 2000; allowed: an integer from 1 to 1000" in err
    assert not (tmp_path / "p").exists()
