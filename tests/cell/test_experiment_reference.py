"""The experiment key ``reference_solution``: what global_error is measured against, per
experiment or per group, validated against each cell's problem, part of the store's cell key."""
from __future__ import annotations

import math

import pandas as pd
import pytest
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.runs.experiment import parse_experiment
from gnibench.suite.runs.runner import run_experiment
from gnibench.suite.runs.store import cell_key

HEAD = 'name = "r"\ntitle = "t"\nreference = "[HLW] I.3"\nsteps = 20\nevery = 5\n'


def test_top_level_and_group_keys_give_canonical_texts():
    e = parse_experiment(HEAD + """
reference_solution = "heyoka:precision=long double"
[[cells]]
problems = ["henon-heiles"]
methods = ["rk4:h=0.1"]
[[cells]]
problems = ["kepler-2d"]
methods = ["rk4:h=0.1"]
reference_solution = "exact"
[[cells]]
problems = ["kepler-2d"]
methods = ["rk4:h=0.05"]
""", "r.toml")
    refs = [c.reference for c in e.cells]
    assert refs[0].startswith("heyoka:precision=long double,tol=")
    assert refs[1] == "exact"
    assert refs[2].startswith("heyoka:precision=long double")     # the top-level default
    # without the key a cell keeps the problem's default (None: exact where there is one)
    plain = parse_experiment(HEAD + '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["rk4:h=0.1"]\n',
                             "p.toml")
    assert plain.cells[0].reference is None


@pytest.mark.parametrize("value, problem, message", [
    ('"exact"', "henon-heiles", "has no exact solution"),
    ('"rebound"', "pendulum", "rebound"),
    ('"heyoka:precision=quad"', "pendulum", "precision"),
    ('"taylor"', "pendulum", "unknown reference 'taylor'"),
    ('3', "pendulum", "bad reference_solution = 3"),
    ('""', "pendulum", "bad reference_solution"),
])
def test_bad_reference_is_refused_before_running(value, problem, message):
    with pytest.raises(UserError, match=message):
        parse_experiment(HEAD + f'[[cells]]\nproblems = ["{problem}"]\nmethods = ["rk4:h=0.1"]\n'
                         f"reference_solution = {value}\n", "bad.toml")


def test_reference_is_part_of_the_cell_key():
    text = HEAD + '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["rk4:h=0.1"]\n'
    keys = {cell_key(parse_experiment(text + extra, "k.toml").cells[0])
            for extra in ("", 'reference_solution = "exact"\n',
                          'reference_solution = "heyoka:precision=long double"\n')}
    assert len(keys) == 3


def test_run_measures_against_the_chosen_reference(tmp_path):
    path = tmp_path / "hh.toml"
    path.write_text(HEAD + """
[[cells]]
problems = ["henon-heiles"]
methods = ["rk4:h=0.1", "rk4:h=0.05"]
reference_solution = "heyoka"
[[cells]]
problems = ["henon-heiles"]
methods = ["euler:h=0.1"]
""")
    out = run_experiment(path, tmp_path / "out", jobs=1)
    cells = pd.read_parquet(out / "cells.parquet")
    assert list(cells["status"]) == ["ok"] * 3
    assert cells["reference"][0].startswith("heyoka:precision=double")
    assert math.isfinite(cells["final_global_error"][0])
    assert cells["final_global_error"][1] < cells["final_global_error"][0]   # order 4 in h
    assert cells["reference"][2] == "" and math.isnan(cells["final_global_error"][2])
    samples = pd.read_parquet(out / "samples.parquet")
    assert samples.loc[samples["cell"] == 0, "global_error"].notna().all()
