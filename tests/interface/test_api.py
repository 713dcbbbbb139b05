"""The Python API (suite/api/, README "Python API") against the command line: same columns, same
numbers, same error lines; the README's example runs; ``import gnibench`` stays cheap."""
from __future__ import annotations

import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import gnibench
import numpy as np
import pandas as pd
import pytest
from gnibench.suite.api.listing import METHOD_COLUMNS, METRIC_COLUMNS, PROBLEM_COLUMNS
from gnibench.suite.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
PERIOD = 6.283185307179586
#: meta entries that are times of this run (not reproducible)
TIMES = ("wall_seconds", "compile_seconds", "numba_cache_misses", "seconds", "cached")


def _cli_json(tmp_path, argv) -> dict:
    out = tmp_path / "cli.json"
    assert main(["solve", *argv, "--format", "json", "-o", str(out)]) == 0
    return json.loads(out.read_text())


def _without_times(meta):
    if isinstance(meta, dict):
        return {k: _without_times(v) for k, v in meta.items() if k not in TIMES}
    return meta


CASES = {
    "fixed step, exact reference": (["kepler-2d", "rk4:h=0.05", "--steps", "200", "--every", "7"],
                                    {"steps": 200, "every": 7}),
    "adaptive, metrics, period grid": (["kepler-2d", "dopri5:rtol=1e-9,atol=1e-9", "--t-end", "20",
                                        "--metrics", "eta,growth:of=H"],
                                       {"t_end": 20.0, "metrics": ["eta", "growth:of=H"]}),
    "section": (["henon-heiles", "dop853:rtol=1e-10,atol=1e-10", "--t-end", "200", "--section",
                 "4"], {"t_end": 200.0, "section": 4}),
    "scipy, dt_out": (["kepler-2d", "scipy-rk45:rtol=1e-8,atol=1e-8", "--t-end", str(PERIOD),
                       "--dt-out", "0.5"], {"t_end": PERIOD, "dt_out": 0.5}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_solve_is_the_cli(tmp_path, case):
    argv, kw = CASES[case]
    doc = _cli_json(tmp_path, argv)
    traj = gnibench.solve(argv[0], argv[1], **kw)
    assert list(traj.samples.columns) == list(doc["columns"])
    for c, values in doc["columns"].items():
        ours = traj.samples[c].to_numpy(dtype=float)
        theirs = np.array([np.nan if v is None else v for v in values], dtype=float)
        assert np.array_equal(ours, theirs, equal_nan=True), c
    assert _without_times(traj.meta) == _without_times(doc["meta"])
    csv = tmp_path / "cli.csv"
    assert main(["solve", *argv, "-o", str(csv)]) == 0
    assert list(pd.read_csv(csv).columns) == list(traj.samples.columns)


@pytest.mark.parametrize("argv, call, words", [
    (["kepler-2dd", "rk4", "--steps", "3"], lambda: gnibench.solve("kepler-2dd", "rk4", steps=3),
     None),
    (["kepler-2d", "rk4:h=-1", "--steps", "3"],
     lambda: gnibench.solve("kepler-2d", "rk4:h=-1", steps=3), None),
    (["kepler-2d", "rk4", "--steps", "0"], lambda: gnibench.solve("kepler-2d", "rk4", steps=0),
     {"--steps 0": "steps=0"}),
    (["kepler-2d", "dopri5", "--steps", "10"],
     lambda: gnibench.solve("kepler-2d", "dopri5", steps=10),
     {"--t-end T": "t_end=T", "--steps)": "steps)"}),
    (["henon-heiles", "dop853", "--t-end", "9", "--section", "2", "--every", "3"],
     lambda: gnibench.solve("henon-heiles", "dop853", t_end=9.0, section=2, every=3),
     {"--every": "every", "--section": "section"}),
    (["kepler-2d", "scipy-rk45+observer:on=H/L", "--t-end", "1"],
     lambda: gnibench.solve("kepler-2d", "scipy-rk45+observer:on=H/L", t_end=1.0), None),
    (["kepler-2d", "rk4", "--steps", "3", "--metrics", "nosuch"],
     lambda: gnibench.solve("kepler-2d", "rk4", steps=3, metrics="nosuch"), None),
])
def test_errors_are_user_errors_with_the_cli_line(capsys, argv, call, words):
    """The API raises the command line's line, with the options named as Python names them (the
    keyword for the flag: ``words``)."""
    assert main(["solve", *argv]) == 2
    line = capsys.readouterr().err.strip()
    with pytest.raises(gnibench.UserError) as e:
        call()
    for flag, keyword in (words or {}).items():
        assert flag in line, line
        line = line.replace(flag, keyword)
    assert line == f"gnibench: error: {e.value}"


def test_api_only_errors():
    """What the command line's parser refuses before (two horizons, none) the API refuses too."""
    with pytest.raises(gnibench.UserError, match="exactly one of"):
        gnibench.solve("kepler-2d", "rk4", steps=3, t_end=1.0)
    with pytest.raises(gnibench.UserError, match="exactly one of"):
        gnibench.solve("kepler-2d", "rk4")


LISTINGS = {"problems": (lambda: gnibench.list_problems(), PROBLEM_COLUMNS),
            "methods": (lambda: gnibench.list_methods(), METHOD_COLUMNS),
            "metrics": (lambda: gnibench.list_metrics(), METRIC_COLUMNS)}


@pytest.mark.parametrize("what", list(LISTINGS))
def test_listings_are_gnibench_list(capsys, what):
    fn, columns = LISTINGS[what]
    assert main(["list", what, "--format", "json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    df = fn()
    assert df["id"].tolist() == [r["id"] for r in rows]
    assert tuple(df.columns) == columns            # the documented columns, in order
    assert df["options"].str.len().ge(0).all()


def test_listing_columns_are_documented():
    """Each column of a listing is named in its function's docstring (the user's script that hit
    KeyError: 'kind' on the problems' listing followed a table that named a column it lacks)."""
    from gnibench.suite.api import listing

    for fn, columns in ((listing.list_problems, PROBLEM_COLUMNS),
                        (listing.list_methods, METHOD_COLUMNS),
                        (listing.list_metrics, METRIC_COLUMNS)):
        doc = fn.__doc__.split("Returns")[1].split("Examples")[0]
        documented = re.findall(r"``([a-z_]+)``", doc)
        assert [c for c in documented if c in columns] == [c for c in columns if c in documented]
        assert set(columns) <= set(documented), set(columns) - set(documented)


def test_listing_values():
    methods = gnibench.list_methods().set_index("id")
    assert methods.loc["scipy-dop853", "kind"] == "external"
    assert methods.loc["scipy-dop853", "engine"] == "scipy"
    assert methods.loc["rk4", "order"] == 4 and methods.loc["rk4", "kind"] == "compiled"
    assert bool(methods.loc["dopri5", "adaptive"]) and not bool(methods.loc["rk4", "adaptive"])
    assert methods.loc["observer", "kind"] == "modifier" and pd.isna(methods.loc["observer", "order"])
    assert methods.loc["projection", "acts_on"] == "step"
    assert "kind" not in gnibench.list_problems().columns         # problems have no kind
    problems = gnibench.list_problems().set_index("id")
    assert problems.loc["kepler-2d", "integrals"] == ["H", "L", "A1", "A2"]
    assert bool(problems.loc["kepler-2d", "exact_solution"])


def test_registry_subpackages_are_only_packages():
    """``gnibench.methods`` and ``gnibench.problems`` are the registries' subpackages, no longer
    callable (Python gives no hint when a module is called); ``gnibench.metrics``, which was
    a function, says where it went."""
    import gnibench.methods.external as ext
    from gnibench.methods import METHODS

    assert ext.ExternalMethod and "rk4" in METHODS
    assert type(gnibench.methods) is type(sys) and type(gnibench.problems) is type(sys)
    with pytest.raises(TypeError, match="not callable"):
        gnibench.methods()
    with pytest.raises(AttributeError, match=r"gnibench.list_metrics\(\)"):
        gnibench.metrics()                                  # noqa: B018
    assert "kepler-2d" in gnibench.list_problems()["id"].tolist()


def test_import_is_cheap():
    code = ("import sys, gnibench\n"
            "heavy = [m for m in ('numpy', 'numba', 'sympy', 'pandas', 'scipy') if m in sys.modules]\n"
            "assert not heavy, heavy\n"
            "assert callable(gnibench.solve) and 'numba' not in sys.modules\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=False, cwd=ROOT.parent)
    assert proc.returncode == 0, proc.stderr


def test_experiment_dicts_are_the_shipped_files():
    """Every shipped experiment, given as the dict its TOML reads to, expands to the same cells and
    figure (strings with quotes, line breaks and non-ASCII text, nested tables, arrays of tables)."""
    from gnibench.suite.api.running import toml_text
    from gnibench.suite.runs.experiment import load_experiment, parse_experiment, shipped

    for name, text in shipped().items():
        a = load_experiment(name, "quick")
        b = parse_experiment(toml_text(tomllib.loads(text)), "dict", "quick")
        assert [c.described() for c in a.cells] == [c.described() for c in b.cells], name
        assert (a.figure, a.description, a.title) == (b.figure, b.description, b.title), name


def test_run_and_report(tmp_path):
    spec = {"name": "api-run", "title": "t", "reference": "r", "t_end": 2.0,
            "cells": [{"problems": ["pendulum"], "methods": ["rk4", "stormer-verlet"],
                       "vary": {"h": [0.1, 0.05]}}]}
    mem = gnibench.run(spec, jobs=1)
    assert mem.output is None and len(mem.cells) == 4 and (mem.cells["status"] == "ok").all()
    res = gnibench.run(spec, output=tmp_path / "out", jobs=1)
    assert res.output == tmp_path / "out" and (res.output / "summary.md").is_file()
    pd.testing.assert_frame_equal(res.samples, mem.samples)
    pd.testing.assert_frame_equal(res.cells, mem.cells)
    assert res.meta["experiment"] == "api-run" and set(res.timings.columns) >= {"cell"}
    index = gnibench.report(res.output, tmp_path / "site")
    assert index.is_file() and "api-run" in index.read_text(encoding="utf-8")
    with pytest.raises(gnibench.UserError, match="bad accuracy"):
        gnibench.report(res.output, tmp_path / "site2", accuracy=["x"])
    with pytest.raises(gnibench.UserError, match="nosuch"):
        gnibench.run("nosuch")
    with pytest.raises(gnibench.UserError, match="allowed"):
        gnibench.run(42)


def test_run_result_repr_says_what_it_holds_and_where(tmp_path):
    """A RunResult's repr names its experiment, its numbers of cells and samples as they are, and
    where its tables are: the results directory, or "in memory" without one."""
    spec = {"name": "api-repr", "title": "t", "reference": "none", "t_end": 0.5,
            "cells": [{"problems": ["pendulum"], "methods": ["rk4:h=0.1", "rk4:h=0.05"]}]}
    mem = gnibench.run(spec, jobs=1)
    assert (len(mem.cells), len(mem.samples)) == (2, 6 + 11)
    assert repr(mem) == "RunResult('api-repr': 2 cells, 17 samples, in memory)"
    out = tmp_path / "out"
    res = gnibench.run(spec, output=out, jobs=1)
    assert repr(res) == f"RunResult('api-repr': 2 cells, 17 samples, {out})"


def test_verify_is_the_cli(tmp_path, capsys):
    ledger = gnibench.verify(["B-2-b"], scale="quick", output=tmp_path / "api")
    assert main(["verify", "B-2-b", "--format", "json", "-o", str(tmp_path / "cli"),
                 "--no-report"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert ledger["id"].tolist() == [r["id"] for r in rows]
    assert ledger["verdict"].tolist() == [r["verdict"] for r in rows]


def test_a_ledger_is_the_same_bytes_whatever_directory_holds_it(tmp_path):
    """ledger.parquet named its experiments' results by absolute path: two runs of the same
    claims into two directories differed (B-3-a needs an experiment)."""
    for d in ("a", "b"):
        gnibench.verify(["B-3-a"], scale="quick", output=tmp_path / d)
    assert (tmp_path / "a" / "ledger.parquet").read_bytes() == \
        (tmp_path / "b" / "ledger.parquet").read_bytes()


def test_docs_python_examples_run(capsys, tmp_path, monkeypatch):
    """The Python blocks of the documentation's how-to pages that are not executed notebooks
    (the notebooks run when the documentation builds), run as they are, so they stay true (in a
    directory of their own: they write files, e.g. global-error.png)."""
    monkeypatch.chdir(tmp_path)
    pages = sorted((ROOT / "docs" / "how-to").glob("*.md"))
    blocks = []
    for page in pages:
        text = page.read_text(encoding="utf-8")
        if "file_format: mystnb" not in text:
            blocks += re.findall(r"```python\n(.*?)```", text, flags=re.DOTALL)
    assert blocks
    for block in blocks:
        exec(compile(block, "docs/how-to", "exec"), {})                  # noqa: S102
    out = capsys.readouterr().out
    assert "ok" in out


def test_solve_takes_typed_values():
    from gnibench.suite.cell.spec import parse_method, parse_problem

    text = gnibench.solve("pendulum:p0=1.4", "rk4:h=0.1+projection", steps=20, every=4)
    typed = gnibench.solve(parse_problem("pendulum:p0=1.4"), parse_method("rk4:h=0.1+projection"),
                           steps=20, every=4)
    pd.testing.assert_frame_equal(text.samples, typed.samples)
    assert typed.meta["method"] == text.meta["method"] and typed.status == "ok"


def test_version_is_pyproject_s():
    doc = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert gnibench.__version__ == doc["project"]["version"]


def test_reproduce_draws_the_figure(tmp_path):
    dirs = gnibench.reproduce(["hlw-fig-1.4"], scale="quick", output=tmp_path, jobs=1)
    assert dirs == {"hlw-fig-1.4": tmp_path / "hlw-fig-1.4"}
    manifest = json.loads((dirs["hlw-fig-1.4"] / "figure" / "figure.json").read_text())
    assert manifest["id"] == "hlw-fig-1.4" and manifest["panels"]
    assert any(p.suffix == ".png" for p in (dirs["hlw-fig-1.4"] / "figure").iterdir())
    with pytest.raises(gnibench.UserError, match="nosuch"):
        gnibench.reproduce(["nosuch"], output=tmp_path)


def test_load_user_definitions():
    """gnibench.load defines a file's problems and methods; the API lists and solves them as the
    command line does with --load."""
    from gnibench.suite.cell.user.loader import unload

    defs = ROOT / "examples" / "definitions.toml"
    try:
        _load_and_solve(defs)
    finally:
        unload(defs)                       # leave the registries as other tests expect them


def _load_and_solve(defs):
    ids = gnibench.load(defs)
    assert {"oscillator", "heun3", "py-rk4"} <= set(ids)
    listed = gnibench.list_methods().set_index("id")
    assert listed.loc["py-rk4", "kind"] == "python" and listed.loc["heun3", "kind"] == "compiled"
    # an order that is not declared is missing (as `gnibench list` says), not order 0
    assert listed.loc["py-rk4", "order"] == 4 and pd.isna(listed.loc["py-dop853", "order"])
    assert "oscillator" in gnibench.list_problems()["id"].tolist()
    api = gnibench.solve("oscillator:omega=2", "py-rk4:h=0.05", steps=40, every=10)
    cli = _cli_json_load(defs, ["oscillator:omega=2", "py-rk4:h=0.05", "--steps", "40",
                                "--every", "10"])
    assert list(api.samples.columns) == list(cli["columns"])
    assert api.samples["nfev"].tolist() == cli["columns"]["nfev"]
    assert api.samples["err_H"].tolist() == cli["columns"]["err_H"]
    # a Python solver that reports no step count (py-dop853): steps missing after t = 0, not 0
    argv = ["oscillator", "py-dop853:dt_out=0.5", "--t-end", "2"]
    api = gnibench.solve("oscillator", "py-dop853:dt_out=0.5", t_end=2.0)
    assert str(api.samples["steps"].dtype) == "Int64" and api.samples["steps"].iloc[0] == 0
    assert api.samples["steps"].iloc[1:].isna().all() and len(api.samples) == 5
    assert _cli_json_load(defs, argv)["columns"]["steps"] == [0.0, None, None, None, None]
    csv = subprocess.run([sys.executable, "-m", "gnibench.suite.cli.main", "solve", *argv,
                          "--load", str(defs)], capture_output=True, text=True, check=True).stdout
    steps = csv.splitlines()[0].split(",").index("steps")
    assert [line.split(",")[steps] for line in csv.splitlines()[1:]] == ["0", "", "", "", ""]


def _cli_json_load(defs, argv) -> dict:
    proc = subprocess.run([sys.executable, "-m", "gnibench.suite.cli.main", "solve", *argv,
                           "--load", str(defs), "--format", "json"], capture_output=True,
                          text=True, check=True)
    return json.loads(proc.stdout)
