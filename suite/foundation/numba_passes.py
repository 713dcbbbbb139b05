"""Two pieces of numba's front end that cost a generated kernel time for nothing.

Measured with py-spy over a cold run of the test suite (2 cores, 2026-11-27): of ~370 s spent
compiling, 18.7 s in numba's ``InlineClosureLikes`` pass and ~10 s in ``Inst._rec_list_vars``
(the walk behind ``list_vars``, which ``compute_use_defs`` and the variable-lifetime analysis run
over every statement, ~10 times per function).

* ``InlineClosureLikes`` inlines calls to closures, ``functools.reduce`` and stencils and turns
  array comprehensions into loops; to look for them it runs numba's post-processor (use-defs and
  variable lifetimes of the whole function) twice. A generated kernel has none of them: the pass
  is skipped for a function whose IR holds no ``make_function``, no ``build_list`` (the start of
  every comprehension), no ``reduce`` and no stencil; any other function gets numba's pass.
* ``Inst._rec_list_vars`` is replaced by a loop that gives the same list, in the same order: the
  variables of an instruction, of the instructions, lists, tuples and dicts it holds, depth
  first, an instruction's own ``list_vars`` answering for it.

:func:`install` is called where a kernel is imported (``suite/cell/codegen.py``, with the typing
memo). ``tests/kernels/test_numba_passes.py`` compiles kernels with and without it and compares the
types, the calls, the LLVM code and the results. Measured on 10 cold kernels of 5 problems and
9 methods (three alternating runs each): 17.2, 14.4, 14.7 s of compilation without, 14.0, 12.9,
13.4 s with.
"""
from __future__ import annotations

_originals: dict = {}           # what install() replaced, by name
_off: list = []                 # uninstall() was called: install() does nothing


def install() -> bool:
    """Put both in place (once per process); False when this numba lacks either piece or after
    :func:`uninstall` (nothing is changed then)."""
    if _originals:
        return True
    if _off:
        return False
    from numba.core import ir, untyped_passes

    run_pass = getattr(getattr(untyped_passes, "InlineClosureLikes", None), "run_pass", None)
    rec = getattr(ir.Inst, "_rec_list_vars", None)
    if run_pass is None or rec is None:
        return False

    def guarded_run_pass(self, state):
        if _has_closure_likes(state.func_ir):
            return run_pass(self, state)
        return False                  # nothing to inline: the IR is left as it is

    guarded_run_pass.__wrapped__ = run_pass
    _originals["run_pass"] = run_pass
    _originals["rec"] = rec
    untyped_passes.InlineClosureLikes.run_pass = guarded_run_pass
    ir.Inst._rec_list_vars = _rec_list_vars
    return True


def uninstall() -> None:
    """Put numba's own pieces back, for good in this process (for the tests that compare)."""
    _off.append(True)
    if _originals:
        from numba.core import ir, untyped_passes

        untyped_passes.InlineClosureLikes.run_pass = _originals.pop("run_pass")
        ir.Inst._rec_list_vars = _originals.pop("rec")


def _has_closure_likes(func_ir) -> bool:
    """Whether the pass could change this IR: a closure made, a list built (comprehensions start
    so), or a global or free variable that is ``reduce`` or a stencil."""
    from numba.core import ir

    for block in func_ir.blocks.values():
        for stmt in block.body:
            if not isinstance(stmt, ir.Assign):
                continue
            value = stmt.value
            if isinstance(value, ir.Expr):
                if value.op in ("make_function", "build_list"):
                    return True
            elif isinstance(value, (ir.Global, ir.FreeVar)):
                obj = value.value
                if getattr(obj, "__name__", None) == "reduce" \
                        or type(obj).__name__ == "StencilFunc":
                    return True
    return False


_KIND: dict = {}                # type -> 1 variable, 2 instruction, 3 sequence, 4 dict, 0 other


def _kind(t) -> int:
    from numba.core import ir

    k = (1 if issubclass(t, ir.Var) else 2 if issubclass(t, ir.Inst) else
         3 if issubclass(t, (list, tuple)) else 4 if issubclass(t, dict) else 0)
    _KIND[t] = k
    return k


def _collect(val, out: list) -> None:
    k = _KIND.get(type(val))
    if k is None:
        k = _kind(type(val))
    if k == 1:
        out.append(val)
    elif k == 2:
        out.extend(val.list_vars())
    elif k == 3:
        for v in val:
            _collect(v, out)
    elif k == 4:
        for v in val.values():
            _collect(v, out)


def _rec_list_vars(self, val) -> list:
    """numba's ``Inst._rec_list_vars``: the same variables in the same order, without building a
    list per level."""
    out: list = []
    _collect(val, out)
    return out
