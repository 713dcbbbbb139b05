"""User code that ends the process, or looks like Ctrl-C (issue 43, "user code that ends the
process" and "data lost after a fault").

A Python step calling ``sys.exit(3)`` made ``gnibench solve`` exit 3 with nothing written, ``run
-j 1`` lose its tables, and a ``-j 2`` worker die with the cell never given a status (so every
rerun died the same way); ``SystemExit``, ``KeyboardInterrupt`` raised by the step and
``GeneratorExit`` escaped ``except Exception``. All are now an ``error`` status with the reason
(suite/foundation/usercode.py), the other cells unharmed; a real Ctrl-C or SIGTERM of ``solve``
during a Python step writes the rows so far (at least t = 0) and exits 130 / 143.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import gnibench
import pandas as pd
import pytest

GNIBENCH = [str(Path(sys.executable).with_name("gnibench"))]

STEPS = '''
import os, sys, time

def euler(f, t, y, h):
    return y + h * f(t, y)

def _late(t):
    return t > 0.25

def exits(f, t, y, h):
    if _late(t):
        sys.exit(3)
    return y + h * f(t, y)

def raises_system_exit(f, t, y, h):
    if _late(t):
        raise SystemExit("bye")
    return y + h * f(t, y)

def interrupts(f, t, y, h):
    if _late(t):
        raise KeyboardInterrupt
    return y + h * f(t, y)

def generator_exit(f, t, y, h):
    if _late(t):
        raise GeneratorExit("closed")
    return y + h * f(t, y)

def complex_state(f, t, y, h):
    return (y + h * f(t, y)) + 1e-3j

def never_returns(f, t, y, h):
    if _late(t):
        open(os.environ["MARK"], "w").close()      # the test signals once this exists
        while True:
            time.sleep(0.01)
    return y + h * f(t, y)

def solver_exits(f, y0, t_span, t_eval, rtol, atol):
    sys.exit(4)

def module_exit():
    pass
'''

KINDS = {"exits": "SystemExit: sys.exit(3)", "raises_system_exit": "SystemExit",
         "interrupts": "KeyboardInterrupt", "generator_exit": "GeneratorExit: closed",
         "complex_state": "returned complex values"}


def _defs(tmp_path: Path) -> Path:
    (tmp_path / "exit_steps.py").write_text(STEPS)
    text = "".join(f'[[method]]\nid = "py-{name.replace("_", "-")}"\nkind = "python"\n'
                   f'entry = "exit_steps:{name}"\n'
                   for name in ("euler", *KINDS, "never_returns"))
    text += ('[[method]]\nid = "py-solver-exits"\nkind = "python-solver"\n'
             'entry = "exit_steps:solver_exits"\n')
    path = tmp_path / "exit_defs.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    """The definitions loaded in this process once (their ids are taken while loaded)."""
    from gnibench.suite.cell.user import loader

    path = _defs(tmp_path_factory.mktemp("exits"))
    gnibench.load(path)
    yield path
    loader.unload(path)


def _cli(args, tmp_path, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(GNIBENCH + list(args), capture_output=True, text=True, timeout=600,
                          cwd=tmp_path, **kw)


@pytest.mark.parametrize("name", list(KINDS))
def test_a_step_that_ends_the_process_is_an_error_status(loaded, name):
    method = f"py-{name.replace('_', '-')}:h=0.1"
    traj = gnibench.solve("kepler-2d", method, t_end=1.0)
    assert traj.status == "error" and KINDS[name] in traj.reason, traj.reason
    assert traj.samples["t"].iloc[0] == 0.0
    late = name != "complex_state"          # the samples before the failing step are kept
    assert len(traj.samples) == (4 if late else 1)


def test_a_python_solver_that_exits_is_an_error_status(loaded):
    traj = gnibench.solve("kepler-2d", "py-solver-exits:dt_out=0.5", t_end=1.0)
    assert traj.status == "error" and "SystemExit: sys.exit(4)" in traj.reason
    assert len(traj.samples) == 1


def test_cli_solve_with_a_step_that_exits_writes_its_rows(tmp_path):
    defs = _defs(tmp_path)
    p = _cli(["solve", "kepler-2d", "py-exits:h=0.1", "--t-end", "1", "--load", str(defs)],
             tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stderr.splitlines() == ["gnibench: error: exit_steps:exits at step 4: SystemExit: "
                                     "sys.exit(3) (user code may not end the process)"]
    assert len(p.stdout.splitlines()) == 1 + 4


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_run_records_every_cell_and_a_rerun_completes(tmp_path, jobs):
    defs = _defs(tmp_path)
    exp = tmp_path / "exits.toml"
    methods = ", ".join(f'"py-{n.replace("_", "-")}"' for n in ("euler", *KINDS))
    exp.write_text(f'name = "exits"\ntitle = "Exits"\nreference = "none"\nload = ["{defs}"]\n'
                   f't_end = 1.0\n[[cells]]\nproblems = ["kepler-2d"]\n'
                   f'methods = [{methods}, "rk4"]\nvary.h = [0.1]\n')
    for attempt in range(2):
        p = _cli(["run", str(exp), "-o", "out", "-j", jobs, "--no-report"], tmp_path)
        assert p.returncode == 0, p.stderr
        assert "Traceback" not in p.stderr
        cells = pd.read_parquet(tmp_path / "out" / "cells.parquet")
        status = dict(zip(cells["method"].str.split(":").str[0], cells["status"]))
        assert status == {"py-euler": "ok", "rk4": "ok",
                          **{f"py-{n.replace('_', '-')}": "error" for n in KINDS}}, attempt
        for name, says in KINDS.items():
            reason = cells.loc[cells["method"].str.startswith(f"py-{name.replace('_', '-')}:"),
                               "reason"].iloc[0]
            assert says in reason


def test_a_module_that_exits_when_imported_is_one_line(tmp_path):
    (tmp_path / "exit_at_import.py").write_text("import sys\nsys.exit(5)\n")
    (tmp_path / "imp.toml").write_text('[[method]]\nid = "py-imp"\nkind = "python"\n'
                                       'entry = "exit_at_import:step"\n')
    p = _cli(["solve", "kepler-2d", "py-imp:h=0.1", "--steps", "2", "--load", "imp.toml"],
             tmp_path)
    assert p.returncode == 2 and p.stdout == ""
    assert len(p.stderr.splitlines()) == 1 and "SystemExit: sys.exit(5)" in p.stderr, p.stderr


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_solve_interrupted_in_a_python_step_writes_the_rows_so_far(tmp_path, signum, code):
    """Ctrl-C or SIGTERM while a Python step runs (one that never returns): the rows computed so
    far are written, t = 0 first, and the exit code is 128 + the signal."""
    defs = _defs(tmp_path)
    mark = tmp_path / "in-the-step"
    proc = subprocess.Popen(GNIBENCH + ["solve", "kepler-2d", "py-never-returns:h=0.1",
                                        "--t-end", "1", "--load", str(defs)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path, env={**os.environ, "MARK": str(mark)})
    try:
        while not mark.exists() and proc.poll() is None:
            time.sleep(0.05)
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(signum)
        out, err = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code, err
    rows = out.splitlines()
    assert rows[0].startswith("t,") and rows[1].startswith("0.0,") and len(rows) == 1 + 4
    assert "Traceback" not in err and len(err.splitlines()) == 1
