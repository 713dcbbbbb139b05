"""The ``gnibench`` command line: bad input is one line and exit 2; good input writes the tables.

Bad input of every class must give exactly one line on stderr starting ``gnibench: error:``, exit
code 2, no traceback, and no output file. The happy-path tables are checked against independent
recomputation: the states against the exact rotation of the harmonic oscillator ([B] end of §3),
err_H against H = (p² + q²)/2 evaluated from the written states.
"""
from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from gnibench import problems
from gnibench.methods import METHODS, MODIFIERS
from gnibench.problems import REGISTRY
from gnibench.suite.cli.main import main
from gnibench.suite.runs.storage import read_parquet_meta
from support import cap

GNIBENCH = Path(sys.executable).with_name("gnibench")
OSC = "harmonic-oscillator"


def run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def assert_user_error(code, err, out_path=None, out=""):
    lines = err.splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith("gnibench: error:"), err
    assert "Traceback" not in err
    assert out == ""
    if out_path is not None:
        assert not Path(out_path).exists()
        assert not list(Path(out_path).parent.iterdir()), "stray (temporary) file left behind"


BAD = {
    "unknown-problem": (["solve", "keplr-2d", "rk4", "--steps", "3"], "did you mean 'kepler-2d'"),
    "unknown-method": (["solve", OSC, "rk5:h=0.1", "--steps", "3"], "unknown method 'rk5'"),
    "modifier-as-method": (["solve", OSC, "observer", "--steps", "3"], "modifier"),
    "unknown-modifier": (["solve", OSC, "rk4:h=0.1+obsrver", "--steps", "3"], "unknown modifier 'obsrver'"),
    "unknown-option": (["solve", OSC, "rk4:step=0.1", "--steps", "3"], "unknown option 'step'"),
    "unknown-problem-option": (["solve", "kepler-2d:ecc=0.1", "rk4", "--steps", "3"], "unknown option"),
    "bad-value": (["solve", OSC, "rk4:h=abc", "--steps", "3"], "bad value h='abc'"),
    "bad-int": (["solve", OSC, "implicit-euler:newton_maxit=2.5", "--steps", "3"], "newton_maxit"),
    "nan-value": (["solve", OSC, "rk4:h=nan", "--steps", "3"], "bad value"),
    "out-of-range": (["solve", "kepler-2d:e=1.5", "rk4", "--steps", "3"], "e='1.5'"),
    "h-zero": (["solve", OSC, "rk4:h=0", "--steps", "3"], "h="),
    "h-negative": (["solve", OSC, "rk4:h=-0.1", "--steps", "3"], "h="),
    "missing-integral": (["solve", "pendulum", "rk4+observer:on=H3", "--steps", "3"], "H3"),
    "theta-count": (["solve", "double-oscillator", "rk4+observer:theta=1/2/3", "--steps", "3"], "theta"),
    "bad-spec-syntax": (["solve", OSC, "rk4:h", "--steps", "3"], "key=value"),
    "option-twice": (["solve", OSC, "rk4:h=0.1,h=0.2", "--steps", "3"], "twice"),
    "unbound-orbit": (["solve", "kepler-2d:p10=0,p20=2,q10=1,q20=0", "rk4", "--steps", "3"], "H ="),
    "no-steps-or-t-end": (["solve", OSC, "rk4"], "steps"),
    "steps-zero": (["solve", OSC, "rk4", "--steps", "0"], "--steps"),
    "steps-not-int": (["solve", OSC, "rk4", "--steps", "ten"], "steps"),
    "t-end-negative": (["solve", OSC, "rk4", "--t-end", "-1"], "--t-end"),
    "every-zero": (["solve", OSC, "rk4", "--steps", "3", "--every", "0"], "--every"),
    "bad-format": (["solve", OSC, "rk4", "--steps", "3", "--format", "xlsx"], "format"),
    "unknown-command": (["solv", OSC, "rk4"], "solv"),
    "list-what": (["list", "integrators"], "integrators"),
}


@pytest.mark.parametrize("argv,needle", list(BAD.values()), ids=list(BAD))
def test_bad_input_is_one_line_exit_2_and_writes_nothing(argv, needle, capsys, tmp_path):
    out_path = tmp_path / "out.csv"
    extra = ["-o", str(out_path)] if argv[0] == "solve" else []
    code, out, err = run(argv + extra, capsys)
    assert_user_error(code, err, out_path if extra else None, out)
    assert needle in err


def test_parquet_needs_an_output_file(capsys):
    code, out, err = run(["solve", OSC, "rk4", "--steps", "3", "--format", "parquet"], capsys)
    assert_user_error(code, err, out=out)
    assert "-o" in err


def test_output_directory_must_exist(capsys, tmp_path):
    target = tmp_path / "missing" / "out.csv"
    code, out, err = run(["solve", OSC, "rk4", "--steps", "3", "-o", str(target)], capsys)
    assert_user_error(code, err, out=out)
    assert not target.parent.exists()


def test_method_needing_a_partition_is_refused(capsys, tmp_path, monkeypatch):
    """[HLW] (1.9) needs blocks (u, v): a problem without partition must be refused, not crash."""
    bare = dataclasses.replace(REGISTRY["lotka-volterra"], id="lotka-volterra-bare",
                               partition=None, canonical=None)
    assert bare.partition is None
    assert [p.name for p in bare.params] == [p.name for p in REGISTRY["lotka-volterra"].params]
    monkeypatch.setitem(problems.REGISTRY, bare.id, bare)
    for mid in [m for m, rec in METHODS.items() if "partition" in rec.needs]:
        out_path = tmp_path / f"{mid}.csv"
        code, out, err = run(["solve", bare.id, f"{mid}:h=0.1", "--steps", "3", "-o", str(out_path)],
                             capsys)
        assert_user_error(code, err, out_path, out)
        assert "partition" in err
    # the same problem is fine for a method that needs no structure
    code, out, err = run(["solve", bare.id, "rk4:h=0.1", "--steps", "3"], capsys)
    assert code == 0 and err == ""


def _osc_check(df, h, n, every):
    """Independent checks of an oscillator table: exact rotation, H from the states, counters."""
    t = df["t"].to_numpy()
    expect_t = np.r_[np.arange(0, n + 1, every), [n] if n % every else []] * h
    assert np.allclose(t, expect_t, rtol=0, atol=1e-12)
    q, p = df["q"].to_numpy(), df["p"].to_numpy()
    assert np.allclose(q, np.cos(t), atol=1e-8) and np.allclose(p, -np.sin(t), atol=1e-8)
    assert np.allclose(df["err_H"], (p * p + q * q) / 2 - 0.5, rtol=0, atol=1e-15)
    ge = np.hypot(q - np.cos(t), p + np.sin(t))
    assert np.allclose(df["global_error"], ge, rtol=1e-6, atol=1e-15)
    assert (df["steps"].to_numpy() == np.round(t / h)).all()
    assert (df["nfev"].to_numpy() == 4 * df["steps"].to_numpy()).all()     # rk4: 4 stages


def test_csv_columns_and_values(capsys, tmp_path):
    out_path = tmp_path / "osc.csv"
    code, out, err = run(["solve", OSC, "rk4:h=0.01", "--steps", "250", "--every", "20",
                          "-o", str(out_path)], capsys)
    assert code == 0 and err == "" and out == ""
    df = pd.read_csv(out_path)
    assert list(df.columns) == ["t", "q", "p", "err_H", "global_error", "steps", "nfev",
                               "reference_error"]
    _osc_check(df, 0.01, 250, 20)


def test_csv_to_stdout_without_exact_solution(capsys):
    """No exact solution (lotka-volterra, [HLW] (1.1)): no global_error column."""
    code, out, err = run(["solve", "lotka-volterra", "rk4:h=0.05", "--steps", "10"], capsys)
    assert code == 0 and err == ""
    cols = out.splitlines()[0].split(",")
    assert cols == ["t", "u", "v", "err_I", "steps", "nfev"]
    assert len(out.splitlines()) == 12


@pytest.mark.parametrize("pid", cap(list(REGISTRY), 4, REGISTRY))
def test_csv_columns_every_problem(pid, capsys):
    """Columns: t, the states, err_<every integral>, global_error iff an exact solution, steps, nfev.

    The four smallest problems by default (one compile each); all with GNIBENCH_TEST_FULL=1.
    """
    from gnibench.problems.codegen import problem_meta

    rec = REGISTRY[pid]
    code, out, err = run(["solve", pid, "euler:h=1e-6", "--steps", "2"], capsys)
    assert code == 0, err
    cols = out.splitlines()[0].split(",")
    want = (["t", *rec.state] + [f"err_{n}" for n in problem_meta(rec)["integrals"]]
            + (["global_error"] if rec.exact is not None else []) + ["steps", "nfev"]
            + (["reference_error"] if rec.exact is not None else []))
    assert cols == want


def test_json_meta(capsys, tmp_path):
    out_path = tmp_path / "osc.json"
    code, out, err = run(["solve", OSC, "rk4:h=1e-2+observer:theta=1e+1", "--steps", "250", "--every", "20",
                          "--format", "json", "-o", str(out_path)], capsys)
    assert code == 0 and err == "" and out == ""
    doc = json.loads(out_path.read_text())
    meta = doc["meta"]
    assert meta["problem"] == "harmonic-oscillator"
    assert meta["method"] == "rk4:h=0.01+observer:mode=simple,on=H,theta=10"
    assert meta["status"] == "ok"
    for key in ("wall_seconds", "compile_seconds"):
        assert isinstance(meta[key], float) and meta[key] >= 0
    assert {"gnibench", "python", "numpy", "numba"} <= set(meta["versions"])
    df = pd.DataFrame(doc["columns"])
    assert list(df.columns) == ["t", "q", "p", "err_H", "global_error", "steps", "nfev",
                               "reference_error"]
    # the observer does not change the exact solution on the level set ([B] (2.5) reduces to (2.1))
    _osc_check(df, 0.01, 250, 20)


def test_parquet_round_trip_and_metadata(capsys, tmp_path):
    pq_path, csv_path = tmp_path / "osc.parquet", tmp_path / "osc.csv"
    args = ["solve", OSC, "rk4:h=0.01", "--steps", "250", "--every", "20"]
    assert run(args + ["--format", "parquet", "-o", str(pq_path)], capsys)[0] == 0
    assert run(args + ["-o", str(csv_path)], capsys)[0] == 0
    df = pd.read_parquet(pq_path)
    pd.testing.assert_frame_equal(df, pd.read_csv(csv_path), check_dtype=False, rtol=0, atol=0)
    meta = read_parquet_meta(pq_path)
    assert meta["problem"] == "harmonic-oscillator" and meta["method"] == "rk4:h=0.01"
    assert meta["status"] == "ok" and "versions" in meta and "compile_seconds" in meta


@pytest.mark.parametrize("what,ids", [("problems", list(REGISTRY)),
                                      ("methods", list(METHODS) + list(MODIFIERS))])
def test_list_json_has_every_registry_id(what, ids, capsys):
    code, out, err = run(["list", what, "--format", "json"], capsys)
    assert code == 0 and err == ""
    rows = json.loads(out)
    assert [r["id"] for r in rows] == ids
    code, out, _ = run(["list", what], capsys)
    assert code == 0 and all(i in out for i in ids)


# ---- true end-to-end: the installed console script in a subprocess ---------------------------

def _cli(*args, cwd):
    env = dict(os.environ)
    return subprocess.run([str(GNIBENCH), *args], capture_output=True, text=True, cwd=cwd, env=env,
                          timeout=300, check=False)


def test_console_script_bad_input(tmp_path):
    out_path = tmp_path / "x.csv"
    p = _cli("solve", "keplr-2d", "rk4", "--steps", "3", "-o", str(out_path), cwd=tmp_path)
    assert p.returncode == 2
    assert len(p.stderr.splitlines()) == 1 and p.stderr.startswith("gnibench: error:")
    assert "kepler-2d" in p.stderr and "Traceback" not in p.stderr and p.stdout == ""
    assert not out_path.exists()
    p = _cli("solve", OSC, "rk4", cwd=tmp_path)                  # argparse-level error
    assert p.returncode == 2 and len(p.stderr.splitlines()) == 1
    assert p.stderr.startswith("gnibench: error:")


def test_console_script_solve_to_stdout(tmp_path):
    p = _cli("solve", OSC, "rk4:h=0.01", "--steps", "250", "--every", "20", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stderr == ""
    from io import StringIO

    _osc_check(pd.read_csv(StringIO(p.stdout)), 0.01, 250, 20)
