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


def test_values_are_checked_below_with_the_command_line_s_words():
    """The schema checks types only: ranges and choices are the library's, worded as the command
    line words them (one source of what is allowed)."""
    with pytest.raises(gnibench.UserError, match=r"^bad --steps 0; allowed: an integer from 1"):
        gnibench.solve("kepler-2d", "rk4", steps=np.int64(0))
    with pytest.raises(gnibench.UserError, match=r"^bad -j 0; allowed"):
        gnibench.run(E, jobs=0)
    with pytest.raises(gnibench.UserError, match=r"^bad --executor 'spark'"):
        gnibench.run(E, executor="spark")


@pytest.mark.parametrize("ids", [[], ""])
@pytest.mark.parametrize("name", ["verify", "reproduce"])
def test_an_empty_id_list_is_refused_not_taken_for_all(name, ids, tmp_path):
    """``verify(ids=[])`` ran all 166 cells of the ledger (an empty selection read as none
    given): an empty list or string is one line, before any work; "all" says every one."""
    import gnibench

    with pytest.raises(gnibench.UserError, match=rf"gnibench\.{name}: bad ids .* \(empty\)"):
        getattr(gnibench, name)(ids, output=tmp_path / "out")
    assert not (tmp_path / "out").exists()
