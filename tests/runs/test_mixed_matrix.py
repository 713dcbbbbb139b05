"""One experiment mixing shipped compiled methods, user methods from a TOML file (a tableau and a
Python step and a Python solver, examples/definitions.toml), a user problem and scipy's solvers
(issue 16 item 5): the same tables, byte for byte, from one process (-j 1), a pool of two (-j 2)
and a Dask cluster (through the Python API).
"""
from __future__ import annotations

from pathlib import Path

import gnibench
import pytest
from gnibench.suite.cli.main import main

DEFINITIONS = Path(__file__).resolve().parents[2] / "examples" / "definitions.toml"
MIXED = """
name = "mixed"
title = "compiled, user and scipy methods in one matrix"
reference = "issue 16"
load = ["DEFINITIONS"]
t_end = 6.283185307179586
every = 5

[[cells]]
problems = ["kepler-2d", "pendulum"]
methods = ["rk4:h=0.05", "stormer-verlet:h=0.05", "dopri5:rtol=1e-8,atol=1e-8"]

[[cells]]
problems = ["kepler-2d", "oscillator:omega=2"]
methods = ["heun3:h=0.05", "py-rk4:h=0.05"]

[[cells]]
problems = ["kepler-2d", "pendulum"]
methods = ["scipy-dop853:dt_out=0.25", "scipy-radau:dt_out=0.25", "scipy-lsoda:dt_out=0.25",
           "py-dop853:dt_out=0.25"]
every = 1
vary.rtol = [1e-6, 1e-9]
"""


def test_mixed_matrix_is_byte_identical_across_executors(tmp_path):
    pytest.importorskip("distributed")
    exp = tmp_path / "mixed.toml"
    exp.write_text(MIXED.replace("DEFINITIONS", str(DEFINITIONS)))
    outs = {"serial": tmp_path / "serial", "pool": tmp_path / "pool", "dask": tmp_path / "dask"}
    assert main(["run", str(exp), "-o", str(outs["serial"]), "-j", "1", "--no-report"]) == 0
    assert main(["run", str(exp), "-o", str(outs["pool"]), "-j", "2", "--no-report"]) == 0
    res = gnibench.run(exp, output=outs["dask"], executor="dask", jobs=2)
    assert len(res.cells) == 26 and (res.cells["status"] == "ok").all(), res.cells["reason"]
    kinds = dict(zip(res.cells["method"].str.split(":").str[0], res.cells["method_kind"]))
    assert {k: kinds[k] for k in ("rk4", "heun3", "py-rk4", "scipy-radau", "py-dop853")} == {
        "rk4": "compiled", "heun3": "compiled", "py-rk4": "python", "scipy-radau": "external",
        "py-dop853": "python"}
    # a Python solver that reports no step count: steps missing (null), not 0
    solver = res.cells["method"].str.startswith("py-dop853:")
    assert res.cells.loc[solver, "steps"].isna().all() and solver.sum() == 4
    assert (res.cells.loc[~solver, "steps"] > 0).all()
    rows = res.samples["method"].str.startswith("py-dop853:")
    first = res.samples["t"] == 0.0
    assert str(res.samples["steps"].dtype) == "Int64"
    assert res.samples.loc[rows & ~first, "steps"].isna().all()
    assert (res.samples.loc[rows & first, "steps"] == 0).all()
    assert res.samples.loc[~rows, "steps"].notna().all()
    for table in ("samples.parquet", "cells.parquet"):
        first = (outs["serial"] / table).read_bytes()
        for name in ("pool", "dask"):
            assert (outs[name] / table).read_bytes() == first, (name, table)
