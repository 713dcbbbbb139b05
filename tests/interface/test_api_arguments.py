"""The API's edge (suite/api/arguments.py): every public function checks its arguments against
one schema before any work; a bad type is one UserError line naming the function, the argument,
the bad value and what is allowed; numpy scalars are numbers (issue 43, item 2)."""
from __future__ import annotations

import inspect

import gnibench
import numpy as np
import pytest

E = {"name": "edge", "title": "t", "reference": "r", "t_end": 0.2,
     "cells": [{"problems": ["pendulum"], "methods": ["rk4:h=0.1"]}]}
PUBLIC = ("solve", "run", "verify", "reproduce", "report", "load", "list_problems",
          "list_methods", "list_metrics")


@pytest.mark.parametrize("name", PUBLIC)
def test_every_public_function_has_a_schema(name):
    fn = getattr(gnibench, name)
    adapters = fn.schema.adapters()             # every annotation maps to a strict type
    assert list(adapters) == list(inspect.signature(fn).parameters)


BAD = {
    "solve t_end='1'": (lambda: gnibench.solve("kepler-2d", "rk4", t_end="1"), "t_end", "'1'"),
    "solve metrics=[1]": (lambda: gnibench.solve("kepler-2d", "rk4", t_end=1.0, metrics=[1]),
                          "metrics", "item 0: 1, an int"),
    "solve metrics=None": (lambda: gnibench.solve("kepler-2d", "rk4", t_end=1.0, metrics=None),
                           "metrics", "None"),
    "solve steps=10.0": (lambda: gnibench.solve("kepler-2d", "rk4", steps=10.0), "steps", "10.0"),
    "solve every=True": (lambda: gnibench.solve("kepler-2d", "rk4", steps=10, every=True),
                         "every", "True"),
    "solve problem=5": (lambda: gnibench.solve(5, "rk4", steps=10), "problem",
                        "allowed: a string, or a parsed problem"),
    "run jobs='2'": (lambda: gnibench.run(E, jobs="2"), "jobs", "'2'"),
    "run output=5": (lambda: gnibench.run(E, output=5), "output", "5"),
    "run fresh='yes'": (lambda: gnibench.run(E, fresh="yes"), "fresh", "'yes'"),
    "run scheduler=12345": (lambda: gnibench.run(E, executor="dask", scheduler=12345),
                            "scheduler", "12345"),
    "run experiment=42": (lambda: gnibench.run(42), "experiment", "42"),
    "verify ids=5": (lambda: gnibench.verify(ids=5), "ids", "5"),
    "verify ids=['B-2-b', 3]": (lambda: gnibench.verify(["B-2-b", 3]), "ids", "item 1: 3"),
    "reproduce redraw='no'": (lambda: gnibench.reproduce("hlw-fig-1.4", redraw="no"), "redraw",
                              "'no'"),
    "load 5": (lambda: gnibench.load(5), "path", "5"),
    "load ''": (lambda: gnibench.load(""), "path", "''"),
    "report accuracy=['x']": (lambda: gnibench.report(".", "site", accuracy=["x"]), "accuracy",
                              "item 0: 'x'"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_types_are_one_line_user_errors(case, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    call, name, shown = BAD[case]
    with pytest.raises(gnibench.UserError) as e:
        call()
    line = str(e.value)
    function = case.split()[0]
    assert line.startswith(f"gnibench.{function}: bad {name} ")
    assert shown in line and "; allowed: " in line and "\n" not in line
    assert list(tmp_path.iterdir()) == []                  # refused before anything is written


def test_nothing_is_run_or_written_on_a_bad_flag(tmp_path):
    with pytest.raises(gnibench.UserError, match="bad fresh 'yes'"):
        gnibench.run(E, output=tmp_path / "out", fresh="yes")
    assert not (tmp_path / "out").exists()


def test_an_empty_report_is_refused(tmp_path):
    with pytest.raises(gnibench.UserError, match="no results directory given"):
        gnibench.report([], tmp_path / "site")
    assert not (tmp_path / "site").exists()


def test_numpy_scalars_are_numbers():
    a = gnibench.solve("kepler-2d", "rk4:h=0.01", steps=np.int64(10), every=np.int64(2))
    b = gnibench.solve("kepler-2d", "rk4:h=0.01", steps=10, every=2)
    assert a.samples.equals(b.samples) and len(a.samples) == 6
    c = gnibench.solve("kepler-2d", "rk4:h=0.01", t_end=np.float32(0.05), every=np.int32(1))
    assert c.samples["t"].iloc[-1] == pytest.approx(0.05)
    d = gnibench.solve("kepler-2d", "rk4:h=0.01", t_end=np.int64(1), every=np.uint8(50))
    assert d.samples["t"].tolist() == [0.0, 0.5, 1.0]


def test_paths_are_str_or_pathlike(tmp_path):
    res = gnibench.run(E, output=str(tmp_path / "a"), jobs=np.int64(1), fresh=np.bool_(False))
    assert res.output == tmp_path / "a" and (res.cells["status"] == "ok").all()


def test_values_are_checked_below_in_the_words_of_the_caller():
    """The schema checks types only: ranges and choices are the library's (one source of what is
    allowed), and its line names the option as the caller gave it: the keyword from Python, the
    flag on the command line."""
    with pytest.raises(gnibench.UserError, match=r"^bad steps=0; allowed: an integer from 1"):
        gnibench.solve("kepler-2d", "rk4", steps=np.int64(0))
    with pytest.raises(gnibench.UserError, match=r"^bad jobs=0; allowed"):
        gnibench.run(E, jobs=0)
    with pytest.raises(gnibench.UserError, match=r"^bad executor='spark'"):
        gnibench.run(E, executor="spark")
    with pytest.raises(gnibench.UserError, match=r"^give exactly one of steps=N or t_end=T$"):
        gnibench.solve("kepler-2d", "rk4")
    with pytest.raises(gnibench.UserError, match=r"^every does not apply with section "):
        gnibench.solve("henon-heiles", "rk4", t_end=10.0, section=1, every=2)


@pytest.mark.parametrize("argv, line", [
    (["solve", "kepler-2d", "rk4", "--steps", "0"], "bad --steps 0; allowed"),
    (["solve", "kepler-2d", "rk4", "--t-end", "-1"], "bad --t-end -1; allowed"),
    (["run", "quick", "-j", "0"], "bad -j 0; allowed"),
    (["run", "quick", "--repeat", "0"], "bad --repeat 0; allowed: an integer from 1 to 1000"),
    (["run", "quick", "--executor", "dask", "--scheduler", "tcp://127.0.0.1:1"],   # in a thread
     "bad --scheduler 'tcp://127.0.0.1:1': cannot connect"),
])
def test_the_command_line_names_its_flags(argv, line, capsys):
    from gnibench.suite.cli.main import main

    assert main(argv) == 2
    err = capsys.readouterr().err
    assert line in err and err.count("\n") == 1
    with pytest.raises(gnibench.UserError, match="steps=0"):   # the API's words again after it
        gnibench.solve("kepler-2d", "rk4", steps=0)


def test_no_library_message_names_a_flag_as_it_is():
    """No UserError raised by the library writes a flag into its text (``"--steps"``, ``-j``):
    options are named through errors.named/spelled, which words them as the caller gave them (a
    flag read from Python would be wrong); the command line's own modules (suite/cli) are
    exempt."""
    import ast
    import re
    from pathlib import Path

    flag = re.compile(r"(^|[\s(])(--[a-z][a-z-]+|-j)\b")
    root = Path(gnibench.__file__).parent
    bad = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        if rel.startswith(("suite/cli/", "tests/", "benchmarks/", "docs/", "examples/", ".")):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "UserError":
                texts = [s for arg in node.args for s in _texts(arg)]
                if any(flag.search(s) and "gnibench " not in s for s in texts):
                    bad.append(f"{rel}:{node.lineno}")
    assert not bad, bad




def _texts(node) -> list[str]:
    """The string constants of an expression, but those given to errors.named/spelled."""
    import ast

    if isinstance(node, ast.Call) and getattr(node.func, "id", "") in ("named", "spelled"):
        return []
    if isinstance(node, ast.Constant):
        return [node.value] if isinstance(node.value, str) else []
    return [s for child in ast.iter_child_nodes(node) for s in _texts(child)]
