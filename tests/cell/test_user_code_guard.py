"""The user's code under one guard (suite/foundation/guard.py): whatever a Python step or solver
raises or calls — ``sys.exit``, ``SystemExit``, ``KeyboardInterrupt`` raised by the code itself,
``GeneratorExit``, complex values — ends its cell with status ``error`` and the reason; the other
cells are unharmed, in ``gnibench solve``, ``run -j 1`` and ``run -j 2``, and a rerun completes.
A real Ctrl-C or SIGTERM still stops the command, keeping the rows computed so far."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

GNIBENCH = [sys.executable, "-m", "gnibench.suite.cli.entry"]

MODULE = '''
import sys
import time

def exits(f, t, y, h):
    sys.exit(3)

def raises_systemexit(f, t, y, h):
    raise SystemExit("bye")

def raises_keyboardinterrupt(f, t, y, h):
    raise KeyboardInterrupt

def raises_generatorexit(f, t, y, h):
    raise GeneratorExit

def complex_values(f, t, y, h):
    return y + 1j * h

def slow_euler(f, t, y, h):
    y = y + h * f(t, y)         # f loaded (or compiled) before the test signals: a signal that
    open("started", "a").close()    # comes while numba loads waits for it, at most GRACE
    time.sleep(0.02)
    return y

def solver_exits(f, y0, t_span, t_eval, rtol, atol):
    sys.exit(4)
'''

BAD = ["exits", "raises_systemexit", "raises_keyboardinterrupt", "raises_generatorexit",
       "complex_values"]


def _definitions(tmp_path: Path) -> Path:
    (tmp_path / "guarded_steps.py").write_text(MODULE)
    tables = [f'[[method]]\nid = "py-{name}"\nkind = "python"\nentry = "guarded_steps:{name}"\n'
              f'order = 1\n' for name in [*BAD, "slow_euler"]]
    tables.append('[[method]]\nid = "py-solver-exits"\nkind = "python-solver"\n'
                  'entry = "guarded_steps:solver_exits"\nrtol = 1e-6\natol = 1e-6\n')
    path = tmp_path / "defs.toml"
    path.write_text("\n".join(tables))
    return path


def _gnibench(args, cwd, **kw):
    env = {**os.environ, "PYTHONPATH": ""}
    return subprocess.run(GNIBENCH + list(args), capture_output=True, text=True, cwd=cwd,
                          env=env, check=False, timeout=600, **kw)


@pytest.mark.parametrize("name", BAD + ["solver-exits"])
def test_solve_with_bad_user_code_ends_in_error_with_the_initial_row(tmp_path, name):
    defs = _definitions(tmp_path)
    spec = ["py-solver-exits", "--t-end", "0.05"] if name == "solver-exits" else \
        [f"py-{name}:h=0.01", "--steps", "5"]
    done = _gnibench(["solve", "kepler-2d", *spec, "--load", str(defs)], tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("t,") and len(lines) >= 2           # the t = 0 row at least
    assert done.stderr.startswith("gnibench: error: ") or "gnibench: error:" in done.stderr
    assert "Traceback" not in done.stderr
    words = {"exits": "SystemExit(3)", "raises_systemexit": "SystemExit('bye')",
             "raises_keyboardinterrupt": "KeyboardInterrupt raised by the code itself",
             "raises_generatorexit": "GeneratorExit", "complex_values": "complex values",
             "solver-exits": "SystemExit(4)"}
    assert words[name] in done.stderr


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_run_keeps_the_other_cells_and_a_rerun_completes(tmp_path, jobs):
    defs = _definitions(tmp_path)
    methods = ", ".join(f'"py-{name}:h=0.01"' for name in BAD) + ', "rk4:h=0.01"'
    exp = tmp_path / "exp.toml"
    exp.write_text(f'name = "guarded"\ntitle = "t"\nreference = "r"\nsteps = 5\n'
                   f'load = ["{defs.name}"]\n\n[[cells]]\nproblems = ["kepler-2d"]\n'
                   f'methods = [{methods}]\n')
    out = tmp_path / "out"
    first = _gnibench(["run", str(exp), "-o", str(out), "-j", jobs, "--no-report"], tmp_path)
    assert first.returncode == 0, first.stderr
    cells = pd.read_parquet(out / "cells.parquet")
    status = dict(zip(cells["method"].str.split(":").str[0], cells["status"]))
    assert status["rk4"] == "ok"
    assert all(status[f"py-{name}"] == "error" for name in BAD), status
    assert cells.loc[cells["status"] == "error", "reason"].str.len().min() > 10
    again = _gnibench(["run", str(exp), "-o", str(out), "-j", jobs, "--no-report"], tmp_path)
    assert again.returncode == 0, again.stderr        # errors are tried again, and end the same
    assert pd.read_parquet(out / "cells.parquet").equals(cells)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_real_interrupt_of_a_python_step_keeps_the_rows_so_far(tmp_path, sig):
    """Ctrl-C (or SIGTERM) while a slow Python step runs: the command stops with 128 + the
    signal, and the rows computed so far are written (before: stdout empty, even t = 0)."""
    defs = _definitions(tmp_path)
    proc = subprocess.Popen(GNIBENCH + ["solve", "kepler-2d", "py-slow_euler:h=0.001", "--steps",
                                        "100000", "--load", str(defs)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    deadline = time.monotonic() + 300
    while not (tmp_path / "started").exists() and proc.poll() is None:   # the loop runs
        assert time.monotonic() < deadline
        time.sleep(0.05)
    time.sleep(0.2)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + sig, err
    rows = out.splitlines()
    assert len(rows) >= 2 and rows[0].startswith("t,"), (out[:200], err)
    assert "Traceback" not in err


class _EntryPoint:
    def __init__(self, name, obj):
        self.name, self.value, self._obj = name, f"plugin:{name}", obj

    def load(self):
        return self._obj


@pytest.mark.parametrize("obj, message", [
    ([{"kind": "python"}, 7], "gives a list whose element 1 is int (7)"),
    (lambda: sys.exit(5), "cannot be loaded: SystemExit(5)"),
    (lambda: (_ for _ in ()).throw(KeyboardInterrupt), "cannot be loaded: KeyboardInterrupt"),
])
def test_a_bad_entry_point_is_one_line_naming_what_is_wrong(monkeypatch, obj, message):
    import importlib.metadata

    from gnibench.suite.cell.user import loader
    from gnibench.suite.foundation import guard
    from gnibench.suite.foundation.errors import UserError

    monkeypatch.setattr(guard, "_watched", [True])      # as under gnibench's signal handlers
    monkeypatch.setattr(importlib.metadata, "entry_points",
                        lambda group: [_EntryPoint("bad", obj)] if group == "gnibench.methods"
                        else [])
    with pytest.raises(UserError, match=message.replace("(", r"\(").replace(")", r"\)")):
        loader._load_entry_point("gnibench.methods", "bad")


API_STEPS = '''
import os
import signal

def own_interrupt(f, t, y, h):
    if t > 0.015:
        raise KeyboardInterrupt
    return y + h * f(t, y)

def ctrl_c(f, t, y, h):
    if t > 0.015:
        os.kill(os.getpid(), signal.SIGINT)      # a real Ctrl-C, delivered in this step
    return y + h * f(t, y)
'''


@pytest.fixture
def api_steps(tmp_path):
    """Two Python steps loaded in this process, and Python's own SIGINT handler (as in a
    notebook or a script; a test process may have another)."""
    import gnibench
    from gnibench.suite.cell.user import loader

    (tmp_path / "api_guard_steps.py").write_text(API_STEPS)
    defs = tmp_path / "api_defs.toml"
    defs.write_text("".join(f'[[method]]\nid = "api-{n}"\nkind = "python"\n'
                            f'entry = "api_guard_steps:{n.replace("-", "_")}"\n'
                            for n in ("own-interrupt", "ctrl-c")))
    gnibench.load(defs)
    saved = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield gnibench
    finally:
        signal.signal(signal.SIGINT, saved)
        loader.unload(defs)


def test_in_the_api_a_steps_own_keyboard_interrupt_is_its_error(api_steps):
    """Without gnibench's command-line handlers (the Python API) a KeyboardInterrupt raised by a
    step was taken for Ctrl-C; Python's handler is watched while user code runs, so it is the
    cell's error, and Python's handler is back afterwards."""
    traj = api_steps.solve("kepler-2d", "api-own-interrupt:h=0.01", steps=5)
    assert traj.status == "error" and "KeyboardInterrupt raised by the code itself" in traj.reason
    assert len(traj.samples) == 3                          # t = 0, 0.01, 0.02: then the step
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_in_the_api_a_real_ctrl_c_in_a_step_stops_with_the_rows_so_far(api_steps):
    with pytest.raises(KeyboardInterrupt) as e:
        api_steps.solve("kepler-2d", "api-ctrl-c:h=0.01", steps=5)
    part = getattr(e.value, "partial", None)
    assert part is not None and len(part.t) == 3 and str(part.status) == "interrupted"
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_in_a_thread_a_keyboard_interrupt_is_the_steps_error(api_steps):
    """A signal is handled in the main thread only: a KeyboardInterrupt in another thread (a Dask
    worker's task, a user's thread) is the step's own."""
    import threading

    out = {}
    thread = threading.Thread(target=lambda: out.setdefault(
        "traj", api_steps.solve("kepler-2d", "api-own-interrupt:h=0.01", steps=5)))
    thread.start()
    thread.join(timeout=600)
    assert out["traj"].status == "error", out["traj"].reason
