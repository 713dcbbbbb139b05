"""numba's front end with the two pieces of suite/foundation/numba_passes.py and without them:
the same IR, types, calls, LLVM code and numbers; and numba's closure pass still runs where a
function has closures or comprehensions (or ``reduce``: the pass is found to run)."""
from __future__ import annotations

import functools
import re
from pathlib import Path

import numpy as np
from numba import njit

from gnibench.suite.foundation import numba_passes
from support import numba_types, with_and_without, sample_step as kernel


def with_closure(x):
    def g(a):
        return a * x + 1.0
    return g(2.0) + g(3.0)


def with_comprehension(n):
    return np.array([i * 0.5 for i in range(n)]).sum()


def with_reduce(a):           # numba's closure pass handles it (numba itself lowers it only so)
    return functools.reduce(lambda u, v: u + v, a, 0.0)


def _compile(fn, *args):
    """The result, types, call signatures and LLVM code of ``fn`` (its symbols' serial numbers,
    which count the compilations of the process, written as ``BvB``)."""
    d = njit(error_model="numpy")(fn)
    result = d(*args)
    llvm = d.inspect_llvm(d.signatures[0])
    llvm = re.sub(r"\[\d+ x i8\]", "[n x i8]", re.sub(r"B\d+v\d+B", "BvB", llvm))
    return (repr(result), *numba_types(d), llvm)


def compiled_all():
    out = np.zeros(2)
    first = _compile(kernel, (0.3, -0.7), 0.1, out)
    # numba's closure pass runs on these two both times; it numbers what it inlines by process
    # counters: their results are compared
    return [first + (out.tolist(),), _compile(with_closure, 1.5)[0],
            _compile(with_comprehension, 5)[0]]


def test_installed_where_kernels_are_imported():
    from gnibench.suite.cell import codegen

    assert "numba_passes.install()" in Path(codegen.__file__).read_text()
    assert numba_passes.install()
    from numba.core import ir, untyped_passes

    assert hasattr(untyped_passes.InlineClosureLikes.run_pass, "__wrapped__")
    assert ir.Inst._rec_list_vars is numba_passes._rec_list_vars


def test_list_vars_is_numbas_on_every_statement_of_a_kernel(monkeypatch):
    """The replacement gives numba's own list, element for element and in order (numba's own
    computed with numba's method in place, down to the nested expressions)."""
    from numba.core import ir
    from numba.core.compiler import run_frontend

    assert numba_passes.install()
    statements = [stmt for fn in (kernel, with_closure, with_comprehension)
                  for block in run_frontend(fn).blocks.values() for stmt in block.body]
    ours = [stmt.list_vars() for stmt in statements]
    monkeypatch.setattr(ir.Inst, "_rec_list_vars", numba_passes._originals["rec"])
    theirs = [stmt.list_vars() for stmt in statements]
    assert len(statements) > 50 and sum(map(len, theirs)) > 50
    assert ours == theirs


def test_the_closure_pass_is_skipped_only_where_it_has_nothing_to_do():
    from numba.core.compiler import run_frontend

    assert not numba_passes._has_closure_likes(run_frontend(kernel))
    for fn in (with_closure, with_comprehension, with_reduce):
        assert numba_passes._has_closure_likes(run_frontend(fn)), fn.__name__


def test_the_same_ir_types_code_and_numbers_without_them():
    """In a fresh process: compile with both pieces, then with numba's own (uninstall)."""
    with_them, without = with_and_without(
        "numba_passes", "test_numba_passes:compiled_all",
        "from numba.core import untyped_passes; "
        "assert not hasattr(untyped_passes.InlineClosureLikes.run_pass, '__wrapped__')")
    assert with_them == without
    assert with_them[1:] == ["9.5", str(float(sum(i * 0.5 for i in range(5))))]
    assert with_them[0][-1] != [0.0, 0.0] and "fdiv" in with_them[0][3]
