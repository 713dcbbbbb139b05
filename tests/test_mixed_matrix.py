"""One experiment mixing shipped compiled methods and scipy's solvers (issue 16 item 5): the same
tables, byte for byte, from one process (-j 1), a pool of two (-j 2) and a Dask cluster (through
the Python API).

(User-TOML methods and Python integrators join this matrix when the loader of user definitions
lands: issue 16 item 3.)
"""
from __future__ import annotations

import gnibench
import pytest
from gnibench.suite.cli.main import main

MIXED = """
name = "mixed"
title = "compiled and scipy methods in one matrix"
reference = "issue 16"
t_end = 6.283185307179586
every = 5

[[cells]]
problems = ["kepler-2d", "pendulum"]
methods = ["rk4:h=0.05", "stormer-verlet:h=0.05", "dopri5:rtol=1e-8,atol=1e-8"]

[[cells]]
problems = ["kepler-2d", "pendulum"]
methods = ["scipy-dop853:dt_out=0.25", "scipy-radau:dt_out=0.25", "scipy-lsoda:dt_out=0.25"]
every = 1
vary.rtol = [1e-6, 1e-9]
"""


def test_mixed_matrix_is_byte_identical_across_executors(tmp_path):
    pytest.importorskip("distributed")
    exp = tmp_path / "mixed.toml"
    exp.write_text(MIXED)
    outs = {"serial": tmp_path / "serial", "pool": tmp_path / "pool", "dask": tmp_path / "dask"}
    assert main(["run", str(exp), "-o", str(outs["serial"]), "-j", "1", "--no-report"]) == 0
    assert main(["run", str(exp), "-o", str(outs["pool"]), "-j", "2", "--no-report"]) == 0
    res = gnibench.run(exp, output=outs["dask"], executor="dask", jobs=2)
    assert len(res.cells) == 18 and (res.cells["status"] == "ok").all()
    assert set(res.cells["method"].str.split(":").str[0]) >= {"rk4", "scipy-radau"}
    for table in ("samples.parquet", "cells.parquet"):
        first = (outs["serial"] / table).read_bytes()
        for name in ("pool", "dask"):
            assert (outs[name] / table).read_bytes() == first, (name, table)
