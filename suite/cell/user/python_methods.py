"""Python integrators of the user's: the one place where gnibench steps in Python.

Two kinds of ``[[method]]`` (docs: reference, "User definitions"):

* ``python``: ``entry = "module:function"`` names ``step(f, t, y, h) -> y_new`` (numpy arrays).
  gnibench calls it once per step, on the same grid as a compiled fixed-step method (``h``,
  ``--steps`` / ``--t-end`` with the last step shortened, a sample every K steps). ``steps``
  counts the calls, ``nfev`` the calls of ``f`` (through a counting wrapper).
* ``python-solver``: ``entry`` names ``solve(f, y0, t_span, t_eval, rtol, atol)``, a whole
  integration returning the samples at ``t_eval`` (an array of shape (len(t_eval), N), or a
  dict with ``y`` and optionally ``nfev``, ``steps``, ``status`` ("ok" or a failure) and
  ``message``). Like an adaptive engine it samples the grid t = k dt_out. ``nfev`` (counted
  through the wrapper, or as reported) and ``steps`` (as reported) are known only at the end:
  the samples after the first carry NaN (missing in the tables), and so does the last one's
  ``steps`` when the solver reports none.

``f(t, y)`` is the problem's compiled vector field (:mod:`gnibench.problems.codegen`), called
from Python. An exception in the user's code, a wrong shape or a non-finite state ends the cell
with status ``error`` or ``nonfinite`` and the reason; the samples before it are kept. Both
kinds are ``Method.kind == "python"``; modifiers, which act on gnibench's compiled field, are
refused.
"""
from __future__ import annotations

import importlib
import re
import sys
import time
from dataclasses import dataclass

import numpy as np
from gnibench.methods.engines.base import EngineRun
from gnibench.methods.external import ExternalMethod
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.guard import UserCodeError, user_code

#: (entry, base) -> (function, module, (mtime, size) of its file, digest of its source)
_ENTRIES: dict[tuple[str, str], tuple] = {}


@dataclass(frozen=True)
class PythonMethod(ExternalMethod):
    """A user's integrator written in Python (``entry``: ``module:function``)."""

    entry: str = ""

    def check_structure(self, problem, has_modifiers: bool) -> None:
        if has_modifiers:
            raise UserError(f"method {self.id} runs in Python (kind python); modifiers (+observer, "
                            f"+penalty, +projection) act on gnibench's compiled vector field and "
                            f"apply only to the compiled methods")

    def describe(self) -> dict:
        d = super().describe()
        d["properties"].update(external=False, python=True)
        d["entry"] = self.entry
        d["order"] = self.order or None             # 0: the entry declares no order
        return d


def _source(mod) -> tuple[tuple | None, str]:
    """((mtime, size) of the module's file or None, sha256 of its source)."""
    import hashlib
    import inspect
    import os

    path = getattr(mod, "__file__", None)
    if path and os.path.isfile(path):
        st = os.stat(path)
        with open(path, "rb") as f:
            return (st.st_mtime_ns, st.st_size), hashlib.sha256(f.read()).hexdigest()
    try:
        return None, hashlib.sha256(inspect.getsource(mod).encode()).hexdigest()
    except (OSError, TypeError):
        return None, getattr(mod, "__name__", "?")


def _changed(stamp, mod) -> bool:
    import os

    path = getattr(mod, "__file__", None)
    if stamp is None or not path or not os.path.isfile(path):
        return False
    st = os.stat(path)
    return (st.st_mtime_ns, st.st_size) != stamp


def entry_code(entry: str, base: str = "") -> tuple:
    """(the function named ``module:function``, the sha256 of its module's source). The module is
    imported as usual, else from ``base`` (the directory of the definitions file); a module whose
    file changed since it was imported is imported again (an edited integrator runs as edited,
    and its digest, part of a stored cell's key, says so)."""
    key = (entry, base)
    if key in _ENTRIES:
        fn, mod, stamp, digest = _ENTRIES[key]
        if not _changed(stamp, mod):
            return fn, digest
        if _source(mod)[1] != digest:
            with user_code(f"importing {mod.__name__}"):
                importlib.reload(mod)
        del _ENTRIES[key]
    match = re.fullmatch(r"\s*([A-Za-z_][\w.]*)\s*:\s*([A-Za-z_][\w.]*)\s*", entry)
    if match is None:
        raise ValueError(f"bad entry {entry!r}; allowed: 'module:function'")
    module, name = match.groups()
    try:
        mod = _import(module)
    except ModuleNotFoundError:
        if not base:
            raise
        sys.path.insert(0, base)
        try:
            mod = _import(module)
        finally:
            sys.path.remove(base)
    stamp, digest = _source(mod)
    fn = mod
    for part in name.split("."):
        fn = getattr(fn, part)
    if not callable(fn):
        raise TypeError(f"{entry} is not callable")
    _ENTRIES[key] = (fn, mod, stamp, digest)
    return fn, digest


def _import(module: str):
    """Import the user's module: what its top level raises (sys.exit included) is a
    UserCodeError; a missing module stays a ModuleNotFoundError."""
    try:
        with user_code(f"importing {module}"):
            return importlib.import_module(module)
    except UserCodeError as e:
        if isinstance(e.__context__, ModuleNotFoundError) and \
                getattr(e.__context__, "name", None) == module.partition(".")[0]:
            raise e.__context__ from None
        raise


def resolve_entry(entry: str, base: str = ""):
    """The function named ``module:function`` (:func:`entry_code`)."""
    return entry_code(entry, base)[0]


def _current(entry: str, base: str, code: str):
    """The function of a method built when its module's source had the digest ``code``; a
    ValueError when the module has changed since (its results would be stored under the key of
    the code it was loaded with: load the definitions again)."""
    fn, digest = entry_code(entry, base)
    if code and digest != code:
        raise ValueError(f"the module of {entry} changed after its definitions were loaded; "
                         f"load them again (gnibench.load, or a new command)")
    return fn


def _field(problem):
    """f(t, y) -> ndarray from the problem's compiled field, and its call counter."""
    from gnibench.suite.cell.compiled import problem_kernel

    pk = problem_kernel(problem)
    base_f, par, n = pk.kernel.base_f, pk.par, problem.record.dim
    # loaded (or compiled) now, with the setup: numba loads a cached function at its first call,
    # and a Ctrl-C inside numba's loading is a hard exit after a grace time (cli/signals.py),
    # which would lose the rows of the first steps
    base_f(tuple(float(v) for v in problem.record.y0(problem.values)), par)
    count = [0]

    def f(t, y):
        count[0] += 1
        y = np.asarray(y, dtype=float)
        return np.array(base_f(tuple(float(y[i]) for i in range(n)), par))

    return f, count


def _real(value, what: str) -> np.ndarray:
    """The user's numbers as floats; complex values are refused, not cut to their real part."""
    a = np.asarray(value)
    if np.iscomplexobj(a):
        raise ValueError(f"{what} complex values; expected real numbers")
    return np.asarray(a, dtype=float)


def _state(value, n: int) -> np.ndarray:
    y = _real(value, "returned")
    if y.shape != (n,):
        raise ValueError(f"returned shape {y.shape}; expected ({n},)")
    return y


def _count(result: dict, key: str) -> int | None:
    """The solver's count ``key`` (a non-negative integer; None when it reports none; a
    ValueError otherwise)."""
    value = result.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer, float)) or \
            not 0 <= value < 2 ** 62 or int(value) != value:
        raise ValueError(f"returned {key} = {value!r}; expected a count (an integer >= 0)")
    return int(value)


def _failed(n: int, problem, reason: str) -> EngineRun:
    """A cell whose integrator could not be called: status ``error``, the initial point only."""
    y0 = np.array([problem.record.y0(problem.values)], dtype=float).reshape(1, n)
    return EngineRun(y=y0, y_full=None, steps=np.zeros(1, dtype=np.int64), nfev=np.zeros(1),
                     status="error", reason=reason, setup_seconds=0.0, seconds=0.0,
                     info={"engine": "python"})


def stepper(entry: str, base: str, code: str = ""):
    """``run(problem, values, grid, kernel) -> EngineRun`` of a ``python`` method (``kernel``: the
    problem's compiled module, passed by the driver to every engine; unused here)."""

    def run(problem, values, grid, kernel=None) -> EngineRun:
        t0 = time.perf_counter()
        n = problem.record.dim
        try:
            step = _current(entry, base, code)
        except Exception as e:  # noqa: BLE001 - the user's module: a status, not a crash
            return _failed(n, problem, f"{entry}: {type(e).__name__}: {e}")
        f, count = _field(problem)
        marks = grid.step
        rows = len(marks)
        y = np.array(problem.record.y0(problem.values), dtype=float)
        out, nfev = np.empty((rows, n)), np.zeros(rows)
        out[0] = y
        setup = time.perf_counter() - t0
        status, reason, done, k = "ok", "", 1, 1
        t1 = time.perf_counter()
        i = 0
        try:
            with user_code(lambda: f"{entry} at step {i}"):
                for i in range(1, grid.nsteps + 1):
                    h = grid.h if i < grid.nsteps else grid.h_last
                    y = _state(step(f, (i - 1) * grid.h, y.copy(), h), n)
                    if not np.all(np.isfinite(y)):
                        status, reason = "nonfinite", f"state overflowed or became NaN at step {i}"
                        break
                    if k < rows and marks[k] == i:
                        out[k], nfev[k] = y, count[0]
                        k += 1
                        done = k
        except UserCodeError as e:          # the user's code: a status, not a crash
            status, reason = "error", str(e)
        except KeyboardInterrupt:           # Ctrl-C, SIGTERM: the rows so far are kept
            status, reason = "interrupted", ""
        seconds = time.perf_counter() - t1
        info = {"engine": "python", "entry": entry, "steps": "calls of the step function",
                "nfev": "calls of f"}
        return EngineRun(y=out[:done], y_full=None, steps=marks[:done].astype(np.int64),
                         nfev=nfev[:done], status=status, reason=reason, setup_seconds=setup,
                         seconds=seconds, info=info)

    return run


def solver(entry: str, base: str, code: str = ""):
    """``run(problem, values, grid, kernel) -> EngineRun`` of a ``python-solver`` method."""

    def run(problem, values, grid, kernel=None) -> EngineRun:
        t0 = time.perf_counter()
        n = problem.record.dim
        try:
            solve = _current(entry, base, code)
        except Exception as e:  # noqa: BLE001 - the user's module: a status, not a crash
            return _failed(n, problem, f"{entry}: {type(e).__name__}: {e}")
        f, count = _field(problem)
        t_eval = np.array(grid.t, dtype=float)
        y0 = np.array(problem.record.y0(problem.values), dtype=float)
        setup = time.perf_counter() - t0
        status, reason, steps, reported, interrupted = "ok", "", None, None, False
        t1 = time.perf_counter()
        try:
            with user_code(entry):
                result = solve(f, y0.copy(), (0.0, float(t_eval[-1])), t_eval.copy(),
                               float(values["rtol"]), float(values["atol"]))
            if isinstance(result, dict):
                status = str(result.get("status", "ok"))
                reason = "" if status == "ok" else str(result.get("message", ""))
                steps, reported = _count(result, "steps"), _count(result, "nfev")
                result = result["y"]
            y = _real(result, "returned samples with")
            if y.ndim != 2 or y.shape[1] != n or len(y) > len(t_eval):
                raise ValueError(f"returned samples of shape {y.shape}; expected "
                                 f"({len(t_eval)}, {n})")
        except UserCodeError as e:      # the user's code: a status, not a crash
            y, status, reason = np.empty((0, n)), "error", str(e)
        except Exception as e:  # noqa: BLE001 - what it returned: a status, not a crash
            y, status, reason = np.empty((0, n)), "error", f"{entry}: {type(e).__name__}: {e}"
        except KeyboardInterrupt:       # Ctrl-C, SIGTERM: the initial point is kept
            y, status, reason, interrupted = np.empty((0, n)), "interrupted", "", True
        seconds = time.perf_counter() - t1
        bad = ~np.all(np.isfinite(y), axis=1)
        if bad.any():
            y, status = y[:int(np.argmax(bad))], "nonfinite"
            reason = reason or "the solver returned non-finite samples"
        elif len(y) < len(t_eval) and status == "ok":
            status, reason = "error", f"the solver returned {len(y)} of {len(t_eval)} samples"
        if status not in ("ok", "nonfinite", "error", "max_steps", "step_too_small") and \
                not interrupted:
            status, reason = "error", f"{entry} returned status {status!r}: {reason}"
        if not len(y):                  # nothing usable: the initial point, as a failed call
            y = y0[None, :]
        rows = len(y)
        nfev, counts = np.full(rows, np.nan), np.full(rows, np.nan)   # NaN: not known there
        nfev[0] = counts[0] = 0.0
        if rows > 1:
            nfev[-1] = float(count[0] if reported is None else reported)
            counts[-1] = np.nan if steps is None else float(steps)
        info = {"engine": "python", "entry": entry, "steps": "as reported by the solver (last "
                "sample; missing when it reports none)", "nfev": "calls of f, or as reported "
                "(last sample)"}
        return EngineRun(y=y, y_full=None, steps=counts, nfev=nfev, status=status, reason=reason,
                         setup_seconds=setup, seconds=seconds, info=info)

    return run
