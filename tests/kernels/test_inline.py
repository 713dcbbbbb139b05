"""Source-level inlining of the generated modules (suite/foundation/inline.py): the small helpers
are written into their callers with the same operations, so a module computes the same bits
before and after, and numba compiles fewer functions.

The modules are run here as plain Python (the ``@njit`` lines removed): Python evaluates the
same floating-point operations as the compiled code, so equal results before and after
inlining show that no operation was changed, reordered or dropped. No numba compilation."""
from __future__ import annotations

import functools
import re

import numpy as np
import pytest
from gnibench.methods.kernels.slots import STATE, Y_ROWS
from gnibench.suite.cell.codegen import _inline, module_source
from gnibench.suite.cell.spec import prepare
from gnibench.suite.foundation.inline import BIG_TUPLE, _function_blocks, inline_source


def _python(text: str, problem=None) -> dict:
    """The functions of a generated module as plain Python. A cell module of a problem with a
    section takes Hénon's locator from the problem's module (suite/cell/codegen.py): that one
    is run as plain Python too, under its name, while the cell's module is executed."""
    import sys
    import types

    from gnibench.suite.cell.codegen import problem_module_name, problem_source

    namespace: dict = {}
    name = problem_module_name(problem) if problem is not None and problem.record.sections else ""
    saved = sys.modules.get(name)
    if name:
        plain = types.ModuleType(name)
        plain.__dict__.update(_python(problem_source(problem)[0]))
        sys.modules[name] = plain
    try:
        exec(compile(re.sub(r"^@njit\(.*\)\n", "", text, flags=re.M), "<module>", "exec"),
             namespace)
    finally:
        if name and saved is not None:
            sys.modules[name] = saved
        elif name:
            del sys.modules[name]
    return namespace


def _run(text: str, problem, method, name: str, args: tuple, rows: int = 40):
    """The driver ``name`` of a module run from the cell's y0 (y_io, st and the output rows)."""
    ns = _python(text, problem)
    rec = problem.record
    y_io = np.zeros((Y_ROWS, rec.dim))
    y_io[0] = rec.y0(problem.values)
    st = np.zeros(STATE)
    st[14] = 3.0                                         # ST_WANTED: crossings of a section run
    par = np.array(rec.par(problem.values), dtype=np.float64)
    out_t, out_y, out_c = np.zeros(rows), np.zeros((rows, rec.dim)), np.zeros((rows, 4))
    status, row = ns[name](y_io, st, par, *args, 10**6, out_t, out_y, out_c)
    return status, row, y_io, st, out_t, out_y, out_c


ADAPTIVE = (2.0, 0.0, 2.0, 1e-6, 1e-6, 1, 0.0, 0, 10**6)       # t_end, h0, hmax, rtol, atol, ...
CELLS = [
    ("kepler-2d", "rk4:h=0.1", "integrate", (0.1, 20, 0.1, 1, 0.0, 0)),
    ("kepler-2d", "rk4:h=0.1,sum=compensated", "integrate", (0.1, 20, 0.1, 1, 0.0, 0)),
    ("kepler-2d", "gauss4:h=0.1", "integrate", (0.1, 20, 0.1, 1, 0.0, 0)),
    ("kepler-2d", "stormer-verlet:h=0.1", "integrate_grid", (0.1, 20, 0.1, 1, 0.07, 30)),
    ("kepler-2d", "dopri5", "integrate_adaptive", ADAPTIVE),
    ("kepler-2d", "dop853", "integrate_dense", ADAPTIVE[:6] + (0.05, 41, 10**6)),
    ("kepler-2d", "odex", "integrate_adaptive", ADAPTIVE),
    ("kepler-2d", "vern6", "integrate_adaptive", ADAPTIVE),
    ("henon-heiles", "dop853", "adaptive_section_dense", (30.0,) + ADAPTIVE[1:]),
    ("henon-heiles", "rk4:h=0.05", "integrate_section", (0.05, 600, 0.05, 1, 0.0, 0)),
]


@pytest.mark.parametrize("spec, method, name, args", CELLS)
def test_inlined_module_computes_the_same_bits(spec, method, name, args):
    problem, cfg = prepare(spec, method)
    text, _ = module_source(problem, cfg)
    inlined = _inline(text, "cell")
    assert inlined != text
    before = _run(text, problem, cfg, name, args)
    after = _run(inlined, problem, cfg, name, args)
    assert before[1] > 1                                 # rows were written
    for a, b in zip(before, after):
        assert np.array_equal(a, b, equal_nan=True), name


@pytest.mark.parametrize("spec, method", [("kepler-2d", "dopri5"), ("kepler-2d", "gauss4"),
                                          ("kepler-2d", "odex"), ("henon-heiles", "dop853"),
                                          ("henon-heiles", "rk4+observer"),
                                          ("kepler-2d", "rk4+projection:on=H/L"),
                                          ("kepler-2d", "implicit-midpoint:fixed_point=5")])
def test_every_marked_helper_is_written_inline(spec, method):
    """A helper marked ``inline='always'`` that the inliner cannot take (a second ``return``, a
    loop exit) would silently be compiled on its own again, as numba inlines it: none is left."""
    problem, cfg = prepare(spec, method)
    text = _inline(module_source(problem, cfg)[0], "cell")
    code = re.sub(r'""".*?"""', "", text, flags=re.S)
    marked = re.findall(r"^@njit\(cache=True, inline='always'\)\ndef (\w+)\(", text, re.M)
    assert marked
    called = [name for name in marked if re.search(rf"(?<!def )(?<![\w.]){name}\(", code)]
    assert called == []


SOURCE = '''
def helper(a, b):
    t = a * b
    return t + a

def proc(t, A, j):
    A[j, 0] = t[0]
    A[j, 1] = t[1]

def early(x):
    if x > 0.0:
        return 1.0
    return 2.0

def pure(a):
    return (a[0] + 1.0, a[1] * 2.0)

def big(a):
    return (BIG)

def caller(x, y, A):
    u = helper(x + y, y) * helper(x, 3.0)
    proc(pure((x, y)), A, 0)
    v = pure((u, x)) if x > 0.0 else pure((x, u))
    w = early(x)
    k = 0
    while helper(k, 1.0) < 3.0:
        k += 1
    t = 0.5
    z = helper(x, t)
    b = big(x)
    return u, v, w, k, z, b[0]
'''.replace("BIG", ", ".join(f"{i}.0 * a" for i in range(BIG_TUPLE + 2)))


def test_inliner_keeps_python_semantics_and_leaves_what_it_cannot_take():
    names = ("helper", "proc", "early", "pure", "big")
    out = inline_source(SOURCE, names)
    caller = out[out.index("def caller("):]
    assert "helper(x" not in caller and "proc(" not in caller     # written inline
    assert "early(x)" in caller                                    # two returns: stays a call
    assert "while helper(k, 1.0) < 3.0" in caller                  # needs a statement: a call
    assert "pure((u, x)) if" in caller                             # conditional branch: a call
    assert re.search(r"tuple__\d+ = \(0\.0 \* x", caller)          # a big tuple gets a local
    for x, y in ((1.5, -0.25), (-2.0, 3.0), (1e300, 1e300)):
        A1, A2 = np.zeros((1, 2)), np.zeros((1, 2))
        r1 = _python(SOURCE)["caller"](x, y, A1)
        r2 = _python(out)["caller"](x, y, A2)
        assert repr(r1) == repr(r2) and np.array_equal(A1, A2)


def test_a_global_shadowed_by_a_local_of_the_caller_is_not_inlined():
    """g reads the global SCALE: written into h, whose local SCALE would capture it, it would
    change h's value; written into k, which has no such local, it is inlined."""
    src = ("def g(a):\n    return a * SCALE\n\n"
           "def h(x):\n    SCALE = 2.0\n    return g(x) + SCALE\n\n"
           "def k(x):\n    return g(x) + 1.0\n")
    out = inline_source(src, ("g",))
    h_out, k_out = out.split("def h(")[1].split("def k(")
    assert "g(x)" in h_out and "g(" not in k_out
    ns = {"SCALE": 3.0}
    exec(out, ns)
    assert ns["h"](1.0) == 5.0 and ns["k"](1.0) == 4.0


def _frontend_failures(text: str, where) -> list[str]:
    """The functions of an inlined module holding a tuple display of more than BIG_TUPLE
    elements that numba's front end (bytecode -> IR) refuses (the others cannot meet this)."""
    import importlib.util

    from numba.core.compiler import run_frontend

    path = where / "gnibench_inline_probe.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("gnibench_inline_probe", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    lines = text.splitlines(keepends=True)
    wide = {name for name, (_, head, end) in _function_blocks(lines).items()
            if _holds_wide_tuple("".join(lines[head:end]))}
    assert wide, "no function holds a wide tuple: the probe would test nothing"
    bad = []
    for name, obj in vars(module).items():
        if name in wide and getattr(obj, "py_func", None) is not None:
            key = _frontend_key(obj.py_func, vars(module))
            if key not in _FRONTEND_SEEN:        # the same function met in another method's module
                try:
                    run_frontend(obj.py_func)
                    _FRONTEND_SEEN[key] = ""
                except Exception as e:                                   # noqa: BLE001
                    _FRONTEND_SEEN[key] = f"{type(e).__name__} {e}"
            if _FRONTEND_SEEN[key]:
                bad.append(f"{name}: {_FRONTEND_SEEN[key]}")
    return bad


@functools.lru_cache(maxsize=None)
def _holds_wide_tuple(function_text: str) -> bool:
    """Whether a function's text holds a tuple display of more than BIG_TUPLE elements (parsed
    once per distinct text: the drivers of a family recur in every method's module)."""
    import ast

    return any(isinstance(t, ast.Tuple) and len(t.elts) > BIG_TUPLE
               for t in ast.walk(ast.parse(function_text)))


#: front-end outcomes by function: its source and the values of the plain globals it reads (the
#: front end turns the same bytecode with the same constants into the same IR); the drivers of
#: one family are the same text in every method's module (394 wide functions, 105 distinct)
_FRONTEND_SEEN: dict[tuple, str] = {}


def _frontend_key(fn, module_globals: dict) -> tuple:
    import inspect

    names = sorted(n for n in fn.__code__.co_names
                   if isinstance(module_globals.get(n), (int, float, bool, str, tuple)))
    return (inspect.getsource(fn), tuple((n, repr(module_globals[n])) for n in names))


# methods whose inlined module has the form of another's, with other coefficients (same family
# generator, same stage structure up to the count): the front end sees nothing new in them
SAME_KERNEL_AS = {"vern7": "vern6", "vern8": "vern6", "vern9": "vern6", "feagin10": "vern6",
                  "merson": "rkf45", "euler": "rk4", "gauss6": "gauss4",
                  "implicit-midpoint": "implicit-euler", "symplectic-euler-adjoint": "symplectic-euler",
                  "yoshida6": "yoshida4", "yoshida8": "yoshida4", "suzuki4": "yoshida4",
                  "mclachlan4": "yoshida4", "kahan-li6": "yoshida4", "kahan-li8": "yoshida4"}


def _wide_cells():
    from gnibench.methods import COMPILED

    for mid, m in COMPILED.items():
        if mid in ("lie-poisson", "generating-function4"):    # so(4) only; sympy per problem
            continue
        if mid in SAME_KERNEL_AS:                            # one method per generated form
            continue
        names = {p.name for p in m.params if p.only_if is None}
        opts = ["h=10"] if "h" in names else []
        # compensated: the module holds the plain step too (the drivers branch on COMPENSATED)
        opts += ["sum=compensated"] if "sum" in names else []
        yield f"{mid}:{','.join(opts)}".rstrip(":")


def test_skipped_methods_share_the_family_of_a_tested_one():
    from gnibench.methods import COMPILED

    for mid, like in SAME_KERNEL_AS.items():
        assert like not in SAME_KERNEL_AS and COMPILED[mid].family == COMPILED[like].family, mid


def test_a_refused_function_is_reported_each_time_it_is_met(tmp_path, monkeypatch):
    """The front-end probe reports a refusal, also for a function met before (its outcome is
    kept by source and constants, not its success assumed)."""
    import numba.core.compiler as compiler

    def refuse(fn):
        raise compiler.errors.UnsupportedError("refused by the test")

    monkeypatch.setattr(compiler, "run_frontend", refuse)
    wide = ", ".join(f"y[{i}]" for i in range(BIG_TUPLE + 1))
    text = (f"from numba import njit\nK = {BIG_TUPLE}\n\n@njit\ndef wide_probe_refused(y):\n"
            f"    return ({wide}) if K else y\n")
    for k in range(2):
        where = tmp_path / str(k)
        where.mkdir()
        assert _frontend_failures(text, where) == [
            "wide_probe_refused: UnsupportedError refused by the test"], k


@pytest.mark.parametrize("method", list(_wide_cells()))
def test_wide_states_pass_numba_front_end_after_inlining(method, tmp_path):
    """36 states (outer solar system) > BIG_TUPLE: the wide functions of every compiled method's
    inlined module (one method per generated form, SAME_KERNEL_AS) go through numba's front end
    (an inlined pair of 36-tuples returned into names a branch also assigns failed in it:
    implicit-euler, sum=compensated, [HLW] Fig 2.4)."""
    problem, cfg = prepare("outer-solar-system", method)
    text, _ = module_source(problem, cfg)
    assert _frontend_failures(_inline(text, "cell"), tmp_path) == []
