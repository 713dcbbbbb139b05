"""The functions of a generated module that only compiled code calls have no Python entry point
(suite/cell/codegen.py, PYTHON_ENTRIES: numba's CPython and cfunc wrappers cost ~40 % of a cell's
compile time); the ones Python calls keep theirs, and calling an internal one from Python raises
TypeError instead of jumping to a missing entry point."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from gnibench.suite.cell.codegen import PYTHON_ENTRIES, PYTHON_PREFIXES
from gnibench.suite.cell.drivers import AdaptiveDriver, FixedStepDriver, ready_cell
from gnibench.suite.cell.spec import prepare

ROOT = Path(__file__).resolve().parents[2]


def test_every_driver_is_a_python_entry():
    for kind in (FixedStepDriver, AdaptiveDriver):
        assert set(kind.names.values()) <= set(PYTHON_ENTRIES), kind


def test_python_calls_of_generated_modules_name_entries_only():
    """Every call of a generated module's function written in the repository (``kernel.<name>``
    or ``mod.<name>`` called) names a function that keeps its Python entry point."""
    call = re.compile(r"\b(?:kernel|mod)\.(\w+)\(")
    called = set()
    for folder in ("suite", "methods", "reports", "tests", "problems"):
        for path in (ROOT / folder).rglob("*.py"):
            called |= set(call.findall(path.read_text()))
    called -= {"append", "integrals"}      # a list's, ProblemKernel.integrals (Python)
    internal = sorted(n for n in called if n not in PYTHON_ENTRIES
                      and not n.startswith(PYTHON_PREFIXES))
    assert internal == []


def test_internal_functions_raise_instead_of_crashing():
    problem, method = prepare("kepler-2d", "rk4:h=0.01")
    cell = ready_cell(problem, method)
    k = cell.kernel
    assert k.step.targetoptions.get("no_cpython_wrapper") is True
    assert not k.integrate.targetoptions.get("no_cpython_wrapper")
    with pytest.raises(TypeError, match="only from compiled code"):
        k.step(cell.y0, 0.01, cell.par, 0)
    assert len(k.f(cell.y0, cell.par)) == len(cell.y0)       # an entry: callable from Python
