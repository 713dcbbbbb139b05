"""Kernel assembly (methods/assembly): what a module holds, who binds each name, what is compiled
and cached, and that the compiled module computes the bits its text says.

* bit-identical: a module's driver compiled by numba (its helpers written into it by numba's
  inliner) gives the same bits as the same text run as plain Python (which evaluates the same
  floating-point operations in the same order);
* the binding tables are complete: for every family, driver kind and output, every name the
  driver's code can reach (the branches of the other outputs dropped, as numba drops them) is
  bound in the module, and each family's writer defines the names its table says;
* roles: every function carries one of the four decorators, and only the functions Python calls
  are compiled into numba's disk cache;
* nothing rewrites a module's text: templates are copied verbatim.
"""
from __future__ import annotations

import ast
import builtins
import inspect
import json
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from gnibench.methods.assembly import assemble, kernel_text, source
from gnibench.methods.assembly.bindings import (
    DENSE_PART,
    DRIVER_NAMES,
    DRIVERS,
    FAMILIES,
    FLAGS,
    SUM,
)
from gnibench.methods.assembly.cell import cell_text, problem_text
from gnibench.methods.assembly.loading import module_name
from gnibench.methods.assembly.templates.slots import STATE, ST_WANTED, Y_ROWS
from gnibench.suite.cell.spec import prepare

ROOT = Path(__file__).resolve().parents[2]
ROLES = (source.ENTRY, source.SHARED, source.INLINE, source.INTERNAL)


# -- the same bits, compiled and as plain Python ---------------------------------------------------

def _plain(text: str, problem=None) -> dict:
    """The module's functions as plain Python (``njit`` a no-op). A section cell of an unchanged
    field takes Hénon's locator from the problem's module: that one is run as plain Python too,
    under its name, while the cell's module is executed."""
    stub = "njit = lambda **kw: (lambda fn: fn)\n"
    namespace: dict = {}
    name = module_name(problem_text(problem), "problem") if problem is not None else ""
    saved = sys.modules.get(name)
    if problem is not None and problem.record.sections:
        plain = types.ModuleType(name)
        plain.__dict__.update(_plain(problem_text(problem)))
        sys.modules[name] = plain
    try:
        exec(compile(text.replace("from numba import njit\n", stub), "<module>", "exec"),
             namespace)
    finally:
        if saved is not None:
            sys.modules[name] = saved
        elif name in sys.modules and problem is not None and problem.record.sections:
            del sys.modules[name]
    return namespace


def _run(fn, problem, args: tuple, rows: int = 40):
    """A driver run from the cell's y0: (status, rows, y_io, st and the output arrays)."""
    rec = problem.record
    y_io = np.zeros((Y_ROWS, rec.dim))
    y_io[0] = rec.y0(problem.values)
    st = np.zeros(STATE)
    st[ST_WANTED] = 3.0                                  # crossings of a section run
    par = np.array(rec.par(problem.values), dtype=np.float64)
    out_t, out_y, out_c = np.zeros(rows), np.zeros((rows, rec.dim)), np.zeros((rows, 4))
    status, row = fn(y_io, st, par, *args, 10**6, out_t, out_y, out_c)
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
def test_compiled_module_computes_the_bits_of_its_text(spec, method, name, args):
    problem, cfg = prepare(spec, method)
    kind, output = DRIVER_NAMES[name]
    loop = DRIVERS[kind].loop.__name__
    compiled = _run(getattr(assemble(problem, cfg, output), loop), problem, args)
    plain = _run(_plain(cell_text(problem, cfg, output), problem)[loop], problem, args)
    assert compiled[1] > 1                               # rows were written
    for a, b in zip(compiled, plain):
        assert np.array_equal(a, b, equal_nan=True), name


# -- the binding tables are complete ---------------------------------------------------------------

def _top(tree: ast.Module) -> tuple[set, dict, dict]:
    """Module-level names, constants (name -> value) and functions (name -> node)."""
    names, consts, functions = set(), {}, {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            names.add(node.name)
            functions[node.name] = node
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                names.update(n.id for n in ast.walk(target) if isinstance(n, ast.Name))
                if isinstance(target, ast.Name) and isinstance(node.value, ast.Constant):
                    consts[target.id] = node.value.value
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
    return names, consts, functions


def _value(node, consts):
    """The value of a test made of module constants (numba prunes such branches), else None."""
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Name) and node.id in consts:
        return consts[node.id]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
        v = _value(node.operand, consts)
        return None if v is None else not v
    return None


def _used(fn: ast.FunctionDef, consts: dict) -> set:
    """The global names a function can reach: loads that are not its locals, the branches whose
    test is a module constant taken as numba takes them."""
    loads, local = set(), {a.arg for a in fn.args.args}

    def visit(node):
        if isinstance(node, (ast.If, ast.IfExp)):
            v = _value(node.test, consts)
            if v is not None:
                chosen = node.body if v else node.orelse
                for child in (chosen if isinstance(chosen, list) else [chosen]):
                    visit(child)
                return
        if isinstance(node, ast.Name):
            (loads if isinstance(node.ctx, ast.Load) else local).add(node.id)
        for child in ast.iter_child_nodes(node):
            visit(child)

    for stmt in fn.body:
        visit(stmt)
    return loads - local


def _unbound(text: str, roots) -> list[str]:
    """Names reached from the functions ``roots`` (through the module's functions) that the
    module does not bind."""
    names, consts, functions = _top(ast.parse(text))
    seen, todo, missing = set(), list(roots), set()
    while todo:
        name = todo.pop()
        if name in seen or name not in functions:
            continue
        seen.add(name)
        for used in _used(functions[name], consts):
            if used in functions:
                todo.append(used)
            elif used not in names and not hasattr(builtins, used):
                missing.add(f"{name}: {used}")
    return sorted(missing)


#: a representative of each family and driver kind, on a problem where it applies
SAMPLES = {
    "explicit-rk": [("kepler-2d", "rk4"), ("kepler-2d", "euler:sum=compensated")],
    "embedded-rk": [("kepler-2d", "merson"), ("kepler-2d", "dopri5"), ("kepler-2d", "dop853"),
                    ("kepler-2d", "rkf45:sum=compensated")],
    "extrapolation": [("kepler-2d", "odex:adaptive=false"), ("kepler-2d", "odex")],
    "implicit-rk": [("kepler-2d", "gauss4"), ("kepler-2d", "implicit-euler:fixed_point=5")],
    "partitioned": [("kepler-2d", "stormer-verlet"), ("pendulum", "symplectic-euler"),
                    ("kepler-2d", "symplectic-euler-adjoint:sum=compensated")],
    "composition": [("kepler-2d", "yoshida4"), ("kepler-2d", "suzuki4")],
    "splitting": [("euler-so4", "lie-poisson")],
    "generating-function": [("kepler-2d", "generating-function4")],
}
SECTION_PROBLEM = {"kepler-2d": "henon-heiles", "pendulum": "henon-heiles"}


def _combinations():
    from gnibench.suite.cell.spec import parse_method

    for family, cells in SAMPLES.items():
        for spec, method in cells:
            cfg = parse_method(method)
            kind = "adaptive" if cfg.base.values.get("adaptive") else "fixed"
            for output in DRIVERS[kind].outputs:
                if output.startswith("section") and spec in SECTION_PROBLEM:
                    spec_out = SECTION_PROBLEM[spec]
                else:
                    spec_out = spec
                if (output in ("dense", "section_dense")
                        and getattr(cfg.base.record.data, "dense", None) is None):
                    continue
                yield pytest.param(family, spec_out, method, output,
                                   id=f"{family}-{spec_out}-{method}-{output}")


@pytest.mark.parametrize("family, spec, method, output", list(_combinations()))
def test_every_name_a_driver_reaches_is_bound(family, spec, method, output):
    problem, cfg = prepare(spec, method)
    if output.startswith("section") and not problem.record.sections:
        pytest.skip("no section")
    kind = "adaptive" if cfg.base.values.get("adaptive") else "fixed"
    text = cell_text(problem, cfg, output)
    assert _unbound(text, [DRIVERS[kind].loop.__name__, "f", "fjac"]) == []
    # and the family's table: its writer defines what the table says for the kind
    names, consts, _ = _top(ast.parse(text))
    table = FAMILIES[family]
    expected = set(table.kinds[kind]) | (set(SUM) if consts["COMPENSATED"] else set())
    if table.dense and kind == "adaptive" and cfg.base.record.data.dense is not None:
        expected |= set(DENSE_PART)
    assert expected <= names


def test_the_problems_module_binds_what_it_reaches():
    for spec in ("kepler-2d", "henon-heiles"):
        problem, _ = prepare(spec, "rk4")
        roots = ["eval_invariants", "base_f", "base_jac"]
        roots += ["section_values", "henon_all"] if problem.record.sections else []
        assert _unbound(problem_text(problem), roots) == [], spec


def test_a_missing_binding_is_seen():
    """The check can fail: a loop whose partial step is not bound, a flag branch taken."""
    problem, cfg = prepare("kepler-2d", "rk4")
    text = cell_text(problem, cfg, "grid")
    assert _unbound(text.replace("def partial_step(", "def partial_step_gone("),
                    ["integrate"]) != []
    assert _unbound(cell_text(problem, cfg, "samples").replace("GRID = False", "GRID = True"),
                    ["integrate"]) != []


def test_every_compiled_family_has_a_binding_table():
    from gnibench.methods import COMPILED

    assert {m.family for m in COMPILED.values()} <= set(FAMILIES)
    for family, table in FAMILIES.items():
        assert set(table.kinds) <= set(DRIVERS), family


# -- roles, and what numba caches ------------------------------------------------------------------

def _roles(text: str) -> dict[str, str]:
    """Function name -> its decorator line."""
    lines = text.splitlines()
    out = {}
    for i, line in enumerate(lines):
        m = re.match(r"def (\w+)\(", line)
        if m:
            out[m.group(1)] = lines[i - 1]
    return out


@pytest.mark.parametrize("spec, method, output", [
    ("kepler-2d", "dop853", "dense"), ("henon-heiles", "rk4+observer", "section"),
    ("kepler-2d", "gauss4+projection:on=H", "grid"), ("kepler-2d", "odex", "grid")])
def test_every_function_has_one_role_and_only_python_s_calls_are_entries(spec, method, output):
    problem, cfg = prepare(spec, method)
    roles = _roles(cell_text(problem, cfg, output))
    assert set(roles.values()) <= set(ROLES), roles
    entries = {name for name, role in roles.items() if role == source.ENTRY}
    kind = "adaptive" if cfg.base.values.get("adaptive") else "fixed"
    python_calls = {DRIVERS[kind].loop.__name__, "f", "fjac", "dense_coeffs", "dense_eval",
                    "dense_slope"}
    assert DRIVERS[kind].loop.__name__ in entries and entries <= python_calls


def test_only_the_functions_python_calls_are_cached_on_disk(tmp_path):
    """A cold run in a fresh process: numba's index files are those of the module's ``@entry``
    and ``@shared`` functions it ran (the driver among them); the others are compiled into their
    callers, whose cache files hold their code."""
    env = {**os.environ, "GNIBENCH_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    subprocess.run([str(Path(sys.executable).with_name("gnibench")), "solve", "kepler-2d",
                    "rk4:h=0.01", "--steps", "20", "--every", "10"], env=env, check=True,
                   capture_output=True, timeout=600)
    kernels = tmp_path / "kernels"
    cell = next(kernels.glob("cell_*.py"))
    roles = _roles(cell.read_text())
    cached = {p.name.split(".")[1].split("-")[0] for p in
              (kernels / "__pycache__").glob(f"{cell.stem}.*.nbi")}
    assert "integrate" in cached
    assert {roles[name] for name in cached} <= {source.ENTRY, source.SHARED}, cached
    manifest = json.loads((kernels / "__pycache__" / f"{cell.stem}.manifest.json").read_text())
    assert {p.name for p in (kernels / "__pycache__").glob(f"{cell.stem}.*.nb[ic]")} == set(manifest)


# -- nothing rewrites a module's text --------------------------------------------------------------

def test_templates_are_copied_verbatim_and_read_once():
    from gnibench.methods.assembly.templates import fixed, rows

    text = source.copy(rows.record_row, source.INLINE)
    assert text == "\n@inline\n" + inspect.getsource(rows.record_row)
    assert source._source(fixed.integrate) is source._source(fixed.integrate)
    problem, cfg = prepare("kepler-2d", "rk4")
    assert inspect.getsource(fixed.integrate) in cell_text(problem, cfg, "samples")


def test_the_assembly_edits_no_text():
    """No pattern substitution on source text anywhere in the assembly (renames, flags), no pass
    over a written module."""
    for path in (ROOT / "methods" / "assembly").rglob("*.py"):
        code = path.read_text()
        assert not re.search(r"^import re$|re\.sub\(|\.replace\(", code, re.M), path


def test_one_driver_per_module_and_the_kernel_key_is_its_text():
    problem, cfg = prepare("kepler-2d", "dopri5")
    texts = {out: cell_text(problem, cfg, out) for out in DRIVERS["adaptive"].outputs
             if not out.startswith("section")}
    assert len(set(texts.values())) == len(texts)
    for out, text in texts.items():
        flags = dict(re.findall(r"^(\w+) = (True|False)$", text, re.M))
        on = {f for f in FLAGS if flags[f] == "True"}
        assert on == set(DRIVERS["adaptive"].outputs[out].flags), out
    assert kernel_text(problem, cfg) == texts["samples"]     # no keyed part in this cell
