"""User definitions end to end: an experiment mixing shipped, TOML and Python methods through
``gnibench run`` (measured orders of user tableaus against their declared orders, byte-identical
tables under -j 1, -j 2 and Dask), and a third-party package registered by entry points."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from gnibench.suite.cell.user import loader
from gnibench.suite.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

EXPERIMENT = """
name = "user-mix"
title = "user definitions beside shipped methods"
reference = "issue 16"
load = ["definitions.toml"]
t_end = 6.283185307179586
every = 25
metrics = ["order"]

[[cells]]
problems = ["oscillator:omega=1"]
methods = ["heun3", "radau2a", "lobatto-3a3b", "triple-jump", "py-rk4", "rk4"]
vary.h = [0.04, 0.02, 0.01]

[[cells]]
problems = ["kepler-2d", "oscillator"]
methods = ["py-dop853:dt_out=0.5", "bs23:rtol=1e-8,atol=1e-8"]
"""


@pytest.fixture(autouse=True)
def _clean_registries():
    yield
    loader.unload()


@pytest.fixture(scope="module")
def experiment(tmp_path_factory):
    d = tmp_path_factory.mktemp("user")
    for name in ("definitions.toml", "my_integrators.py"):
        shutil.copy(EXAMPLES / name, d / name)
    (d / "mix.toml").write_text(EXPERIMENT)
    return d


def _run(experiment, out, *args) -> pd.DataFrame:
    assert main(["run", str(experiment / "mix.toml"), "-o", str(out), "--no-report", *args]) == 0
    return pd.read_parquet(out / "cells.parquet")


def test_measured_orders_of_user_tableaus_match_their_declared_orders(experiment):
    cells = _run(experiment, experiment / "j1", "-j", "1").set_index("cell")
    assert (cells["status"] == "ok").all(), cells["reason"].tolist()
    declared = {"heun3": 3, "radau2a": 3, "lobatto-3a3b": 4, "triple-jump": 4, "py-rk4": 4,
                "rk4": 4}
    for k, (method, p) in enumerate(declared.items()):
        family = cells.iloc[3 * k:3 * k + 3]
        assert family["method"].str.startswith(method + ":").all()
        assert (family["order_points_global"] == 3).all()
        assert abs(family["order_global"].iloc[0] - p) <= 0.15, (method, family["order_global"])
    assert set(cells["method_kind"]) == {"compiled", "python"}
    assert set(cells.loc[cells["method"].str.startswith("py-"), "method_kind"]) == {"python"}
    # the Python step is the compiled rk4 up to round-off: the same grid, the same counts
    py, rk4 = cells.iloc[12:15], cells.iloc[15:18]
    assert list(py["nfev"]) == list(rk4["nfev"]) and list(py["steps"]) == list(rk4["steps"])
    ratio = py["max_global_error"].to_numpy() / rk4["max_global_error"].to_numpy()
    assert (abs(ratio - 1) < 1e-5).all()
    solver = cells[cells["method"].str.startswith("py-dop853")]          # rtol = atol = 1e-9
    assert (solver["nfev"] > 0).all() and (solver["max_global_error"] < 1e-6).all()


@pytest.mark.parametrize("args", [("-j", "2"), ("--executor", "dask", "-j", "2")])
def test_tables_are_byte_identical_across_executors(experiment, args):
    """-j 2 (fork) and Dask (spawned workers: the definitions travel with the records)."""
    if not (experiment / "j1" / "cells.parquet").exists():
        _run(experiment, experiment / "j1", "-j", "1")
    out = experiment / "-".join(a.strip("-") for a in args)
    _run(experiment, out, *args)
    for name in ("samples.parquet", "cells.parquet"):
        assert (out / name).read_bytes() == (experiment / "j1" / name).read_bytes(), name


def _offline_build() -> bool:
    """Whether this interpreter can build the example package itself (setuptools >= 61 with a
    bdist_wheel: the package wheel, or setuptools >= 70.1), so pip needs no index."""
    try:
        import setuptools
    except ImportError:
        return False
    major, minor = (int(x) for x in setuptools.__version__.split(".")[:2])
    if (major, minor) >= (70, 1):
        return True
    try:
        import wheel  # noqa: F401
    except ImportError:
        return False
    return major >= 61


def pip_install_example(tmp_path: Path) -> Path:
    """Install the example package as a user would (pip), into a target directory; returns it.
    The package is copied first (a build writes build/ and *.egg-info next to its sources, which
    must not land in the repository). With setuptools and wheel in this environment (the test
    extra) the build runs here, without an index (--no-build-isolation --no-index: fast, offline);
    otherwise pip builds it in isolation, fetching setuptools from the index."""
    source, target = tmp_path / "package", tmp_path / "site"
    shutil.copytree(EXAMPLES / "gnibench-example-integrator", source,
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    fast = ["--no-build-isolation", "--no-index"] if _offline_build() else []
    pip = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                          "--disable-pip-version-check", *fast, "--target", str(target),
                          str(source)], capture_output=True, text=True, check=False)
    assert pip.returncode == 0, pip.stderr
    return target


def test_the_example_package_registers_by_entry_points(tmp_path):
    """pip install --target + PYTHONPATH: its entry points are found by importlib.metadata."""
    target = pip_install_example(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(target)}
    env.pop("GNIBENCH_LOAD", None)
    gnibench = [sys.executable, "-m", "gnibench.suite.cli.main"]
    listed = subprocess.run(gnibench + ["list", "methods"], capture_output=True, text=True,
                            env=env, check=True).stdout
    assert "ssprk3  order 3  python" in listed and "ralston2  order 2  explicit-rk" in listed
    (tmp_path / "plugin.toml").write_text(
        'name = "plugin"\ntitle = "t"\nreference = "r"\nsteps = 200\nevery = 50\n'
        '[[cells]]\nproblems = ["morse", "pendulum"]\nmethods = ["ssprk3:h=0.01", '
        '"ralston2:h=0.01", "rk4:h=0.01"]\n')
    run = subprocess.run(gnibench + ["run", str(tmp_path / "plugin.toml"), "-o",
                                     str(tmp_path / "out"), "-j", "2", "--no-report"],
                         capture_output=True, text=True, env=env, check=False, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    cells = pd.read_parquet(tmp_path / "out" / "cells.parquet")
    assert (cells["status"] == "ok").all() and len(cells) == 6
    assert list(cells["method_kind"]) == ["python", "compiled", "compiled"] * 2
    morse = cells[cells["problem"].str.startswith("morse")]
    assert (morse["max_abs_err_H"] < 1e-5).all()                     # h = 0.01, orders 2-4
